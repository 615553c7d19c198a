"""Spans as data: re-span a configuration's bridge over spans of any lengths, continuous or
simply supported, on piers or bearings of their own stiffness (docs/track.md).

The bridge is the structure's bottom layer; its supports are the discrete couplings from it to
the ground. :func:`spans` replaces those with one support per pier (and abutment) at the span
ends — or, for simply supported spans, cuts the girder at each span end (a joint) and puts a
bearing on either side of it — stretches the structure to the spans' total length, re-lays
every other discrete coupling (the fasteners) on its own spacing over the new length, and
scales the modal bases and uniform meshes with the length so that they keep resolving the
same wavelengths.
"""

from __future__ import annotations

import math
import numbers
from typing import Sequence, Union

import numpy as np

from .fields import Config, Coupling, check_new_length, checked_config
from ..errors import config_error

#: Stiffness (N/m) of a rigid support: the article's piers.
RIGID = 1e15
#: Distance (m) from a simply supported girder's end to its bearing: the standard 32 m box
#: girder of Chinese high-speed lines is 32.6 m long with 31.5 m between bearings.
BEARING_OFFSET = 0.55
#: The most spans :func:`spans` takes (a 100 km viaduct of 32 m spans has about 3 000).
MAX_SPANS = 10_000


def spans(config: Config, lengths: Sequence[float], pier_stiffness: Union[float, Sequence[float]] = RIGID,
          pier_damping: Union[float, Sequence[float]] = 0.0, simply_supported: bool = False,
          bearing_offset: float = BEARING_OFFSET) -> Config:
    """A copy of ``config`` whose bridge runs continuously over spans of ``lengths`` (m, from
    x = 0), supported at the n + 1 span ends by piers and abutments of ``pier_stiffness``
    (N/m; one value, or one per support from x = 0) and ``pier_damping`` (N·s/m, likewise).

    ``simply_supported=True``: each span is its own girder instead — the bridge layer is cut at
    every inner span end (``Layer.joints``, finite elements only) and each girder rests on two
    bearings ``bearing_offset`` (m) inside its ends, so a support stiffness or damping is given
    per bearing (one value, or 2n from x = 0).

    Also: the structure's length becomes Σ lengths; every other discrete coupling keeps its
    first position and spacing over the new length; modal layers keep their modes per metre
    and a uniform finite-element mesh its elements per metre; an empty ``output.points`` is set
    to the middle of the middle span (of the longer of the two middle spans for an even count),
    where the default mid-length could fall on a pier. Vehicles, forces and dampers keep their
    positions (the run checks them against the new length).

    Raises :class:`vtb.ConfigError` naming the argument for an empty or non-positive list of
    lengths (or one of a non-number), more than :data:`MAX_SPANS` spans, a total length beyond
    the plausible ``structure.length`` (docs/limits.md), a per-support list of the wrong length
    or with negative values, or a field of ``config`` of the wrong type — all before any work."""
    checked_config(config)
    lengths = _as_list(lengths, "lengths")
    if not lengths:
        raise config_error("lengths", lengths, "needs at least one span")
    for i, v in enumerate(lengths):
        if isinstance(v, bool) or not isinstance(v, numbers.Real) or not math.isfinite(v) or v <= 0:
            raise config_error(f"lengths[{i}]", v, "must be a finite length > 0 (m)")
    lengths = [float(v) for v in lengths]
    if len(lengths) > MAX_SPANS:
        raise config_error("lengths", f"{len(lengths)} spans", f"at most {MAX_SPANS} spans")
    if not isinstance(simply_supported, bool):
        raise config_error("simply_supported", simply_supported, "must be True or False")
    check_new_length(config, "lengths", math.fsum(lengths))
    ends = np.concatenate(([0.0], np.cumsum(lengths)))
    supports = ends
    if simply_supported:
        if config.discretisation.method != "fem":
            raise config_error("discretisation.method", config.discretisation.method,
                               "simply supported spans need finite elements (the girder is cut at each span end)")
        if isinstance(bearing_offset, bool) or not isinstance(bearing_offset, (int, float)) or not 0 < bearing_offset < min(lengths) / 2:
            raise config_error("bearing_offset", bearing_offset, f"must lie within (0, {min(lengths) / 2:g}) m: inside the shortest span's half")
        supports = np.ravel([[a + bearing_offset, b - bearing_offset] for a, b in zip(ends[:-1], ends[1:])])
    k = _per_support(pier_stiffness, supports.size, "pier_stiffness", positive=True)
    c = _per_support(pier_damping, supports.size, "pier_damping", positive=False)
    out = config.copy()
    st = out.structure
    if len(st.layers) < 2:
        raise config_error("structure.layers", [l.name for l in st.layers], "spans need a bridge below the track (at least two layers)")
    if st.layers[-1].start is not None or st.layers[-1].end is not None:
        raise config_error("structure.layers[-1].start", st.layers[-1].start,
                           "the bridge already covers part of the structure: re-span it before adding track zones")
    bridge = st.layers[-1].name
    old, new = float(st.length), float(ends[-1])
    if not math.isfinite(old) or old <= 0:
        raise config_error("structure.length", st.length, "must be a finite length > 0 (m)")
    couplings = []
    for cp in st.couplings:
        if cp.upper == bridge and cp.lower == "ground" and cp.kind == "discrete":
            continue  # the old supports
        if cp.kind == "discrete" and len(cp.positions) >= 2:
            first, spacing = cp.positions[0], cp.positions[1] - cp.positions[0]
            cp = Coupling.grid(cp.upper, cp.lower, cp.stiffness, cp.damping, spacing, new, first)
        couplings.append(cp)
    groups: dict = {}
    for x, ki, ci in zip(supports, k, c):
        groups.setdefault((ki, ci), []).append(float(x))
    couplings += [Coupling(bridge, "ground", "discrete", ki, ci, xs) for (ki, ci), xs in groups.items()]
    st.couplings = couplings
    st.layers[-1].joints = [float(x) for x in ends[1:-1]] if simply_supported else []
    st.length = new
    ratio = new / old
    for layer in st.layers:
        layer.modes = max(1, int(round(layer.modes * ratio)))
        if layer.local_modes:
            layer.local_modes = max(1, int(round(layer.local_modes * ratio)))
    out.discretisation.fem_elements = max(1, int(round(out.discretisation.fem_elements * ratio)))
    if not out.output.points:
        n = len(lengths)
        middle = n // 2 if n % 2 else max(n // 2 - 1, n // 2, key=lambda i: lengths[i])
        out.output.points = [float(ends[middle] + lengths[middle] / 2)]
    return out


def _as_list(v, name: str) -> list:
    if isinstance(v, (str, bytes, dict, set)) or not hasattr(v, "__iter__") or getattr(v, "ndim", 1) != 1:
        raise config_error(name, v, "expected a list of numbers")
    return list(v)


def _per_support(v, n: int, name: str, positive: bool) -> list:
    values = [v] * n if isinstance(v, (int, float)) and not isinstance(v, bool) else _as_list(v, name)
    if len(values) != n:
        raise config_error(name, v, f"needs one value or one per support ({n}, from x = 0)")
    for i, x in enumerate(values):
        if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x) or (x <= 0 if positive else x < 0):
            raise config_error(f"{name}[{i}]" if not isinstance(v, (int, float)) else name, x, "must be a finite number " + ("> 0" if positive else ">= 0"))
    return [float(x) for x in values]
