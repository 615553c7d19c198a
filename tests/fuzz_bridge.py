"""Generated bad input for the bridge engineer's surfaces (tests/fuzz_surfaces.py registers
them): ``load_trains`` (:func:`vtb.load_train` by name, HSLM-B, the library's trains, CSV
tables, :class:`vtb.LoadTrain`, its forces, :func:`vtb.apply_load_train`), ``damping``
(vtb.bridge.damping), ``scan`` (vtb.bridge.scan), ``interaction`` (vtb.bridge.interaction),
``static`` (vtb.bridge.static), ``checks`` (vtb.bridge.checks) and ``bridge_check``
(:class:`~vtb.bridge.settings.BridgeCheck`, its TOML table, :func:`vtb.bridge_check` and
``vtb bridge-check``).

Each case mutates a good call on a cheap model: a 20 m simply supported beam of 8 modes at a
time step of 2 ms, a few speeds and short trains, so that a valid run takes milliseconds and
only a bad value can make a case slow.
"""

from __future__ import annotations

import contextlib
import copy
import io
import math
import random
import tempfile
from pathlib import Path

import numpy as np

import vtb
from vtb import cli
from vtb.bridge import checks, damping, interaction, load_trains, scan, settings, static
from fuzz_cases import BAD_NUMBERS, BAD_OTHER, small_config

#: The beam of tests/test_bridge_check.py: span (m), mass (kg/m), first frequency (Hz).
SPAN, MASS, N0 = 20.0, 12000.0, 4.0
#: Values no caller means, that a check must refuse before any work: a count or a length that
#: would allocate or run for ever.
HUGE = [10**9, 1e9, 1e8, 1e15, 1e300, 2**63]
TINY = [1e-15, 1e-300, 1e-9]


def beam(dt: float = 2e-3):
    """The 20 m simply supported beam (n0 = 4 Hz), 8 modes, observed at midspan."""
    e = 3.5e10
    ei = (2 * N0 * SPAN**2 / math.pi) ** 2 * MASS
    return vtb.moving_load_config(SPAN, 2500.0, MASS / 2500.0, e, ei / e, [vtb.MovingForce(1.0, 0.0)], 50.0, points=[SPAN / 2],
                                  modes=8, dt=dt)


def _bad(rng: random.Random):
    r = rng.random()
    if r < 0.45:
        return rng.choice(BAD_NUMBERS)
    if r < 0.6:
        return rng.choice(HUGE + TINY)
    return copy.deepcopy(rng.choice(BAD_OTHER))


def _or_bad(rng: random.Random, good, p: float = 0.35):
    """``good`` (1 − p) or a bad value (p)."""
    return _bad(rng) if rng.random() < p else good


def _kwargs(rng: random.Random, fields: dict, p: float = 0.3) -> dict:
    """Some of ``fields`` (name → good value), each replaced by a bad value with chance 0.35."""
    return {k: _or_bad(rng, v) for k, v in fields.items() if rng.random() < p}


_TRAIN_NAMES = [f"HSLM-A{i}" for i in range(1, 11)] + ["crh3", "velaro_e", "HSLM-B"]
_ODD_NAMES = ["HSLM-A0", "HSLM-A11", "hslm-a3", "HSLM-A", "HSLM-A-1", "HSLM-A1.5", "HSLM-Ax", "hslm-b", "ice", "", "CRH3", "x.csv",
              3, None, 2.5, ["HSLM-A1"], b"HSLM-A1"]

#: CSV rows: good, and each kind of bad one.
_ROWS = {
    "good": "0.0,170000\n3.0,170000\n14.0,190000\n",
    "header": "position,load\n0,1e5\n2.5,1e5\n",
    "comment": "# axles\n0,1e5\n",
    "nan": "0,nan\n1,1e5\n",
    "inf": "0,1e5\ninf,1e5\n",
    "negative": "0,-1e5\n",
    "zero": "0,0\n",
    "unsorted": "0,1e5\n5,1e5\n2,1e5\n",
    "text": "0,1e5\nx,y\n",
    "three": "0,1e5,7\n",
    "one": "0\n",
    "empty": "",
    "only_header": "position,load\n",
    "huge": "0,1e300\n1e300,1e300\n",
    "many": "".join(f"{i * 0.5},1e5\n" for i in range(2000)),
    "binary": "\x00\x01\x02",
    "semicolon": "0;1e5\n",
}


def _load_trains(rng):
    kind = rng.choice(["name", "name", "hslm_b", "library", "csv", "csv", "table", "forces", "apply", "apply", "list", "resonant"])
    if kind == "list":
        return "load_trains()", load_trains.load_trains, ()
    if kind == "name":
        name = rng.choice(_TRAIN_NAMES) if rng.random() < 0.6 else copy.deepcopy(rng.choice(_ODD_NAMES))
        return f"load_train({name!r})", (lambda: vtb.load_train(name)), ()
    if kind == "hslm_b":
        kw = {"n": _or_bad(rng, rng.choice([1, 5, 10, 20])), "d": _or_bad(rng, rng.choice([2.5, 3.0, 4.5]))}
        if rng.random() < 0.2:
            kw.pop(rng.choice(["n", "d"]))
        return f"load_train('HSLM-B', {kw})", (lambda: vtb.load_train("HSLM-B", **kw)), ()
    if kind == "library":
        name = rng.choice(["crh3", "velaro_e"])
        cars = _or_bad(rng, rng.choice([None, 1, 2, 8]), 0.5)
        return f"load_train({name!r}, cars={cars!r})", (lambda: vtb.load_train(name, cars=cars)), ()
    if kind == "csv":
        rows = rng.choice(list(_ROWS))
        how = rng.choice(["name", "path", "read", "read", "missing", "folder"])
        spacing = _or_bad(rng, rng.choice([None, 18.0]), 0.4)

        def run():
            with tempfile.TemporaryDirectory() as d:
                p = Path(d) / "train.csv"
                p.write_text(_ROWS[rows])
                if how == "missing":
                    p = Path(d) / "absent.csv"
                if how == "folder":
                    p = Path(d) / "dir.csv"
                    p.mkdir()
                if how == "read":
                    return load_trains.read_load_train(p, spacing=spacing)
                return vtb.load_train(str(p) if how == "name" else p)
        return f"csv {rows} by {how}, spacing={spacing!r}", run, ()
    if kind == "table":
        n = rng.choice([0, 1, 3])
        positions = [rng.choice([0.0, 3.0, 14.0]) for _ in range(n)] if rng.random() < 0.7 else _bad(rng)
        loads = [_or_bad(rng, 1e5, 0.2) for _ in range(n)] if rng.random() < 0.7 else _bad(rng)
        positions = sorted(positions) if isinstance(positions, list) and rng.random() < 0.7 and all(isinstance(x, float) for x in positions) else positions
        spacing = _or_bad(rng, rng.choice([None, 18.0]), 0.3)
        use = rng.choice(["length", "forces", "scan"])

        def run():
            t = vtb.LoadTrain("user", positions, loads, "fuzz", spacing=spacing)
            if use == "length":
                return (t.length, t.axles)
            if use == "forces":
                return t.forces(10.0)
            return scan.speed_scan(beam(), [t], [60.0], progress=False)
        return f"LoadTrain({positions!r}, {loads!r}, spacing={spacing!r}).{use}", run, ()
    if kind == "forces":
        kw = _kwargs(rng, {"x_front": 10.0, "layer": None, "share": 0.5}, 0.6)
        if "layer" in kw and rng.random() < 0.5:
            kw["layer"] = rng.choice(["beam", "deck", "rail", ""])
        name = rng.choice(["HSLM-A1", "crh3"])
        return f"load_train({name!r}).forces({kw})", (lambda: vtb.load_train(name).forces(**kw)), ()
    if kind == "apply":
        base = beam()
        kw = _kwargs(rng, {"share": 0.5, "tail": 0.2, "gap": 1.0, "layer": None}, 0.5)
        train = rng.choice(["HSLM-A1", "HSLM-A9", "crh3"]) if rng.random() < 0.8 else copy.deepcopy(rng.choice(_ODD_NAMES))
        run_it = rng.random() < 0.5

        def run():
            cfg = vtb.apply_load_train(base, train, **kw)
            if run_it:
                cfg.speed = 80.0
                return vtb.simulate(cfg, progress=False)
            return cfg
        return f"apply_load_train(beam, {train!r}, {kw}){' run' if run_it else ''}", run, (base,)
    # resonant speeds: the check's arithmetic, public in the module
    args = [_or_bad(rng, 4.0), _or_bad(rng, 18.0), _or_bad(rng, 75.0)]
    orders = rng.choice([range(1, 6), [1, 2], [0], [], [-1], [1.5], "x"]) if rng.random() < 0.3 else range(1, 6)
    return f"resonant_speeds({args}, orders={orders!r})", (lambda: load_trains.resonant_speeds(*args, orders=orders)), ()


_KINDS = list(damping.BRIDGE_TYPES) + ["timber", "", None, 3, "Steel_Composite"]


def _damping(rng):
    kind = rng.choice(_KINDS) if rng.random() < 0.3 else rng.choice(list(damping.BRIDGE_TYPES))
    span = _or_bad(rng, rng.choice([5.0, 20.0, 29.9, 30.0, 80.0]))
    what = rng.choice(["code", "table", "delta", "rayleigh", "achieved", "apply", "apply"])
    if what == "code":
        inter = _or_bad(rng, True, 0.2)
        return f"code_damping({kind!r}, {span!r}, {inter!r})", (lambda: damping.code_damping(kind, span, inter)), ()
    if what == "table":
        return f"table_6_6({kind!r}, {span!r})", (lambda: damping.table_6_6(kind, span)), ()
    if what == "delta":
        return f"delta_zeta({span!r})", (lambda: damping.delta_zeta(span)), ()
    ratio, f_low, f_high = _or_bad(rng, 0.013), _or_bad(rng, 4.0), _or_bad(rng, 36.0)
    if what == "rayleigh":
        return f"code_rayleigh({ratio!r}, {f_low!r}, {f_high!r})", (lambda: damping.code_rayleigh(ratio, f_low, f_high)), ()
    if what == "achieved":
        freqs = rng.choice([[4.0, 16.0], [], [0.0], [float("nan")], "x", [[1.0]], 4.0])

        def achieved():
            return damping.achieved_ratios(damping.code_rayleigh(0.013, 4.0, 36.0), freqs)
        return f"achieved_ratios({freqs!r})", achieved, ()
    base = beam()
    layer = rng.choice([None, None, "beam", "deck", "", 3])
    run_it = rng.random() < 0.5

    def apply():
        cfg = damping.apply_code_damping(base, damping.code_damping(kind, span), f_low, f_high, layer)
        return vtb.simulate(cfg, progress=False) if run_it else cfg
    return f"apply_code_damping(beam, {kind!r}, {span!r}, {f_low!r}, {f_high!r}, layer={layer!r})", apply, (base,)


def _speeds(rng):
    if rng.random() < 0.7:
        return [rng.choice([40.0, 60.0, 80.0]) for _ in range(rng.choice([1, 2]))]
    return copy.deepcopy(rng.choice([[], [float("nan")], [-60.0], [0.0], 60.0, "60", [None], [[60.0, 70.0]], np.array([60.0, 70.0]),
                                     [1e9], [1e-15], {"a": 60.0}, [60.0, "x"]]))


def _trains_arg(rng):
    if rng.random() < 0.7:
        return [rng.choice(["HSLM-A1", "HSLM-A5", "crh3", "velaro_e"])]
    return copy.deepcopy(rng.choice([[], "HSLM-A1", ["HSLM-A11"], ["nope"], [None], [3], None, ["HSLM-B"], [["HSLM-A1"]]]))


def _bounds(rng):
    if rng.random() < 0.7:
        return rng.choice([None, {"nominal": 1.0}, {"lower": 1.0, "upper": 1.15}])
    return copy.deepcopy(rng.choice([{}, {"x": 0.0}, {"x": -1.0}, {"x": float("nan")}, {"x": float("inf")}, {"x": "1"}, {"x": 1e300},
                                     {"x": None}, [1.0], "x", 3, {None: 1.0}, {3: 1.0}, {"a/b": 1.0}, {"": 1.0}]))


def _out(rng, d: Path):
    kind = rng.choice([None, None, "dir", "file-as-dir", "missing-parent", "int"])
    if kind == "file-as-dir":
        (d / "f").write_text("")
        return kind, d / "f"
    return kind, {None: None, "dir": d / "scan", "missing-parent": d / "no" / "scan", "int": 3}[kind]


def _scan(rng):
    what = rng.choice(["scan", "scan", "scan", "speeds", "speeds", "band", "mass", "points", "indices"])
    if what == "scan":
        base = beam()
        trains, speeds, bounds = _trains_arg(rng), _speeds(rng), _bounds(rng)
        kw = _kwargs(rng, {"band": 30.0, "share": 0.5, "tail": 0.2, "gap": 1.0, "threads": 1}, 0.3)
        inputs = [base, trains, speeds, bounds]
        seed = rng.random()

        def run():
            with tempfile.TemporaryDirectory() as d:
                _, out = _out(random.Random(seed), Path(d))
                return scan.speed_scan(base, trains, speeds, mass_bounds=bounds, out=out, progress=False, **kw)
        return f"speed_scan(beam, {trains!r}, {speeds!r}, mass_bounds={bounds!r}, {kw})", run, inputs
    if what == "speeds":
        args = [_or_bad(rng, 40 / 3.6), _or_bad(rng, 270 / 3.6)]
        kw = _kwargs(rng, {"step": 10 / 3.6, "fine_step": 0.5, "fine_width": 5.0}, 0.4)
        if rng.random() < 0.3:
            kw["resonances"] = rng.choice([[72.0], [], [float("nan")], "x", [None], [1e300], 72.0])
        return f"scan_speeds({args}, {kw})", (lambda: scan.scan_speeds(*args, **kw)), ()
    base = beam() if rng.random() < 0.6 else small_config()
    if what == "band":
        band = _or_bad(rng, 30.0, 0.6)
        run_it = rng.random() < 0.4 and base.structure.length < 100

        def banded():
            cfg = scan.with_band(base, band)
            return vtb.simulate(cfg, progress=False) if run_it else cfg
        return f"with_band({band!r}){' run' if run_it else ''}", banded, (base,)
    if what == "mass":
        factor = _or_bad(rng, 1.15, 0.6)
        return f"with_mass({factor!r})", (lambda: scan.with_mass(base, factor)), (base,)
    fn = {"points": scan.span_points, "indices": rng.choice([scan.deck_indices, scan.point_indices])}[what]
    change = rng.choice([None, "layers", "points", "joints", "length"])
    value = _bad(rng)

    def observe():
        cfg = base.copy()
        if change == "layers":
            cfg.structure.layers = []
        elif change == "points":
            cfg.output.points = value
        elif change == "joints":
            cfg.structure.layers[-1].joints = value
        elif change == "length":
            cfg.structure.length = value
        return fn(cfg)
    return f"{fn.__name__}(cfg with {change} = {value!r})", observe, (base,)


def _interaction(rng):
    base = beam()
    trains = [rng.choice(["crh3", "velaro_e"])] if rng.random() < 0.7 else copy.deepcopy(
        rng.choice([[], ["HSLM-A1"], ["nope"], [None], "crh3", None, [3]]))
    speeds = [rng.choice([60.0, 80.0])] if rng.random() < 0.8 else _speeds(rng)
    kw = _kwargs(rng, {"band": 30.0, "cars": 1, "tail": 0.2, "gap": 1.0}, 0.3)
    if rng.random() < 0.15:
        kw["irregularity"] = rng.choice([vtb.Irregularity(), "smooth", 3, vtb.Irregularity(kind="cosine_dip", position=10.0, depth=1e-3, length=2.0)])
    if rng.random() < 0.3:
        kw["mass_bounds"] = _bounds(rng)
    if rng.random() < 0.3:
        name = trains[0] if isinstance(trains, list) and trains else trains
        vk = {k: v for k, v in kw.items() if k in ("gap", "tail", "cars", "irregularity")}
        return f"with_vehicles(beam, {name!r}, {vk})", (lambda: interaction.with_vehicles(base, name, **vk)), (base,)
    seed = rng.random()

    def run():
        with tempfile.TemporaryDirectory() as d:
            _, out = _out(random.Random(seed), Path(d))
            return interaction.interaction_scan(base, trains, speeds, out=out, progress=False, **kw)
    return f"interaction_scan(beam, {trains!r}, {speeds!r}, {kw})", run, (base, trains, speeds)


def _static(rng):
    base = beam() if rng.random() < 0.8 else small_config()
    what = rng.choice(["line", "line", "train", "lm71", "freq"])
    if what == "freq":
        kw = _kwargs(rng, {"fmax": 120.0, "share": 0.5, "cluster": 0.03}, 0.6)
        return f"deck_frequencies({kw})", (lambda: static.deck_frequencies(base, **kw)), (base,)
    kw = _kwargs(rng, {"point": 10.0, "dx": 0.25}, 0.5)
    if rng.random() < 0.2:
        kw["layer"] = rng.choice(["beam", "deck", "", 3, None, -1, 5])
    if what == "line":
        return f"influence_line({kw})", (lambda: static.influence_line(base, **kw)), (base,)
    share = _or_bad(rng, 1.0)
    if what == "train":
        train = rng.choice(["HSLM-A1", "crh3"])
        return (f"influence_line({kw}).train({train!r}, {share!r})",
                lambda: static.influence_line(base, **kw).train(vtb.load_train(train), share), (base,))
    alpha = _or_bad(rng, 1.0)
    return f"influence_line({kw}).lm71({alpha!r}, {share!r})", (lambda: static.influence_line(base, **kw).lm71(alpha, share)), (base,)


def _checks(rng):
    what = rng.choice(["limits", "flow", "phi2", "phi3", "irr", "acc"])
    if what == "acc":
        track = rng.choice(list(checks.ACCELERATION_LIMITS) + ["slab", "", None, 3, ["ballasted"]])
        return f"acceleration_limit({track!r})", (lambda: checks.acceleration_limit(track)), ()
    span, n0, speed = _or_bad(rng, 20.0), _or_bad(rng, 4.0), _or_bad(rng, 60.0)
    if what == "limits":
        def limits():
            lower, upper = checks.n0_limits(span)
            if not 4.0 <= span <= 100.0:  # the figure's range: (nan, nan) outside it, as documented
                if not (math.isnan(lower) and math.isnan(upper)):
                    raise AssertionError(f"n0_limits({span!r}) = {(lower, upper)} outside Fig. 6.10's 4–100 m")
                return ()
            return lower, upper
        return f"n0_limits({span!r})", limits, ()
    if what == "flow":
        simple, cont = _or_bad(rng, True, 0.2), _or_bad(rng, False, 0.2)
        return (f"dynamic_analysis_required({span!r}, {n0!r}, {speed!r}, {simple!r}, {cont!r})",
                lambda: checks.dynamic_analysis_required(span, n0, speed, simple, cont), ())
    if what == "phi2":
        return f"phi_2({span!r})", (lambda: checks.phi_2(span)), ()
    if what == "phi3":
        return f"phi_3({span!r})", (lambda: checks.phi_3(span)), ()
    return f"phi_irregularity({span!r}, {n0!r}, {speed!r})", (lambda: checks.phi_irregularity(span, n0, speed)), ()


#: A cheap check of the beam: two speeds of one train.
_SETTINGS = dict(span=SPAN, bridge_type="prestressed_concrete", track="ballasted", line_speed=225 / 3.6, v_min=220 / 3.6,
                 step=10 / 3.6, trains=["HSLM-A1"], dt=2e-3)
_OPTIONAL = dict(mass_bounds={"nominal": 1.0}, interaction=True, vehicles=["crh3"], n0=4.0, band=36.0, share=1.0, alpha=1.0,
                 maintenance="standard", l_phi=20.0, comfort_ratio=1000.0, simple_structure=True, continuous=False, tail=0.2)
_FIELD_VALUES = {"bridge_type": ["timber", "", None, 3], "track": ["slab", "", None], "maintenance": ["poor", "", None],
                 "trains": [[], ["nope"], ["HSLM-A11"], "HSLM-A1", [3], ["HSLM-B"], [None]], "vehicles": [["nope"], "crh3", [3], None],
                 "mass_bounds": [{}, {"x": 0.0}, {"x": "1"}, [1.0], {"x": float("nan")}, {"x": 1e9}]}


def _bridge_check(rng):
    data = dict(_SETTINGS)
    for k, v in _OPTIONAL.items():
        if rng.random() < 0.15:
            data[k] = copy.deepcopy(v)
    for k in rng.sample(sorted(data), rng.choice([0, 1, 1, 2])):
        data[k] = copy.deepcopy(rng.choice(_FIELD_VALUES[k])) if k in _FIELD_VALUES and rng.random() < 0.6 else _bad(rng)
    how = rng.choice(["dataclass", "dict", "dict", "run", "run", "toml", "cli"])
    if how != "dataclass":  # a table may lack a field or have one too many; a call with a wrong keyword is Python's TypeError
        if rng.random() < 0.05:
            data["speeed"] = 1.0
        if rng.random() < 0.05:
            data.pop(rng.choice(["span", "bridge_type", "track", "line_speed"]))
    base = beam()
    inputs = (base, data)
    if how == "dataclass":
        return f"BridgeCheck(**{data}).validate()", (lambda: settings.BridgeCheck(**data).validate()), inputs
    if how == "dict":
        return f"BridgeCheck.from_dict({data})", (lambda: settings.BridgeCheck.from_dict(data)), inputs
    out_kind = rng.choice(["dir", "dir", "dir", "file-as-dir", "missing-parent"])

    def folder(d: Path) -> Path:
        if out_kind == "file-as-dir":
            (d / "f").write_text("")
            return d / "f"
        return d / ("no/check" if out_kind == "missing-parent" else "check")
    if how == "run":
        def run():
            with tempfile.TemporaryDirectory() as d:
                return vtb.bridge_check(base, data, folder(Path(d)), progress=False, figures=False)
        return f"bridge_check(beam, {data}, out={out_kind})", run, inputs
    text = base.to_toml() + "\n[bridge_check]\n" + "".join(f"{k} = {_toml(v)}\n" for k, v in data.items())

    def toml():
        with tempfile.TemporaryDirectory() as d:
            p = Path(d) / "bridge.toml"
            p.write_text(text)
            if how == "toml":
                return settings.split_toml(p)
            with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):  # the runner reads its worker's stdout
                code = cli.main(["bridge-check", str(p), "--out", str(folder(Path(d))), "--no-progress", "--no-plot"])
            if code not in (0, 1, 2):
                raise AssertionError(f"exit status {code}")
            return code
    return f"{how} [bridge_check] {data} out={out_kind}", toml, inputs


def _toml(v) -> str:
    """A value as TOML text (None: a bare word TOML refuses; NaN and infinities as TOML's)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return "nan" if math.isnan(v) else ("inf" if v > 0 else "-inf") if math.isinf(v) else repr(v)
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, dict):
        return "{" + ", ".join(f'"{k}" = {_toml(x)}' for k, x in v.items()) + "}"
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml(x) for x in v) + "]"
    return str(v)


MAKERS = {"load_trains": _load_trains, "damping": _damping, "scan": _scan, "interaction": _interaction, "static": _static,
          "checks": _checks, "bridge_check": _bridge_check}
