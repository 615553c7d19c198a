"""Irregularity spectra and generators."""

import math

import numpy as np
import pytest
from scipy import signal

import vtb
from vtb.config import irregularity as irr
from vtb.errors import ConfigError
from vtb.config.irregularity import Irregularity

SPECTRA = ["tbt3352", "sato", "iso3095", "german_low", "german_high", "fra1", "fra6"]


def test_tbt3352_segments_are_continuous_and_published_rms():
    """Segments meet at their break frequencies to < 0.4 %, and the 2–200 m band has an RMS of
    1.22 mm, 2–120 m 0.72 mm, 2–70 m 0.46 mm."""
    for fb in irr.TBT3352_BREAKS:
        below, above = irr.psd_tbt3352(np.array([fb * (1 - 1e-12)]))[0], irr.psd_tbt3352(np.array([fb * (1 + 1e-12)]))[0]
        assert abs(below / above - 1) < 0.004
    for lmax, rms_mm in [(200.0, 1.22), (120.0, 0.72), (70.0, 0.46)]:
        rms = math.sqrt(irr.band_variance("tbt3352", 2.0, lmax)) * 1e3
        assert rms == pytest.approx(rms_mm, rel=0.01)


def test_sato_unit_reading_and_rms():
    """Sato with Ω in rad/m: S_f = A/(4π²f³); A = 4.15e−8 gives 23 µm RMS over 0.01–1 m and
    A = 5e−7 80 µm."""
    f = np.array([1.0, 10.0])
    assert irr.psd_sato(f) == pytest.approx(4.15e-8 / (4 * math.pi**2 * f**3))
    assert math.sqrt(irr.band_variance("sato", 0.01, 1.0, sato_a=4.15e-8)) == pytest.approx(23e-6, rel=0.02)
    assert math.sqrt(irr.band_variance("sato", 0.01, 1.0, sato_a=5e-7)) == pytest.approx(80e-6, rel=0.02)


def test_iso3095_band_values():
    """The 1/3-octave limit converted to a one-sided PSD: λ = 40 cm → 8.9e−11 m³, 10 cm →
    1.34e−12, 1 cm → 6.9e−15; total RMS over the 22 bands 11.7 µm."""
    for lam_cm, s_ref in [(40, 8.9e-11), (10, 1.34e-12), (1, 6.9e-15)]:
        assert irr.psd_iso3095(np.array([100.0 / lam_cm]))[0] == pytest.approx(s_ref, rel=0.01)
    total = sum(10 ** (lev / 10) for _, lev in irr.ISO3095_LIMIT) * 1e-12
    assert math.sqrt(total) == pytest.approx(11.7e-6, rel=0.01)


def test_unit_conversions_of_angular_spectra():
    """German and FRA spectra are published per rad/m: S_f(f) = 2π·S_Ω(2πf); FRA in cm²."""
    f = 0.05
    w = 2 * math.pi * f
    s_omega = 4.032e-7 * 0.8246**2 / ((w**2 + 0.0206**2) * (w**2 + 0.8246**2))
    assert irr.psd_german(np.array([f]), "low")[0] == pytest.approx(2 * math.pi * s_omega)
    s_cm2 = 0.25 * 0.0339 * 0.8245**2 / (w**2 * (w**2 + 0.8245**2))
    assert irr.psd_fra(np.array([f]), 6)[0] == pytest.approx(2 * math.pi * s_cm2 * 1e-4)


def _welch_check(kind, lmin, lmax, method, dx, n_samples, seed):
    cfg = Irregularity(kind=kind, wavelength_min=lmin, wavelength_max=lmax, method=method, seed=seed, dx=dx)
    x0, dx_out, r = cfg.profile(0.0, (n_samples - 1) * dx)
    assert dx_out == dx and r.size == n_samples
    s = irr.psd(kind)
    # Variance against the spectrum's band integral.
    assert np.var(r) == pytest.approx(irr.band_variance(kind, lmin, lmax), rel=0.05)
    f, pxx = signal.welch(r, fs=1.0 / dx, window="hann", nperseg=4096, noverlap=2048)
    f_lo, f_hi = 1.0 / lmax, 1.0 / lmin
    inner = (f > f_lo * 1.25) & (f < f_hi / 1.25)
    ratio = pxx[inner] / s(f[inner])
    # Band-averaged ratio in 1/3-octave bands.
    edges = f_lo * 1.25 * 2 ** (np.arange(0, 40) / 3)
    for a, b in zip(edges[:-1], edges[1:]):
        sel = (f[inner] >= a) & (f[inner] < b)
        if sel.sum() >= 8:
            assert np.mean(ratio[sel]) == pytest.approx(1.0, abs=0.10), (kind, method, a, b)


@pytest.mark.parametrize("kind", SPECTRA)
@pytest.mark.parametrize("method", ["ifft", "spectral"])
def test_generated_profiles_reproduce_their_psd(kind, method):
    """Welch estimate / target PSD averaged over 1/3-octave bands within ±10 %, sample variance
    within ±5 % of the band integral; short-wave band for the roughness spectra, long-wave
    band for the track-geometry ones."""
    if kind in ("tbt3352", "german_low", "german_high", "fra1", "fra6"):
        lmin, lmax, dx = 2.0, 100.0, 0.25
    else:
        lmin, lmax, dx = 0.01, 1.0, 0.001
    n = 2**17 if method == "ifft" else 2**16
    _welch_check(kind, lmin, lmax, method, dx, n, seed=7)


def test_profiles_are_reproducible_from_the_seed():
    a = Irregularity(kind="tbt3352", seed=3).profile(0, 160)[2]
    b = Irregularity(kind="tbt3352", seed=3).profile(0, 160)[2]
    c = Irregularity(kind="tbt3352", seed=4).profile(0, 160)[2]
    assert np.array_equal(a, b) and not np.array_equal(a, c)
    s1 = Irregularity(kind="sato", method="spectral", seed=1, n_freq=300).profile(0, 10)[2]
    s2 = Irregularity(kind="sato", method="spectral", seed=1, n_freq=300).profile(0, 10)[2]
    assert np.array_equal(s1, s2)


def test_ifft_variance_is_exact():
    """The inverse-FFT method has deterministic amplitudes: variance = Σ S(f_k)·Δf exactly."""
    n, dx = 2**14, 0.01
    r = irr.generate_ifft(irr.psd_sato, n, dx, 1.0, 20.0, np.random.default_rng(0))
    df = 1 / (n * dx)
    f = np.arange(n // 2 + 1) * df
    band = (f >= 1.0) & (f <= 20.0)
    assert np.mean(r**2) == pytest.approx(np.sum(irr.psd_sato(f[band]) * df), rel=1e-12)


def test_deterministic_shapes():
    dip = Irregularity(kind="cosine_dip", depth=2e-3, length=1.0, position=5.0, dx=0.01)
    x0, dx, r = dip.profile(0.0, 10.0)
    x = x0 + dx * np.arange(r.size)
    assert r.max() == pytest.approx(2e-3) and x[np.argmax(r)] == pytest.approx(5.5)
    assert np.all(r[(x < 5.0) | (x > 6.0)] == 0.0) and np.all(r >= 0)
    cor = Irregularity(kind="corrugation", amplitude=1e-4, wavelength=0.05, start=2.0, end=3.0, dx=0.001)
    _, _, r = cor.profile(0.0, 5.0)
    assert r.max() == pytest.approx(1e-4, rel=1e-3) and r.min() == 0.0
    user = Irregularity(kind="sampled", x0=-1.0, dx=0.5, values=[0.0, 1e-3, 0.0, -1e-3], scale=2.0)
    assert user.profile(0, 1)[2].tolist() == [0.0, 2e-3, 0.0, -2e-3]


@pytest.mark.parametrize(
    "changes,field",
    [
        ({"kind": "nope"}, "irregularity.kind"),
        ({"kind": "sato", "wavelength_min": 0.0}, "irregularity.wavelength_min"),
        ({"kind": "sato", "wavelength_max": 0.005}, "irregularity.wavelength_max"),
        ({"kind": "sato", "method": "magic"}, "irregularity.method"),
        ({"kind": "sato", "scale": -1.0}, "irregularity.scale"),
        ({"kind": "sato", "dx": 0.01}, "irregularity.dx"),
        ({"kind": "sampled", "dx": 0.1, "values": [0.0, float("nan")]}, "irregularity.values[1]"),
        ({"kind": "cosine_dip", "length": 0.0}, "irregularity.length"),
    ],
)
def test_bad_settings_name_the_field(changes, field):
    with pytest.raises(ConfigError) as e:
        Irregularity(**changes).validate()
    assert e.value.field == field


def test_band_beyond_time_step_resolution_is_rejected():
    """At 80 m/s and Δt = 5e−5 s, wavelengths below 2·v·Δt = 8 mm cannot be resolved."""
    Irregularity(kind="tbt3352", wavelength_min=0.01).validate(speed=80, dt=5e-5)
    with pytest.raises(ConfigError) as e:
        Irregularity(kind="tbt3352", wavelength_min=0.006, dx=0.001).validate(speed=80, dt=5e-5)
    assert e.value.field == "irregularity.wavelength_min"


@pytest.mark.parametrize("kind", [[], 3, None])
def test_a_kind_that_is_no_name_is_refused_naming_it(kind):
    """Found by the fuzzer: a list as the kind raised a raw TypeError while the core's default
    ω_r looked up the excited band; it is refused as the kind's own error."""
    c = vtb.paper_config()
    c.solver.t_end = 0.01
    c.irregularity.kind = kind
    with pytest.raises(vtb.ConfigError) as e:
        vtb.simulate(c, progress=False)
    assert e.value.field == "irregularity.kind"
