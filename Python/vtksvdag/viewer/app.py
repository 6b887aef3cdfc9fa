"""The trame application: one server, one volume, one :class:`ViewSession` per browser.

trame's state is shared by every browser of a server, so nothing of a view lives there: each
browser keeps its own (selection, hidden labels, search, cuts, slice) as client-only state and
changes it through triggers, whose answers go to the caller alone; its 3-D frames go to its own
websocket under an image-stream name of its own. Shared state holds what every browser sees
alike: the segment list.
"""
import asyncio
import functools
import itertools
import json
import logging
import os
import socket
import time
import webbrowser

from trame_rca.utils import RcaViewAdapter

from .._settingnames import names as setting_names
from ..volume import SegmentationVolume
from .security import required_token, token_middleware
from .scheduler import ProgressiveScheduler
from .session import ViewSession, png_data_url

log = logging.getLogger("vtksvdag.viewer")

#: JPEG quality of the frames while they change, and of the last one once the view is still.
INTERACTIVE_QUALITY = 70
STILL_QUALITY = 92
#: Rows the segment list shows at most (a search narrows it).
MAX_LISTED = 300
#: Seconds the screenshot waits at most for the view to converge.
SCREENSHOT_TIMEOUT = 120.0

_names = itertools.count()

_STATE_DEFAULTS = {
    "view_name": "",
    "selected": {"label": None},
    "search": "",
    "hidden": [],
    "slice": {"src": "", "axis": "z", "index": 0, "count": 1},
    "lod": None,  # the settings' own, set with the rest
    "shading": None,
    "clip": {"enabled": False, "axis": "x", "position": 0.5, "flip": False},
    "crop": [0.0, 1.0, 0.0, 1.0, 0.0, 1.0],
    "crop_on": False,
    "down": [0, 0],
}


def _rgb_hex(rgb):
    return "#" + "".join(f"{int(round(max(0.0, min(1.0, c)) * 255)):02x}" for c in rgb)


class ViewerApp:
    """The viewer of one segmentation volume (see :func:`vtksvdag.view`).

    Parameters
    ----------
    volume : SegmentationVolume
    host : str
        Address to bind (127.0.0.1 by default; beyond loopback a token is demanded).
    port : int
        Port (0: a free one).
    token : str, optional
        Token demanded on any address.
    size : (int, int), optional
        Fixed size of the 3-D image in CSS pixels (default: it fills its panel).
    options : dict
        add_segmentation options for every view.
    """

    def __init__(self, volume, *, host="127.0.0.1", port=0, token=None, size=None, options=None):
        from trame.app import get_server

        if not isinstance(volume, SegmentationVolume):
            raise TypeError("volume must be a SegmentationVolume")
        self.volume = volume
        self.host = host
        self.token = required_token(host, token)
        self.port = int(port)
        self.size = None if size is None else (int(size[0]), int(size[1]))
        self.options = dict(options or {})
        self.sessions = {}  # wslink client id -> (ViewSession, adapter)
        # trame parses sys.argv for its own options unless TRAME_ARGS is set: the viewer's
        # command line is its own.
        os.environ.setdefault("TRAME_ARGS", "")
        self.server = get_server(f"vtksvdag-view-{next(_names)}", client_type="vue3")
        # The first view is made now, so that the device, the upload and the pipelines are ready
        # when the first browser arrives; it is that browser's.
        self._spare = ViewSession(volume, size=self.size or (512, 512), options=self.options)
        self._setup_state()
        self._setup_protocol()
        self._setup_triggers()
        self._build_ui()

    # -- serving ---------------------------------------------------------------------------
    @property
    def url(self):
        """The page's URL (with ``?token=`` where one is demanded)."""
        host = self.host
        if host in ("0.0.0.0", "::", ""):
            host = socket.gethostname()
        elif ":" in host:
            host = f"[{host}]"
        query = "" if self.token is None else f"?token={self.token}"
        return f"http://{host}:{self.port}/index.html{query}"

    def _start_options(self):
        if self.port == 0:
            # A free port chosen now, so that the URL is known before the server runs (Jupyter
            # shows the page as soon as the cell returns).
            with socket.socket(socket.AF_INET6 if ":" in self.host else socket.AF_INET) as probe:
                probe.bind((self.host, 0))
                self.port = probe.getsockname()[1]
        return {"port": self.port, "host": self.host, "open_browser": False,
                "show_connection_info": False, "disable_logging": True, "timeout": 0}

    def serve(self, open_browser=True, as_json=False):
        """Serve until interrupted (Ctrl+C), printing the URL (a line, or a JSON object
        ``{"url": ...}``) and opening the browser."""
        options = self._start_options()

        def ready(**_):
            print(json.dumps({"url": self.url}) if as_json else f"vtksvdag view: serving {self.url}",
                  flush=True)
            if open_browser:
                webbrowser.open(self.url)

        self.server.controller.on_server_ready.add(ready)
        self.server.start(exec_mode="main", **options)

    def start(self):
        """Start serving as a task of the running asyncio loop (Jupyter); returns the task."""
        return self.server.start(exec_mode="task", **self._start_options())

    async def stop(self):
        """Stop the server (a task started with :meth:`start`)."""
        await self.server.stop()

    def _repr_html_(self):
        # The page inline, as trame's own Jupyter display does (an iframe on the server).
        return (f'<iframe src="{self.url}" style="border: none; width: 100%; height: 640px;">'
                "</iframe>")

    def __repr__(self):
        return f"<vtksvdag ViewerApp {self.url}>"

    # -- server side -----------------------------------------------------------------------
    def _setup_state(self):
        state = self.server.state
        actor = self._spare.actor
        table = actor._vtksvdag_style.table
        names = table["name"] if "name" in table.columns else None
        state.segments = [
            {"value": int(v), "name": (names[v] if names is not None and isinstance(names[v], str) else ""),
             "voxels": int(table.loc[v, "voxel_count"]), "color": _rgb_hex(actor.get_color(v))}
            for v in table.index.tolist()
        ]
        state.lod_names = list(setting_names("LOD"))
        state.shading_names = list(setting_names("Shading"))
        state.max_listed = MAX_LISTED
        state.dims = list(self.volume.dims)
        state.trame__title = "vtksvdag view"
        settings = self._spare.mapper.GetSettings()
        defaults = {**_STATE_DEFAULTS, "lod": settings.GetLODAsString(),
                    "shading": settings.GetShadingAsString()}
        for key, value in defaults.items():
            state[key] = value
        state.client_only(*_STATE_DEFAULTS)

    def _setup_protocol(self):
        from wslink.websocket import LinkProtocol

        app = self

        class SessionProtocol(LinkProtocol):
            """Frees a browser's view when its websocket closes."""

            def onClose(self, client_id):
                app._close(client_id)

        def configure(root_protocol):
            root_protocol.registerLinkProtocol(SessionProtocol())

        self.server.add_protocol_to_configure(configure)

        @self.server.controller.add("on_server_bind")
        def bind(wslink_server):
            if self.token is not None:
                wslink_server.app.middlewares.append(token_middleware(self.token))

    def _client_id(self):
        return self.server._server.last_active_client_id

    def _session(self):
        entry = self.sessions.get(self._client_id())
        if entry is None:
            raise RuntimeError("this browser has no view yet (call svdag_open first)")
        return entry[0]

    def _open(self):
        """A new view for the calling browser (its own camera, selection and stream)."""
        client_id = self._client_id()
        if client_id in self.sessions:
            session, adapter = self.sessions[client_id]
        else:
            session, self._spare = self._spare, None
            if session is None:
                session = ViewSession(self.volume, size=self.size or (512, 512), options=self.options)
            scheduler = ProgressiveScheduler(session, INTERACTIVE_QUALITY, STILL_QUALITY)
            adapter = _BrowserAdapter(session, f"svdag-view-{client_id}", scheduler=scheduler,
                                      client_id=client_id)
            session.on_change = adapter.schedule_render
            self.server.controller.rc_area_register(adapter)
            self.sessions[client_id] = (session, adapter)
        return {"view_name": adapter.area_name, "slice": session.slice_image(),
                "selected": session.selection(), "hidden": sorted(session.hidden)}

    def _close(self, client_id):
        entry = self.sessions.pop(client_id, None)
        if entry is None:
            return
        session, adapter = entry
        try:
            self.server.controller.rc_area_unregister(adapter.area_name)
        except KeyError:
            pass

        async def close():
            await adapter.close()
            session.close()

        asyncio.ensure_future(close())

    def _answer(self, session, **extra):
        """What a view change returns to its browser: its selection, hidden labels and slice."""
        return {"selected": session.selection(), "hidden": sorted(session.hidden),
                "slice": session.slice_image(), **extra}

    def _setup_triggers(self):
        def trigger(name):
            # A bad or hostile request answers an error to its browser alone (wslink sends the
            # exception to the caller); it is logged here, and the server goes on.
            def register(function):
                @functools.wraps(function)
                def guarded(*args, **kwargs):
                    try:
                        return function(*args, **kwargs)
                    except Exception as error:
                        log.warning("%s%r failed: %s: %s", name, args, type(error).__name__, error)
                        raise
                return self.server.trigger(name)(guarded)
            return register

        @trigger("svdag_open")
        def open_view():
            return self._open()

        @trigger("svdag_pick")
        def pick(fx, fy):
            session = self._session()
            hit = session.pick(fx, fy)
            # When the pick was answered (ms, the clock of the frames' "st"): bench/view.py
            # times the click to the first frame encoded after it.
            return self._answer(session, selected={**hit, "server_ms": time.time_ns() // 1_000_000})

        @trigger("svdag_pick_slice")
        def pick_slice(fx, fy):
            session = self._session()
            session.pick_slice(fx, fy)
            return self._answer(session)

        @trigger("svdag_select")
        def select(label):
            session = self._session()
            session.select(None if label is None else int(label))
            return self._answer(session)

        @trigger("svdag_visibility")
        def visibility(label, visible):
            session = self._session()
            session.set_hidden(int(label), not bool(visible))
            return self._answer(session)

        @trigger("svdag_show_only_selected")
        def show_only_selected():
            session = self._session()
            if session.selected is not None:
                session.show_only([session.selected["label"]])
            return self._answer(session)

        @trigger("svdag_show_all")
        def show_all():
            session = self._session()
            session.show_all()
            return self._answer(session)

        @trigger("svdag_option")
        def option(name, value):
            session = self._session()
            session.set_option(str(name), value)
            return self._answer(session)

        @trigger("svdag_slice")
        def slice_(axis, index):
            session = self._session()
            return {"slice": session.slice_image(axis, int(index))}

        @trigger("svdag_reset_camera")
        def reset_camera():
            session = self._session()
            session.reset_camera()
            session.on_change()
            return {}

        @trigger("svdag_screenshot")
        def screenshot():
            session = self._session()  # the caller's, before any other message is handled

            async def refined():
                image = await asyncio.wait_for(session.refined_future(), SCREENSHOT_TIMEOUT)
                return {"src": png_data_url(image)}
            return refined()

    # -- page ------------------------------------------------------------------------------
    def _build_ui(self):
        from trame.ui.vuetify3 import VAppLayout
        from trame.widgets import client, rca, vuetify3 as v3

        view_style = ("width: {}px; height: {}px;".format(*self.size) if self.size
                      else "width: 100%; height: 100%;")
        with VAppLayout(self.server, full_height=True) as layout:
            self.layout = layout
            client.Style(_CSS)
            client.ClientTriggers(mounted=(
                "trigger('svdag_open').then(r => { view_name = r.view_name; slice = r.slice; "
                "selected = r.selected; hidden = r.hidden; })"))
            with v3.VNavigationDrawer(permanent=True, width=340):
                with v3.VContainer(classes="pa-2"):
                    v3.VTextField(
                        v_model=("search",), label="Search labels (value or name)",
                        density="compact", hide_details=True, clearable=True,
                        raw_attrs=['data-testid="svdag-label-search"'],
                    )
                    with v3.VRow(dense=True, classes="my-1"):
                        v3.VBtn("Show only selected", size="small", classes="ma-1",
                                click=f"trigger('svdag_show_only_selected').then(r => {{ {_APPLY_BODY} }})",
                                raw_attrs=['data-testid="svdag-show-only-selected"'])
                        v3.VBtn("Show all", size="small", classes="ma-1",
                                click=f"trigger('svdag_show_all').then(r => {{ {_APPLY_BODY} }})")
                    self._segment_list()
                    self._controls(v3)
            with v3.VMain():
                with v3.VContainer(fluid=True, classes="pa-2 fill-height align-start"):
                    with v3.VRow(classes="fill-height", dense=True):
                        with v3.VCol(cols=7, classes="svdag-panel"):
                            with v3.VSheet(classes="svdag-view" + ("" if self.size else " svdag-view-fill"),
                                           style=view_style,
                                           raw_attrs=['data-testid="svdag-view"',
                                                      '@pointerdown.capture="down = [$event.clientX, $event.clientY]"',
                                                      '@click="' + _PICK_3D + '"']):
                                rca.RemoteControlledArea(
                                    v_if="view_name", name=("view_name",), display="image",
                                    style="width: 100%; height: 100%;",
                                )
                            self._selected_row(v3)
                        with v3.VCol(cols=5, classes="svdag-panel"):
                            self._slice_panel(v3)
        return layout

    def _segment_list(self):
        from trame.widgets import html

        html.Div(
            raw_attrs=['data-testid="svdag-segment-list"', 'class="svdag-list"'],
            children=[_SEGMENT_ROWS],
        )

    def _controls(self, v3):
        with v3.VExpansionPanels(multiple=True, classes="mt-2"):
            with v3.VExpansionPanel(title="Render"):
                with v3.VExpansionPanelText():
                    v3.VSelect(label="LOD", items=("lod_names",), v_model=("lod",),
                               density="compact", hide_details=True,
                               update_modelValue=_option("'lod'", "$event"))
                    v3.VSelect(label="Shading", items=("shading_names",), v_model=("shading",),
                               density="compact", hide_details=True, classes="mt-2",
                               update_modelValue=_option("'shading'", "$event"))
                    v3.VBtn("Reset camera", size="small", classes="mt-2",
                            click="trigger('svdag_reset_camera')")
                    v3.VBtn("Screenshot", size="small", classes="mt-2 ml-2",
                            raw_attrs=['data-testid="svdag-screenshot"'],
                            click=("trigger('svdag_screenshot').then(r => { const a = "
                                   "document.createElement('a'); a.href = r.src; "
                                   "a.download = 'vtksvdag-view.png'; a.click(); })"))
            with v3.VExpansionPanel(title="Clipping plane"):
                with v3.VExpansionPanelText():
                    v3.VSwitch(label="Clip", v_model=("clip.enabled",), density="compact",
                               hide_details=True,
                               update_modelValue=_option("'clip'", "clip"))
                    with v3.VBtnToggle(v_model=("clip.axis",), mandatory=True, density="compact",
                                       update_modelValue=_option("'clip'", "clip")):
                        for axis in "xyz":
                            v3.VBtn(axis, value=axis, size="small")
                    v3.VSlider(v_model=("clip.position",), min=0, max=1, step=0.01,
                               density="compact", hide_details=True,
                               end=_option("'clip'", "clip"))
                    v3.VCheckbox(label="Flip", v_model=("clip.flip",), density="compact",
                                 hide_details=True, update_modelValue=_option("'clip'", "clip"))
            with v3.VExpansionPanel(title="Crop box"):
                with v3.VExpansionPanelText():
                    v3.VSwitch(label="Crop", v_model=("crop_on",), density="compact",
                               hide_details=True, update_modelValue=_option("'crop'", _CROP))
                    for axis, (lo, hi) in zip("xyz", ((0, 1), (2, 3), (4, 5))):
                        v3.VRangeSlider(
                            label=axis, model_value=(f"[crop[{lo}], crop[{hi}]]",),
                            min=0, max=1, step=0.01, density="compact", hide_details=True,
                            update_modelValue=f"crop[{lo}] = $event[0]; crop[{hi}] = $event[1]",
                            end=_option("'crop'", _CROP),
                        )

    def _selected_row(self, v3):
        from trame.widgets import html

        with html.Div(classes="svdag-selected"):
            html.Span("Selected: ")
            html.Span("{{ selected.label === null ? '' : selected.label }}",
                      raw_attrs=['data-testid="svdag-selected-label"',
                                 ":data-camera=\"selected.camera ? JSON.stringify(selected.camera) : ''\"",
                                 ":data-x=\"selected.x\"", ":data-y=\"selected.y\""])
            html.Span("{{ selected.label === null ? '(click a label)' : "
                      "(selected.name || '') + '  voxels: ' + selected.voxel_count + "
                      "(selected.position ? '  at (' + selected.position.join(', ') + ')' : '') }}",
                      classes="ml-2 text-medium-emphasis")

    def _slice_panel(self, v3):
        from trame.widgets import html

        with v3.VBtnToggle(model_value=("slice.axis",), mandatory=True, density="compact",
                           update_modelValue=("trigger('svdag_slice', [$event, Math.floor(dims["
                                              "'xyz'.indexOf($event)] / 2)]).then(r => { slice = r.slice })")):
            for axis in "xyz":
                v3.VBtn(axis, value=axis, size="small")
        v3.VSlider(model_value=("slice.index",), min=0, max=("slice.count - 1",), step=1,
                   density="compact", hide_details=True, thumb_label=True,
                   update_modelValue=("trigger('svdag_slice', [slice.axis, $event])"
                                      ".then(r => { slice = r.slice })"))
        html.Img(src=("slice.src",), classes="svdag-slice",
                 raw_attrs=['data-testid="svdag-slice"', '@click="' + _PICK_2D + '"'])


#: Applies a view change's answer to the browser's client-only state.
_APPLY_BODY = "selected = r.selected; hidden = r.hidden; slice = r.slice;"
_CROP = "crop_on ? crop : null"
_PICK_3D = ("Math.hypot($event.clientX - down[0], $event.clientY - down[1]) < 5 && "
            "trigger('svdag_pick', [($event.clientX - $event.currentTarget.getBoundingClientRect().left) "
            "/ $event.currentTarget.clientWidth, ($event.clientY - $event.currentTarget"
            ".getBoundingClientRect().top) / $event.currentTarget.clientHeight])"
            ".then(r => { " + _APPLY_BODY + " })")
_PICK_2D = ("trigger('svdag_pick_slice', [$event.offsetX / $event.currentTarget.clientWidth, "
            "$event.offsetY / $event.currentTarget.clientHeight]).then(r => { " + _APPLY_BODY + " })")


def _option(name, value):
    return f"trigger('svdag_option', [{name}, {value}]).then(r => {{ {_APPLY_BODY} }})"


_SEGMENT_ROWS = """
<div v-for="s in segments.filter(s => !search || String(s.value).startsWith(search.trim())
        || s.name.toLowerCase().includes(search.trim().toLowerCase())).slice(0, max_listed)"
     :key="s.value" :data-label="s.value" class="svdag-row"
     :class="{ 'svdag-row-selected': selected.label === s.value }"
     @click="trigger('svdag_select', [s.value]).then(r => { selected = r.selected; hidden = r.hidden; slice = r.slice; })">
  <input type="checkbox" data-action="visible" title="show / hide"
         :checked="!hidden.includes(s.value)" @click.stop
         @change="trigger('svdag_visibility', [s.value, $event.target.checked]).then(r => { selected = r.selected; hidden = r.hidden; slice = r.slice; })" />
  <span class="svdag-swatch" :style="{ background: s.color }"></span>
  <span class="svdag-value">{{ s.value }}</span>
  <span class="svdag-name">{{ s.name }}</span>
  <span class="svdag-count">{{ s.voxels }}</span>
</div>
"""

_CSS = """
.svdag-list { max-height: 40vh; overflow-y: auto; font-size: 13px; margin-top: 6px; }
.svdag-row { display: flex; align-items: center; gap: 6px; padding: 1px 4px; cursor: pointer; }
.svdag-row-selected { background: rgba(255, 191, 0, 0.3); }
.svdag-swatch { width: 12px; height: 12px; border-radius: 2px; flex: none; }
.svdag-value { width: 5em; font-variant-numeric: tabular-nums; }
.svdag-name { flex: 1; overflow: hidden; text-overflow: ellipsis; white-space: nowrap; }
.svdag-count { color: #888; font-variant-numeric: tabular-nums; }
.svdag-view { position: relative; background: #222; touch-action: none; }
.svdag-view-fill { min-height: 360px; }
.svdag-panel { height: 100%; }
.svdag-slice { width: 100%; image-rendering: pixelated; cursor: crosshair; margin-top: 4px; }
.svdag-selected { font-size: 13px; padding: 4px; }
"""


class _BrowserAdapter(RcaViewAdapter):
    """trame-rca's view adapter, sending frames to its own browser alone and ignoring
    malformed events instead of raising them into wslink."""

    def __init__(self, window, name, *, scheduler, client_id):
        super().__init__(window, name, scheduler=scheduler)
        self.client_id = client_id

    def push(self, content, meta):
        if self.streamer is None or not content:
            return
        self.streamer.publish(
            "trame.rca.topic.stream",
            {"name": self.area_name, "meta": meta, "content": self.streamer.addAttachment(content)},
            client_id=self.client_id,
        )

    def on_interaction(self, origin, event):
        try:
            super().on_interaction(origin, dict(event))
        except (TypeError, ValueError, KeyError, AttributeError) as error:
            log.info("ignored a malformed interaction event: %s", error)

    def update_size(self, origin, size):
        try:
            size = {k: float(size[k]) for k in ("w", "h")} | {"p": float(size.get("p", 1))}
            size["w"], size["h"] = min(size["w"], 4096), min(size["h"], 4096)
            size["p"] = min(max(size["p"], 0.25), 4)
            super().update_size(origin, size)
        except (TypeError, ValueError, KeyError, AttributeError) as error:
            log.info("ignored a malformed size event: %s", error)
