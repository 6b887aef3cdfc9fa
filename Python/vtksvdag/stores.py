"""Chunked array stores (Zarr v2/v3, OME-Zarr, N5, neuroglancer precomputed) through tensorstore.

A store is compressed slab by slab: z-slabs of 16·k slices are read with tensorstore and fed to
:class:`vtksvdag.Builder`, so the whole array is never in memory, and tensorstore's chunk cache
is bounded by a ``cache_pool`` ``total_bytes_limit`` in the context every store is opened with.
:func:`write_zarr` goes the other way (a ``.svdag`` volume to an OME-Zarr, slab by slab).

Locations are local directories or URLs (``file://``, ``gs://``, ``s3://``, ``http(s)://``,
handed to tensorstore's kvstores as they are). Only local directories and ``file://`` URLs are
tested here; remote stores need network access and credentials tensorstore finds itself.

Axis conventions, per ``tensorstore`` dimension (``axis_order`` overrides the spatial ones):

* Zarr v2/v3 arrays: the last three dimensions are (z, y, x), x fastest, as numpy and OME-Zarr
  write them; OME-Zarr's ``axes`` name them instead when present.
* N5 and neuroglancer precomputed: the first three are (x, y, z) (N5's ``dimensions`` list x
  first; precomputed adds a 4th ``channel`` dimension).
* Any other dimension (time, channel) must have size 1.
"""
import json
import math
import os
import posixpath
import time

import numpy as np

from ._labels import ExactCast, float_labels_error

#: URL schemes handed to tensorstore's kvstores (only file:// is tested here).
URL_SCHEMES = ("file://", "gs://", "s3://", "http://", "https://")
#: Bound of tensorstore's chunk cache (bytes) where slabs do not keep to the chunks along z.
DEFAULT_CACHE_BYTES = 256 * 2**20
#: Slabs are sized to about this many bytes (then rounded to 16·k slices).
SLAB_BYTES = 64 * 2**20

ZARR2, ZARR3, N5, PRECOMPUTED, OME = "zarr", "zarr3", "n5", "neuroglancer_precomputed", "ome-zarr"


def is_url(path):
    """True when ``path`` is a string URL of a scheme in :data:`URL_SCHEMES`."""
    return isinstance(path, str) and path.lower().startswith(URL_SCHEMES)


def context_spec(cache_bytes=DEFAULT_CACHE_BYTES):
    """The tensorstore context (JSON) stores are opened with: a bounded chunk cache."""
    if isinstance(cache_bytes, bool) or not isinstance(cache_bytes, (int, np.integer)) or cache_bytes < 0:
        raise ValueError(f"cache_bytes must be a non-negative integer, not {cache_bytes!r}")
    return {"cache_pool": {"total_bytes_limit": int(cache_bytes)}}


def _tensorstore():
    try:
        import tensorstore
    except ImportError as e:  # an optional dependency: only chunked stores need it
        raise ImportError(
            "reading or writing chunked stores (Zarr, N5, neuroglancer precomputed) needs the "
            "tensorstore package (pip install tensorstore)"
        ) from e
    return tensorstore


# -- locations: a local directory or a tensorstore kvstore spec -----------------------------
class _Location:
    """A directory of a store: local (``local`` is its path) or a kvstore spec of a URL."""

    def __init__(self, text, local=None, kvstore=None):
        self.text = text
        self.local = local
        self.kvstore = kvstore

    @classmethod
    def of(cls, path):
        if is_url(path):
            ts = _tensorstore()
            try:
                spec = ts.KvStore.Spec(path).to_json()
            except ValueError as e:
                raise ValueError(f"{path}: not a URL tensorstore can open ({e})") from None
            if spec.get("driver") == "file":  # a file:// URL is a local directory after all
                return cls(path, local=spec["path"])
            spec["path"] = spec.get("path", "").rstrip("/") + "/"
            return cls(path, kvstore=spec)
        return cls(path, local=os.fsdecode(path))

    def join(self, sub):
        sub = str(sub).strip("/")
        if not sub:
            return self
        text = self.text.rstrip("/") + "/" + sub
        if self.local is not None:
            return _Location(text, local=os.path.join(self.local, *sub.split("/")))
        spec = dict(self.kvstore)
        spec["path"] = posixpath.join(spec["path"], sub) + "/"
        return _Location(text, kvstore=spec)

    def is_dir(self):
        return self.local is None or os.path.isdir(self.local)

    def read_json(self, key):
        """The JSON object stored under ``key``, or None when there is no such key."""
        if self.local is not None:
            file = os.path.join(self.local, key)
            if not os.path.isfile(file):
                return None
            with open(file, "rb") as f:
                data = f.read()
        else:
            ts = _tensorstore()
            try:
                result = ts.KvStore.open(self.kvstore).result().read(key).result()
            except ValueError as e:
                raise OSError(f"{self.text}: cannot read {key} ({e})") from None
            if result.state != "value":
                return None
            data = bytes(result.value)
        try:
            value = json.loads(data)
        except ValueError as e:
            raise OSError(f"{self.text}/{key}: not valid JSON ({e})") from None
        return value if isinstance(value, dict) else None

    def kvstore_spec(self):
        if self.local is not None:
            return {"driver": "file", "path": os.path.abspath(self.local) + "/"}
        return self.kvstore


def _ome_multiscales(attributes):
    """The "multiscales" list of OME-Zarr group attributes (0.4 top level, 0.5 under "ome")."""
    if not isinstance(attributes, dict):
        return None
    for holder in (attributes.get("ome"), attributes):
        if isinstance(holder, dict) and isinstance(holder.get("multiscales"), list):
            return holder["multiscales"]
    return None


#: What detect() looks for in a directory, in its order (for the message of read(directory)).
LOOKED_FOR = (
    "a Zarr v2 array (.zarray)",
    "a Zarr v3 array or OME-Zarr group (zarr.json)",
    "an OME-Zarr group (.zattrs with multiscales)",
    "an N5 array (attributes.json with dimensions)",
    "a neuroglancer precomputed volume (info with scales)",
)


def ome_attributes(location):
    """The group attributes of the OME-Zarr at ``location``: its ``.zattrs`` (0.4), or the
    ``attributes`` of its ``zarr.json`` (0.5)."""
    attributes = location.read_json(".zattrs")
    if not _ome_multiscales(attributes):
        attributes = (location.read_json("zarr.json") or {}).get("attributes")
    return attributes


def detect(location):
    """The kind of store at ``location`` (a _Location): one of ZARR2, ZARR3, N5, PRECOMPUTED,
    OME, or None when it holds no store this module knows."""
    if location.local is not None and not os.path.isdir(location.local):
        return None
    if location.read_json(".zarray") is not None:
        return ZARR2
    zarr_json = location.read_json("zarr.json")
    if zarr_json is not None:
        if zarr_json.get("node_type") == "array":
            return ZARR3
        if _ome_multiscales(zarr_json.get("attributes")):
            return OME
        return None
    if _ome_multiscales(location.read_json(".zattrs")):
        return OME
    attributes = location.read_json("attributes.json")
    if attributes is not None and "dimensions" in attributes:
        return N5
    info = location.read_json("info")
    if info is not None and isinstance(info.get("scales"), list):
        return PRECOMPUTED
    return None


def find_store(path, dataset=None):
    """(location, kind) of the store at ``path`` (optionally the sub-path ``dataset`` in it);
    kind is None when it is no known store."""
    location = _Location.of(path)
    if dataset is not None:
        location = location.join(dataset)
    return location, detect(location)


# -- metadata -------------------------------------------------------------------------------
class StoreArray:
    """An opened store array and what the reader needs to know about it.

    Attributes: ``store`` (the tensorstore.TensorStore, its domain translated to start at 0),
    ``kind``, ``roles`` (per store dimension: "x", "y", "z" or another axis name, which must
    have size 1), ``dims`` (nx, ny, nz), ``dtype`` (numpy: integer, bool or float; open_store
    refuses float unless asked), ``spacing``/``origin`` (x, y, z), ``direction`` (3x3 or None),
    ``context`` (the context JSON it was opened with).
    """

    def __init__(self, store, kind, roles, spacing, origin, direction, context, where):
        self.store = store
        self.kind = kind
        self.roles = list(roles)
        self.context = context
        self.where = where
        shape = store.shape
        for role, size in zip(self.roles, shape):
            if role not in ("x", "y", "z") and size != 1:
                raise ValueError(
                    f"{where}: the array has shape {tuple(shape)} with a {role!r} axis of size "
                    f"{size}; only one channel (size 1) can be read as a label volume"
                )
        self.axis = {r: self.roles.index(r) for r in ("x", "y", "z")}
        self.dims = tuple(int(shape[self.axis[r]]) for r in ("x", "y", "z"))
        self.dtype = np.dtype(store.dtype.numpy_dtype)
        if self.dtype.kind not in "iubf":
            raise ValueError(
                f"{where}: the array has dtype {self.dtype}; segmentation labels must be integers "
                f"(int8..int64, uint8..uint64)"
            )
        self.spacing = [float(spacing[self.axis[r]]) for r in ("x", "y", "z")]
        self.origin = [float(origin[self.axis[r]]) for r in ("x", "y", "z")]
        self.direction = direction
        # Slabs go to the Builder as they come when the store is (x, y, z), else as (z, y, x).
        kept = [r for r in self.roles if r in ("x", "y", "z")]
        self.slab_order = "xyz" if kept == ["x", "y", "z"] else "zyx"

    def chunk_z(self):
        """The z extent of the store's read chunks (None when unknown)."""
        try:
            shape = self.store.chunk_layout.read_chunk.shape
        except (AttributeError, ValueError):
            return None
        value = shape[self.axis["z"]] if shape is not None else None
        return int(value) if value else None

    def read_slab(self, z0, z1):
        """Slices z0..z1-1 as a numpy array in :attr:`slab_order`: (nx, ny, n) or (n, ny, nx)."""
        index = []
        for role in self.roles:
            if role == "z":
                index.append(slice(z0, z1))
            elif role in ("x", "y"):
                index.append(slice(None))
            else:
                index.append(0)  # a size-1 axis, dropped
        array = self.store[tuple(index)].read().result()
        if self.slab_order == "xyz":
            return array
        kept = [r for r in self.roles if r in ("x", "y", "z")]
        return np.transpose(array, [kept.index(r) for r in ("z", "y", "x")])

    def as_xyz(self, slab):
        """A slab of :meth:`read_slab` as an (nx, ny, n) view, indexed as the volume is."""
        return slab if self.slab_order == "xyz" else slab.transpose(2, 1, 0)


def _spatial_roles(rank, kind, where, axis_order):
    """Per-dimension roles of a plain array: spatial axes last (zarr) or first (N5, precomputed)."""
    if rank < 3:
        raise ValueError(f"{where}: the array is {rank}D; a label volume must have 3 spatial axes")
    if kind in (ZARR2, ZARR3):
        order = axis_order or "zyx"
        return [f"axis{i}" for i in range(rank - 3)] + list(order)
    order = axis_order or "xyz"
    extra = ["channel"] if kind == PRECOMPUTED and rank == 4 else [f"axis{i}" for i in range(3, rank)]
    return list(order) + extra


def _numbers(values, n, what, where, positive=False):
    try:
        vector = [float(v) for v in values]
    except (TypeError, ValueError):
        raise ValueError(f"{where}: {what} must be numbers, not {values!r}") from None
    if len(vector) != n or not all(math.isfinite(v) for v in vector) or (
        positive and any(v <= 0 for v in vector)
    ):
        raise ValueError(f"{where}: {what} {values!r} is not {n} finite{' positive' if positive else ''} numbers")
    return vector


def _open(ts, spec, context, where):
    try:
        store = ts.open(spec, read=True, context=ts.Context(context)).result()
    except ValueError as e:
        raise OSError(f"{where}: tensorstore cannot open the array ({e})") from None
    return store[ts.d[:].translate_to[0]]  # precomputed domains start at voxel_offset


def _check_scale(scale, count, where):
    if scale is None:
        return 0
    if isinstance(scale, bool) or not isinstance(scale, (int, np.integer)):
        raise TypeError(f"scale must be an integer (a scale index), not {scale!r}")
    if not 0 <= scale < count:
        raise ValueError(
            f"{where}: scale {scale} is out of range; the store has {count} scale"
            f"{'s' if count != 1 else ''} (0..{count - 1})"
        )
    return int(scale)


def _open_ome(ts, location, attributes, scale, axis_order, context):
    where = location.text
    multiscales = _ome_multiscales(attributes)
    multiscale = multiscales[0]
    datasets = multiscale.get("datasets") if isinstance(multiscale, dict) else None
    if not isinstance(datasets, list) or not datasets:
        raise OSError(f"{where}: the OME-Zarr multiscales list no datasets")
    level = datasets[_check_scale(scale, len(datasets), where)]
    if not isinstance(level, dict):
        raise OSError(f"{where}: OME-Zarr dataset {level!r} is not an object")
    array_location = location.join(level.get("path", ""))
    kind = detect(array_location)
    if kind not in (ZARR2, ZARR3):
        raise OSError(f"{array_location.text}: the OME-Zarr level is no Zarr array")
    store = _open(ts, {"driver": kind, "kvstore": array_location.kvstore_spec()}, context, where)
    rank = store.rank
    axes = multiscale.get("axes")
    if axis_order is not None or axes is None:
        roles = _spatial_roles(rank, kind, where, axis_order)  # 0.1/0.2: (t, c,) z, y, x
    else:
        roles = [a.get("name") if isinstance(a, dict) else a for a in axes]
        if len(roles) != rank or not {"x", "y", "z"} <= set(roles):
            raise ValueError(f"{where}: OME-Zarr axes {axes!r} do not name x, y and z of the "
                             f"{rank}D array")
    # Scale and translation of the level, then those of the whole multiscale (applied after).
    spacing, origin = [1.0] * rank, [0.0] * rank
    for transforms in (level.get("coordinateTransformations"),
                       multiscale.get("coordinateTransformations")):
        for t in transforms if isinstance(transforms, list) else ():
            if not isinstance(t, dict):
                raise OSError(f"{where}: OME-Zarr coordinate transformation {t!r} is not an object")
            if t.get("type") == "scale":
                s = _numbers(t.get("scale"), rank, "scale", where, positive=True)
                spacing = [a * b for a, b in zip(spacing, s)]
                origin = [a * b for a, b in zip(origin, s)]
            elif t.get("type") == "translation":
                o = _numbers(t.get("translation"), rank, "translation", where)
                origin = [a + b for a, b in zip(origin, o)]
    direction = None
    ours = attributes.get("vtksvdag") if isinstance(attributes, dict) else None
    if isinstance(ours, dict) and "direction" in ours:  # written by write_zarr
        direction = ours["direction"]
    return StoreArray(store, kind, roles, spacing, origin, direction, context, where)


def open_store(location, kind, scale=None, axis_order=None, cache_bytes=DEFAULT_CACHE_BYTES,
               floats=False):
    """Open the store ``kind`` at ``location`` (from :func:`find_store`) as a StoreArray; a float
    array is refused (FloatLabelsError) unless ``floats`` (for ``cast="exact"``)."""
    array = _open_store(location, kind, scale, axis_order, cache_bytes)
    if array.dtype.kind == "f" and not floats:
        raise float_labels_error(array.dtype, f"array of {array.where}")
    return array


def _open_store(location, kind, scale, axis_order, cache_bytes):
    ts = _tensorstore()
    where = location.text
    if axis_order is not None and axis_order not in ("xyz", "zyx"):
        raise ValueError(f"axis_order must be 'xyz' or 'zyx', not {axis_order!r}")
    context = context_spec(cache_bytes)
    if kind == OME:
        return _open_ome(ts, location, ome_attributes(location), scale, axis_order, context)
    spec = {"driver": kind, "kvstore": location.kvstore_spec()}
    if kind == PRECOMPUTED:
        info = location.read_json("info")
        index = _check_scale(scale, len(info["scales"]), where)
        if not isinstance(info["scales"][index], dict):
            raise OSError(f"{where}: scale {index} of the info file is not an object")
        spec["scale_index"] = index
        store = _open(ts, spec, context, where)
        roles = _spatial_roles(store.rank, kind, where, axis_order)
        meta = info["scales"][index]
        resolution = _numbers(meta.get("resolution", (1, 1, 1)), 3, "resolution", where, positive=True)
        offset = _numbers(meta.get("voxel_offset", (0, 0, 0)), 3, "voxel_offset", where)
        # voxel_offset is in voxels: voxel 0 of the array lies at voxel_offset * resolution.
        spacing = resolution + [1.0] * (store.rank - 3)
        origin = [o * r for o, r in zip(offset, resolution)] + [0.0] * (store.rank - 3)
        return StoreArray(store, kind, roles, spacing, origin, None, context, where)
    _check_scale(scale, 1, where)
    store = _open(ts, spec, context, where)
    roles = _spatial_roles(store.rank, kind, where, axis_order)
    spacing, origin = [1.0] * store.rank, [0.0] * store.rank
    if kind == N5:
        attributes = location.read_json("attributes.json")
        # N5 viewers' conventions: "resolution" [x, y, z] or "pixelResolution" {"dimensions"}.
        resolution = attributes.get("resolution")
        pixel = attributes.get("pixelResolution")
        if resolution is None and isinstance(pixel, dict):
            resolution = pixel.get("dimensions")
        if resolution is not None:
            spacing = _numbers(resolution, store.rank, "resolution", where, positive=True)
    return StoreArray(store, kind, roles, spacing, origin, None, context, where)


# -- reading: slab by slab into the Builder -------------------------------------------------
def z_unit(array):
    """(unit, aligned): the z step that slab and task boundaries keep to. The least multiple
    of 16 slices that is also one of the chunks' z extent, when such a step is at most 4 chunks
    deep or 4 * SLAB_BYTES (then every chunk is fetched by exactly one slab: ``aligned``); else
    16 slices."""
    nx, ny, _ = array.dims
    slice_bytes = nx * ny * array.dtype.itemsize
    chunk = array.chunk_z()
    if chunk:
        unit = math.lcm(16, chunk)
        if unit <= 4 * max(16, chunk) or unit * slice_bytes <= 4 * SLAB_BYTES:
            return unit, True
    return 16, False


def slab_slices_for(array, slab_slices=None):
    """The z thickness of the slabs read from ``array``: a multiple of :func:`z_unit` of about
    SLAB_BYTES bytes, covering at least one chunk along z (so that a chunk is fetched by at most
    two slabs, and by one when the unit is aligned to the chunks)."""
    if slab_slices is not None:
        if isinstance(slab_slices, bool) or not isinstance(slab_slices, (int, np.integer)) or (
            slab_slices <= 0 or slab_slices % 16
        ):
            raise ValueError(f"slab_slices must be a positive multiple of 16, not {slab_slices!r}")
        return int(slab_slices)
    nx, ny, _ = array.dims
    unit, _ = z_unit(array)
    k = max(1, SLAB_BYTES // (unit * nx * ny * array.dtype.itemsize),
            -(-(array.chunk_z() or 16) // unit))
    return unit * k


def open_for_reading(location, kind, scale=None, axis_order=None, cache_bytes=None,
                     slab_slices=None, z0=0, floats=False):
    """(array, slab thickness) for one streaming pass over the store from slice ``z0``.
    Without an explicit ``cache_bytes``, the chunk cache is off when the slabs keep to the
    chunks along z (each chunk is read once: a cache would only hold memory) and
    DEFAULT_CACHE_BYTES otherwise. ``floats``: see :func:`open_store`."""
    array = open_store(location, kind, scale=scale, axis_order=axis_order,
                       cache_bytes=0 if cache_bytes is None else cache_bytes, floats=floats)
    thickness = slab_slices_for(array, slab_slices)
    unit, aligned = z_unit(array)
    if cache_bytes is None and not (aligned and thickness % unit == 0 and z0 % unit == 0):
        array = open_store(location, kind, scale=scale, axis_order=axis_order,
                           cache_bytes=DEFAULT_CACHE_BYTES, floats=floats)
    return array, thickness


def release_freed_memory():
    """Hand memory freed by the last slab back to the system (glibc keeps freed large blocks
    once its dynamic mmap threshold has grown past them, so peak memory would creep up by a
    slab or two); a no-op elsewhere."""
    global _malloc_trim
    if _malloc_trim is None:
        try:
            import ctypes

            _malloc_trim = ctypes.CDLL("libc.so.6").malloc_trim
        except (OSError, AttributeError):
            _malloc_trim = False
    if _malloc_trim:
        _malloc_trim(0)


_malloc_trim = None


def read_store(location, kind, background=0, exclude=(), scale=None, axis_order=None,
               progress=None, cache_bytes=None, slab_slices=None, cast=None):
    """Compress the store ``kind`` at ``location`` (see :func:`find_store`) slab by slab.

    A float array with ``cast="exact"`` is read twice, slab by slab: a pass that checks every
    value (:class:`vtksvdag._labels.ExactCast`) and finds the integer dtype, then the pass that
    converts and compresses; each takes half of the progress."""
    from .streaming import Builder
    from .volume import SegmentationVolume

    array, thickness = open_for_reading(location, kind, scale, axis_order, cache_bytes,
                                        slab_slices, floats=cast == "exact")
    nz = array.dims[2]
    start = time.perf_counter()
    if min(array.dims) < 1:
        raise ValueError(f"{location.text}: the array is empty (dimensions {array.dims})")
    slabs = [(z0, min(nz, z0 + thickness)) for z0 in range(0, nz, thickness)]
    dtype, convert, done = array.dtype, None, 0.0
    if array.dtype.kind == "f":
        check = ExactCast(array.dtype, f"array of {location.text}")
        for z0, z1 in slabs:
            check.check(array.as_xyz(array.read_slab(z0, z1)), (0, 0, z0))
            release_freed_memory()
            if progress is not None:
                progress(z1 / nz / 2)
        dtype, convert, done = check.dtype(), check.convert, 0.5
    with Builder(array.dims, dtype, spacing=array.spacing, origin=array.origin,
                 direction=array.direction, background=background, exclude=exclude,
                 axis_order=array.slab_order) as builder:
        for z0, z1 in slabs:
            slab = array.read_slab(z0, z1)
            builder.add_slab(slab if convert is None else convert(slab))
            del slab
            release_freed_memory()
            if progress is not None:
                progress(done + (1 - done) * z1 / nz)
        volume = builder.finish()
    seconds = time.perf_counter() - start
    return SegmentationVolume(volume.dataobject, build_seconds=seconds)


# -- writing: an OME-Zarr (Zarr v2) store ---------------------------------------------------
#: Chunk edge of the arrays write_zarr writes (clipped to the volume).
ZARR_CHUNK = 64


def _tree_bytes(path):
    return sum(
        os.path.getsize(os.path.join(root, name)) for root, _, names in os.walk(path) for name in names
    )


def write_zarr(volume, path, progress=None, chunk=ZARR_CHUNK):
    """Decode ``volume`` slab by slab into a new OME-Zarr 0.4 store at ``path`` (a directory).

    The store is a Zarr v2 group holding one multiscale of one level, the array ``0``:
    dimensions (z, y, x) with x fastest, the volume's dtype, chunks of ``chunk``^3 voxels
    (``"/"`` separated keys, blosc-zstd), ``fill_value`` the background (chunks of background
    only are not written). Its ``.zattrs`` give the spacing and origin as the level's
    ``scale`` and ``translation`` (z, y, x order), and a ``vtksvdag`` entry with the background
    and the 3x3 direction matrix (OME-Zarr has no rotation; :func:`vtksvdag.read` uses it).

    Raises FileExistsError when ``path`` exists and is not an empty directory.
    """
    ts = _tensorstore()
    path = os.fsdecode(path)
    if os.path.exists(path) and not (os.path.isdir(path) and not os.listdir(path)):
        raise FileExistsError(17, "File exists (write_zarr makes a new store)", path)
    nx, ny, nz = volume.dims
    dtype = np.dtype(volume.dtype)
    os.makedirs(path, exist_ok=True)
    background = int(volume.background)
    spacing, origin = list(volume.spacing), list(volume.origin)
    attributes = {
        "multiscales": [{
            "version": "0.4",
            "name": os.path.basename(path.rstrip(os.sep)),
            "axes": [{"name": a, "type": "space"} for a in "zyx"],
            "datasets": [{
                "path": "0",
                "coordinateTransformations": [
                    {"type": "scale", "scale": spacing[::-1]},
                    {"type": "translation", "translation": origin[::-1]},
                ],
            }],
        }],
        "vtksvdag": {
            "background": background,
            "direction": np.asarray(volume.direction, float).tolist(),
        },
    }
    with open(os.path.join(path, ".zgroup"), "w") as f:
        json.dump({"zarr_format": 2}, f)
    with open(os.path.join(path, ".zattrs"), "w") as f:
        json.dump(attributes, f, indent=1)
    chunks = [min(chunk, n) for n in (nz, ny, nx)]
    spec = {
        "driver": "zarr",
        "kvstore": {"driver": "file", "path": os.path.abspath(os.path.join(path, "0")) + "/"},
        "metadata": {
            "shape": [nz, ny, nx],
            "chunks": chunks,
            "dtype": dtype.newbyteorder("<").str,
            "fill_value": background,
            "order": "C",
            "dimension_separator": "/",
            "compressor": {"id": "blosc", "cname": "zstd", "clevel": 5, "shuffle": 1},
        },
    }
    store = ts.open(spec, create=True, context=ts.Context(context_spec())).result()
    # Whole chunks along z per slab (a multiple of 16, as the decoder's cells): no chunk is
    # written twice.
    thickness = max(16, -(-chunks[0] // 16) * 16)
    for z0 in range(0, nz, thickness):
        z1 = min(nz, z0 + thickness)
        slab = volume.to_numpy(axis_order="zyx", bounds=(0, nx - 1, 0, ny - 1, z0, z1 - 1))
        store[z0:z1].write(slab).result()
        if progress is not None:
            progress(z1 / nz)
    return _tree_bytes(path)
