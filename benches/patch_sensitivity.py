"""How much the converged preset's indices depend on the length of the Hertz contact patch
(docs/contact-patch.md, "What is approximated"): the smooth-rail case (80 m/s, uncontrolled)
with the patch of the static wheel load, and with a patch 10 % shorter and 10 % longer (the
change of a dynamic load of about ∓30 %), set through the rail's crown radius. About 2 minutes
on two cores.

    python benches/patch_sensitivity.py
"""

from scipy.optimize import brentq

import vtb

base = vtb.paper_config(calibrated=True, model="converged")
base.irregularity = vtb.Irregularity(kind="none")
wheel = base.vehicles[0].wheel_radius
load = 71613.0  # the static wheel load on the modelled rail (N): contact_force at t = 0
a0 = vtb.contact_patch_half_length(load, wheel, base.vehicles[0].rail_crown_radius)
cases = []
for f in (0.9, 1.0, 1.1):
    r = brentq(lambda r: vtb.contact_patch_half_length(load, wheel, r) - f * a0, 0.02, 5.0) if f != 1.0 else base.vehicles[0].rail_crown_radius
    c = base.copy()
    c.vehicles[0].rail_crown_radius = r
    cases.append((f, r, c))
for (f, r, _), m in zip(cases, vtb.simulate_batch([c for _, _, c in cases], progress=True)):
    a = vtb.contact_patch_half_length(load, wheel, r)
    print(f"patch × {f}: crown radius {r:.4f} m, a = {1e3 * a:.3f} mm: rail_acc_max (≤ 2 kHz) {m['rail_acc_max']:.3f} m/s², "
          f"raw {m['rail_acc_max_raw']:.1f} m/s², rail r.m.s. {m['rail_acc_rms']:.4f} m/s², slab peak {m['slab_acc_max']:.4f} m/s²")
