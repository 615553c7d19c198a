"""A passage over a viaduct of uneven spans on elastic piers, with and without a tuned mass
damper on the deck: each car's ride comfort, each wheel's force peak and the deck acceleration
in the band of EN 1990 A2 against its limit (fast converged model, two cars). The damper
lowers the deck's resonance peak (its point receptance at the first mode); at 80 m/s two cars
25 m apart are far from resonance (25 m × 4.6 Hz = 115 m/s), so the passage barely shows it.

    python examples/viaduct_passage.py
"""

import math

import numpy as np

import vtb

#: EN 1990 A2 (A2.4.4.2.1): peak deck acceleration for direct fastening (m/s²).
DECK_LIMIT = 5.0


def main():
    cfg = vtb.paper_config(model="fast")
    cfg.output.points = []  # observe the middle of the middle span
    cfg = vtb.spans(cfg, [24.0, 32.0, 40.0, 32.0, 24.0], pier_stiffness=[1e15, 2e9, 2e9, 2e9, 2e9, 1e15])
    lead = cfg.vehicles[0]
    cfg.vehicles = [lead, vtb.crh3_car(lead.x_front + 25.0)]
    cfg.irregularity = vtb.Irregularity(kind="tbt3352", seed=2025)
    cfg.output.deck_band = vtb.deck_band(cfg)
    x = cfg.output.points[0]
    first = vtb.modes(cfg, 6.0)
    f1 = first.frequencies[0]
    # A 20 t damper on the middle of the 40 m span, tuned by Den Hartog's rules for its mass
    # ratio μ = m·φ² (φ the mass-normalised mode there): f = f1/(1 + μ), ζ = √(3μ/(8(1 + μ)³)).
    mass = 20000.0
    mu = mass * float(np.ravel(first.displacement("bridge", x, mode=0))[0]) ** 2
    w = 2 * math.pi * f1 / (1 + mu)
    zeta = math.sqrt(3 * mu / (8 * (1 + mu) ** 3))
    tmd = vtb.DamperGroup(kind="tmd", inertance=mass, stiffness=mass * w**2, damping=2 * zeta * mass * w,
                          positions=[x], upper="bridge", lower="ground")
    with_tmd = cfg.copy()
    with_tmd.dampers = [tmd]
    runs = vtb.simulate_batch([cfg, with_tmd], progress=False)
    f = np.linspace(0.8 * f1, 1.2 * f1, 161)
    peaks = [np.abs(vtb.receptance(c, x, f, layer="bridge")).max() for c in (cfg, with_tmd)]
    print(f"deck: first mode {f1:.2f} Hz, EN 1990 band {cfg.output.deck_band:g} Hz, observed at x = {cfg.output.points[0]:g} m")
    print(f"TMD: {mass:g} kg, μ = {mu:.3f}, tuned to {w / (2 * math.pi):.2f} Hz with ζ = {zeta:.3f}")
    print(f"deck receptance peak at the first mode: {peaks[0]:.3e} m/N, with the TMD {peaks[1]:.3e} m/N "
          f"({20 * math.log10(peaks[1] / peaks[0]):+.1f} dB)")
    for name, m in zip(("no damper", f"TMD {mass:g} kg"), runs):
        wheels = [m[f"wheel{w}_force_max"] / 1e3 for w in range(8)]
        print(f"{name:>12s}: deck {m['deck_acc_max']:.4f} m/s² ({m['deck_acc_max'] / DECK_LIMIT:.1%} of {DECK_LIMIT:g}), "
              f"comfort a_w car 0 {m['car_comfort_aw']:.4f}, car 1 {m['car1_comfort_aw']:.4f} m/s², "
              f"wheel peaks {min(wheels):.1f}–{max(wheels):.1f} kN")


if __name__ == "__main__":
    main()
