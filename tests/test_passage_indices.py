"""The indices of a passage: each car's ride comfort, each wheel's force extremes and the deck
acceleration of EN 1990 A2 in its band, against second computations of the same records."""

import math
import warnings

import numpy as np
import pytest
from scipy.signal import butter, sosfiltfilt

import vtb


@pytest.fixture(scope="module")
def two_cars():
    """Two article cars 25 m apart over the article bridge for 0.4 s, on the FE track."""
    cfg = vtb.paper_config()
    cfg.discretisation.method = "fem"
    cfg.solver.t_end = 0.4
    cfg.irregularity = vtb.Irregularity(kind="tbt3352", seed=3, parts=[vtb.Irregularity(kind="wheel_flat", wheel=6, length=0.03, position=10.0)])
    lead = cfg.vehicles[0]
    cfg.vehicles = [lead, vtb.crh3_car(lead.x_front + 25.0)]
    return cfg, vtb.simulate(cfg, progress=False)


def test_each_wheel_has_its_force_extremes(two_cars):
    cfg, res = two_cars
    m = res.metrics()
    f = res.contact_force
    assert f.shape[1] == 8
    for w in range(8):
        assert m[f"wheel{w}_force_max"] == f[:, w].max() and m[f"wheel{w}_force_min"] == f[:, w].min()
    assert m["contact_force_max"] == max(m[f"wheel{w}_force_max"] for w in range(8))
    assert max(range(8), key=lambda w: m[f"wheel{w}_force_max"]) == 6  # the flat wheel
    assert vtb.metric_unit("wheel6_force_max") == "N"


def test_each_car_has_its_ride_comfort(two_cars):
    """car{k}_comfort_aw from the core's Wk filter against vtb.comfort's SciPy filter on the
    same car's record."""
    cfg, res = two_cars
    m = res.metrics()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", vtb.analysis.comfort.ComfortWarning)
        assert m["car_comfort_aw"] == pytest.approx(res.comfort(car=0)["a_w"], rel=1e-8)
        assert m["car1_comfort_aw"] == pytest.approx(res.comfort(car=1)["a_w"], rel=1e-8)
    assert m["car1_comfort_aw"] != m["car_comfort_aw"]
    one = vtb.simulate_batch([cfg], progress=False)[0]  # a batch records every car's body
    assert one["car1_comfort_aw"] == m["car1_comfort_aw"]


def test_deck_acceleration_is_the_bottom_layer_in_its_band(two_cars):
    """deck_acc_max against SciPy's zero-phase 8th-order Butterworth (sosfiltfilt applies it
    forwards and backwards, as the core does) of the bridge's record at 30 Hz; the two differ
    only in how the record's ends are padded."""
    cfg, res = two_cars
    assert cfg.output.deck_band == 30.0
    a = res.acceleration("bridge")
    sos = butter(8, 30.0, fs=1.0 / cfg.solver.dt, output="sos")
    want = np.abs(sosfiltfilt(sos, a, padtype=None)).max()
    assert res.metrics()["deck_acc_max"] == pytest.approx(want, rel=0.02)
    assert res.metrics()["deck_acc_max"] < res.metrics()["bridge_acc_max"]
    only = cfg.copy()
    only.output.indices = ["deck_acc_max"]
    assert vtb.simulate_batch([only], progress=False)[0] == {"deck_acc_max": pytest.approx(res.metrics()["deck_acc_max"], rel=1e-12)}


def test_the_deck_band_follows_en_1990_from_the_deck_modes():
    """The article bridge's first deck mode against the closed form of a simply supported span
    carrying the track (a continuous beam of equal spans on rigid piers has it as its first
    mode), and the EN 1990 A2 band max(30 Hz, 1.5·f1, f3) = 30 Hz for it."""
    cfg = vtb.paper_config()
    layers = {l.name: l for l in cfg.structure.layers}
    b = layers["bridge"]
    mass = sum(l.density * l.area for l in cfg.structure.layers)
    span = 32.0
    f1 = math.pi / (2 * span**2) * math.sqrt(b.youngs_modulus * b.inertia / mass)
    deck = vtb.modes(cfg, 7.0).frequencies
    assert deck[0] == pytest.approx(f1, rel=0.01)
    assert vtb.deck_band(cfg) == 30.0
    with pytest.raises(vtb.ConfigError, match="fmax"):
        vtb.deck_band(cfg, fmax=6.0)
    bad = cfg.copy()
    bad.output.deck_band = 1e6
    with pytest.raises(vtb.ConfigError, match="output.deck_band"):
        bad.validate()


def test_deck_deflection_is_the_bottom_layers_peak_displacement(two_cars):
    """deck_disp_max (EN 1990 A2.4.4.3's deflection) is the peak |displacement| of the bottom
    layer's record at the first observation point, read from the record itself."""
    cfg, res = two_cars
    want = np.abs(res.displacement(res.layer_names[-1])).max()
    assert res.metrics()["deck_disp_max"] == want
    assert vtb.run.indices.kind_of("deck_disp_max").unit == "m"
