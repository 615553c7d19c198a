"""A train passage: two Velaro E cars run off an approach embankment, over a 32 m bridge and
onto the exit embankment, starting before the modelled track; the bridge then rings for a
free-vibration tail (docs/zones.md). The synthesis of the converged finite-element structure
at a passage-grade cut-off (modes below 300 Hz: deck and ride comfort, not rail bands).

    python examples/train_passage.py
"""

import numpy as np

import vtb


def main():
    cfg = vtb.paper_config(model="fast")
    cfg.discretisation.synthesis_cutoff = 300.0  # resolved band 150 Hz
    cfg.output.band_limit = 150.0
    cfg.solver.dt = 2e-4
    cfg.output.points = []  # the middle of the span
    cfg = vtb.spans(cfg, [32.0])
    cfg = vtb.track_zones(cfg, approach=20.0, exit=20.0, tail=0.3)
    cfg.vehicles = vtb.train("velaro_e", cars=2, x_front=-2.0, contact_patch=True)
    cfg.irregularity = vtb.Irregularity(kind="german_low", wavelength_min=2.0, wavelength_max=80.0, seed=7)
    cfg.solver.fade_in = 20.0  # grow the long waves in over the approach, not at the start
    cfg.output.deck_band = vtb.deck_band(cfg)
    r = vtb.simulate(cfg, progress=False)
    m = r.metrics()
    start, end = vtb.bridge_extent(cfg)
    rear = vtb.consist_extent(cfg.vehicles)[0]
    left = (end - rear) / cfg.speed  # the last axle leaves the bridge
    deck = r.disp[:, -1, 0]
    tail = r.t > left
    print(f"track {cfg.structure.length:g} m, bridge [{start:g}, {end:g}] m, {len(cfg.vehicles)} Velaro E cars, "
          f"run {r.t[-1]:.3f} s, last axle off the bridge at {left:.3f} s")
    print("comfort a_w: " + ", ".join(f"car {k} {m['car_comfort_aw' if k == 0 else f'car{k}_comfort_aw']:.4f} m/s²" for k in range(2)))
    print(f"wheel forces {min(m[f'wheel{w}_force_min'] for w in range(8)) / 1e3:.1f}–"
          f"{max(m[f'wheel{w}_force_max'] for w in range(8)) / 1e3:.1f} kN; deck acceleration "
          f"{m['deck_acc_max']:.4f} m/s² (band {cfg.output.deck_band:g} Hz)")
    print(f"deck displacement: peak {np.abs(deck).max() * 1e3:.3f} mm during the passage, "
          f"{np.abs(deck[tail]).max() * 1e3:.4f} mm in the free-vibration tail")


if __name__ == "__main__":
    main()
