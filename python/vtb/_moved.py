"""The old flat module paths (``vtb.simulate``, ``vtb.moga``, …) for one release."""

import importlib
import warnings


def moved(old: str, new: str):
    """The module at ``new``, after a :class:`DeprecationWarning` naming it: an old path's file
    puts it in ``sys.modules`` under its own name, so the old name is the same module object
    (``monkeypatch.setattr(vtb.scaleout, ...)`` reaches the real one)."""
    warnings.warn(f"{old} has moved to {new}; the old path goes in the next release", DeprecationWarning, stacklevel=3)
    return importlib.import_module(new)
