"""Generated bad input for the fuzz test (tests/test_fuzz.py) and the long fuzz run
(benches/fuzz_config.py): one case from a seeded ``random.Random``, and the verdict on what
the API did with it.

A case mutates a small, fast configuration (the article's case with 8 modes per layer and
40 time steps) in one of four ways: values replaced in its plain dict (NaN, infinities,
negatives, zero, huge and tiny numbers, huge integers, strings, booleans, None, nested and 2-D
lists, tables), its structure changed (fields dropped or added, lists emptied or duplicated),
an attribute assigned on a config object (typos of field names, bad values, numpy arrays), or
its TOML text edited. The API may answer with a documented exception naming the field, or a
run whose every index and history is finite; anything else is a finding.
"""

from __future__ import annotations

import copy
import dataclasses
import math
import random

import numpy as np

import vtb
from vtb.errors import ConfigError, ConvergenceError, SolverError

#: Fields of a ConfigError that name no field.
UNNAMED = {None, "", "<config>", "<json>"}

BAD_NUMBERS = [
    float("nan"), float("inf"), -float("inf"), -1.0, -1e-12, 0.0, 1e-300, -1e-300, 1e300, -1e300,
    1e30, 1e15, 1e-15, 10**20, -(10**20), -5, 2**63, 3.5, 1, 0,
]
BAD_OTHER = ["x", "", "1.0", "true", True, False, None, [], [1.0, 2.0], [[1.0, 2.0], [3.0, 4.0]], {}, {"a": 1}, [None], ["x"]]


def small_config(t_end: float = 0.002, tids: bool = True) -> vtb.Config:
    """The article's case cut down (8 modes per layer, 8 local rail modes) to run in a few
    milliseconds for ``t_end`` s, with four dampers around mid-span unless ``tids=False``."""
    cfg = vtb.paper_config()
    for layer in cfg.structure.layers:
        layer.modes = 8
    cfg.structure.layers[0].local_modes = 8
    cfg.solver.t_end = t_end
    cfg.tids = vtb.TIDs(5.0, 2e8, 1e3, 4, 78.08, 0.64) if tids else None
    return cfg


def _leaves(d, path=()):
    """Paths of every leaf and every list of a plain config dict."""
    if isinstance(d, dict):
        for k, v in d.items():
            yield from _leaves(v, path + (k,))
    elif isinstance(d, list):
        yield path
        for i, v in enumerate(d):
            if isinstance(v, (dict, list)):
                yield from _leaves(v, path + (i,))
    else:
        yield path


def _tables(d, path=()):
    if isinstance(d, dict):
        yield path
        for k, v in d.items():
            yield from _tables(v, path + (k,))
    elif isinstance(d, list):
        for i, v in enumerate(d):
            yield from _tables(v, path + (i,))


def _node(d, path):
    for k in path:
        d = d[k]
    return d


def _bad_value(rng: random.Random):
    return rng.choice(BAD_NUMBERS) if rng.random() < 0.6 else copy.deepcopy(rng.choice(BAD_OTHER))


def _typo(rng: random.Random, name: str) -> str:
    i = rng.randrange(len(name) + 1)
    op = rng.randrange(4)
    if op == 0:
        return name[:i] + rng.choice("abcdefghijklmnopqrstuvwxyz_") + name[i:]
    if op == 1 and len(name) > 1:
        return name[:i] + name[i + 1:]
    if op == 2:
        return name + rng.choice(["s", "_", "1", "_m"])
    return name.upper()


def _config_objects(cfg):
    """(path, object) of every dataclass in a config tree."""
    out = [("", cfg)]
    i = 0
    while i < len(out):
        path, obj = out[i]
        i += 1
        for f in dataclasses.fields(obj):
            v = getattr(obj, f.name)
            sub = f"{path}.{f.name}" if path else f.name
            if dataclasses.is_dataclass(v):
                out.append((sub, v))
            elif isinstance(v, list):
                out.extend((f"{sub}[{j}]", x) for j, x in enumerate(v) if dataclasses.is_dataclass(x))
    return out


def make_case(rng: random.Random):
    """(label, thunk): calling the thunk runs the case through the public API."""
    kind = rng.choices(["values", "structure", "attribute", "toml"], weights=[5, 2, 2, 1])[0]
    base = small_config()
    # A second damper group of another kind at explicit positions: its fields are fuzzed too.
    base.dampers = [vtb.DamperGroup(kind="tvmd", inertance=3.0, stiffness=1e8, damping=2e3, positions=[40.0, 120.0])]
    if rng.random() < 0.2:  # the other vehicle model, its fields fuzzed alike
        base.vehicles = [vtb.Vehicle.quarter_car(13_600.0, 2_400.0, 1e6, 4e4, x_front=base.vehicles[0].x_front)]
    if kind == "values":
        d = base.to_dict()
        leaves = sorted(_leaves(d), key=str)
        changes = []
        for _ in range(rng.choice([1, 1, 1, 2, 3])):
            path = rng.choice(leaves)
            value = _bad_value(rng)
            try:
                parent = _node(d, path[:-1])
                parent[path[-1]] = value
            except (KeyError, IndexError, TypeError):
                continue
            changes.append(f"{'.'.join(map(str, path))} = {value!r}")
        return f"values: {'; '.join(changes)}", lambda: vtb.simulate(vtb.Config.from_dict(d))
    if kind == "structure":
        d = base.to_dict()
        tables = sorted((p for p in _tables(d) if p), key=str)
        path = rng.choice(tables)
        node = _node(d, path)
        op = rng.randrange(4)
        if op == 0 and node:
            key = rng.choice(sorted(node))
            del node[key]
            what = f"drop {'.'.join(map(str, path))}.{key}"
        elif op == 1:
            key = _typo(rng, rng.choice(sorted(node) or ["x"]))
            node[key] = _bad_value(rng)
            what = f"add {'.'.join(map(str, path))}.{key}"
        else:
            lists = [p for p in _leaves(d) if isinstance(_node(d, p), list)]
            lp = rng.choice(lists)
            lst = _node(d, lp)
            if op == 2 or not lst:
                lst.clear()
                what = f"empty {'.'.join(map(str, lp))}"
            else:
                lst.append(copy.deepcopy(rng.choice(lst)))
                what = f"duplicate an item of {'.'.join(map(str, lp))}"
        return f"structure: {what}", lambda: vtb.simulate(vtb.Config.from_dict(d))
    if kind == "attribute":
        cfg = base
        objs = _config_objects(cfg)
        path, obj = rng.choice(objs)
        names = [f.name for f in dataclasses.fields(obj)]
        name = rng.choice(names)
        if rng.random() < 0.5:
            name = _typo(rng, name)
        value = _bad_value(rng) if rng.random() < 0.8 else np.ones((2, 2))

        def run():
            setattr(obj, name, value)
            return vtb.simulate(cfg)

        return f"attribute: {path or 'config'}.{name} = {value!r}", run
    text = base.to_toml()
    lines = text.splitlines()
    i = rng.randrange(len(lines))
    op = rng.randrange(4)
    if op == 0:
        del lines[i]
    elif op == 1 and "=" in lines[i]:
        key = lines[i].split("=")[0]
        lines[i] = key + "= " + rng.choice(["nan", "inf", "-1", "\"x\"", "[1, [2]]", "{a = 1}", "1e400", "0", "true", "", "9223372036854775808"])
    elif op == 2:
        lines.insert(i, lines[i])
    else:
        lines[i] = lines[i][: rng.randrange(len(lines[i]) + 1)]
    edited = "\n".join(lines)
    return f"toml: line {i} op {op}", lambda: vtb.simulate(vtb.Config.from_toml_text(edited))


def verdict(thunk) -> tuple[str, str]:
    """Runs a case: ``("ok", "")`` for a finite run or a documented exception naming its
    field, else a finding — ``"nonfinite"``, ``"unnamed"``, ``"panic"`` or ``"undocumented"``
    — with its detail."""
    try:
        res = thunk()
    except ConfigError as e:
        if e.field in UNNAMED:
            return "unnamed", str(e)
        return "ok", ""
    except (ConvergenceError, SolverError) as e:
        if "internal error" in str(e):
            return "panic", str(e)
        return "ok", ""
    except BaseException as e:  # noqa: BLE001 - any other exception is a finding
        if type(e).__name__ == "PanicException":
            return "panic", str(e)
        if isinstance(e, KeyboardInterrupt):
            raise
        return "undocumented", f"{type(e).__name__}: {e}"
    finite = all(math.isfinite(v) for v in res.metrics().values()) and all(
        np.isfinite(a).all() for a in (res.disp, res.acc, res.vehicle_disp, res.vehicle_acc, res.contact_force)
    )
    return ("ok", "") if finite else ("nonfinite", str(res.metrics()))


def accept_implausible(cfg):
    """A test rig (an SDOF on 1e14 N/m², a vanishing damper) opts out of the plausible ranges
    field by field: every field the core refuses as implausible is listed in
    ``cfg.accept_implausible``. Returns ``cfg``."""
    while True:
        try:
            vtb._core.check_plausible(cfg.to_core_json())
            return cfg
        except ConfigError as e:
            if e.field in cfg.accept_implausible:
                raise
            cfg.accept_implausible.append(e.field)
