"""The long fuzz run: N generated bad configurations, TOML texts and attribute assignments
(tests/fuzz_cases.py) thrown at the API in worker processes, so that an abort or a hang is
caught and counted instead of ending the run.

    python benches/fuzz_config.py --cases 10000 [--workers 2] [--timeout 120] [--seed 0]

Prints the counts of every outcome: ok (a documented exception naming its field, or a finite
run), aborts (the worker process died), panics, hangs (no answer within --timeout s),
non-finite successes, errors without a field name and undocumented exceptions, with the
first cases of each finding. Exit status 1 when there is any finding.
"""

from __future__ import annotations

import argparse
import collections
import json
import os
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
WORKER = r"""
import json, random, sys, warnings
sys.path.insert(0, sys.argv[1])
warnings.simplefilter("ignore")
import fuzz_cases
seed, start, stop = map(int, sys.argv[2:5])
for i in range(start, stop):
    label, thunk = fuzz_cases.make_case(random.Random(seed * 1_000_003 + i))
    print(json.dumps({"i": i, "label": label, "started": True}), flush=True)
    v, detail = fuzz_cases.verdict(thunk)
    print(json.dumps({"i": i, "label": label, "verdict": v, "detail": detail[:300]}), flush=True)
"""


def run_range(seed: int, start: int, stop: int, timeout: float, out: collections.Counter, findings: dict) -> None:
    """Cases [start, stop) in one worker; a dead or silent worker is restarted after the case
    it was on."""
    i = start
    while i < stop:
        proc = subprocess.Popen(
            [sys.executable, "-c", WORKER, str(HERE.parent / "tests"), str(seed), str(i), str(stop)],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        )
        current = None
        os.set_blocking(proc.stdout.fileno(), True)
        import selectors

        sel = selectors.DefaultSelector()
        sel.register(proc.stdout, selectors.EVENT_READ)
        last = time.monotonic()
        while True:
            ready = sel.select(timeout=1.0)
            if ready:
                line = proc.stdout.readline()
                if not line:
                    break
                rec = json.loads(line)
                last = time.monotonic()
                if rec.get("started"):
                    current = rec
                    continue
                out[rec["verdict"]] += 1
                if rec["verdict"] != "ok":
                    findings.setdefault(rec["verdict"], []).append(f"#{rec['i']} {rec['label']}: {rec['detail']}")
                current = None
                i = rec["i"] + 1
            elif time.monotonic() - last > timeout:
                proc.kill()
                out["hang"] += 1
                findings.setdefault("hang", []).append(f"#{current['i']} {current['label']}" if current else "?")
                i = (current["i"] if current else i) + 1
                current = None
                break
        proc.wait()
        if current is not None:  # the worker died inside a case
            out["abort"] += 1
            err = proc.stderr.read()[-300:]
            findings.setdefault("abort", []).append(f"#{current['i']} {current['label']}: exit {proc.returncode} {err}")
            i = current["i"] + 1


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=10_000)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--timeout", type=float, default=120.0, help="seconds without an answer that make a case a hang")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    from concurrent.futures import ThreadPoolExecutor

    t0 = time.perf_counter()
    counts: collections.Counter = collections.Counter()
    findings: dict = {}
    chunk = -(-args.cases // args.workers)
    with ThreadPoolExecutor(args.workers) as pool:
        parts = [(collections.Counter(), {}) for _ in range(args.workers)]
        futs = [pool.submit(run_range, args.seed, w * chunk, min(args.cases, (w + 1) * chunk), args.timeout, *parts[w]) for w in range(args.workers)]
        for f in futs:
            f.result()
    for c, fnd in parts:
        counts.update(c)
        for k, v in fnd.items():
            findings.setdefault(k, []).extend(v)
    tried = sum(counts.values())
    print(f"# fuzz: {tried} cases (seed {args.seed}) in {time.perf_counter() - t0:.0f} s")
    for key in ("ok", "abort", "panic", "hang", "nonfinite", "unnamed", "undocumented"):
        print(f"{key:<13} {counts.get(key, 0)}")
    for key, cases in findings.items():
        print(f"\n## {key} ({len(cases)})")
        for c in cases[:10]:
            print("  " + c)
    return 1 if findings else 0


if __name__ == "__main__":
    sys.exit(main())
