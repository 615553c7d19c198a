"""The FE–SEA hybrid (docs/model.md §6) through the public API.

Independent checks: the local modes' frequencies and loss factors are recomputed here from the
beam and fastener data (pinned–pinned sines on discrete springs); the displacement recovery is
recomputed in numpy from the recorded contact forces; the hybrid is compared with the FEM model.
The frequency-domain check against exact condensation is in the Rust core
(`fesea::tests::full_coupled_correction_matches_band_averaged_exact_condensation`).
"""

import math

import numpy as np
import pytest

import vtb
from vtb.errors import ConfigError


@pytest.fixture(scope="module")
def paper():
    return vtb.paper_config()


@pytest.fixture(scope="module")
def report(paper):
    return vtb.fesea_report(paper)


def _rail_springs(cfg):
    rail = cfg.structure.layers[0].name
    return [c for c in cfg.structure.couplings if c.upper == rail]


def test_local_modes_match_a_pinned_beam_on_discrete_springs(paper, report):
    """ω_n² = EI(nπ/L)⁴/ρA + Σ_f k_f·s_n(x_f)², c_n = α + β·EI(nπ/L)⁴/ρA + Σ_f c_f·s_n(x_f)² for
    mass-normalised sines s_n = sqrt(2/(ρAL))·sin(nπx/L); η_n = c_n/ω_n."""
    rail = paper.structure.layers[0]
    L = paper.structure.length
    rho_a, ei = rail.density * rail.area, rail.youngs_modulus * rail.inertia
    d = rail.damping
    w1, w2 = 2 * math.pi * d.f1, 2 * math.pi * d.f2
    alpha, beta = 2 * d.ratio * w1 * w2 / (w1 + w2), 2 * d.ratio / (w1 + w2)
    n = np.arange(rail.modes + 1, rail.modes + rail.local_modes + 1)
    assert np.array_equal(report.modes["index"], n)
    bend = ei * (n * math.pi / L) ** 4 / rho_a
    k, c = bend.copy(), alpha + beta * bend
    for sp in _rail_springs(paper):
        s2 = (2 / (rho_a * L)) * np.sin(np.outer(n, sp.positions) * math.pi / L) ** 2
        k += sp.stiffness * s2.sum(axis=1)
        c += sp.damping * s2.sum(axis=1)
    omega = np.sqrt(k)
    np.testing.assert_allclose(report.modes["omega"], omega, rtol=1e-10)
    np.testing.assert_allclose(report.modes["frequency"], omega / (2 * math.pi), rtol=1e-10)
    np.testing.assert_allclose(report.modes["loss_factor"], c / omega, rtol=1e-10)
    np.testing.assert_allclose(report.modes["mass"], 1.0)


def test_classes_follow_the_band_and_the_default_omega_r(paper, report):
    """Default ω_r: 2π·v/sqrt(λ_min·λ_max) of the irregularity band; classes by the band B."""
    irr = paper.irregularity
    assert report.omega_r == pytest.approx(2 * math.pi * paper.speed / math.sqrt(irr.wavelength_min * irr.wavelength_max))
    lo, hi = report.band
    assert lo < report.omega_r < hi
    expect = ["below" if w < lo else "resonant" if w <= hi else "above" for w in report.modes["omega"]]
    assert list(report.modes["class"]) == expect
    counts = report.counts()
    assert sum(counts.values()) == paper.structure.layers[0].local_modes
    assert counts["resonant"] / (hi - lo) == pytest.approx(report.modal_density)
    assert "resonant" in str(report)


def test_corrections_are_symmetric_and_the_coupling_option_is_honoured(paper, report):
    for m in (report.delta_m, report.delta_k, report.delta_c):
        np.testing.assert_allclose(m, m.T, rtol=1e-12, atol=1e-12 * np.abs(m).max())
    # Removing local content takes mass from the cubic functions.
    assert np.all(np.diag(report.delta_m) <= 0.0)
    cfg = paper.copy()
    cfg.discretisation.fesea_coupling = "mass"
    mass = vtb.fesea_report(cfg)
    assert mass.coupling == "mass" and report.coupling == "full"
    # The article's reading has no stiffness correction.
    assert np.all(mass.delta_k == 0.0)
    cfg.discretisation.omega_r = 2 * math.pi * 500.0
    assert vtb.fesea_report(cfg).omega_r == pytest.approx(2 * math.pi * 500.0)


@pytest.mark.parametrize("method", ["modal", "fem"])
def test_report_needs_a_hybrid_config(paper, method):
    cfg = paper.copy()
    cfg.discretisation.method = method
    with pytest.raises(ConfigError, match="method"):
        vtb.fesea_report(cfg)


@pytest.mark.parametrize("value", [-1.0, 0.0, float("nan")])
def test_bad_omega_r_names_the_field(paper, value):
    cfg = paper.copy()
    cfg.discretisation.omega_r = value
    with pytest.raises(ConfigError, match="omega_r"):
        vtb.simulate(cfg)


@pytest.fixture(scope="module")
def runs(paper):
    modal, modal220, fem = paper.copy(), paper.copy(), paper.copy()
    modal.discretisation.method = "modal"
    modal220.discretisation.method = "modal"
    modal220.structure.layers[0].modes = 220
    modal220.structure.layers[0].local_modes = 0
    fem.discretisation.method = "fem"
    return {name: vtb.simulate(c) for name, c in [("hybrid", paper), ("modal", modal), ("modal220", modal220), ("fem", fem)]}


def _low_pass(a, dt, fc):
    spec = np.fft.rfft(a)
    spec[np.fft.rfftfreq(len(a), dt) > fc] = 0.0
    return np.fft.irfft(spec, len(a))


def test_rail_displacement_recovery(paper, report, runs):
    """The hybrid's rail displacement output adds the local modes' static deflection
    Σ_w P_w·Σ_j s_j(x_o)s_j(x_w)/k_j. Recomputed here in numpy from the recorded contact forces:
    without it the output is the global part, which matches the uncorrected modal run; with it
    the output matches the run that keeps the 100 local modes as global DOFs (modal 220)."""
    hyb = runs["hybrid"]
    L = paper.structure.length
    rail = paper.structure.layers[0]
    n, k = report.modes["index"], report.modes["stiffness"]
    scale = math.sqrt(2 / (rail.density * rail.area * L))
    veh = paper.vehicles[0]
    offsets = np.array([0.0, 2 * veh.l_t, 2 * veh.l_c, 2 * veh.l_c + 2 * veh.l_t])
    so = scale * np.sin(n * math.pi * hyb.points[0] / L) / k
    xs = veh.x_front - offsets[None, :] + paper.speed * hyb.t[:, None]
    flex = np.einsum("j,twj->tw", so, scale * np.sin(xs[..., None] * n * math.pi / L))
    local = np.sum(hyb.contact_force * flex, axis=1)
    total = hyb.displacement("rail")
    peak = lambda u: np.max(np.abs(u))
    assert peak(local) > 0.05 * peak(total)
    assert peak(total - local) == pytest.approx(peak(runs["modal"].displacement("rail")), rel=0.005)
    assert peak(total) == pytest.approx(peak(runs["modal220"].displacement("rail")), rel=0.01)


def test_hybrid_agrees_with_fem_251(runs):
    """Issue #3 acceptance, as far as the physics allows (docs/validation.md has the study with
    the refined FEM 502 as referee): displacement amplitudes within 5 %, rail acceleration within
    10 %. Slab acceleration above ~1 kHz is not converged even in the FEM (it grows from FEM 251
    to FEM 502) and no modal model carries it; below 500 Hz hybrid and FEM agree within 10 %.
    The car body (rigid) is compared below 20 Hz, where its model is meant to hold."""
    hyb, fem = runs["hybrid"], runs["fem"]
    mh, mf = hyb.metrics(), fem.metrics()
    for key, tol in [("rail_disp_max", 0.05), ("slab_disp_max", 0.05), ("rail_acc_max", 0.10)]:
        assert mh[key] == pytest.approx(mf[key], rel=tol), key
    dt = hyb.t[1]
    for signal, fc in [(lambda r: r.acceleration("slab"), 500.0), (lambda r: r.car_body_acc, 20.0)]:
        a_h, a_f = (np.max(np.abs(_low_pass(signal(r), dt, fc))) for r in (hyb, fem))
        assert a_h == pytest.approx(a_f, rel=0.10)


def _short_run(paper, method, piers=None):
    """0.1 s of the article's case observed 4 m ahead of the leading wheelset (passed at
    t = 0.05 s), optionally with the girder's supports set to ``piers`` N/m."""
    cfg = paper.copy()
    cfg.discretisation.method = method
    if piers is not None:
        ground = [c for c in cfg.structure.couplings if c.lower == "ground"]
        assert len(ground) == 1
        ground[0].stiffness = piers
    cfg.solver.t_end = 0.1
    cfg.output.points = [cfg.vehicles[0].x_front + 4.0]
    return vtb.simulate(cfg)


def test_hybrid_on_soft_supports_agrees_with_fem(paper):
    """The girder on 1e6 N/m supports instead of 1e15: the whole track sinks 0.11 m on them.
    The hybrid split once gave the rail's end functions a stiffness to ground (2.8e8 N/m
    against the supports' 6e6) and, with no error, came out too stiff: 27 % low in a static
    solve, 1.04e-2 m against modal's and FEM's 3.94e-2 m at mid-length over 0.05 s. Now every
    layer's displacement peak is within 1 % of FEM 251 on both supports (measured on soft ones:
    rail 0.004 %) and the rail–slab deflection is as close to FEM as on the article's rigid
    piers (peak 0.5 %, history within 4.1 % of its peak against 4.0 % on rigid piers)."""
    err = {}
    for piers in (None, 1e6):
        hyb, fem = (_short_run(paper, m, piers) for m in ("hybrid", "fem"))
        for layer in ("rail", "slab", "bridge"):
            assert np.max(np.abs(hyb.displacement(layer))) == pytest.approx(np.max(np.abs(fem.displacement(layer))), rel=0.01), layer
        rel_h, rel_f = (r.displacement("rail") - r.displacement("slab") for r in (hyb, fem))
        assert np.max(np.abs(rel_h)) == pytest.approx(np.max(np.abs(rel_f)), rel=0.02)
        err[piers] = np.max(np.abs(rel_h - rel_f)) / np.max(np.abs(rel_f))
    assert err[1e6] < 0.05 and err[1e6] < err[None] + 0.005, err


def test_hybrid_refuses_a_rail_without_springs(paper):
    """Without fasteners the rail floats (modal and FEM fail in the static solve); the hybrid's
    local modes, the rail on its own springs, have no support: a ConfigError up front, not
    rail displacements of hundreds of metres."""
    cfg = paper.copy()
    rail = cfg.structure.layers[0].name
    cfg.structure.couplings = [c for c in cfg.structure.couplings if rail not in (c.upper, c.lower)]
    cfg.solver.t_end = 0.01
    with pytest.raises(ConfigError, match="springs") as e:
        vtb.simulate(cfg)
    assert e.value.field == "structure.couplings"
