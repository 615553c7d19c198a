"""The configuration schema of the Rust core: the one definition of every field, type and
default. The dataclasses of :mod:`vtb.config` take their defaults from it, and
``tests/test_schema.py`` holds their fields and types to it."""

from __future__ import annotations

import copy
import dataclasses
import json
from typing import Any

from . import _core

#: The JSON schema of the core's configuration (``$defs`` holds one entry per struct).
SCHEMA: dict = json.loads(_core.schema())


def properties(struct: str) -> dict:
    """The schema properties of a core struct (``"Config"`` is the root)."""
    return SCHEMA["properties"] if struct == "Config" else SCHEMA["$defs"][struct]["properties"]


def default(struct: str, name: str) -> Any:
    """A dataclass field holding the core's default of ``struct.name`` (a fresh copy per
    instance for lists and tables)."""
    value = properties(struct)[name]["default"]
    if isinstance(value, (list, dict)):
        return dataclasses.field(default_factory=lambda: copy.deepcopy(value))
    return value


class StrictFields:
    """Base of the configuration dataclasses: assigning an attribute the class does not
    declare (``cfg.sped = 100``) raises :class:`~vtb.errors.ConfigError` with the known
    names instead of silently adding it."""

    __slots__ = ()

    def __setattr__(self, name: str, value) -> None:
        fields = getattr(type(self), "__dataclass_fields__", None)
        if fields is not None and name not in fields:
            from .errors import config_error

            known = ", ".join(sorted(fields))
            raise config_error(name, value, f"{type(self).__name__} has no such field (known: {known})")
        object.__setattr__(self, name, value)
