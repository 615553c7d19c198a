"""ISO 2631-1 ride comfort: the Wk weighting against the standard's Table 3, the digital
filter against the analogue weighting, and a_w and MTVV of signals with known answers."""

import math
import warnings

import numpy as np
import pytest

import vtb
from fuzz_cases import small_config
from vtb.analysis import comfort

#: ISO 2631-1:1997 Table 3, Wk × 1000 at the nominal one-third-octave frequencies (Hz).
ISO_2631_WK = {
    0.1: 31.2, 0.125: 48.6, 0.16: 79.0, 0.2: 121, 0.25: 182, 0.315: 263, 0.4: 352, 0.5: 418, 0.63: 459, 0.8: 477,
    1.0: 482, 1.25: 484, 1.6: 494, 2.0: 531, 2.5: 631, 3.15: 804, 4.0: 967, 5.0: 1039, 6.3: 1054, 8.0: 1036,
    10.0: 988, 12.5: 902, 16.0: 768, 20.0: 636, 25.0: 513, 31.5: 405, 40.0: 314, 50.0: 246, 63.0: 186, 80.0: 132,
    100.0: 88.7, 125.0: 54.0, 160.0: 28.5, 200.0: 15.2, 250.0: 7.90, 315.0: 3.98, 400.0: 1.95,
}


def test_wk_matches_the_standards_table():
    f = np.array(list(ISO_2631_WK))
    table = np.array(list(ISO_2631_WK.values())) / 1000
    # the table gives three significant digits
    assert np.abs(comfort.wk(f) / table - 1).max() < 0.004


@pytest.mark.parametrize("fs", [4000.0, 20_000.0])
def test_the_digital_filter_is_the_analogue_weighting(fs):
    from scipy.signal import sosfreqz

    f = np.geomspace(0.2, 100.0, 60)
    _, h = sosfreqz(comfort.wk_sos(fs), worN=f, fs=fs)
    assert np.abs(np.abs(h) / comfort.wk(f) - 1).max() < 0.01


@pytest.mark.parametrize("f0", [1.0, 4.0, 6.3, 25.0])
def test_weighted_rms_and_mtvv_of_a_sine(f0):
    fs, a0 = 1000.0, 0.8
    t = np.arange(int(120 * fs)) / fs
    ramp = np.minimum(t / 10.0, 1.0)  # faded in: the filter's start-up transient would set MTVV
    out = comfort.iso2631(a0 * ramp * np.sin(2 * math.pi * f0 * t), fs)
    expected = a0 / math.sqrt(2) * float(comfort.wk(f0))
    steady = math.sqrt((110 + 10 / 3) / 120)  # the r.m.s. share of the record (ramp included)
    assert out["a_w"] == pytest.approx(expected * steady, rel=0.01)
    # a 1 s window over a non-whole number of periods ripples by up to 1/(4π·f0·τ) of the r.m.s.
    assert expected <= out["mtvv"] * 1.005 and out["mtvv"] <= expected * (1.005 + 1 / (4 * math.pi * f0))
    assert out["duration"] == pytest.approx(120.0)


def test_mtvv_catches_a_one_second_burst():
    fs, a0, f0 = 1000.0, 1.0, 5.0
    t = np.arange(int(60 * fs)) / fs
    a = np.where((t >= 30) & (t < 31), a0 * np.sin(2 * math.pi * f0 * t), 0.0)
    out = comfort.iso2631(a, fs)
    burst = a0 / math.sqrt(2) * float(comfort.wk(f0))
    assert out["mtvv"] == pytest.approx(burst, rel=0.05)
    assert out["a_w"] == pytest.approx(burst / math.sqrt(60), rel=0.05)
    assert out["mtvv_ratio"] > 1.5


def test_short_records_warn_and_runs_report_their_car_body():
    with pytest.warns(comfort.ComfortWarning, match="20 s"):
        comfort.iso2631(np.sin(np.arange(2000) * 0.05), 1000.0)
    cfg = small_config(t_end=0.2, tids=False)
    res = vtb.simulate(cfg)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", comfort.ComfortWarning)
        c = res.comfort()
        w = res.comfort(window=(0.1, 0.2))
    assert c["a_w"] > 0 and c["wz"] > 0 and math.isnan(c["mtvv"]) and w["duration"] == pytest.approx(0.1, abs=1e-3)
    with pytest.raises(vtb.ConfigError) as e:
        res.comfort(car=3)
    assert e.value.field == "car"
    with pytest.raises(vtb.ConfigError) as e:
        comfort.wk_sos(100.0)
    assert e.value.field == "fs"


#: Sperling's vertical correction factor F(f) as the standards tabulate it (0.325 f² on
#: 0.5–5.9 Hz, 400/f² on 5.9–20 Hz, 1 above), at round frequencies (Hz).
SPERLING_F_TABLE = {0.5: 0.08125, 1.0: 0.325, 2.0: 1.3, 4.0: 5.2, 5.0: 8.125, 6.0: 11.11, 8.0: 6.25, 10.0: 4.0, 15.0: 1.778, 20.0: 1.0, 30.0: 1.0}


def test_sperling_correction_factor_matches_the_table():
    f = np.array(list(SPERLING_F_TABLE))
    assert np.allclose(comfort.sperling_f(f), list(SPERLING_F_TABLE.values()), rtol=1e-3)
    assert comfort.sperling_f(0.3) == 0.0


@pytest.mark.parametrize("f0", [1.0, 4.0, 8.0, 25.0])
def test_sperling_of_a_sine_is_sperlings_displacement_formula(f0):
    # Sperling's original form rates a harmonic displacement of z cm at f Hz as
    # Wz = 2.7·(z³·f⁵·F(f))^(1/10); the acceleration form's 0.896 must agree with it.
    fs, z_cm = 2000.0, 0.05 / f0
    t = np.arange(int(10 * fs)) / fs  # a whole number of periods: one spectral line
    a = (z_cm / 100) * (2 * math.pi * f0) ** 2 * np.sin(2 * math.pi * f0 * t)
    expected = 2.7 * (z_cm**3 * f0**5 * float(comfort.sperling_f(f0))) ** 0.1
    assert comfort.sperling(a, fs)["wz"] == pytest.approx(expected, rel=1e-3)


def test_sperling_components_combine_as_a_tenth_power_sum_within_its_band():
    fs = 2000.0
    t = np.arange(int(10 * fs)) / fs
    one = 0.3 * np.sin(2 * math.pi * 1.5 * t)
    two = 0.5 * np.sin(2 * math.pi * 9.0 * t)
    w1, w2 = (comfort.sperling(x, fs)["wz"] for x in (one, two))
    assert comfort.sperling(one + two, fs)["wz"] == pytest.approx((w1**10 + w2**10) ** 0.1, rel=1e-9)
    # 60 Hz lies outside the index's 0.5–40 Hz band
    assert comfort.sperling(one + 2.0 * np.sin(2 * math.pi * 60.0 * t), fs)["wz"] == pytest.approx(w1, rel=1e-9)
    with pytest.warns(comfort.ComfortWarning, match="5 s"):
        comfort.sperling(one[:4000], fs)
