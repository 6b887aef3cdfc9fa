#!/usr/bin/env python3
"""The browser viewer measured (issue 21): frame delivery, dragging, click to highlight, start-up
against the pyvista route, and the server's memory per browser, in one run.

Run from the repository root, under Xvfb, with Debian's chromium and chromedriver installed:

    xvfb-run -a -s "-screen 0 1024x768x24" .venv/bin/python bench/view.py [--quick]
        [--volume FILE] [--size 512] [--repeats 3] [--out DIR]

Rows (all in one run, on the same machine):

  encode-jpeg, encode-png   one 512x512 frame of the view (--size) encoded as the stream sends
                            it (JPEG, quality 70 while it changes, 92 once still: trame-rca's
                            PIL encoder) and as PNG (the screenshot's), milliseconds and bytes.
  frame-delivery            encode + send + receive of the streamed frames: the browser's
                            arrival time of each frame minus its server time stamp (trame-rca's
                            meta "st", taken as encoding starts), for the frames of a still,
                            refining view at --size.
  drag-fps                  frames per second arriving in the browser while a pointer drags
                            (orbit) for --drag seconds, moving every 16 ms (pointer events on the
                            image, as a 60 Hz mouse sends); the mapper keeps each frame to its
                            budget (the drag's update rate: coarser LOD, reduced resolution).
  click-to-highlight        from the click (the browser's click event) to the first frame
                            encoded after the pick was answered, which shows the highlight:
                            on a converged view, and on a view still refining (a still pass in
                            flight is finished first).
  first-image-view          `vtksvdag view FILE --no-browser` started as a new process, to the
                            first 3-D image shown in an already running chromium.
  first-image-pyvista       the pyvista route in a new process, as bench/startup.py's pyvista
                            scene: an off-screen Plotter of --size, add_segmentation(plotter,
                            FILE, spp=1) and plotter.screenshot(), to that image (one sample
                            per pixel, like the viewer's first frame).
  memory-per-browser        the server's resident memory (VmRSS) with 0, 1, 2 and 3 browser
                            tabs: the first takes the view made at start-up, each later one a
                            new view (plotter, mapper, device buffers).

Prints a table with the issue's targets (click <= 250 ms at 512x512 on lavapipe, drag >= 8 fps,
first image within 1.5x of pyvista's) and writes view.csv to --out (default bench/out).
--quick: examples/data/cells.nrrd at 128x128, one repeat, short drags (a smoke test).
"""
from __future__ import annotations

import argparse
import csv
import json
import pathlib
import shutil
import statistics
import subprocess
import sys
import time

import numpy as np

REPO = pathlib.Path(__file__).resolve().parents[1]
FIELDS = ["row", "repeat", "value", "unit", "detail"]

# The pyvista route's child, as bench/startup.py's pyvista scene: its first image is one sample
# per pixel, like the viewer's first frame. Prints the wall-clock time (time.time()) it has it.
PYVISTA_CHILD = r"""
import sys, time
import pyvista as pv
import vtksvdag
path, size = sys.argv[1], int(sys.argv[2])
plotter = pv.Plotter(off_screen=True, window_size=(size, size))
vtksvdag.add_segmentation(plotter, path, spp=1)
plotter.screenshot(return_img=True)
print(time.time(), flush=True)
plotter.close()
"""

# The browser side: records each streamed frame's arrival (Date.now()) and server stamp.
RECORDER = """
window.__frames = [];
const session = window.trame.client.getConnection().getSession();
session.subscribe('trame.rca.topic.stream', ([m]) => {
  if (m && m.meta) window.__frames.push([Date.now(), m.meta.st, m.content.length || m.content.byteLength || 0]);
});
"""


def browser():
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = shutil.which("chromium") or "/usr/bin/chromium"
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                "--window-size=1400,1000", "--force-device-scale-factor=1"):
        options.add_argument(arg)
    return webdriver.Chrome(service=Service(shutil.which("chromedriver") or "/usr/bin/chromedriver"),
                            options=options)


def serve(volume, size):
    command = [sys.executable, "-m", "vtksvdag", "view", str(volume), "--no-browser", "--json",
               "--size", f"{size}x{size}"]
    start = time.time()
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    line = process.stdout.readline()
    if not line.startswith("{"):
        process.kill()
        raise SystemExit(f"vtksvdag view printed no URL: {line!r}")
    return process, json.loads(line)["url"], start


def rss_mib(pid):
    for line in pathlib.Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return float("nan")


def image_shown(driver):
    """Whether the 3-D view shows a decoded, non-uniform frame."""
    return driver.execute_script("""
        const img = document.querySelector('[data-testid="svdag-view"] img');
        if (!img || !img.complete || !img.naturalWidth) return false;
        const c = document.createElement('canvas'); c.width = 32; c.height = 32;
        const g = c.getContext('2d'); g.drawImage(img, 0, 0, 32, 32);
        const d = g.getImageData(0, 0, 32, 32).data; let lo = 255, hi = 0;
        for (let i = 0; i < d.length; i += 4) { lo = Math.min(lo, d[i + 1]); hi = Math.max(hi, d[i + 1]); }
        return hi - lo > 30;""")


def wait(predicate, timeout=120, step=0.01, what="the viewer"):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = predicate()
        if value:
            return value
        time.sleep(step)
    raise SystemExit(f"timed out waiting for {what}")


def open_view(driver, url):
    driver.get(url)
    wait(lambda: image_shown(driver))
    driver.execute_script(RECORDER)


def frames(driver):
    return driver.execute_script("return window.__frames.splice(0)")


def encode_rows(volume_path, size, repeats):
    """Encoding one frame as the stream (JPEG) and the screenshot (PNG) do, in this process."""
    import vtksvdag
    from trame_rca.encoders import RcaImageEncoder
    from vtksvdag.viewer.app import INTERACTIVE_QUALITY, STILL_QUALITY
    from vtksvdag.viewer.session import ViewSession, png_data_url

    session = ViewSession(vtksvdag.read(str(volume_path)), size=(size, size))
    for _ in range(4):
        image, cols, rows = session.img_cols_rows
    encoder = RcaImageEncoder("jpeg")
    rows_out = []
    for quality in (INTERACTIVE_QUALITY, STILL_QUALITY):
        times, sizes = [], []
        for _ in range(repeats * 5):
            t = time.perf_counter()
            content, _, _ = encoder.encode(image, cols, rows, quality)
            times.append((time.perf_counter() - t) * 1000)
            sizes.append(len(content))
        rows_out.append(("encode-jpeg", statistics.median(times), "ms",
                         f"quality {quality}, {statistics.median(sizes) / 1024:.0f} KiB"))
    times = []
    for _ in range(repeats * 2):
        t = time.perf_counter()
        url = png_data_url(image)
        times.append((time.perf_counter() - t) * 1000)
    rows_out.append(("encode-png", statistics.median(times), "ms", f"{len(url) * 3 / 4 / 1024:.0f} KiB"))
    session.close()
    return rows_out


def click_to_highlight(driver, converged):
    """ms from a click in the middle of the view to the first frame encoded after the pick was
    answered (the answer carries the server's time, the frames their encoding's)."""
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By

    if converged:
        # Converged: the stream has gone quiet.
        wait(lambda: (time.sleep(1.5), not frames(driver))[1], timeout=600, step=0,
             what="the view to converge")
    view = driver.find_element(By.CSS_SELECTOR, '[data-testid="svdag-view"]')
    driver.execute_script("""
        window.__click = null;
        arguments[0].addEventListener('click', () => { window.__click = Date.now(); },
                                      {once: true, capture: true});""", view)
    previous = driver.execute_script("const s = window.trame.state.get('selected'); return s.server_ms || 0")
    frames(driver)
    ActionChains(driver).move_to_element(view).click().perform()
    answered = wait(lambda: driver.execute_script(
        "const s = window.trame.state.get('selected'); return s.server_ms > arguments[0] && s.server_ms",
        previous), what="the pick's answer")
    arrived = wait(lambda: [f for f in driver.execute_script("return window.__frames") if f[1] >= answered],
                   what="the highlighted frame")
    clicked = driver.execute_script("return window.__click")
    frames(driver)
    return arrived[0][0] - clicked


def drag_fps(driver, seconds):
    """Frames per second arriving while a pointer drags across the view for ``seconds``, its
    moves sent every 16 ms (a 60 Hz mouse) as pointer events on the image."""
    frames(driver)
    return driver.execute_async_script("""
        const [seconds, done] = [arguments[0], arguments[arguments.length - 1]];
        const target = document.querySelector('[data-testid="svdag-view"] .remote-controlled-area');
        const r = target.getBoundingClientRect();
        const at = (x) => ({clientX: r.left + x, clientY: r.top + r.height / 2, pointerId: 1,
                            pointerType: 'mouse', isPrimary: true, buttons: 1, button: 0,
                            bubbles: true});
        let x = r.width / 2, dx = 4;
        target.dispatchEvent(new PointerEvent('pointerdown', at(x)));
        const start = Date.now();
        const timer = setInterval(() => {
          if (x > r.width * 0.8 || x < r.width * 0.2) dx = -dx;
          x += dx;
          target.dispatchEvent(new PointerEvent('pointermove', at(x)));
          if (Date.now() - start > seconds * 1000) {
            clearInterval(timer);
            const duration = (Date.now() - start) / 1000;
            const count = window.__frames.filter(f => f[0] >= start).length;
            target.dispatchEvent(new PointerEvent('pointerup', {...at(x), buttons: 0}));
            done([count / duration, count, duration]);
          }
        }, 16);""", seconds)


def first_image_pyvista(volume, size):
    start = time.time()
    out = subprocess.run([sys.executable, "-c", PYVISTA_CHILD, str(volume), str(size)],
                         capture_output=True, text=True, check=True).stdout
    return float(out.strip().splitlines()[-1]) - start


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--volume", default=str(REPO / "examples" / "data" / "cells.nrrd"))
    parser.add_argument("--size", type=int, default=512)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--drag", type=float, default=5.0, help="seconds of dragging")
    parser.add_argument("--out", default=str(REPO / "bench" / "out"))
    args = parser.parse_args(argv)
    if args.quick:
        args.size, args.repeats, args.drag = 128, 1, 1.5
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    results = []

    def add(row, repeat, value, unit, detail=""):
        results.append({"row": row, "repeat": repeat, "value": round(float(value), 2), "unit": unit,
                        "detail": detail})

    for row, value, unit, detail in encode_rows(args.volume, args.size, args.repeats):
        add(row, 0, value, unit, f"{args.size}x{args.size}, {detail}")

    driver = browser()
    try:
        for repeat in range(args.repeats):
            # Start-up: the two routes alternate, so both see the same machine.
            driver.get("about:blank")
            process, url, started = serve(args.volume, args.size)
            try:
                driver.get(url)
                wait(lambda: image_shown(driver))
                add("first-image-view", repeat, time.time() - started, "s")
                add("first-image-pyvista", repeat, first_image_pyvista(args.volume, args.size), "s")
                driver.execute_script(RECORDER)
                # Frame delivery while the still view refines: a change of LOD restarts it.
                frames(driver)
                driver.execute_script("window.trame.trigger('svdag_option', ['lod', 'voxel'])")
                wait(lambda: len(driver.execute_script("return window.__frames")) >= 8, timeout=300,
                     what="refining frames")
                latencies = [f[0] - f[1] for f in frames(driver)]
                add("frame-delivery", repeat, statistics.median(latencies), "ms",
                    f"median of {len(latencies)} frames, {args.size}x{args.size}")
                add("click-to-highlight", repeat, click_to_highlight(driver, False), "ms",
                    "view still refining")
                add("click-to-highlight", repeat, click_to_highlight(driver, True), "ms",
                    "view converged")
                fps, count, duration = drag_fps(driver, args.drag)
                add("drag-fps", repeat, fps, "fps", f"{count} frames in {duration:.1f} s")
                if repeat == 0:
                    memory = [rss_mib(process.pid)]
                    driver.get("about:blank")
                    time.sleep(2)
                    memory[0] = rss_mib(process.pid)
                    handles = [driver.current_window_handle]
                    open_view(driver, url)
                    memory.append(rss_mib(process.pid))
                    for _ in range(2):
                        driver.switch_to.new_window("tab")
                        handles.append(driver.current_window_handle)
                        open_view(driver, url)
                        memory.append(rss_mib(process.pid))
                    for n, mib in enumerate(memory):
                        add("memory-server", 0, mib, "MiB", f"{n} browsers")
                    for n in range(1, len(memory)):
                        add("memory-per-browser", 0, memory[n] - memory[n - 1], "MiB",
                            f"browser {n}" + (" (the view made at start-up)" if n == 1 else ""))
                    for handle in handles[1:]:
                        driver.switch_to.window(handle)
                        driver.close()
                    driver.switch_to.window(handles[0])
            finally:
                process.terminate()
                process.wait(20)
    finally:
        driver.quit()

    with open(out / "view.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=FIELDS)
        writer.writeheader()
        writer.writerows(results)

    def median(row, detail=None):
        values = [r["value"] for r in results if r["row"] == row and (detail is None or detail in r["detail"])]
        return statistics.median(values) if values else float("nan")

    print(f"viewer, {pathlib.Path(args.volume).name}, {args.size}x{args.size}, {args.repeats} repeats (medians)")
    print(f"{'row':34} {'value':>10}  unit  detail")
    seen = set()
    for r in results:
        key = (r["row"], r["detail"] if r["row"].startswith(("memory", "encode", "click")) else "")
        if key in seen:
            continue
        seen.add(key)
        value = median(r["row"], r["detail"] if key[1] else None)
        print(f"{r['row']:34} {value:10.2f}  {r['unit']:4}  {r['detail'] if key[1] else ''}")
    view, pyvista = median("first-image-view"), median("first-image-pyvista")
    print(f"\ntargets: click-to-highlight (converged) {median('click-to-highlight', 'converged'):.0f} ms "
          f"(<= 250), drag {median('drag-fps'):.1f} fps (>= 8), first image view / pyvista "
          f"{view / pyvista:.2f}x (<= 1.5)")
    print(f"wrote {out / 'view.csv'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
