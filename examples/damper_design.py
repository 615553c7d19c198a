"""Damper design: a small sweep of rail–slab tuned inerter dampers on the article's case, the
best design, and a check of that design on an irregularity sample it was not chosen on. It
runs on the fast converged model (the converged finite elements by complex-modal synthesis),
the model the README recommends for damper design; the first run builds and caches its
reduction (161 s on a 2-core machine, docs/synthesis-verification.md).

    python examples/damper_design.py
"""

import vtb

B_T = [2.0, 5.0, 8.0]  # inertance (kg)
K_T = [5e7, 1e8, 2e8]  # stiffness (N/m)
C_T = [1e3]  # damping (N·s/m)


def main():
    cfg = vtb.paper_config(model="fast", calibrated=True)  # the article's level, converged model
    cfg.tids = vtb.tids_around(cfg)  # ten dampers, one per fastener bay around mid-span
    print(f"rail pinned–pinned frequency (Timoshenko): {vtb.pinned_pinned_frequency(cfg):.0f} Hz")

    result = vtb.sweep(cfg, B_T, K_T, C_T, progress=False)
    best = result.best()
    base = result.baseline
    print(f"uncontrolled: a_rm = {base['rail_acc_max']:.1f} m/s², a_sm = {base['slab_acc_max']:.2f} m/s²")
    print(f"best of {len(result) - 1} designs: b_t = {best['b_t']:g} kg, k_t = {best['k_t']:.3g} N/m, c_t = {best['c_t']:.3g} N·s/m, "
          f"working frequency {best['working_frequency']:.0f} Hz")
    print(f"  a_rm {base['rail_acc_max']:.1f} → {best['rail_acc_max']:.1f} m/s² ({100 * best['eta_rail_acc_max']:.1f} % lower), "
          f"a_sm {base['slab_acc_max']:.2f} → {best['slab_acc_max']:.2f} m/s²")

    # The same design on another sample of the same spectrum and level: a design chosen on one
    # sample is fitted to it.
    other = vtb.paper_config(seed=7, model="fast", calibrated=True)
    other.tids = cfg.tids
    unc = other.copy()
    unc.tids = None
    ctl = other.copy()
    ctl.tids.inertance, ctl.tids.stiffness, ctl.tids.damping = best["b_t"], best["k_t"], best["c_t"]
    m0, m1 = vtb.simulate_batch([unc, ctl])
    print(f"sample 7: a_rm {m0['rail_acc_max']:.1f} → {m1['rail_acc_max']:.1f} m/s² "
          f"({100 * (1 - m1['rail_acc_max'] / m0['rail_acc_max']):.1f} % lower), "
          f"a_sm {m0['slab_acc_max']:.2f} → {m1['slab_acc_max']:.2f} m/s²")


if __name__ == "__main__":
    main()
