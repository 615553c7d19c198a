"""The start of a run (docs/model.md §4, "Fade-in"): with the default fade-in no car-body or
rail acceleration of the first 0.05 s reaches the running level, whereas the abrupt start
(``fade_in = 0``) sets the car body's maximum in its first milliseconds; and the metrics'
analysis window (``output.window``) against the histories it selects."""

import math

import numpy as np
import pytest

import vtb
from fuzz_cases import small_config

START = 0.05  # s: the start-up period the fade must keep below the running level
RUNNING = 0.1  # s: from here on the run counts as running
DEFAULT_FADE = vtb.Solver().fade_in


def _article(fade_in):
    cfg = vtb.paper_config(calibrated=True)
    cfg.solver.fade_in = fade_in
    front = cfg.vehicles[0].x_front
    # the first point is the metrics' mid-span point; the others lie just ahead of the
    # leading wheel, which passes them within the first 0.05 s
    cfg.output.points = [cfg.structure.length / 2, front + 0.2, front + 0.6, front + 1.2]
    return vtb.simulate(cfg)


@pytest.fixture(scope="module")
def runs():
    return {f: _article(f) for f in (0.0, DEFAULT_FADE)}


def _start_and_running(t, a):
    a = np.abs(a)
    return a[t < START].max(), a[t > RUNNING].max()


def test_the_default_fade_keeps_the_start_below_the_running_level(runs):
    res = runs[DEFAULT_FADE]
    t = res.t
    car_start, car_running = _start_and_running(t, res.vehicle_acc[:, 0, 0])
    assert car_start < car_running
    assert res.metrics()["car_acc_max"] == pytest.approx(car_running)
    # the rail just ahead of the leading wheel, during the wheel's passage, against the rail's
    # running level at mid-span (the metrics' point)
    rail = np.abs(res.acc[:, 0, :])
    assert rail[t < 0.025, 1:].max() < rail[t > RUNNING, 0].max()


def test_the_abrupt_start_sets_the_car_body_maximum(runs):
    """The check above can fail: without the fade the first milliseconds dominate."""
    res = runs[0.0]
    t = res.t
    car_start, car_running = _start_and_running(t, res.vehicle_acc[:, 0, 0])
    assert car_start > 2 * car_running
    assert t[np.abs(res.vehicle_acc[:, 0, 0]).argmax()] < 0.02
    rail = np.abs(res.acc[:, 0, :])
    assert rail[t < 0.025, 1:].max() > rail[t > RUNNING, 0].max()


def test_the_fade_leaves_the_rail_peak_at_mid_span(runs):
    faded, abrupt = (runs[f].metrics()["rail_acc_max"] for f in (DEFAULT_FADE, 0.0))
    assert faded == pytest.approx(abrupt, rel=1e-4)


def test_metrics_window_selects_its_samples():
    cfg = small_config(t_end=0.02, tids=False)
    full = vtb.simulate(cfg)
    cfg.output.window = [0.005, 0.015]
    res = vtb.simulate(cfg)
    keep = (full.t >= 0.005 - 1e-12) & (full.t <= 0.015 + 1e-12)
    a = full.acc[keep, 0, 0]
    m = res.metrics()
    assert m["rail_acc_max"] == pytest.approx(np.abs(a).max(), rel=1e-12)
    assert m["rail_acc_rms"] == pytest.approx(math.sqrt(np.mean(a**2)), rel=1e-12)
    assert m["car_acc_max"] == pytest.approx(np.abs(full.vehicle_acc[keep, 0, 0]).max(), rel=1e-12)
    assert m["contact_force_max"] == pytest.approx(full.contact_force[keep].max(), rel=1e-12)
    # settle times count from t = 0
    assert m["rail_acc_settle"] >= 0.005
    # a window past the run's end ends with the run
    cfg.output.window = [0.005, 10.0]
    assert vtb.simulate(cfg).metrics()["rail_acc_max"] == pytest.approx(np.abs(full.acc[full.t >= 0.005 - 1e-12, 0, 0]).max())


@pytest.mark.parametrize("window", [[0.02, 0.01], [0.5, 0.6], [-0.1, 0.01], [0.0, float("nan")]])
def test_a_bad_window_is_refused_by_name(window):
    cfg = small_config(t_end=0.02, tids=False)
    cfg.output.window = window
    with pytest.raises(vtb.ConfigError) as e:
        vtb.simulate(cfg)
    assert e.value.field.startswith("output.window")


def test_a_negative_fade_is_refused_by_name():
    cfg = small_config(t_end=0.002, tids=False)
    cfg.solver.fade_in = -1.0
    with pytest.raises(vtb.ConfigError) as e:
        vtb.simulate(cfg)
    assert e.value.field == "solver.fade_in"
