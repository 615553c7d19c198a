"""Generated bad input for every public surface (tests/test_fuzz.py and the long fuzz run,
benches/fuzz_config.py): one case per call from a seeded ``random.Random`` and a surface, and
the verdict on what the API did with it.

Surfaces: ``config`` (the older configuration surface: values, structure, attributes, TOML;
tests/fuzz_cases.py), ``trains``, ``zones``, ``spans``, ``profile`` (irregularity parts and
local defects), ``dampers`` (damper groups), ``bands`` (band levels, band limit, deck band),
``contact`` (the wheels' contact fields), ``edges`` (vehicles crossing a rail end, the
hand-over, tails), ``studies`` (:func:`vtb.study`: grids, cases, references, indices, journals)
and ``optimisation`` (:func:`vtb.optimize`), then the bridge engineer's surfaces of
tests/fuzz_bridge.py (``load_trains``, ``damping``, ``scan``, ``interaction``, ``static``,
``checks``, ``bridge_check``). Every run is cheap: the small configuration runs
a few milliseconds of time.

Verdicts: ``ok`` (a finite result), ``refused`` (a documented vtb error naming a usable field),
and the findings: ``panic``, ``unnamed`` (an error naming no usable field), ``undocumented``
(an exception that is not a vtb error), ``nonfinite`` (a success with a NaN or infinity),
``mutated`` (the call changed an input it was given) and ``slow`` (a refusal after more than a
second: the check came after work it should have preceded). Aborts and hangs are counted by the
runner, which runs the cases in worker processes.
"""

from __future__ import annotations

import copy
import math
import random
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

import vtb
from vtb.errors import ConfigError, ConvergenceError, OutputError, SolverError, VtbError
import fuzz_bridge
import fuzz_cases
from fuzz_cases import BAD_NUMBERS, BAD_OTHER, small_config

FINDINGS = ("panic", "unnamed", "undocumented", "nonfinite", "mutated", "slow")
#: Seconds within which a refusal must answer: a bad value is refused before any work.
REFUSAL_SECONDS = 1.0
UNNAMED = fuzz_cases.UNNAMED

#: Plausible values per role, mixed with the bad ones so that a case gets past its first check.
_GOOD = {
    "length": [0.5, 1.0, 5.0, 20.0, 32.0], "position": [0.0, 10.0, 21.0, 80.0, 159.0], "count": [1, 2, 3],
    "stiffness": [1e7, 2e8, 1e9], "damping": [0.0, 1e3, 5e4], "time": [0.0, 0.001, 0.01], "freq": [10.0, 100.0, 1000.0],
    "depth": [1e-4, 1e-3, 5e-3], "flag": [True, False], "seed": [0, 1, 7],
}


def _value(rng: random.Random, role: str):
    """A plausible value for ``role`` (60 %) or a bad one."""
    if rng.random() < 0.6:
        return rng.choice(_GOOD[role])
    return rng.choice(BAD_NUMBERS) if rng.random() < 0.6 else copy.deepcopy(rng.choice(BAD_OTHER))


def _fem_config(t_end: float = 0.002):
    """A small finite-element configuration (zones, simply supported spans, contact patches)."""
    cfg = small_config(t_end, tids=False)
    cfg.discretisation.method = "fem"
    cfg.discretisation.fem_elements = 40
    return cfg


def _run(cfg):
    return vtb.simulate(cfg, progress=False)


# -------------------------------------------------------------------------------- surfaces

def _trains(rng):
    kw = {}
    for name, role in (("cars", "count"), ("x_front", "position")):
        if rng.random() < 0.6:
            kw[name] = _value(rng, role)
    if rng.random() < 0.3:
        kw[rng.choice(["rails", "contact_patch", "wheel_radius", "m_c", "x_fronts", "speed"])] = _value(rng, rng.choice(["count", "flag", "length"]))
    name = rng.choice(["crh3", "velaro_e", "crh3", "ice", 3, None]) if rng.random() < 0.3 else "crh3"

    def run():
        cars = vtb.train(name, **kw)
        if rng.random() < 0.3:
            cfg = vtb.track_zones(_fem_config(), approach=20.0, exit=20.0)
            cfg.vehicles = cars[:2]
            return _run(cfg)
        return cars
    return f"train({name!r}, {kw})", run, ()


def _zones(rng):
    kw = {}
    for name, role in (("approach", "length"), ("exit", "length"), ("ground_stiffness", "stiffness"), ("ground_damping", "damping"),
                       ("tail", "time"), ("edge_ramp", "length")):
        if rng.random() < 0.35:
            kw[name] = _value(rng, role)
    base = _fem_config() if rng.random() < 0.8 else small_config()
    if rng.random() < 0.15:
        kw["approach"] = rng.choice([1e8, 1e6, 5e4])

    def run():
        cfg = vtb.track_zones(base, **kw)
        # a run is cheap: only on a zoned structure of modest length (a valid 50 km viaduct runs for minutes)
        if rng.random() < 0.3 and cfg.structure.length < 1000.0:
            cfg.solver.t_end = 0.002
            return _run(cfg)
        return cfg
    return f"track_zones({kw})", run, (base,)


def _spans(rng):
    n = rng.choice([0, 1, 2, 3, 5])
    lengths = [_value(rng, "length") if rng.random() < 0.3 else rng.choice([20.0, 32.0, 40.0]) for _ in range(n)]
    if rng.random() < 0.1:
        lengths = rng.choice(["20", 20.0, None, [[20.0, 30.0]], np.array([20.0, 30.0]), [1e8], {"a": 1}])
    kw = {}
    for name, role in (("pier_stiffness", "stiffness"), ("pier_damping", "damping"), ("bearing_offset", "length"), ("simply_supported", "flag")):
        if rng.random() < 0.3:
            kw[name] = _value(rng, role) if rng.random() < 0.8 else [_value(rng, role) for _ in range(rng.choice([1, 2, 4, 6]))]
    base = _fem_config() if kw.get("simply_supported") is True or rng.random() < 0.4 else small_config()

    def run():
        cfg = vtb.spans(base, lengths, **kw)
        if rng.random() < 0.3:
            return _run(cfg)
        return cfg
    return f"spans({lengths!r}, {kw})", run, (base,)


_PART_FIELDS = {
    "rail_joint": [("position", "position"), ("depth", "depth"), ("length", "length"), ("step", "depth"), ("wheel_radius", "length")],
    "dipped_weld": [("position", "position"), ("depth", "depth"), ("length", "length"), ("crown", "depth"), ("crown_length", "length")],
    "wheel_flat": [("position", "position"), ("depth", "depth"), ("length", "depth"), ("wheel", "count"), ("flat_shape", "flag")],
    "cosine_dip": [("position", "position"), ("depth", "depth"), ("length", "length")],
    "corrugation": [("amplitude", "depth"), ("wavelength", "length"), ("start", "position"), ("end", "position")],
    "sampled": [("x0", "position"), ("dx", "length"), ("values", "depth")],
    "tbt3352": [("wavelength_min", "length"), ("wavelength_max", "length"), ("seed", "seed"), ("scale", "depth"), ("dx", "length")],
}


def _part(rng):
    kind = rng.choice(list(_PART_FIELDS)) if rng.random() < 0.9 else rng.choice(["joint", "", 3, "none"])
    kw = {"kind": kind}
    defaults = {"rail_joint": dict(position=21.0, depth=1e-3, length=0.3), "dipped_weld": dict(position=21.0, depth=1e-3, length=1.0),
                "wheel_flat": dict(position=21.0, length=0.05), "cosine_dip": dict(position=21.0, depth=1e-3, length=2.0),
                "corrugation": dict(amplitude=1e-4, wavelength=0.1, start=15.0, end=30.0), "sampled": dict(x0=15.0, dx=0.01, values=[0.0, 1e-4, 0.0]),
                "tbt3352": dict(seed=1)}
    kw.update(defaults.get(kind, {}))
    for name, role in _PART_FIELDS.get(kind, []):
        if rng.random() < 0.3:
            v = _value(rng, role)
            kw[name] = ([v, v] if name == "values" else v)
    return kw


def _profile(rng):
    parts = [_part(rng) for _ in range(rng.choice([1, 1, 2]))]
    as_part = rng.random() < 0.5

    def run():
        cfg = small_config(0.004)
        made = [vtb.Irregularity(**p) for p in parts]
        if as_part:
            cfg.irregularity.parts = made
        else:
            cfg.irregularity = made[0]
        return _run(cfg)
    return f"irregularity {'parts' if as_part else ''}{parts}", run, ()


def _dampers(rng):
    fields = [("inertance", "depth"), ("stiffness", "stiffness"), ("damping", "damping"), ("count", "count"), ("x0", "position"),
              ("spacing", "length"), ("kind", "flag"), ("upper", "flag"), ("lower", "flag"), ("name", "flag"), ("positions", "position")]
    changes = {}
    for name, role in rng.sample(fields, rng.choice([1, 2, 3])):
        v = _value(rng, role)
        if name in ("kind", "upper", "lower", "name") and rng.random() < 0.6:
            v = rng.choice(["tid", "tvmd", "tmd", "rail", "slab", "ground", "tids", "", "bridge", "x"])
        if name == "positions" and rng.random() < 0.7:
            v = [rng.choice([40.0, 80.0, 200.0, -1.0, float("nan")]) for _ in range(rng.choice([0, 1, 2]))]
        changes[name] = v
    groups = rng.choice([1, 2])

    def run():
        cfg = small_config()
        g = cfg.dampers[0] if groups == 1 else vtb.DamperGroup(kind="tvmd", inertance=3.0, stiffness=1e8, damping=2e3, positions=[40.0, 120.0])
        if groups == 2:
            cfg.dampers = cfg.dampers + [g]
        for k, v in changes.items():
            setattr(g, k, v)
        return _run(cfg)
    return f"dampers[{groups - 1}] {changes}", run, ()


def _bands(rng):
    changes = {}
    if rng.random() < 0.6:
        changes["band_levels"] = [_value(rng, "freq") for _ in range(rng.choice([0, 1, 2, 3]))] if rng.random() < 0.9 else _value(rng, "freq")
    if rng.random() < 0.4:
        changes["band_limit"] = rng.choice([None, 1e-9, 1e-3, 0.5, 30.0, 1e4, 2e4]) if rng.random() < 0.5 else _value(rng, "freq")
    if rng.random() < 0.3:
        changes["deck_band"] = _value(rng, "freq")
    method = rng.choice(["hybrid", "modal", "fem"])

    def run():
        cfg = small_config(0.004) if method != "fem" else _fem_config(0.004)
        cfg.discretisation.method = method
        for k, v in changes.items():
            setattr(cfg.output, k, v)
        return _run(cfg)
    return f"output {changes} on {method}", run, ()


def _contact(rng):
    fields = [("contact_patch", "flag"), ("contact_constant", "stiffness"), ("rail_crown_radius", "length"), ("rails", "count"), ("wheel_radius", "length")]
    changes = {n: _value(rng, r) for n, r in rng.sample(fields, rng.choice([1, 2]))}
    fem = rng.random() < 0.5

    def run():
        cfg = _fem_config() if fem else small_config()
        for k, v in changes.items():
            setattr(cfg.vehicles[0], k, v)
        return _run(cfg)
    return f"vehicles[0] {changes} ({'fem' if fem else 'hybrid'})", run, ()


def _edges(rng):
    changes = {}
    for name, role in (("edge_ramp", "length"), ("edge_step", "flag"), ("tail", "time"), ("end_margin", "length"), ("t_end", "time")):
        if rng.random() < 0.4:
            changes[name] = _value(rng, role)
    x_front = rng.choice([None, -5.0, 0.0, 158.0, 170.0, 1e6]) if rng.random() < 0.5 else None
    if rng.random() < 0.1:
        # long runs that must be refused at once (a wheel crossing the rail's end; too many
        # steps), not long valid runs off the structure: cases stay cheap
        changes.update(t_end=rng.choice([100.0, 1000.0, 1e5]), edge_step=False, edge_ramp=0.0)
    fem = rng.random() < 0.5

    def run():
        cfg = _fem_config() if fem else small_config()
        for k, v in changes.items():
            setattr(cfg.solver, k, v)
        if x_front is not None:
            cfg.vehicles[0].x_front = x_front
        return _run(cfg)
    return f"solver {changes}, x_front {x_front}", run, ()


_STUDY_KEYS = ["speed", "tids.stiffness", "k_t", "irregularity.seed", "solver.dt", "structure.couplings[0].stiffness", "spede", "",
               None, ("speed",), 3, "vehicles[9].m_c", "structure..length", "dampers"]


def _studies(rng):
    n_keys = rng.choice([1, 1, 2])
    grid = {}
    for _ in range(n_keys):
        key = rng.choice(_STUDY_KEYS[:4]) if rng.random() < 0.6 else rng.choice(_STUDY_KEYS)
        values = [rng.choice([60.0, 70.0, 1e8, 2.0])] if rng.random() < 0.7 else _value(rng, "freq")
        if key == "speed" and isinstance(values, list):
            values = [rng.choice([60.0, 70.0])]
        if key == "irregularity.seed" and isinstance(values, list):
            values = [rng.choice([1.0, 2.0, 2.5, -1.0])]
        try:
            grid[key] = values
        except TypeError:
            grid["speed"] = [60.0]
    kw = {}
    if rng.random() < 0.15:
        kw["reference"] = rng.choice([{"tids": None}, "tids", {"spede": 1.0}, {None: 1}, [], {"speed": float("nan")}])
    if rng.random() < 0.15:
        kw["indices"] = rng.choice([["rail_acc_max"], "rail_acc_max", [], ["nope"], 3, [3], None])
    if rng.random() < 0.1:
        kw["threads"] = rng.choice([1, 0, -1, "x", 2.5])
    if rng.random() < 0.1:
        kw["cases"], grid = rng.choice([[{"speed": 60.0}], [], "x", [{"speed": 60.0}, {"k_t": 1e8}], [{None: 1.0}]]), None
    out_kind = rng.choice([None, None, None, "file", "file", "dir-as-file", "blocked", "parquet", 3])

    def run():
        with tempfile.TemporaryDirectory() as d:
            out = {None: None, "file": Path(d) / "s.csv", "dir-as-file": Path(d), "parquet": Path(d) / "s.parquet",
                   "blocked": Path(d) / "f" / "s.csv", 3: 3}[out_kind]
            if out_kind == "blocked":
                (Path(d) / "f").write_text("")
            res = vtb.study(small_config(), grid, progress=False, out=out, **kw)
            return res
    return f"study({grid}, out={out_kind}, {kw})", run, ()


def _optimisation(rng):
    kw = {"pop_size": 4, "n_gen": 1, "seed": 0, "progress": False}
    for name, role in (("pop_size", "count"), ("n_gen", "count"), ("seed", "seed")):
        if rng.random() < 0.3:
            kw[name] = _value(rng, role)
    if rng.random() < 0.2:
        kw["algorithm"] = rng.choice(["nsga2", "gamultiobj", "ga", 3])
    if rng.random() < 0.1:
        kw["pop_size"] = 10**9
    custom = rng.random() < 0.7
    if custom:
        kw["variables"] = rng.choice([{"k_t": (1e7, 1e9, "log")}, {"speed": (60.0, 70.0, "linear")}, {"k_t": (1e9, 1e7, "log")},
                                      {"k_t": ("a", 1e9, "log")}, {None: (1, 2, "log")}, {}, "k_t", {"spede": (1.0, 2.0, "linear")}])
        kw["objectives"] = rng.choice([["rail_acc_rms"], ["rail_acc_rms", "slab_acc_rms"], [], "rail_acc_rms", ["nope"], None])
        if rng.random() < 0.3:
            kw["constraints"] = rng.choice([[("rail_acc_max", "reference")], [("rail_acc_max", float("nan"))], "x", [("nope", 1.0)]])
            kw["reference"] = rng.choice([{"tids": None}, None, "tids"])
    if rng.random() < 0.1:
        kw["checkpoint"] = rng.choice([3, "", None])

    def run():
        return vtb.optimize(small_config(), **kw)
    return f"optimize({kw})", run, ()


def _older(rng):
    label, thunk = fuzz_cases.make_case(rng)
    return label, thunk, ()


_MAKERS = {"config": _older, "trains": _trains, "zones": _zones, "spans": _spans, "profile": _profile, "dampers": _dampers,
           "bands": _bands, "contact": _contact, "edges": _edges, "studies": _studies, "optimisation": _optimisation,
           **fuzz_bridge.MAKERS}
#: The surfaces, in the order the long run takes them (benches/fuzz_config.py imports this).
SURFACES = tuple(_MAKERS)


def make_case(rng: random.Random, surface: str):
    """(label, thunk, inputs) of one case of ``surface``; ``inputs``: objects the call must leave
    unchanged."""
    return _MAKERS[surface](rng)


# -------------------------------------------------------------------------------- verdict

def _finite(res) -> bool:
    if isinstance(res, vtb.Result):
        return all(math.isfinite(v) for v in res.metrics().values()) and all(
            np.isfinite(a).all() for a in (res.disp, res.acc, res.vehicle_disp, res.vehicle_acc, res.contact_force))
    if isinstance(res, vtb.Config):
        text = res.to_json() if hasattr(res, "to_json") else str(res.to_dict())
        return "NaN" not in text and "Infinity" not in text
    if isinstance(res, (list, tuple)):
        return all(_finite(x) for x in res)
    if isinstance(res, dict):
        return all(_finite(x) for x in res.values())
    if isinstance(res, vtb.StudyResult):
        ok = res.succeeded
        return all(np.isfinite(res.columns[k][ok]).all() for k in res.indices)
    if isinstance(res, vtb.ScanResult):  # a failed run's row is NaN by design, its error says why
        ok = res.columns["error"] == ""
        return all(np.isfinite(res.columns[k][ok]).all() for k in ("speed", "acc", "disp", "acc_x", "disp_x"))
    if isinstance(res, vtb.Assessment):
        return all(math.isfinite(v) for v in (res.n0, res.band, res.lm71, res.phi, res.damping.ratio)) and _finite(res.scan)
    if isinstance(res, vtb.LoadTrain):
        return _finite(res.positions) and _finite(res.loads) and (res.spacing is None or math.isfinite(res.spacing))
    if isinstance(res, vtb.MovingForce):
        return math.isfinite(res.magnitude) and math.isfinite(res.x0)
    if hasattr(res, "ratio") and hasattr(res, "interaction"):  # the code's damping
        return math.isfinite(res.ratio)
    if hasattr(res, "g") and hasattr(res, "x"):  # an influence line
        return bool(np.isfinite(res.g).all() and np.isfinite(res.x).all())
    if isinstance(res, np.ndarray) and res.dtype.kind in "fiu":
        return bool(np.isfinite(res).all())
    if isinstance(res, (float, np.floating)) and not isinstance(res, bool):
        return math.isfinite(res)
    if hasattr(res, "F"):
        return bool(np.isfinite(np.asarray(res.F, dtype=float)).all())
    if hasattr(res, "x_front"):  # a vehicle
        return math.isfinite(res.x_front)
    return True


def _snapshot(objs):
    # as text: NaN compares equal to itself, and arrays compare as a whole
    return [repr(o.to_dict() if isinstance(o, vtb.Config) else o) for o in objs]


def verdict(label: str, thunk, inputs=()) -> tuple[str, str]:
    """Runs a case: ``("ok", "")`` for a finite result, ``("refused", field)`` for a vtb error
    naming a usable field, else a finding (module docstring) with its detail."""
    before = _snapshot(inputs)
    t0 = time.perf_counter()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            res = thunk()
    except (ConfigError, OutputError) as e:
        if not isinstance(e.field, str) or e.field.strip() in UNNAMED or e.field.strip() == "":
            return "unnamed", f"{type(e).__name__} field={e.field!r}: {e}"
        out = ("refused", str(e.field))
    except (ConvergenceError, SolverError) as e:
        if "internal error" in str(e) or "panic" in str(e).lower():
            return "panic", str(e)
        out = ("refused", type(e).__name__)
    except VtbError as e:
        out = ("refused", type(e).__name__)
    except BaseException as e:  # noqa: BLE001 - any other exception is a finding
        if isinstance(e, KeyboardInterrupt):
            raise
        if type(e).__name__ == "PanicException":
            return "panic", str(e)
        return "undocumented", f"{type(e).__name__}: {e}"
    else:
        out = ("ok", "") if _finite(res) else ("nonfinite", label)
    seconds = time.perf_counter() - t0
    if _snapshot(inputs) != before:
        return "mutated", label
    if out[0] == "refused" and seconds > REFUSAL_SECONDS:
        return "slow", f"refused ({out[1]}) after {seconds:.2f} s"
    return out
