"""Checks that need no model run before anything costly (docs/resolution.md, "The irregularity
against the grade"): each irregularity part against the band the model resolves for the rail,
and the core's whole validation before a synthesis reduction is built. A build is replaced by
one that fails the test, so a check that came after it would show."""

import dataclasses
import time
import warnings

import pytest

import vtb
from vtb.run import synthesis


@pytest.fixture
def no_build(monkeypatch, tmp_path):
    """Any reduction build fails the test; the cache is empty."""
    monkeypatch.setenv(synthesis.CACHE_ENV, str(tmp_path))
    synthesis._MEMORY.clear()

    def refuse(*_a, **_k):
        raise AssertionError("a reduction build started")

    monkeypatch.setattr(synthesis, "build", refuse)
    yield
    synthesis._MEMORY.clear()


def passage(short_wave: bool = True):
    """The passage grade of the docs (synthesis below 300 Hz, Δt = 2e-4 s) at 300 km/h under a
    long-wave spectrum, with the article's short-wave spectrum from 4 cm as a part."""
    c = vtb.paper_config(model="fast")
    c.discretisation.synthesis_cutoff = 300.0
    c.solver.dt = 2e-4
    c.speed = 300.0 / 3.6
    c.output.band_limit = 150.0
    parts = [vtb.Irregularity(kind="tbt3352", wavelength_min=0.04, wavelength_max=1.0)] if short_wave else []
    c.irregularity = vtb.Irregularity(kind="german_low", wavelength_min=2.0, wavelength_max=80.0, parts=parts)
    return c


def test_a_short_wave_part_beyond_the_rails_band_warns_before_any_set_up(no_build):
    """v/λ = 2.1 kHz on a model that resolves the rail to 150 Hz: a ResolutionWarning naming the
    part, its band and what takes it, before the reduction is built (as an error here, the
    warning stops the run before the build would)."""
    c = passage()
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("error", vtb.ResolutionWarning)
        with pytest.raises(vtb.ResolutionWarning) as w:
            vtb.simulate(c, progress=False)
    assert time.perf_counter() - t0 < 1.0
    msg = str(w.value)
    assert "irregularity.parts[0].wavelength_min" in msg and "2083 Hz" in msg and "150 Hz" in msg, msg
    assert "synthesis_cutoff ≥ 4167 Hz" in msg and "solver.dt ≤" in msg and "0.556 m" in msg, msg


def test_the_presets_and_a_resolved_part_do_not_warn():
    """The shipped grades with their own spectra stay quiet, and so does the passage once its
    part starts at the wavelength the message names."""
    for c in (vtb.paper_config(), vtb.paper_config(model="fast"), vtb.paper_config(model="converged")):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            vtb.config.prepare.prepare(c)
        assert not [w for w in caught if "excites the rail" in str(w.message)]
    c = passage()
    c.irregularity.parts[0].wavelength_min = 0.556
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        vtb.config.prepare.prepare(c)
    assert not [w for w in caught if "excites the rail" in str(w.message)]


def test_a_corrugation_beyond_the_band_warns():
    c = passage(short_wave=False)
    c.irregularity.parts = [vtb.Irregularity(kind="corrugation", amplitude=2e-5, wavelength=0.06, start=0.0, end=160.0)]
    with pytest.warns(vtb.ResolutionWarning, match=r"irregularity.parts\[0\].wavelength = 0.06 m"):
        vtb.config.prepare.prepare(c)


def test_the_cores_validation_refuses_before_a_reduction_is_built(no_build):
    """A field the core refuses (a band limit beyond the time step's Nyquist frequency) is
    named before the reduction is built, in under a second."""
    c = passage(short_wave=False)
    c.output.band_limit = 5000.0  # Δt = 2e-4 s: Nyquist 2.5 kHz
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", vtb.ResolutionWarning)
        with pytest.raises(vtb.ConfigError, match="output.band_limit"):
            vtb.simulate(c, progress=False)
    assert time.perf_counter() - t0 < 1.0


def test_a_part_beyond_the_band_is_run_without_its_unresolved_wavelengths():
    """The profile a run rolls on drops the out-of-band part's wavelengths below v/f_max and
    keeps the rest of its draw: against an FFT low-pass of the unfiltered draw (the inverse-FFT
    spectra), and a corrugation beyond the band left out."""
    import numpy as np

    c = passage()
    with pytest.warns(vtb.ResolutionWarning, match=r"leaves those wavelengths out of irregularity.parts\[0\]") as w:
        text, profile = vtb.config.prepare.prepare(c)
    cut = c.speed / vtb.resolved_band(c).rail.f_max  # v/f_max, 0.556 m
    assert "0.556 m" in str(w[0].message)
    part = c.irregularity.parts[0]
    lo, hi = profile.x0, profile.x0 + profile.dx * (profile.values.size - 1)
    x0, dx, raw, _ = part.sample(lo, hi)
    _, _, kept, _ = part.sample(lo, hi, shortest={"irregularity": cut})
    spectrum = np.fft.rfft(raw)
    spectrum[np.fft.rfftfreq(raw.size, dx) > 1.0 / cut] = 0.0
    assert np.abs(kept - np.fft.irfft(spectrum, n=raw.size)).max() < 1e-9 * np.abs(raw).max()
    # what was left out: the part's roughness below the cut, as its spectrum integrates it
    gone = np.sqrt(vtb.config.irregularity.band_variance("tbt3352", 0.04, cut))
    assert abs(np.std(raw - kept) - gone) < 0.03 * gone
    # What the run rolls on: the irregularity with that part kept so (also when asked for alone).
    a, b = vtb.config.prepare._rolled_extent(c, text)
    _, _, whole, _ = c.irregularity.sample(a, b, shortest={"irregularity.parts[0]": cut})
    assert np.array_equal(profile.values, whole)
    vtb.config.prepare._profiles.clear()
    assert np.array_equal(vtb.irregularity_profile(c).values, whole)
    # A corrugation beyond the band: left out.
    c = passage(short_wave=False)
    c.irregularity.parts = [vtb.Irregularity(kind="corrugation", amplitude=2e-5, wavelength=0.06, start=0.0, end=160.0)]
    with pytest.warns(vtb.ResolutionWarning):
        text, profile = vtb.config.prepare.prepare(c)
    base = dataclasses.replace(c.irregularity, parts=[])
    x0, dx, values, _ = base.sample(*vtb.config.prepare._rolled_extent(c, text))
    grid = profile.x0 + profile.dx * np.arange(profile.values.size)
    assert np.array_equal(profile.values, np.interp(grid, x0 + dx * np.arange(values.size), values))
