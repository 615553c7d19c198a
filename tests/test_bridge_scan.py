"""A moving-load speed scan of a simply supported span against Frýba's closed-form modal series
(L. Frýba, Vibration of Solids and Structures under Moving Loads, 3rd ed., 1999, §1.2: a
constant force crossing a simply supported Euler–Bernoulli beam; the modes' responses summed
over the axles), written here independently of vtb: at resonance and off it the peak deck
acceleration in the check's band agrees within 1 %, and the scan's peaks fall at the resonant
speeds n0·D/i within the scan step."""

import math

import numpy as np
import pytest

import vtb
from vtb.bridge.damping import code_damping, apply_code_damping
from vtb.bridge.load_trains import load_train
from vtb.bridge.scan import scan_speeds, speed_scan, with_band

L = 30.0           # span (m)
M = 15000.0        # mass per metre (kg/m)
N0 = 2.5           # first bending frequency (Hz)
EI = (2 * N0 * L**2 / math.pi) ** 2 * M   # n0 = (π / 2L²)·√(EI/m)
BAND = 30.0        # max(30 Hz, 1.5 n0, n3 = 22.5 Hz)
DT = 2.5e-4       # Newmark's error in the resonant peak: 1.2 % at 1e-3 s, 0.15 % at 2.5e-4 s (second order)
TAIL = 0.5
GAP = 1.0          # the first axle's distance before the span at t = 0 (m)


def _beam(speed=40.0, dt=DT):
    e = 3.5e10
    cfg = vtb.moving_load_config(L, 2500.0, M / 2500.0, e, EI / e, [vtb.MovingForce(1.0, 0.0)], speed, points=[L / 2], modes=40,
                                 dt=dt, initial_state="rest")
    cfg = with_band(cfg, BAND)
    return apply_code_damping(cfg, code_damping("prestressed_concrete", L), N0, BAND)


def _rayleigh_ratio(f, zeta, f1, f2):
    """ζ(f) of C = αM + βK fitted to ζ at f1 and f2 (Chopra, Dynamics of Structures, §11.4)."""
    w1, w2, w = 2 * math.pi * f1, 2 * math.pi * f2, 2 * math.pi * f
    a0 = zeta * 2 * w1 * w2 / (w1 + w2)
    a1 = zeta * 2 / (w1 + w2)
    return a0 / (2 * w) + a1 * w / 2


def _sdof_sine(t, amp, w, zeta, big_w):
    """q, q̇ of q̈ + 2ζωq̇ + ω²q = amp·sin(Ωt), q(0) = q̇(0) = 0 (closed form)."""
    den = (w**2 - big_w**2) ** 2 + (2 * zeta * w * big_w) ** 2
    a = amp * (w**2 - big_w**2) / den
    b = -amp * 2 * zeta * w * big_w / den
    wd = w * math.sqrt(1 - zeta**2)
    c1 = -b
    c2 = (zeta * w * c1 - a * big_w) / wd
    e = np.exp(-zeta * w * t)
    q = a * np.sin(big_w * t) + b * np.cos(big_w * t) + e * (c1 * np.cos(wd * t) + c2 * np.sin(wd * t))
    qd = (a * big_w * np.cos(big_w * t) - b * big_w * np.sin(big_w * t)
          + e * ((-zeta * w * c1 + wd * c2) * np.cos(wd * t) + (-zeta * w * c2 - wd * c1) * np.sin(wd * t)))
    return q, qd


def _mode_acceleration(n, p, speed, zeta, tau):
    """q̈_n (m/s² per unit mode shape) of mode n under one force p (N) that entered the span
    τ (s) ago: the forced response while it crosses, free vibration after it has left."""
    w, big_w, cross = 2 * math.pi * N0 * n**2, n * math.pi * speed / L, L / speed
    amp = 2 * p / (M * L)
    wd = w * math.sqrt(1 - zeta**2)
    on = (tau >= 0) & (tau <= cross)
    q, qd = _sdof_sine(np.where(on, tau, 0.0), amp, w, zeta, big_w)
    qdd_on = amp * np.sin(big_w * tau) - 2 * zeta * w * qd - w**2 * q
    q_t, qd_t = _sdof_sine(np.array([cross]), amp, w, zeta, big_w)
    s = tau - cross
    e = np.exp(-zeta * w * s)
    qf = e * (q_t * np.cos(wd * s) + (qd_t + zeta * w * q_t) / wd * np.sin(wd * s))
    qfd = e * (qd_t * np.cos(wd * s) - (w * q_t + zeta * qd_t) / math.sqrt(1 - zeta**2) * np.sin(wd * s))
    qdd_off = -2 * zeta * w * qfd - w**2 * qf
    return np.where(on, qdd_on, np.where(s > 0, qdd_off, 0.0))


def frýba_midspan_acceleration(positions, loads, speed, zeta_total, t):
    """Midspan acceleration (m/s²) of the simply supported beam under the axles (the first GAP
    before the span at t = 0, the others behind it), summed over the modes below the band (odd
    modes 1, 3: the even ones have a node at midspan), each weighted by the band's low-pass at
    its own frequency — the zero-phase 8th-order Butterworth of docs/indices.md,
    |H|² = 1/(1 + (f/fc)^16): 1 − 2e−17 for mode 1, 0.990 for mode 3 (its free vibration
    carries its response)."""
    acc = np.zeros_like(t)
    for n in (1, 3):
        f = N0 * n**2
        zeta = _rayleigh_ratio(f, zeta_total, N0, BAND)
        gain = 1 / (1 + (f / BAND) ** 16)
        for x, p in zip(positions, loads):
            acc += gain * math.sin(n * math.pi / 2) * _mode_acceleration(n, p, speed, zeta, t - (x + GAP) / speed)
    return acc


def _reference_peak(train, speed):
    zeta = code_damping("prestressed_concrete", L).ratio
    t = np.arange(0.0, (GAP + L + train.length) / speed + TAIL, 1e-4)
    return float(np.max(np.abs(frýba_midspan_acceleration(train.positions, train.loads, speed, zeta, t))))


def test_the_closed_form_solves_its_modal_equation():
    """The series' own check, independent of vtb: mode 1 under one force (crossing, then free
    vibration) equals a Runge–Kutta integration of q̈ + 2ζωq̇ + ω²q = (2P/mL)·sin(πvt/L)."""
    from scipy.integrate import solve_ivp

    speed, p, zeta = 40.0, 1e5, 0.02
    w, big_w, cross = 2 * math.pi * N0, math.pi * speed / L, L / speed

    def rhs(t, y):
        f = 2 * p / (M * L) * math.sin(big_w * t) if t <= cross else 0.0
        return [y[1], f - 2 * zeta * w * y[1] - w**2 * y[0]]

    t = np.linspace(0.0, 2.5 * cross, 801)
    sol = solve_ivp(rhs, (0.0, t[-1]), [0.0, 0.0], t_eval=t, rtol=1e-10, atol=1e-14, max_step=1e-3)
    qdd = np.array([rhs(ti, yi)[1] for ti, yi in zip(t, sol.y.T)])
    got = _mode_acceleration(1, p, speed, zeta, t)
    assert np.max(np.abs(got - qdd)) < 1e-5 * np.max(np.abs(qdd))


@pytest.mark.parametrize("speed", [45.0, 38.0, 55.0], ids=["resonance_i1", "below", "above"])
def test_scan_matches_fryba_at_and_off_resonance(speed):
    train = load_train("HSLM-A1")
    res = speed_scan(_beam(), [train], [speed], band=BAND, tail=TAIL, gap=GAP, progress=False)
    got = float(res.columns["acc"][0])
    ref = _reference_peak(train, speed)
    print(f"Frýba at {speed} m/s: vtb {got:.5f}, closed form {ref:.5f} m/s², {100 * (got / ref - 1):+.3f} %")
    assert abs(got / ref - 1) < 0.01, (speed, got, ref)


def test_scan_peaks_fall_at_the_resonant_speeds():
    """HSLM-A1 (D = 18 m) over the span: the acceleration peaks at n0·D = 45 m/s (i = 1) and
    n0·D/2 = 22.5 m/s (i = 2), each within the scan step."""
    step = 1.0
    speeds = scan_speeds(18.0, 52.0, step)
    res = speed_scan(_beam(dt=1e-3), ["HSLM-A1"], speeds, band=BAND, tail=TAIL, gap=GAP, progress=False, threads=2)
    acc, v = res.columns["acc"], res.columns["speed"]
    for resonance, lo, hi in ((45.0, 36.0, 52.0), (22.5, 18.0, 30.0)):
        window = (v >= lo) & (v <= hi)
        peak = v[window][np.argmax(acc[window])]
        assert abs(peak - resonance) <= step, (resonance, peak)


def test_scan_resumes_from_its_journals_and_runs_on_any_executor(tmp_path):
    """A scan journals each (train, bound) study; a re-run reads them and runs nothing; an
    executor (here one that runs each task at once, as a Dask client's would elsewhere) gives
    the batch's results bit for bit; the heavier bound (deck mass × 1.21) peaks at n0/1.1·D."""
    from concurrent.futures import Executor, Future

    class InPlace(Executor):
        submitted = 0

        def submit(self, fn, *args, **kwargs):
            InPlace.submitted += 1
            f = Future()
            f.set_result(fn(*args, **kwargs))
            return f

    speeds = [38.0, 40.0, 41.0, 42.0, 45.0]
    bounds = {"lower": 1.0, "upper": 1.21}
    first = speed_scan(_beam(dt=1e-3), ["HSLM-A1"], speeds, band=BAND, mass_bounds=bounds, out=tmp_path, progress=False)
    assert sorted(p.name for p in tmp_path.glob("*.csv")) == ["HSLM-A1__lower.csv", "HSLM-A1__upper.csv"]
    again = speed_scan(_beam(dt=1e-3), ["HSLM-A1"], speeds, band=BAND, mass_bounds=bounds, out=tmp_path, progress=False,
                       executor=InPlace())
    assert InPlace.submitted == 0
    np.testing.assert_array_equal(first.columns["acc"], again.columns["acc"])
    elsewhere = speed_scan(_beam(dt=1e-3), ["HSLM-A1"], speeds, band=BAND, mass_bounds=bounds, progress=False, executor=InPlace())
    assert InPlace.submitted > 0
    np.testing.assert_array_equal(first.columns["acc"], elsewhere.columns["acc"])
    upper = first.select(bound="upper")
    assert upper["speed"][np.argmax(upper["acc"])] == 41.0          # n0·D/1.1 = 40.9 m/s
    lower = first.select(bound="lower")
    assert lower["speed"][np.argmax(lower["acc"])] == 45.0


# Findings of the fuzzer (tests/fuzz_bridge.py), each refused with the field named, at once.

@pytest.mark.parametrize("kwargs, field", [
    ({"speeds": {"a": 60.0}}, "speeds"),             # was TypeError from float()
    ({"speeds": [60.0, "x"]}, "speeds"),             # was ValueError from float()
    ({"speeds": [[60.0, 70.0]]}, "speeds"),
    ({"speeds": []}, "speeds"),
    ({"mass_bounds": [1.0]}, "mass_bounds"),         # was TypeError from dict()
    ({"mass_bounds": "x"}, "mass_bounds"),           # was ValueError from dict()
    ({"mass_bounds": {None: 1.0}}, "mass_bounds"),
    ({"band": "true"}, "band"),                      # was ValueError from float()
    ({"out": 3}, "out"),                             # was TypeError from Path()
    ({"trains": "HSLM-A1"}, "trains"),               # a name, not a list: was read letter by letter
])
def test_speed_scan_refuses_bad_arguments(kwargs, field):
    args = {"trains": ["HSLM-A1"], "speeds": [60.0], **kwargs}
    with pytest.raises(vtb.ConfigError) as e:
        speed_scan(_beam(dt=2e-3), args.pop("trains"), args.pop("speeds"), progress=False, **args)
    assert e.value.field == field


def test_speed_scan_refuses_a_file_as_its_folder_before_running(tmp_path):
    (tmp_path / "f").write_text("")
    with pytest.raises(vtb.OutputError) as e:
        speed_scan(_beam(dt=2e-3), ["HSLM-A1"], [60.0], out=tmp_path / "f", progress=False)
    assert e.value.field == "out"


@pytest.mark.parametrize("args, kwargs, field", [((11.1, 1e30), {}, "step"),                      # was a hang: 4·10^29 speeds
                                                 ((11.1, 75.0), {"fine_step": 1e-12}, "fine_step"),
                                                 ((11.1, 75.0), {"resonances": 72.0}, "resonances")])  # was TypeError
def test_scan_speeds_refuse_too_many_speeds_at_once(args, kwargs, field):
    import time
    t0 = time.perf_counter()
    with pytest.raises(vtb.ConfigError) as e:
        scan_speeds(*args, resonances=kwargs.pop("resonances", [72.0]), **kwargs)
    assert e.value.field == field and time.perf_counter() - t0 < 1.0


@pytest.mark.parametrize("change, value, field", [("layers", [], "structure.layers"), ("length", "x", "structure.length"),
                                                  ("joints", [1e9], "structure.layers[0].joints")])
def test_span_points_name_a_bad_structure(change, value, field):
    from vtb.bridge.scan import span_points
    cfg = _beam(dt=2e-3)
    if change == "joints":
        cfg.structure.layers[-1].joints = value
    else:
        setattr(cfg.structure, change, value)  # no layers was an IndexError, a text length a ValueError
    with pytest.raises(vtb.ConfigError) as e:
        span_points(cfg)
    assert e.value.field == field
