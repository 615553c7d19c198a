"""Benchmark: how far EN 1991-2's Δζ shortcut is from explicit vehicle–bridge interaction, per
span length (issue 40, "beyond the code").

For single simply supported spans of 5, 10, 15, 20, 25, 30 and 40 m with the track on them (the
article's rail, pads, slab and base, ``vtb.paper_config(model="fast")``, re-spanned by
``vtb.spans``) and continuing over ``--approach`` m of embankment before and after the span
(``vtb.track_zones``, the wheels and forces handed over to the modelled track on a 10 m ramp:
without it they step onto the rail's free end at the span's, a transient that on a 5 m span is
larger than the resonance and fails the contact), a real train (the library's Velaro E, 8 cars) runs over a speed range
around its first resonances n0·D/i three ways:

- moving loads, Table 6.6's damping (prestressed concrete) without Δζ;
- moving loads, Table 6.6 + Δζ (eq. 6.13) — the code's shortcut;
- the train as vehicles with full interaction (Hertz contact, smooth rail), Table 6.6 only.

It prints, per span, the peak deck acceleration (in the check's band max(30 Hz, 1.5·n0, n3),
over the quarter, middle and three-quarter points) of each and the ratios Δζ/interaction and
no-Δζ/interaction. Each girder keeps the article's section's mass; its bending stiffness is set
so that n0 is the geometric mean of EN 1991-2 Fig. 6.10's limits for the span. The axles act on
the modelled rail with half their load (one rail and its share of the deck), as the vehicles'
two rails do.

    python benches/dzeta_interaction.py [--step 10] [--spans 5 10 15 20 25 30 40] [--approach 20] [--threads 2]

``--step`` (km/h) is the speed step, coarser than a check's near the resonances (the peaks can
be missed by up to a step); the scan runs from 40 km/h to 420 km/h.
"""

import argparse
import math
import time

import numpy as np

import vtb
from vtb.bridge.assess import deck_band_of
from vtb.bridge.checks import n0_limits
from vtb.bridge.damping import apply_code_damping, code_damping
from vtb.bridge.interaction import interaction_scan
from vtb.bridge.load_trains import load_train
from vtb.bridge.scan import span_points, speed_scan, with_band
from vtb.bridge.static import deck_frequencies

TRAIN = "velaro_e"
KIND = "prestressed_concrete"
STEPS_PER_BAND_PERIOD = 40
EDGE_RAMP = 10.0


def span_model(span: float, approach: float = 0.0) -> tuple:
    """(configuration with the track on one simply supported span of ``span`` m between
    embankments of ``approach`` m (none: 0), n0, band)."""
    cfg = vtb.paper_config(model="fast")
    cfg.irregularity = vtb.Irregularity()
    cfg.output.band_limit = None
    cfg.output.points = []
    for layer in cfg.structure.layers:
        layer.element_length = min(0.3, span / 40)
    cfg = vtb.spans(cfg, [span], simply_supported=True)
    lower, upper = n0_limits(span)
    target = math.sqrt(lower * upper)
    girder = cfg.structure.layers[-1]
    mass = sum(l.density * l.area for l in cfg.structure.layers)  # kg/m, all on the girder
    bearings = span - 2 * vtb.config.spans.BEARING_OFFSET
    girder.inertia = (2 * target * bearings**2 / math.pi) ** 2 * mass / girder.youngs_modulus  # Euler–Bernoulli first guess
    for _ in range(2):  # n0 ∝ √I nearly (the track adds a little stiffness)
        girder.inertia *= (target / float(deck_frequencies(cfg, 12 * target)[0])) ** 2
    freqs = deck_frequencies(cfg, 12 * target)
    n0 = float(freqs[0])
    band = deck_band_of(freqs, n0)
    cfg.discretisation.synthesis_cutoff = 2.0 * band
    cfg.solver.dt = 1.0 / (STEPS_PER_BAND_PERIOD * band)
    cfg.output.points = span_points(cfg)
    if approach > 0:
        cfg = vtb.track_zones(cfg, approach=approach, exit=approach, edge_ramp=min(EDGE_RAMP, approach))
    return with_band(cfg, band), n0, band


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--spans", type=float, nargs="+", default=[5.0, 10.0, 15.0, 20.0, 25.0, 30.0, 40.0])
    p.add_argument("--step", type=float, default=10.0, help="speed step (km/h)")
    p.add_argument("--v-min", type=float, default=40.0, help="lowest speed (km/h)")
    p.add_argument("--v-max", type=float, default=420.0, help="highest speed (km/h)")
    p.add_argument("--approach", type=float, default=20.0, help="embankment (m) before and after the span; 0: none")
    p.add_argument("--threads", type=int, default=2)
    args = p.parse_args(argv)
    speeds = np.arange(args.v_min, args.v_max + 1e-9, args.step) / 3.6
    train = load_train(TRAIN)
    rows = []
    t0 = time.perf_counter()
    for span in args.spans:
        cfg, n0, band = span_model(span, args.approach)
        peaks = {}
        for name, dz in (("plain", False), ("dzeta", True)):
            damped = apply_code_damping(cfg, code_damping(KIND, span, dz), n0, band)
            res = speed_scan(damped, [train], speeds, band=band, share=0.5, threads=args.threads, progress=False)
            peaks[name] = res.governing("acc")
        plain = apply_code_damping(cfg, code_damping(KIND, span, False), n0, band)
        res = interaction_scan(plain, [TRAIN], speeds, band=band, threads=args.threads, progress=False)
        peaks["vehicles"] = res.governing("acc")
        failed = int(np.sum(res.columns["error"] != ""))
        rows.append((span, n0, band, code_damping(KIND, span, True), peaks, failed))
        print(f"{span:g} m done after {time.perf_counter() - t0:.0f} s", flush=True)
    seconds = time.perf_counter() - t0
    print(f"\n{TRAIN}, {len(speeds)} speeds {args.v_min:g}–{args.v_max:g} km/h every {args.step:g} km/h, "
          f"{len(rows) * 3 * len(speeds)} runs in {seconds:.0f} s on {args.threads} threads, {args.approach:g} m embankments\n")
    print("| span (m) | n0 (Hz) | band (Hz) | ζ (%) | Δζ (%) | moving loads (m/s²) | + Δζ (m/s²) | interaction (m/s²) | "
          "+Δζ / interaction | moving loads / interaction |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for span, n0, band, d, pk, failed in rows:
        a, b, c = (pk[k]["acc"] for k in ("plain", "dzeta", "vehicles"))
        at = lambda k: f" at {pk[k]['speed'] * 3.6:.0f}"  # noqa: E731 - a table cell
        print(f"| {span:g} | {n0:.2f} | {band:.0f} | {d.table:.3f} | {d.interaction:.3f} | {a:.3f}{at('plain')} | {b:.3f}{at('dzeta')} | "
              f"{c:.3f}{at('vehicles')}{' (%d failed)' % failed if failed else ''} | {b / c:.3f} | {a / c:.3f} |")


if __name__ == "__main__":
    main()
