"""A configuration made ready for the core: the one way a run reaches it.

:func:`prepare` makes the core JSON of a configuration once and, from it, checks the plausible
ranges, the irregularity (which lives on this side), warns of indices and band levels beyond
the band the run resolves, and samples the irregularity profile the wheels roll on
(:func:`irregularity_profile`, shared by the runs on one sample). The core validates the rest
once, when it runs the configuration; :meth:`vtb.Config.validate` asks it now.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import threading
import typing
import warnings
from collections import OrderedDict
from typing import NamedTuple, Optional

import numpy as np

from . import gateway
from .fields import Config, check_types, to_plain
from .irregularity import Irregularity
from .resolution import ResolutionWarning, check_excitation, out_of_band, real_or_none, resolved_band, warn_beyond
from ..errors import VtbError, config_error

#: Extra length of generated irregularity beyond the structure at each end (m).
PROFILE_MARGIN = 0.0


class SampledProfile(NamedTuple):
    """What the wheels of a run roll on, on the grid x0 + i·dx (m): the rail's irregularity
    ``values`` (m, positive = dip) and, with a wheel flat, one ``treads`` row per wheel (m, an
    empty array for a round wheel; vehicles in order, wheelsets front to rear)."""

    x0: float
    dx: float
    values: np.ndarray
    treads: list

    def core_args(self) -> tuple:
        """The profile as the core takes it: (x0, dx, values or None, treads)."""
        return self.x0, self.dx, self.values if self.values.size else None, self.treads


def prepare(cfg: Config, full: bool = False) -> tuple[str, SampledProfile]:
    """The core JSON of a configuration and its irregularity profile, the plausible ranges and
    the irregularity checked and the resolution warnings given (module docstring); every check
    that needs no profile is made before the profile is drawn (``full``: for a run that records
    full histories)."""
    if not isinstance(cfg, Config):
        raise config_error("config", type(cfg).__name__, "expected a vtb.Config")
    _check_sections(cfg)
    text = cfg.to_core_json()
    # A unit mistake (a speed in km/h) is named before the irregularity's checks it would trip.
    gateway.check_plausible(text)
    if not isinstance(cfg.irregularity, Irregularity):
        raise config_error("irregularity", cfg.irregularity, "expected a vtb.Irregularity")
    check_types(cfg.irregularity, "irregularity")
    vehicles = cfg.vehicles if isinstance(cfg.vehicles, list) else []
    cfg.irregularity.validate(speed=real_or_none(cfg.speed), dt=real_or_none(getattr(cfg.solver, "dt", None)),
                              wheel_radii=[v.wheel_radius for v in vehicles for _ in range(v.n_wheels)],
                              extent=_rolled_extent(cfg, text))
    _warn_band_limit(cfg, text)
    shortest = _check_excitation(cfg, text)
    # Every check that needs no profile (a run too long, a wheel crossing a rail end, the memory
    # budget) answers in microseconds: before the profile, which may take seconds to draw.
    gateway.validate(text, full=full)
    return text, irregularity_profile(cfg, text, shortest)


def _check_sections(cfg: Config) -> None:
    """Each section of ``cfg`` (``structure``, ``discretisation``, ``solver``, ...) is its
    dataclass: a table put in its place would reach the core but not the Python checks."""
    hints = typing.get_type_hints(Config)
    for f in dataclasses.fields(cfg):
        kind, value = hints[f.name], getattr(cfg, f.name)
        if dataclasses.is_dataclass(kind) and not isinstance(value, kind):
            raise config_error(f.name, value, f"expected a vtb.{kind.__name__} (Config.from_dict reads a table)")


def _rolled_extent(cfg: Config, text: str) -> Optional[tuple]:
    """The stretch (m) the irregularity is drawn over: the structure and every wheel's travel
    (``None`` when the core refuses the configuration; the run then names the field)."""
    L = real_or_none(getattr(cfg.structure, "length", None))
    if L is None or L <= 0:
        return None
    try:
        travel = gateway.wheel_travel(text)
    except (VtbError, ValueError, TypeError):
        return None
    return (min(0.0, travel[0]), max(L, travel[1])) if travel else (0.0, L)


def _warn_band_limit(cfg: Config, text: str) -> None:
    """A band-limited index beyond the band the run resolves for its top layer, or a band level
    (``output.band_levels``) beyond the band of its layer, warns (:class:`vtb.ResolutionWarning`);
    a configuration the core refuses is left to the run, which names the field."""
    fc = real_or_none(getattr(cfg.output, "band_limit", None))
    layers = getattr(cfg.structure, "layers", None)
    if not layers:
        return
    bands = [b for b in (real_or_none(b) for b in (getattr(cfg.output, "band_levels", None) or [])) if b is not None and b > 0]
    if fc is None and not bands:
        return
    try:
        resolved = resolved_band(cfg, text)
        if fc is not None:
            warn_beyond(cfg, layers[0].name, fc, "output.band_limit", band=resolved)
        if bands:
            # the top band's upper edge: exact base-10 midband · 10^(1/20) (docs/spectra.md)
            top = 1000.0 * 10.0 ** (round(10.0 * np.log10(max(bands) / 1000.0)) / 10.0 + 0.05)
            # one warning for the cause (the top band), naming every layer it exceeds
            beyond = [(l.name, b.f_max, b.limited_by) for l in layers
                      if (b := resolved.layers.get(l.name)) is not None and top > b.f_max]
            if beyond:
                where = "; ".join(f"{name} {f:.0f} Hz (its {by})" for name, f, by in beyond)
                warnings.warn(f"output.band_levels ({max(bands):g} Hz band) reaches {top:.0f} Hz, beyond the band this "
                              f"discretisation resolves for {where} (vtb.resolved_band(config))", ResolutionWarning, stacklevel=4)
    except (VtbError, AttributeError, TypeError):
        pass


def _check_excitation(cfg: Config, text: str) -> dict:
    """Each irregularity part against the band the model resolves for the rail
    (:func:`vtb.config.resolution.check_excitation`): what the run keeps of the parts beyond it.
    A configuration the core refuses is left to the run, which names the field."""
    try:
        band = resolved_band(cfg, text)
    except (VtbError, AttributeError, TypeError):
        return {}
    return check_excitation(cfg, band)


def _shortest(cfg: Config, text: str) -> dict:
    """The parts a run filters to its grade, silently (:func:`_check_excitation` warns)."""
    try:
        return {p.path: p.shortest for p in out_of_band(cfg, resolved_band(cfg, text))}
    except (VtbError, AttributeError, TypeError):
        return {}


#: Bytes of generated profiles this process keeps (the least recently used go first).
PROFILE_CACHE_BYTES = 256 * 2**20
_profiles: OrderedDict = OrderedDict()  # key → (profile, the warnings drawing it gave)
_profiles_lock = threading.Lock()
if hasattr(os, "register_at_fork"):  # a child forked while another thread held the lock gets a free one
    os.register_at_fork(after_in_child=lambda: globals().update(_profiles_lock=threading.Lock()))


def _nbytes(profile: SampledProfile) -> int:
    return profile.values.nbytes + sum(t.nbytes for t in profile.treads)


def irregularity_profile(cfg: Config, text: Optional[str] = None, shortest: Optional[dict] = None) -> SampledProfile:
    """The sampled irregularity a configuration runs on (arrays read-only): a stationary part
    that excites the rail beyond the band the model resolves without its wavelengths beyond it
    (:func:`vtb.config.resolution.check_excitation`; ``shortest`` as it returns, found here
    when not given). A structure length the core will refuse gets no profile (the core then
    names the length). ``text``: the configuration's core JSON when the caller has made it.

    A profile is a function of the irregularity, the stretch the wheels travel, the memory
    budget and the wheels' radii alone, and generating one costs tens of milliseconds: this
    process keeps the last ones (:data:`PROFILE_CACHE_BYTES`; a larger one is not kept), so the
    runs of a study on one sample — every design, every generation, every executor task on this
    worker — share it. The warnings drawing it gave are given again at every call."""
    L = real_or_none(getattr(cfg.structure, "length", None))
    if L is None or L <= 0:
        return SampledProfile(0.0, 1.0, np.zeros(0), [])
    budget = real_or_none(getattr(cfg.solver, "memory_budget", None))
    radii = [float(v.wheel_radius) for v in cfg.vehicles for _ in range(v.n_wheels)]
    # Wheels may start before the structure and end beyond it (on a rigid track).
    try:
        text = cfg.to_core_json() if text is None else text
        travel = gateway.wheel_travel(text)
    except (VtbError, ValueError, TypeError):  # refused later, naming the field
        travel = None
    lo, hi = (min(0.0, travel[0]), max(L, travel[1])) if travel else (0.0, L)
    if shortest is None:
        shortest = _shortest(cfg, text) if text is not None else {}
    spec = json.dumps(to_plain(cfg.irregularity), default=repr)  # a measured profile's values too
    key = (hashlib.sha256(spec.encode()).hexdigest(), lo, hi, budget, tuple(radii), tuple(sorted(shortest.items())))
    with _profiles_lock:
        hit = _profiles.get(key)
        if hit is not None:
            _profiles.move_to_end(key)
    if hit is None:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            x0, dx, values, treads = cfg.irregularity.sample(lo - PROFILE_MARGIN, hi + PROFILE_MARGIN, memory_budget=budget,
                                                             wheel_radii=radii, shortest=shortest)
        if treads and not values.size:
            values = np.zeros(treads[0].size if treads[0].size else max(t.size for t in treads))
        for a in (values, *treads):
            a.flags.writeable = False  # shared by every run on this sample
        hit = (SampledProfile(x0, dx, values, treads), [(w.message, w.category) for w in caught])
        if _nbytes(hit[0]) <= PROFILE_CACHE_BYTES:
            with _profiles_lock:
                _profiles[key] = hit
                total = sum(_nbytes(p) for p, _ in _profiles.values())
                while total > PROFILE_CACHE_BYTES:
                    _, (old, _) = _profiles.popitem(last=False)
                    total -= _nbytes(old)
    profile, said = hit
    for message, category in said:
        warnings.warn(message, category, stacklevel=3)
    return profile


def validate(cfg: Config) -> None:
    """The core's whole check of a configuration now, against its generated irregularity
    (:meth:`vtb.Config.validate`)."""
    text, profile = prepare(cfg)
    gateway.validate(text, *profile.core_args())
