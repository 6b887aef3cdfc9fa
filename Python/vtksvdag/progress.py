"""A minimal text progress bar for VTK ProgressEvents (no tqdm dependency)."""
import sys


class ProgressBar:
    """Draws ``label [#####-----]  50%`` on one line of a text stream; call it with a fraction.

    Parameters
    ----------
    label : str
        Text in front of the bar.
    stream : file, default: sys.stderr
        Where to draw.
    width : int, default: 30
        Number of characters of the bar.

    Examples
    --------
    >>> import io
    >>> out = io.StringIO()
    >>> with ProgressBar("compress", stream=out, width=4) as bar:
    ...     bar(0.5)
    >>> out.getvalue().splitlines()[-1].strip()
    'compress [####] 100%'
    """

    def __init__(self, label, stream=None, width=30):
        self.label = label
        self.stream = stream if stream is not None else sys.stderr
        self.width = width
        self._percent = -1

    def __call__(self, fraction):
        fraction = min(max(float(fraction), 0.0), 1.0)
        percent = int(fraction * 100)
        if percent == self._percent:  # redraw only when the number changes
            return
        self._percent = percent
        filled = int(round(fraction * self.width))
        bar = "#" * filled + "-" * (self.width - filled)
        self.stream.write(f"\r{self.label} [{bar}] {percent:3d}%")
        self.stream.flush()

    def close(self):
        """Draw 100% and end the line (only if something was drawn)."""
        if self._percent >= 0:
            self(1.0)
            self.stream.write("\n")
            self.stream.flush()
            self._percent = -1

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
