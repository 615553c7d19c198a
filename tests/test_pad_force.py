"""The rail fastener (pad) force: ``output.pad_forces`` records the force in the fastener nearest
each observation point, reported as ``pad{j}_force_range`` (the load range of a fatigue check).
Held against statics (the pads under a standing load carry it all), against the receptance-free
closed form of a rail on an elastic foundation, and between the engines (the synthesis against
the finite elements it reduces)."""

import warnings

import numpy as np
import pytest

import vtb
from vtb.run import synthesis

P = 1.0e5  # N


def standing_load(x=80.16, reach=30.0, model="converged"):
    """The converged track under a force P standing at ``x``, observed at every fastener within
    ``reach`` of it."""
    c = vtb.paper_config(model=model)
    c.vehicles, c.speed = [], 0.0
    c.forces = [vtb.MovingForce(P, x)]
    c.solver.t_end = 0.005
    c.output.points = [p for p in c.structure.couplings[0].positions if abs(p - x) < reach]
    c.output.pad_forces = True
    return c


def test_the_pads_under_a_standing_load_carry_all_of_it():
    """Statics: the rail rests on its fasteners alone, so their forces sum to the load (to
    4e-6 with every fastener within 30 m; 1e-4 within 10 m, the tail of the slab's bending)."""
    r = vtb.simulate(standing_load(), progress=False)
    assert r.pad_force.shape == (r.t.size, len(r.points))
    assert r.pad_force[0].sum() == pytest.approx(P, rel=1e-5)
    # standing still: the forces hold
    assert np.allclose(r.pad_force[-1], r.pad_force[0], rtol=1e-9, atol=1e-6 * P)
    m = r.metrics()
    assert all(m[f"pad{j}_force_range"] < 1e-6 * P for j in range(len(r.points)))


def test_the_largest_pad_force_is_near_the_elastic_foundation_closed_form():
    """A rail on continuous springs k = k_pad/d (Winkler, Euler–Bernoulli) gives its largest
    support force P·d·β/2, β = (k/4EI)^(1/4); the discrete, Timoshenko rail on a slab that gives
    way is within 5 % of it."""
    c = standing_load(x=80.0, reach=2.0)
    rail, pads = c.structure.layers[0], c.structure.couplings[0]
    d = pads.positions[1] - pads.positions[0]
    beta = (pads.stiffness / d / (4 * rail.youngs_modulus * rail.inertia)) ** 0.25
    r = vtb.simulate(c, progress=False)
    assert r.pad_force[0].max() == pytest.approx(P * d * beta / 2, rel=0.05)


def test_pad_forces_are_opt_in_and_named_by_point():
    c = standing_load(reach=1.0)
    names = vtb.index_names(c)
    assert [n for n in names if n.startswith("pad")] == [f"pad{j}_force_range" for j in range(len(c.output.points))]
    assert vtb.run.indices.metric_unit("pad3_force_range") == "N"
    c.output.pad_forces = False
    assert not any(n.startswith("pad") for n in vtb.index_names(c))
    r = vtb.simulate(c, progress=False)
    assert r.pad_force.shape == (r.t.size, 0)


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    mp = pytest.MonkeyPatch()
    mp.setenv(synthesis.CACHE_ENV, str(tmp_path_factory.mktemp("cache")))
    yield
    mp.undo()


def test_the_synthesis_records_the_pads_of_the_finite_elements(cache):
    """The car's leading wheelset rolls by two fasteners of one span: the synthesis' pad
    forces (its ends' displacements and velocities from the modes, the residual and the
    force's direct term) against the finite elements' (Newmark at Δt = 2.5e-5 s): force ranges
    within 1 % (measured 0.3 %), histories within 2 % of the range (measured 1.3 %)."""
    c = vtb.paper_config(model="fast", calibrated=True)
    c = vtb.spans(c, [32.0])
    c.solver.t_end = 0.05
    c.output.points = [20.48, 21.0]  # the wheelset runs from 20.9 to 24.9 m
    c.output.pad_forces = True
    fem = c.copy()
    fem.discretisation.synthesis_cutoff = None
    fem.solver.dt = 2.5e-5
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        a, b = vtb.simulate(c, progress=False), vtb.simulate(fem, progress=False)
    ma, mb = a.metrics(), b.metrics()
    for j in range(2):
        assert ma[f"pad{j}_force_range"] == pytest.approx(mb[f"pad{j}_force_range"], rel=0.01), j
        fb = b.pad_force[::2, j]
        assert np.abs(a.pad_force[:, j] - fb).max() < 0.02 * np.ptp(fb), j
