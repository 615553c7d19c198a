"""The deck's bending moment on both Newmark engines (tests/test_bridge_moment.py holds it against
Frýba's series): the static moment influence line against beam theory (M = P·a·b/L, a train,
LM71) and the recorded moment at a slow speed against the same model's static one, on a 20 m
simply supported span; finite elements are exact at their nodes, the modal basis converges as
1/N (the sine series of a kinked moment). The slow run's small excess over the static moment is
dynamic: it shrinks in proportion to the speed (0.25 % at 0.25 m/s, 0.08 % at 0.0625 m/s on a
softer beam)."""

import math

import numpy as np
import pytest

import vtb
from vtb.bridge.load_trains import load_train
from vtb.bridge.static import LM71_AXLES, influence_line

L, M, N0, E = 20.0, 12000.0, 4.0, 3.5e10
EI = (2 * N0 * L**2 / math.pi) ** 2 * M
ONE = vtb.LoadTrain("one", (0.0,), (1e5,), "test")


def _beam(method="fem", n=100, speed=50.0, dt=1e-3):
    cfg = vtb.moving_load_config(L, 2500.0, M / 2500.0, E, EI / E, [vtb.MovingForce(1e5, 0.0)], speed, points=[L / 2],
                                 modes=n, dt=dt, initial_state="rest")
    if method == "fem":
        cfg.discretisation.method, cfg.discretisation.fem_elements = "fem", n
    return cfg


def _g(xs, x0):
    """Beam theory's moment influence line at x0 (N·m per N)."""
    return np.where((xs >= 0) & (xs <= L), np.where(xs <= x0, xs * (L - x0) / L, x0 * (L - xs) / L), 0.0)


def _train(t, x0):
    pos, p = np.asarray(t.positions), np.asarray(t.loads)
    fronts = np.concatenate([np.arange(0.0, L + t.length + 1e-3, 1e-3), x0 + pos])
    return float(np.max(_g(fronts[:, None] - pos[None, :], x0) @ p))


@pytest.mark.parametrize("x0", [4.0, 5.0, 10.0])
def test_static_moment_is_beam_theory_at_fe_nodes(x0):
    line = influence_line(_beam(), point=x0, quantity="moment", dx=0.2)  # samples on the nodes
    assert line.train(ONE) == pytest.approx(1e5 * x0 * (L - x0) / L, rel=1e-8)
    t = load_train("HSLM-A1")
    assert line.train(t) == pytest.approx(_train(t, x0), rel=1e-6)


def test_static_lm71_moment_is_beam_theory():
    """LM71 at mid-span: four axles centred anywhere (one on the point among them) and 80 kN/m
    beyond ±3.2 m of their centre, the largest moment by brute force on beam theory's line."""
    x0 = 10.0
    line = influence_line(_beam(), point=x0, quantity="moment", dx=0.2)
    xs = np.linspace(0.0, L, 40001)
    best = 0.0
    for c in np.concatenate([np.arange(-3.0, L + 3.0, 0.01), x0 - np.asarray(LM71_AXLES)]):
        out = (xs < c - 3.2) | (xs > c + 3.2)
        best = max(best, 250e3 * _g(c + np.asarray(LM71_AXLES), x0).sum() + 80e3 * np.trapezoid(np.where(out, _g(xs, x0), 0), xs))
    assert line.lm71() == pytest.approx(best, rel=2e-4)


@pytest.mark.parametrize("method,n", [("fem", 100), ("modal", 40), ("modal", 160)])
def test_slow_dynamic_moment_is_the_static_one(method, n):
    """At 0.25 m/s (v/(2·n0·L) = 0.0016) the recorded peak moment equals the same model's
    static influence-line moment within 0.3 % (measured +0.26 % on 100 elements), at every discretisation."""
    cfg = _beam(method, n, speed=0.25, dt=0.01)
    got = vtb.simulate(cfg, progress=False).metrics()["deck_moment_max"]
    static = influence_line(cfg, quantity="moment").train(ONE)
    print(f"{method} {n}: recorded {got:.1f}, static {static:.1f}, beam theory {1e5 * L / 4:.1f} N·m")
    assert got == pytest.approx(static, rel=3e-3)
