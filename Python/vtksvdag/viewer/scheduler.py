"""When a view renders: trame-rca's render-scheduler protocol, made for progressive frames.

trame-rca's own image scheduler renders back to back inside the event loop, and re-renders each
frame at a higher quality once nothing new was asked. Refining frames here are always asked
again (each adds samples), and a path-traced frame blocks the loop for its whole trace, so each
step of a message's way in or a frame's way out (encoding done, publish, send) waited one more
frame: seconds at 512x512 on lavapipe. This scheduler leaves the loop a short gap before each
frame, so everything that is ready runs between two frames, encodes in a thread, and pushes each
frame once, at the still quality once the view has converged.
"""
import asyncio
from concurrent.futures import ThreadPoolExecutor

from trame_rca.encoders import RcaImageEncoder

#: Seconds the event loop runs other work before each frame.
GAP = 0.01

_ENCODERS = ThreadPoolExecutor(2, thread_name_prefix="vtksvdag-encode")


class ProgressiveScheduler:
    """Renders ``view`` (a :class:`~vtksvdag.viewer.session.ViewSession`) when asked, encodes
    its frames (JPEG) and hands them to the push callback.

    Parameters
    ----------
    view : ViewSession
    interactive_quality, still_quality : int
        JPEG quality of frames while the view changes or refines, and once it has converged.
    """

    def __init__(self, view, interactive_quality, still_quality, encoder="jpeg"):
        self._view = view
        self._encoder = RcaImageEncoder(encoder)
        self._quality = (interactive_quality, still_quality)
        self._push = None
        self._timer = None
        self._closed = False
        self.target_fps = 1.0 / GAP  # trame-rca's protocol; the frames' own time paces them

    @property
    def rca(self):
        return self._view

    def set_push_callback(self, callback):
        self._push = callback

    def update_quality(self, interactive, still):
        self._quality = (interactive, still)

    def schedule_render(self):
        if self._closed or self._timer is not None:
            return
        self._timer = asyncio.get_event_loop().call_later(GAP, self._render)

    def _render(self):
        self._timer = None
        if self._closed:
            return
        image, cols, rows = self._view.img_cols_rows
        quality = self._quality[0] if self._view.refining or self._view.dragging else self._quality[1]
        future = asyncio.get_event_loop().run_in_executor(
            _ENCODERS, self._encoder.encode, image, cols, rows, quality)
        future.add_done_callback(self._encoded)

    def _encoded(self, future):
        if self._closed or future.cancelled() or future.exception() is not None:
            return
        content, meta, _ = future.result()
        if self._push is not None:
            self._push(content, meta)

    def reset(self):
        """Nothing to reset for images (trame-rca's protocol)."""

    async def close(self):
        self._closed = True
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
