"""The long fuzz run: N generated bad inputs per public surface (tests/fuzz_surfaces.py: the
older configuration surface of tests/fuzz_cases.py, trains, zones, spans, profile parts,
damper groups, band levels, contact, edges, studies and optimisation, and the bridge
engineer's surfaces of tests/fuzz_bridge.py: load trains, damping, scans, interaction, static,
checks and bridge_check) thrown at the API in worker processes, so that an abort or a hang is caught and counted instead of ending the run.

    python benches/fuzz_config.py --cases 10000 [--surface all|config|trains|...] [--workers 2]
                                  [--timeout 10] [--seed 0]

Cases go round the surfaces chosen (``all``: every one, in turn). Prints a table per surface —
cases, ok (a finite result), refused (a documented vtb error naming a usable field) and the
findings: aborts (the worker process died), panics, hangs (no answer within --timeout s),
non-vtb exceptions, errors naming no usable field, non-finite successes, mutated inputs and
slow refusals (a bad input refused after more than a second: its check came after work) —
then the first cases of each finding. Exit status 1 when there is any finding.
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
#: Seconds a fresh worker may take to import vtb before its first case (not a case's hang).
STARTUP = 120.0
WORKER = r"""
import json, random, sys, warnings
sys.path.insert(0, sys.argv[1])
warnings.simplefilter("ignore")
import fuzz_surfaces
seed, start, stop = map(int, sys.argv[2:5])
surfaces = sys.argv[5].split(",")
for i in range(start, stop):
    surface = surfaces[i % len(surfaces)]
    label, thunk, inputs = fuzz_surfaces.make_case(random.Random(seed * 1_000_003 + i), surface)
    print(json.dumps({"i": i, "surface": surface, "label": label[:200], "started": True}), flush=True)
    v, detail = fuzz_surfaces.verdict(label, thunk, inputs)
    print(json.dumps({"i": i, "surface": surface, "label": label[:200], "verdict": v, "detail": detail[:300]}), flush=True)
"""
sys.path.insert(0, str(HERE.parent / "tests"))
from fuzz_surfaces import FINDINGS, SURFACES  # noqa: E402 - the one list of surfaces and verdicts

#: ok, refused, then the findings: the two the runner sees (a dead worker, a silent one) and the verdict's.
VERDICTS = ("ok", "refused", "abort", "hang") + FINDINGS


def run_range(seed: int, start: int, stop: int, timeout: float, out: collections.Counter, findings: dict, surfaces: str) -> None:
    """Cases [start, stop) in one worker; a dead or silent worker is restarted after the case
    it was on."""
    i = start
    while i < stop:
        proc = subprocess.Popen(
            [sys.executable, "-c", WORKER, str(HERE.parent / "tests"), str(seed), str(i), str(stop), surfaces],
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
                    last = time.monotonic()
                    continue
                out[(rec["surface"], rec["verdict"])] += 1
                if rec["verdict"] not in ("ok", "refused"):
                    findings.setdefault(rec["verdict"], []).append(f"#{rec['i']} [{rec['surface']}] {rec['label']}: {rec['detail']}")
                current = None
                i = rec["i"] + 1
            elif time.monotonic() - last > (timeout if current is not None else STARTUP):  # a worker's imports are no case
                proc.kill()
                out[(current["surface"] if current else "?", "hang")] += 1
                findings.setdefault("hang", []).append(f"#{current['i']} [{current['surface']}] {current['label']}" if current else "?")
                i = (current["i"] if current else i) + 1
                current = None
                break
        proc.wait()
        if current is not None:  # the worker died inside a case
            out[(current["surface"], "abort")] += 1
            err = proc.stderr.read()[-300:]
            findings.setdefault("abort", []).append(f"#{current['i']} [{current['surface']}] {current['label']}: exit {proc.returncode} {err}")
            i = current["i"] + 1


def table(counts: collections.Counter, surfaces) -> str:
    """The Markdown table of the counts (surface, verdict) per surface, with a total row."""
    head = "| surface | cases | " + " | ".join(VERDICTS) + " |"
    lines = [head, "|" + "---|" * (len(VERDICTS) + 2)]
    total = collections.Counter()
    for s in surfaces:
        row = [counts.get((s, v), 0) for v in VERDICTS]
        total.update(dict(zip(VERDICTS, row)))
        lines.append(f"| {s} | {sum(row)} | " + " | ".join(map(str, row)) + " |")
    lines.append(f"| **all** | {sum(total.values())} | " + " | ".join(str(total[v]) for v in VERDICTS) + " |")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=10_000)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--timeout", type=float, default=10.0, help="seconds without an answer that make a case a hang")
    ap.add_argument("--surface", default="all", help="all, or a comma-separated list of: " + ", ".join(SURFACES))
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    surfaces = SURFACES if args.surface == "all" else tuple(args.surface.split(","))
    unknown = sorted(set(surfaces) - set(SURFACES))
    if unknown:
        ap.error(f"unknown surface(s) {unknown}; known: {', '.join(SURFACES)}")
    from concurrent.futures import ThreadPoolExecutor

    t0 = time.perf_counter()
    counts: collections.Counter = collections.Counter()
    findings: dict = {}
    chunk = -(-args.cases // args.workers)
    with ThreadPoolExecutor(args.workers) as pool:
        parts = [(collections.Counter(), {}) for _ in range(args.workers)]
        futs = [pool.submit(run_range, args.seed, w * chunk, min(args.cases, (w + 1) * chunk), args.timeout, *parts[w], ",".join(surfaces))
                for w in range(args.workers)]
        for f in futs:
            f.result()
    for c, fnd in parts:
        counts.update(c)
        for k, v in fnd.items():
            findings.setdefault(k, []).extend(v)
    tried = sum(counts.values())
    print(f"# fuzz: {tried} cases (seed {args.seed}, surfaces {args.surface}, hang = {args.timeout:g} s) in {time.perf_counter() - t0:.0f} s\n")
    print(table(counts, surfaces))
    for key, cases in findings.items():
        print(f"\n## {key} ({len(cases)})")
        for c in cases[:10]:
            print("  " + c)
    return 1 if findings else 0


if __name__ == "__main__":
    sys.exit(main())
