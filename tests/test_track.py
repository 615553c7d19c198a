"""Validation of the frequency-domain track tools (vtb.receptance, vtb.decay_rate, vtb.modes).

Reference values come from closed forms coded here, independently of vtb:

* the infinite Euler–Bernoulli beam on a damped Winkler foundation under a harmonic point force,
  EI w'''' + (s − ρAω²) w = F δ(x), s = k + iωc (time factor e^{iωt}, w positive along F).
  With q⁴ = (ρAω² − s)/EI, the four roots are ±q, ±iq; k1, k2 are the two with Im > 0 (the
  waves e^{ik|x|} that decay away from the force; k1 the one with the smaller Im, the
  propagating wave above the cut-on frequency), and k2² = −k1². Writing w = a1 e^{ik1|x|} +
  a2 e^{ik2|x|}, symmetry w'(0) = 0 and the shear jump 2EI w'''(0⁺) = F give
      a1 = iF / (2EI k1 (k1² − k2²)),   a2 = −iF / (2EI k2 (k1² − k2²)),
      w(x)/F = i/(2EI(k1² − k2²)) · (e^{ik1|x|}/k1 − e^{ik2|x|}/k2).
  Static check (ω = 0): k1 = β(1 + i), k2 = β(−1 + i), β = (k/4EI)^¼, and w(0)/F = 1/(8EIβ³)
  = β/(2k), Hetényi's result;
* the simply supported beam's natural frequencies (nπ/L)²·√(EI/ρA)/2π and mass-normalised
  modes √(2/ρAL)·sin(nπx/L).
"""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import vtb

# One UIC60-like rail on a continuous damped foundation (pad + support smeared over the length).
E, I, RHO, AREA = 2.059e11, 3.217e-5, 7830.0, 7.745e-3
EI, RHOA = E * I, RHO * AREA
K_F = 1.0e8  # foundation stiffness (N/m²)
C_F = 4.0e4  # foundation damping (N·s/m²): loss factor ωc/k ≈ 0.5 at the cut-on frequency
F_CUT_ON = math.sqrt(K_F / RHOA) / (2 * math.pi)  # ≈ 204 Hz
BEAM_L = 120.0  # m: waves at 3 kHz lose > 99.96 % of their amplitude over one round trip
BEAM_ELEMENTS = 3000  # 4 cm elements: ≥ 20 per bending wavelength at 3 kHz (0.83 m)
LOG10E = math.log10(math.e)


def winkler_beam(length=BEAM_L, elements=BEAM_ELEMENTS, foundation=True):
    layer = vtb.Layer("rail", RHO, AREA, E, I, 1, vtb.RayleighCoefficients(0.0, 0.0))
    couplings = [vtb.Coupling("rail", "ground", "continuous", K_F, C_F)] if foundation else []
    cfg = vtb.Config(structure=vtb.Structure(length, [layer], couplings), speed=0.0)
    cfg.discretisation.method = "fem"
    cfg.discretisation.fem_elements = elements
    return cfg


def wavenumbers(f):
    """(k1, k2): the roots of EI q⁴ = ρAω² − s with Im > 0, k1 with the smaller Im."""
    w = 2 * np.pi * np.asarray(f, float)
    q4 = ((RHOA * w**2 - (K_F + 1j * w * C_F)) / EI).astype(complex)
    q = q4**0.25
    roots = np.stack([q, 1j * q, -q, -1j * q], axis=-1)
    k1, k2 = [], []
    for r in roots:
        r = r[np.imag(r) > 0]
        assert r.size == 2
        r = r[np.argsort(np.imag(r))]
        k1.append(r[0])
        k2.append(r[1])
    return np.array(k1), np.array(k2)


def infinite_beam_amplitudes(f):
    """(a1, a2, k1, k2) of w(x)/F = a1 e^{ik1|x|} + a2 e^{ik2|x|}."""
    k1, k2 = wavenumbers(f)
    c = 1j / (2 * EI * (k1**2 - k2**2))
    return c / k1, -c / k2, k1, k2


def infinite_beam_receptance(f, distance):
    """w(x)/F (m/N) of the infinite beam, shape (n_f, n_x), x = distance from the force."""
    a1, a2, k1, k2 = (v[:, None] for v in infinite_beam_amplitudes(f))
    x = np.abs(np.atleast_1d(np.asarray(distance, float)))[None, :]
    return a1 * np.exp(1j * k1 * x) + a2 * np.exp(1j * k2 * x)


def en15461_estimator(a, d):
    """DR = 10·log10(e) / Σ |A(x_n)|²/|A(x_0)|²·Δx_n, Δx_n = half the neighbours' distance."""
    w = np.empty_like(d)
    w[0], w[-1] = 0.5 * (d[1] - d[0]), 0.5 * (d[-1] - d[-2])
    w[1:-1] = 0.5 * (d[2:] - d[:-2])
    return 10 * LOG10E / ((np.abs(a) ** 2 / np.abs(a[:, [0]]) ** 2) @ w)


def continuous_estimator(f, length):
    """The estimator with the sum replaced by its integral ∫₀^D |w(x)|²dx / |w(0)|², in closed
    form for the two-wave field: ∫₀^D e^{iκx}dx = (e^{iκD} − 1)/(iκ)."""
    a1, a2, k1, k2 = infinite_beam_amplitudes(f)

    def integral(kappa):
        return (np.exp(1j * kappa * length) - 1) / (1j * kappa)

    s = (
        np.abs(a1) ** 2 * integral(k1 - np.conj(k1))
        + np.abs(a2) ** 2 * integral(k2 - np.conj(k2))
        + 2 * np.real(a1 * np.conj(a2) * integral(k1 - np.conj(k2)))
    )
    return 10 * LOG10E * np.abs(a1 + a2) ** 2 / np.real(s)


@pytest.fixture(scope="module")
def beam():
    return winkler_beam()


FREQS = np.geomspace(50.0, 3000.0, 30)
OFFSETS = np.array([0.0, 0.3, 1.0, 3.0, 10.0])


def test_receptance_of_beam_on_elastic_foundation_matches_infinite_beam(beam):
    """Point and transfer receptances of a 120 m FEM beam on a damped Winkler foundation, force
    at mid-length, vs the infinite beam over 50–3000 Hz: within 1 % (measured: 0.05 % at the
    force, 0.15 % at 10 m). End reflections are negligible: the propagating wave loses
    e^{−Im(k1)·L} < 1e−3 over the round trip to an end and back, and a beam 20 m shorter
    gives the same point receptance within 0.5 % (measured 0.14 %); halving the elements
    changes it by < 0.1 % (measured 0.015 %)."""
    k1, _ = wavenumbers(FREQS)
    assert np.all(np.exp(-np.imag(k1) * BEAM_L) < 1e-3)

    x0 = BEAM_L / 2
    got = vtb.receptance(beam, x0, FREQS, layer="rail", response_x=x0 + OFFSETS)
    assert got.shape == (FREQS.size, OFFSETS.size)
    ref = infinite_beam_receptance(FREQS, OFFSETS)
    rel = np.abs(got - ref) / np.abs(ref)
    assert rel.max() < 0.01, rel.max(axis=0)
    # The other side of the force: the same by symmetry (transfer receptance at x0 − d).
    left = vtb.receptance(beam, x0, FREQS, layer=0, response_x=x0 - OFFSETS[1:])
    assert np.max(np.abs(left - ref[:, 1:]) / np.abs(ref[:, 1:])) < 0.01

    point = got[:, 0]
    shorter = vtb.receptance(winkler_beam(BEAM_L - 20.0, BEAM_ELEMENTS - 500), (BEAM_L - 20.0) / 2, FREQS, layer="rail")
    assert np.max(np.abs(shorter / point - 1)) < 0.005
    coarse = vtb.receptance(winkler_beam(BEAM_L, BEAM_ELEMENTS // 2), x0, FREQS, layer="rail")
    assert np.max(np.abs(coarse / point - 1)) < 0.001


def test_static_receptance_matches_hetenyi(beam):
    """At 0 Hz the point receptance is Hetényi's β/(2k), β = (k/4EI)^¼, and the deflection line
    is β/(2k)·e^{−βx}(cos βx + sin βx): within 1e−4 (the damping plays no role)."""
    beta = (K_F / (4 * EI)) ** 0.25
    x = np.array([0.0, 0.25, 0.5, 1.0, 2.0])
    ref = beta / (2 * K_F) * np.exp(-beta * x) * (np.cos(beta * x) + np.sin(beta * x))
    got = vtb.receptance(beam, BEAM_L / 2, 0.0, layer="rail", response_x=BEAM_L / 2 + x)[0]
    assert np.max(np.abs(got.imag)) < 1e-12 * ref[0]
    assert np.max(np.abs(got.real - ref)) < 1e-4 * ref[0]
    # The closed form of the dynamic solution tends to the same value (checks the test's algebra).
    assert abs(infinite_beam_receptance([0.0], [0.0])[0, 0] / ref[0] - 1) < 1e-12
    point = vtb.receptance(beam, BEAM_L / 2, [0.0], layer="rail")
    assert point.shape == (1,) and abs(point[0].real / ref[0] - 1) < 1e-4


def test_decay_rate_of_infinite_beam_matches_its_wavenumber(beam):
    """The EN 15461 estimator on the FEM beam vs the same estimator on the infinite beam's
    closed-form receptances at the same positions (within 1 %; measured 0.12 %), vs its
    integral form in closed form with the default positions (within 1.5 %; measured 0.6 %,
    the trapezoid sum on the geometric grid), and against the wavenumber:

    * far from the force the transfer receptance decays at 20·log10(e)·Im(k1) dB/m (its level
      between 10 m and 30 m, within 1 %);
    * above the cut-on frequency, where the propagating wave dominates the sum, the estimator
      tends to 20·log10(e)·Im(k1)·|A(x_0)|²/|a1|² = 2·20·log10(e)·Im(k1): the point receptance
      includes the near field, a1(1 − k1/k2) with |1 − k1/k2|² = 2. Within 6 % for
      f ≥ 1500 Hz (measured 2.4–5.4 %, the near-field wave's share of the sum)."""
    f = np.array([100.0, 204.0, 300.0, 500.0, 800.0, 1000.0, 1500.0, 2000.0, 3000.0])
    x0 = BEAM_L / 2
    d = np.concatenate(([0.0], np.geomspace(0.01, 40.0, 50)))
    got = vtb.decay_rate(beam, f, x0=x0, layer="rail", positions=d)
    ref = en15461_estimator(infinite_beam_receptance(f, d), d)
    assert np.max(np.abs(got / ref - 1)) < 0.01

    default = vtb.decay_rate(beam, f, layer="rail")  # x0 = L/2, geometric positions to the end
    assert np.max(np.abs(default / continuous_estimator(f, BEAM_L / 2) - 1)) < 0.015

    k1, k2 = wavenumbers(f)
    wave = 20 * LOG10E * np.imag(k1)
    far = vtb.receptance(beam, x0, f, layer="rail", response_x=[x0 + 10.0, x0 + 30.0])
    slope = 20 * np.log10(np.abs(far[:, 0]) / np.abs(far[:, 1])) / 20.0
    assert np.max(np.abs(slope / wave - 1)) < 0.01
    assert np.allclose(np.abs(1 - k1 / k2) ** 2, 2.0)
    high = f >= 1500.0
    assert np.all(f[high] > 7 * F_CUT_ON)
    assert np.max(np.abs(got[high] / (2 * wave[high]) - 1)) < 0.06


def test_modes_of_simply_supported_beam_match_closed_form():
    """A 10 m beam on stiff point supports at both ends (vtb.moving_load_config), 100 FEM
    elements: the first 10 frequencies within 0.5 % of (nπ/L)²√(EI/ρA)/2π (measured 4e−5),
    φᵀMφ = I, and each mode along the beam equals ±√(2/ρAL)·sin(nπx/L) within 0.5 % of its
    amplitude; a band [fmin, fmax] returns exactly the modes inside it."""
    length = 10.0
    cfg = vtb.moving_load_config(length, RHO, AREA, E, I, [vtb.MovingForce(1.0, 0.0)], 1.0)
    cfg.discretisation.method = "fem"
    cfg.discretisation.fem_elements = 100

    def closed(n):
        return (n * math.pi / length) ** 2 * math.sqrt(EI / RHOA) / (2 * math.pi)

    res = vtb.modes(cfg, 1.02 * closed(10))
    assert len(res) == 10
    exact = np.array([closed(n) for n in range(1, 11)])
    assert np.max(np.abs(res.frequencies / exact - 1)) < 0.005
    assert np.all(np.diff(res.frequencies) > 0)
    m = vtb.assembled_matrices(cfg)["m"]
    assert res.shapes.shape == (m.shape[0], 10)
    assert np.max(np.abs(res.shapes.T @ m @ res.shapes - np.eye(10))) < 1e-9

    x = np.linspace(0.0, length, 41)
    amp = math.sqrt(2 / (RHOA * length))
    along = res.displacement("beam", x)
    assert along.shape == (41, 10)
    for n in range(1, 11):
        phi = along[:, n - 1]
        ref = amp * np.sin(n * math.pi * x / length)
        ref *= np.sign(ref @ phi)
        assert np.max(np.abs(phi - ref)) < 0.005 * amp
    assert np.allclose(res.displacement(0, x, mode=2), along[:, 2])

    band = vtb.modes(cfg, 1.01 * closed(8), fmin=0.99 * closed(5))
    assert np.max(np.abs(band.frequencies / exact[4:8] - 1)) < 0.005 and len(band) == 4


def test_modes_are_found_by_spectrum_slicing_beyond_one_block():
    """More modes than one shift-invert block (40) — a 60 m simply supported beam, 300
    elements, up to 2 kHz (about 120 modes), and a band 500–1500 Hz: exactly the eigenvalues of
    scipy's dense generalised solver on the same assembled matrices, none missed or repeated
    (within 1e−8 relative, 1e−6 Hz absolute)."""
    import scipy.linalg

    length = 60.0
    cfg = vtb.moving_load_config(length, RHO, AREA, E, I, [vtb.MovingForce(1.0, 0.0)], 1.0)
    cfg.discretisation.method = "fem"
    cfg.discretisation.fem_elements = 300
    mats = vtb.assembled_matrices(cfg)
    lam = scipy.linalg.eigh(mats["k"], mats["m"], eigvals_only=True)
    dense = np.sqrt(np.clip(lam, 0.0, None)) / (2 * math.pi)
    for fmin, fmax in ((0.0, 2000.0), (500.0, 1500.0)):
        res = vtb.modes(cfg, fmax, fmin=fmin)
        ref = dense[(dense >= fmin) & (dense <= fmax)]
        assert res.method == "shift-invert" and len(res) == ref.size > 40
        # The dense solver's eigenvalues carry an absolute error ~ ε·λ_max (here ~1e−7 Hz at
        # the lowest mode, where shift-invert is the more accurate of the two).
        assert np.allclose(res.frequencies, ref, rtol=1e-8, atol=1e-6)


def two_layer_track(method="fem", tids=False):
    """A 12 m rail on discrete fasteners over a slab on a continuous foundation."""
    length = 12.0
    rail = vtb.Layer("rail", RHO, AREA, E, I, 30, vtb.RayleighCoefficients(0.0, 1e-5))
    slab = vtb.Layer("slab", 2500.0, 0.51, 3.6e10, 1.7e-3, 20, vtb.RayleighCoefficients(1.0, 0.0))
    couplings = [
        vtb.Coupling.grid("rail", "slab", 6e7, 4.77e4, 0.6, length),
        vtb.Coupling("slab", "ground", "continuous", 9e8, 8.3e4),
    ]
    cfg = vtb.Config(structure=vtb.Structure(length, [rail, slab], couplings), speed=0.0)
    cfg.discretisation.method = method
    cfg.discretisation.fem_elements = 60
    if tids:
        cfg.tids = vtb.TIDs(inertance=5.0, stiffness=2e8, damping=1e3, count=4, x0=4.5, spacing=0.6)
    return cfg


TRACKS = {(m, t): two_layer_track(m, t) for m in ("fem", "modal") for t in (False, True)}


@settings(max_examples=25, deadline=None)
@given(
    x=st.floats(0.0, 12.0),
    y=st.floats(0.0, 12.0),
    f=st.floats(0.0, 3000.0),
    method=st.sampled_from(["fem", "modal"]),
    tids=st.booleans(),
    layers=st.sampled_from([("rail", "rail"), ("rail", "slab"), ("slab", "slab")]),
)
def test_transfer_receptance_is_reciprocal(x, y, f, method, tids, layers):
    """Maxwell–Betti: the receptance from a force on layer a at x to layer b at y equals the
    one from b at y to a at x (K, C, M symmetric, dampers included), to round-off."""
    cfg = TRACKS[(method, tids)]
    a, b = layers
    xy = vtb.receptance(cfg, x, [f], layer=a, response_x=y, response_layer=b)[0]
    yx = vtb.receptance(cfg, y, [f], layer=b, response_x=x, response_layer=a)[0]
    assert abs(xy - yx) <= 1e-8 * max(abs(xy), abs(yx)) + 1e-30
    assert np.isfinite(xy)


def test_tuned_inerter_dampers_enter_the_receptance():
    """The dampers' internal DOFs are kept: they change the rail's receptance at the damper,
    near the frequency of the spring-inerter pair sqrt(k/b)/2π ≈ 1 kHz, but not at 0 Hz (an
    inerter carries no static force; the spring alone, in series with a free node, none)."""
    plain, damped = two_layer_track("fem", False), two_layer_track("fem", True)
    f = np.array([0.0, 1000.0])
    a0 = vtb.receptance(plain, 5.1, f)
    a1 = vtb.receptance(damped, 5.1, f)
    assert abs(a1[0] / a0[0] - 1) < 1e-9
    assert abs(a1[1] / a0[1] - 1) > 0.01


def test_receptance_shapes_and_frequency_forms(beam):
    a = vtb.receptance(beam, 60.0, 500.0, layer="rail")
    assert a.shape == (1,) and a.dtype == complex
    b = vtb.receptance(beam, 60.0, [500.0, 600.0], layer="rail", response_x=[60.0])
    assert b.shape == (2, 1) and b[0, 0] == pytest.approx(a[0], rel=1e-12)
    assert vtb.decay_rate(beam, 500.0, layer="rail").shape == (1,)


def test_decay_rate_defaults_on_a_fastened_rail():
    """On a rail on discrete fasteners, the default positions are multiples of the fastener
    spacing (vtb.analysis.track.DEFAULT_DECAY_POSITIONS × a), truncated at the end of the structure:
    the result equals the estimator with those positions given explicitly."""
    cfg = two_layer_track("fem")
    f = [300.0, 1000.0]
    d = 0.6 * np.asarray(vtb.analysis.track.DEFAULT_DECAY_POSITIONS)
    d = d[d <= 6.0 + 1e-9]
    assert np.allclose(vtb.decay_rate(cfg, f), vtb.decay_rate(cfg, f, x0=6.0, positions=d, direction=1))
    assert np.all(vtb.decay_rate(cfg, f) > 0)


# ---------------------------------------------------------------------------- bad input
CFG_SMALL = two_layer_track("fem")

BAD = [
    ("frequencies", lambda: vtb.receptance(CFG_SMALL, 6.0, [-1.0])),
    ("frequencies", lambda: vtb.receptance(CFG_SMALL, 6.0, [100.0, float("nan")])),
    ("frequencies", lambda: vtb.receptance(CFG_SMALL, 6.0, float("inf"))),
    ("frequencies", lambda: vtb.receptance(CFG_SMALL, 6.0, [])),
    ("frequencies", lambda: vtb.receptance(CFG_SMALL, 6.0, "loud")),
    ("frequencies", lambda: vtb.receptance(CFG_SMALL, 6.0, [[1.0, 2.0]])),
    ("x", lambda: vtb.receptance(CFG_SMALL, -0.1, [100.0])),
    ("x", lambda: vtb.receptance(CFG_SMALL, 12.5, [100.0])),
    ("x", lambda: vtb.receptance(CFG_SMALL, float("nan"), [100.0])),
    ("x", lambda: vtb.receptance(CFG_SMALL, [1.0, 2.0], [100.0])),
    ("response_x", lambda: vtb.receptance(CFG_SMALL, 6.0, [100.0], response_x=[1.0, 13.0])),
    ("layer", lambda: vtb.receptance(CFG_SMALL, 6.0, [100.0], layer="girder")),
    ("layer", lambda: vtb.receptance(CFG_SMALL, 6.0, [100.0], layer=2)),
    ("layer", lambda: vtb.receptance(CFG_SMALL, 6.0, [100.0], layer=True)),
    ("response_layer", lambda: vtb.receptance(CFG_SMALL, 6.0, [100.0], response_layer="ground")),
    ("config", lambda: vtb.receptance("track.toml", 6.0, [100.0])),
    ("frequencies", lambda: vtb.receptance(winkler_beam(10.0, 20, foundation=False), 5.0, [0.0])),
    ("fmax", lambda: vtb.modes(CFG_SMALL, 0.0)),
    ("fmax", lambda: vtb.modes(CFG_SMALL, -5.0)),
    ("fmax", lambda: vtb.modes(CFG_SMALL, float("nan"))),
    ("fmax", lambda: vtb.modes(CFG_SMALL, "high")),
    ("fmin", lambda: vtb.modes(CFG_SMALL, 100.0, fmin=-1.0)),
    ("fmin", lambda: vtb.modes(CFG_SMALL, 100.0, fmin=100.0)),
    ("frequencies", lambda: vtb.decay_rate(CFG_SMALL, [0.0, -3.0])),
    ("x0", lambda: vtb.decay_rate(CFG_SMALL, [100.0], x0=20.0)),
    ("positions", lambda: vtb.decay_rate(CFG_SMALL, [100.0], positions=[0.0, 2.0, 1.0])),
    ("positions", lambda: vtb.decay_rate(CFG_SMALL, [100.0], positions=[0.0, 7.0], x0=6.0, direction=1)),
    ("positions", lambda: vtb.decay_rate(CFG_SMALL, [100.0], positions=[0.0, -1.0])),
    ("positions", lambda: vtb.decay_rate(CFG_SMALL, [100.0], positions=[0.0])),
    ("direction", lambda: vtb.decay_rate(CFG_SMALL, [100.0], direction=2)),
    ("layer", lambda: vtb.decay_rate(CFG_SMALL, [100.0], layer="beam")),
    ("layer", lambda: vtb.modes(CFG_SMALL, 200.0).displacement("beam", [1.0])),
    ("x", lambda: vtb.modes(CFG_SMALL, 200.0).displacement("rail", [13.0])),
    ("mode", lambda: vtb.modes(CFG_SMALL, 200.0).displacement("rail", [1.0], mode=10_000)),
]


@pytest.mark.parametrize("field,call", BAD, ids=[f"{f}-{i}" for i, (f, _) in enumerate(BAD)])
def test_bad_input_raises_config_error_naming_the_argument(field, call):
    with pytest.raises(vtb.ConfigError) as e:
        call()
    assert e.value.field.split("[")[0] == field
    assert field in str(e.value)


def test_invalid_structure_is_reported_by_its_field():
    cfg = two_layer_track("fem")
    cfg.structure.layers[1].youngs_modulus = -1.0
    with pytest.raises(vtb.ConfigError, match="youngs_modulus"):
        vtb.receptance(cfg, 6.0, [100.0])
