"""Each car of a 3-car consist against an independent solution of the same equations.

The consist (three Velaro E cars from `vtb.train`, different cars of the formation) runs on
the rigid track before the structure (docs/zones.md) over a smooth rail bump, so its cars are
independent 10-DOF vehicles on Hertz springs. Zhai's vertical car is coded here from its
textbook form (car body and bogie bounce and pitch, primary and secondary spring–dashpots,
one nonlinear Hertz spring per wheelset carrying 1/rails of the axle load on the modelled
rail), brought to its static equilibrium by a root finder and integrated by SciPy's DOP853 at
tight tolerances — no vtb code is used — and compared with vtb's Newmark run car by car.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import fsolve

import vtb

X_FRONT = -200.0  # the whole run stays before the structure: a rigid track
BUMP_START, BUMP_LENGTH, BUMP_HEIGHT = -190.0, 3.0, 1e-3  # a 1 − cos bump on the rail (m)
DT, T_END = 2e-5, 1.3


def bump(x):
    """Rail-top irregularity r(x) (m, dip positive): a raised bump of BUMP_HEIGHT."""
    s = np.clip((np.asarray(x) - BUMP_START) / BUMP_LENGTH, 0.0, 1.0)
    return -0.5 * BUMP_HEIGHT * (1.0 - np.cos(2.0 * np.pi * s))


def _car_equations(v, g, x_front, under=None, speed=80.0):
    """The car's equations; ``under(x)``: the irregularity under its four wheels at their
    positions x (m, dip positive), default the rail bump."""
    under = under or bump
    m = np.array([v.m_c, v.j_c, v.m_t, v.j_t, v.m_t, v.j_t] + [v.m_w] * 4)
    bogie = [v.l_c, -v.l_c]  # bogie offsets from the car centre (front first)
    wheel = [(0, v.l_t), (0, -v.l_t), (1, v.l_t), (1, -v.l_t)]  # (bogie, offset) per wheelset
    G = v.contact_constant or 4.57e-8 * v.wheel_radius ** -0.149
    x_wheels = np.array([x_front, x_front - 2 * v.l_t, x_front - 2 * v.l_c, x_front - 2 * v.l_c - 2 * v.l_t])

    def forces(t, z, zd):
        f = np.zeros(10)
        f[[0, 2, 4, 6, 7, 8, 9]] = m[[0, 2, 4, 6, 7, 8, 9]] * g
        for i, s in enumerate(bogie):  # secondary: bogie i against the car body at s
            e = z[2 + 2 * i] - (z[0] + s * z[1])
            ed = zd[2 + 2 * i] - (zd[0] + s * zd[1])
            q = v.k_s * e + v.c_s * ed
            f[2 + 2 * i] -= q
            f[0] += q
            f[1] += s * q
        for j, (i, a) in enumerate(wheel):  # primary: wheelset j against bogie i at a
            e = z[6 + j] - (z[2 + 2 * i] + a * z[3 + 2 * i])
            ed = zd[6 + j] - (zd[2 + 2 * i] + a * zd[3 + 2 * i])
            q = v.k_p * e + v.c_p * ed
            f[6 + j] -= q
            f[2 + 2 * i] += q
            f[3 + 2 * i] += a * q
        delta = z[6:] - under(x_wheels + speed * t)
        p = np.where(delta > 0, np.maximum(delta, 0.0) / G, 0.0) ** 1.5
        f[6:] -= v.rails * p
        return f, p

    def rhs(t, y):
        f, _ = forces(t, y[:10], y[10:])
        return np.concatenate([y[10:], f / m])

    z0 = fsolve(lambda z: forces(0.0, z, np.zeros(10))[0], np.full(10, 1e-3), xtol=1e-14)
    return rhs, forces, z0


@pytest.fixture(scope="module")
def consist():
    cfg = vtb.paper_config()
    cfg.vehicles = vtb.train("velaro_e", cars=3, x_front=X_FRONT)
    values = bump(np.arange(-300.0, -50.0, 0.01))
    cfg.irregularity = vtb.Irregularity(kind="sampled", x0=-300.0, dx=0.01, values=list(values))
    cfg.solver.fade_in = 0.0
    cfg.solver.dt = DT
    cfg.solver.t_end = T_END
    cfg.accept_implausible = [f"vehicles[{i}].x_front" for i in range(3)]  # meant to stay off the structure
    return cfg, vtb.simulate(cfg, progress=False)


@pytest.mark.parametrize("car", [0, 1, 2])
def test_each_car_of_a_consist_matches_an_independent_solution(consist, car):
    cfg, r = consist
    v = cfg.vehicles[car]
    rhs, forces, z0 = _car_equations(v, cfg.solver.gravity, v.x_front)
    sol = solve_ivp(rhs, (0.0, T_END), np.concatenate([z0, np.zeros(10)]), method="DOP853",
                    rtol=1e-10, atol=1e-13, t_eval=r.t, max_step=1e-3)
    assert sol.success
    z = sol.y[:10].T
    p = np.array([forces(t, zi, zdi)[1] for t, zi, zdi in zip(sol.t, z, sol.y[10:].T)])
    static = (v.m_c / 4 + v.m_t / 2 + v.m_w) * cfg.solver.gravity / v.rails
    # The bump reaches every wheel of the car within the run and loads it well off its static value.
    got_p = r.contact_force[:, 4 * car:4 * car + 4]
    assert np.all(np.ptp(got_p, axis=0) > 0.2 * static)
    np.testing.assert_allclose(got_p, p, atol=2e-3 * static)
    # Car body and bogie bounce (relative to the static state), and each wheelset.
    for k in (0, 2, 4, 6, 7, 8, 9):
        want = z[:, k] - z0[k]
        np.testing.assert_allclose(r.vehicle_disp[:, car, k], want, atol=2e-3 * np.abs(want).max())


def test_a_wheel_flat_matches_an_independent_solution():
    """A 50 mm rounded flat (depth L²/16R, Wu & Thompson's worn shape) on the second wheelset
    of one car at 80 m/s on the rigid track: three impacts, one per wheel revolution, each
    unloading the wheel and striking it back. The flat is coded here from its formula and
    rolled by the exact geometry, under that wheel only, and the car integrated by DOP853;
    vtb's run (the flat's wheel-centre path sampled on its grid and carried as that wheel's
    tread row) matches it force by force: the impact peak (1.47 × the static load) within
    0.1 %, every wheel's force within 0.5 % of the static load."""
    length, x_flat, flat_wheel = 0.05, -199.0, 1
    cfg = vtb.paper_config()
    v = cfg.vehicles[0]
    v.x_front = X_FRONT
    cfg.accept_implausible = ["vehicles[0].x_front"]  # on the rigid track alone, as meant
    cfg.irregularity = vtb.Irregularity(kind="wheel_flat", wheel=flat_wheel, length=length, position=x_flat)
    cfg.solver.fade_in = 0.0
    cfg.solver.dt = 1e-5
    cfg.solver.t_end = 0.1
    r = vtb.simulate(cfg, progress=False)
    radius = v.wheel_radius
    depth = length**2 / (16 * radius)
    # The wheel centre's drop as the dented tread rolls on the rail, by the exact rolling
    # geometry: a tread of radius ρ(θ) = R − dent(Rθ) turned by φ = u/R holds its centre
    # max_θ ρ(θ)·cos(θ − φ) above the rail.
    theta = np.linspace(-length / radius, length / radius, 20001)
    rho = radius - np.where(np.abs(theta) <= 0.5 * length / radius, 0.5 * depth * (1 + np.cos(2 * np.pi * radius * theta / length)), 0.0)
    u_tab = np.linspace(-length, length, 4001)
    drop = np.array([radius - np.max(rho * np.cos(theta - p)) for p in u_tab / radius])

    def under(x):
        u = np.mod(x - x_flat + np.pi * radius, 2 * np.pi * radius) - np.pi * radius
        return np.where(np.arange(4) == flat_wheel, np.interp(u, u_tab, drop, left=0.0, right=0.0), 0.0)

    rhs, forces, z0 = _car_equations(v, cfg.solver.gravity, v.x_front, under=under, speed=cfg.speed)
    sol = solve_ivp(rhs, (0.0, 0.1), np.concatenate([z0, np.zeros(10)]), method="DOP853",
                    rtol=1e-10, atol=1e-13, t_eval=r.t, max_step=2e-5)
    assert sol.success
    p = np.array([forces(t, zi, zdi)[1] for t, zi, zdi in zip(sol.t, sol.y[:10].T, sol.y[10:].T)])
    got = r.contact_force[:, :4]
    static = (v.m_c / 4 + v.m_t / 2 + v.m_w) * cfg.solver.gravity / v.rails
    # Three revolutions' impacts: the flat wheel loses contact and is struck back well above
    # its static load, the other wheels barely notice.
    assert np.sum(np.diff((p[:, flat_wheel] == 0).astype(int)) == 1) == 3
    assert p[:, flat_wheel].max() > 1.4 * static
    assert got[:, flat_wheel].max() == pytest.approx(p[:, flat_wheel].max(), rel=1e-3)
    # Measured: 0.07 % of the static load at worst.
    np.testing.assert_allclose(got, p, atol=5e-3 * static)
