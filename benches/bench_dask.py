"""Benchmark: a robust study (a TID sweep over irregularity samples and speeds) on the fast
converged model, on a local Dask cluster of one worker and of two (one thread each), and in
this process on every core; the speed-up from one worker to two, measured in one run.

    python benches/bench_dask.py [--samples 8] [--t-end 0.6] [--repeat 3]

Both clusters start together (``vtb.run.scaleout.local_cluster``: Dask set up for studies) and
each worker loads the cached reduction before the clock starts; then the study runs ``--repeat`` times on each, alternating between
them so that the machine's load (it is shared) falls on both alike, and each keeps its best
time. Prints every time, the speed-up of the best times and whether the results are bit for
bit those of the in-process run, and the in-process run on one core and on every core. The machine's own scaling, with no vtb in the loop, is ``benches/machine_scaling.py``'s.
"""

import argparse
import contextlib
import time

import numpy as np

import vtb
from vtb.run.scaleout import local_cluster
from vtb.article.tid_problem import COLUMNS


def study(cfg, samples, executor=None, threads=None):
    return vtb.sweep(cfg, [3.0, 5.0], [1e8, 2e8], [1e3], samples=samples, speeds=[70.0, 80.0], executor=executor, threads=threads,
                     progress=False)


def same(a, b) -> bool:
    return all(
        (list(x.columns[k]) == list(y.columns[k])) if k == "error" else np.array_equal(x.columns[k], y.columns[k], equal_nan=True)
        for (_, _, x), (_, _, y) in zip(a.sweeps, b.sweeps) for k in COLUMNS
    )


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--samples", type=int, default=8)
    ap.add_argument("--t-end", type=float, default=0.6)
    ap.add_argument("--repeat", type=int, default=3, help="timed studies per cluster, alternated; the best counts (default 3)")
    args = ap.parse_args()
    cfg = vtb.paper_config(model="fast", calibrated=True)
    cfg.solver.t_end = args.t_end
    cfg.tids = vtb.tids_around(cfg)
    warm = cfg.copy()
    warm.solver.t_end = 0.01
    n_runs = 2 * args.samples * (4 + 1)  # 2 speeds × samples × (4 designs + the uncontrolled run)
    vtb.simulate(warm)  # this process's reduction, and the disk cache the workers load
    t0 = time.perf_counter()
    local = study(cfg, args.samples)
    t_local = time.perf_counter() - t0
    t0 = time.perf_counter()
    study(cfg, args.samples, threads=1)
    t_one = time.perf_counter() - t0
    times = {1: [], 2: []}
    with contextlib.ExitStack() as stack:
        executors = {}
        for n in times:  # every worker holds the reduction before the clock starts
            executors[n] = stack.enter_context(local_cluster(n, preload=warm))
        for _ in range(args.repeat):
            for n, ex in executors.items():
                t0 = time.perf_counter()
                res = study(cfg, args.samples, ex)
                times[n].append(time.perf_counter() - t0)
                print(f"{n} worker(s): {times[n][-1]:.1f} s for {n_runs} runs; bit for bit the in-process result: {same(local, res)}", flush=True)
    print(f"in process: {t_one:.1f} s on one core, {t_local:.1f} s on every core ({t_one / t_local:.2f}×)")
    print(f"speed-up from 1 to 2 workers, best of {args.repeat} each: {min(times[1]) / min(times[2]):.2f} (target ≥ 1.8); "
          f"time by time: {', '.join(f'{a / b:.2f}' for a, b in zip(times[1], times[2]))}")


if __name__ == "__main__":
    main()
    import os

    print("machine load: %.2f %.2f %.2f (1, 5, 15 min averages)" % os.getloadavg())
