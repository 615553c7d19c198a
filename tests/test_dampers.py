"""Damper kinds and groups (docs/dampers.md) against independent solutions: the closed-form
receptance of a primary with each kind, an ODE integration of the same equations by SciPy,
and groups of several kinds against the finite elements."""

import math
import re
import warnings

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import vtb
from fuzz_cases import accept_implausible
from vtb import Config, Coupling, Layer, MovingForce, RayleighRatio, Structure

M, K_S = 100.0, 1e6  # the primary: ω_s = 100 rad/s
W_S = math.sqrt(K_S / M)


def _primary(kind: str, b: float, k: float, c: float, **solver) -> Config:
    """A rigid 100 kg beam on two springs (its translation is the primary) with one grounded
    damper and a 1 kN force at its centre, FEM with two elements so x = 0.5 m is node 1."""
    rail = Layer("rail", density=M / 0.01, area=0.01, youngs_modulus=1e11, inertia=1.0, modes=1, damping=RayleighRatio(0.0, 1.0, 2.0))
    cfg = Config(structure=Structure(1.0, [rail], [Coupling("rail", "ground", "discrete", K_S / 2, 0.0, [0.0, 1.0])]),
                 speed=1e-3, forces=[MovingForce(1e3, 0.5)])
    cfg.discretisation.method = "fem"
    cfg.discretisation.fem_elements = 2
    cfg.dampers = [vtb.DamperGroup(kind=kind, inertance=b, stiffness=k, damping=c, positions=[0.5], lower="ground")]
    cfg.solver.t_end = 0.1
    for key, value in solver.items():
        setattr(cfg.solver, key, value)
    return accept_implausible(cfg)


def _device_stiffness(kind: str, b: float, k: float, c: float, w: np.ndarray) -> np.ndarray:
    """Dynamic stiffness of a grounded device, its two branches in series (Z_u·Z_l/(Z_u + Z_l))."""
    inerter = -(w**2) * b
    upper, lower = {"tid": (k + 1j * w * c, inerter), "tmd": (k + 1j * w * c, inerter),
                    "tvmd": (k + 0j * w, inerter + 1j * w * c)}[kind]
    return upper * lower / (upper + lower)


TUNING = dict(b=5.0, k=5.0 * (0.95 * W_S) ** 2, c=150.0)


@pytest.mark.parametrize("kind", ["tid", "tvmd", "tmd"])
def test_each_kind_has_the_closed_form_receptance(kind):
    """X/F at the primary from the assembled matrices (the stamp) against
    1/(k_s − ω²m + Z(ω)), Z the device's two branches in series."""
    cfg = _primary(kind, **TUNING)
    mats = vtb.assembled_matrices(cfg)
    m, k, c = mats["m"], mats["k"], mats["c"]
    f = np.zeros(len(m))
    f[2] = 1.0  # node 1 (x = 0.5 m), displacement DOF
    w = np.linspace(0.5, 1.5, 301) * W_S
    got = np.array([np.linalg.solve(k - wi**2 * m + 1j * wi * c, f)[2] for wi in w])
    want = 1.0 / (K_S - w**2 * M + _device_stiffness(kind, TUNING["b"], TUNING["k"], TUNING["c"], w))
    assert np.max(np.abs(got / want - 1.0)) < 1e-6


def _ode(kind: str, b: float, k: float, c: float, force: float, t: np.ndarray) -> np.ndarray:
    """The primary's displacement from rest under a step force: m·ü + k_s·u = F − F_d, the
    device's node z (massless, between the branches) from F_d through both branches."""
    def rhs(_, y):
        u, v, z, zd = y
        if kind == "tvmd":  # k(u − z) = b·z̈ + c·ż
            fd = k * (u - z)
            zdd = (fd - c * zd) / b
        else:  # k(u − z) + c(u̇ − ż) = b·z̈
            fd = k * (u - z) + c * (v - zd)
            zdd = fd / b
        return [v, (force - K_S * u - fd) / M, zd, zdd]

    sol = solve_ivp(rhs, (0.0, t[-1]), [0.0] * 4, method="DOP853", t_eval=t, rtol=1e-11, atol=1e-15)
    return sol.y[0]


@pytest.mark.parametrize("kind", ["tid", "tvmd", "tmd"])
def test_each_kind_steps_like_an_independent_ode_solution(kind):
    """From rest under the 1 kN step: the coupled step's eliminated node against SciPy's
    DOP853 on the same three-body equations, within 0.3 % of the peak at Δt = 1e-4 s
    (the average-acceleration rule's period error at ω·Δt = 0.01 is 1e-5 per cycle)."""
    cfg = _primary(kind, **TUNING, dt=1e-4, t_end=0.3, initial_state="rest")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", vtb.ResolutionWarning)
        res = vtb.simulate(cfg, progress=False)
    got = res.displacement("rail")
    want = _ode(kind, TUNING["b"], TUNING["k"], TUNING["c"], 1e3, res.t)
    assert np.max(np.abs(got - want)) < 3e-3 * np.max(np.abs(want))


def test_kinds_differ_where_the_dashpot_sits():
    """The same numbers as TID and TVMD are different devices: their receptances differ
    by more than the tolerance above (the test would catch a kind ignored)."""
    w = np.linspace(0.5, 1.5, 301) * W_S
    tid, tvmd = (1.0 / (K_S - w**2 * M + _device_stiffness(k, TUNING["b"], TUNING["k"], TUNING["c"], w)) for k in ("tid", "tvmd"))
    assert np.max(np.abs(tid / tvmd - 1.0)) > 0.1


def test_groups_of_several_kinds_and_explicit_positions_match_the_finite_elements():
    """The article's TIDs plus a TVMD group at explicit positions and a TMD on the bridge,
    on the default (synthesis) model against the finite elements within the tolerances of
    the single-kind check (tests/test_synthesis.py)."""
    from test_synthesis import assert_matches_the_finite_elements, one_span

    c = one_span()
    c.tids = vtb.tids_around(c, inertance=3.0, stiffness=1.46e8, damping=1e3, count=2, x=12.8)
    c.dampers = [
        vtb.DamperGroup(kind="tvmd", inertance=4.0, stiffness=1.2e8, damping=2e3, positions=[11.84, 13.76]),
        vtb.DamperGroup(kind="tmd", inertance=500.0, stiffness=500.0 * (2 * math.pi * 8.0) ** 2, damping=400.0,
                        positions=[16.0], upper=c.structure.layers[-1].name, lower="ground"),
    ]
    assert_matches_the_finite_elements(c)


def test_a_group_is_refused_naming_its_path():
    c = vtb.paper_config()
    good = dict(inertance=3.0, stiffness=1e8, damping=1e3)
    cases = [
        (vtb.DamperGroup(**good, positions=[10.0, 170.0]), "dampers[0].positions[1]"),
        (vtb.DamperGroup(**good), "dampers[0].count"),
        (vtb.DamperGroup(**good, count=3), "dampers[0].x0"),
        (vtb.DamperGroup(**good, count=3, x0=1.0), "dampers[0].spacing"),
        (vtb.DamperGroup(**good, count=1, x0=1.0, positions=[2.0]), "dampers[0].positions"),
        (vtb.DamperGroup(**good, positions=[]), "dampers[0].positions"),
        (vtb.DamperGroup(**good, kind="tmd", positions=[10.0]), "dampers[0].lower"),
        (vtb.DamperGroup(**good, positions=[10.0], upper="deck"), "dampers[0].upper"),
        (vtb.DamperGroup(**{**good, "damping": -1.0}, positions=[10.0]), "dampers[0].damping"),
    ]
    cases.append((vtb.DamperGroup(**good, kind="viscous", positions=[1.0]), "dampers[0].kind"))
    for group, field in cases:
        d = c.copy()
        d.dampers = [group]
        with pytest.raises(vtb.ConfigError, match=re.escape(field)):
            d.validate()


def test_a_study_varies_any_groups_parameters():
    """``vtb.study`` over ``dampers[1].stiffness`` (a TVMD group after a TMD group): each case
    is the run of its own configuration, and the parameter changes the result."""
    c = _primary("tmd", **TUNING, dt=1e-4, t_end=0.1, initial_state="rest")
    c.dampers.append(vtb.DamperGroup(kind="tvmd", inertance=2.0, stiffness=1e4, damping=50.0, positions=[0.25], lower="ground"))
    values = [1e4, 3e4]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", vtb.ResolutionWarning)
        res = vtb.study(c, {"dampers[1].stiffness": values}, indices=["rail_disp_max"], progress=False, threads=1)
        alone = []
        for k in values:
            d = c.copy()
            d.dampers[1].stiffness = k
            alone.append(vtb.simulate(d, progress=False).metrics()["rail_disp_max"])
    col = res.columns
    got = [col["rail_disp_max"][list(col["dampers[1].stiffness"]).index(k)] for k in values]
    assert got == pytest.approx(alone, rel=1e-12)
    assert abs(alone[0] / alone[1] - 1.0) > 1e-4
