"""Timoshenko rail elements and per-layer finite-element meshes against closed forms.

Reference values are the frequency equation of a simply supported Timoshenko beam (span ℓ,
wavenumber k = nπ/ℓ, rotary inertia ρI, shear stiffness κGA):

    (ρ²I/κG)·ω⁴ − [ρA + ρI·k²·(1 + E/κG)]·ω² + EI·k⁴ = 0        (lower root),

its Rayleigh limit (κG → ∞), and the Euler–Bernoulli ω = k²·sqrt(EI/ρA). The pinned–pinned
mode of a rail on discrete supports has its nodes on the supports, so its frequency is the
simply supported span's whatever the support stiffness.
"""

import math

import numpy as np
import pytest
import scipy.linalg

import vtb

# The article's rail (Table 1) and a shear modulus/coefficient for a 60 kg rail in vertical
# bending (G = E/2(1 + ν), ν = 0.3; κ = 0.4).
RHO, AREA, E, INERTIA = 7800.0, 7.745e-3, 2.1e11, 3.217e-5
G, KAPPA = 8.1e10, 0.4
BAY = 0.64


def timoshenko_frequency(k: float, g: float = G, kappa: float = KAPPA, rotary: bool = True) -> float:
    """Lower natural frequency (Hz) of the simply supported span mode of wavenumber k."""
    ri = RHO * INERTIA if rotary else 0.0
    a = RHO * ri / (kappa * g) if math.isfinite(g) else 0.0
    b = RHO * AREA + ri * k * k * (1.0 + (E / (kappa * g) if math.isfinite(g) else 0.0))
    c = E * INERTIA * k**4
    w2 = c / b if a == 0.0 else (b - math.sqrt(b * b - 4 * a * c)) / (2 * a)
    return math.sqrt(w2) / (2 * math.pi)


def beam_config(length: float, element_length: float, g=G, kappa=KAPPA, supports=(), support_k=0.0) -> vtb.Config:
    """A single rail with rigid point supports at both ends (rotation free) and optional
    springs ``support_k`` at ``supports``."""
    rigid = 1e6 * 48.0 * E * INERTIA / length**3
    layer = vtb.Layer("rail", RHO, AREA, E, INERTIA, 0, vtb.RayleighCoefficients(0.0, 0.0), shear_modulus=g, shear_coefficient=kappa, element_length=element_length)
    couplings = [vtb.Coupling("rail", "ground", "discrete", rigid, 0.0, [0.0, length])]
    if supports:
        couplings.append(vtb.Coupling("rail", "ground", "discrete", support_k, 0.0, list(supports)))
    cfg = vtb.Config(structure=vtb.Structure(length, [layer], couplings), speed=1.0, forces=[vtb.MovingForce(1.0, 0.0)], solver=vtb.Solver(t_end=1e-3))
    cfg.discretisation.method = "fem"
    return cfg


def frequencies(cfg: vtb.Config, count: int) -> np.ndarray:
    m = vtb.assembled_matrices(cfg)
    w2 = scipy.linalg.eigh(m["k"], m["m"], eigvals_only=True, subset_by_index=[0, count - 1])
    return np.sqrt(np.abs(w2)) / (2 * math.pi)


def test_simply_supported_timoshenko_beam_frequencies_match_closed_form():
    """First ten modes of a 3 m simply supported rail (320 elements): within 0.1 % of the
    Timoshenko frequency equation, which is 10–40 % below Euler–Bernoulli there."""
    length = 3.0
    f = frequencies(beam_config(length, length / 320), 10)
    for n in range(1, 11):
        k = n * math.pi / length
        ref = timoshenko_frequency(k)
        assert abs(f[n - 1] / ref - 1) < 1e-3, (n, f[n - 1], ref)
    eb10 = (10 * math.pi / length) ** 2 * math.sqrt(E * INERTIA / (RHO * AREA)) / (2 * math.pi)
    assert f[9] < 0.8 * eb10


def test_large_shear_stiffness_tends_to_the_rayleigh_and_euler_bernoulli_beams():
    """κG → ∞ leaves rotary inertia (Rayleigh beam); the Euler–Bernoulli mesh is its ρI → 0."""
    length = 3.0
    f = frequencies(beam_config(length, length / 80, g=1e30), 6)
    eb = frequencies(beam_config(length, length / 80, g=None, kappa=None), 6)
    for n in range(1, 7):
        k = n * math.pi / length
        assert abs(f[n - 1] / timoshenko_frequency(k, g=math.inf) - 1) < 5e-4
        assert abs(eb[n - 1] / timoshenko_frequency(k, g=math.inf, rotary=False) - 1) < 5e-4


@pytest.mark.parametrize("timoshenko,low,high", [(False, 3.5, 5.0), (True, 1.8, 2.3)])
def test_mesh_convergence_order(timoshenko, low, high):
    """Error of mode 4 of a simply supported span against its closed form as the mesh halves
    (8, 16, 32 elements): the cubic Hermite element with consistent mass converges as h⁴; the
    interdependent Timoshenko element as h², since its shear strain is constant within an
    element while the mode's shear force varies along it."""
    length = 3.0
    k = 4 * math.pi / length
    g, kappa = (G, KAPPA) if timoshenko else (None, None)
    ref = timoshenko_frequency(k) if timoshenko else k * k * math.sqrt(E * INERTIA / (RHO * AREA)) / (2 * math.pi)
    errs = [abs(frequencies(beam_config(length, length / n, g=g, kappa=kappa), 4)[3] / ref - 1) for n in (8, 16, 32)]
    orders = [math.log2(errs[i] / errs[i + 1]) for i in range(2)]
    assert all(low < p < high for p in orders), (errs, orders)


@pytest.mark.parametrize("timoshenko", [False, True])
def test_pinned_pinned_frequency_of_article_rail_matches_closed_form(timoshenko):
    """A rail on the article's fasteners every 0.64 m (k = 6.5e7 N/m, ten bays, rigid ends):
    one mode lies at the span closed form (EB ≈ 1282 Hz, Timoshenko κ = 0.4 ≈ 1.0 kHz) within
    1 % on 16 elements per bay — the fastener stiffness does not enter (nodes on supports)."""
    n_bays = 10
    length = n_bays * BAY
    g, kappa = (G, KAPPA) if timoshenko else (None, None)
    supports = [BAY * i for i in range(1, n_bays)]
    cfg = beam_config(length, BAY / 16, g=g, kappa=kappa, supports=supports, support_k=6.5e7)
    f = frequencies(cfg, 40)
    k = math.pi / BAY
    ref = timoshenko_frequency(k) if timoshenko else k * k * math.sqrt(E * INERTIA / (RHO * AREA)) / (2 * math.pi)
    nearest = f[np.argmin(np.abs(f - ref))]
    assert abs(nearest / ref - 1) < 0.01, (nearest, ref)
    if timoshenko:
        assert 950 < ref < 1100
    else:
        assert abs(ref - 1282) < 2


def _static_rail_deflection(cfg: vtb.Config, x: float) -> float:
    """Rail deflection at x under a unit load at x: sparse solve of K·u = N(x)."""
    import scipy.sparse
    import scipy.sparse.linalg

    from vtb import _core

    core = cfg.to_core_json()
    mats = _core.matrices(core)
    r, c, v = mats["k"]
    k = scipy.sparse.coo_matrix((v, (r, c)), shape=(mats["n"], mats["n"])).tocsc()
    starts, values = _core.shapes(core, 0, np.array([x]))
    f = np.zeros(mats["n"])
    f[starts[0] : starts[0] + values.shape[1]] = values[0]
    return float(f @ scipy.sparse.linalg.spsolve(k, f))


def test_per_layer_meshes_put_nodes_on_fasteners_and_agree_with_a_uniform_fine_mesh():
    """The article's stack with the rail at 8 elements per bay and the lower layers at one per
    bay: the meshes have nodes on every fastener and pier, and the static rail deflection under
    a load at mid-bay agrees with every layer at 8 per bay to 0.1 % (the lower layers are
    smooth on the bay scale)."""
    cfg = vtb.paper_config()
    cfg.discretisation.method = "fem"
    layers = cfg.structure.layers
    layers[0].element_length = BAY / 8
    for layer in layers[1:]:
        layer.element_length = BAY
    sizes = {name: n for name, _, n in vtb._core.matrices(cfg.to_core_json())["layer_offsets"]}
    assert sizes == {"rail": 2 * (250 * 8 + 1), "slab": 2 * 251, "base": 2 * 251, "bridge": 2 * 251}
    x = 80.0 + BAY / 2
    coarse = _static_rail_deflection(cfg, x)
    for layer in layers[1:]:
        layer.element_length = BAY / 8
    fine = _static_rail_deflection(cfg, x)
    assert abs(coarse / fine - 1) < 1e-3, (coarse, fine)


def test_timoshenko_needs_the_finite_element_method_and_both_shear_fields():
    cfg = vtb.paper_config()
    cfg.structure.layers[0].shear_modulus = G
    cfg.structure.layers[0].shear_coefficient = KAPPA
    with pytest.raises(vtb.ConfigError, match="shear_modulus"):
        vtb.simulate(cfg)
    cfg.discretisation.method = "fem"
    cfg.structure.layers[0].shear_coefficient = None
    with pytest.raises(vtb.ConfigError, match="shear_coefficient"):
        vtb.simulate(cfg)
    cfg.structure.layers[0].shear_coefficient = -0.4
    with pytest.raises(vtb.ConfigError, match="shear_coefficient"):
        vtb.simulate(cfg)
    cfg.structure.layers[0].shear_coefficient = KAPPA
    cfg.structure.layers[0].element_length = 0.0
    with pytest.raises(vtb.ConfigError, match="element_length"):
        vtb.simulate(cfg)


def test_pinned_pinned_resonance_measured_from_receptance_of_converged_track():
    """The converged preset's rail: the point receptance at mid-bay peaks (and its ratio to
    the receptance above a fastener is largest) at the Timoshenko span closed form for a 0.64 m
    bay, 980 Hz, within 1 % — not at Euler–Bernoulli's 1282 Hz."""
    cfg = vtb.paper_config(model="converged")
    ref = timoshenko_frequency(math.pi / BAY)
    f = np.arange(900.0, 1065.0, 5.0)
    mid = np.abs(vtb.receptance(cfg, 80.0 + BAY / 2, f))
    over = np.abs(vtb.receptance(cfg, 80.0, f))
    assert abs(f[np.argmax(mid)] / ref - 1) < 0.01
    assert abs(f[np.argmax(mid / over)] / ref - 1) < 0.01
