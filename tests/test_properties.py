"""Property-based tests (hypothesis) of the assembled model, linearity, and bad input."""

import copy
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

import vtb
from fuzz_cases import accept_implausible
from vtb import Config, Coupling, Layer, MovingForce, RayleighRatio, Solver, Structure
from vtb.errors import VtbError

LAYER_NAMES = ["l0", "l1", "l2", "l3"]


@st.composite
def structures(draw, methods=("modal",)):
    n_layers = draw(st.integers(1, 4))
    length = draw(st.floats(5.0, 60.0))
    layers = []
    for i in range(n_layers):
        layers.append(
            Layer(
                LAYER_NAMES[i],
                density=draw(st.floats(500.0, 9000.0)),
                area=draw(st.floats(1e-3, 10.0)),
                youngs_modulus=draw(st.floats(1e9, 3e11)),
                inertia=draw(st.floats(1e-6, 10.0)),
                modes=draw(st.integers(1, 12)),
                damping=RayleighRatio(draw(st.floats(0.0, 0.1)), 1.0, draw(st.floats(2.0, 500.0))),
            )
        )
    couplings = []
    for i in range(n_layers):
        lower = LAYER_NAMES[i + 1] if i + 1 < n_layers else "ground"
        k, c = draw(st.floats(1e5, 1e9)), draw(st.floats(0.0, 1e5))
        if draw(st.booleans()):
            couplings.append(Coupling(LAYER_NAMES[i], lower, "continuous", k, c))
        else:
            n = draw(st.integers(2, 40))
            couplings.append(Coupling(LAYER_NAMES[i], lower, "discrete", k, c, [length * j / (n - 1) for j in range(n)]))
    method = draw(st.sampled_from(methods))
    cfg = Config(structure=Structure(length, layers, couplings), speed=10.0, forces=[MovingForce(1e4, 0.0)])
    cfg.discretisation.method = method
    cfg.discretisation.fem_elements = draw(st.integers(2, 30))
    if n_layers >= 2 and draw(st.booleans()):
        count = draw(st.integers(1, 4))
        spacing = length / (count + 1)
        cfg.tids = vtb.TIDs(
            inertance=draw(st.floats(1e-3, 50.0)), stiffness=draw(st.floats(1e2, 1e9)), damping=draw(st.floats(0.0, 1e4)),
            count=count, x0=draw(st.floats(0.0, spacing)), spacing=spacing, upper="l0", lower="l1",
        )
    if method == "fem":
        # Per-layer meshes (nodes on the coupling points) and Timoshenko layers.
        for layer in layers:
            if draw(st.booleans()):
                layer.element_length = length / draw(st.integers(2, 40))
            if draw(st.booleans()):
                layer.shear_modulus = layer.youngs_modulus / draw(st.floats(2.0, 3.0))
                layer.shear_coefficient = draw(st.floats(0.3, 1.0))
    if method == "hybrid":
        layers[0].local_modes = draw(st.integers(1, 20))
        cfg.discretisation.omega_r = draw(st.floats(2 * np.pi * 10.0, 2 * np.pi * 5000.0))
        cfg.discretisation.fesea_coupling = draw(st.sampled_from(["full", "mass"]))
    return cfg


@settings(max_examples=90, deadline=None)
@given(structures(methods=("modal", "hybrid", "fem")))
def test_assembled_matrices_are_symmetric_and_definite(cfg):
    """M symmetric positive definite; K and C symmetric positive semi-definite, for every
    discretisation, the FE–SEA corrections included (random rigs opt out of the plausible
    ranges)."""
    mats = vtb.assembled_matrices(accept_implausible(cfg))
    for name in ("m", "k", "c"):
        a = mats[name]
        scale = np.abs(a).max()
        assert np.abs(a - a.T).max() <= 1e-12 * scale, name
    m, k, c = mats["m"], mats["k"], mats["c"]
    # Definiteness of the diagonally scaled matrices (units differ between DOFs).
    for name, a, strict in (("m", m, True), ("k", k, False), ("c", c, False)):
        d = np.sqrt(np.where(np.diag(a) > 0, np.diag(a), 1.0))
        w = np.linalg.eigvalsh(a / d[:, None] / d[None, :])
        if strict:
            assert w.min() > 0, name
        else:
            assert w.min() >= -1e-9 * w.max(), name


def _moving_force_config(p1, p2):
    layers = [Layer("rail", 7800, 7.745e-3, 2.1e11, 3.217e-5, 40, RayleighRatio(0.02, 5, 500)), Layer("slab", 2500, 0.51, 3.9e10, 1.7e-3, 20, RayleighRatio(0.05, 5, 500))]
    couplings = [Coupling.grid("rail", "slab", 6e7, 4.77e4, 0.64, 32.0), Coupling("slab", "ground", "continuous", 1e8, 1e5)]
    forces = [MovingForce(p1, 1.0)] + ([MovingForce(p2, 4.0)] if p2 is not None else [])
    # forces of any size: the linearity holds below the plausible wheel loads too
    accept = [f"forces[{i}].magnitude" for i in range(len(forces))]
    return Config(structure=Structure(32.0, layers, couplings), speed=50.0, forces=forces, solver=Solver(dt=1e-4, t_end=0.2), output=vtb.Output([10.0, 16.0]),
                  accept_implausible=accept)


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.floats(1e3, 2e5), st.floats(-3.0, 3.0))
def test_linear_case_scales_with_the_load(p, factor):
    """Without contact nonlinearity the response is linear: scaling the force scales every
    history, and two forces superpose. (Accelerations come from Newmark's recursion
    a_{n+1} = 4(v̄ − v_n)/Δt − a_n, which carries round-off of about 1e−8 of the peak.)"""
    assume(abs(factor) > 1e-3)
    a = vtb.simulate(_moving_force_config(p, None))
    b = vtb.simulate(_moving_force_config(factor * p, None))
    for x, y, tol in ((a.disp, b.disp, 1e-12), (a.acc, b.acc, 1e-7)):
        assert np.abs(factor * x - y).max() <= tol * np.abs(y).max()
    two = vtb.simulate(_moving_force_config(p, factor * p))
    other = copy.deepcopy(_moving_force_config(p, factor * p))
    other.forces, other.accept_implausible = [other.forces[1]], ["forces[0].magnitude"]
    o = vtb.simulate(other)
    assert np.abs(a.disp + o.disp - two.disp).max() <= 1e-12 * np.abs(two.disp).max()
    assert np.abs(a.acc + o.acc - two.acc).max() <= 1e-7 * np.abs(two.acc).max()


@pytest.mark.parametrize(
    "mutate,field",
    [
        (lambda c: setattr(c.vehicles[0], "m_c", -1.0), "vehicles[0].m_c"),
        (lambda c: setattr(c.vehicles[0], "k_p", float("nan")), "vehicles[0].k_p"),
        (lambda c: setattr(c.structure.layers[1], "density", 0.0), "structure.layers[1].density"),
        (lambda c: setattr(c.structure.couplings[0], "stiffness", -5.0), "structure.couplings[0].stiffness"),
        (lambda c: setattr(c.solver, "dt", 0.0), "solver.dt"),
        (lambda c: setattr(c.solver, "dt", -1e-5), "solver.dt"),
        (lambda c: setattr(c.structure.layers[0], "modes", 0), "structure.layers[0].modes"),
        (lambda c: setattr(c.vehicles[0], "x_front", float("inf")), "vehicles[0].x_front"),
        (lambda c: setattr(c.solver, "tail", -0.1), "solver.tail"),
        (lambda c: setattr(c.structure.layers[3], "start", 10.0), "structure.layers[3].start"),
        (lambda c: setattr(c, "speed", -80.0), "speed"),
        (lambda c: setattr(c.irregularity, "wavelength_min", 0.005), "irregularity.wavelength_min"),
        (lambda c: setattr(c.irregularity, "seed", -5), "irregularity.seed"),
        (lambda c: setattr(c.structure.couplings[0], "upper", "nope"), "structure.couplings[0].upper"),
        (lambda c: setattr(c.output, "points", [500.0]), "output.points[0]"),
        (lambda c: setattr(c, "tids", vtb.TIDs(5.0, 0.0, 1e3, 1, 80.0, 0.64)), "tids.stiffness"),
        (lambda c: setattr(c, "tids", vtb.TIDs(-1.0, 2e8, 1e3, 1, 80.0, 0.64)), "tids.inertance"),
        (lambda c: setattr(c, "tids", vtb.TIDs(5.0, 2e8, 1e3, 0, 80.0, 0.64)), "tids.count"),
        (lambda c: setattr(c, "tids", vtb.TIDs(5.0, 2e8, 1e3, 3, 159.5, 0.64)), "tids.count"),
        (lambda c: setattr(c, "tids", vtb.TIDs(5.0, 2e8, 1e3, 1, 80.0, 0.64, lower="nope")), "tids.lower"),
    ],
)
def test_bad_fields_are_named(mutate, field):
    cfg = vtb.paper_config()
    mutate(cfg)
    with pytest.raises(vtb.ConfigError) as e:
        vtb.simulate(cfg)
    assert e.value.field == field
