"""Benchmark: the bridge check's speed scan — HSLM-A1 … A10 as moving loads on the track of ten
simply supported 32 m spans, 40–420 km/h every 5 km/h (10 × 77 = 770 runs). Target (issue 40):
at most 3 minutes on 2 cores.

The structure is the article's track and girder (``vtb.paper_config(model="fast")``: rail on
pads, slab, base, girder) re-meshed at 0.6 m, re-spanned as 10 × 32 m simply supported girders
(``vtb.spans``), run by complex-modal synthesis up to 100 Hz; the axles act on the rail, half of
each axle load (the model is one rail with its share of the deck); the girder has Table 6.6's
damping for prestressed concrete (1 %, no Δζ at 32 m) fitted over n0 … 30 Hz; the deck's
acceleration is low-passed at 30 Hz at mid-span of the middle girder.

    python benches/bridge_scan.py [--threads 2] [--dt 2e-3] [--every 1] [--out benches/results/bridge_scan] [--check-dt]

``--vehicles velaro_e crh3`` runs those library trains as vehicles with full interaction
instead (smooth rail, the same structure and damping; target: at most 20 minutes on 2 cores);
``--workers n`` runs the scan on a local Dask cluster of n one-thread workers instead of threads.
``--every k`` runs every k-th speed only (a quick estimate; the printed figure scales it to the
full scan by the simulated time). Resumable: the journals in --out; ``--fresh`` starts over (a
fair timing needs it). ``--check-dt`` reruns the governing cases (acceleration, deflection) at
dt/2 and dt/4 and says whether their peaks agree within 0.1 %.

Measured 2026-12-05 (``PYTHONPATH=python python benches/bridge_scan.py --fresh --check-dt``,
load average 8.7–9.2 on the 2 cores): 770 runs in 85.5 s at dt = 2 ms, none failed; largest
deck acceleration 0.812 m/s² (HSLM-A1 at 405 km/h); dt = 2 ms passes the check (peaks within
0.02 % of dt/4). See docs/bridge-check.md, "Performance".
"""

import argparse
import contextlib
import os
import shutil
import time
from pathlib import Path

import numpy as np

import vtb
from vtb.bridge.damping import apply_code_damping, code_damping
from vtb.bridge.interaction import interaction_scan, with_vehicles
from vtb.bridge.load_trains import apply_load_train, load_train
from vtb.bridge.scan import deck_indices, speed_scan, with_band
from vtb.bridge.static import deck_frequencies
from vtb.run.scaleout import local_cluster

SPANS = [32.0] * 10
TRAINS = [f"HSLM-A{i}" for i in range(1, 11)]
SPEEDS_KMH = np.arange(40.0, 420.0 + 1e-9, 5.0)
BAND = 30.0


def structure(dt: float, cutoff: float = 100.0) -> vtb.Config:
    cfg = vtb.paper_config(model="fast")
    cfg.irregularity = vtb.Irregularity()
    for layer in cfg.structure.layers:
        layer.element_length = 0.6
    cfg.discretisation.synthesis_cutoff = cutoff
    cfg.output.points = []
    cfg = vtb.spans(cfg, SPANS, simply_supported=True)
    cfg.solver.dt = dt
    cfg.output.band_limit = None
    n0 = float(deck_frequencies(cfg, 60.0)[0])
    cfg = apply_code_damping(with_band(cfg, BAND), code_damping("prestressed_concrete", 32.0), n0, BAND)
    return cfg


def peaks(dt: float, train: str, speed: float) -> np.ndarray:
    """The deck's peak acceleration in the band and peak deflection of one scan run at ``dt``."""
    cfg = apply_load_train(structure(dt), load_train(train), share=0.5, tail=0.5)
    cfg.speed = speed
    res = vtb.simulate(cfg, progress=False)
    return np.array([res.metrics()[k] for k in deck_indices(cfg)])


def check_dt(dt: float, train: str, speed: float, tol: float = 1e-3) -> bool:
    """Whether the peaks of ``train`` at ``speed`` (m/s) at Δt, Δt/2 and Δt/4 agree within
    ``tol`` (relative to the Δt/4 ones): Δt resolves the governing response."""
    ref = peaks(dt / 4, train, speed)
    ok = True
    for k in (1, 2):
        got = peaks(dt / k, train, speed)
        rel = np.abs(got / ref - 1)
        ok &= bool(np.all(rel <= tol))
        print(f"  dt/{k}: acc {got[0]:.5f} m/s², disp {got[1] * 1e3:.5f} mm; vs dt/4: {rel[0]:.2e}, {rel[1]:.2e}")
    print(f"  dt/4: acc {ref[0]:.5f} m/s², disp {ref[1] * 1e3:.5f} mm")
    print(f"dt = {dt:g} s {'passes' if ok else 'FAILS'} the {tol:.1%} check at {train}, {speed * 3.6:.0f} km/h")
    return ok


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--dt", type=float, default=2e-3)
    p.add_argument("--every", type=int, default=1, help="run every k-th speed only")
    p.add_argument("--out", default="benches/results/bridge_scan")
    p.add_argument("--fresh", action="store_true", help="delete the journals first")
    p.add_argument("--check-dt", action="store_true", help="after the scan, rerun its governing case at dt/2 and dt/4")
    p.add_argument("--vehicles", nargs="+", help="library trains run as vehicles with full interaction instead of HSLM-A")
    p.add_argument("--workers", type=int, help="run on a local Dask cluster of this many workers")
    args = p.parse_args(argv)
    if args.fresh and Path(args.out).exists():
        shutil.rmtree(args.out)
    cfg = structure(args.dt)
    trains = args.vehicles or TRAINS
    warm = with_vehicles(cfg, trains[0]) if args.vehicles else apply_load_train(cfg, load_train("HSLM-A1"), share=0.5)
    warm.speed = 400 / 3.6
    vtb.simulate(warm, progress=False)  # the reduction built (or loaded) before the clock starts
    speeds = SPEEDS_KMH[:: args.every] / 3.6
    load = os.getloadavg()
    with contextlib.ExitStack() as stack:
        executor = stack.enter_context(local_cluster(args.workers, preload=warm)) if args.workers else None
        t0 = time.perf_counter()
        if args.vehicles:
            res = interaction_scan(cfg, trains, speeds, band=BAND, tail=0.5, out=args.out, executor=executor, threads=args.threads)
        else:
            res = speed_scan(cfg, trains, speeds, band=BAND, share=0.5, tail=0.5, out=args.out, executor=executor, threads=args.threads)
        seconds = time.perf_counter() - t0
    full = sum((sum(SPANS) + 1.0 + load_train(t).length) / (v / 3.6) + 0.5 for t in trains for v in SPEEDS_KMH)
    done = sum((sum(SPANS) + 1.0 + load_train(t).length) / v + 0.5 for t in trains for v in speeds)
    failed = int(np.sum(res.columns["error"] != ""))
    gov = res.governing("acc")
    where = f"{args.workers} Dask workers" if args.workers else f"{args.threads} threads"
    print(f"bridge scan{' with interaction' if args.vehicles else ''}: {len(res)} runs ({failed} failed) in {seconds:.1f} s on {where}, dt = {args.dt:g} s")
    if args.every > 1:
        print(f"full scan ({len(trains) * len(SPEEDS_KMH)} runs) estimated at {seconds * full / done:.0f} s ({seconds * full / done / 60:.1f} min) by simulated time")
    print(f"largest deck acceleration {gov['acc']:.3f} m/s² ({gov['train']} at {gov['speed'] * 3.6:.0f} km/h)")
    print("machine load before: %.2f %.2f %.2f, after: %.2f %.2f %.2f (1, 5, 15 min averages)" % (*load, *os.getloadavg()))
    res.to_csv(Path(args.out) / "envelopes.csv")
    if args.check_dt:
        for column in ("acc", "disp"):
            g = res.governing(column)
            check_dt(args.dt, g["train"], g["speed"])


if __name__ == "__main__":
    main()
