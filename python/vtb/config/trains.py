"""Train consists from the core's library of published cars.

:func:`train` places the cars of a formation one behind the other (their bodies end to end)
and returns their :class:`~vtb.config.Vehicle` s, ready for ``Config.vehicles``;
:func:`trains` lists the library with its sources. The numbers live in the Rust core
(``rust/src/trains.rs``); this module only arranges them.

>>> import vtb
>>> cfg = vtb.track_zones(vtb.paper_config(model="fast"), approach=20.0, exit=20.0)
>>> cfg.vehicles = vtb.train("velaro_e", cars=8, x_front=-5.0)
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass
from typing import Optional

from . import gateway
from .fields import Vehicle, check_types
from ..errors import config_error

_LIBRARY = {t["name"]: t for t in gateway.train_library()}
#: The most cars :func:`train` lays (a consist is at most a few hundred metres; ten 16-car
#: double units is far beyond any service).
MAX_CARS = 160


@dataclass(frozen=True)
class TrainInfo:
    """A train of the library: ``name`` (what :func:`train` takes), ``title``, ``source``
    (where each number comes from), ``roles`` of its cars in formation order and their
    ``lengths`` over the car bodies (m)."""

    name: str
    title: str
    source: str
    roles: tuple
    lengths: tuple


def trains() -> dict:
    """The train library: name → :class:`TrainInfo`."""
    out = {}
    for name, t in _LIBRARY.items():
        lengths = tuple(c["front_overhang"] + Vehicle(**c["vehicle"]).length + c["rear_overhang"] for c in t["cars"])
        out[name] = TrainInfo(name, t["title"], t["source"], tuple(c["role"] for c in t["cars"]), lengths)
    return out


def train(name: str = "crh3", cars: Optional[int] = None, x_front: float = 0.0, **fields) -> list:
    """The vehicles of a consist, front to back.

    Parameters
    ----------
    name
        A train of the library (:func:`trains`): ``"crh3"`` (the article's CRH3, 4 motor and
        4 trailer cars) or ``"velaro_e"`` (Siemens Velaro E / RENFE AVE S-103).
    cars
        Number of cars (count, ≥ 1): the first ``cars`` of the formation, which repeats as
        coupled units beyond its length (16 = a double unit). Default: one unit.
    x_front
        Position (m) of the leading wheelset at t = 0. Cars may start before the structure
        (x < 0): off it they run on a rigid track, and a wheel that crosses an end of the rail
        needs ``solver.edge_ramp`` (:func:`vtb.track_zones` sets it) or ``solver.edge_step``,
        or the run is refused.
    **fields
        Vehicle fields set on every car, e.g. ``contact_patch=True`` or ``rails=2``.

    Raises
    ------
    ConfigError
        Unknown train, a car count outside 1 … :data:`MAX_CARS`, a non-finite or non-numeric
        ``x_front``, an unknown vehicle field or a value of the wrong type for one (checked
        before any car is laid).
    """
    if not isinstance(name, str) or name not in _LIBRARY:
        raise config_error("name", name, f"unknown train (known: {sorted(_LIBRARY)})")
    formation = _LIBRARY[name]["cars"]
    n = len(formation) if cars is None else cars
    if isinstance(n, bool) or not isinstance(n, numbers.Integral) or not 1 <= n <= MAX_CARS:
        raise config_error("cars", cars, f"must be a whole number of cars from 1 to {MAX_CARS}")
    n = int(n)
    if isinstance(x_front, bool) or not isinstance(x_front, numbers.Real) or not math.isfinite(x_front):
        raise config_error("x_front", x_front, "must be a finite position (m)")
    known = set(Vehicle.__dataclass_fields__) - {"x_front"}
    for f in fields:
        if f not in known:
            raise config_error(f, fields[f], f"not a vehicle field (known: {sorted(known)})")
    probe = Vehicle(**formation[0]["vehicle"])
    for f, value in fields.items():
        setattr(probe, f, value)
    check_types(probe)
    out, x = [], float(x_front)
    for i in range(n):
        car = formation[i % len(formation)]
        if i:
            x -= formation[(i - 1) % len(formation)]["rear_overhang"] + car["front_overhang"]
        v = Vehicle(**{**car["vehicle"], "x_front": x})
        for f, value in fields.items():
            setattr(v, f, value)
        out.append(v)
        x -= v.length
    return out


def consist_extent(vehicles: list) -> tuple:
    """(rearmost, leading) wheelset positions (m) at t = 0 of a list of vehicles."""
    return min(v.x_front - v.length for v in vehicles), max(v.x_front for v in vehicles)
