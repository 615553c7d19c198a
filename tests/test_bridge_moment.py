"""The deck's bending moment (``deck_moment_max``, the static moment influence line) against
closed forms for a simply supported Euler–Bernoulli beam: the static moment at mid-span under a
unit force at a, M = a/2 left of mid-span and (L − a)/2 right of it; and the moment under a force crossing the beam, Frýba's modal series
M(L/2, t) = Σ_n EI (nπ/L)² sin(nπ/2) q_n(t) (L. Frýba, Vibration of Solids and Structures under
Moving Loads, 3rd ed., 1999, §1.2), summed here over 500 odd modes (its peak moves by 0.15 %
from 100 to 500 modes, so by about 0.03 % beyond), written independently of vtb. A moment converges more slowly with the modes than a deflection (its series falls as 1/n²,
and at the force's kink the truncation error is ∝ 1/modes), so each check shows the refinement."""

import math

import numpy as np
import pytest

import vtb
from vtb.bridge.static import influence_line
from test_bridge_scan import _sdof_sine

L, M, N0 = 30.0, 15000.0, 2.5
EI = (2 * N0 * L**2 / math.pi) ** 2 * M   # n0 = (π / 2L²)·√(EI/m)
E = 3.5e10
P = 1e5          # the moving force (N)
GAP = 1.0        # its distance before the span at t = 0 (m)
DT = 2.5e-4


def _beam(speed, modes):
    cfg = vtb.moving_load_config(L, 2500.0, M / 2500.0, E, EI / E, [vtb.MovingForce(P, -GAP)], speed, points=[L / 2],
                                 modes=modes, dt=DT, initial_state="rest")
    cfg.solver.t_end = round(((GAP + L) / speed + 0.5) / DT) * DT
    return cfg


def frýba_midspan_moment(speed, t, nmax=999):
    """M(L/2, t) (N·m, sagging positive) of the undamped beam under the force P entering at
    t = GAP/speed: each odd mode's forced response while it crosses, free vibration after."""
    out = np.zeros_like(t)
    tau, cross = t - GAP / speed, L / speed
    for n in range(1, nmax + 1, 2):
        w, big_w, amp = 2 * math.pi * N0 * n**2, n * math.pi * speed / L, 2 * P / (M * L)
        on = (tau >= 0) & (tau <= cross)
        q, _ = _sdof_sine(np.where(on, tau, 0.0), amp, w, 0.0, big_w)
        q_t, qd_t = _sdof_sine(np.array([cross]), amp, w, 0.0, big_w)
        s = tau - cross
        free = q_t * np.cos(w * s) + qd_t / w * np.sin(w * s)
        out += EI * (n * math.pi / L) ** 2 * math.sin(n * math.pi / 2) * np.where(on, q, np.where(s > 0, free, 0.0))
    return out


def test_the_moment_influence_line_is_the_simply_supported_beams():
    """Away from mid-span within 0.1 % at 40 modes; at mid-span (the line's kink) the error
    halves as the modes double: −2.0 %, −1.0 %, −0.5 % at 20, 40, 80 modes."""
    a = np.array([L / 4, L / 3, 0.8 * L])
    exact = np.where(a <= L / 2, a / 2, (L - a) / 2)
    line = influence_line(_beam(10.0, 40), quantity="moment")
    assert np.allclose(np.interp(a, line.x, line.g), exact, rtol=1e-3)
    kink = [np.interp(L / 2, (il := influence_line(_beam(10.0, m), quantity="moment")).x, il.g) / (L / 4) - 1 for m in (20, 40, 80)]
    print("moment influence line at mid-span, 20/40/80 modes:", [f"{100 * e:+.2f} %" for e in kink])
    assert kink[0] < kink[1] < kink[2] < 0 and abs(kink[1]) < 0.011 and abs(kink[2]) < 0.006
    assert 1.8 < kink[0] / kink[1] < 2.2 and 1.8 < kink[1] / kink[2] < 2.2


@pytest.mark.parametrize("speed", [10.0, 75.0])
def test_the_recorded_moment_matches_frybas_series(speed):
    """The peak mid-span moment of a force crossing the beam, slow (10 m/s, quasi-static) and
    fast (75 m/s, speed parameter v/(2·n0·L) = 0.5): vtb's error shrinks with the modes and is
    within 0.5 % at 80 (measured −1.80/−0.90/−0.42 % at 10 m/s, −0.12/−0.03/+0.01 % at 75 m/s
    for 20/40/80 modes)."""
    t = np.arange(0.0, (GAP + L) / speed + 0.5, 1e-4)
    ref = float(np.max(np.abs(frýba_midspan_moment(speed, t))))
    errors = [vtb.simulate(_beam(speed, m), progress=False).metrics()["deck_moment_max"] / ref - 1 for m in (20, 40, 80)]
    print(f"{speed} m/s: closed form {ref:.6g} N·m; vtb at 20/40/80 modes", [f"{100 * e:+.3f} %" for e in errors])
    assert abs(errors[2]) < 0.005
    assert abs(errors[0]) > abs(errors[1]) > abs(errors[2]) or abs(errors[2]) < 1e-3
