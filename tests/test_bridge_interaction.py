"""The interaction scan against the moving-load scan, and the deck searched along its length.

The issue asks that "as the vehicles' suspensions stiffen and the irregularity vanishes, the
interaction result tends to the moving-load one". What holds is narrower, and both halves are
tested here (docs/bridge-check.md, "Interaction against moving loads"):

- lightening the vehicle's masses (body, bogies, wheelsets) while holding its axle loads (the
  gravity scaled by the inverse factor) takes the interaction result to the moving-load one:
  the largest gap over the speeds shrinks monotonically towards 0;
- stiffening the suspensions alone does not: a stiff vehicle is a moving *mass* on the deck,
  not a moving force, and the gap grows;
- on a lightened vehicle, a rail irregularity adds a gap that vanishes with it.

The reference is the moving-load scan of the same axles (a second method: constant forces, no
vehicle), which tests/test_bridge_scan.py holds against Frýba's closed form.
"""

import math

import numpy as np
import pytest

import vtb
from vtb.bridge.damping import apply_code_damping, code_damping
from vtb.bridge.interaction import interaction_scan, with_vehicles
from vtb.bridge.load_trains import load_train
from vtb.bridge.scan import COLUMNS, span_points, speed_scan, with_band
from vtb.studies.grid import study

L = 15.0          # span (m)
M = 10000.0       # mass per metre (kg/m)
N0 = 6.0          # first bending frequency (Hz)
EI = (2 * N0 * L**2 / math.pi) ** 2 * M
BAND = 30.0
SPEEDS = [40.0, 55.0, 74.0, 85.0]   # m/s: off and near the resonances n0·D/i of one car (D = 24.775 m)
MASSES = ("m_c", "j_c", "m_t", "j_t", "m_w")


def _beam():
    e = 3.5e10
    cfg = vtb.moving_load_config(L, 2500.0, M / 2500.0, e, EI / e, [vtb.MovingForce(1.0, 0.0)], 40.0, points=[L / 2], modes=20,
                                 dt=5e-4, initial_state="rest")
    return apply_code_damping(with_band(cfg, BAND), code_damping("prestressed_concrete", L), N0, BAND)


@pytest.fixture(scope="module")
def moving_loads():
    """The peak deck acceleration of one Velaro E car's axles as constant forces (half of each
    axle on the modelled rail, as the vehicles' two rails put it)."""
    res = speed_scan(_beam(), [load_train("velaro_e", cars=1)], SPEEDS, share=0.5, progress=False)
    assert (res.columns["error"] == "").all()
    return res.columns["acc"]


def _gap(reference, mass=1.0, stiffness=1.0, irregularity=None):
    """Largest relative gap over the speeds between the interaction and the moving loads, for a
    car whose masses are scaled by ``mass`` (gravity by 1/mass: the axle loads held) and
    suspension stiffnesses by ``stiffness``."""
    cfg = with_vehicles(_beam(), "velaro_e", cars=1, irregularity=irregularity)
    cfg.solver.gravity = 9.81 / mass
    car = cfg.vehicles[0]
    for f in MASSES:
        setattr(car, f, getattr(car, f) * mass)
    for f in ("k_s", "k_p"):
        setattr(car, f, getattr(car, f) * stiffness)
    cfg.accept_implausible = [f"vehicles[0].{f}" for f in MASSES + ("k_s", "k_p")]
    res = study(cfg, cases=[{"speed": v} for v in SPEEDS], indices=["beam_acc_max"], progress=False)
    acc = np.asarray(res.columns["beam_acc_max"], dtype=float)
    return float(np.max(np.abs(acc / reference - 1.0)))


def test_lighter_vehicles_tend_to_the_moving_loads(moving_loads):
    """Masses ×1, ×0.1, ×0.01 at equal axle loads: the gap shrinks monotonically, below 1 %."""
    gaps = [_gap(moving_loads, mass=s) for s in (1.0, 0.1, 0.01)]
    assert gaps[0] > gaps[1] > gaps[2], gaps
    assert gaps[0] > 0.05 and gaps[2] < 0.01, gaps


def test_stiffer_suspensions_alone_do_not(moving_loads):
    """Suspensions ×100 stiffer at the real masses: the car rides as a moving mass, and the gap
    grows instead of shrinking."""
    assert _gap(moving_loads, stiffness=100.0) > 2 * _gap(moving_loads)


def test_the_irregularity_gap_vanishes_with_it(moving_loads):
    """A lightened car on a random rail profile (scale 1, 0.1, 0): the gap shrinks with the
    irregularity's amplitude to the smooth rail's."""
    gaps = [_gap(moving_loads, mass=0.01, irregularity=vtb.Irregularity(kind="tbt3352", seed=1, wavelength_min=1.0, wavelength_max=20.0, dx=0.1, scale=s)) for s in (1.0, 0.1)]
    smooth = _gap(moving_loads, mass=0.01)
    assert gaps[0] > gaps[1] > smooth, (gaps, smooth)


def test_interaction_scan_has_the_moving_load_scans_shape(tmp_path):
    """Journaled per (train, bound), resumable, the same columns; an unknown train is refused by
    name."""
    res = interaction_scan(_beam(), ["velaro_e"], [50.0, 70.0], cars=1, out=tmp_path, progress=False)
    assert set(res.columns) == set(COLUMNS)
    assert (tmp_path / "velaro_e__nominal.csv").is_file() and (res.columns["error"] == "").all()
    again = interaction_scan(_beam(), ["velaro_e"], [50.0, 70.0], cars=1, out=tmp_path, progress=False)
    assert np.array_equal(again.columns["acc"], res.columns["acc"])
    with pytest.raises(vtb.ConfigError, match="trains"):
        interaction_scan(_beam(), ["HSLM-A1"], [50.0], progress=False)


def _two_spans():
    cfg = vtb.paper_config(model="fast")
    cfg.irregularity = vtb.Irregularity()
    cfg.output.points = []
    cfg = vtb.spans(cfg, [20.0, 24.0], simply_supported=True)
    cfg.solver.dt = 1e-3
    cfg.output.band_limit = None
    return cfg


def test_span_points_are_the_quarters_of_each_girder_between_its_bearings():
    """Two simply supported girders of 20 and 24 m, bearings 0.55 m inside their ends."""
    b = vtb.config.spans.BEARING_OFFSET
    expect = [a + f * (c - a) for a, c in ((b, 20 - b), (20 + b, 44 - b)) for f in (0.25, 0.5, 0.75)]
    assert np.allclose(span_points(_two_spans()), expect, atol=1e-9)


def test_the_scan_reads_the_deck_at_every_point_and_the_largest_governs():
    """The per-point deck deflections of a batch equal the full histories' peaks at each point
    (a second record of the same run), and the scan reports the largest with its point."""
    cfg = _two_spans()
    cfg.output.points = span_points(cfg)
    train = load_train("HSLM-A1")
    res = speed_scan(cfg, [train], [60.0], share=0.5, progress=False)
    from vtb.bridge.load_trains import apply_load_train

    full = apply_load_train(with_band(cfg, cfg.output.deck_band), train, share=0.5, tail=0.5, gap=1.0)
    full.speed = 60.0
    run = vtb.simulate(full, progress=False)
    deck = full.structure.layers[-1].name
    peaks = np.array([np.max(np.abs(run.displacement(deck, j))) for j in range(len(cfg.output.points))])
    assert res.columns["disp"][0] == pytest.approx(peaks.max(), rel=1e-9)
    assert res.columns["disp_x"][0] == pytest.approx(cfg.output.points[int(np.argmax(peaks))])


def test_the_report_sets_the_interaction_beside_the_moving_loads(tmp_path):
    """``vehicles`` adds the section "beyond the code": the interaction scan runs over the
    moving-load scan's speeds, journaled beside it, and its row holds both peaks."""
    settings = dict(span=L, bridge_type="prestressed_concrete", track="ballasted", line_speed=250 / 3.6, v_min=230 / 3.6,
                    step=10 / 3.6, trains=["velaro_e"], vehicles=["velaro_e"], dt=1e-3)
    a = vtb.bridge_check(_beam(), settings, tmp_path / "check", progress=False, figures=False)
    text = (tmp_path / "check" / "report.md").read_text()
    assert "## Beyond the code" in text and (tmp_path / "check" / "interaction.csv").is_file()
    assert np.array_equal(np.sort(a.interaction.columns["speed"]), np.sort(a.scan.columns["speed"]))
    peak = np.nanmax(a.interaction.columns["acc"])
    row = next(line for line in text.splitlines() if line.startswith("| velaro_e | nominal |"))
    assert f"{peak:.4g}" in row and f"{np.nanmax(a.scan.columns['acc']):.4g}" in row
    assert a.damping.interaction > 0 and "without Δζ" not in text.split("## Beyond")[0]
    assert "no Δζ" in text.split("## Beyond")[1]
    assert all(str(tmp_path / "check" / "interaction") in p for p in a.interaction.journals.values())
    with pytest.raises(vtb.ConfigError) as e:
        vtb.bridge_check(_beam(), {**settings, "vehicles": ["HSLM-A1"]}, tmp_path / "bad", progress=False)
    assert e.value.field == "bridge_check.vehicles"


# Findings of the fuzzer (tests/fuzz_bridge.py), each refused with the field named.

@pytest.mark.parametrize("args, kwargs, field", [(([],), {}, "trains"),                     # was TypeError: unhashable type
                                                 (("crh3",), {"tail": {"a": 1}}, "tail"),    # was TypeError from float()
                                                 (("crh3",), {"irregularity": "smooth"}, "irregularity")])
def test_with_vehicles_names_bad_arguments(args, kwargs, field):
    with pytest.raises(vtb.ConfigError) as e:
        with_vehicles(_beam(), *args, **kwargs)
    assert e.value.field == field


@pytest.mark.parametrize("kwargs, field", [({"out": 3}, "out"), ({"band": "true"}, "band"), ({"speeds": "60"}, "speeds")])
def test_interaction_scan_names_bad_arguments(kwargs, field):
    args = {"speeds": [60.0], **kwargs}
    with pytest.raises(vtb.ConfigError) as e:
        interaction_scan(_beam(), ["crh3"], args.pop("speeds"), progress=False, **args)  # out=3 was a TypeError from Path()
    assert e.value.field == field
