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

#: z-slices per task when not given: 256 slices of a 1024^2 uint32 store are 1 GiB of input.
DEFAULT_SLAB = 256


def _check_slab(slab):
    if isinstance(slab, (bool, np.bool_)) or not isinstance(slab, (numbers.Integral, np.integer)):
        raise TypeError(f"slab must be a positive multiple of 16 (z-slices per task), not {slab!r}")
    if slab <= 0 or slab % 16:
        raise ValueError(f"slab must be a positive multiple of 16 (z-slices per task), not {slab}")
    return int(slab)


def z_ranges(nz, slab=DEFAULT_SLAB, partitions=None):
    """The z-ranges [z0, z1) of the tasks: ``slab`` slices each, or with ``partitions`` the
    16-slice slabs shared out as evenly as possible (at most one range per slab)."""
    if partitions is None:
        return [(z0, min(nz, z0 + slab)) for z0 in range(0, nz, slab)]
    slabs = -(-nz // 16)
    count = min(partitions, slabs)
    ranges, first = [], 0
    for p in range(count):
        n = slabs // count + (1 if p < slabs % count else 0)
        ranges.append((16 * first, min(nz, 16 * (first + n))))
        first += n
    return ranges


def _open(source, dataset, scale, axis_order, cache_bytes=None):
    from . import stores
    from .fileio import _chunked_store, check_cache_bytes

    found = _chunked_store(source, dataset)
    if found is None:
        raise ValueError(
            f"{os.fsdecode(source) if not stores.is_url(source) else source}: build_distributed "
            "reads chunked stores (Zarr, OME-Zarr, N5, neuroglancer precomputed); a single file "
            "is read by one process: use vtksvdag.read"
        )
    location, kind = found
    return stores.open_store(location, kind, scale=scale, axis_order=axis_order,
                             cache_bytes=check_cache_bytes(cache_bytes))


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


def _build_part(source, dataset, scale, axis_order, cache_bytes, z0, z1, background, exclude):
    """Task: compress slices z0..z1-1 of the store; returns (volume, seconds)."""
    from .stores import slab_slices_for

    _one_thread_per_task()
    start = time.perf_counter()
    array = _open(source, dataset, scale, axis_order, cache_bytes)
    thickness = min(slab_slices_for(array), 16 * -(-(z1 - z0) // 16))
    chunk = array.chunk_z()
    with _builder(array, z1 - z0, background, exclude) as builder:
        for z in range(z0, z1, thickness):
            end = min(z1, z + thickness)
            try:
                slab = array.read_slab(z, end)
            except Exception as e:  # tensorstore raises ValueError / OSError subclasses
                chunks = (f" (chunks {z // chunk}..{(end - 1) // chunk} along z)" if chunk else "")
                raise OSError(f"{array.where}: reading z-slices {z}..{end - 1}{chunks} failed: "
                              f"{e}") from e
            builder.add_slab(slab)
        volume = builder.finish()
    return volume, time.perf_counter() - start


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


def build_distributed(source, client=None, slab=DEFAULT_SLAB, *, partitions=None, background=0,
                      exclude=(), scale=None, axis_order=None, dataset=None, progress=None,
                      retries=2, cache_bytes=None):
    """Compress a chunked store on a Dask cluster, byte-identical to :func:`vtksvdag.read`.

    The store is cut into z-ranges of ``slab`` slices; each task reads its own range from the
    store (the data never pass through this process) and compresses it; the partial volumes
    are merged pairwise in z order. The result does not depend on ``slab`` or on the number of
    workers: it is the same, byte for byte, as ``vtksvdag.read(source)``.

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
    slab : int, default: 256
        z-slices per task, a positive multiple of 16. A worker holds the slices it reads at a
        time (about 64 MiB) and its partial volume; a merge holds two partials and their merge.
        Each task runs on one thread (Dask's parallelism is the tasks): give a machine's
        cores to its workers' threads.
    partitions : int, optional
        Instead of ``slab``: the number of tasks that read the store, each given a share of the
        16-slice slabs as even as possible (at most one task per slab).
    background, exclude, scale, axis_order, dataset, cache_bytes
        As for :func:`vtksvdag.read` (``cache_bytes`` bounds each task's chunk cache).
    progress : callable, optional
        Called with the fraction of tasks done, in [0, 1].
    retries : int, default: 2
        Times Dask reruns a task whose worker was lost.

    Returns
    -------
    SegmentationVolume
        The volume; its ``build_report`` attribute is a dict: ``partitions`` (tasks that read
        the store), ``partial_seconds`` and ``merge_seconds`` (per task, as measured on the
        workers), ``wall_seconds``.

    Raises
    ------
    ValueError
        ``source`` is no chunked store, or an argument is invalid (as for :func:`vtksvdag.read`).
    OSError
        The store cannot be read; a read failing on a worker names the z-slices and chunks.

    Examples
    --------
    >>> import vtksvdag
    >>> volume = vtksvdag.build_distributed("seg.zarr", "local:2", slab=128)  # doctest: +SKIP
    >>> volume.to_bytes() == vtksvdag.read("seg.zarr").to_bytes()  # doctest: +SKIP
    True
    """
    from dask import distributed

    from .volume import SegmentationVolume

    slab = _check_slab(slab)
    if partitions is not None and (isinstance(partitions, bool) or not isinstance(
            partitions, numbers.Integral) or partitions < 1):
        raise ValueError(f"partitions must be an integer >= 1, not {partitions!r}")
    if progress is not None and not callable(progress):
        raise TypeError(f"progress must be callable, not {type(progress).__name__}")
    if isinstance(retries, bool) or not isinstance(retries, numbers.Integral) or retries < 0:
        raise ValueError(f"retries must be an integer >= 0, not {retries!r}")
    exclude = label_list(exclude)
    # Metadata only (dims, dtype, geometry): the labels are read by the tasks.
    array = _open(source, dataset, scale, axis_order, cache_bytes)
    nz = array.dims[2]
    if min(array.dims) < 1:
        raise ValueError(f"{array.where}: the array is empty (dimensions {array.dims})")
    # The builder checks the labels against the dtype; fail here, not on every worker.
    _builder(array, 1, background, exclude).close()
    source = source if isinstance(source, str) else os.fsdecode(source)

    start = time.perf_counter()
    client, owned = _parse_client(client)
    try:
        def submit(fn, *args):
            return client.submit(fn, *args, pure=False, retries=int(retries))

        parts = [submit(_build_part, source, dataset, scale, axis_order, cache_bytes, z0, z1,
                        background, exclude)
                 for z0, z1 in z_ranges(nz, slab, partitions)]
        timings = {"partial": [submit(operator.itemgetter(1), p) for p in parts], "merge": []}
        level = parts
        while len(level) > 1:
            merged = [submit(_merge, level[i], level[i + 1], background, exclude)
                      for i in range(0, len(level) - 1, 2)]
            timings["merge"] += [submit(operator.itemgetter(1), m) for m in merged]
            level = merged + level[len(level) - len(level) % 2:]
        result = submit(operator.itemgetter(0), level[0])
        pending = [result] + timings["partial"] + timings["merge"]
        done = 0
        for _ in distributed.as_completed(pending):
            done += 1
            if progress is not None:
                progress(done / len(pending))
        volume = result.result()
        report = {
            "partitions": len(parts),
            "partial_seconds": client.gather(timings["partial"]),
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
