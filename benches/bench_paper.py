"""Python-side timing of vtb.simulate(vtb.paper_config()) (one core).

    python benches/bench_paper.py [repeats]

Prints the best and median wall time of the whole call (profile generation, assembly and
~34 500 Newmark steps) and of the core run alone.
"""

import statistics
import sys
import time

import vtb
from vtb import _core

repeats = int(sys.argv[1]) if len(sys.argv) > 1 else 5
cfg = vtb.paper_config()
x0, dx, values = vtb.irregularity_profile(cfg)
js = cfg.to_core_json()
total, core = [], []
for _ in range(repeats):
    t0 = time.perf_counter()
    vtb.simulate(cfg)
    total.append(time.perf_counter() - t0)
    t0 = time.perf_counter()
    _core.simulate(js, x0, dx, values)
    core.append(time.perf_counter() - t0)
print(f"vtb.simulate(paper_config()): best {min(total):.3f} s, median {statistics.median(total):.3f} s over {repeats}")
print(f"core run (assembly + time stepping): best {min(core):.3f} s, median {statistics.median(core):.3f} s")
