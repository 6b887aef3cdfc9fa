"""The browser viewer (``vtksvdag view``) in a real headless chromium (Debian's, through selenium
and chromedriver): the 3-D image, picking against :func:`vtksvdag.pick` on the same view, search
and hide, orbiting, separate views per browser, and the token rules beyond loopback.

The reference for every pick is an independent pyvista plotter in this process, set to the
camera and size the server reports for the click.
"""
import io
import json
import os
import re
import shutil
import subprocess
import sys
import time
import urllib.error
import urllib.request

import numpy as np
import pytest

from conftest import REPO

pytest.importorskip("trame", reason="the viewer extra (pip install .[viewer]) is not installed")
pytest.importorskip("trame_rca", reason="the viewer extra (pip install .[viewer]) is not installed")
webdriver = pytest.importorskip("selenium.webdriver", reason="selenium is not installed")
from PIL import Image  # noqa: E402
from selenium.webdriver.chrome.service import Service  # noqa: E402
from selenium.webdriver.common.action_chains import ActionChains  # noqa: E402
from selenium.webdriver.common.by import By  # noqa: E402
from selenium.webdriver.common.keys import Keys  # noqa: E402
from selenium.webdriver.support.ui import WebDriverWait  # noqa: E402

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
CHROMEDRIVER = shutil.which("chromedriver") or "/usr/bin/chromedriver"
DATA = REPO / "examples" / "data" / "cells.nrrd"
SIZE = (256, 192)
TIMEOUT = 60


def _require_chromium():
    missing = [p for p in (CHROMIUM, CHROMEDRIVER) if not os.access(p, os.X_OK)]
    if missing:
        # scripts/install-deps.sh installs both (Debian's chromium and chromium-driver).
        pytest.skip(f"headless chromium is not installed ({', '.join(missing)} missing; "
                    "scripts/install-deps.sh installs chromium and chromium-driver)")


def _serve(*extra):
    """Start `vtksvdag view` and return (process, url) once it printed its URL."""
    command = [sys.executable, "-m", "vtksvdag", "view", str(DATA), "--no-browser", "--json",
               "--size", f"{SIZE[0]}x{SIZE[1]}", *extra]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + TIMEOUT
    while time.monotonic() < deadline:
        line = process.stdout.readline()
        if line.startswith("{"):
            return process, json.loads(line)["url"]
        if process.poll() is not None:
            raise AssertionError(f"vtksvdag view exited: {process.stderr.read()}")
    process.kill()
    raise AssertionError("vtksvdag view printed no URL")


def _stop(process):
    process.terminate()
    try:
        process.wait(10)
    except subprocess.TimeoutExpired:
        process.kill()


@pytest.fixture(scope="module")
def server():
    _require_chromium()
    process, url = _serve()
    yield url
    _stop(process)


@pytest.fixture(scope="module")
def browser():
    _require_chromium()
    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                "--window-size=1100,700", "--force-device-scale-factor=1"):
        options.add_argument(arg)
    driver = webdriver.Chrome(service=Service(CHROMEDRIVER), options=options)
    yield driver
    driver.quit()


def _by_id(driver, testid):
    return driver.find_element(By.CSS_SELECTOR, f'[data-testid="{testid}"]')


def _view_pixels(driver):
    """The 3-D image as the page shows it (the element's screenshot), RGB."""
    png = _by_id(driver, "svdag-view").screenshot_as_png
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), dtype=np.int16)


def _wait_for_image(driver, differs_from=None):
    """Wait for a non-uniform 3-D image (and, given one, one that differs from it)."""
    def ready(_):
        img = driver.find_elements(By.CSS_SELECTOR, '[data-testid="svdag-view"] img[src^="blob:"]')
        if not img:
            return False
        pixels = _view_pixels(driver)
        if pixels.std() < 10 or len(np.unique(pixels.reshape(-1, 3), axis=0)) < 50:
            return False
        return differs_from is None or np.abs(pixels - differs_from).mean() > 4
    WebDriverWait(driver, TIMEOUT, poll_frequency=0.5).until(ready)
    return _view_pixels(driver)


def _open(driver, url):
    driver.get(url)
    return _wait_for_image(driver)


def _selected(driver, previous=None):
    """Wait for the selection to change from ``previous`` (the data-x/y/camera of a new pick)
    and return (label text, pick details)."""
    def changed(_):
        # One read of all four, so that no answer lands between them.
        state = tuple(driver.execute_script("""
            const e = document.querySelector('[data-testid="svdag-selected-label"]');
            return [e.textContent.trim(), e.getAttribute('data-camera'), e.getAttribute('data-x'),
                    e.getAttribute('data-y')];"""))
        return state if state[1] and state != previous else False
    state = WebDriverWait(driver, TIMEOUT, poll_frequency=0.2).until(changed)
    return state


def _click_view(driver, x, y):
    """Click the 3-D image at (x, y) pixels from its top left."""
    view = _by_id(driver, "svdag-view")
    width, height = view.size["width"], view.size["height"]
    ActionChains(driver).move_to_element_with_offset(view, x - width // 2, y - height // 2).click().perform()


def _reference_pick(state, hidden=()):
    """vtksvdag.pick on an independent plotter at the camera and size of the server's pick."""
    import pyvista as pv

    import vtksvdag

    camera = json.loads(state[1])
    plotter = pv.Plotter(off_screen=True, window_size=tuple(camera["size"]))
    actor = vtksvdag.add_segmentation(plotter, str(DATA))
    actor.GetMapper().SetRefineStillRenders(False)
    if hidden:
        actor.hide(list(hidden))
    plotter._on_first_render_request()
    vtk_camera = plotter.renderer.GetActiveCamera()
    vtk_camera.SetPosition(*camera["position"])
    vtk_camera.SetFocalPoint(*camera["focal_point"])
    vtk_camera.SetViewUp(*camera["view_up"])
    vtk_camera.SetViewAngle(camera["view_angle"])
    plotter.renderer.ResetCameraClippingRange()
    plotter.render()
    hit = vtksvdag.pick(plotter, float(state[2]), float(state[3]))
    plotter.close()
    return None if hit is None else hit["label"]


def _assert_row_selected(driver, label):
    """The label's row of the segment list is the one marked selected."""
    selected = lambda: [e.get_attribute("data-label") for e in driver.find_elements(  # noqa: E731
        By.CSS_SELECTOR, '[data-testid="svdag-segment-list"] > .svdag-row-selected')]
    try:
        WebDriverWait(driver, 10).until(lambda _: selected() == [label])
    except Exception:
        raise AssertionError(f"rows marked selected: {selected()}, expected [{label}]; selected "
                             f"label shown: {_by_id(driver, 'svdag-selected-label').text!r}") from None


def _find_label_pixel(driver):
    """Click near the image's center until a label is selected; return (x, y, state)."""
    previous = None
    for x, y in ((SIZE[0] // 2, SIZE[1] // 2), (SIZE[0] // 2 - 20, SIZE[1] // 2), (SIZE[0] // 2, SIZE[1] // 2 + 15)):
        _click_view(driver, x, y)
        previous = _selected(driver, previous)
        if previous[0]:
            return x, y, previous
    raise AssertionError("no label under the image's center")


def test_page_shows_the_volume_and_segment_list(server, browser):
    pixels = _open(browser, server)
    # The background is the plotter's; the volume covers a good part of the middle.
    assert pixels.shape[:2] == (SIZE[1], SIZE[0])
    rows = browser.find_elements(By.CSS_SELECTOR, '[data-testid="svdag-segment-list"] > [data-label]')
    import vtksvdag

    volume = vtksvdag.read(str(DATA))
    assert [int(r.get_attribute("data-label")) for r in rows] == volume.labels.tolist()
    slice_src = _by_id(browser, "svdag-slice").get_attribute("src")
    assert slice_src.startswith("data:image/png;base64,")


def test_click_selects_the_label_vtksvdag_pick_finds(server, browser):
    before = _open(browser, server)
    x, y, state = _find_label_pixel(browser)
    assert int(state[0]) == _reference_pick(state)
    # Highlighted: the other labels are dimmed in the next frames (the background stays).
    WebDriverWait(browser, TIMEOUT, poll_frequency=0.5).until(
        lambda _: _view_pixels(browser).mean() < before.mean() - 5)
    _assert_row_selected(browser, state[0])


def test_search_and_hide_then_the_next_frame_does_not_pick_it(server, browser):
    _open(browser, server)
    x, y, state = _find_label_pixel(browser)
    label = state[0]
    search = _by_id(browser, "svdag-label-search").find_element(By.CSS_SELECTOR, "input")
    search.clear()
    search.send_keys(label)
    listed = lambda: browser.find_elements(By.CSS_SELECTOR, '[data-testid="svdag-segment-list"] > [data-label]')  # noqa: E731
    WebDriverWait(browser, TIMEOUT).until(lambda _: 0 < len(listed()) < 125)
    values = [r.get_attribute("data-label") for r in listed()]
    assert label in values and all(v.startswith(label) for v in values)
    row = browser.find_element(By.CSS_SELECTOR, f'[data-testid="svdag-segment-list"] > [data-label="{label}"]')
    row.find_element(By.CSS_SELECTOR, 'input[data-action="visible"]').click()
    WebDriverWait(browser, TIMEOUT).until(
        lambda _: not row.find_element(By.CSS_SELECTOR, 'input[data-action="visible"]').is_selected())
    _click_view(browser, x, y)
    after = _selected(browser, state)
    assert after[0] != label
    expected = _reference_pick(after, hidden=[int(label)])
    assert (int(after[0]) if after[0] else None) == expected
    # Show it again for the tests after this one (they share the page's server).
    row.find_element(By.CSS_SELECTOR, 'input[data-action="visible"]').click()
    search.send_keys(Keys.CONTROL, "a", Keys.DELETE)


def test_drag_orbits_and_each_browser_has_its_own_view(server, browser):
    before = _open(browser, server)
    view = _by_id(browser, "svdag-view")
    ActionChains(browser).move_to_element(view).click_and_hold().move_by_offset(40, 0) \
        .move_by_offset(40, 10).release().perform()
    after = _wait_for_image(browser, differs_from=before)
    assert np.abs(after - before).mean() > 4
    # A second browser (tab) gets a view of its own: the initial one, not the orbited one.
    first = browser.current_window_handle
    browser.switch_to.new_window("tab")
    try:
        other = _open(browser, server)
        other = _wait_for_image(browser)
        assert np.abs(other - before).mean() < np.abs(other - after).mean()
    finally:
        browser.close()
        browser.switch_to.window(first)


def _status(url):
    try:
        with urllib.request.urlopen(url, timeout=10) as response:
            return response.status
    except urllib.error.HTTPError as error:
        return error.code


def test_beyond_loopback_a_token_is_required(browser):
    import asyncio

    import aiohttp

    process, url = _serve("--host", "0.0.0.0")
    try:
        token = re.search(r"[?&]token=([^&]+)", url).group(1)
        port = re.search(r":(\d+)/", url).group(1)
        base = f"http://127.0.0.1:{port}"
        assert _status(f"{base}/index.html") == 403
        assert _status(f"{base}/index.html?token=wrong{token}") == 403
        assert _status(f"{base}/index.html?token={token}") == 200

        async def websocket(query):
            async with aiohttp.ClientSession() as session:
                try:
                    async with session.ws_connect(f"ws://127.0.0.1:{port}/ws{query}") as ws:
                        # A hostile message: not msgpack at all. The server closes this
                        # connection (or ignores it) and goes on serving.
                        await ws.send_bytes(b"\xc1\xff not a wslink message")
                        await ws.send_str("text")
                        await ws.receive(timeout=5)
                        return "open"
                except aiohttp.WSServerHandshakeError as error:
                    return error.status

        assert asyncio.run(websocket("")) == 403
        assert asyncio.run(websocket(f"?token={token}")) == "open"
        assert process.poll() is None
        assert _status(f"{base}/index.html?token={token}") == 200
        # The browser with the printed URL's token gets the viewer.
        _open(browser, f"{base}/index.html?token={token}")
    finally:
        _stop(process)


def _slice_pixels(driver):
    import base64

    src = _by_id(driver, "svdag-slice").get_attribute("src")
    return np.asarray(Image.open(io.BytesIO(base64.b64decode(src.split(",", 1)[1]))).convert("RGB"))


def test_slice_and_3d_selections_are_linked(server, browser):
    import vtksvdag

    _open(browser, server)
    volume = vtksvdag.read(str(DATA))
    labels = volume.slice("z", volume.dims[2] // 2)  # the slice shown first, (nx, ny)
    in_image = lambda value: (labels == value).T[::-1]  # noqa: E731 (rows: y from the top)
    before = _slice_pixels(browser)
    # 2-D -> 3-D: a click on a voxel of the slice selects its label (read from the compressed
    # form), the 3-D view's selection and the list show it, and the slice highlights its voxels.
    image = _by_id(browser, "svdag-slice")
    width, height = image.size["width"], image.size["height"]
    nx, ny = labels.shape
    u, v = nx // 2 + 7, ny // 2 - 5
    first = int(labels[u, v])
    assert first != volume.background
    px, py = (u + 0.5) * width / nx, (ny - 1 - v + 0.5) * height / ny
    ActionChains(browser).move_to_element_with_offset(image, int(px - width / 2), int(py - height / 2)) \
        .click().perform()
    element = _by_id(browser, "svdag-selected-label")
    WebDriverWait(browser, TIMEOUT).until(lambda _: element.text == str(first))
    _assert_row_selected(browser, str(first))
    highlighted = _slice_pixels(browser)
    assert np.array_equal(np.any(highlighted != before, axis=2), in_image(first))
    # 3-D -> 2-D: a pick in the 3-D view moves the slice's highlight to the picked label.
    x, y, state = _find_label_pixel(browser)
    second = int(state[0])
    if second != first:
        changed = np.any(_slice_pixels(browser) != highlighted, axis=2)
        assert np.array_equal(changed, in_image(first) | in_image(second))


def test_touch_drag_orbits(server, browser):
    before = _open(browser, server)
    view = _by_id(browser, "svdag-view")
    rect = browser.execute_script("const r = arguments[0].getBoundingClientRect(); return [r.left, r.top];", view)
    x0, y0 = rect[0] + SIZE[0] / 2, rect[1] + SIZE[1] / 2

    def touch(kind, points):
        browser.execute_cdp_cmd("Input.dispatchTouchEvent", {
            "type": kind, "touchPoints": [{"x": x, "y": y, "id": i} for i, (x, y) in enumerate(points)]})
    touch("touchStart", [(x0, y0)])
    for step in range(1, 9):
        touch("touchMove", [(x0 + 8 * step, y0 + 2 * step)])
    touch("touchEnd", [])
    after = _wait_for_image(browser, differs_from=before)
    assert np.abs(after - before).mean() > 4


def test_cut_controls_and_full_quality_screenshot(server, browser):
    import base64

    before = _open(browser, server)
    panel = browser.find_element(By.XPATH, "//button[contains(@class, 'v-expansion-panel-title')]"
                                           "[.//text()[contains(., 'Clipping plane')]]")
    panel.click()
    switch = WebDriverWait(browser, TIMEOUT).until(lambda d: d.find_element(
        By.XPATH, "//div[contains(@class, 'v-switch')][.//label[contains(., 'Clip')]]//input"))
    browser.execute_script("arguments[0].click()", switch)
    clipped = _wait_for_image(browser, differs_from=before)
    assert np.abs(clipped - before).mean() > 4
    # The screenshot: the view refined to its target samples, as a PNG of the view's size.
    result = browser.execute_async_script(
        "const done = arguments[arguments.length - 1];"
        "window.trame.trigger('svdag_screenshot').then(r => done(r.src), e => done('error ' + e));")
    assert result.startswith("data:image/png;base64,"), result[:200]
    shot = np.asarray(Image.open(io.BytesIO(base64.b64decode(result.split(",", 1)[1]))).convert("RGB"))
    assert shot.shape == (SIZE[1], SIZE[0], 3)
    # The same cut view as the stream shows (JPEG there), to within compression and noise.
    assert np.abs(shot.astype(np.int16) - _view_pixels(browser)).mean() < 12
    browser.execute_script("arguments[0].click()", switch)


def test_hostile_messages_are_refused_and_the_view_goes_on(server, browser):
    _open(browser, server)
    # Calls a page's own script could make: wrong types, unknown labels and options, garbage
    # interaction and size events, unknown methods. Each is answered (or dropped) alone.
    answers = browser.execute_async_script("""
        const done = arguments[arguments.length - 1];
        const session = window.trame.client.getConnection().getSession();
        const name = document.querySelector('[data-testid="svdag-view"]') && window.trame.state.get('view_name');
        const calls = [
          window.trame.trigger('svdag_pick', ['a', {}]),
          window.trame.trigger('svdag_select', [123456789]),
          window.trame.trigger('svdag_visibility', [null, 'x']),
          window.trame.trigger('svdag_option', ['path', '/etc/passwd']),
          window.trame.trigger('svdag_slice', ['w', 1e30]),
          window.trame.trigger('svdag_pick_slice', [Infinity, -1]),
          session.call('trame.rca.event', [name, 'x', {type: 5}]),
          session.call('trame.rca.event', [name, 'x', {type: 'LeftButtonPress', x: 'a', y: null}]),
          session.call('trame.rca.event', [name, 'x', {type: 'MouseWheel', spinY: 1e308}]),
          session.call('trame.rca.size', [name, 'x', {w: -5, h: 'big'}]),
          session.call('no.such.method', [1, 2, 3]),
        ];
        Promise.allSettled(calls).then(r => done(r.map(x => x.status)));
    """)
    assert len(answers) == 11
    assert answers[:6] == ["rejected"] * 6
    # The server still serves this view: a click still picks what vtksvdag.pick finds.
    x, y, state = _find_label_pixel(browser)
    assert int(state[0]) == _reference_pick(state)
