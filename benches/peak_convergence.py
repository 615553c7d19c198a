"""Convergence of the rail peak under mesh and time-step refinement, point contact against the
Hertz contact patch (docs/contact-patch.md).

The converged preset on a smooth rail (80 m/s, uncontrolled): the rail's raw acceleration
peak at the observation point, when it occurs, and the peaks low-passed at 2 and 5 kHz (the
core's band-limited index, ``output.band_limit``), for a point contact and for the distributed
Hertz contact, at 20, 40 and 80 rail elements per fastener bay and Δt = 2.5e-5 s, and at 20 and
40 per bay with Δt halved; the patch also at 80 per bay with Δt halved and at 20 and 40 per bay
with Δt quartered. The last lines give the changes the convergence criterion is judged on
(raw peak within 3 % from 20 to 40 per bay and under Δt halved). About 25 minutes on two
cores; ``--quick`` runs two cases over the first 0.3 s of the passage only (a smoke run: no
wheel crosses the observation point in it).

    python benches/peak_convergence.py [--quick]
"""

import argparse

import numpy as np

import vtb

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--quick", action="store_true")
args = parser.parse_args()

cases = [(20, 2.5e-5), (40, 2.5e-5), (80, 2.5e-5), (20, 1.25e-5), (40, 1.25e-5)]
finer = [(80, 1.25e-5), (20, 6.25e-6), (40, 6.25e-6)]
if args.quick:
    cases, finer = cases[:2], []


def config(per_bay, dt, patch, band):
    c = vtb.paper_config(calibrated=True, model="converged")
    c.irregularity = vtb.Irregularity(kind="none")
    c.structure.layers[0].element_length = 0.64 / per_bay
    c.solver.dt = dt
    c.vehicles[0].contact_patch = patch
    c.output.band_limit = band
    if args.quick:
        c.solver.t_end = 0.3
    return c


rows = {}
for patch in (False, True):
    runs = cases + finer if patch else cases
    cfgs = [config(n, dt, patch, None) for n, dt in runs]
    results = vtb.simulate_batch(cfgs, histories=True, progress=True)
    for (n, dt), r in zip(runs, results):
        a, t = r.acc[:, 0, 0], r.t
        # The core's band-limit filter on this record, as every study's index takes it.
        banded = [np.abs(vtb.low_pass(a, fc, dt)).max() for fc in (2000.0, 5000.0)]
        rows[(patch, n, dt)] = (np.abs(a).max(), t[np.argmax(np.abs(a))], *banded)

print("| contact | rail elements per bay | Δt (s) | raw peak (m/s²) | at t (s) | peak ≤ 2 kHz | peak ≤ 5 kHz |")
print("|---|---|---|---|---|---|---|")
for (patch, n, dt), (raw, at, b2, b5) in rows.items():
    print(f"| {'patch' if patch else 'point'} | {n} | {dt:g} | {raw:.1f} | {at:.4f} | {b2:.2f} | {b5:.2f} |")
checks = (
    ((20, 2.5e-5), (40, 2.5e-5), "20 → 40 per bay at Δt = 2.5e-5 s"),
    ((20, 1.25e-5), (40, 1.25e-5), "20 → 40 per bay at Δt = 1.25e-5 s"),
    ((40, 1.25e-5), (80, 1.25e-5), "40 → 80 per bay at Δt = 1.25e-5 s"),
    ((20, 6.25e-6), (40, 6.25e-6), "20 → 40 per bay at Δt = 6.25e-6 s"),
    ((20, 2.5e-5), (20, 1.25e-5), "Δt halved from 2.5e-5 s at 20 per bay"),
    ((40, 2.5e-5), (40, 1.25e-5), "Δt halved from 2.5e-5 s at 40 per bay"),
    ((20, 1.25e-5), (20, 6.25e-6), "Δt halved from 1.25e-5 s at 20 per bay"),
    ((40, 1.25e-5), (40, 6.25e-6), "Δt halved from 1.25e-5 s at 40 per bay"),
)
for patch in (False, True):
    name = "patch" if patch else "point"
    for a, b, what in checks:
        if (patch, *a) in rows and (patch, *b) in rows:
            ch = [100.0 * (rows[(patch, *b)][i] / rows[(patch, *a)][i] - 1.0) for i in (0, 2, 3)]
            print(f"{name}, {what}: raw {ch[0]:+.1f} %, ≤ 2 kHz {ch[1]:+.2f} %, ≤ 5 kHz {ch[2]:+.2f} %")
