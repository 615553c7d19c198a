"""Band-limited indices (``output.band_limit``, docs/model.md §8): the core's zero-phase filter
against SciPy's independent ``sosfiltfilt`` of an 8th-order Butterworth, and every index of a
band-limited run against the same indices of the filtered raw record."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.signal import butter, sosfiltfilt

import vtb
from fuzz_cases import small_config


def scipy_low_pass(x, fc, dt):
    return sosfiltfilt(butter(8, fc, fs=1.0 / dt, output="sos"), x)


@pytest.mark.parametrize("fc,dt", [(2000.0, 2.5e-5), (2000.0, 5e-5), (500.0, 5e-5), (9000.0, 5e-5), (20.0, 1e-3)])
def test_core_filter_matches_scipy_sosfiltfilt(fc, dt):
    x = np.random.default_rng(7).standard_normal(4000).cumsum() * 0.1 + np.random.default_rng(8).standard_normal(4000)
    got, want = vtb.low_pass(x, fc, dt), scipy_low_pass(x, fc, dt)
    assert np.abs(got - want).max() <= 1e-10 * np.abs(want).max()


def test_filter_gain_is_the_squared_butterworth_magnitude():
    # A steady sine is scaled by 1/(1 + (f/fc)^16) (bilinear warping included); −6 dB at fc.
    dt, fc = 2.5e-5, 2000.0
    t = np.arange(40000) * dt
    for f in (800.0, 1600.0, 2000.0, 2500.0):
        y = vtb.low_pass(np.sin(2 * np.pi * f * t), fc, dt)[10000:30000]
        r = math.tan(math.pi * f * dt) / math.tan(math.pi * fc * dt)
        assert np.abs(y).max() == pytest.approx(1.0 / (1.0 + r**16), rel=2e-3, abs=1e-4)


def run_pair(band_limit, window=None):
    cfg = small_config(t_end=0.02, tids=False)
    cfg.output.window = window
    raw = vtb.simulate(cfg)
    cfg.output.band_limit = band_limit
    return raw, vtb.simulate(cfg)


def test_band_limited_indices_are_the_indices_of_the_filtered_record():
    raw, lim = run_pair(2000.0)
    m, dt = lim.metrics(), raw.t[1] - raw.t[0]
    for i, name in enumerate(raw.layer_names):
        a = scipy_low_pass(raw.acc[:, i, 0], 2000.0, dt)
        assert m[f"{name}_acc_max"] == pytest.approx(np.abs(a).max(), rel=1e-9)
        assert m[f"{name}_acc_rms"] == pytest.approx(np.sqrt(np.mean(a**2)), rel=1e-9)
        # The raw peak stays, labelled.
        assert m[f"{name}_acc_max_raw"] == pytest.approx(np.abs(raw.acc[:, i, 0]).max(), rel=1e-12)
        assert m[f"{name}_disp_max"] == raw.metrics()[f"{name}_disp_max"]
    car = scipy_low_pass(raw.car_body_acc, 2000.0, dt)
    assert m["car_acc_max"] == pytest.approx(np.abs(car).max(), rel=1e-9)
    # Without a band limit there is no raw label: the plain names are the raw indices.
    assert "rail_acc_max_raw" not in raw.metrics()
    assert vtb.metric_unit("rail_acc_max_raw") == "m/s²"


def test_the_record_is_filtered_whole_before_the_window():
    raw, lim = run_pair(1000.0, window=[0.005, 0.015])
    dt = raw.t[1] - raw.t[0]
    a = scipy_low_pass(raw.acc[:, 0, 0], 1000.0, dt)
    inside = (raw.t >= 0.005 - 1e-12) & (raw.t <= 0.015 + 1e-12)
    assert lim.metrics()["rail_acc_max"] == pytest.approx(np.abs(a[inside]).max(), rel=1e-9)


@pytest.mark.parametrize("bad", [0.0, -5.0, float("nan"), float("inf"), 10000.0, 1e9])
def test_a_bad_band_limit_names_the_field(bad):
    cfg = small_config(t_end=0.002, tids=False)  # Δt = 5e-5 s: Nyquist 10 kHz
    cfg.output.band_limit = bad
    with pytest.raises(vtb.ConfigError) as e:
        vtb.simulate(cfg)
    assert e.value.field == "output.band_limit"


@pytest.mark.parametrize("x,fc,dt,field", [
    (np.ones(10), 3000.0, 2e-4, "band_limit"),
    (np.ones(10), 100.0, 0.0, "dt"),
    (np.ones(10), 100.0, float("nan"), "dt"),
    (np.array([1.0, float("nan"), 2.0]), 100.0, 1e-3, "x"),
    (np.ones((3, 3)), 100.0, 1e-3, "x"),
    (np.ones(1), 100.0, 1e-3, "x"),
])
def test_low_pass_refuses_bad_input_by_name(x, fc, dt, field):
    with pytest.raises(vtb.ConfigError) as e:
        vtb.low_pass(x, fc, dt)
    assert e.value.field == field


@settings(max_examples=30, deadline=None)
@given(st.lists(st.floats(-1e6, 1e6), min_size=2, max_size=300), st.floats(1.0, 499.0))
def test_low_pass_is_finite_and_keeps_constants(values, fc):
    x = np.array(values)
    y = vtb.low_pass(x, fc, 1e-3)
    assert np.isfinite(y).all() and y.shape == x.shape
    assert np.allclose(vtb.low_pass(np.full(len(values), 3.0), fc, 1e-3), 3.0, rtol=1e-12)
