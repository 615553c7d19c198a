"""The converged finite elements' cost in length (docs/track-models.md, "The solver's
ordering"): the converged preset (`vtb.paper_config(model="converged")`, rail in 0.032 m
elements, lower layers in 0.32 m ones, each layer its own mesh) re-spanned over N simply
supported 32 m spans, one CRH3 car, for N = 5, 10, 20, 40; set-up (the core's assembly and
factorisation, before the first step) and the cost of one step, with their exponents in the
structure's length fitted by least squares in log–log. With ``--cars K`` (K > 1) a K-car CRH3
on the spans between 100 m embankments, its front 5 m past its length at the start: a train's
wheels keep asking for new columns of A⁻¹ as they cross the elements.

    python benches/fem_length.py [--spans 5 10 20 40] [--steps 2000] [--cars 8]
                                 [--baseline /path/to/old/python] [--old-max-spans 20]

Each measurement runs in a process of its own. With ``--baseline`` (a ``python/`` folder whose
``vtb`` holds an older build, e.g. the branch point's) the old build is measured in the same
run, alternating with the new one span count by span count, and the two are compared: times
as ratios, results (the displacement and acceleration histories and the metrics of the short
run) as their largest relative difference.

Times are CPU seconds of the process (the core steps on one thread; the machine is shared, so
wall times are noisier) read from the run's progress callback: the steps done against time are
fitted by a line whose slope is the time per step and whose intercept is the set-up.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
NEW_PYTHON = HERE.parent / "python"


def config(n_spans: int, steps: int, cars: int = 1):
    import vtb

    c = vtb.paper_config(model="converged")
    c = vtb.spans(c, [32.0] * n_spans, simply_supported=True)
    if cars > 1:
        c = vtb.track_zones(c, approach=100.0, exit=100.0)
        c.vehicles = vtb.train("crh3", cars=cars, x_front=26.0 * cars + 5.0, contact_patch=True)
    c.solver.t_end = steps * c.solver.dt
    return c


def measure(n_spans: int, steps: int, cars: int = 1) -> dict:
    """One run in this process: set-up and per-step CPU time, and the results' histories."""
    import time
    import warnings

    import numpy as np
    from vtb import _core
    from vtb.run.simulate import prepare

    warnings.simplefilter("ignore")
    cfg = config(n_spans, steps, cars)
    text, profile = prepare(cfg)
    marks = []
    c0, w0 = time.process_time(), time.perf_counter()

    def tick(done, total):
        marks.append((done, time.process_time() - c0, time.perf_counter() - w0))

    out = _core.simulate(text, *profile.core_args(), progress=tick)
    marks.append((out["n_steps"], time.process_time() - c0, time.perf_counter() - w0))
    # Stepping: the marks after the first step; a line through them (steps → time).
    pts = [m for m in marks if m[0] > 0]
    if len(pts) < 3:
        raise SystemExit(f"{n_spans} spans: too few progress marks ({len(pts)}); raise --steps")
    fit = {}
    for col, name in ((1, "cpu"), (2, "wall")):
        slope, icpt = np.polyfit([p[0] for p in pts], [p[col] for p in pts], 1)
        fit[name] = (float(icpt), float(slope))
    return {
        "spans": n_spans,
        "length": cfg.structure.length,
        "setup": fit["cpu"][0],
        "step": fit["cpu"][1],
        "setup_wall": fit["wall"][0],
        "step_wall": fit["wall"][1],
        "disp": np.asarray(out["disp"]).ravel().tolist(),
        "acc": np.asarray(out["acc"]).ravel().tolist(),
        "metrics": {k: float(v) for k, v in out["metrics"].items()},
    }


def run_in(python_dir: Path, n_spans: int, steps: int, cars: int) -> dict:
    env = {**os.environ, "PYTHONPATH": str(python_dir)}
    res = subprocess.run([sys.executable, __file__, "--one", str(n_spans), "--steps", str(steps), "--cars", str(cars)],
                         env=env, capture_output=True, text=True, check=True)
    return json.loads(res.stdout.strip().splitlines()[-1])


def exponent(rows, key):
    """Least-squares slope of log(value) against log(length)."""
    pts = [(math.log(r["length"]), math.log(r[key])) for r in rows if r and r[key] > 0]
    if len(pts) < 2:
        return float("nan")
    mx = sum(p[0] for p in pts) / len(pts)
    my = sum(p[1] for p in pts) / len(pts)
    return sum((x - mx) * (y - my) for x, y in pts) / sum((x - mx) ** 2 for x, _ in pts)


def rel_diff(a: dict, b: dict) -> float:
    """Largest difference of the two runs' histories and metrics, relative to each quantity's
    largest magnitude."""
    worst = 0.0
    for key in ("disp", "acc"):
        x, y = a[key], b[key]
        scale = max((abs(v) for v in x), default=0.0)
        if scale > 0:
            worst = max(worst, max(abs(u - v) for u, v in zip(x, y)) / scale)
    for k, v in a["metrics"].items():
        w = b["metrics"].get(k)
        if w is not None and math.isfinite(v) and v != 0:
            worst = max(worst, abs(v - w) / abs(v))
    return worst


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--spans", type=int, nargs="+", default=[5, 10, 20, 40])
    ap.add_argument("--steps", type=int, default=2000)
    ap.add_argument("--cars", type=int, default=1, help="a CRH3 train of this many cars (1: the preset's car)")
    ap.add_argument("--baseline", type=Path, help="python/ folder of an older build to compare with")
    ap.add_argument("--old-max-spans", type=int, default=40, help="measure the old build up to this many spans")
    ap.add_argument("--json", type=Path, help="write the rows here")
    ap.add_argument("--one", type=int, help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.one is not None:
        print(json.dumps(measure(a.one, a.steps, a.cars)))
        return
    new_rows, old_rows = [], []
    for n in a.spans:
        new = run_in(NEW_PYTHON, n, a.steps, a.cars)
        old = run_in(a.baseline, n, a.steps, a.cars) if a.baseline and n <= a.old_max_spans else None
        new_rows.append(new)
        old_rows.append(old)
        line = f"{n:3d} spans  set-up {new['setup']:7.2f} s  step {1e3 * new['step']:7.3f} ms"
        if old:
            line += (f"   old: set-up {old['setup']:7.2f} s  step {1e3 * old['step']:7.3f} ms"
                     f"   ratio old/new: set-up {old['setup'] / new['setup']:6.1f}  step {old['step'] / new['step']:5.2f}"
                     f"   results rel. diff {rel_diff(old, new):.1e}")
        print(line, flush=True)
    print(f"exponents in length: set-up {exponent(new_rows, 'setup'):.2f}, step {exponent(new_rows, 'step'):.2f}")
    if any(old_rows):
        olds = [r for r in old_rows if r]
        print(f"old build ({', '.join(str(r['spans']) for r in olds)} spans): set-up {exponent(olds, 'setup'):.2f}, "
              f"step {exponent(olds, 'step'):.2f}")
    if a.json:
        strip = lambda r: r and {k: v for k, v in r.items() if k not in ("disp", "acc")}
        a.json.write_text(json.dumps({"new": [strip(r) for r in new_rows], "old": [strip(r) for r in old_rows]}, indent=1))


if __name__ == "__main__":
    main()
