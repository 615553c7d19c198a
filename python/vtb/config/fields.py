"""Run configuration as plain dataclasses.

The Rust core owns the configuration: its schema (:mod:`vtb.config.schema`) defines every field,
type and default, the defaults here are read from it, ``tests/test_schema.py`` holds these
classes to it, and the core alone validates the values (naming the field on error).
:meth:`Config.to_core_json` serialises everything except the irregularity, which is
generated here and passed to the core as a sampled profile. Configurations copy with
:func:`dataclasses.replace`, pickle, and load from / save to TOML. Assigning an attribute a
class does not have raises :class:`~vtb.errors.ConfigError` naming the known ones.

Units are SI (m, s, kg, N, Pa); vertical displacements are positive downward.
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import json
import math
import sys
import typing
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal, Optional, Union

import numpy as np

from ..errors import config_error
from .irregularity import SPECTRA, Irregularity
from . import gateway
from .schema import StrictFields
from .vehicles import VEHICLE_MODELS, QuarterCar, Vehicle, vehicle_table  # noqa: F401 - the classes are re-exported
from .schema import default as _default
from .schema import documented

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib


@dataclass
class RayleighRatio(StrictFields):
    """Rayleigh damping C = αM + βK giving damping ratio ``ratio`` at ``f1`` and ``f2`` (Hz)."""

    ratio: float
    f1: float
    f2: float


@dataclass
class RayleighCoefficients(StrictFields):
    """Rayleigh damping with explicit α (1/s) and β (s)."""

    alpha: float
    beta: float


Damping = Union[RayleighRatio, RayleighCoefficients]


@documented("LayerConfig")
@dataclass
class Layer(StrictFields):
    """A beam layer (rail, slab, base, girder …): Euler–Bernoulli, or Timoshenko when
    ``shear_modulus`` and ``shear_coefficient`` are given."""

    name: str
    density: float
    area: float
    youngs_modulus: float
    inertia: float
    modes: int
    damping: Damping
    local_modes: int = _default("LayerConfig", "local_modes")
    shear_modulus: Optional[float] = _default("LayerConfig", "shear_modulus")
    shear_coefficient: Optional[float] = _default("LayerConfig", "shear_coefficient")
    element_length: Optional[float] = _default("LayerConfig", "element_length")
    start: Optional[float] = _default("LayerConfig", "start")
    end: Optional[float] = _default("LayerConfig", "end")
    joints: list = _default("LayerConfig", "joints")


@documented("CouplingConfig")
@dataclass
class Coupling(StrictFields):
    """Spring–dashpot connection of layer ``upper`` to layer ``lower`` (or ``"ground"``).

    ``kind="discrete"``: point springs at ``positions`` (stiffness N/m, damping N·s/m each);
    ``kind="continuous"``: distributed (N/m², N·s/m²) over [``start``, ``end``], by default
    the part of the structure both layers cover.
    """

    upper: str
    lower: str
    kind: Literal["discrete", "continuous"]
    stiffness: float
    damping: float = _default("CouplingConfig", "damping")
    positions: list = _default("CouplingConfig", "positions")
    start: Optional[float] = _default("CouplingConfig", "start")
    end: Optional[float] = _default("CouplingConfig", "end")

    @classmethod
    def grid(cls, upper: str, lower: str, stiffness: float, damping: float, spacing: float, length: float, first: float = 0.0) -> "Coupling":
        """Discrete springs every ``spacing`` from ``first`` up to ``length`` (inclusive); at
        most :data:`MAX_GRID_POSITIONS` of them."""
        for name, v in (("spacing", spacing), ("length", length), ("first", first)):
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or (name == "spacing" and v <= 0):
                raise config_error(name, v, "must be a finite number" + (" > 0 (m)" if name == "spacing" else " (m)"))
        if (length - first) / spacing > MAX_GRID_POSITIONS:
            raise config_error("spacing", spacing, f"lays {(length - first) / spacing:.3g} springs over [{first:g}, {length:g}] m (at most {MAX_GRID_POSITIONS})")
        n = int(round((length - first) / spacing + 1e-9)) + 1
        return cls(upper, lower, "discrete", stiffness, damping, [first + i * spacing for i in range(n) if first + i * spacing <= length + 1e-9])


@documented("StructureConfig")
@dataclass
class Structure(StrictFields):
    """The track–bridge beam stack over [0, ``length``]: layers (each over the whole length
    or, with finite elements, over [``start``, ``end``]) joined by couplings."""

    length: float
    layers: list
    couplings: list = _default("StructureConfig", "couplings")


@documented("DiscretisationConfig")
@dataclass
class Discretisation(StrictFields):
    """``method``: ``"modal"`` (Hermite + sine modes, all global), ``"hybrid"`` (modal plus the
    FE–SEA correction of the local rail modes) or ``"fem"`` (cubic Hermite beam elements).
    ``synthesis_cutoff`` (Hz): run a finite-element structure by complex-modal synthesis
    (:mod:`vtb.run.synthesis`) instead of stepping its elements; ``substructure_cutoff`` (Hz):
    step it in substructured coordinates (:mod:`vtb.run.substructures`)."""

    method: Literal["modal", "hybrid", "fem"] = _default("DiscretisationConfig", "method")
    fem_elements: int = _default("DiscretisationConfig", "fem_elements")
    omega_r: Optional[float] = _default("DiscretisationConfig", "omega_r")
    fesea_coupling: Literal["full", "mass"] = _default("DiscretisationConfig", "fesea_coupling")
    local_deflection: bool = _default("DiscretisationConfig", "local_deflection")
    element_flexibility: bool = _default("DiscretisationConfig", "element_flexibility")
    synthesis_cutoff: Optional[float] = _default("DiscretisationConfig", "synthesis_cutoff")
    substructure_cutoff: Optional[float] = _default("DiscretisationConfig", "substructure_cutoff")
    excitation_wavelengths: Optional[list] = _default("DiscretisationConfig", "excitation_wavelengths")


@documented("MovingForceConfig")
@dataclass
class MovingForce(StrictFields):
    """A constant force moving at the common speed (moving-load mode)."""

    magnitude: float
    x0: float
    layer: Optional[str] = _default("MovingForceConfig", "layer")


@documented("SolverConfig")
@dataclass
class Solver(StrictFields):
    """Time integration (Newmark, docs/model.md §7), the contact iteration, and how a run
    starts and ends."""

    dt: float = _default("SolverConfig", "dt")
    t_end: Optional[float] = _default("SolverConfig", "t_end")
    tail: Optional[float] = _default("SolverConfig", "tail")
    edge_ramp: float = _default("SolverConfig", "edge_ramp")
    edge_step: bool = _default("SolverConfig", "edge_step")
    end_margin: float = _default("SolverConfig", "end_margin")
    gravity: float = _default("SolverConfig", "gravity")
    contact_tol: float = _default("SolverConfig", "contact_tol")
    contact_max_iter: int = _default("SolverConfig", "contact_max_iter")
    initial_state: Literal["static", "rest"] = _default("SolverConfig", "initial_state")
    memory_budget: float = _default("SolverConfig", "memory_budget")
    fade_in: float = _default("SolverConfig", "fade_in")


@documented("OutputConfig")
@dataclass
class Output(StrictFields):
    """What a run records and where its metrics are taken (docs/model.md §8)."""

    points: list = _default("OutputConfig", "points")
    window: Optional[list] = _default("OutputConfig", "window")
    band_limit: Optional[float] = _default("OutputConfig", "band_limit")
    indices: Optional[list] = _default("OutputConfig", "indices")
    deck_band: float = _default("OutputConfig", "deck_band")
    band_levels: list = _default("OutputConfig", "band_levels")
    pad_forces: bool = _default("OutputConfig", "pad_forces")


@documented("DamperGroup")
@dataclass
class DamperGroup(StrictFields):
    """Identical dampers of one ``kind`` between ``upper`` and ``lower`` (docs/dampers.md), at
    ``positions`` or at ``x0 + i·spacing`` for ``i < count``. Every kind is a spring
    ``stiffness`` (N/m) from the upper layer to an internal node and an inerter ``inertance``
    (kg) from the node to the lower layer (or the ground, where it is a mass); the dashpot
    ``damping`` (N·s/m) sits beside the spring (``"tid"``, ``"tmd"``) or beside the inerter
    (``"tvmd"``). ``TIDs`` is the same class, the name of the article's group."""

    inertance: float
    stiffness: float
    damping: float
    count: Optional[int] = _default("DamperGroup", "count")
    x0: Optional[float] = _default("DamperGroup", "x0")
    spacing: Optional[float] = _default("DamperGroup", "spacing")
    positions: Optional[list] = _default("DamperGroup", "positions")
    upper: str = _default("DamperGroup", "upper")
    lower: str = _default("DamperGroup", "lower")
    kind: Literal["tid", "tvmd", "tmd"] = _default("DamperGroup", "kind")
    name: Optional[str] = _default("DamperGroup", "name")

    def _field_path(self, name: str) -> str:
        """A named group's fields are addressed by its name (``tids.count``), as the core does."""
        return f"{self.name}.{name}" if isinstance(self.name, str) and self.name else super()._field_path(name)

    def locations(self) -> np.ndarray:
        """The dampers' positions (m): ``positions``, or the pattern ``x0 + i·spacing``."""
        if self.positions is not None:
            return np.asarray(self.positions, dtype=float)
        if self.count is None or self.x0 is None:  # incomplete: validate() names the field
            return np.zeros(0)
        return self.x0 + (self.spacing or 0.0) * np.arange(self.count)

    def placement(self) -> str:
        """Where the dampers are: ``"x = x0 m + i·spacing m"`` or the list of positions."""
        if self.positions is not None:
            return "x = " + ", ".join(f"{x:g}" for x in self.positions) + " m"
        if self.x0 is None:
            return "no positions"
        return f"x = {self.x0:g} m + i·{self.spacing or 0.0:g} m"

    def describe(self) -> str:
        """One line: how many, of which kind and tuning, between which layers."""
        return (f"{len(self.locations())} {self.kind.upper()} × (b {self.inertance:g} kg, k {self.stiffness:g} N/m, "
                f"c {self.damping:g} N·s/m) {self.upper}–{self.lower}")


TIDs = DamperGroup
#: The name of the article's damper group (``Config.tids``).
TIDS = "tids"


@documented("Config", irregularity="The track irregularity under the wheels, generated on the Python side (:class:`vtb.Irregularity`; m, positive = dip).")
@dataclass
class Config(StrictFields):
    """A complete run: structure, discretisation, vehicles or moving forces, speed, solver
    settings, observation points, irregularity and optional TIDs."""

    structure: Structure
    speed: float
    vehicles: list = _default("Config", "vehicles")
    forces: list = _default("Config", "forces")
    discretisation: Discretisation = field(default_factory=Discretisation)
    solver: Solver = field(default_factory=Solver)
    output: Output = field(default_factory=Output)
    irregularity: Irregularity = field(default_factory=Irregularity)
    dampers: list = _default("Config", "dampers")
    accept_implausible: list = _default("Config", "accept_implausible")

    def __repr__(self) -> str:
        """One line: method, layers (modes), length, loads, speed, step, irregularity, dampers.
        ``to_dict()`` or ``to_toml()`` show everything."""
        try:
            layers = ", ".join(
                f"{l.name}({l.modes}{'+' + str(l.local_modes) if l.local_modes else ''})" if self.discretisation.method != "fem" else l.name
                for l in self.structure.layers
            )
            irr = self.irregularity
            irr_text = irr.kind if irr.kind in ("none", "sampled") else f"{irr.kind} seed {irr.seed}, scale {irr.scale:g}"
            tids = "; ".join(g.describe() for g in self.dampers) or "none"
            end = "auto" if self.solver.t_end is None else f"{self.solver.t_end:g} s"
            return (f"Config({self.discretisation.method}: {layers}; L = {self.structure.length:g} m; {len(self.vehicles)} car(s), "
                    f"{len(self.forces)} force(s) at {self.speed:g} m/s; dt = {self.solver.dt:g} s, t_end {end}; irregularity {irr_text}; dampers {tids})")
        except Exception:  # noqa: BLE001 - a malformed config still has a representation
            return f"Config(<{len(self.__dict__)} fields; to_dict() shows them>)"

    @property
    def tids(self) -> Optional[DamperGroup]:
        """The article's tuned inerter dampers: the damper group named ``"tids"`` (``None``
        without one), the group the article's studies vary; field paths ``tids.stiffness``
        reach it. Assigning a group names it ``"tids"`` and puts it in that group's place (first
        when there was none); assigning ``None`` removes it."""
        return next((g for g in self.dampers if getattr(g, "name", None) == TIDS), None)

    @tids.setter
    def tids(self, group: Optional[DamperGroup]) -> None:
        rest = [g for g in self.dampers if getattr(g, "name", None) != TIDS]
        if group is None:
            self.dampers = rest
            return
        if not isinstance(group, DamperGroup):
            raise config_error("tids", group, "expected a vtb.DamperGroup (or None)")
        group.name = TIDS
        at = next((i for i, g in enumerate(self.dampers) if getattr(g, "name", None) == TIDS), 0)
        self.dampers = rest[:at] + [group] + rest[at:]

    # ------------------------------------------------------------------ serialisation
    def to_dict(self) -> dict:
        """Plain nested dict (TOML/JSON friendly; damping carries a ``kind`` tag)."""
        return to_plain(self)

    def excitation_wavelengths(self) -> Optional[list]:
        """[λ_min, λ_max] (m) the irregularity excites: a spectrum's band, a corrugation's
        ``wavelength`` or a dip's ``length`` twice; ``None`` without a wavelength. The core
        takes its default ω_r from it (``discretisation.excitation_wavelengths``)."""
        irr = self.irregularity
        kind = getattr(irr, "kind", None)
        if not isinstance(kind, str):
            return None  # a bad irregularity or kind is named by the irregularity's own check
        band = {"corrugation": ("wavelength", "wavelength"), "cosine_dip": ("length", "length")}.get(
            kind, ("wavelength_min", "wavelength_max") if kind in SPECTRA else None)
        if band is None:
            return None
        values = [getattr(irr, name, None) for name in band]
        # a bad band is named by the irregularity's own check
        return [float(v) for v in values] if all(isinstance(v, (int, float)) and not isinstance(v, bool) and v > 0 for v in values) else None

    def to_core_json(self) -> str:
        """JSON for the Rust core (everything but the irregularity; a hybrid run carries the
        wavelengths its irregularity excites, from which the core takes the default ω_r). Non-finite numbers, which JSON cannot carry, raise
        :class:`~vtb.errors.ConfigError` here."""
        d = self.to_dict()
        d.pop("irregularity")
        disc = d.get("discretisation")
        if isinstance(disc, dict) and disc.get("method") == "hybrid" and disc.get("excitation_wavelengths") is None:
            disc["excitation_wavelengths"] = self.excitation_wavelengths()
        try:
            return json.dumps(d, allow_nan=False)
        except (TypeError, ValueError):
            _check_finite(d, "")  # names the field that JSON cannot carry
            raise

    @classmethod
    def from_dict(cls, data: dict) -> "Config":
        """A configuration from a plain nested dict (the shape of :meth:`to_dict`); unknown
        or missing fields raise :class:`~vtb.errors.ConfigError`. Values are validated by
        the core when the configuration runs, or now by :meth:`validate`; their types and
        ranges are checked here, by the core's schema."""
        cfg = _from_plain(cls, data, "")
        gateway.check_schema(cfg.to_core_json())
        return cfg

    def validate(self) -> None:
        """Checks the whole configuration now (the core's validation, against the generated
        irregularity) and raises :class:`~vtb.errors.ConfigError` naming the first bad field;
        :func:`vtb.run.simulate` does the same check when it runs."""
        # The one import circle of vtb: a configuration's own check is that of a prepared run,
        # and the preparation (vtb.config.prepare) takes a Config.
        from .prepare import validate

        validate(self)

    def to_toml(self, path: Union[str, Path, None] = None) -> str:
        import tomli_w

        text = tomli_w.dumps(_drop_none(self.to_dict()))
        if path is not None:
            Path(path).write_text(text)
        return text

    @classmethod
    def from_toml(cls, path: Union[str, Path]) -> "Config":
        """Loads a TOML file. ``path`` is always a file name (TOML text goes to
        :meth:`from_toml_text`); a missing file, a directory or unreadable text raise
        :class:`~vtb.errors.ConfigError` naming the path."""
        if not isinstance(path, (str, Path)):
            raise config_error("path", path, "expected a file path (str or pathlib.Path)")
        p = Path(path)
        if isinstance(path, str) and ("\n" in path or "=" in path):
            try:
                is_file = p.is_file()
            except OSError:  # e.g. too long for a file name
                is_file = False
            if not is_file:
                raise config_error("path", path[:60], "no such file; this looks like TOML text: use Config.from_toml_text")
        if p.is_dir():
            raise config_error("path", str(p), "is a directory, not a TOML file")
        try:
            text = p.read_text()
        except FileNotFoundError:
            raise config_error("path", str(p), "no such file") from None
        except (OSError, UnicodeDecodeError) as e:
            raise config_error("path", str(p), f"cannot be read: {e}") from None
        return cls._from_toml(text, str(p))

    @classmethod
    def from_toml_text(cls, text: str) -> "Config":
        """Parses TOML text (see :meth:`from_toml` for files)."""
        if not isinstance(text, str):
            raise config_error("text", type(text).__name__, "expected TOML text (str)")
        return cls._from_toml(text, "(text)")

    @classmethod
    def _from_toml(cls, text: str, source: str) -> "Config":
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as e:
            raise config_error("<toml>", source, str(e)) from None
        return cls.from_dict(data)

    def copy(self) -> "Config":
        return copy.deepcopy(self)


def _check_finite(x, path: str) -> None:
    """Every leaf is a JSON value (number, string, boolean, null) and every number finite."""
    if isinstance(x, dict):
        for k, v in x.items():
            _check_finite(v, f"{path}.{k}" if path else k)
    elif isinstance(x, list):
        for i, v in enumerate(x):
            _check_finite(v, f"{path}[{i}]")
    elif isinstance(x, float):
        if not math.isfinite(x):
            raise config_error(path, x, "must be a finite number")
    elif not (x is None or isinstance(x, (str, int))):
        raise config_error(path, x, f"a {type(x).__name__} is not a configuration value (number, string, boolean or list)")


def _drop_none(x):
    if isinstance(x, dict):
        return {k: _drop_none(v) for k, v in x.items() if v is not None}
    if isinstance(x, list):
        return [_drop_none(v) for v in x]
    return x


@functools.lru_cache(maxsize=None)
def _field_names(cls) -> tuple:
    """A dataclass's field names (``dataclasses.fields`` is slow enough to show in a study's
    set-up, which converts thousands of configurations)."""
    return tuple(f.name for f in dataclasses.fields(cls))


def to_plain(obj):
    if obj is None or type(obj) in (float, int, str, bool):  # exact types: numpy scalars convert below
        return obj
    if isinstance(obj, (RayleighRatio, RayleighCoefficients)):
        kind = "ratio" if isinstance(obj, RayleighRatio) else "coefficients"
        return {"kind": kind, **{n: to_plain(getattr(obj, n)) for n in _field_names(type(obj))}}
    if dataclasses.is_dataclass(obj):
        return {n: to_plain(getattr(obj, n)) for n in _field_names(type(obj))}
    if isinstance(obj, (list, tuple)):
        return [to_plain(v) for v in obj]
    if hasattr(obj, "tolist"):  # numpy arrays and scalars
        return obj.tolist()
    return obj


_LIST_ITEM = {("Structure", "layers"): Layer, ("Structure", "couplings"): Coupling, ("Config", "vehicles"): tuple(VEHICLE_MODELS.values()), ("Config", "forces"): MovingForce, ("Config", "dampers"): DamperGroup, ("Irregularity", "parts"): Irregularity}

def _legacy_tids(data: dict) -> dict:
    """A table written when the article's group was a key of its own (``tids``, beside
    ``dampers``): that group, named ``"tids"``, first among the damper groups."""
    data = dict(data)
    group = data.pop("tids")
    if group is None:
        return data
    if isinstance(group, DamperGroup):
        group.name = TIDS
    elif isinstance(group, dict):
        group = {"name": TIDS, **group}
    dampers = data.get("dampers", [])
    data["dampers"] = [group, *dampers] if isinstance(dampers, (list, tuple)) else dampers
    return data


def _from_plain(cls, data, path: str):
    where = path or "<config>"
    if isinstance(data, cls):
        return data
    if not isinstance(data, dict):
        raise config_error(where, data, f"expected a table for {cls.__name__}")
    if cls is Config and "tids" in data:
        data = _legacy_tids(data)
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
            kwargs[f.name] = [_from_plain(*(vehicle_table(x, f"{sub}[{i}]") if isinstance(item, tuple) else (item, x)), f"{sub}[{i}]")
                              for i, x in enumerate(v)]
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
                        names = " or ".join(c.__name__ for c in (item if isinstance(item, tuple) else (item,)))
                        raise config_error(f"{sub}[{i}]", x, f"expected a {names}")
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


def structure_json(config: Config, text: Optional[str] = None) -> str:
    """The core JSON of ``config`` (``text`` when the caller has made it) with its loads, speed,
    solver and outputs replaced by a neutral single zero force, so that only the structure is
    validated and assembled (what the frequency-domain tools, the resolved band and the
    synthesis' reduction are computed from)."""
    if not isinstance(config, Config):
        raise config_error("config", type(config).__name__, "expected a vtb.Config")
    d = json.loads(config.to_core_json() if text is None else text)  # resolves a hybrid's default ω_r from the irregularity
    d["vehicles"] = []
    top = (d.get("structure") or {}).get("layers") or [{}]
    start = top[0].get("start") if isinstance(top[0], dict) else None
    # on the top layer, wherever it starts: a force that never reaches its layer is refused
    d["forces"] = [{"magnitude": 0.0, "x0": start if isinstance(start, (int, float)) else 0.0, "layer": None}]
    d["speed"] = 0.0
    d["solver"] = to_plain(Solver(dt=1e-3, t_end=1e-3, initial_state="rest"))
    d["output"] = {"points": []}
    return json.dumps(d, allow_nan=False)


def core_dict(cfg: Config) -> dict[str, Any]:
    """The dict the core receives (for inspection)."""
    return json.loads(cfg.to_core_json())


def plausible_ranges() -> list:
    """The plausible range of every physical field the core checks, as rows ``{"field", "min",
    "max", "unit", "covers"}`` (SI units; ``[*]`` stands for every index of a list). A value
    outside its range raises :class:`vtb.ConfigError` naming the field, the value and the likely
    unit mistake, unless ``Config.accept_implausible`` lists the field's path."""
    return [dict(field=f, min=lo, max=hi, unit=u, covers=c) for f, lo, hi, u, c in gateway.plausible_ranges()]


#: The most springs :meth:`Coupling.grid` lays in one coupling (fasteners every 0.6 m over a
#: 100 km viaduct are 170 000).
MAX_GRID_POSITIONS = 1_000_000


def checked_config(config, name: str = "config") -> "Config":
    """``config`` if it is a :class:`Config` whose every field has its type; raises
    :class:`~vtb.errors.ConfigError` naming ``name`` or the field otherwise (the first step of
    a function that rearranges a configuration, before any work)."""
    if not isinstance(config, Config):
        raise config_error(name, type(config).__name__, "expected a vtb.Config")
    check_types(config)
    return config


def check_new_length(config: "Config", field: str, value: float, given=None) -> None:
    """A structure of ``value`` m, which the argument ``field`` would make of ``config``, within
    the core's plausible ``structure.length`` (unless ``config.accept_implausible`` lists it)
    and within the springs :data:`MAX_GRID_POSITIONS` lays; checked before anything is laid.
    ``given``: the argument's value (default ``value``)."""
    given = value if given is None else given
    row = next(r for r in plausible_ranges() if r["field"] == "structure.length")
    accepted = isinstance(config.accept_implausible, list) and "structure.length" in config.accept_implausible
    if value > row["max"] and not accepted:
        raise config_error(field, given, f"makes a structure {value:g} m long, beyond the plausible {row['min']:g} … {row['max']:g} m "
                                         f"of structure.length ({row['covers']}; docs/limits.md); if it is meant, list "
                                         "\"structure.length\" in accept_implausible")
    spacing = min((cp.positions[1] - cp.positions[0] for cp in config.structure.couplings
                   if cp.kind == "discrete" and len(cp.positions) >= 2 and cp.positions[1] > cp.positions[0]), default=None)
    if spacing is not None and value / spacing > MAX_GRID_POSITIONS:
        raise config_error(field, given, f"makes a structure {value:g} m long, which would lay {value / spacing:.3g} springs "
                                         f"{spacing:g} m apart (at most {MAX_GRID_POSITIONS})")
