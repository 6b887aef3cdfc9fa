"""Keyword checking shared by the public functions: an unknown option is a TypeError that names
the closest option names, instead of Python's bare "unexpected keyword argument"."""
import difflib
import functools
import inspect


def keywords_checked(function):
    """Makes an unknown keyword argument of ``function`` a TypeError that suggests the closest
    option names (difflib)."""
    parameters = inspect.signature(function).parameters

    @functools.wraps(function)
    def checked(*args, **kwargs):
        unknown = sorted(set(kwargs) - set(parameters))
        if unknown:
            hints = []
            for option in unknown:
                close = difflib.get_close_matches(option, parameters, n=3)
                hints.append(f"{option!r}" + (f" (did you mean {' or '.join(map(repr, close))}?)"
                                              if close else ""))
            raise TypeError(f"{function.__name__}() got unknown options: {', '.join(hints)}")
        return function(*args, **kwargs)

    return checked


def close_names(value, names):
    """" (did you mean 'x'?)" for the closest of ``names`` to the string ``value``, else ""."""
    close = difflib.get_close_matches(value, list(names), n=3) if isinstance(value, str) else []
    return f" (did you mean {' or '.join(map(repr, close))}?)" if close else ""
