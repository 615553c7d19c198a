"""The bridge check's arithmetic and its report: the code's formulas (EN 1991-2 Fig. 6.10, eqs.
6.4/6.5, Annex C; EN 1990 A2) written out here, LM71's static deflection of a simply supported
span by beam theory, and the report of a small bridge written by vtb.bridge_check and by
``vtb bridge-check``."""

import math

import numpy as np
import pytest

import vtb
from vtb import cli
from vtb.bridge.checks import acceleration_limit, dynamic_analysis_required, n0_limits, phi_2, phi_3, phi_irregularity
from vtb.bridge.load_trains import load_train
from vtb.bridge.settings import BridgeCheck, split_toml
from vtb.bridge.static import influence_line

L, M, N0 = 20.0, 12000.0, 4.0
EI = (2 * N0 * L**2 / math.pi) ** 2 * M


def _beam(dt=1e-3):
    e = 3.5e10
    return vtb.moving_load_config(L, 2500.0, M / 2500.0, e, EI / e, [vtb.MovingForce(1.0, 0.0)], 50.0, points=[L / 2], modes=20, dt=dt)


@pytest.mark.parametrize("span", [5.0, 15.0, 20.0, 30.0, 80.0])
def test_n0_limits_of_fig_6_10(span):
    lower, upper = n0_limits(span)
    assert upper == pytest.approx(94.76 * span**-0.748, rel=1e-12)
    assert lower == pytest.approx(80 / span if span <= 20 else 23.58 * span**-0.592, rel=1e-12)
    assert all(math.isnan(v) for v in n0_limits(3.0))


def test_flow_chart_of_fig_6_9():
    assert dynamic_analysis_required(20.0, 5.0, 250 / 3.6).required is True      # V > 200 km/h
    assert dynamic_analysis_required(20.0, 2.0, 160 / 3.6).required is True      # n0 below 80/L = 4 Hz
    assert dynamic_analysis_required(50.0, 3.0, 160 / 3.6).required is False     # L ≥ 40 m, n0 within [2.3, 5.0] Hz
    assert dynamic_analysis_required(20.0, 5.0, 160 / 3.6).required is None      # Annex F decides


def test_dynamic_factors():
    for lphi in (4.0, 10.0, 30.0, 100.0):
        assert phi_2(lphi) == pytest.approx(min(1.67, max(1.0, 1.44 / (math.sqrt(lphi) - 0.2) + 0.82)))
        assert phi_3(lphi) == pytest.approx(min(2.0, max(1.0, 2.16 / (math.sqrt(lphi) - 0.2) + 0.73)))
    assert phi_2(4.0) == pytest.approx(1.62) and phi_2(100.0) == 1.0 and phi_3(3.0) == 2.0
    # Annex C at L = 10 m, n0 = 8 Hz, v ≥ 22 m/s: (56 e^-1 + 50·0·e^-0.25)/100
    assert phi_irregularity(10.0, 8.0, 50.0) == pytest.approx(0.56 * math.exp(-1.0), rel=1e-12)
    assert phi_irregularity(10.0, 8.0, 11.0) == pytest.approx(0.28 * math.exp(-1.0), rel=1e-12)
    assert acceleration_limit("ballasted") == 3.5 and acceleration_limit("direct_fastened") == 5.0


def test_lm71_and_a_train_on_a_simply_supported_span_by_beam_theory():
    line = influence_line(_beam(), dx=0.05)

    def g(a):  # midspan deflection per newton at a (beam theory, symmetric)
        a = min(a, L - a)
        return a * (3 * L**2 - 4 * a**2) / (48 * EI)

    b = L / 2 - 3.2
    udl = 2 * 80e3 * (1.5 * L**2 * b**2 - b**4) / (48 * EI)
    axles = 250e3 * sum(g(L / 2 + s) for s in (-2.4, -0.8, 0.8, 2.4))
    assert line.lm71() == pytest.approx(axles + udl, rel=1e-4)
    # one force of the train: its static deflection is the largest over positions
    one = vtb.LoadTrain("one", (0.0,), (1e5,), "test")
    assert line.train(one) == pytest.approx(1e5 * L**3 / (48 * EI), rel=1e-4)


def test_bad_settings_are_named():
    with pytest.raises(vtb.ConfigError) as e:
        BridgeCheck(span=20.0, bridge_type="timber", track="ballasted", line_speed=50.0).validate()
    assert e.value.field == "bridge_check.bridge_type"
    with pytest.raises(vtb.ConfigError) as e:
        BridgeCheck(span=20.0, bridge_type="steel_composite", track="ballasted", line_speed=50.0, step=5.0).validate()
    assert e.value.field == "bridge_check.step"
    with pytest.raises(vtb.ConfigError) as e:
        BridgeCheck.from_dict({"span": 20.0, "bridge_type": "steel_composite", "track": "ballasted", "line_speed": 50.0, "speed": 3})
    assert e.value.field == "bridge_check.speed"
    with pytest.raises(vtb.ConfigError):
        BridgeCheck(span=20.0, bridge_type="steel_composite", track="ballasted", line_speed=50.0).spam = 1


SETTINGS = dict(span=L, bridge_type="prestressed_concrete", track="ballasted", line_speed=225 / 3.6, v_min=220 / 3.6,
                step=10 / 3.6, trains=["HSLM-A1", "HSLM-A2"], dt=1e-3)


def test_report_of_a_small_bridge(tmp_path):
    a = vtb.bridge_check(_beam(), SETTINGS, tmp_path / "check", progress=False)
    text = (tmp_path / "check" / "report.md").read_text()
    assert "EN 1990 A2.4.4.2.1(4)P" in text and "HSLM-A1" in text and "Table 6.6" in text
    assert (tmp_path / "check" / "envelopes.csv").is_file() and (tmp_path / "check" / "acceleration.png").is_file()
    acc = next(c for c in a.checks if c.name == "deck acceleration")
    assert acc.limit == 3.5 and acc.value == pytest.approx(np.nanmax(a.scan.columns["acc"]))
    assert acc.passed == (acc.value <= 3.5) and acc.margin == pytest.approx(1 - acc.value / 3.5)
    # damping: Table 6.6 + Δζ at 20 m, and the band max(30, 1.5·4, 36) = 36 Hz
    assert a.damping.ratio == pytest.approx((1.0 + 0.296) / 100, abs=5e-6)
    assert a.band == pytest.approx(9 * N0, rel=1e-3) and a.n0 == pytest.approx(N0, rel=1e-4)
    for e in a.envelopes:
        for r, quantity in ((e.deflection, "deflection"), (e.moment, "moment")):
            assert r.static == pytest.approx(influence_line(a.config, quantity=quantity).train(load_train(e.train)))
            assert r.phi_dyn == pytest.approx(max(0.0, r.dynamic / r.static - 1))
        # both reported, the larger governs (EN 1991-2 §6.4.6.5(3)) and enters both envelopes
        assert e.phi_dyn == max(e.deflection.phi_dyn, e.moment.phi_dyn)
        assert e.moment.design == pytest.approx((1 + e.phi_dyn + 0.5 * e.phi_irr) * e.moment.static)
    assert "φ'dyn, M" in text and "bending moment" in text and (tmp_path / "check" / "moment.png").is_file()
    assert {c.name for c in a.checks} >= {"dynamic envelope within Φ·LM71, deflection", "dynamic envelope within Φ·LM71, bending moment"}
    # HSLM-A1's resonance n0·D = 72 m/s (259 km/h) lies in range: scanned at it, 5 times finer around it
    v = a.scan.select(train="HSLM-A1")["speed"]
    at = np.argmin(np.abs(v - N0 * 18.0))
    assert abs(v[at] - N0 * 18.0) < 1e-2 and np.diff(v)[at - 1] == pytest.approx(SETTINGS["step"] / 5, rel=1e-3)


def test_cli_writes_the_report(tmp_path):
    cfg = _beam()
    text = cfg.to_toml() + "\n[bridge_check]\n" + "\n".join(
        f"{k} = {v!r}".replace("'", '"') for k, v in SETTINGS.items() if k != "trains") + '\ntrains = ["HSLM-A3"]\n'
    (tmp_path / "bridge.toml").write_text(text)
    cfg2, check = split_toml(tmp_path / "bridge.toml")
    assert check.trains == ["HSLM-A3"] and cfg2.structure.length == L
    code = cli.main(["bridge-check", str(tmp_path / "bridge.toml"), "--out", str(tmp_path / "out"), "--no-progress", "--no-plot"])
    assert code in (0, 1) and (tmp_path / "out" / "report.md").is_file()
    assert cli.main(["bridge-check", str(tmp_path / "missing.toml"), "--out", str(tmp_path / "o2")]) == 2


# Findings of the fuzzer (tests/fuzz_bridge.py), each refused with the field named, at once.

def test_acceleration_limit_names_an_unhashable_track():
    with pytest.raises(vtb.ConfigError) as e:
        acceleration_limit(["ballasted"])  # was TypeError: unhashable type
    assert e.value.field == "track"


def test_phi_irregularity_of_a_huge_length_is_zero_not_an_overflow():
    assert phi_irregularity(1e300, 4.0, 60.0) == 0.0  # was OverflowError from LΦ²
    assert phi_irregularity(1000.0, 4.0, 60.0) == 0.0 == phi_irregularity(600.0, 4.0, 60.0)


@pytest.mark.parametrize("call, field", [
    (lambda line: line.lm71({"a": 1}, 1.0), "alpha"),          # was TypeError
    (lambda line: line.lm71(float("inf"), 1.0), "alpha"),      # was an infinite deflection
    (lambda line: line.train(load_train("crh3"), float("nan")), "share"),  # was NaN
    (lambda line: line.train(load_train("crh3"), [1.0, 2.0]), "share"),    # was a broadcast ValueError
])
def test_influence_line_effects_refuse_bad_factors(call, field):
    with pytest.raises(vtb.ConfigError) as e:
        call(influence_line(_beam()))
    assert e.value.field == field


def test_influence_line_refuses_a_tiny_step_at_once():
    import time
    t0 = time.perf_counter()
    with pytest.raises(vtb.ConfigError) as e:
        influence_line(_beam(), dx=1e-15)  # was a MemoryError allocating 2·10^16 samples
    assert e.value.field == "dx" and time.perf_counter() - t0 < 1.0


@pytest.mark.parametrize("kwargs, field", [({"share": "true"}, "share"), ({"fmax": float("nan")}, "fmax"), ({"cluster": -1.0}, "cluster")])
def test_deck_frequencies_refuse_bad_options(kwargs, field):
    from vtb.bridge.static import deck_frequencies
    with pytest.raises(vtb.ConfigError) as e:
        deck_frequencies(_beam(), **kwargs)  # share "true" was a numpy UFuncTypeError
    assert e.value.field == field


@pytest.mark.parametrize("changes, field", [({"bridge_type": {}}, "bridge_check.bridge_type"), ({"track": ["ballasted"]}, "bridge_check.track"),
                                            ({"line_speed": 1e30}, "bridge_check.line_speed"), ({"step": 1e-12}, "bridge_check.step")])
def test_bad_settings_are_named_at_once(changes, field):
    import time
    t0 = time.perf_counter()
    with pytest.raises(vtb.ConfigError) as e:
        BridgeCheck.from_dict({**SETTINGS, **changes})  # an unhashable type was a TypeError; line_speed 1e30 a hang in the scan's speeds
    assert e.value.field == field and time.perf_counter() - t0 < 1.0
