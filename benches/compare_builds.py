"""Two builds of vtb timed against each other in one run: a refactoring's performance check.

    python benches/compare_builds.py --old OLD_PYTHONPATH --new NEW_PYTHONPATH [--rounds 5]

Each round runs every case once in a fresh process of each build, old and new alternated (the
order swapped every round, so a drift of the machine's load falls on both); a case's time is
the best of three runs in its process after a warm-up run (the model's assembly and the
irregularity's sampling included: a whole ``vtb.simulate``), in CPU time of the process (all
its threads): on a shared machine the wall time of a run varies with the other load, its CPU
time much less. Prints, per case, the median time of each build over the rounds and the ratio
new/old. The fast case needs the 160 m
reduction in the cache (both builds read the same file).
"""

import argparse
import json
import os
import statistics
import subprocess
import sys

#: The cases: a name and the Python that makes its configuration ``cfg`` (or list ``cfgs``
#: for a batch) from ``vtb``.
CASES = {
    "article_hybrid": "cfg = vtb.paper_config()",
    "converged_fem": "cfg = vtb.paper_config(model='converged')",
    "fast_synthesis": "cfg = vtb.paper_config(model='fast')",
    "tid_batch_8": ("base = vtb.paper_config(); cfgs = []\n"
                    "for k in range(8):\n"
                    "    c = base.copy(); c.tids = vtb.tids_around(c, inertance=5.0 + k); cfgs.append(c)"),
}

TIMER = """
import json, time, warnings
import vtb
warnings.simplefilter("ignore")
{make}
run = (lambda: vtb.simulate_batch(cfgs, progress=False)) if "cfgs" in dir() else (lambda: vtb.simulate(cfg, progress=False))
run()
best = float("inf")
for _ in range(3):
    t = time.process_time(); run(); best = min(best, time.process_time() - t)
print(json.dumps(best))
"""


def timed(path: str, case: str) -> float:
    env = {**os.environ, "PYTHONPATH": path}
    out = subprocess.run([sys.executable, "-c", TIMER.format(make=CASES[case])], env=env, capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--old", required=True, help="PYTHONPATH of the old build (its python/ folder with _core built)")
    ap.add_argument("--new", required=True, help="PYTHONPATH of the new build")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--cases", nargs="*", default=list(CASES), choices=list(CASES))
    a = ap.parse_args()
    times = {c: {"old": [], "new": []} for c in a.cases}
    for r in range(a.rounds):
        order = ("old", "new") if r % 2 == 0 else ("new", "old")
        for c in a.cases:
            for build in order:
                times[c][build].append(timed(getattr(a, build), c))
            print(f"round {r + 1}: {c}: old {times[c]['old'][-1]:.3f} s, new {times[c]['new'][-1]:.3f} s", flush=True)
    print("\n| case | old (s, median) | new (s, median) | new/old |\n|---|---|---|---|")
    for c in a.cases:
        o, n = statistics.median(times[c]["old"]), statistics.median(times[c]["new"])
        print(f"| {c} | {o:.3f} | {n:.3f} | {n / o:.3f} |")


if __name__ == "__main__":
    main()
