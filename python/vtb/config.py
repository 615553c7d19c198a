"""Run configuration as plain dataclasses.

The classes mirror the JSON schema of the Rust core field for field (see
``rust/src/config.rs``); :meth:`Config.to_core_json` serialises everything except the
irregularity, which is generated here and passed to the core as a sampled profile.
Configurations copy with :func:`dataclasses.replace`, pickle, and load from / save to TOML.

Units are SI (m, s, kg, N, Pa); vertical displacements are positive downward.
"""

from __future__ import annotations

import copy
import dataclasses
import json
import math
import sys
import typing
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal, Optional, Union

from .errors import config_error
from .irregularity import Irregularity

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib


@dataclass
class RayleighRatio:
    """Rayleigh damping C = αM + βK giving damping ratio ``ratio`` at ``f1`` and ``f2`` (Hz)."""

    ratio: float
    f1: float
    f2: float


@dataclass
class RayleighCoefficients:
    """Rayleigh damping with explicit α (1/s) and β (s)."""

    alpha: float
    beta: float


Damping = Union[RayleighRatio, RayleighCoefficients]


@dataclass
class Layer:
    """A beam layer (rail, slab, base, girder …): Euler–Bernoulli, or Timoshenko when
    ``shear_modulus`` and ``shear_coefficient`` are given."""

    name: str
    density: float  #: ρ (kg/m³)
    area: float  #: A (m²)
    youngs_modulus: float  #: E (Pa)
    inertia: float  #: I (m⁴)
    modes: int  #: sine modes of the modal basis (4 boundary functions come on top)
    damping: Damping
    local_modes: int = 0  #: extra sine modes treated as local (FE–SEA) modes by the hybrid method
    #: shear modulus G (Pa); with ``shear_coefficient`` the layer is a Timoshenko beam (shear
    #: deformation and rotary inertia ρI), finite-element method only
    shear_modulus: Optional[float] = None
    shear_coefficient: Optional[float] = None  #: shear coefficient κ (−); ≈ 0.4 for a rail in vertical bending
    #: longest finite element (m) of this layer; its nodes then fall on every discrete coupling
    #: point of the layer (fasteners, piers, dampers). ``None``: ``discretisation.fem_elements``
    #: equal elements, wherever the couplings fall
    element_length: Optional[float] = None


@dataclass
class Coupling:
    """Spring–dashpot connection of layer ``upper`` to layer ``lower`` (or ``"ground"``).

    ``kind="discrete"``: point springs at ``positions`` (stiffness N/m, damping N·s/m each);
    ``kind="continuous"``: distributed over the length (N/m², N·s/m²).
    """

    upper: str
    lower: str
    kind: Literal["discrete", "continuous"]
    stiffness: float
    damping: float = 0.0
    positions: list = field(default_factory=list)

    @classmethod
    def grid(cls, upper: str, lower: str, stiffness: float, damping: float, spacing: float, length: float, first: float = 0.0) -> "Coupling":
        """Discrete springs every ``spacing`` from ``first`` up to ``length`` (inclusive)."""
        n = int(round((length - first) / spacing + 1e-9)) + 1
        return cls(upper, lower, "discrete", stiffness, damping, [first + i * spacing for i in range(n) if first + i * spacing <= length + 1e-9])


@dataclass
class Structure:
    length: float  #: common length L of all layers (m)
    layers: list  #: list[Layer], top (wheels run on it) to bottom
    couplings: list = field(default_factory=list)  #: list[Coupling]


@dataclass
class Discretisation:
    """``method``: ``"modal"`` (Hermite + sine modes, all global), ``"hybrid"`` (modal plus the
    FE–SEA correction of the local rail modes) or ``"fem"`` (cubic Hermite beam elements)."""

    method: Literal["modal", "hybrid", "fem"] = "modal"
    fem_elements: int = 251
    #: FE–SEA representative excitation frequency ω_r (rad/s). ``None``: the geometric centre
    #: 2π·v/sqrt(λ_min·λ_max) of the irregularity's excitation band (a spectrum's band, or the
    #: wavelength of a corrugation or dip), else the geometric centre of the local modes'
    #: frequency range (docs/fesea.md).
    omega_r: Optional[float] = None
    #: FE–SEA global–local coupling: ``"full"`` (mass, bending and rail springs; default) or
    #: ``"mass"`` (the article's mass-only reading).
    fesea_coupling: Literal["full", "mass"] = "full"
    #: Hybrid: add the local modes' static deflection under the rail loads to the rail's
    #: displacement outputs (docs/fesea.md). ``False`` follows model.md §6 literally.
    local_deflection: bool = True
    #: finite-element rails: each wheel also sees the static deflection of the rail element under
    #: it with the element's nodes fixed (in series with the contact), which the element's
    #: interpolation misses; keeps the static wheel–rail stiffness independent of the wheel's
    #: position in its element
    element_flexibility: bool = True


@dataclass
class Vehicle:
    """Zhai's 10-DOF car. Secondary suspension per bogie, primary per wheelset (both sides
    lumped). The modelled top layer is one of ``rails`` identical rails, so it carries
    1/``rails`` of every axle load."""

    m_c: float  #: car body mass (kg)
    j_c: float  #: car body pitch inertia (kg·m²)
    m_t: float  #: bogie mass (kg)
    j_t: float  #: bogie pitch inertia (kg·m²)
    m_w: float  #: wheelset mass (kg)
    k_s: float  #: secondary stiffness per bogie (N/m)
    c_s: float  #: secondary damping per bogie (N·s/m)
    k_p: float  #: primary stiffness per wheelset (N/m)
    c_p: float  #: primary damping per wheelset (N·s/m)
    l_c: float  #: half distance between bogie centres (m)
    l_t: float  #: half wheelbase (m)
    wheel_radius: float  #: (m), sets G = 4.57·R^−0.149·1e−8 m/N^(2/3)
    x_front: float  #: position of the leading wheelset at t = 0 (m)
    contact_constant: Optional[float] = None  #: overrides the Hertz constant G
    rails: int = 2

    @property
    def length(self) -> float:
        """Distance from the leading to the trailing wheelset (m)."""
        return 2.0 * (self.l_c + self.l_t)


@dataclass
class MovingForce:
    """A constant force moving at the common speed (moving-load mode)."""

    magnitude: float  #: N, positive downward
    x0: float  #: position at t = 0 (m)
    layer: Optional[str] = None  #: top layer when None


@dataclass
class Solver:
    dt: float = 5e-5  #: Newmark time step (s)
    t_end: Optional[float] = None  #: end time (s); None: leading wheel reaches L − end_margin
    end_margin: float = 1.0  #: (m)
    gravity: float = 9.81  #: (m/s²)
    contact_tol: float = 1e-10  #: |P − h(δ)| ≤ tol·(static wheel load) per wheel
    contact_max_iter: int = 50
    initial_state: Literal["static", "rest"] = "static"


@dataclass
class Output:
    points: list = field(default_factory=list)  #: observation points (m); empty: x = L/2


@dataclass
class TIDs:
    """``count`` identical tuned inerter dampers between ``upper`` and ``lower`` at
    ``x0 + i·spacing``: spring ``stiffness`` (N/m) and dashpot ``damping`` (N·s/m) from the upper
    layer to an internal node, inerter ``inertance`` (kg) from the node to the lower layer."""

    inertance: float
    stiffness: float
    damping: float
    count: int
    x0: float
    spacing: float
    upper: str = "rail"
    lower: str = "slab"


@dataclass
class Config:
    """A complete run: structure, discretisation, vehicles or moving forces, speed, solver
    settings, observation points, irregularity and optional TIDs."""

    structure: Structure
    speed: float  #: (m/s), +x direction
    vehicles: list = field(default_factory=list)  #: list[Vehicle]
    forces: list = field(default_factory=list)  #: list[MovingForce]
    discretisation: Discretisation = field(default_factory=Discretisation)
    solver: Solver = field(default_factory=Solver)
    output: Output = field(default_factory=Output)
    irregularity: Irregularity = field(default_factory=Irregularity)
    tids: Optional[TIDs] = None

    # ------------------------------------------------------------------ serialisation
    def to_dict(self) -> dict:
        """Plain nested dict (TOML/JSON friendly; damping carries a ``kind`` tag)."""
        return _to_plain(self)

    def excitation_omega_r(self) -> Optional[float]:
        """The default ω_r (rad/s) from the irregularity: 2π·v/sqrt(λ_min·λ_max) for a
        spectrum (the centre of its band v/λ on a log scale), 2π·v/λ for a corrugation
        (``wavelength``) or a dip (``length``); ``None`` when there is no wavelength."""
        irr = self.irregularity
        from .irregularity import SPECTRA

        try:
            if irr.kind in SPECTRA:
                lam = math.sqrt(irr.wavelength_min * irr.wavelength_max)
            elif irr.kind == "corrugation":
                lam = irr.wavelength
            elif irr.kind == "cosine_dip":
                lam = irr.length
            else:
                return None
            w = 2.0 * math.pi * self.speed / lam
        except (TypeError, ValueError, ZeroDivisionError):
            return None
        return w if math.isfinite(w) and w > 0 else None

    def to_core_json(self) -> str:
        """JSON for the Rust core (everything but the irregularity, with the default ω_r of a
        hybrid run resolved from it). Non-finite numbers, which JSON cannot carry, raise
        :class:`~vtb.errors.ConfigError` here."""
        d = self.to_dict()
        d.pop("irregularity")
        disc = d.get("discretisation")
        if isinstance(disc, dict) and disc.get("method") == "hybrid" and disc.get("omega_r") is None:
            disc["omega_r"] = self.excitation_omega_r()
        if d.get("tids") is None:
            d.pop("tids", None)
        _check_finite(d, "")
        return json.dumps(d, allow_nan=False)

    @classmethod
    def from_dict(cls, data: dict) -> "Config":
        cfg = _from_plain(cls, data, "")
        check_types(cfg)
        return cfg

    def to_toml(self, path: Union[str, Path, None] = None) -> str:
        import tomli_w

        text = tomli_w.dumps(_drop_none(self.to_dict()))
        if path is not None:
            Path(path).write_text(text)
        return text

    @classmethod
    def from_toml(cls, path_or_text: Union[str, Path]) -> "Config":
        """Loads a TOML file (or TOML text)."""
        p = Path(path_or_text) if not isinstance(path_or_text, str) or "\n" not in path_or_text else None
        text = p.read_text() if p is not None else str(path_or_text)
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as e:
            raise config_error("<toml>", str(p) if p else "(text)", str(e)) from None
        return cls.from_dict(data)

    def copy(self) -> "Config":
        return copy.deepcopy(self)


def _check_finite(x, path: str) -> None:
    if isinstance(x, dict):
        for k, v in x.items():
            _check_finite(v, f"{path}.{k}" if path else k)
    elif isinstance(x, list):
        for i, v in enumerate(x):
            _check_finite(v, f"{path}[{i}]")
    elif isinstance(x, float) and not math.isfinite(x):
        raise config_error(path, x, "must be a finite number")


def _drop_none(x):
    if isinstance(x, dict):
        return {k: _drop_none(v) for k, v in x.items() if v is not None}
    if isinstance(x, list):
        return [_drop_none(v) for v in x]
    return x


def _to_plain(obj):
    if isinstance(obj, (RayleighRatio, RayleighCoefficients)):
        kind = "ratio" if isinstance(obj, RayleighRatio) else "coefficients"
        return {"kind": kind, **{f.name: _to_plain(getattr(obj, f.name)) for f in dataclasses.fields(obj)}}
    if dataclasses.is_dataclass(obj):
        return {f.name: _to_plain(getattr(obj, f.name)) for f in dataclasses.fields(obj)}
    if isinstance(obj, (list, tuple)):
        return [_to_plain(v) for v in obj]
    if hasattr(obj, "tolist"):  # numpy arrays and scalars
        return obj.tolist()
    return obj


_LIST_ITEM = {("Structure", "layers"): Layer, ("Structure", "couplings"): Coupling, ("Config", "vehicles"): Vehicle, ("Config", "forces"): MovingForce}


def _from_plain(cls, data, path: str):
    where = path or "<config>"
    if isinstance(data, cls):
        return data
    if not isinstance(data, dict):
        raise config_error(where, data, f"expected a table for {cls.__name__}")
    hints = typing.get_type_hints(cls)
    names = {f.name for f in dataclasses.fields(cls)}
    unknown = sorted(set(data) - names)
    if unknown:
        raise config_error(f"{path}.{unknown[0]}" if path else unknown[0], data[unknown[0]], f"unknown field of {cls.__name__} (known: {', '.join(sorted(names))})")
    kwargs = {}
    for f in dataclasses.fields(cls):
        sub = f"{path}.{f.name}" if path else f.name
        if f.name not in data:
            if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
                raise config_error(sub, None, "required field is missing")
            continue
        v = data[f.name]
        item = _LIST_ITEM.get((cls.__name__, f.name))
        hint = hints[f.name]
        if item is not None:
            if not isinstance(v, (list, tuple)):
                raise config_error(sub, v, "expected a list")
            kwargs[f.name] = [_from_plain(item, x, f"{sub}[{i}]") for i, x in enumerate(v)]
        elif f.name == "damping" and cls is Layer:
            kwargs[f.name] = _damping_from_plain(v, sub)
        else:
            target = _dataclass_in(hint)
            kwargs[f.name] = _from_plain(target, v, sub) if (target is not None and v is not None) else v
    return cls(**kwargs)


def _dataclass_in(hint):
    if dataclasses.is_dataclass(hint):
        return hint
    for a in typing.get_args(hint):
        if dataclasses.is_dataclass(a):
            return a
    return None


def _damping_from_plain(v, path: str) -> Damping:
    if isinstance(v, (RayleighRatio, RayleighCoefficients)):
        return v
    if not isinstance(v, dict):
        raise config_error(path, v, "expected a table with kind = \"ratio\" or \"coefficients\"")
    d = dict(v)
    kind = d.pop("kind", "ratio" if "ratio" in d else "coefficients")
    cls = {"ratio": RayleighRatio, "coefficients": RayleighCoefficients}.get(kind) if isinstance(kind, str) else None
    if cls is None:
        raise config_error(f"{path}.kind", kind, "must be \"ratio\" or \"coefficients\"")
    return _from_plain(cls, d, path)


def check_types(obj, path: str = "") -> None:
    """Checks every field of a configuration tree against its annotation (numbers are real
    numbers — not bools or strings —, integers integral, literals among their choices, lists
    lists) and raises :class:`~vtb.errors.ConfigError` naming the first offending field."""
    if isinstance(obj, (RayleighRatio, RayleighCoefficients, Irregularity)) or dataclasses.is_dataclass(obj):
        hints = typing.get_type_hints(type(obj))
        for f in dataclasses.fields(obj):
            sub = f"{path}.{f.name}" if path else f.name
            v = getattr(obj, f.name)
            item = _LIST_ITEM.get((type(obj).__name__, f.name))
            if item is not None:
                if not isinstance(v, (list, tuple)):
                    raise config_error(sub, v, "expected a list")
                for i, x in enumerate(v):
                    if not isinstance(x, item):
                        raise config_error(f"{sub}[{i}]", x, f"expected a {item.__name__}")
                    check_types(x, f"{sub}[{i}]")
            else:
                _check_value(v, hints[f.name], sub)


def _check_value(v, hint, path: str) -> None:
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if origin is Union:
        if v is None and type(None) in args:
            return
        options = [a for a in args if a is not type(None)]
        if len(options) == 1:
            return _check_value(v, options[0], path)
        if any(dataclasses.is_dataclass(a) and isinstance(v, a) for a in options):
            return check_types(v, path)
        raise config_error(path, v, f"expected one of {[getattr(a, '__name__', a) for a in options]}")
    if origin is Literal:
        if v not in args:
            raise config_error(path, v, f"must be one of {list(args)}")
        return
    if hint is float:
        if isinstance(v, bool) or not isinstance(v, (int, float)) and not (hasattr(v, "dtype") and v.dtype.kind in "fiu" and getattr(v, "ndim", 1) == 0):
            raise config_error(path, v, "must be a number")
    elif hint is int:
        if isinstance(v, bool) or not (isinstance(v, int) or (hasattr(v, "dtype") and v.dtype.kind in "iu" and getattr(v, "ndim", 1) == 0)):
            raise config_error(path, v, "must be an integer")
    elif hint is str:
        if not isinstance(v, str):
            raise config_error(path, v, "must be a string")
    elif hint is list or origin is list:
        if not isinstance(v, (list, tuple)) and not hasattr(v, "tolist"):
            raise config_error(path, v, "must be a list")
        for i, x in enumerate(list(v)):
            if isinstance(x, bool) or not isinstance(x, (int, float)) and not hasattr(x, "dtype"):
                raise config_error(f"{path}[{i}]", x, "must be a number")
    elif dataclasses.is_dataclass(hint):
        if not isinstance(v, hint):
            raise config_error(path, v, f"expected a {hint.__name__}")
        check_types(v, path)


def core_dict(cfg: Config) -> dict[str, Any]:
    """The dict the core receives (for inspection)."""
    return json.loads(cfg.to_core_json())
