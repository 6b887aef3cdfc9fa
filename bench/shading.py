#!/usr/bin/env python3
"""Smooth shading benchmark: normal accuracy against analytic normals, and its frame-time cost.

Run from the repository root (the picture needs an X display for VTK's OpenGL mesh render):

    xvfb-run -a .venv/bin/python bench/shading.py [--quick] [--out bench/out] [--picture docs/smooth_shading.png]

1. Accuracy: voxelized spheres and tubes (cylinders along z, through the whole volume) of radius
   4, 8, 16, 32 and 64 voxels, centers off the voxel grid. On the primary hits of a 512 x 512
   view (azimuth 30, elevation 20, framing the volume) the angle between the analytic normal
   (of the sphere or tube at the hit point) and (a) the entry face normal, (b) the smooth normal
   from the renderer's Normal output (Shading smooth, GPU) and (c) the CPU ray caster's
   GetHitShadingNormal on every 4th hit pixel's ray: mean and 95th percentile, degrees. Tube
   hits within 4 voxels of the volume's z ends are left out (there the tube is cut).
2. Cost: path-traced frames (1 sample per pixel, 4 bounces, NEE, sun) at 512 x 512: two
   renderers on the same volume, one voxel and one smooth shading, frames alternated (warm-up
   first), the median of --frames accumulation frames each; the ratio smooth / voxel. Also on
   ../shared/data/voronoi256.nrrd when it is there. The smooth renderer's neighbour table bytes.
3. The picture: examples/data/cells.nrrd, the same view path-traced with voxel shading, with
   smooth shading, and VTK's meshing route (vtkDiscreteFlyingEdges3D of every label, the
   surface drawn by VTK with Phong shading), side by side.

Prints a table, writes shading.csv to the output folder.
"""
from __future__ import annotations

import argparse
import csv
import os
import pathlib
import statistics
import sys
import time

import numpy as np

REPO = pathlib.Path(__file__).resolve().parents[1]
SHARED_DATA = pathlib.Path(os.environ.get("VTKSVDAG_SHARED_DATA") or REPO.parent / "shared" / "data")
COLUMNS = [
    "shape", "radius", "hits", "face_mean_deg", "face_p95_deg", "gpu_smooth_mean_deg",
    "gpu_smooth_p95_deg", "cpu_smooth_mean_deg", "cpu_smooth_p95_deg", "cpu_rays",
    "gpu_cpu_max_deg", "ratio_mean", "voxel_ms", "smooth_ms", "time_ratio",
    "neighbour_table_bytes", "blocks", "volume_bytes",
]


def shape_volume(shape, radius):
    """(z, y, x) labels of a sphere or a z tube, and the analytic normal function (index space)."""
    margin = 6
    n = int(2 * radius + 2 * margin)
    center = np.array([n / 2 + 0.31, n / 2 - 0.23, n / 2 + 0.17])
    if shape == "sphere":
        dims = (n, n, n)
    else:
        dims = (max(24, int(1.5 * radius)), n, n)  # z, y, x
    z, y, x = np.indices(dims, dtype=np.float32) + 0.5
    d2 = (x - center[0]) ** 2 + (y - center[1]) ** 2
    if shape == "sphere":
        d2 = d2 + (z - center[2]) ** 2
    labels = (d2 <= radius ** 2).astype(np.uint8)

    def normals(points):
        v = points - center
        if shape == "tube":
            v[:, 2] = 0
        return v / np.linalg.norm(v, axis=1, keepdims=True)

    def usable(points):
        if shape == "sphere":
            return np.ones(len(points), bool)
        return (points[:, 2] > 4) & (points[:, 2] < dims[0] - 4)

    return labels, normals, usable


def angles(a, b):
    return np.degrees(np.arccos(np.clip(np.sum(a * b, axis=1), -1.0, 1.0)))


def make_renderer(volume, size, shading, bounces=0, sun=False):
    from vtksvdag.vtkSVDAGRendering import vtkSegmentationSVDAGRenderer

    r = vtkSegmentationSVDAGRenderer()
    r.SetInputData(volume)
    r.SetWidth(size)
    r.SetHeight(size)
    s = r.GetSettings()
    s.SetShading(shading)
    s.SetMaximumBounces(bounces)
    s.SetSamplesPerPixel(1)
    if sun:
        s.SunOn()
        s.SetSunDirection(0.4, -0.5, 0.77)
        s.SetEnvironmentColor(0.25, 0.27, 0.3)
    return r


def pixel_rays(renderer):
    sys.path.insert(0, str(REPO / "Testing" / "Python"))
    from conftest import primary_rays

    return primary_rays(renderer)


def frame_times(volume, size, frames, view):
    """Median ms of accumulation frames, voxel and smooth shading, alternated; table bytes."""
    renderers = [make_renderer(volume, size, shading, bounces=4, sun=True) for shading in (0, 1)]
    for r in renderers:
        assert r.ResetCamera(*view) == 1
        r.Render()  # warm-up: shader compilation, BVH, the neighbour table
        r.Render()
    times = ([], [])
    for _ in range(frames):
        for i, r in enumerate(renderers):
            r.Render()
            times[i].append(r.GetLastFrameMilliseconds())
    return (statistics.median(times[0]), statistics.median(times[1]),
            renderers[1].GetNeighbourTableBytes())


def accuracy_row(shape, radius, size, frames):
    from vtkmodules.util.numpy_support import vtk_to_numpy

    from vtksvdag.vtkSVDAGCore import vtkSegmentationSVDAGRayCaster

    sys.path.insert(0, str(REPO / "Testing" / "Python"))
    from conftest import compress_zyx

    labels, normals, usable = shape_volume(shape, radius)
    volume = compress_zyx(labels)
    view = (30.0, 20.0, 1.0)
    r = make_renderer(volume, size, 1)
    assert r.ResetCamera(*view) == 1
    assert r.Render() == 1
    data = r.GetOutput().GetPointData()
    label = vtk_to_numpy(data.GetArray("Label"))
    depth = vtk_to_numpy(data.GetArray("Depth")).astype(np.float64)
    smooth = vtk_to_numpy(data.GetArray("Normal")).astype(np.float64)
    face = vtk_to_numpy(data.GetArray("FaceNormal")).astype(np.float64)
    origin, dirs = pixel_rays(r)
    points = origin + depth[:, None] * dirs + 0.5  # index space (origin 0, spacing 1)
    hit = np.nonzero(label > 0)[0]
    hit = hit[usable(points[hit])]
    truth = normals(points[hit])
    face_err = angles(face[hit], truth)
    gpu_err = angles(smooth[hit], truth)

    caster = vtkSegmentationSVDAGRayCaster()
    caster.SetInputData(volume)
    sample = hit[::4]
    cpu = np.zeros((len(sample), 3))
    for k, i in enumerate(sample):
        caster.CastRay(origin, dirs[i])
        cpu[k] = caster.GetHitShadingNormal()
    cpu_err = angles(cpu, normals(points[sample]))
    gpu_cpu = angles(cpu, smooth[sample])

    voxel_ms, smooth_ms, table = frame_times(volume, size, frames, view)
    blocks = volume.GetNumberOfBlocks()
    return {
        "shape": shape, "radius": radius, "hits": len(hit),
        "face_mean_deg": face_err.mean(), "face_p95_deg": np.percentile(face_err, 95),
        "gpu_smooth_mean_deg": gpu_err.mean(), "gpu_smooth_p95_deg": np.percentile(gpu_err, 95),
        "cpu_smooth_mean_deg": cpu_err.mean(), "cpu_smooth_p95_deg": np.percentile(cpu_err, 95),
        "cpu_rays": len(sample), "gpu_cpu_max_deg": gpu_cpu.max(),
        "ratio_mean": gpu_err.mean() / face_err.mean(),
        "voxel_ms": voxel_ms, "smooth_ms": smooth_ms, "time_ratio": smooth_ms / voxel_ms,
        "neighbour_table_bytes": table, "blocks": blocks, "volume_bytes": volume_bytes(volume),
    }


def volume_bytes(volume):
    """Blocks + DAG + label table: what the renderer uploads besides its BVH."""
    return int(volume.GetBlocksMemorySize() + volume.GetDAGMemorySize() +
               volume.GetLabelTableMemorySize())


def real_row(name, size, frames):
    from vtksvdag import read

    path = SHARED_DATA / f"{name}.nrrd"
    if not path.exists():
        return None
    seg = read(str(path))
    voxel_ms, smooth_ms, table = frame_times(seg.dataobject, size, frames, (30.0, 20.0, 1.0))
    return {"shape": name, "radius": "", "blocks": seg.dataobject.GetNumberOfBlocks(), "voxel_ms": voxel_ms, "smooth_ms": smooth_ms,
            "time_ratio": smooth_ms / voxel_ms, "neighbour_table_bytes": table,
            "volume_bytes": volume_bytes(seg.dataobject)}


def picture(path, size, spp):
    """voxel | smooth | flying-edges mesh of examples/data/cells.nrrd, one PNG."""
    import nrrd
    from PIL import Image, ImageDraw
    from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
    from vtkmodules.vtkCommonDataModel import vtkImageData
    from vtkmodules.vtkFiltersGeneral import vtkDiscreteFlyingEdges3D
    import vtkmodules.vtkRenderingOpenGL2  # noqa: F401
    from vtkmodules.vtkRenderingCore import (vtkActor, vtkPolyDataMapper, vtkRenderer,
                                             vtkRenderWindow, vtkWindowToImageFilter, vtkLight)
    from vtkmodules.vtkCommonCore import vtkLookupTable

    sys.path.insert(0, str(REPO / "Testing" / "Python"))
    from conftest import compress_zyx

    labels_xyz, _ = nrrd.read(str(REPO / "examples" / "data" / "cells.nrrd"))
    zyx = np.ascontiguousarray(labels_xyz.transpose(2, 1, 0))
    volume = compress_zyx(zyx)
    view = (35.0, 25.0, 1.25)
    panels = []
    camera = None
    for shading in (0, 1):
        r = make_renderer(volume, size, shading, bounces=3, sun=True)
        assert r.ResetCamera(*view) == 1
        for _ in range(spp):
            r.Render()
        image = vtk_to_numpy(r.GetOutput().GetPointData().GetArray("Color")).reshape(size, size, 4)
        panels.append(image[::-1, :, :3].copy())  # bottom row first -> top row first
        camera = (r.GetCameraPosition(), r.GetCameraFocalPoint(), r.GetCameraViewUp(),
                  r.GetCameraViewAngle())

    # VTK's meshing route: one discrete flying-edges surface per label, in the renderer's default
    # label colors, drawn by OpenGL with the same camera. The label grid's point i is at world
    # i - 0.5 like the renderer's voxel centers (index space = world + 0.5).
    image = vtkImageData()
    image.SetDimensions(zyx.shape[2], zyx.shape[1], zyx.shape[0])
    image.SetOrigin(0.0, 0.0, 0.0)  # compress_zyx's origin: voxel centers at world i
    image.GetPointData().SetScalars(numpy_to_vtk(zyx.ravel(), deep=True))
    values = [int(v) for v in np.unique(zyx) if v != 0]
    flying = vtkDiscreteFlyingEdges3D()
    flying.SetInputData(image)
    for i, v in enumerate(values):
        flying.SetValue(i, v)
    flying.ComputeNormalsOn()
    flying.Update()
    lut = vtkLookupTable()
    lut.SetNumberOfTableValues(len(values))
    for i in range(len(values)):
        lut.SetTableValue(i, *label_color(i), 1.0)
    lut.SetTableRange(0, len(values) - 1)
    lut.Build()
    index_of = {v: i for i, v in enumerate(values)}
    scalars = vtk_to_numpy(flying.GetOutput().GetPointData().GetScalars())
    indices = np.array([index_of.get(int(s), 0) for s in scalars], np.float32)
    flying.GetOutput().GetPointData().SetScalars(numpy_to_vtk(indices, deep=True))
    mapper = vtkPolyDataMapper()
    mapper.SetInputData(flying.GetOutput())
    mapper.SetLookupTable(lut)
    mapper.SetScalarRange(0, len(values) - 1)
    actor = vtkActor()
    actor.SetMapper(mapper)
    actor.GetProperty().SetInterpolationToPhong()
    renderer = vtkRenderer()
    renderer.AddActor(actor)
    renderer.SetBackground(0.34, 0.34, 0.36)  # the path tracer's background after its tone curve
    window = vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.SetSize(size, size)
    window.AddRenderer(renderer)
    cam = renderer.GetActiveCamera()
    position, focal, up, angle = camera
    cam.SetPosition(*position)
    cam.SetFocalPoint(*focal)
    cam.SetViewUp(*up)
    cam.SetViewAngle(angle)
    renderer.ResetCameraClippingRange()
    headlight = vtkLight()
    headlight.SetLightTypeToHeadlight()
    headlight.SetIntensity(0.5)
    renderer.AddLight(headlight)
    light = vtkLight()  # the path tracer's sun direction
    light.SetLightTypeToSceneLight()
    light.SetPosition(0.4 * 1000, -0.5 * 1000, 0.77 * 1000)
    light.SetFocalPoint(0, 0, 0)
    light.SetIntensity(0.7)
    renderer.AddLight(light)
    window.Render()
    grab = vtkWindowToImageFilter()
    grab.SetInput(window)
    grab.Update()
    mesh = vtk_to_numpy(grab.GetOutput().GetPointData().GetScalars()).reshape(size, size, -1)
    panels.append(mesh[::-1, :, :3].copy())
    triangles = flying.GetOutput().GetNumberOfCells()

    gap = 6
    canvas = Image.new("RGB", (3 * size + 2 * gap, size + 28), (255, 255, 255))
    draw = ImageDraw.Draw(canvas)
    titles = ("SVDAG, voxel shading", "SVDAG, smooth shading (no mesh)",
              f"vtkDiscreteFlyingEdges3D mesh ({triangles:,} triangles)")
    for k, (panel, title) in enumerate(zip(panels, titles)):
        canvas.paste(Image.fromarray(panel.astype(np.uint8)), (k * (size + gap), 28))
        draw.text((k * (size + gap) + 6, 8), title, fill=(0, 0, 0))
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    canvas.save(path)
    return path, triangles


def label_color(index):
    """GpuLayout.h's svdagLabelColor: the renderer's default base color of a label index (linear
    RGB, shown here as display values: close enough for a side-by-side look)."""
    x = index & 0xFFFFFFFF
    x ^= x >> 16
    x = (x * 0x7FEB352D) & 0xFFFFFFFF
    x ^= x >> 15
    x = (x * 0x846CA68B) & 0xFFFFFFFF
    x ^= x >> 16
    c = np.array([x & 255, (x >> 8) & 255, (x >> 16) & 255]) / 255.0
    return tuple(float(v) ** (1 / 2.2) for v in 0.15 + 0.8 * c)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="small sizes (a smoke test)")
    parser.add_argument("--out", default=str(REPO / "bench" / "out"))
    parser.add_argument("--frames", type=int, default=7)
    parser.add_argument("--picture", default=str(REPO / "docs" / "smooth_shading.png"),
                        help="the side-by-side PNG ('' for none)")
    args = parser.parse_args(argv)
    size = 128 if args.quick else 512
    radii = (4, 8) if args.quick else (4, 8, 16, 32, 64)
    frames = 2 if args.quick else args.frames

    rows = []
    for shape in ("sphere", "tube"):
        for radius in radii:
            start = time.perf_counter()
            rows.append(accuracy_row(shape, radius, size, frames))
            print(f"  {shape} r={radius}: {time.perf_counter() - start:.1f} s", file=sys.stderr)
    if not args.quick:
        for name in ("voronoi256",):
            row = real_row(name, size, frames)
            if row:
                rows.append(row)

    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "shading.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=COLUMNS)
        writer.writeheader()
        for row in rows:
            writer.writerow({k: row.get(k, "") for k in COLUMNS})

    header = (f"{'shape':<11}{'r':>4}{'hits':>8} | {'face mean/p95':>14} | {'GPU smooth':>12} | "
              f"{'CPU smooth':>12} | {'smooth/face':>11} | {'GPU-CPU max':>11} | "
              f"{'voxel ms':>9}{'smooth ms':>10}{'ratio':>7} | {'table B':>9}")
    print(f"Smooth shading, {size} x {size}, lavapipe or the device below; angles in degrees")
    print(header)
    print("-" * len(header))
    for r in rows:
        if r.get("radius", "") == "":
            print(f"{r['shape']:<11}{'':>4}{'':>8} | {'':>14} | {'':>12} | {'':>12} | {'':>11} | "
                  f"{'':>11} | {r['voxel_ms']:9.1f}{r['smooth_ms']:10.1f}{r['time_ratio']:7.2f} | "
                  f"{r['neighbour_table_bytes']:9,}")
            continue
        print(f"{r['shape']:<11}{r['radius']:>4}{r['hits']:>8} | "
              f"{r['face_mean_deg']:6.1f} /{r['face_p95_deg']:5.1f}  | "
              f"{r['gpu_smooth_mean_deg']:5.1f} /{r['gpu_smooth_p95_deg']:5.1f} | "
              f"{r['cpu_smooth_mean_deg']:5.1f} /{r['cpu_smooth_p95_deg']:5.1f} | "
              f"{r['ratio_mean']:11.3f} | {r['gpu_cpu_max_deg']:11.4f} | "
              f"{r['voxel_ms']:9.1f}{r['smooth_ms']:10.1f}{r['time_ratio']:7.2f} | "
              f"{r['neighbour_table_bytes']:9,}")
    print(f"wrote {out / 'shading.csv'}")
    if args.picture:
        path, triangles = picture(args.picture, 256 if args.quick else 512, 4 if args.quick else 64)
        print(f"wrote {path} (mesh: {triangles:,} triangles)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
