"""The quarter car (moving sprung mass) against an independent solution of the same equations.

The classical vehicle–bridge interaction problem (the sprung mass of Yang & Wu 2001, Biggs'
moving oscillator): a sprung mass on a spring ∥ dashpot over a wheel on a nonlinear Hertz
spring, crossing a simply supported Euler–Bernoulli girder. The reference is coded here from
the textbook form — the girder by its sine modes (Galerkin), the vehicle by Newton's law, the
Hertz force P = (δ/G)^1.5 — and integrated by SciPy's DOP853 at tight tolerances; no vtb code
is used. vtb runs the same case through its own quarter-car model and modal girder.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import vtb
from fuzz_cases import accept_implausible

L, RHO, AREA, E, INERTIA = 32.0, 2500.0, 8.75, 3.945e10, 9.25  # the article's 32 m girder
EI, MASS = E * INERTIA, RHO * AREA
SPRUNG, WHEEL, K_V, C_V = 13_600.0, 2_400.0, 1.0e6, 4.0e4  # a quarter of a high-speed car
SPEED, MODES, G = 80.0, 30, 9.81


def reference(speed=SPEED, modes=MODES, hertz_g=4.57e-8 * 0.46 ** -0.149):
    """Midspan deflection (m), sprung-mass acceleration (m/s², z down) and contact force (N)
    from the independent modal solution, as functions of t."""
    n = np.arange(1, modes + 1)
    wn = (n * np.pi / L) ** 2 * math.sqrt(EI / MASS)
    mmod = MASS * L / 2.0
    p0 = (SPRUNG + WHEEL) * G
    zw0 = hertz_g * p0 ** (2.0 / 3.0)  # the wheel enters over the support: the girder at rest
    z0 = np.concatenate([np.zeros(modes), [SPRUNG * G / K_V + zw0, zw0], np.zeros(modes + 2)])

    def contact(t, y):
        phi = np.sin(n * np.pi * speed * t / L)
        delta = y[modes + 1] - phi @ y[:modes]
        return (max(delta, 0.0) / hertz_g) ** 1.5, phi

    def rhs(t, y):
        q, zc, zw = y[:modes], y[modes], y[modes + 1]
        dq, dzc, dzw = y[modes + 2:2 * modes + 2], y[2 * modes + 2], y[2 * modes + 3]
        p, phi = contact(t, y)
        s = K_V * (zc - zw) + C_V * (dzc - dzw)
        acc_q = p * phi / mmod - wn**2 * q
        return np.concatenate([dq, [dzc, dzw], acc_q, [(SPRUNG * G - s) / SPRUNG, (WHEEL * G + s - p) / WHEEL]])

    sol = solve_ivp(rhs, (0.0, L / speed), z0, method="DOP853", rtol=1e-10, atol=1e-13, dense_output=True)
    assert sol.success

    def at(t):
        y = sol.sol(t)
        mid = np.sin(n * np.pi / 2) @ y[:modes]
        acc = np.array([rhs(ti, y[:, i])[modes + modes + 2] for i, ti in enumerate(t)])
        force = np.array([contact(ti, y[:, i])[0] for i, ti in enumerate(t)])
        return mid, acc, force

    return at


@pytest.fixture(scope="module")
def runs():
    cfg = vtb.moving_load_config(L, RHO, AREA, E, INERTIA, [], SPEED, modes=MODES, dt=2e-5, t_end=L / SPEED, points=[L / 2])
    cfg.vehicles = [vtb.Vehicle.quarter_car(SPRUNG, WHEEL, K_V, C_V, x_front=0.0, rails=1)]
    return vtb.simulate(accept_implausible(cfg), progress=False), reference()


def test_a_quarter_car_on_a_girder_matches_an_independent_modal_solution(runs):
    """Midspan deflection, contact force and the sprung mass's acceleration over the whole
    crossing within 0.5 % of their ranges."""
    res, ref = runs
    t = res.t[1:]
    mid, acc, force = ref(t)
    sim_mid = res.displacement("beam")[1:] - res.displacement("beam")[0]
    assert np.max(np.abs(sim_mid - mid)) < 0.005 * np.max(np.abs(mid))
    assert np.max(np.abs(res.contact_force[1:, 0] - force)) < 0.005 * np.ptp(force)
    body = res.vehicle_acc[1:, 0, 0]
    assert np.max(np.abs(body - acc)) < 0.005 * np.max(np.abs(acc))
    # The result's shapes come from the model: two DOFs, one wheel.
    assert res.vehicle_disp.shape[2] == 2 and res.contact_force.shape[1] == 1
    assert res.config.vehicles[0].dofs == ("Z_c", "Z_w")


def test_a_quarter_car_carries_only_its_own_fields():
    """A quarter car's table has no bogie or pitch fields: a value there is an unknown field,
    named; a file written when quarter cars held the car's fields at 0 still loads, the zeros
    dropped with a DeprecationWarning."""
    cfg = vtb.paper_config()
    cfg.vehicles = [vtb.Vehicle.quarter_car(11000.0, 1200.0, 1.2e6, 3e4, x_front=3.0)]
    table = cfg.to_dict()
    assert table["vehicles"][0]["model"] == "quarter_car" and "l_c" not in table["vehicles"][0]
    old = dict(table, vehicles=[dict(table["vehicles"][0], j_c=0.0, l_c=0.0, l_t=0.0)])
    with pytest.warns(DeprecationWarning, match="l_c"):
        assert vtb.Config.from_dict(old).vehicles == cfg.vehicles
    bad = dict(table, vehicles=[dict(table["vehicles"][0], l_c=8.0)])
    with pytest.raises(vtb.ConfigError, match=r"vehicles\[0\]\.l_c"):
        vtb.Config.from_dict(bad)
