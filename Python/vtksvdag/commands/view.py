"""``vtksvdag view DATA``: the viewer in the browser (needs the optional extra ``viewer``)."""
from ._common import add_input_options, add_output_options, load

NAME = "view"
HELP = "serve a label volume in the browser: path-traced view, 2-D slice and segment list"


def _size(text):
    import argparse

    try:
        width, height = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be WIDTHxHEIGHT in pixels, got {text!r}") from None
    if not (16 <= width <= 4096 and 16 <= height <= 4096):
        raise argparse.ArgumentTypeError(f"width and height must be in 16..4096, got {text!r}")
    return width, height


def add_arguments(parser):
    parser.add_argument("input", metavar="DATA", help=".svdag file, label volume file or chunked store")
    parser.add_argument("--port", type=int, default=0, metavar="P",
                        help="port to listen on (default: 0, a free port; the URL is printed)")
    parser.add_argument("--host", default="127.0.0.1", metavar="H",
                        help="address to bind (default: 127.0.0.1); beyond loopback a random "
                             "token is demanded, printed in the URL")
    parser.add_argument("--token", metavar="T",
                        help="demand this token (?token=T) on any address")
    parser.add_argument("--no-browser", action="store_true", help="do not open a browser")
    parser.add_argument("--size", type=_size, metavar="WxH",
                        help="fixed size of the 3-D image in pixels (default: fills its panel)")
    add_input_options(parser)
    add_output_options(parser)


def run(args):
    try:
        from ..viewer.app import ViewerApp
    except ImportError as error:
        raise RuntimeError(f"the viewer needs the optional extra 'viewer' (pip install "
                           f"vtksvdag[viewer]): {error}") from None
    if not 0 <= args.port <= 65535:
        raise ValueError(f"--port must be in 0..65535, got {args.port}")
    volume = load(args, args.input)
    app = ViewerApp(volume, host=args.host, port=args.port, token=args.token, size=args.size)
    app.serve(open_browser=not args.no_browser, as_json=args.json)
    return 0
