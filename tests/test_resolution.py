"""What each discretisation resolves (vtb.resolved_band, docs/resolution.md), and the warnings
of the functions asked beyond it. The core's Bloch analysis is held against the continuous
beams in ``cargo test`` (resolution::tests)."""

import math
import warnings

import numpy as np
import pytest
from scipy.optimize import brentq

import vtb


def test_the_time_step_limit_is_newmarks_one_percent_period_error():
    # Newmark's average acceleration maps ω to 2·atan(ωΔt/2)/Δt: 1 % low at ωΔt = x.
    x = brentq(lambda x: 1 - 2 * math.atan(x / 2) / x - 0.01, 0.01, 2.0)
    for model, dt in (("article", 5e-5), ("converged", 2.5e-5)):
        band = vtb.resolved_band(vtb.paper_config(model=model))
        assert band.rail.time_f_max == pytest.approx(x / (2 * math.pi * dt), rel=1e-9)


def test_the_article_hybrid_holds_no_pinned_pinned_mode_and_the_converged_preset_does():
    art = vtb.resolved_band(vtb.paper_config())
    # 120 sines on 160 m: the shortest wavelength is 2L/N = 2.67 m, and its free bending wave
    # EI·k⁴ = ρA·ω² (k = Nπ/L) is the basis limit.
    rail = vtb.paper_config().structure.layers[0]
    k = 120 * math.pi / 160.0
    f = math.sqrt(rail.youngs_modulus * rail.inertia * k**4 / (rail.density * rail.area)) / (2 * math.pi)
    assert art.rail.shortest_wavelength == pytest.approx(2 * 160.0 / 120, rel=1e-12)
    assert art.rail.basis_f_max == pytest.approx(f, rel=1e-12)
    assert not art.holds_pinned_pinned and art.rail.limited_by == "basis"
    conv = vtb.resolved_band(vtb.paper_config(model="converged"))
    assert conv.holds_pinned_pinned and conv.rail.limited_by == "time step"
    assert conv.pinned_pinned == pytest.approx(vtb.pinned_pinned_frequency(vtb.paper_config(model="converged")))
    assert "not held" in str(art) and "held" in str(conv)


def test_a_receptance_beyond_the_basis_warns_and_within_it_does_not():
    art = vtb.paper_config()
    with pytest.warns(vtb.ResolutionWarning, match="the receptance reaches 1000 Hz"):
        vtb.receptance(art, 80.32, [100.0, 1000.0])
    with warnings.catch_warnings():
        warnings.simplefilter("error", vtb.ResolutionWarning)
        vtb.receptance(art, 80.32, [100.0, 250.0])
        # A frequency-domain answer has no time step: the converged basis reaches 5 kHz.
        vtb.receptance(vtb.paper_config(model="converged"), 80.32, [1000.0, 3000.0])


def test_decay_rate_and_band_levels_warn_beyond_the_band():
    art = vtb.paper_config()
    with pytest.warns(vtb.ResolutionWarning, match="decay rate"):
        vtb.decay_rate(art, [500.0, 2000.0])
    from fuzz_cases import small_config

    r = vtb.simulate(small_config(t_end=0.05, tids=False))
    with pytest.warns(vtb.ResolutionWarning, match="top band"):
        r.third_octave("rail")


def test_a_band_limit_beyond_the_band_warns():
    from fuzz_cases import small_config

    cfg = small_config(t_end=0.002, tids=False)
    cfg.output.band_limit = 2000.0
    with pytest.warns(vtb.ResolutionWarning, match="output.band_limit reaches 2000 Hz"):
        vtb.simulate(cfg)
