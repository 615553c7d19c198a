"""EN 1991-2 §6.4.6.3.1: Table 6.6's lower limits of damping and the additional damping Δζ of
eq. (6.13), against the formulas written out here (EN 1991-2:2003 Table 6.6 and eq. 6.13, as
also coded in public tools), at 5, 10, 15, 20, 25 and 29.9 m; the Rayleigh fit over the band."""

import math

import pytest

import vtb
from vtb.bridge.damping import achieved_ratios, apply_code_damping, code_damping, code_rayleigh, delta_zeta, table_6_6

SPANS = (5.0, 10.0, 15.0, 20.0, 25.0, 29.9)


def _table(kind, span):
    base, rate = {"steel_composite": (0.5, 0.125), "prestressed_concrete": (1.0, 0.07), "reinforced_concrete": (1.5, 0.07)}[kind]
    return base + rate * (20 - span) if span < 20 else base


@pytest.mark.parametrize("span", SPANS)
@pytest.mark.parametrize("kind", ["steel_composite", "prestressed_concrete", "reinforced_concrete"])
def test_table_6_6(kind, span):
    assert table_6_6(kind, span) == pytest.approx(_table(kind, span), abs=1e-12)


#: Δζ (%) by eq. (6.13) evaluated by hand (3 decimals), and clamped at 0 at 29.9 m where it is −0.005 %.
DELTA = {5.0: 0.110, 10.0: 0.329, 15.0: 0.653, 20.0: 0.296, 25.0: 0.060, 29.9: 0.0}


@pytest.mark.parametrize("span", SPANS)
def test_delta_zeta(span):
    raw = (0.0187 * span - 0.00064 * span**2) / (1 - 0.0441 * span - 0.0044 * span**2 + 0.000255 * span**3)
    assert delta_zeta(span) == pytest.approx(max(raw, 0.0), abs=1e-12)
    assert delta_zeta(span) == pytest.approx(DELTA[span], abs=5e-4)
    assert delta_zeta(30.0) == 0.0 and delta_zeta(40.0) == 0.0


def test_total_and_rayleigh_fit():
    d = code_damping("prestressed_concrete", 15.0)
    assert d.ratio == pytest.approx((1.0 + 0.07 * 5 + DELTA[15.0]) / 100, abs=5e-6)
    assert code_damping("prestressed_concrete", 15.0, interaction=False).ratio == pytest.approx(0.0135)
    r = code_rayleigh(d.ratio, 4.0, 36.0)
    z = achieved_ratios(r, [4.0, 12.0, 36.0])
    assert z[0] == pytest.approx(d.ratio) and z[2] == pytest.approx(d.ratio) and z[1] < d.ratio
    # ζ(f) between the fit's frequencies is 2√(f1 f2)/(f1 + f2) of the ratio at its least (at √(f1 f2))
    assert achieved_ratios(r, [12.0])[0] == pytest.approx(d.ratio * 2 * math.sqrt(4 * 36) / 40, rel=1e-12)
    cfg = vtb.moving_load_config(20.0, 2500.0, 4.0, 3.5e10, 1.0, [vtb.MovingForce(1.0, 0.0)], 50.0)
    out = apply_code_damping(cfg, d, 4.0, 36.0)
    assert out.structure.layers[-1].damping == r and cfg.structure.layers[-1].damping != r


@pytest.mark.parametrize("call, field", [
    (lambda: table_6_6("timber", 10.0), "bridge_type"),
    (lambda: table_6_6("steel_composite", -1.0), "span"),
    (lambda: delta_zeta(float("nan")), "span"),
    (lambda: code_rayleigh(2.0, 1.0, 2.0), "ratio"),
    (lambda: code_rayleigh(0.01, 3.0, 2.0), "f_high"),
])
def test_bad_inputs_are_named(call, field):
    with pytest.raises(vtb.ConfigError) as e:
        call()
    assert e.value.field == field


def test_an_unhashable_bridge_type_is_named():
    with pytest.raises(vtb.ConfigError) as e:
        code_damping({}, 20.0)  # was TypeError: unhashable type
    assert e.value.field == "bridge_type"


@pytest.mark.parametrize("frequencies", [[0.0], [float("nan")], "x", [[1.0]]])
def test_achieved_ratios_refuse_frequencies_that_are_not_positive(frequencies):
    with pytest.raises(vtb.ConfigError) as e:
        achieved_ratios(code_rayleigh(0.013, 4.0, 36.0), frequencies)  # 0 Hz gave inf, NaN gave NaN, "x" a ValueError
    assert e.value.field == "frequencies"
