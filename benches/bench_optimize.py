"""Benchmark: one TID optimisation of the article's problem (NSGA-II, population 100 ×
100 generations = 10 000 evaluations) on the calibrated article case, all cores.

    python benches/bench_optimize.py [--pop 100] [--gen 100]

With fewer generations the time per generation is printed with the extrapolation to 100.
"""

import argparse
import time

import vtb

p = argparse.ArgumentParser()
p.add_argument("--pop", type=int, default=100)
p.add_argument("--gen", type=int, default=100)
args = p.parse_args()
cfg = vtb.paper_config(calibrated=True)
cfg.tids = vtb.tids_around(cfg)
t0 = time.perf_counter()
res = vtb.optimize(cfg, pop_size=args.pop, n_gen=args.gen, seed=0)
s = time.perf_counter() - t0
print(f"optimisation: population {args.pop} × {args.gen} generations ({res.moga.n_evals} evaluations) in {s:.1f} s = {s / 60:.1f} min")
print(f"per generation {s / args.gen:.1f} s; 100 generations ≈ {s / args.gen * 100 / 60:.1f} min")
for r in res.table():
    print(r)

import os  # noqa: E402

print("machine load: %.2f %.2f %.2f (1, 5, 15 min averages)" % os.getloadavg())
