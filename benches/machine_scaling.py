"""Benchmark: how this machine itself scales from one process to two, with no vtb in the
loop — the ceiling against which a study's speed-up on 2 workers is read.

    python benches/machine_scaling.py [--seconds 3]

Three loads, each run in one process and then in two at once (separate processes, so no
GIL): arithmetic on arrays that stay in the first-level cache, a stream through arrays that
fit the last-level cache, and a stream through arrays far larger than any cache (main
memory). For each it prints the throughput of one process, of the two together, and the
ratio: 2.0 means the two cores do not slow each other down for that kind of work.
"""

import argparse
import multiprocessing as mp
import time

import numpy as np

#: (name, elements per array, repetitions of the inner kernel per timing check)
LOADS = (("arithmetic, in L1", 2_000, 2_000), ("stream, in L3", 1_000_000, 20), ("stream, main memory", 40_000_000, 1))


def _kernel(n: int, reps: int, seconds: float, start, out) -> None:
    a, b, c = np.ones(n), np.full(n, 2.0), np.zeros(n)
    np.multiply(b, 1.0001, out=c)  # the pages touched before the clock
    start.wait()
    t0, done = time.perf_counter(), 0
    while time.perf_counter() - t0 < seconds:
        for _ in range(reps):
            np.multiply(b, 1.0001, out=c)
            np.add(c, a, out=c)
        done += reps
    # bytes moved per repetition: c = b·s reads one array and writes one, c += a reads two and writes one
    out.put(done * 5 * 8 * n / (time.perf_counter() - t0))


def throughput(n: int, reps: int, seconds: float, processes: int) -> float:
    """Bytes per second moved by ``processes`` processes together."""
    ctx = mp.get_context("spawn")
    start, out = ctx.Barrier(processes), ctx.Queue()
    ps = [ctx.Process(target=_kernel, args=(n, reps, seconds, start, out)) for _ in range(processes)]
    for p in ps:
        p.start()
    total = sum(out.get() for _ in ps)
    for p in ps:
        p.join()
    return total


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seconds", type=float, default=3.0, help="timed seconds per measurement (default 3)")
    args = ap.parse_args()
    print(f"{'load':22s} {'1 process':>12s} {'2 processes':>12s} {'ratio':>6s}")
    for name, n, reps in LOADS:
        one = throughput(n, reps, args.seconds, 1)
        two = throughput(n, reps, args.seconds, 2)
        print(f"{name:22s} {one / 1e9:9.1f} GB/s {two / 1e9:9.1f} GB/s {two / one:6.2f}")
    import os

    print("machine load: %.2f %.2f %.2f (1, 5, 15 min averages)" % os.getloadavg())


if __name__ == "__main__":
    main()
