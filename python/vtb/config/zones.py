"""Track zones: the bridge of a configuration between an approach and an exit embankment
(docs/zones.md).

The bridge is the structure's bottom layer; the layers above it (rail, slab, base) are the
track, which runs on over both embankments. On an embankment the track's lowest layer rests
on the ground through a continuous support of stated stiffness and damping per unit length;
on the bridge it rests on the bridge as before. :func:`track_zones` lengthens the structure by
the two zones, moves everything on it by the approach length, makes the bridge a layer over
its own part of the structure, lays the track's discrete couplings (the fasteners) on their
spacing over the whole length, and adds the embankments' supports.
"""

from __future__ import annotations

import math
from typing import Optional

from .fields import Config, Coupling, check_new_length, checked_config
from ..errors import config_error

#: Ground support of an embankment per unit length (N/m²): a subgrade modulus K30 = 190 MPa/m,
#: the minimum for the bed of a ballastless high-speed track (TB 10001-2016), under the
#: 2.95 m wide base of a CRTS II slab track.
GROUND_STIFFNESS = 190e6 * 2.95
#: Its damping per unit length (N·s/m²): an assumed value, of the order vehicle–track models
#: give a subgrade; not a measured one (docs/zones.md).
GROUND_DAMPING = 1.0e5
#: Length (m) over which a wheel's force passes between the rigid track beyond the structure
#: and the modelled track (``solver.edge_ramp``): 10 m keeps the wheel forces within 2 % of
#: the static load where a car joins and leaves the track (docs/zones.md).
EDGE_RAMP = 10.0

# The position fields of each irregularity kind that lie along the track.
_POSITIONS = {"cosine_dip": ("start",), "corrugation": ("start", "end"), "rail_joint": ("position",),
              "dipped_weld": ("position",), "sampled": ("x0",)}


def track_zones(config: Config, approach: float = 50.0, exit: float = 50.0,
                ground_stiffness: float = GROUND_STIFFNESS, ground_damping: float = GROUND_DAMPING,
                tail: Optional[float] = None, edge_ramp: float = EDGE_RAMP) -> Config:
    """A copy of ``config`` with an approach embankment of ``approach`` m before its bridge and
    an exit embankment of ``exit`` m after it.

    The structure's length grows to approach + L + exit and every position on it (couplings,
    dampers, observation points, vehicles, forces, local defects) moves by ``approach``. The
    bottom layer (the bridge) covers [approach, approach + L]; the layers above it run over
    the whole length, the lowest of them on the ground (``ground_stiffness`` N/m²,
    ``ground_damping`` N·s/m² per unit length) along both embankments. An empty
    ``output.points`` becomes the bridge's middle. With ``tail`` (s), the run records that
    long after the last wheel has left the exit embankment (``solver.tail``).

    Vehicles may start before x = 0 and end beyond the structure: off it they run on a rigid
    track, and over the first and last ``edge_ramp`` m of the embankments (``solver.edge_ramp``)
    their forces pass smoothly between that rigid track and the modelled one (docs/zones.md
    measures the transient); each embankment must be at least that long. ``edge_ramp = 0``
    hands nothing over: a vehicle crossing the track's ends is then refused unless
    ``solver.edge_step`` asks for the step.

    Needs a finite-element structure (the bridge covers part of it) whose upper layers span
    the whole length. Raises :class:`vtb.ConfigError` naming the argument or field."""
    checked_config(config)
    for name, v in (("approach", approach), ("exit", exit)):
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0:
            raise config_error(name, v, "must be a finite length >= 0 (m)")
    for name, v in (("ground_stiffness", ground_stiffness), ("ground_damping", ground_damping)):
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0 or (name == "ground_stiffness" and v == 0):
            raise config_error(name, v, "must be a finite number " + ("> 0 (N/m²)" if name == "ground_stiffness" else ">= 0 (N·s/m²)"))
    if isinstance(edge_ramp, bool) or not isinstance(edge_ramp, (int, float)) or not math.isfinite(edge_ramp) or edge_ramp < 0:
        raise config_error("edge_ramp", edge_ramp, "must be a finite length >= 0 (m)")
    for name, v in (("approach", approach), ("exit", exit)):
        if v < edge_ramp:
            raise config_error(name, v, f"must be at least edge_ramp = {edge_ramp:g} m: the hand-over to the rigid track must not reach the bridge")
    if tail is not None and (isinstance(tail, bool) or not isinstance(tail, (int, float)) or not math.isfinite(tail) or tail < 0):
        raise config_error("tail", tail, "must be a finite duration >= 0 (s) or None")
    L = config.structure.length
    if not math.isfinite(L) or L <= 0:
        raise config_error("structure.length", L, "must be a finite length > 0 (m)")
    check_new_length(config, "exit" if exit > approach else "approach", float(approach) + L + float(exit), max(approach, exit))
    if config.discretisation.method != "fem":
        raise config_error("discretisation.method", config.discretisation.method,
                           "track zones need finite elements: the bridge covers only part of the structure")
    out = config.copy()
    st = out.structure
    if len(st.layers) < 2:
        raise config_error("structure.layers", [l.name for l in st.layers], "track zones need a bridge below the track (at least two layers)")
    for i, layer in enumerate(st.layers[:-1]):
        if layer.start is not None or layer.end is not None:
            raise config_error(f"structure.layers[{i}].start", layer.start, "the track layers must span the whole structure")
    a, old = float(approach), float(st.length)
    new = a + old + float(exit)
    bridge, bed = st.layers[-1], st.layers[-2]
    bridge.start, bridge.end = (bridge.start or 0.0) + a, (old if bridge.end is None else bridge.end) + a
    for layer in st.layers:
        layer.joints = [x + a for x in layer.joints]
    couplings = []
    for cp in st.couplings:
        if cp.kind == "discrete":
            track = bridge.name not in (cp.upper, cp.lower)
            if track and len(cp.positions) >= 2:
                spacing = cp.positions[1] - cp.positions[0]
                cp = Coupling.grid(cp.upper, cp.lower, cp.stiffness, cp.damping, spacing, new, (cp.positions[0] + a) % spacing)
            else:
                cp.positions = [x + a for x in cp.positions]
        else:
            cp.start, cp.end = (None if cp.start is None else cp.start + a), (None if cp.end is None else cp.end + a)
        couplings.append(cp)
    for lo, hi in ((0.0, a), (a + old, new)):
        if hi > lo:
            couplings.append(Coupling(bed.name, "ground", "continuous", float(ground_stiffness), float(ground_damping), start=lo, end=hi))
    st.couplings, st.length = couplings, new
    out.discretisation.fem_elements = max(1, int(round(out.discretisation.fem_elements * new / old)))
    for v in out.vehicles:
        v.x_front += a
    for f in out.forces:
        f.x0 += a
    for g in out.dampers:
        if g.positions is not None:
            g.positions = [x + a for x in g.positions]
        else:
            g.x0 += a
    out.output.points = [x + a for x in out.output.points] or [a + old / 2]
    for part in (out.irregularity, *out.irregularity.parts):
        for name in _POSITIONS.get(part.kind, ()):
            setattr(part, name, getattr(part, name) + a)
    if tail is not None:
        out.solver.tail = tail
    out.solver.edge_ramp = float(edge_ramp)
    return out


def bridge_extent(config: Config) -> tuple:
    """(start, end) of the bridge, the structure's bottom layer (m)."""
    b = config.structure.layers[-1]
    return (b.start or 0.0, config.structure.length if b.end is None else b.end)
