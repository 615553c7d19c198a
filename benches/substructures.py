"""The substructured engine (docs/substructures.md): its cost against the length and its
results against the finite elements it reduces. Writes docs/substructures-verification.md.

    python benches/substructures.py              # scaling (5–100 spans), verification, train, convergence, maxima
    python benches/substructures.py --passage    # also the whole 100-span passage of a 16-car train

Scaling: simply supported 32 m spans between 100 m embankments, the converged preset's track,
an 8-car CRH3 at 300 km/h on the deck grade (vtb.paper_config(model="deck"): substructure
cut-off and Δt as it sets them); each
size in a process of its own (its peak memory), the step cost from 1000 steps, the build from
a cold process. Exponents are least-squares slopes of log(figure) on log(length).
"""

from __future__ import annotations

import argparse
import copy
import json
import math
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

import vtb
from vtb.analysis import substructures
from vtb.analysis.eigen import assemble, sliced_eigsh
from vtb.run import substructures as engine

ROOT = Path(__file__).resolve().parent.parent
SPANS = (5, 10, 20, 40, 100)
_DECK = vtb.paper_config(model="deck")
CUTOFF = _DECK.discretisation.substructure_cutoff  # the deck grade's
DT = _DECK.solver.dt
SPEED = 300 / 3.6


def viaduct(n_spans: int, cars: int = 8, cutoff=CUTOFF, simply_supported: bool = True, approach: float = 100.0,
            t_end=None) -> vtb.Config:
    cfg = vtb.paper_config(model="fast")
    cfg.discretisation.synthesis_cutoff = None
    cfg.output.points = []
    cfg = vtb.spans(cfg, [32.0] * n_spans, simply_supported=simply_supported)
    cfg = vtb.track_zones(cfg, approach=approach, exit=approach, tail=None if t_end else 0.1)
    cfg.vehicles = vtb.train("crh3", cars=cars, x_front=-1.0, contact_patch=True)
    cfg.speed = SPEED
    cfg.irregularity = vtb.Irregularity(kind="german_low", wavelength_min=1.0, wavelength_max=30.0, seed=1)
    cfg.solver.dt = DT
    cfg.solver.fade_in = 20.0
    if t_end:
        cfg.solver.t_end = t_end
    cfg.output.band_limit = 150.0
    cfg.discretisation.substructure_cutoff = cutoff
    return cfg


def one_size(n: int, method: str) -> dict:
    """Build, memory and step cost of one size (run in a process of its own)."""
    cfg = viaduct(n, t_end=0.2)
    cfg.vehicles = vtb.train("crh3", cars=8, x_front=26.0 * 8 + 5.0, contact_patch=True)
    out = {"spans": n, "length": cfg.structure.length}
    if method == "fem":
        cfg.discretisation.substructure_cutoff = None
    else:
        t = time.perf_counter()
        built = engine.reduction(cfg)
        out.update(build=time.perf_counter() - t, distinct=built.substructuring.distinct,
                   substructures=built.substructuring.substructures, reduced=built.substructuring.reduced_dofs)
    t = time.perf_counter()
    vtb.simulate(cfg, progress=False)
    out["step_ms"] = (time.perf_counter() - t) / round(cfg.solver.t_end / cfg.solver.dt) * 1e3
    out["peak_gb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6
    return out


def in_process(n: int, method: str) -> dict:
    text = subprocess.run([sys.executable, __file__, "--one", str(n), method], check=True, capture_output=True, text=True).stdout
    return json.loads(text.strip().splitlines()[-1])


def slope(x, y) -> float:
    return float(np.polyfit(np.log(x), np.log(y), 1)[0])


def scaling() -> list[str]:
    sub = [in_process(n, "sub") for n in SPANS]
    fem = {n: in_process(n, "fem") for n in SPANS[:3]}
    lines = ["## Cost against the length", "",
             "An 8-car train at 300 km/h over simply supported 32 m spans between 100 m embankments, "
             f"substructure cut-off {CUTOFF:g} Hz, Δt = {DT:g} s; the finite elements it reduces beside it.", "",
             "| spans | length (m) | distinct / substructures | reduced DOFs | build (s) | peak memory (GB) | step (ms) | FE step (ms) |",
             "|---|---|---|---|---|---|---|---|"]
    for r in sub:
        f = fem.get(r["spans"])
        lines.append(f"| {r['spans']} | {r['length']:.0f} | {r['distinct']} / {r['substructures']} | {r['reduced']} | {r['build']:.1f} | "
                     f"{r['peak_gb']:.2f} | {r['step_ms']:.2f} | {'' if f is None else format(f['step_ms'], '.1f')} |")
    length = [r["length"] for r in sub]
    lines += ["", "Fitted exponents in length (5–100 spans): "
              f"build {slope(length, [r['build'] for r in sub]):.2f}, memory {slope(length, [r['peak_gb'] for r in sub]):.2f}, "
              f"step {slope(length, [r['step_ms'] for r in sub]):.2f}; the reduced DOFs {slope(length, [r['reduced'] for r in sub]):.2f}. "
              f"The finite elements' step (5–20 spans) {slope([fem[n]['length'] for n in fem], [fem[n]['step_ms'] for n in fem]):.2f}.", ""]
    return lines


def compare(fem: dict, sub: dict, names) -> str:
    return " | ".join(f"{100 * (sub[k] - fem[k]) / abs(fem[k]):+.2f}" for k in names)


#: Where the verification observes the deck (m): the second span's middle, crossed in the run.
OBSERVED = 78.0

INDICES = ("deck_disp_max", "deck_moment_max", "deck_acc_max", "car_comfort_aw", "contact_force_max", "contact_force_min")


#: The reference's time step (s): the finite elements converged in it (the contact extremes
#: move by at most 0.1 % from 5e-5 s, shown in the table's last rows).
REFERENCE_DT = 2.5e-5


def verification() -> list[str]:
    lines = ["## Against the finite elements", "",
             f"The same structure on its finite elements, converged in the time step (Newmark at Δt = {REFERENCE_DT:g} s), "
             f"and on the substructured engine at the deck grade (cut-off {CUTOFF:g} Hz, Δt = {DT:g} s) and at the former "
             "deck grade (600 Hz, 2e-4 s); relative differences (%) of the run's indices (deck and car in their bands: "
             "output.band_limit = 150 Hz; the deck observed at the middle of the second span, x = 78 m, which the "
             "train crosses; the contact force as it is). 300 km/h, 30 m embankments, the first 1.5 s.", "",
             "| spans | supports | cars | model | " + " | ".join(INDICES) + " |", "|---" * (4 + len(INDICES)) + "|"]
    for n in (5, 10):
        for ss in (True, False):
            for cars in (1, 4):
                cfg = viaduct(n, cars=cars, simply_supported=ss, approach=30.0, t_end=1.5)
                cfg.output.points = [OBSERVED]
                ref = copy.deepcopy(cfg)
                ref.discretisation.substructure_cutoff = None
                ref.solver.dt = REFERENCE_DT
                fem = vtb.simulate(ref, progress=False).metrics()
                runs = [(f"substructures {CUTOFF:g} Hz, {DT:g} s (deck grade)", CUTOFF, DT), ("substructures 600 Hz, 2e-4 s", 600.0, 2e-4)]
                if n == 10 and ss:
                    runs.append(("finite elements, 5e-05 s", None, 5e-5))
                for name, fc, dt in runs:
                    c = copy.deepcopy(cfg)
                    c.discretisation.substructure_cutoff = fc
                    c.solver.dt = dt
                    sub = vtb.simulate(c, progress=False).metrics()
                    lines.append(f"| {n} | {'simply supported' if ss else 'continuous'} | {cars} | {name} | {compare(fem, sub, INDICES)} |")
                    print(lines[-1], flush=True)
    return lines + [""]


def convergence() -> list[str]:
    """Natural frequencies below 60 Hz of 5 spans, substructured against the global eigensolve."""
    lines = ["## Natural frequencies against the kept interior modes", "",
             "Five simply supported and five continuous 32 m spans between 30 m embankments: the largest relative "
             "error of the substructured frequencies below 60 Hz against the global eigensolve, over all modes and over "
             "the deck's (kinetic energy mostly in the girder), as the interiors keep their modes below ratio × 60 Hz.", "",
             "| supports | ratio | reduced DOFs | all modes | deck modes |", "|---|---|---|---|---|"]
    fmax = 60.0
    hi = (2 * math.pi * fmax) ** 2
    for ss in (True, False):
        cfg = viaduct(5, simply_supported=ss, approach=30.0)
        system = assemble(cfg)
        lam, phi = sliced_eigsh(system.k.tocsc(), system.m.tocsc(), -1e-6 * hi, hi)
        fg = np.sqrt(np.clip(lam, 0, None))
        _, first, count = system.layers[-1]
        d = slice(first, first + count)
        deck = np.einsum("ij,ij->j", phi[d], system.m.tocsr()[d, d] @ phi[d]) > 0.5
        for ratio in (1.0, 2.0, 3.0, 5.0, 8.0):
            cut = substructures.reduce(system, fmax, ratio)
            lr, _ = sliced_eigsh(cut.k, cut.m, -1e-6 * hi, hi)
            fs = np.sqrt(np.clip(lr, 0, None))
            k = min(fs.size, fg.size)
            err = np.abs(fs[:k] - fg[:k]) / fg[:k]
            lines.append(f"| {'simply supported' if ss else 'continuous'} | {ratio:g} | {cut.reduced_dofs} | {err.max():.1e} | {err[deck[:k]].max():.1e} |")
    return lines + [""]


def train() -> list[str]:
    """The deck grade against the converged finite elements under an 8-car train standing on
    ten spans at the start (its front 213 m in), 1.5 s, simply supported and continuous."""
    lines = ["## Against the finite elements under an 8-car train", "",
             f"Ten spans between 30 m embankments, an 8-car CRH3 standing on them at the start (front at 213 m, "
             f"the static state) and running 1.5 s at 300 km/h; the finite elements at Δt = {REFERENCE_DT:g} s, the "
             f"substructures at the deck grade ({CUTOFF:g} Hz, Δt = {DT:g} s); relative differences (%) as above.", "",
             "| supports | " + " | ".join(INDICES) + " |", "|---" * (1 + len(INDICES)) + "|"]
    for ss in (True, False):
        cfg = viaduct(10, simply_supported=ss, approach=30.0, t_end=1.5)
        cfg.output.points = [OBSERVED]
        cfg.vehicles = vtb.train("crh3", cars=8, x_front=26.0 * 8 + 5.0, contact_patch=True)
        ref = copy.deepcopy(cfg)
        ref.discretisation.substructure_cutoff = None
        ref.solver.dt = REFERENCE_DT
        fem = vtb.simulate(ref, progress=False).metrics()
        sub = vtb.simulate(cfg, progress=False).metrics()
        lines.append(f"| {'simply supported' if ss else 'continuous'} | {compare(fem, sub, INDICES)} |")
        print(lines[-1], flush=True)
    return lines + [""]


def maxima() -> list[str]:
    """The contact force's maximum against the cut-off: five simply supported spans, a 4-car
    train, all at Δt = 5e-5 s (the finite elements' own step converged to 0.1 %), the first 1.1 s."""
    lines = ["## The contact force's maximum against the cut-off", "",
             "Five simply supported spans between 30 m embankments, a 4-car train at 300 km/h, the first 1.1 s, "
             "every model at Δt = 5e-5 s: the relative difference (%) of the largest contact force from the finite "
             "elements', and of the force low-passed (4th-order Butterworth, zero phase) at 100 and 300 Hz.", "",
             "| cut-off (Hz) | maximum | low-passed 100 Hz | low-passed 300 Hz |", "|---|---|---|---|"]
    from scipy.signal import butter, filtfilt

    def peaks(r):
        f = r.contact_force
        out = [f.max()]
        for fc in (100.0, 300.0):
            b, a = butter(4, fc, fs=1.0 / (r.t[1] - r.t[0]))
            out.append(filtfilt(b, a, f, axis=0).max())
        return out

    cfg = viaduct(5, cars=4, approach=30.0, t_end=1.1)
    cfg.solver.dt = 5e-5
    ref = copy.deepcopy(cfg)
    ref.discretisation.substructure_cutoff = None
    want = peaks(vtb.simulate(ref, progress=False))
    for cutoff in (600.0, 1200.0, 2400.0):
        c = copy.deepcopy(cfg)
        c.discretisation.substructure_cutoff = cutoff
        got = peaks(vtb.simulate(c, progress=False))
        lines.append(f"| {cutoff:g} | " + " | ".join(f"{100 * (g - w) / w:+.2f}" for g, w in zip(got, want)) + " |")
        print(lines[-1], flush=True)
    return lines + [""]


def whole_passage() -> list[str]:
    cfg = viaduct(100, cars=16)
    t = time.perf_counter()
    built = engine.reduction(cfg)
    build = time.perf_counter() - t
    t = time.perf_counter()
    r = vtb.simulate(cfg, progress=True)
    run = time.perf_counter() - t
    steps = len(r.t) - 1
    m = r.metrics()
    return ["## The whole passage", "",
            f"100 simply supported spans between 100 m embankments ({cfg.structure.length:.0f} m), a 16-car CRH3 at 300 km/h "
            f"over the whole viaduct, cut-off {CUTOFF:g} Hz, Δt = {DT:g} s: build {build:.1f} s ({built.substructuring.distinct} distinct of "
            f"{built.substructuring.substructures}), run {run:.0f} s ({steps} steps), peak memory "
            f"{resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6:.2f} GB; deck_acc_max {m['deck_acc_max']:.3f} m/s², "
            f"contact force {m['contact_force_min'] / 1e3:.1f}–{m['contact_force_max'] / 1e3:.1f} kN.", ""]


SECTIONS = {"scaling": scaling, "convergence": convergence, "verification": verification, "train": train, "maxima": maxima,
            "passage": whole_passage}
PAGE = ROOT / "docs" / "substructures-verification.md"


def sections_of(text: str) -> dict:
    """The page's sections by their "## " title (the heading first)."""
    out, title = {}, None
    for line in text.splitlines():
        if line.startswith("## "):
            title = line
            out[title] = []
        if title is not None:
            out[title].append(line)
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--one", nargs=2)
    ap.add_argument("--passage", action="store_true")
    ap.add_argument("--only", help="comma-separated sections to run again (scaling, convergence, verification, "
                                   "train, maxima, passage); the page keeps the others as they are")
    ap.add_argument("--page", type=Path, default=PAGE, help="the page written (default: the docs' page)")
    a = ap.parse_args()
    if a.one:
        print(json.dumps(one_size(int(a.one[0]), a.one[1])))
        return
    names = a.only.split(",") if a.only else ["scaling", "convergence", "verification", "train", "maxima"] + (["passage"] if a.passage else [])
    kept = sections_of(a.page.read_text()) if a.only and a.page.exists() else {}
    for name in names:
        new = SECTIONS[name]()
        kept.update(sections_of("\n".join(new)))
    lines = ["# The substructured engine: cost and verification", "",
             "Generated by `python benches/substructures.py` (2 cores, shared machine; `--only SECTION` runs one "
             "section again); the model is described in docs/substructures.md.", ""]
    for body in kept.values():
        lines += body
    a.page.write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
