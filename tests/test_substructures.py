"""Substructured natural modes (vtb.analysis.substructures) held against the global eigensolve
of the same finite-element structure: a 5-span viaduct between embankments, simply supported
and continuous."""

import copy
import math
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg

import vtb
from vtb.analysis import substructures
from vtb.analysis.eigen import assemble, sliced_eigsh

FMAX = 60.0

#: The deck grade's cut-off (vtb.paper_config(model="deck")).
DECK = 1200.0


def viaduct(n_spans: int, simply_supported: bool = True, approach: float = 30.0) -> vtb.Config:
    cfg = vtb.paper_config(model="fast")
    cfg = vtb.spans(cfg, [32.0] * n_spans, simply_supported=simply_supported)
    return vtb.track_zones(cfg, approach=approach, exit=approach)


def frequencies(k, m, fmax: float = FMAX):
    hi = (2 * math.pi * fmax) ** 2
    lam, vec = sliced_eigsh(k.tocsc(), m.tocsc(), -1e-6 * hi, hi)
    return np.sqrt(np.clip(lam, 0, None)) / (2 * math.pi), vec


@pytest.fixture(scope="module", params=[True, False], ids=["simply-supported", "continuous"])
def five_spans(request):
    system = assemble(viaduct(5, request.param))
    f, phi = frequencies(system.k, system.m)
    _, first, count = system.layers[-1]
    deck = slice(first, first + count)
    share = np.einsum("ij,ij->j", phi[deck], system.m.tocsr()[deck, deck] @ phi[deck])
    return system, f, share > 0.5


def test_substructured_frequencies_are_upper_bounds_within_3e_4_of_the_global_ones(five_spans):
    system, f_global, deck = five_spans
    cut = substructures.reduce(system, FMAX)
    assert cut.substructures >= 7 and cut.distinct < cut.substructures
    f, _ = frequencies(cut.k, cut.m)
    assert f.size == f_global.size
    err = (f - f_global) / f_global
    assert np.all(err > -1e-8)  # Rayleigh–Ritz: never below the structure's own
    assert np.max(err) < 3e-4
    assert np.max(err[deck]) < 2e-4


def test_the_error_falls_as_more_interior_modes_are_kept(five_spans):
    system, f_global, deck = five_spans
    errors = []
    for ratio in (2.0, 3.0, 5.0, 8.0):
        f, _ = frequencies(*_km(system, ratio))
        errors.append(np.max((f - f_global) / f_global))
    assert all(b < a for a, b in zip(errors, errors[1:])), errors
    assert errors[-1] < 0.2 * errors[0]


def _km(system, ratio):
    cut = substructures.reduce(system, FMAX, ratio)
    return cut.k, cut.m


def test_equal_spans_share_one_reduction():
    small, large = (substructures.reduce(assemble(viaduct(n)), FMAX) for n in (4, 9))
    assert large.substructures - small.substructures == 5
    assert large.distinct == small.distinct


def test_substructured_modes_give_the_global_deck_shapes_and_band():
    cfg = viaduct(6)
    glob, sub = vtb.modes(cfg, 40.0, method="global"), vtb.modes(cfg, 40.0)
    assert sub.method == "substructured" and glob.method == "shift-invert"
    assert len(sub) == len(glob)
    # The six spans' first bending modes form a cluster whose members any perturbation mixes:
    # compare the subspaces they span along the deck, not single modes.
    xs = np.linspace(30.0, 30.0 + 6 * 32.0, 193)
    a, b = glob.displacement("bridge", xs)[:, :6], sub.displacement("bridge", xs)[:, :6]
    assert np.max(scipy.linalg.subspace_angles(a, b)) < 1e-3
    deck_g, deck_s = (m.frequencies[m.layer_energy("bridge") > 0.5] for m in (glob, sub))
    np.testing.assert_allclose(deck_s, deck_g, rtol=2e-4)
    assert vtb.deck_band(cfg) == pytest.approx(float(max(30.0, 1.5 * deck_g[0], deck_g[2])), rel=2e-4)
    # the expanded shapes are mass-normalised like the global ones
    m = assemble(cfg).m
    np.testing.assert_allclose(np.einsum("ij,ij->j", sub.shapes, m @ sub.shapes), 1.0, rtol=1e-9)


def test_a_bad_method_or_a_structure_that_cannot_be_cut_is_refused():
    cfg = viaduct(3)
    with pytest.raises(vtb.ConfigError, match="method"):
        vtb.modes(cfg, 20.0, method="lanczos")
    with pytest.raises(vtb.ConfigError, match="method"):
        vtb.modes(vtb.paper_config(), 20.0, method="substructured")  # the article's modal layers
    assert vtb.modes(vtb.paper_config(), 20.0).method == "shift-invert"


# ---------------------------------------------------------------- the substructured engine
def passage(simply_supported: bool, cutoff=None) -> vtb.Config:
    """One CRH3 car at 80 m/s over 3 spans between 30 m embankments, long-wave irregularity."""
    cfg = vtb.paper_config(model="fast")
    cfg.discretisation.synthesis_cutoff = None
    cfg.output.points = []
    cfg = vtb.spans(cfg, [32.0] * 3, simply_supported=simply_supported)
    cfg = vtb.track_zones(cfg, approach=30.0, exit=30.0, tail=0.1)
    cfg.irregularity = vtb.Irregularity(kind="german_low", wavelength_min=1.0, wavelength_max=30.0, seed=1)
    cfg.solver.dt = 2e-4
    cfg.solver.fade_in = 20.0
    cfg.output.band_limit = 150.0
    cfg.discretisation.substructure_cutoff = cutoff
    return cfg


def test_the_residual_moments_are_the_truncated_modes_receptance_about_zero():
    """R₀ + sR₁ + s²R₂ (residual_bands) against the interior's receptance solved directly,
    (K_II + sC_II + s²M_II)⁻¹ less the kept modes' Φ(Λ + sD + s²I)⁻¹Φᵀ, at a rail row (cut-off 300 Hz): the
    error falls as s³ (the next moment), so halving the frequency cuts it about eightfold."""
    system = assemble(passage(True))
    sub = substructures.reduce(system, 300.0, ratio=1.0)
    substructures.residual_bands(system, sub)
    piece = next(p for p in sub.pieces if p.inner.size and sub.groups[p.group].phi.shape[1] > 5)
    g = sub.groups[piece.group]
    k, m, c = (a.tocsr()[piece.inner][:, piece.inner].toarray() for a in (system.k, system.m, system.c))
    _, first, count = system.layers[0]
    rail = np.flatnonzero((piece.inner >= first) & (piece.inner < first + count))
    r = rail[rail.size // 2]
    d = g.phi.T @ c @ g.phi

    def error(f, terms=3):
        s = 2j * math.pi * f
        exact = np.linalg.solve(k + s * c + s * s * m, np.eye(k.shape[0])[:, r])
        exact -= g.phi @ np.linalg.solve(np.diag(g.omega2) + s * d + s * s * np.eye(d.shape[0]), g.phi[r])
        series = sum(s ** j * g.residual[j, r, 0] for j in range(terms))
        return abs(exact[r] - series) / abs(exact[r])

    assert g.residual[0, r, 0] > 0 and g.residual[1, r, 0] < 0
    e = [error(f) for f in (50.0, 25.0, 12.5)]
    assert e[0] < 2e-3 and e[1] / e[2] > 6.0, e
    # the static residual alone is 0.5 % off at 12.5 Hz already (the truncated modes' damping)
    assert error(12.5, terms=1) > 100 * e[2]


@pytest.fixture(scope="module", params=[True, False], ids=["simply-supported", "continuous"])
def runs(request):
    fem = vtb.simulate(passage(request.param), progress=False).metrics()
    return fem, {fc: vtb.simulate(passage(request.param, fc), progress=False).metrics() for fc in (600.0, DECK)}


def rel(a, b):
    return abs(b - a) / abs(a)


def test_the_deck_grade_gives_the_finite_elements_deck_within_1_and_2_percent(runs):
    fem, sub = runs
    for fc in (600.0, DECK):
        assert rel(fem["deck_disp_max"], sub[fc]["deck_disp_max"]) < 0.01
        assert rel(fem["deck_moment_max"], sub[fc]["deck_moment_max"]) < 0.01
        assert rel(fem["deck_acc_max"], sub[fc]["deck_acc_max"]) < 0.02
        assert rel(fem["car_comfort_aw"], sub[fc]["car_comfort_aw"]) < 0.01


@pytest.fixture(scope="module")
def converged_contact():
    """The simply supported passage's contact forces on the finite elements at Δt = 5e-5 and
    2.5e-5 s (the reference: converged in the time step) and at the deck grade."""
    out = {}
    for dt in (5e-5, 2.5e-5):
        c = passage(True)
        c.solver.dt = dt
        out[dt] = vtb.simulate(c, progress=False).metrics()
    c = passage(True, DECK)
    c.solver.dt = vtb.paper_config(model="deck").solver.dt
    out["deck"] = vtb.simulate(c, progress=False).metrics()
    return out


def test_the_deck_grades_contact_force_extremes_are_within_1_percent_of_the_converged_finite_elements(converged_contact):
    fem, fine, deck = converged_contact[5e-5], converged_contact[2.5e-5], converged_contact["deck"]
    for name in ("contact_force_max", "contact_force_min"):
        assert rel(fine[name], fem[name]) < 0.005, (name, fem[name], fine[name])  # the reference has converged
        assert rel(fine[name], deck[name]) < 0.01, (name, fine[name], deck[name])


def test_the_deck_grade_preset_is_the_converged_structure_on_substructures():
    deck, conv = vtb.paper_config(model="deck"), vtb.paper_config(model="converged")
    assert deck.discretisation.substructure_cutoff == DECK and deck.discretisation.synthesis_cutoff is None
    assert deck.structure == conv.structure and deck.vehicles == conv.vehicles
    assert deck.solver.dt == 1e-4 and deck.output.band_limit == 150.0
    band = vtb.resolved_band(deck).rail
    assert band.basis_f_max == pytest.approx(DECK / 2) and band.f_max >= deck.output.band_limit
    assert deck.irregularity.wavelength_min * deck.output.band_limit >= deck.speed


def test_moving_forces_load_the_deck_as_on_the_finite_elements():
    cfg = passage(True)
    cfg.vehicles = []
    cfg.irregularity = vtb.Irregularity()
    cfg.forces = [vtb.MovingForce(magnitude=170e3, x0=x0) for x0 in (0.0, -3.0, -17.0, -20.0)]
    fem = vtb.simulate(cfg, progress=False).metrics()
    cfg.discretisation.substructure_cutoff = 300.0
    sub = vtb.simulate(cfg, progress=False).metrics()
    for name in ("deck_disp_max", "deck_moment_max"):
        assert rel(fem[name], sub[name]) < 0.01, name
    assert rel(fem["deck_acc_max"], sub["deck_acc_max"]) < 0.02


def test_damper_designs_share_one_reduction_and_run_in_lockstep_as_alone():
    cfg = passage(True, 300.0)
    cfg.solver.tail, cfg.solver.t_end = None, 0.3
    designs = []
    for k in (1e8, 2e8, 4e8, 8e8):
        c = copy.deepcopy(cfg)
        c.dampers = [vtb.DamperGroup(kind="tvmd", inertance=5.0, stiffness=k, damping=1e3, positions=[40.0, 60.0, 80.0])]
        designs.append(c)
    batch = vtb.simulate_batch(designs, lanes=4, progress=False)
    alone = [vtb.simulate(d, progress=False).metrics() for d in designs]
    assert [b["rail_acc_max"] for b in batch] == [a["rail_acc_max"] for a in alone]
    assert len({b["rail_acc_max"] for b in batch}) == 4
    # the dampers act as on the finite elements
    fem = copy.deepcopy(designs[1])
    fem.discretisation.substructure_cutoff = None
    ref = vtb.simulate(fem, progress=False).metrics()
    assert rel(ref["deck_disp_max"], alone[1]["deck_disp_max"]) < 0.01
    assert rel(ref["contact_force_max"], alone[1]["contact_force_max"]) < 0.05


def test_a_substructured_run_refuses_a_bad_cutoff_or_a_modal_structure():
    cfg = passage(True, -5.0)
    with pytest.raises(vtb.ConfigError, match="substructure_cutoff"):
        vtb.simulate(cfg, progress=False)
    cfg = passage(True, 300.0)
    cfg.discretisation.synthesis_cutoff = 300.0
    with pytest.raises(vtb.ConfigError, match="substructure_cutoff"):
        vtb.simulate(cfg, progress=False)
    art = vtb.paper_config()
    art.discretisation.substructure_cutoff = 300.0
    with pytest.raises(vtb.ConfigError, match="substructure_cutoff|method"):
        vtb.simulate(art, progress=False)


def test_a_substructured_build_announces_itself_and_shows_its_substructures(capsys):
    from vtb.run import substructures as built

    cfg = passage(True, 450.0)  # a cut-off no other test builds: this process builds it here
    built.reduction(cfg, progress=True)
    err = capsys.readouterr().err
    assert "reducing this structure" in err and "450 Hz" in err and "vtb substructures" in err
    built.reduction(cfg, progress=True)  # built: nothing to say
    assert capsys.readouterr().err == ""


def _build_digest(cutoff: float) -> str:
    """A digest of every array of a fresh substructured build of the 3-span passage."""
    import hashlib

    from vtb.run import substructures as built

    built._MEMORY.clear()
    sub = built.reduction(passage(True, cutoff), progress=False).substructuring
    h = hashlib.sha256()
    for g in sub.groups:
        for a in (g.omega2, g.phi, g.psi, g.residual):
            h.update(np.ascontiguousarray(a).tobytes())
    for a in (sub.m, sub.k):
        h.update(a.data.tobytes())
    return h.hexdigest()


def test_substructured_builds_are_bit_identical_across_rebuilds_and_processes():
    import subprocess
    import sys

    here = _build_digest(300.0)
    assert _build_digest(300.0) == here
    code = "import sys; sys.path.insert(0, 'tests'); import test_substructures as t; print(t._build_digest(300.0))"
    other = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True, cwd=str(Path(__file__).resolve().parent.parent)).stdout.split()[-1]
    assert other == here
