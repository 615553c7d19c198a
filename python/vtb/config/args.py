"""Checks of the plain arguments of the public functions (counts, seeds, numbers, paths, flags):
each raises :class:`~vtb.errors.ConfigError` naming the argument and its value before any
work. Configuration fields are checked by the core; these are the arguments that never reach
it."""

from __future__ import annotations

import math
import numbers
import os
from typing import Optional


#: Most worker threads a run or study may ask for: more than the largest machines' cores only
#: multiplies threads (a mistyped 10**6 started thousands before failing).
MAX_THREADS = 1024


def threads(v):
    """A ``threads`` argument: None (all cores) or a whole number from 1 to :data:`MAX_THREADS`."""
    return whole("threads", v, 1, MAX_THREADS, none=True)


def whole(name: str, v, low: int = 0, high: Optional[int] = None, none: bool = False):
    """``v`` as an int within [low, high] (``None`` allowed with ``none``)."""
    from ..errors import config_error

    if v is None and none:
        return None
    if isinstance(v, bool) or not isinstance(v, numbers.Integral) or v < low or (high is not None and v > high):
        span = f"from {low} to {high}" if high is not None else f">= {low}"
        raise config_error(name, v, f"must be a whole number {span}" + (" or None" if none else ""))
    return int(v)


def real(name: str, v, low: float = -math.inf, high: float = math.inf, none: bool = False, open_low: bool = False):
    """``v`` as a finite float within [low, high] (``(low, high]`` with ``open_low``)."""
    from ..errors import config_error

    if v is None and none:
        return None
    if isinstance(v, bool) or not isinstance(v, numbers.Real) or not math.isfinite(v) or v < low or v > high or (open_low and v == low):
        bounds = f"{'(' if open_low else '['}{low:g}, {high:g}]"
        raise config_error(name, v, f"must be a finite number in {bounds}" + (" or None" if none else ""))
    return float(v)


def flag(name: str, v) -> bool:
    from ..errors import config_error

    if not isinstance(v, (bool, numbers.Integral)) or v not in (0, 1):
        raise config_error(name, v, "must be True or False")
    return bool(v)


def path(name: str, v, none: bool = False):
    """``v`` as a path (str or os.PathLike, not empty)."""
    from pathlib import Path

    from ..errors import config_error

    if v is None and none:
        return None
    if isinstance(v, bool) or not isinstance(v, (str, os.PathLike)) or not os.fspath(v) or "\0" in str(os.fspath(v)):
        raise config_error(name, v, "must be a file path (a non-empty str or os.PathLike)" + (" or None" if none else ""))
    return Path(v)


def choice(name: str, v, options) -> str:
    from ..errors import config_error

    if not isinstance(v, str) or v not in options:
        raise config_error(name, v, f"must be one of {', '.join(map(repr, options))}")
    return v


def mapping(name: str, v, none: bool = False):
    """``v``, a mapping with non-empty string keys (field paths)."""
    from collections.abc import Mapping

    from ..errors import config_error

    if v is None and none:
        return None
    if not isinstance(v, Mapping):
        raise config_error(name, v, "must be a mapping {field path: value}, e.g. {'tids': None}")
    for k in v:
        if not isinstance(k, str) or not k.strip():
            raise config_error(f"{name}[{k!r}]", k, "a key must be a field path (a non-empty string such as 'speed')")
    return v
