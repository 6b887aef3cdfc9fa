"""One browser's view of the volume: its own off-screen plotter, camera, selection and cuts.

A session is the pyvista route (:func:`vtksvdag.add_segmentation` into an off-screen
``pyvista.Plotter``, :func:`vtksvdag.pick`, the actor's hide/show/highlight), driven by the
browser's pointer events instead of a desktop interactor. It also is what trame-rca's image
scheduler renders (``img_cols_rows``, ``process_resize_event``, ``process_interaction_event``:
trame-rca's RemoteControlledAreaProtocol), so no VTK web module is needed (Debian's VTK 9.1 has
none).

Progressive frames: while a pointer drags, the render window's desired update rate is the drag
rate, so the mapper keeps each frame to that budget (AutoAdjustToRenderTime: coarser LOD and
resolution); once still, every frame adds samples until the mapper has converged.
"""
import base64
import io
import math
import numbers

import numpy as np

from .. import plotting
from .._settingnames import set_by_name
from ..volume import check_axis

#: Frames per second asked of the mapper while the pointer drags (its frame budget).
DRAG_UPDATE_RATE = 15.0
#: The desired update rate of a still view: VTK's still rate, so every render refines.
STILL_UPDATE_RATE = 0.0001
#: Pixels a press may move before it is a drag rather than a click.
CLICK_SLOP = 4
#: The slice's colors for background (and hidden labels) and the selection's highlight.
SLICE_BACKGROUND = (30, 30, 36)
SLICE_HIGHLIGHT = np.array((255, 191, 0), float)
#: The other labels' brightness while one is selected (the pyvista explorer example's).
HIGHLIGHT_DIM = 0.35


def _number(event, key, default=None):
    value = event.get(key, default)
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
        raise ValueError(f"event field {key!r} must be a finite number, got {value!r}")
    return float(value)


def png_data_url(rgb):
    """A ``data:image/png;base64,...`` URL of an (h, w, 3) uint8 array."""
    from PIL import Image

    buffer = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(rgb)).save(buffer, "PNG")
    return "data:image/png;base64," + base64.b64encode(buffer.getvalue()).decode("ascii")


class ViewSession:
    """The view of one browser.

    Parameters
    ----------
    volume : SegmentationVolume
        The one volume the server serves (shared, read only).
    size : (int, int)
        Initial render size in pixels.
    options : dict
        Keyword arguments of :func:`vtksvdag.add_segmentation`.
    on_change : callable, optional
        Called with no argument when the view needs a new frame (the image scheduler's
        ``schedule_render``).
    """

    def __init__(self, volume, size=(512, 512), options=None, on_change=None):
        import pyvista as pv
        from vtkmodules.vtkRenderingCore import vtkWindowToImageFilter

        self.volume = volume
        self.on_change = on_change or (lambda: None)
        self.plotter = pv.Plotter(off_screen=True, window_size=tuple(int(s) for s in size))
        self.actor = plotting.add_segmentation(self.plotter, volume, **(options or {}))
        self.mapper = self.actor.GetMapper()
        # The image scheduler refines frame by frame: a still render must not block until it
        # has converged (add_segmentation turns that on for off-screen plotters).
        self.mapper.SetRefineStillRenders(False)
        self.render_window = self.plotter.render_window
        self.render_window.SetDesiredUpdateRate(STILL_UPDATE_RATE)
        self.camera = self.plotter.renderer.GetActiveCamera()
        # pyvista places the camera on its first render; do it now, so picks before the first
        # frame and the reference views of the tests see the same camera.
        first = getattr(self.plotter, "_on_first_render_request", None)
        if first is not None:
            first()
        self._capture = vtkWindowToImageFilter()
        self._capture.SetInput(self.render_window)
        self._capture.ReadFrontBufferOff()
        self._capture.ShouldRerenderOff()
        self._capture.SetInputBufferTypeToRGB()
        self._label_values = set(volume.labels.tolist())
        self.selected = None
        self.hidden = set()
        self.clip = {"enabled": False, "axis": "x", "position": 0.5, "flip": False}
        self.crop = None
        self.slice_axis = "z"
        self.slice_index = volume.dims[2] // 2
        self._drag = None  # {"button", "start", "last", "moved"} while a button is held
        self._gesture = None
        self._coarse_next = False
        self._waiters = []

    # -- trame-rca's RemoteControlledAreaProtocol -----------------------------------------
    @property
    def img_cols_rows(self):
        """Render one frame and return it as (rows x cols x 3 uint8, cols, rows). The first
        frame after a change (selection, visibility, cuts, options) keeps to the drag's budget,
        so the change shows at once; the frames after it refine."""
        coarse = self._coarse_next and not self.dragging
        self._coarse_next = False
        if coarse:
            self.render_window.SetDesiredUpdateRate(DRAG_UPDATE_RATE)
        try:
            self.render_window.Render()
        finally:
            if coarse:
                self.render_window.SetDesiredUpdateRate(STILL_UPDATE_RATE)
        image = self._read_window()
        if self.mapper.IsConverged():
            waiters, self._waiters = self._waiters, []
            for future in waiters:
                if not future.done():
                    future.set_result(image)
        elif not self.dragging:
            self.on_change()
        rows, cols = image.shape[:2]
        return image, cols, rows

    @property
    def dragging(self):
        """True while a pointer drags or a touch gesture goes on."""
        return self._drag is not None or self._gesture is not None

    @property
    def refining(self):
        """True while frames still add samples (a still view not yet converged)."""
        return not self.dragging and not self.mapper.IsConverged()

    def process_resize_event(self, width, height):
        width, height = max(16, int(width)), max(16, int(height))
        if tuple(self.render_window.GetSize()) != (width, height):
            self.plotter.window_size = (width, height)
            self.render_window.SetSize(width, height)

    def process_interaction_event(self, event):
        """Orbit (left drag), pan (middle or shift+left drag), zoom (right drag, wheel, pinch),
        from trame-rca's pointer events; anything malformed raises ValueError (the caller
        ignores the event)."""
        if not isinstance(event, dict) or not isinstance(event.get("type"), str):
            raise ValueError("an interaction event is a dict with a string 'type'")
        kind = event["type"]
        if kind.endswith("ButtonPress"):
            x, y = _number(event, "x"), _number(event, "y")
            button = kind[: -len("ButtonPress")]
            if button == "Left" and event.get("shiftKey"):
                button = "Middle"
            self._drag = {"button": button, "start": (x, y), "last": (x, y), "moved": False}
        elif kind == "MouseMove" and self._drag is not None:
            x, y = _number(event, "x"), _number(event, "y")
            drag = self._drag
            if not drag["moved"] and max(abs(x - drag["start"][0]), abs(y - drag["start"][1])) <= CLICK_SLOP:
                return
            if not drag["moved"]:
                drag["moved"] = True
                self.render_window.SetDesiredUpdateRate(DRAG_UPDATE_RATE)
            dx, dy = x - drag["last"][0], y - drag["last"][1]
            drag["last"] = (x, y)
            {"Left": self.orbit, "Middle": self.pan, "Right": lambda a, b: self.zoom(1.01 ** b)}.get(
                drag["button"], self.orbit)(dx, dy)
        elif kind.endswith("ButtonRelease"):
            self._drag = None
            self.render_window.SetDesiredUpdateRate(STILL_UPDATE_RATE)
        elif kind == "MouseWheel":
            self.zoom(1.1 ** -max(-10.0, min(10.0, _number(event, "spinY", 0.0))))
        elif kind in ("StartPinch", "StartPan", "StartRotate"):
            self._gesture = {"scale": _number(event, "scale", 1.0),
                             "translation": self._pair(event.get("translation", [0, 0])),
                             "rotation": _number(event, "rotation", 0.0)}
            self.render_window.SetDesiredUpdateRate(DRAG_UPDATE_RATE)
        elif kind in ("Pinch", "Pan", "Rotate") and self._gesture is not None:
            gesture = self._gesture
            if kind == "Pinch":
                scale = _number(event, "scale", 1.0)
                if scale > 0 and gesture["scale"] > 0:
                    self.zoom(scale / gesture["scale"])
                gesture["scale"] = scale
            elif kind == "Pan":
                translation = self._pair(event.get("translation", [0, 0]))
                self.pan(translation[0] - gesture["translation"][0],
                         translation[1] - gesture["translation"][1])
                gesture["translation"] = translation
            else:
                rotation = _number(event, "rotation", 0.0)
                self.camera.Roll(rotation - gesture["rotation"])
                gesture["rotation"] = rotation
        elif kind in ("EndPinch", "EndPan", "EndRotate"):
            self._gesture = None
            self.render_window.SetDesiredUpdateRate(STILL_UPDATE_RATE)

    @staticmethod
    def _pair(value):
        if not isinstance(value, (list, tuple)) or len(value) != 2:
            raise ValueError(f"a translation is 2 numbers, got {value!r}")
        return tuple(_number({"v": v}, "v") for v in value)

    def was_drag(self):
        """Whether the last press moved beyond a click (the click handler then ignores it)."""
        return self._drag is not None and self._drag["moved"]

    # -- camera ----------------------------------------------------------------------------
    def orbit(self, dx, dy):
        width, height = self.render_window.GetSize()
        self.camera.Azimuth(-200.0 * dx / max(width, 1))
        self.camera.Elevation(-200.0 * dy / max(height, 1))
        self.camera.OrthogonalizeViewUp()
        self._camera_moved()

    def pan(self, dx, dy):
        width, height = self.render_window.GetSize()
        camera = self.camera
        focal = np.array(camera.GetFocalPoint())
        position = np.array(camera.GetPosition())
        distance = np.linalg.norm(position - focal)
        view_height = 2.0 * distance * math.tan(math.radians(camera.GetViewAngle()) / 2)
        up = np.array(camera.GetViewUp())
        right = np.cross(focal - position, up)
        right /= max(np.linalg.norm(right), 1e-12)
        shift = (-dx * right + -dy * up) * view_height / max(height, 1)
        camera.SetFocalPoint(*(focal + shift))
        camera.SetPosition(*(position + shift))
        self._camera_moved()

    def zoom(self, factor):
        if factor > 0 and math.isfinite(factor):
            self.camera.Dolly(factor)
            self._camera_moved()

    def reset_camera(self):
        plotting._frame_visible(self.plotter.renderer)
        self._camera_moved()

    def _camera_moved(self):
        self.plotter.renderer.ResetCameraClippingRange()

    def camera_state(self):
        """The camera as plain numbers (what a reference view needs to be the same view)."""
        camera = self.camera
        return {"position": list(camera.GetPosition()), "focal_point": list(camera.GetFocalPoint()),
                "view_up": list(camera.GetViewUp()), "view_angle": camera.GetViewAngle(),
                "size": list(self.render_window.GetSize())}

    # -- labels ----------------------------------------------------------------------------
    def pick(self, fx, fy):
        """Select the label under a point of the image given as fractions of its width and
        height from the top left (how the browser reports a click). Returns the selection."""
        fx, fy = _number({"v": fx}, "v"), _number({"v": fy}, "v")
        width, height = self.render_window.GetSize()
        x = min(max(fx, 0.0), 1.0 - 1e-9) * width
        y = (1.0 - min(max(fy, 1e-9), 1.0)) * height
        hit = plotting.pick(self.plotter, x, y)
        self.select(None if hit is None else hit["label"], position=None if hit is None else hit["position"])
        return {**self.selection(), "x": x, "y": y, "camera": self.camera_state()}

    def select(self, label, position=None):
        if label is not None and label not in self._values():
            raise ValueError(f"{label!r} is not a label of the volume")
        self.selected = None if label is None else {"label": int(label), "position": position}
        self.actor.set_highlight(None if label is None else [int(label)], dim=HIGHLIGHT_DIM)
        self._changed()

    def _changed(self):
        self._coarse_next = True
        self.on_change()

    def _values(self):
        return self._label_values

    def selection(self):
        """The selected label's row (value, name, position, voxel count), or {}."""
        if self.selected is None:
            return {"label": None}
        value = self.selected["label"]
        table = self.actor._vtksvdag_style.table
        row = table.loc[value]
        name = row["name"] if "name" in table.columns and isinstance(row.get("name"), str) else ""
        position = self.selected["position"]
        return {"label": value, "name": name, "voxel_count": int(row["voxel_count"]),
                "position": None if position is None else [round(float(p), 3) for p in position]}

    def set_hidden(self, label, hidden):
        if label not in self._values():
            raise ValueError(f"{label!r} is not a label of the volume")
        (self.actor.hide if hidden else self.actor.show)(int(label))
        (self.hidden.add if hidden else self.hidden.discard)(int(label))
        self._changed()

    def show_only(self, labels):
        labels = {int(v) for v in labels} & self._values()
        others = [v for v in self._values() if v not in labels]
        if others:
            self.actor.hide(others)
        if labels:
            self.actor.show(sorted(labels))
        self.hidden = set(others)
        self._changed()

    def show_all(self):
        self.show_only(self._values())

    # -- render options --------------------------------------------------------------------
    def set_option(self, name, value):
        """LOD, shading, clipping plane and crop box, by name (ValueError for a bad value)."""
        settings = self.mapper.GetSettings()
        if name in ("lod", "shading"):
            set_by_name(settings, {"lod": "LOD", "shading": "Shading"}[name], value, name)
        elif name == "clip":
            if not isinstance(value, dict):
                raise ValueError("clip is a dict (enabled, axis, position, flip)")
            clip = dict(self.clip)
            clip.update({k: value[k] for k in ("enabled", "axis", "position", "flip") if k in value})
            check_axis(clip["axis"])
            clip["position"] = min(max(_number(clip, "position"), 0.0), 1.0)
            self.clip = clip
            self._apply_clip()
        elif name == "crop":
            if value is None:
                self.crop = None
                self.mapper.CroppingOff()
            else:
                fractions = [min(max(_number({"v": v}, "v"), 0.0), 1.0) for v in value]
                if len(fractions) != 6:
                    raise ValueError("crop is 6 fractions (xmin, xmax, ymin, ymax, zmin, zmax)")
                self.crop = fractions
                lo, hi = self._world_box()
                box = [lo[a] + (hi[a] - lo[a]) * fractions[2 * a + s] for a in range(3) for s in (0, 1)]
                for a in range(3):
                    if box[2 * a] > box[2 * a + 1]:
                        box[2 * a], box[2 * a + 1] = box[2 * a + 1], box[2 * a]
                self.mapper.SetCroppingRegionPlanes(*box)
                self.mapper.CroppingOn()
        else:
            raise ValueError(f"unknown view option {name!r}")
        self._changed()

    def _world_box(self):
        """The volume's world bounds (voxel boxes, axis-aligned volumes)."""
        dims = np.array(self.volume.dims, float)
        corners = np.array([[(dims[a] if c >> a & 1 else 0.0) for a in range(3)] for c in range(8)])
        frame = np.asarray(self.volume.direction, float) * np.asarray(self.volume.spacing, float)
        world = np.asarray(self.volume.origin, float) + (corners - 0.5) @ frame.T
        return world.min(axis=0), world.max(axis=0)

    def _apply_clip(self):
        from vtkmodules.vtkCommonDataModel import vtkPlane

        self.mapper.RemoveAllClippingPlanes()
        if not self.clip["enabled"]:
            return
        a = check_axis(self.clip["axis"])
        lo, hi = self._world_box()
        origin = (lo + hi) / 2
        origin[a] = lo[a] + (hi[a] - lo[a]) * self.clip["position"]
        normal = np.zeros(3)
        normal[a] = -1.0 if self.clip["flip"] else 1.0
        plane = vtkPlane()
        plane.SetOrigin(*origin)
        plane.SetNormal(*normal)
        self.mapper.AddClippingPlane(plane)

    # -- 2-D slice -------------------------------------------------------------------------
    def slice_image(self, axis=None, index=None):
        """The slice (decoded from the compressed form) in the labels' colors, hidden labels as
        background and the selected one highlighted, as a PNG data URL with its geometry."""
        if axis is not None:
            a = check_axis(axis)
            self.slice_axis = "xyz"[a]
        a = "xyz".index(self.slice_axis)
        if index is not None:
            if isinstance(index, bool) or not isinstance(index, numbers.Integral):
                raise ValueError(f"slice index must be an integer, got {index!r}")
            self.slice_index = int(index)
        self.slice_index = min(max(self.slice_index, 0), self.volume.dims[a] - 1)
        labels = self.volume.slice(self.slice_axis, self.slice_index)  # (nu, nv), u right, v up
        rgb = self._label_rgb(labels)
        image = rgb.transpose(1, 0, 2)[::-1]
        return {"src": png_data_url(image), "axis": self.slice_axis, "index": self.slice_index,
                "count": int(self.volume.dims[a]), "width": int(labels.shape[0]),
                "height": int(labels.shape[1])}

    def _label_rgb(self, labels):
        values = self.volume.labels
        colors = np.array([self.actor.get_color(v) for v in values.tolist()], float).reshape(-1, 3) * 255
        lookup = np.clip(np.searchsorted(values, labels), 0, max(len(values) - 1, 0))
        known = (values[lookup] == labels) if len(values) else np.zeros(labels.shape, bool)
        if self.hidden:
            known &= ~np.isin(labels, list(self.hidden))
        rgb = np.empty(labels.shape + (3,), float)
        rgb[...] = SLICE_BACKGROUND
        rgb[known] = colors[lookup[known]] if len(values) else SLICE_BACKGROUND
        if self.selected is not None:
            mine = labels == self.selected["label"]
            rgb[mine] = 0.35 * rgb[mine] + 0.65 * SLICE_HIGHLIGHT
        return rgb.astype(np.uint8)

    def pick_slice(self, fx, fy):
        """Select the label at a point of the slice image (fractions from its top left)."""
        a = "xyz".index(self.slice_axis)
        nu, nv = [self.volume.dims[b] for b in range(3) if b != a]
        u = min(int(_number({"v": fx}, "v") * nu), nu - 1)
        v = nv - 1 - min(int(_number({"v": fy}, "v") * nv), nv - 1)
        if u < 0 or v < 0:
            raise ValueError("the point is outside the slice")
        index = [0, 0, 0]
        index[a] = self.slice_index
        index[[b for b in range(3) if b != a][0]] = u
        index[[b for b in range(3) if b != a][1]] = v
        label = self.volume.label_at(*index)
        background = self.volume.background
        hidden = label in self.hidden
        self.select(None if (label == background or hidden or label not in self._values()) else label)
        return self.selection()

    # -- full quality ----------------------------------------------------------------------
    def refined_future(self):
        """An asyncio future resolved with the next converged frame (rows x cols x 3)."""
        import asyncio

        future = asyncio.get_running_loop().create_future()
        self._waiters.append(future)
        self.on_change()
        return future

    def _read_window(self):
        from vtkmodules.util.numpy_support import vtk_to_numpy

        self._capture.Modified()
        self._capture.Update()
        output = self._capture.GetOutput()
        cols, rows, _ = output.GetDimensions()
        pixels = vtk_to_numpy(output.GetPointData().GetScalars()).reshape(rows, cols, -1)
        return np.ascontiguousarray(pixels[::-1, :, :3])

    def close(self):
        for future in self._waiters:
            if not future.done():
                future.cancel()
        self._waiters = []
        self.plotter.close()
