"""The converged preset's raw rail peak on a smooth rail, against refined rails (docs/robust.md).

Runs the converged preset with no irregularity (80 m/s, uncontrolled) at 20 rail elements per
fastener bay and Δt = 2.5e-5 s (the preset), 40 per bay, and 40 per bay with Δt = 1.25e-5 s,
and prints for each the raw peak of the rail acceleration at the observation point, when it
occurs, and the peaks of the same signal low-passed at 2 and 5 kHz (eighth-order Butterworth,
zero phase). About 4 minutes on two cores.

    python benches/peak_convergence.py
"""

import numpy as np
from scipy.signal import butter, sosfiltfilt

import vtb

cases = ((20, 2.5e-5), (40, 2.5e-5), (40, 1.25e-5))
cfgs = []
for per_bay, dt in cases:
    c = vtb.paper_config(calibrated=True, model="converged")
    c.irregularity = vtb.Irregularity(kind="none")
    c.structure.layers[0].element_length = 0.64 / per_bay
    c.solver.dt = dt
    cfgs.append(c)
print("| rail elements per bay, Δt | raw peak a_rm (m/s²) | at t (s) | peak low-passed at 2 kHz | at 5 kHz |")
print("|---|---|---|---|---|")
for (per_bay, dt), r in zip(cases, vtb.simulate_batch(cfgs, histories=True, progress=True)):
    a, t = r.acc[:, 0, 0], r.t
    fs = 1.0 / (t[1] - t[0])
    low = [np.abs(sosfiltfilt(butter(8, fc, fs=fs, output="sos"), a)).max() for fc in (2000.0, 5000.0)]
    print(f"| {per_bay}, {dt:g} s | {np.abs(a).max():.0f} | {t[np.argmax(np.abs(a))]:.4f} | {low[0]:.1f} | {low[1]:.1f} |")
