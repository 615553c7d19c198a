"""Damper kinds side by side on the article's case (fast converged model): ten dampers
between rail and slab around mid-span as tuned inerter dampers (dashpot beside the spring)
and as tuned viscous mass dampers (dashpot beside the inerter), with the same inertance,
stiffness and damping, and the TIDs again with a tuned mass damper group on the girder. Each
line gives the rail and slab acceleration indices against the uncontrolled track.

    python examples/damper_kinds.py
"""

import math

import numpy as np

import vtb


def main():
    cfg = vtb.paper_config(model="fast")
    tids = vtb.tids_around(cfg)  # the article's ten dampers, one per bay around mid-span
    tvmd = vtb.DamperGroup(**{**vars(tids), "kind": "tvmd"})
    # A 2 t mass on the girder at mid-span, tuned to its first bending mode.
    f1 = vtb.modes(cfg, 6.0).frequencies[0]
    w = 2 * math.pi * f1
    tmd = vtb.DamperGroup(kind="tmd", inertance=2000.0, stiffness=2000.0 * w**2, damping=2 * 0.1 * 2000.0 * w,
                          positions=[cfg.structure.length / 2], upper="bridge", lower="ground")
    cases = {"no dampers": dict(tids=None), "10 TIDs": dict(tids=tids), "10 TVMDs": dict(tids=tvmd),
             "10 TIDs + a girder TMD": dict(tids=tids, dampers=[tmd])}
    configs = []
    for fields in cases.values():
        c = cfg.copy()
        for name, value in fields.items():
            setattr(c, name, value)
        configs.append(c)
    runs = vtb.simulate_batch(configs, progress=False)
    base = runs[0]
    print(f"dampers: b {tids.inertance:g} kg, k {tids.stiffness:g} N/m, c {tids.damping:g} N·s/m at x = "
          f"{np.round(tids.locations(), 2).tolist()} m; girder TMD 2000 kg at {f1:.2f} Hz")
    for name, m in zip(cases, runs):
        change = {k: 100 * (m[k] / base[k] - 1) for k in ("rail_acc_rms", "slab_acc_rms", "deck_acc_max")}
        print(f"{name:>24s}: rail acc rms {m['rail_acc_rms']:7.2f} m/s² ({change['rail_acc_rms']:+5.1f} %), "
              f"slab acc rms {m['slab_acc_rms']:6.3f} m/s² ({change['slab_acc_rms']:+5.1f} %), "
              f"deck acc max {m['deck_acc_max']:.4f} m/s² ({change['deck_acc_max']:+5.1f} %)")


if __name__ == "__main__":
    main()
