"""Checks that need no model run before anything costly (docs/resolution.md, "The irregularity
against the grade"): each irregularity part against the band the model resolves for the rail,
and the core's whole validation before a synthesis reduction is built. A build is replaced by
one that fails the test, so a check that came after it would show."""

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
