"""Compress a chunked store on a Dask cluster: :func:`build_distributed`.

Each task reads its own z-range from the store and compresses it (a partial volume); partials
are merged pairwise in z order, a tree of log2(parts) levels (:meth:`Builder.add_volume`). The
merge deduplicates the nodes of both parts in the order one scan over both would have seen
them, so the result is byte-identical to the single-machine build whatever the partition.
Partials travel between workers as ``.svdag`` bytes (checked on arrival, like a file).
"""
import contextlib
import numbers
import operator
import os
import time

import numpy as np

from ._labels import label_list


def _check_count(value, what, multiple=1):
    """None, or ``value`` as a positive int that is a multiple of ``multiple``."""
    if value is None:
        return None
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (numbers.Integral, np.integer)):
        raise TypeError(f"{what}, not {value!r}")
    if value <= 0 or value % multiple:
        raise ValueError(f"{what}, not {value}")
    return int(value)


def z_ranges(nz, partitions, unit=16):
    """The z-ranges [z0, z1) of ``partitions`` tasks: the volume's steps of ``unit`` slices
    (a multiple of 16, see stores.z_unit) shared out as evenly as possible, at most one task
    per step."""
    steps = -(-nz // unit)
    count = min(partitions, steps)
    ranges, first = [], 0
    for p in range(count):
        n = steps // count + (1 if p < steps % count else 0)
        ranges.append((unit * first, min(nz, unit * (first + n))))
        first += n
    return ranges


def _find(source, dataset):
    from . import stores
    from .fileio import _chunked_store

    found = _chunked_store(source, dataset)
    if found is None:
        raise ValueError(
            f"{os.fsdecode(source) if not stores.is_url(source) else source}: build_distributed "
            "reads chunked stores (Zarr, OME-Zarr, N5, neuroglancer precomputed); a single file "
            "is read by one process: use vtksvdag.read"
        )
    return found


def _builder(array, depth, background, exclude):
    from .streaming import Builder

    nx, ny, _ = array.dims
    return Builder((nx, ny, depth), array.dtype, spacing=array.spacing, origin=array.origin,
                   direction=array.direction, background=background, exclude=exclude,
                   axis_order=array.slab_order)


def _one_thread_per_task():
    """Dask runs one task per worker thread: the builder's own threads (vtkSMPTools) would
    oversubscribe the cores, so a task builds on its thread alone."""
    from vtkmodules.vtkCommonCore import vtkSMPTools

    vtkSMPTools.Initialize(1)


def _build_part(source, dataset, scale, axis_order, cache_bytes, slab, z0, z1, background,
                exclude):
    """Task: compress slices z0..z1-1 of the store; returns (volume, seconds, its bytes)."""
    from .stores import open_for_reading, release_freed_memory

    _one_thread_per_task()
    start = time.perf_counter()
    location, kind = _find(source, dataset)
    array, thickness = open_for_reading(location, kind, scale, axis_order, cache_bytes, slab, z0)
    chunk = array.chunk_z()
    with _builder(array, z1 - z0, background, exclude) as builder:
        for z in range(z0, z1, thickness):
            end = min(z1, z + thickness)
            try:
                slab_array = array.read_slab(z, end)
            except Exception as e:  # tensorstore raises ValueError / OSError subclasses
                chunks = (f" (chunks {z // chunk}..{(end - 1) // chunk} along z)" if chunk else "")
                raise OSError(f"{array.where}: reading z-slices {z}..{end - 1}{chunks} failed: "
                              f"{e}") from e
            builder.add_slab(slab_array)
            del slab_array
            release_freed_memory()
        volume = builder.finish()
    return volume, time.perf_counter() - start, volume.stats()["bytes_total"]


def _merge(lower, upper, background, exclude):
    """Task: the volume of two consecutive z-ranges; returns (volume, seconds)."""
    from .streaming import Builder

    _one_thread_per_task()
    start = time.perf_counter()
    a, b = lower[0], upper[0]
    nx, ny, nz = a.dims
    with Builder((nx, ny, nz + b.dims[2]), a.dtype, spacing=a.spacing, origin=a.origin,
                 direction=a.direction, background=background, exclude=exclude) as builder:
        builder.add_volume(a)
        builder.add_volume(b)
        volume = builder.finish()
    return volume, time.perf_counter() - start


def _parse_client(client):
    """A distributed.Client from ``client`` (a Client, a scheduler address, "local:N", or
    None for the default client), and whether it was made here (and must be closed)."""
    from dask import distributed

    if isinstance(client, distributed.Client):
        return client, False
    if client is None:
        with contextlib.suppress(ValueError):
            return distributed.get_client(), False
        client = f"local:{os.cpu_count() or 1}"
    if not isinstance(client, str):
        raise TypeError(f"client must be a dask.distributed.Client, a scheduler address or "
                        f"'local:N', not {type(client).__name__}")
    if client.startswith("local:"):
        count = client[len("local:"):]
        if not count.isdigit() or int(count) < 1:
            raise ValueError(f"'local:N' needs a number of workers N >= 1, not {client!r}")
        cluster = distributed.LocalCluster(n_workers=int(count), threads_per_worker=1,
                                           processes=True, dashboard_address=":0")
        return distributed.Client(cluster), True
    return distributed.Client(client), True


def build_distributed(source, client=None, slab=None, *, partitions=None, background=0,
                      exclude=(), scale=None, axis_order=None, dataset=None, progress=None,
                      retries=2, cache_bytes=None):
    """Compress a chunked store on a Dask cluster, byte-identical to :func:`vtksvdag.read`.

    The store's z-slices are shared out among ``partitions`` tasks; each task reads its own
    z-range from the store (the data never pass through this process), ``slab`` slices at a
    time, and compresses it; the partial volumes are merged pairwise in z order. The result
    does not depend on how the work was split: it is the same, byte for byte, as
    ``vtksvdag.read(source)``.

    Parameters
    ----------
    source : str or os.PathLike
        A chunked store (Zarr v2/v3, OME-Zarr, N5, neuroglancer precomputed): a directory or a
        URL that every worker can read (``file://``, ``gs://``, ``s3://``, ``http(s)://``).
    client : dask.distributed.Client or str, optional
        Where to run: a Client, a scheduler address (``"tcp://scheduler:8786"``), or
        ``"local:N"`` for a local cluster of N single-threaded worker processes made for this
        call. By default the current Dask client, else a local cluster with one worker per
        core.
    slab : int, optional
        z-slices a task reads and compresses at a time, a positive multiple of 16. By default
        as :func:`vtksvdag.read` does: about 64 MiB, kept to the store's chunks along z. A
        worker holds one slab and its partial volume; a merge holds two partials and their
        merge.
    partitions : int, optional
        The number of tasks that read the store; by default one per worker thread of the
        cluster (more tasks balance uneven workers, at the cost of more merging: the merge
        work is about the output's size per level of the tree). Task boundaries keep to the
        store's chunks along z (each chunk is then read by one task) unless that gives fewer
        tasks than asked; there is at most one task per 16-slice step.
    background, exclude, scale, axis_order, dataset, cache_bytes
        As for :func:`vtksvdag.read` (``cache_bytes`` bounds each task's chunk cache).
    progress : callable, optional
        Called with the fraction of tasks done, in [0, 1].
    retries : int, default: 2
        Times Dask reruns a task that raised (a task whose worker was lost is rerun anyway).

    Returns
    -------
    SegmentationVolume
        The volume; its ``build_report`` attribute is a dict: ``partitions`` (tasks that read
        the store), their ``z_ranges`` ([z0, z1) each), ``partial_seconds`` and
        ``merge_seconds`` (per task, as measured on the workers), ``partial_bytes`` (each
        partial volume's in-memory bytes), ``wall_seconds``.

    Raises
    ------
    ValueError
        ``source`` is no chunked store, or an argument is invalid (as for :func:`vtksvdag.read`).
    OSError
        The store cannot be read; a read failing on a worker names the z-slices and chunks.

    Notes
    -----
    Each task runs on one thread (Dask's parallelism is the tasks): give a machine's cores to
    its workers' threads.

    Examples
    --------
    >>> import vtksvdag
    >>> volume = vtksvdag.build_distributed("seg.zarr", "local:2")  # doctest: +SKIP
    >>> volume.to_bytes() == vtksvdag.read("seg.zarr").to_bytes()  # doctest: +SKIP
    True
    """
    from dask import distributed

    from .volume import SegmentationVolume

    from .fileio import check_cache_bytes
    from .stores import open_store, z_unit

    slab = _check_count(slab, "slab must be a positive multiple of 16 (z-slices read at a time)",
                        16)
    partitions = _check_count(partitions, "partitions must be an integer >= 1")
    if progress is not None and not callable(progress):
        raise TypeError(f"progress must be callable, not {type(progress).__name__}")
    if isinstance(retries, bool) or not isinstance(retries, numbers.Integral) or retries < 0:
        raise ValueError(f"retries must be an integer >= 0, not {retries!r}")
    cache_bytes = check_cache_bytes(cache_bytes)
    exclude = label_list(exclude)
    # Metadata only (dims, dtype, geometry, chunks): the labels are read by the tasks.
    location, kind = _find(source, dataset)
    array = open_store(location, kind, scale=scale, axis_order=axis_order, cache_bytes=0)
    nz = array.dims[2]
    if min(array.dims) < 1:
        raise ValueError(f"{array.where}: the array is empty (dimensions {array.dims})")
    # The builder checks the labels against the dtype; fail here, not on every worker.
    _builder(array, 1, background, exclude).close()
    source = source if isinstance(source, str) else os.fsdecode(source)
    unit, _ = z_unit(array)

    start = time.perf_counter()
    client, owned = _parse_client(client)
    try:
        def submit(fn, *args):
            return client.submit(fn, *args, pure=False, retries=int(retries))

        if partitions is None:
            partitions = max(1, sum(client.nthreads().values()))
        # Task boundaries keep to the chunks along z unless that leaves fewer tasks than asked.
        if -(-nz // unit) < partitions:
            unit = 16
        ranges = z_ranges(nz, partitions, unit)
        parts = [submit(_build_part, source, dataset, scale, axis_order, cache_bytes, slab, z0,
                        z1, background, exclude)
                 for z0, z1 in ranges]
        timings = {"partial": [submit(operator.itemgetter(1), p) for p in parts], "merge": [],
                   "bytes": [submit(operator.itemgetter(2), p) for p in parts]}
        level = parts
        while len(level) > 1:
            merged = [submit(_merge, level[i], level[i + 1], background, exclude)
                      for i in range(0, len(level) - 1, 2)]
            timings["merge"] += [submit(operator.itemgetter(1), m) for m in merged]
            level = merged + level[len(level) - len(level) % 2:]
        result = submit(operator.itemgetter(0), level[0])
        pending = [result] + timings["partial"] + timings["merge"] + timings["bytes"]
        done = 0
        for _ in distributed.as_completed(pending):
            done += 1
            if progress is not None:
                progress(done / len(pending))
        volume = result.result()
        report = {
            "partitions": len(parts),
            "z_ranges": ranges,
            "partial_seconds": client.gather(timings["partial"]),
            "partial_bytes": client.gather(timings["bytes"]),
            "merge_seconds": client.gather(timings["merge"]),
        }
    finally:
        if owned:
            cluster = client.cluster
            client.close()
            if cluster is not None:
                cluster.close()
    report["wall_seconds"] = time.perf_counter() - start
    volume = SegmentationVolume(volume.dataobject, build_seconds=report["wall_seconds"])
    volume.build_report = report
    return volume
