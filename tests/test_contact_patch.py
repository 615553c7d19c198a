"""The distributed Hertz contact (``vehicles[i].contact_patch``, docs/contact-patch.md): what it
needs and refuses, and what it does to a run. The patch's shape integrals and its Hertz
half-length are proven against independent quadrature and closed forms in the core's tests
(``cargo test``: basis::tests, contact::tests)."""

import numpy as np
import pytest

import vtb
from fuzz_cases import small_config


def converged_short(patch: bool, t_end: float = 0.02, point: float = 21.2) -> vtb.Config:
    """The converged preset on a smooth rail for ``t_end`` s, observed just ahead of the
    leading wheelset (x_front = 20.875 m), which crosses the point at t ≈ 4 ms."""
    cfg = vtb.paper_config(model="converged")
    cfg.irregularity = vtb.Irregularity(kind="none")
    cfg.vehicles[0].contact_patch = patch
    cfg.solver.t_end = t_end
    cfg.output.points = [point]
    return cfg


@pytest.mark.parametrize("method", ["modal", "hybrid"])
def test_a_patch_needs_a_finite_element_rail(method):
    cfg = small_config(tids=False)
    cfg.discretisation.method = method
    cfg.vehicles[0].contact_patch = True
    with pytest.raises(vtb.ConfigError) as e:
        vtb.simulate(cfg)
    assert e.value.field == "vehicles[0].contact_patch"


@pytest.mark.parametrize("bad", [0.0, -0.3, float("nan"), float("inf")])
def test_a_bad_crown_radius_names_the_field(bad):
    cfg = converged_short(True)
    cfg.vehicles[0].rail_crown_radius = bad
    with pytest.raises(vtb.ConfigError) as e:
        vtb.simulate(cfg)
    assert e.value.field == "vehicles[0].rail_crown_radius"


def test_the_patch_smooths_the_crossing_without_moving_the_band_below_2khz():
    # A wheel crossing a material point: the point contact's spike is cut by the patch, which
    # filters the rail's response by 3(sin ka − ka·cos ka)/(ka)³ along the rail (0.99 at
    # 500 Hz, 0.90 at 2 kHz for a = 6.4 mm at 80 m/s): the response low-passed at 500 Hz
    # moves by well under 1 %, and the static wheel load is carried as before.
    point, patch = (vtb.simulate(converged_short(p)) for p in (False, True))
    a_pt, a_pa = point.acceleration("rail"), patch.acceleration("rail")
    assert np.isfinite(a_pa).all()
    assert np.abs(a_pa).max() < 0.9 * np.abs(a_pt).max()
    dt = point.t[1] - point.t[0]
    lo_pt, lo_pa = (np.abs(vtb.low_pass(a, 500.0, dt)).max() for a in (a_pt, a_pa))
    assert lo_pa == pytest.approx(lo_pt, rel=0.01)
    # The contact carries the same static load; the displacement under the crossing agrees.
    assert patch.contact_force[0, 0] == pytest.approx(point.contact_force[0, 0], rel=1e-12)
    assert np.abs(patch.displacement("rail")).max() == pytest.approx(np.abs(point.displacement("rail")).max(), rel=2e-3)


def test_lockstep_jobs_on_patches_give_the_bits_of_single_runs():
    # The patch's port vectors are shared by the lanes of a batch (the patch of the static
    # load): jobs with different dampers and samples give bit for bit their single runs, and
    # their band-limited indices too.
    from vtb.article.tid_problem import case_config

    base = converged_short(True, t_end=0.01)
    base.output.band_limit = 2000.0
    base.irregularity = vtb.paper_irregularity(scale=vtb.config.presets.PAPER_CALIBRATED_SCALE)
    base.tids = vtb.tids_around(base, count=2, x=21.2)
    jobs = [case_config(base, *p) for p in ((5.0, 2e8, 1e3), (3.0, 1e8, 10.0), (8.0, 4e8, 1e4))]
    jobs[2].irregularity.seed = 11
    for c in jobs:
        c.output.indices = None  # every index, the labelled raw peak included
    alone = [vtb.simulate(c).metrics() for c in jobs]
    for lanes in (4, 2):
        out = vtb.simulate_batch(jobs, threads=1, lanes=lanes)
        for a, b in zip(alone, out):
            assert a.keys() == b.keys() and all(np.float64(a[k]).tobytes() == np.float64(b[k]).tobytes() for k in a)
    assert "rail_acc_max_raw" in alone[0]


def test_patch_half_length_solves_hertzs_ellipse_equations():
    # An independent solution of the same equations with SciPy's elliptic integrals.
    from scipy.optimize import brentq
    from scipy.special import ellipe, ellipk

    def scipy_half(p, rw, rr, e=2.1e11, nu=0.3):
        A, B = 0.5 / rw, 0.5 / rr
        es, lo, hi = e / (2 * (1 - nu**2)), min(A, B), max(A, B)
        m = brentq(lambda m: (ellipe(m) / (1 - m) - ellipk(m)) / (ellipk(m) - ellipe(m)) - hi / lo, 1e-14, 1 - 1e-14, xtol=1e-15)
        a = (3 * p * (ellipk(m) - ellipe(m)) / (2 * np.pi * lo * es * m)) ** (1 / 3)
        return a if A <= B else a * np.sqrt(1 - m)

    for p, rw, rr in ((72e3, 0.46, 0.3), (50e3, 0.43, 0.3), (100e3, 0.46, 0.8), (72e3, 0.46, 0.05)):
        assert vtb.contact_patch_half_length(p, rw, rr) == pytest.approx(scipy_half(p, rw, rr), rel=1e-7)
    for bad in (0.0, -1.0, float("nan"), float("inf")):
        with pytest.raises(vtb.ConfigError) as e:
            vtb.contact_patch_half_length(72e3, bad, 0.3)
        assert e.value.field == "wheel_radius"
