"""What a bridge check is asked: :class:`BridgeCheck`, a dataclass that refuses unknown fields
and loads from the ``[bridge_check]`` table of a configuration's TOML file
(:func:`split_toml`)."""

from __future__ import annotations

import dataclasses
import math
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional, Union

from ..config.fields import Config
from ..config.schema import StrictFields
from ..config.trains import trains as library_trains
from ..errors import config_error
from .checks import ACCELERATION_LIMITS
from .damping import BRIDGE_TYPES
from .scan import MAX_SPEEDS, MAX_STEP

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

#: The ten HSLM-A trains, the default trains of a check.
HSLM_ALL = [f"HSLM-A{i}" for i in range(1, 11)]


@dataclass
class BridgeCheck(StrictFields):
    """The questions of an EN 1991-2 §6.4.6 dynamic analysis of one configuration's bridge.

    Attributes
    ----------
    span
        The span L (m) the code's rules take: Table 6.6's and Δζ's, Fig. 6.10's, and the
        determinant length LΦ unless ``l_phi`` is given.
    bridge_type
        Table 6.6's row: ``"steel_composite"``, ``"prestressed_concrete"`` or
        ``"reinforced_concrete"`` (filler beam and reinforced concrete).
    track
        ``"ballasted"`` (3.5 m/s²) or ``"direct_fastened"`` (5 m/s²), EN 1990 A2.4.4.2.1.
    line_speed
        The line's maximum speed (m/s); the scan runs to 1.2 × it (§6.4.6.2(1)).
    v_min
        The scan's lowest speed (m/s). Default 40 km/h.
    step
        The scan's step (m/s), at most 10 km/h; around each resonance it is 5 times finer.
    trains
        Load trains (names of :func:`vtb.load_trains`, CSV paths). Default: HSLM-A1 … A10.
    mass_bounds
        Bounds of the deck's mass: name → factor on the deck's density (e.g. ``{lower = 1.0,
        upper = 1.15}`` for the ballast's least and greatest density and depth).
    interaction
        Add Δζ (eq. 6.13) to Table 6.6's damping (moving loads stand in for the vehicles).
    vehicles
        Beyond the code: library trains (:func:`vtb.trains`) run as vehicles with full
        interaction over the same speeds, on a smooth rail, with Table 6.6's damping without
        Δζ (:func:`vtb.bridge.interaction.interaction_scan`), reported beside the moving loads
        (add the same names to ``trains`` to compare train by train). Default: none.
    n0
        The deck's first bending frequency (Hz); default: computed from the structure.
    band
        The acceleration's band (Hz); default max(30 Hz, 1.5·n0, n3), EN 1990 A2.4.4.2.1.
    share
        Share of each axle load on the modelled track (1: the whole deck; 0.5: one of two rails).
    alpha
        LM71's classification factor α (§6.3.2(3)).
    maintenance
        ``"careful"`` (Φ2, and φ''/2 for the real trains) or ``"standard"`` (Φ3, φ''), §6.4.5.2.
    l_phi
        The determinant length LΦ (m) of Table 6.2; default ``span``.
    comfort_ratio
        L/δ of EN 1990 Fig. A2.3 for the span and speed (very good comfort), read by the user;
        the comfort check is not evaluated without it.
    simple_structure, continuous
        For Fig. 6.9's flow chart.
    dt
        Time step (s); default 1/(100 × band).
    tail
        Free vibration (s) recorded after the last axle.
    """

    span: float
    bridge_type: str
    track: str
    line_speed: float
    v_min: float = 40.0 / 3.6
    step: float = 5.0 / 3.6
    trains: list = field(default_factory=lambda: list(HSLM_ALL))
    mass_bounds: dict = field(default_factory=lambda: {"nominal": 1.0})
    interaction: bool = True
    vehicles: list = field(default_factory=list)
    n0: Optional[float] = None
    band: Optional[float] = None
    share: float = 1.0
    alpha: float = 1.0
    maintenance: str = "careful"
    l_phi: Optional[float] = None
    comfort_ratio: Optional[float] = None
    simple_structure: bool = True
    continuous: bool = False
    dt: Optional[float] = None
    tail: float = 0.5

    def validate(self) -> None:
        """Raises :class:`vtb.ConfigError` naming the first bad field."""
        for name in ("span", "line_speed", "v_min", "step", "share", "alpha"):
            _number(f"bridge_check.{name}", getattr(self, name), positive=True)
        for name in ("n0", "band", "l_phi", "comfort_ratio", "dt"):
            if getattr(self, name) is not None:
                _number(f"bridge_check.{name}", getattr(self, name), positive=True)
        _number("bridge_check.tail", self.tail, positive=False)
        if not isinstance(self.bridge_type, str) or self.bridge_type not in BRIDGE_TYPES:
            raise config_error("bridge_check.bridge_type", self.bridge_type, f"must be one of {', '.join(BRIDGE_TYPES)} (EN 1991-2 Table 6.6)")
        if not isinstance(self.track, str) or self.track not in ACCELERATION_LIMITS:
            raise config_error("bridge_check.track", self.track, f"must be one of {', '.join(ACCELERATION_LIMITS)}")
        if self.maintenance not in ("careful", "standard"):
            raise config_error("bridge_check.maintenance", self.maintenance, "must be \"careful\" (Φ2) or \"standard\" (Φ3)")
        if self.step > MAX_STEP + 1e-12:
            raise config_error("bridge_check.step", self.step, f"must be at most {MAX_STEP:.4g} m/s (10 km/h, EN 1991-2 §6.4.6.2)")
        if self.share > 1:
            raise config_error("bridge_check.share", self.share, "is a share of the axle load: at most 1")
        if self.v_min >= 1.2 * self.line_speed:
            raise config_error("bridge_check.v_min", self.v_min, f"must lie below 1.2 × line_speed = {1.2 * self.line_speed:g} m/s")
        if (1.2 * self.line_speed - self.v_min) / self.step > MAX_SPEEDS:  # too many speeds even at 10 km/h: the line speed is wrong
            wrong = "line_speed" if (1.2 * self.line_speed - self.v_min) / MAX_STEP > MAX_SPEEDS else "step"
            raise config_error(f"bridge_check.{wrong}", getattr(self, wrong),
                               f"makes more than {MAX_SPEEDS} speeds from v_min to 1.2 × line_speed at steps of {self.step:g} m/s")
        if not isinstance(self.trains, (list, tuple)) or not self.trains or not all(isinstance(t, str) for t in self.trains):
            raise config_error("bridge_check.trains", self.trains, "must be a non-empty list of train names or CSV paths")
        known = library_trains()
        if not isinstance(self.vehicles, (list, tuple)) or not all(isinstance(t, str) and t in known for t in self.vehicles):
            raise config_error("bridge_check.vehicles", self.vehicles, f"must be a list of the library's trains ({', '.join(sorted(known))})")
        if not isinstance(self.mass_bounds, dict) or not self.mass_bounds:
            raise config_error("bridge_check.mass_bounds", self.mass_bounds, "must be a table name → factor on the deck's density")
        for k, v in self.mass_bounds.items():
            _number(f"bridge_check.mass_bounds.{k}", v, positive=True)
        for name in ("interaction", "simple_structure", "continuous"):
            if not isinstance(getattr(self, name), bool):
                raise config_error(f"bridge_check.{name}", getattr(self, name), "must be true or false")

    @classmethod
    def from_dict(cls, data: dict) -> "BridgeCheck":
        """From a plain table; unknown or missing fields raise :class:`vtb.ConfigError`."""
        if not isinstance(data, dict):
            raise config_error("bridge_check", data, "expected a table")
        names = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(data) - names)
        if unknown:
            raise config_error(f"bridge_check.{unknown[0]}", data[unknown[0]], f"unknown field of BridgeCheck (known: {', '.join(sorted(names))})")
        missing = [f.name for f in dataclasses.fields(cls) if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING
                   and f.name not in data]
        if missing:
            raise config_error(f"bridge_check.{missing[0]}", None, "required field is missing")
        out = cls(**data)
        out.validate()
        return out

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)


def _number(name: str, v, positive: bool) -> None:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or (v <= 0 if positive else v < 0):
        raise config_error(name, v, "must be a finite number " + ("> 0" if positive else ">= 0"))


def split_toml(path: Union[str, Path]) -> tuple:
    """(:class:`vtb.Config`, :class:`BridgeCheck`) from a TOML file: the configuration's tables
    and a ``[bridge_check]`` table."""
    p = Path(path)
    if not p.is_file():
        raise config_error("CONFIG", str(p), "no such TOML file")
    try:
        data = tomllib.loads(p.read_text())
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as e:
        raise config_error("CONFIG", str(p), f"not TOML: {e}") from None
    if "bridge_check" not in data:
        raise config_error("bridge_check", None, f"{p.name} has no [bridge_check] table (span, bridge_type, track, line_speed, …)")
    check = BridgeCheck.from_dict(data.pop("bridge_check"))
    return Config.from_dict(data), check
