"""The viewer's parts without a browser: the token rules, a view session's pointer events,
cuts and labels, the non-blocking (Jupyter) start of vtksvdag.view, and the command line.
(test_viewer_browser.py drives the whole application in chromium.)"""
import asyncio

import numpy as np
import pytest

from conftest import REPO

pytest.importorskip("trame", reason="the viewer extra (pip install .[viewer]) is not installed")
pytest.importorskip("trame_rca", reason="the viewer extra (pip install .[viewer]) is not installed")

from vtksvdag.cli import main  # noqa: E402
from vtksvdag.viewer.security import is_loopback, required_token, token_middleware  # noqa: E402

DATA = REPO / "examples" / "data" / "cells.nrrd"


def test_token_rules():
    assert is_loopback("127.0.0.1") and is_loopback("127.8.0.2") and is_loopback("::1")
    assert is_loopback("localhost")
    assert not is_loopback("0.0.0.0") and not is_loopback("192.0.2.1") and not is_loopback("example.org")
    assert required_token("127.0.0.1") is None
    first, second = required_token("0.0.0.0"), required_token("0.0.0.0")
    assert len(first) >= 24 and first != second  # random, one per server
    assert required_token("127.0.0.1", token="abc") == "abc"
    for bad in ("", "a b", 5):
        with pytest.raises(ValueError, match="token"):
            required_token("0.0.0.0", token=bad)


def test_token_middleware_answers_403_without_the_token():
    from aiohttp import web
    from aiohttp.test_utils import TestClient, TestServer

    async def page(request):
        return web.Response(text="page")

    async def run():
        app = web.Application(middlewares=[token_middleware("s3cret")])
        app.router.add_get("/index.html", page)
        async with TestClient(TestServer(app)) as client:
            assert (await client.get("/index.html")).status == 403
            assert (await client.get("/index.html?token=wrong")).status == 403
            response = await client.get("/index.html?token=s3cret")
            assert response.status == 200 and await response.text() == "page"
            # The page's cookie lets its own later requests (scripts, websocket) through.
            assert (await client.get("/index.html")).status == 200
    asyncio.run(run())


@pytest.fixture(scope="module")
def session():
    import vtksvdag
    from vtksvdag.viewer.session import ViewSession

    view = ViewSession(vtksvdag.read(str(DATA)), size=(96, 72))
    yield view
    view.close()


def _camera(view):
    return np.array(view.camera.GetPosition())


def test_pointer_events_orbit_pan_zoom_and_clicks_do_not_move(session):
    before = _camera(session)
    session.process_interaction_event({"type": "LeftButtonPress", "x": 40, "y": 30})
    session.process_interaction_event({"type": "MouseMove", "x": 42, "y": 31})  # within a click
    assert np.allclose(_camera(session), before) and not session.was_drag()
    session.process_interaction_event({"type": "MouseMove", "x": 70, "y": 30})
    assert session.was_drag()
    # While dragging, the mapper keeps to the drag's frame budget; released, it refines.
    assert session.render_window.GetDesiredUpdateRate() > 1
    session.process_interaction_event({"type": "LeftButtonRelease", "x": 70, "y": 30})
    assert session.render_window.GetDesiredUpdateRate() < 0.001
    orbited = _camera(session)
    focal = np.array(session.camera.GetFocalPoint())
    assert not np.allclose(orbited, before)
    assert np.isclose(np.linalg.norm(orbited - focal), np.linalg.norm(before - focal))  # an orbit
    session.process_interaction_event({"type": "MouseWheel", "x": 40, "y": 30, "spinY": 1})
    assert np.linalg.norm(_camera(session) - focal) > np.linalg.norm(orbited - focal)  # zoom out
    session.process_interaction_event({"type": "StartPinch", "scale": 1.0})
    distance = np.linalg.norm(_camera(session) - focal)
    session.process_interaction_event({"type": "Pinch", "scale": 2.0})
    session.process_interaction_event({"type": "EndPinch"})
    assert np.isclose(np.linalg.norm(_camera(session) - focal), distance / 2)
    session.process_interaction_event({"type": "StartPan", "translation": [0, 0]})
    session.process_interaction_event({"type": "Pan", "translation": [10, 0]})
    session.process_interaction_event({"type": "EndPan"})
    assert not np.allclose(np.array(session.camera.GetFocalPoint()), focal)
    session.reset_camera()


@pytest.mark.parametrize("event", [
    {"type": "LeftButtonPress", "x": "a", "y": 1},
    {"type": "LeftButtonPress", "x": float("nan"), "y": 1},
    {"type": "MouseWheel", "spinY": [1]},
    {"type": "StartPan", "translation": "up"},
    {"type": 3},
    [1, 2],
])
def test_malformed_events_are_errors_that_change_nothing(session, event):
    before = _camera(session)
    with pytest.raises(ValueError):
        session.process_interaction_event(event)
    assert np.allclose(_camera(session), before)


def test_labels_cuts_and_slice(session):
    volume = session.volume
    values = volume.labels.tolist()
    session.show_only(values[:3])
    assert session.hidden == set(values[3:])
    assert sorted(session.actor.visible_labels) == values[:3]
    session.show_all()
    assert session.hidden == set() and len(session.actor.visible_labels) == len(values)
    with pytest.raises(ValueError, match="not a label"):
        session.select(10**9)
    session.select(values[5])
    assert session.selection()["label"] == values[5]
    assert session.actor.highlighted_labels == [values[5]]
    assert session.selection()["voxel_count"] == int(volume.label_voxel_counts[5])
    session.select(None)
    session.set_option("clip", {"enabled": True, "axis": "y", "position": 0.25})
    assert session.mapper.GetClippingPlanes().GetNumberOfItems() == 1
    plane = session.mapper.GetClippingPlanes().GetItem(0)
    assert plane.GetNormal() == (0.0, 1.0, 0.0)
    session.set_option("clip", {"enabled": False})
    assert session.mapper.GetClippingPlanes().GetNumberOfItems() == 0
    session.set_option("crop", [0, 0.5, 0, 1, 0, 1])
    assert session.mapper.GetCropping()
    lo, hi = session._world_box()
    assert np.isclose(session.mapper.GetCroppingRegionPlanes()[1], (lo[0] + hi[0]) / 2)
    session.set_option("crop", None)
    assert not session.mapper.GetCropping()
    session.set_option("lod", "block")
    assert session.mapper.GetSettings().GetLODAsString() == "block"
    session.set_option("lod", "auto")
    for name, value in (("lod", "fine"), ("shading", 3), ("clip", "on"), ("crop", [0, 1]), ("path", "/")):
        with pytest.raises(ValueError):
            session.set_option(name, value)
    # A slice click selects the voxel's label (the volume's own), background selects nothing.
    picked = session.slice_image("x", 40)
    labels = volume.slice("x", 40)  # (ny, nz): image columns y, rows z from the top
    ny, nz = labels.shape
    u, v = ny // 2, nz // 2
    session.pick_slice((u + 0.5) / ny, (nz - 1 - v + 0.5) / nz)
    expected = int(labels[u, v])
    assert session.selection()["label"] == (None if expected == volume.background else expected)
    assert picked["width"] == ny and picked["height"] == nz


def test_view_without_blocking_serves_in_the_running_loop():
    """vtksvdag.view inside a running asyncio loop (what Jupyter has) starts the server as a
    task and returns the app, which shows itself inline as an iframe on its URL."""
    import urllib.request

    import vtksvdag

    async def run():
        app = vtksvdag.view(str(DATA), open_browser=False, size=(64, 48))
        try:
            await asyncio.wait_for(app.server.ready, 60)
            page = await asyncio.to_thread(lambda: urllib.request.urlopen(app.url, timeout=10).read())
            assert b"<html" in page.lower()
            assert app.url in app._repr_html_() and app._repr_html_().startswith("<iframe")
        finally:
            await app.stop()
    asyncio.run(run())


def test_command_line(capsys):
    assert main(["view", "--help"]) == 0
    assert "--no-browser" in capsys.readouterr().out
    assert main(["view", str(DATA), "--size", "3x3"]) == 2
    assert main(["view", str(DATA), "--port", "70000", "--no-browser"]) == 1
    assert "--port" in capsys.readouterr().err
    with pytest.raises(TypeError, match="did you mean"):
        import vtksvdag

        vtksvdag.view(str(DATA), prot=8080)
