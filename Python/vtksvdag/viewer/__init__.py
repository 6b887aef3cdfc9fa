"""A viewer in the browser and in Jupyter: the path-traced view, a 2-D slice and a segment list,
served by trame from the compressed volume (``pip install .[viewer]``).

:func:`view` is the entry point (``vtksvdag.view``, ``vtksvdag view FILE``).
"""
import asyncio
import webbrowser

from .._options import keywords_checked as _keywords_checked

#: add_segmentation options that say how ``data`` is read, not how it is drawn.
_INPUT_OPTIONS = ("scalars", "spacing", "origin", "axis_order", "cast")


def _in_running_loop():
    try:
        asyncio.get_running_loop()
    except RuntimeError:
        return False
    return True


@_keywords_checked
def view(data, *, host="127.0.0.1", port=0, token=None, open_browser=True, size=None,
         block=None, **options):
    """Serve a segmentation in the browser: the path-traced 3-D view, a 2-D slice and the
    segment list, each browser with its own view.

    Parameters
    ----------
    data : SegmentationVolume, str, os.PathLike, numpy.ndarray or pyvista.ImageData
        Anything :func:`vtksvdag.add_segmentation` takes.
    host : str, default: "127.0.0.1"
        Address to bind. Beyond loopback a random token is demanded (in the printed URL).
    port : int, default: 0
        Port; 0 picks a free one.
    token : str, optional
        Demand this token on any address (``?token=...``).
    open_browser : bool, default: True
        Open the system browser on the page (plain scripts).
    size : (int, int), optional
        Fixed size of the 3-D image in CSS pixels (default: it fills its panel).
    block : bool, optional
        Serve until interrupted (default: True in a plain script; in Jupyter, or any running
        asyncio loop, the server runs as a task and the returned app shows inline).
    **options
        add_segmentation options (``attributes=``, ``lod=``, ``shading=``, ``spp=``, ...),
        applied to every view; ``scalars``/``spacing``/``origin``/``axis_order``/``cast``
        say how ``data`` is read.

    Returns
    -------
    ViewerApp
        Its ``url``; in Jupyter, displaying it shows the viewer inline.

    Examples
    --------
    >>> vtksvdag.view("cells.nrrd")  # doctest: +SKIP
    >>> app = vtksvdag.view(volume, block=False, open_browser=False)  # doctest: +SKIP
    >>> app  # in a notebook: the viewer inline  # doctest: +SKIP
    """
    from ..plotting import _segmentation_volume
    from .app import ViewerApp

    read = {k: options.pop(k) for k in _INPUT_OPTIONS if k in options}
    volume = _segmentation_volume(data, **read)
    app = ViewerApp(volume, host=host, port=port, token=token, size=size, options=options)
    if block is None:
        block = not _in_running_loop()
    if block:
        app.serve(open_browser=open_browser)
    else:
        app.start()
    return app


__all__ = ["view"]
