"""Volcanite 0.6 (Piochowiak and Dachsbacher's segmentation volume renderer, TVCG 2024; not a
dependency of this project) run beside ours by bench/render.py: its input file, its view, its
median frame time.

Volcanite reads NRRD only as `NRRD0004` with raw encoding and unsigned little-endian labels, so
each volume is written that way once (write_input), compressed once to its CSGV form
(COMPRESS_COMMAND), and rendered headless for a number of frames of one still view
(DEFAULT_COMMAND) with its own evaluation log, whose median frame time is the figure (the first
frames decode its bricks into the cache and the first one also compiles its shaders).
"""
from __future__ import annotations

import pathlib
import re
import shlex
import subprocess

import numpy as np

# Volcanite skips devices named llvmpipe unless VOLCANITE_DEVICE picks one; -i makes its headless
# mode render (the image is written after the timed frames). Its a-trous post-process, on by
# default, is switched off: ours is timed without its denoiser (on lavapipe the post-process took
# 4 of 24.8 ms a frame of em_like512 at 256^2, 13 of 120 at 512^2, 12 of 39 on voronoi256).
DEFAULT_COMMAND = ('VOLCANITE_DEVICE=0 {binary} --headless -r {width}x{height} -i {image} '
                   '--config "[Display] Accumulation Frames: {frames};'
                   '[Development] Enable_\u00c0-Trous_Post-Processing: 0" '
                   '--eval-logfiles {log} {volume}')
COMPRESS_COMMAND = "VOLCANITE_DEVICE=0 {binary} --headless -c {csgv} {volume}"

# Volcanite's default view (an orbit around the volume's center: elevation 0.5 rad, azimuth
# 4 rad, 1.5 of the longest side away, a vertical field of view of 0.33 pi) as this project's
# ResetCamera(azimuth, elevation, zoom) after SetCameraViewAngle (anchors.md: the view matched
# image against image on 2026-12-02).
CAMERA = {"azimuth": -139.18, "elevation": 28.648, "zoom": 1.1653, "view_angle": 59.4}


def write_input(labels_zyx: np.ndarray, path: pathlib.Path) -> pathlib.Path:
    """The labels, (z, y, x) with x fastest, as the NRRD Volcanite reads. Signed labels keep
    their bit patterns as the unsigned type of their size (a label stays one label)."""
    labels = np.ascontiguousarray(labels_zyx)
    if labels.dtype.kind == "i":
        labels = labels.view(np.dtype(f"u{labels.dtype.itemsize}"))
    labels = labels.astype(labels.dtype.newbyteorder("<"), copy=False)
    z, y, x = labels.shape
    header = (f"NRRD0004\ntype: uint{8 * labels.dtype.itemsize}\ndimension: 3\n"
              f"sizes: {x} {y} {z}\nencoding: raw\nendian: little\n\n")
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "wb") as f:
        f.write(header.encode())
        f.write(labels.tobytes(order="C"))
    return path


def _run(command: str, what: str, timeout: float) -> str:
    run = subprocess.run(command, shell=True, capture_output=True, text=True, timeout=timeout)
    if run.returncode != 0:
        raise RuntimeError(f"Volcanite {what} failed (exit {run.returncode}; command: {command}):\n"
                           f"{(run.stdout + run.stderr)[-2000:]}")
    return run.stdout + run.stderr


def compress(binary: str, nrrd: pathlib.Path) -> pathlib.Path:
    """The CSGV file of `nrrd` beside it (made once)."""
    csgv = nrrd.with_suffix(".csgv")
    if not csgv.is_file():
        _run(COMPRESS_COMMAND.format(binary=shlex.quote(binary), csgv=shlex.quote(str(csgv)),
                                     volume=shlex.quote(str(nrrd))), "compression", 3600)
    return csgv


def frame_ms(binary: str, template: str, volume: pathlib.Path, width: int, height: int,
             frames: int, work: pathlib.Path) -> float:
    """Volcanite's median frame time in ms over `frames` frames of its default view: its
    evaluation log's median, or, for a template without {log}, the last "<n> ms" it prints."""
    work.mkdir(parents=True, exist_ok=True)
    log = work / "volcanite_eval.txt"
    log.write_text("#fmt:median_ms={frame_med_ms}\n")
    output = _run(template.format(binary=shlex.quote(binary), width=width, height=height,
                                  frames=frames, image=shlex.quote(str(work / "volcanite.png")),
                                  log=shlex.quote(str(log)), volume=shlex.quote(str(volume))),
                  "rendering", 900)
    # The format line has no number after "median_ms=": a log no run wrote finds nothing.
    found = (re.findall(r"median_ms=([0-9.]+)", log.read_text())
             or re.findall(r"([0-9]+(?:\.[0-9]+)?)\s*ms", output))
    if not found:
        raise RuntimeError(f"Volcanite printed no frame time:\n{output[-2000:]}")
    return float(found[-1])
