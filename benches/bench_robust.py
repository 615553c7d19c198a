"""Benchmark: what one robust design costs on the converged preset, and what batching the
cases buys. One design over 8 samples at 80 m/s (uncontrolled + controlled = 16 converged
runs), evaluated (a) one run at a time and (b) as one batch (vtb.evaluate_design: the samples
share one model and run in lockstep, on every core). Both in the same invocation, so the ratio
is robust to a noisy shared machine.

    python benches/bench_robust.py [--samples 8] [--t-end SECONDS]

``--t-end`` shortens every run (default: the whole passage, ≈ 1.7 s of simulated time); the
ratio barely depends on it. The whole robust study is the second benchmark:
``vtb study robust --out DIR`` states its run time per stage in its report.
"""

import argparse
import time

import vtb
from vtb.article import robust

p = argparse.ArgumentParser()
p.add_argument("--samples", type=int, default=8)
p.add_argument("--t-end", type=float, default=None)
args = p.parse_args()

cfg = vtb.paper_config(calibrated=True, model="converged")
cfg.irregularity.scale /= 2  # the study's level without contact loss
cfg.solver.t_end = args.t_end
cfg.tids = vtb.tids_around(cfg)
design = dict(b_t=5.0, k_t=1.9e8, c_t=1e3)

t0 = time.perf_counter()
batched = vtb.evaluate_design(cfg, design, samples=args.samples, first_seed=robust.DESIGN_SEED0)
t_batch = time.perf_counter() - t0

t0 = time.perf_counter()
single = []
for _, _, c in robust.cases(cfg, args.samples, None, robust.DESIGN_SEED0):
    ctl = c.copy()
    ctl.tids = batched.design
    single.append((vtb.simulate(c).metrics(), vtb.simulate(ctl).metrics()))
t_single = time.perf_counter() - t0

assert all(r["rail_acc_max"] == m1["rail_acc_max"] and r["rail_acc_max_0"] == m0["rail_acc_max"] for r, (m0, m1) in zip(batched.rows, single))
n = 2 * args.samples
print(f"{n} converged runs: one at a time {t_single:.1f} s ({t_single / n:.2f} s/run); batched {t_batch:.1f} s ({t_batch / n:.2f} s/run); "
      f"speed-up {t_single / t_batch:.2f}x")

import os  # noqa: E402

print("machine load: %.2f %.2f %.2f (1, 5, 15 min averages)" % os.getloadavg())
