"""Benchmark: the article's full TID sweep (1 840 cases + baseline) on this machine, all cores,
on the calibrated article case (``paper_config(calibrated=True)``, the one `vtb reproduce` uses;
``--uncalibrated`` for the raw TB/T 3352 level; ``--model fast`` on the fast converged model,
the synthesis of the converged finite elements, docs/synthesis.md).

    python benches/bench_sweep.py [--out benches/results/sweep_article.csv] [--report benches/results/sweep.md]
    python benches/bench_sweep.py --model fast --fresh --out benches/results/sweep_fast.csv --report benches/results/sweep_fast.md

Resumable (the CSV journal); the wall time printed is that of this invocation, so a fresh
figure needs a fresh journal (--fresh).
"""

import argparse
import time
from pathlib import Path

import vtb
from vtb.article.tid_sweep import sweep_report

p = argparse.ArgumentParser()
p.add_argument("--out", default="benches/results/sweep_article.csv")
p.add_argument("--report", default="benches/results/sweep.md")
p.add_argument("--fresh", action="store_true", help="delete the journal first")
p.add_argument("--uncalibrated", action="store_true", help="the raw irregularity level")
p.add_argument("--model", default="article", choices=["article", "fast"], help="the discretisation (vtb.paper_config's model)")
args = p.parse_args()
if args.fresh:
    Path(args.out).unlink(missing_ok=True)
cfg = vtb.paper_config(calibrated=not args.uncalibrated, model=args.model)
cfg.tids = vtb.tids_around(cfg)
vtb.simulate(cfg, progress=False)  # the reduction loaded (or built) before the clock starts
t0 = time.perf_counter()
res = vtb.sweep(cfg, out=args.out)
seconds = time.perf_counter() - t0
print(f"sweep: {len(res)} runs in {seconds:.1f} s ({seconds / 60:.1f} min)")
print(sweep_report(res, args.report, seconds=seconds))

import os  # noqa: E402

print("machine load: %.2f %.2f %.2f (1, 5, 15 min averages)" % os.getloadavg())
