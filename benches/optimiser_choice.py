"""Evidence for the reproduction's default optimiser: the article's TID problem (NSGA-II,
population 100, at most 100 generations, the hypervolume stop ``vtb.article.reproduce.STOP_HV``) run
from a cold (random) start and from a warm start (the reproduction's sweep) over several seeds,
with the hypervolume of the feasible front against the evaluations.

    python benches/optimiser_choice.py [--seeds 5] [--out docs/optimiser-choice]

Each finished run is recorded in ``OUT/runs.json`` at once, and every generation is
checkpointed under ``--work`` (default benches/results/optimiser_choice), so a stopped bench
resumes: finished runs are not repeated, an unfinished one continues after its last generation.
Both starts run as ``vtb reproduce --optimiser cold|warm`` does (``vtb.article.reproduce.optimisations``'
options: the same stop, the warm start from the reproduction's sweep journal, whose points come
in (b_t, k_t, c_t) order as the sweep's own). ``--report-only`` rewrites the report from
``runs.json``.

The rule, fixed before the runs: the default is the start with the higher median final
hypervolume over the seeds; when the two medians are within 0.5 % of each other, the one with
the fewer median evaluations. The verdict is given before the last runs only when no result
of theirs could change it (``verdict``). Evaluations are the cost: one is one article-model run (the warm
start's first population is the sweep's cases, which the reproduction runs anyway and which
cost no evaluation here).
"""

import argparse
import json
import math
import os
import statistics
import sys
import time
from pathlib import Path

import vtb
from vtb.machine import describe
from vtb.article.reproduce import STOP_HV

REPRO = Path(__file__).resolve().parents[1] / "docs" / "reproduction"
STARTS = ("cold", "warm")
POP, N_GEN = 100, 100
#: Medians of the final hypervolume closer than this (relative) count as a tie, broken by cost.
TIE = 5e-3


def run_one(cfg, start: str, seed: int, work: Path) -> dict:
    ckpt = work / f"{start}_seed{seed}.npz"
    resumed = ckpt.exists()
    opts = dict(warm_start=REPRO / "sweep.csv") if start == "warm" else {}
    t0 = time.perf_counter()
    res = vtb.optimize(cfg, pop_size=POP, n_gen=N_GEN, seed=seed, stop_hv=STOP_HV, checkpoint=ckpt, **opts)
    seconds = time.perf_counter() - t0
    h = res.moga.history
    return dict(start=start, seed=seed, generations=len(h), evaluations=res.moga.n_evals, hypervolume=h[-1].hypervolume,
                stop=res.moga.message, seconds=None if resumed else round(seconds, 1), load=describe(),
                history=[[g.n_evals, g.hypervolume] for g in h])


def _decisive(a: float, b: float) -> bool:
    """Median hypervolume a beats b by more than the tie margin."""
    return a - b > TIE * max(a, b)


def verdict(runs: list, n_seeds: int):
    """The default by the rule of the module docstring over seeds 0 … n_seeds − 1 (further
    ones are not counted), or ``None`` while the seeds still missing could change it.

    With seeds missing, a start's median lies between its median with the missing runs at
    −∞ and at +∞; the verdict is given early only when one start wins the hypervolume
    comparison beyond the tie margin at the extremes least favourable to it (a tie, broken by
    the evaluations, waits for every seed)."""
    by = {s: [r for r in runs if r["start"] == s and r["seed"] < n_seeds] for s in STARTS}
    missing = {s: n_seeds - len(v) for s, v in by.items()}
    if any(missing.values()):
        def median(s, fill):
            return statistics.median([r["hypervolume"] for r in by[s]] + [fill] * missing[s])
        for s, o in (STARTS, STARTS[::-1]):
            if _decisive(median(s, -math.inf), median(o, math.inf)):
                return s
        return None
    hv = {s: statistics.median(r["hypervolume"] for r in v) for s, v in by.items()}
    ev = {s: statistics.median(r["evaluations"] for r in v) for s, v in by.items()}
    a, b = STARTS
    if abs(hv[a] - hv[b]) <= TIE * max(hv.values()):
        return min(STARTS, key=lambda s: ev[s])
    return max(STARTS, key=lambda s: hv[s])


def hv_at(history, evals: int):
    """The hypervolume reached within ``evals`` evaluations (a run that stopped before keeps
    its final front)."""
    return max(hv for n, hv in history if n <= evals)


#: Tolerances of the hypervolume stop compared in the report, over the rule's own window.
STOP_TOLS = (3e-4, 1e-3, 3e-3, 1e-2)


def stopped_at(history, tol: float, window: int):
    """The first (generation, evaluations, hypervolume) at which ``stop_hv=(tol, window)`` would
    have stopped a run of this history, or ``None`` within the recorded generations."""
    hv = [h for _, h in history]
    for g in range(window + 1, len(hv) + 1):
        if vtb.optim.hypervolume_settled(hv[:g], tol, window):
            return g, history[g - 1][0], hv[g - 1]
    return None


def stop_table(runs: list) -> list:
    """The report's section on the stop: where each tolerance would have stopped each run."""
    window = STOP_HV[1]
    L = ["## The stop", "",
         f"Where the hypervolume stop with each tolerance (over {window} generations, as the rule's) would have stopped each "
         "run: evaluations, and the hypervolume then as a share of the run's final one. —: not within the run's record (a run "
         "that reached the cap never met that tolerance; a run the rule stopped ends there, so a tighter one cannot be followed "
         "beyond it).", "",
         "| start | seed | " + " | ".join(f"{t:g}" + (" (the rule)" if t == STOP_HV[0] else "") for t in STOP_TOLS) + " |",
         "|---|---|" + "---|" * len(STOP_TOLS)]
    for r in runs:
        cells = []
        for t in STOP_TOLS:
            s = stopped_at(r["history"], t, window)
            cells.append("—" if s is None else f"{s[1]} ({100 * s[2] / r['hypervolume']:.1f} %)")
        L.append(f"| {r['start']} | {r['seed']} | " + " | ".join(cells) + " |")
    return L


def report(out: Path, runs: list, n_seeds: int) -> None:
    from vtb.analysis.plotting import plot_hypervolume

    runs = sorted(runs, key=lambda r: (r["start"], r["seed"]))
    hists = {f"{s} start": [[vtb.optim.Generation(gen=i + 1, n_evals=n, n_feasible=0, n_front=0, cv_min=0.0, hypervolume=hv) for i, (n, hv) in enumerate(r["history"])]
                            for r in runs if r["start"] == s] for s in STARTS}
    fig = plot_hypervolume({k: v for k, v in hists.items() if v})
    for suffix in ("png", "pdf"):
        fig.savefig(out / f"fig_hypervolume_seeds.{suffix}", dpi=150)
    v = verdict(runs, n_seeds)
    marks = (1000, 2000, 3000, 5000)
    L = ["# The reproduction's optimiser: cold or warm start, over seeds", "",
         "Generated by `python benches/optimiser_choice.py` (do not edit). The article's TID problem "
         f"(NSGA-II, population {POP}, at most {N_GEN} generations, stop when the hypervolume moves by less than "
         f"{STOP_HV[0]:g} (relative) over {STOP_HV[1]} generations) from a random start (cold) and from the reproduction's "
         "sweep (warm: its cases within the bounds are the first population and cost no evaluation, since the reproduction "
         "runs the sweep anyway). Hypervolume: of the feasible first front in (a_rm, a_sm), reference the uncontrolled "
         "(a_rm0, a_sm0), in (m/s²)².", "",
         f"Rule, fixed before the runs: the default is the start with the higher median final hypervolume over the seeds; "
         f"medians within {100 * TIE:g} % of each other are a tie, broken by the fewer median evaluations.", "",
         "| start | seed | generations | evaluations | final H | " + " | ".join(f"H at {m}" for m in marks) + " | time (s) | stop |",
         "|---|---|---|---|---|" + "---|" * len(marks) + "---|---|"]
    for r in runs:
        cells = [f"{hv_at(r['history'], m):.2f}" for m in marks]
        t = f"{r['seconds']:.0f}" if r["seconds"] is not None else "resumed"
        L.append(f"| {r['start']} | {r['seed']} | {r['generations']} | {r['evaluations']} | {r['hypervolume']:.2f} | " + " | ".join(cells) + f" | {t} | {r['stop']} |")
    L += ["", "H at N: the best front within N evaluations (a run that stopped before N keeps its final front). "
          "Time: the run's wall time on the machine named in runs.json (`load`: its load at the run's end; the machine is shared).", ""]
    for s in STARTS:
        rs = [r for r in runs if r["start"] == s]
        if rs:
            hv = [r["hypervolume"] for r in rs]
            ev = [r["evaluations"] for r in rs]
            L.append(f"* {s}: {len(rs)} seed(s); final H median {statistics.median(hv):.2f}, worst {min(hv):.2f}, best {max(hv):.2f}; "
                     f"evaluations median {statistics.median(ev):.0f} ({min(ev)}–{max(ev)}).")
    L.append("")
    done = sum(r["seed"] < n_seeds for r in runs)
    if v is None:
        L.append(f"**No verdict yet** ({done} of {2 * n_seeds} runs): the seeds still missing could change it; rerun the command to continue.")
    else:
        if done < 2 * n_seeds:
            L.append(f"Decided with {done} of {2 * n_seeds} runs: whatever the missing runs reach, the other start's median "
                     "hypervolume cannot come within the tie margin of this one's.")
            L.append("")
        L.append(f"**Verdict: the {v} start** is the reproduction's default (`vtb reproduce --optimiser {v}`; "
                 "tests/test_optimize.py holds the default equal to this verdict).")
    L += ["", *stop_table(runs), "", "![hypervolume against evaluations, every seed](fig_hypervolume_seeds.png)"]
    (out / "report.md").write_text("\n".join(L) + "\n")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--seeds", type=int, default=5, help="seeds per start (default 5)")
    p.add_argument("--out", type=Path, default=Path(__file__).resolve().parents[1] / "docs" / "optimiser-choice")
    p.add_argument("--work", type=Path, default=Path(__file__).resolve().parent / "results" / "optimiser_choice", help="per-generation checkpoints")
    p.add_argument("--report-only", action="store_true")
    args = p.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    args.work.mkdir(parents=True, exist_ok=True)
    record = args.out / "runs.json"
    runs = json.loads(record.read_text()) if record.exists() else []
    if not args.report_only:
        cfg = vtb.paper_config(calibrated=True)
        cfg.tids = vtb.tids_around(cfg)
        for seed in range(args.seeds):
            for start in STARTS:
                if any(r["start"] == start and r["seed"] == seed for r in runs):
                    continue
                print(f"{start} start, seed {seed}", file=sys.stderr)
                runs.append(run_one(cfg, start, seed, args.work))
                tmp = record.with_suffix(".tmp")
                tmp.write_text(json.dumps(runs, indent=1))
                os.replace(tmp, record)
                report(args.out, runs, args.seeds)
    report(args.out, runs, args.seeds)
    print((args.out / "report.md").read_text())


if __name__ == "__main__":
    main()
