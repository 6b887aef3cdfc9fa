"""Run a VTK algorithm and turn its errors into Python exceptions.

VTK reports failures through ``vtkErrorMacro``: the message goes to an ``ErrorEvent`` observer
when there is one, otherwise it is printed and the pipeline carries on with an empty output.
Every call into a VTK pipeline in this package goes through :func:`run_algorithm`, so that a bad
file or bad input surfaces as one exception carrying VTK's own message.
"""
import contextlib
import re
import warnings

from vtkmodules.util.misc import calldata_type
from vtkmodules.vtkCommonCore import VTK_STRING, vtkCommand
from vtkmodules.vtkCommonMisc import vtkErrorCode

# Error codes of readers and writers that say the file itself is the problem.
_FILE_ERROR_CODES = {
    vtkErrorCode.CannotOpenFileError,
    vtkErrorCode.UnrecognizedFileTypeError,
    vtkErrorCode.PrematureEndOfFileError,
    vtkErrorCode.FileFormatError,
    vtkErrorCode.NoFileNameError,
    vtkErrorCode.OutOfDiskSpaceError,
}

# "ERROR: In /path/file.cxx, line 12\nvtkClass (0x55d0c1a2): the message\n\n"
_HEADER = re.compile(r"^(?:ERROR|Warning): In .*?, line \d+\s*\n\s*\w+ \(0x[0-9a-fA-F]+\):\s*", re.S)


def clean_vtk_message(text):
    """Strip the source-location header VTK puts in front of an error message."""
    text = _HEADER.sub("", str(text)).strip()
    return " ".join(line.strip() for line in text.splitlines() if line.strip())


def _error_collector(messages):
    """An ErrorEvent observer that appends messages to ``messages`` instead of printing them."""

    # VTK passes the message as call data only when the callback declares a string call data type.
    @calldata_type(VTK_STRING)
    def on_error(caller, event, message):
        messages.append(clean_vtk_message(message))

    return on_error


@contextlib.contextmanager
def _collected_errors(objects):
    """Within the block, the cleaned messages of the ErrorEvents of ``objects`` (a sequence)."""
    messages = []
    on_error = _error_collector(messages)
    tags = [(obj, obj.AddObserver(vtkCommand.ErrorEvent, on_error)) for obj in objects]
    try:
        yield messages
    finally:
        for obj, tag in tags:
            obj.RemoveObserver(tag)


@contextlib.contextmanager
def vtk_errors_raised(objects, error=RuntimeError):
    """Within the block, ErrorEvents of ``objects`` are collected; on leaving, the first one
    is raised as ``error`` (VTK would only print it).

    Parameters
    ----------
    objects : vtkObject or sequence of vtkObject
        The objects whose errors count.
    error : type, default: RuntimeError
        The exception raised with VTK's message.
    """
    if not isinstance(objects, (list, tuple)):
        objects = [objects]
    with _collected_errors(objects) as messages:
        yield messages
    if messages:
        raise error(messages[0])


def run_algorithm(algorithm, *, action="Update", progress=None, error=ValueError, what=None):
    """Run ``algorithm.<action>()`` and raise if VTK reported an error.

    Parameters
    ----------
    algorithm : vtkAlgorithm
        The reader, writer or filter to run.
    action : str, default: "Update"
        The method to call ("Update" for filters and readers, "Write" for writers).
    progress : callable, optional
        Called with the algorithm's progress, a float in [0, 1], on every ProgressEvent. An
        exception it raises aborts the algorithm and is raised from here.
    error : type, default: ValueError
        Exception raised for errors that are not about a file.
    what : str, optional
        A short description put in front of the message, for example the file name.

    Raises
    ------
    TypeError
        ``progress`` is not callable.
    Exception
        Whatever ``progress`` raised (the algorithm is aborted).
    FileNotFoundError
        The algorithm reports ``vtkErrorCode::FileNotFoundError``.
    OSError
        The algorithm reports another file error code (cannot open, truncated, bad format).
    error
        Any other error message from the algorithm or its executive.
    """
    if progress is not None and not callable(progress):
        raise TypeError(f"progress must be a callable taking a fraction, not {progress!r}")
    observed = [algorithm]
    executive = algorithm.GetExecutive() if hasattr(algorithm, "GetExecutive") else None
    if executive is not None:
        observed.append(executive)  # "returned failure for request" comes from the executive
    tags = []
    # An exception raised in an observer cannot travel through VTK's C++: VTK would print it and
    # carry on. The progress observer keeps it, asks the algorithm to stop, and it is raised
    # below once the call has returned.
    failures = []
    if progress is not None:

        def on_progress(caller, event):
            if failures:
                return
            try:
                progress(caller.GetProgress())
            except BaseException as e:  # noqa: B902 (KeyboardInterrupt too: Ctrl-C must stop it)
                failures.append(e)
                caller.SetAbortExecute(1)

        tags.append((algorithm, algorithm.AddObserver(vtkCommand.ProgressEvent, on_progress)))
    # The algorithm's warnings become Python warnings once it succeeded (VTK would print them);
    # its "was aborted" warning is about an abort asked for here, which raises instead.
    warnings_seen = []
    tags.append(
        (algorithm, algorithm.AddObserver(vtkCommand.WarningEvent, _error_collector(warnings_seen)))
    )
    try:
        with _collected_errors(observed) as messages:
            getattr(algorithm, action)()
    finally:
        for obj, tag in tags:
            obj.RemoveObserver(tag)
        if failures:
            algorithm.SetAbortExecute(0)  # the next update must run
    if failures:
        raise failures[0]

    code = algorithm.GetErrorCode() if hasattr(algorithm, "GetErrorCode") else 0
    if not messages and code == vtkErrorCode.NoError:
        for message in warnings_seen:
            warnings.warn(message, RuntimeWarning, stacklevel=3)
        return
    # The algorithm's own message explains; the executive's only says that the request failed.
    message = messages[0] if messages else vtkErrorCode.GetStringFromErrorCode(code)
    if what and what not in message:
        message = f"{what}: {message}"
    if code == vtkErrorCode.FileNotFoundError:
        raise FileNotFoundError(message)
    if code in _FILE_ERROR_CODES:
        raise OSError(message)
    raise error(message)
