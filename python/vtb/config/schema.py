"""The configuration schema of the Rust core: the one definition of every field, type and
default. The dataclasses of :mod:`vtb.config` take their defaults from it, and
``tests/test_schema.py`` holds their fields and types to it."""

from __future__ import annotations

import copy
import dataclasses
import inspect
import json
from typing import Any

from . import gateway
from ..errors import config_error

#: The JSON schema of the core's configuration (``$defs`` holds one entry per struct).
SCHEMA: dict = gateway.schema()


def node(struct: str) -> dict:
    """The schema of a core struct (``"Config"`` is the root); ``"Enum.variant"`` is the table
    of one variant of a tagged enum of tables (``"VehicleConfig.quarter_car"``)."""
    if struct == "Config":
        return SCHEMA
    name, _, variant = struct.partition(".")
    n = SCHEMA["$defs"][name]
    return next(v for v in n["oneOf"] if v.get("title") == variant) if variant else n


def properties(struct: str) -> dict:
    """The schema properties of a core struct (see :func:`node`)."""
    return node(struct)["properties"]


def default(struct: str, name: str) -> Any:
    """A dataclass field holding the core's default of ``struct.name`` (a fresh copy per
    instance for lists and tables)."""
    value = properties(struct)[name]["default"]
    if isinstance(value, (list, dict)):
        return dataclasses.field(default_factory=lambda: copy.deepcopy(value))
    return value


def description(struct: str, name: str) -> str:
    """The core's doc comment of field ``struct.name`` (its meaning and unit), one paragraph."""
    return " ".join(properties(struct)[name].get("description", "").split())


def documented(struct: str, **python_only: str):
    """Class decorator: appends to the docstring an ``Attributes`` section listing every field
    with the core's description of ``struct`` (the one place a field's meaning and unit are
    written); ``python_only`` documents the fields the core does not have."""

    def decorate(cls):
        lines = [inspect.cleandoc(cls.__doc__ or cls.__name__), "", "Attributes", "----------"]
        for f in dataclasses.fields(cls):
            text = python_only.get(f.name) or description(struct, f.name)
            prop = properties(struct).get(f.name, {})
            if "default" in prop and not isinstance(prop["default"], (dict, list)):
                text += f" Default: ``{json.dumps(prop['default'])}``."
            lines += [f"{f.name}", f"    {text}"]
        cls.__doc__ = "\n".join(lines) + "\n"
        cls.__schema_struct__ = struct
        return cls

    return decorate


class StrictFields:
    """Base of the configuration dataclasses: assigning an attribute the class does not
    declare (``cfg.sped = 100``) raises :class:`~vtb.errors.ConfigError` with the known
    names instead of silently adding it, naming the full dotted path from the configuration
    (``solver.time_step``, ``structure.layers[0].densty``). Each nested configuration knows
    where it was assigned (its parent and field) for that message."""

    __slots__ = ()

    def __setattr__(self, name: str, value) -> None:
        fields = getattr(type(self), "__dataclass_fields__", None)
        if isinstance(getattr(type(self), name, None), property):
            return object.__setattr__(self, name, value)  # a property's setter checks the value
        if fields is not None and name not in fields:
            known = ", ".join(sorted(fields))
            raise config_error(self._field_path(name), value, f"{type(self).__name__} has no such field (known: {known})")
        object.__setattr__(self, name, value)
        if isinstance(value, StrictFields):
            object.__setattr__(value, "_vtb_owner", (self, name))
        elif isinstance(value, list):
            for i, item in enumerate(value):
                if isinstance(item, StrictFields):
                    object.__setattr__(item, "_vtb_owner", (self, f"{name}[{i}]"))

    def _field_path(self, name: str) -> str:
        """``name`` prefixed by where this object sits in its configuration."""
        owner = getattr(self, "_vtb_owner", None)
        if owner is None:
            return name
        parent, key = owner
        return parent._field_path(f"{key}.{name}")
