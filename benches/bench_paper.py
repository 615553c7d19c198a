"""Python-side timing of vtb.simulate(vtb.paper_config()) and of the converged preset
vtb.paper_config(model="converged") (one core each), and their ratio in the same run.

    python benches/bench_paper.py [repeats]

Prints the best and median wall time of the whole call (profile generation, assembly and the
Newmark steps: ≈ 34 500 for the article's model, ≈ 69 000 for the converged one at half the
time step) and of the core run alone.
"""

import statistics
import sys
import time

import vtb
from vtb import _core

repeats = int(sys.argv[1]) if len(sys.argv) > 1 else 5


def timings(cfg):
    x0, dx, values, _ = vtb.irregularity_profile(cfg)
    js = cfg.to_core_json()
    total, core = [], []
    for _ in range(repeats):
        t0 = time.perf_counter()
        vtb.simulate(cfg)
        total.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        _core.simulate(js, x0, dx, values)
        core.append(time.perf_counter() - t0)
    return total, core


best = {}
for label, cfg in [("paper_config()", vtb.paper_config()), ('paper_config(model="converged")', vtb.paper_config(model="converged"))]:
    total, core = timings(cfg)
    best[label] = min(core)
    print(f"vtb.simulate({label}): best {min(total):.3f} s, median {statistics.median(total):.3f} s over {repeats}")
    print(f"  core run (assembly + time stepping): best {min(core):.3f} s, median {statistics.median(core):.3f} s")
a, b = best.values()
print(f"converged / article hybrid (core, best of {repeats}): {b / a:.1f}x")

import os  # noqa: E402

print("machine load: %.2f %.2f %.2f (1, 5, 15 min averages)" % os.getloadavg())
