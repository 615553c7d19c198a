"""Layers over part of the structure, continuous couplings over a range, wheels off the
structure, the free-vibration tail, trains and track zones (docs/zones.md)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

import vtb
from vtb import ConfigError

EI, RHO_A = 2.0e9, 500.0  # a girder: E·I (N·m²), ρ·A (kg/m)


def _beam_config(start=10.0, end=30.0, length=40.0) -> vtb.Config:
    """One finite-element layer over [start, end] of a 40 m structure, pinned at its ends by
    stiff ground springs, under a moving force (the run is not used)."""
    layer = vtb.Layer("girder", density=RHO_A, area=1.0, youngs_modulus=EI, inertia=1.0, modes=1,
                      damping=vtb.RayleighCoefficients(0.0, 0.0), element_length=0.25, start=start, end=end)
    return vtb.Config(
        structure=vtb.Structure(length, [layer], [vtb.Coupling("girder", "ground", "discrete", 1e14, 0.0, [start, end])]),
        discretisation=vtb.Discretisation(method="fem"),
        forces=[vtb.MovingForce(1e4, 0.0)],
        speed=10.0,
        output=vtb.Output(points=[0.5 * (start + end)]),
        accept_implausible=["structure.layers[0].density", "structure.layers[0].area", "structure.layers[0].youngs_modulus",
                            "structure.layers[0].inertia", "structure.couplings[0].stiffness"],
    )


def test_a_layer_over_part_of_the_structure_is_a_simply_supported_beam():
    """Closed forms of a pinned–pinned Euler–Bernoulli beam of span ℓ = 20 m: midspan static
    compliance ℓ³/(48EI) and first natural frequency (π/ℓ)²·sqrt(EI/ρA)/(2π)."""
    cfg = _beam_config()
    span = 20.0
    static = vtb.receptance(cfg, 20.0, [0.0], layer="girder")[0].real
    assert static == pytest.approx(span**3 / (48 * EI), rel=1e-6)
    f1 = vtb.modes(cfg, fmax=10.0).frequencies[0]
    assert f1 == pytest.approx((math.pi / span) ** 2 * math.sqrt(EI / RHO_A) / (2 * math.pi), rel=1e-5)


def test_a_continuous_coupling_acts_over_its_range_only():
    """A nearly rigid beam on a Winkler foundation k (N/m²) over [10, 30] m only: a central
    load P sinks it by P/(k·20 m) (the rigid-body limit: the beam's own bending adds
    (β·10 m)⁴/… ≈ 1e-5 here, and the round-off of EI/h³ against k·h about as much)."""
    cfg = _beam_config(start=0.0, end=40.0)
    cfg.structure.layers[0].youngs_modulus = 1e13
    cfg.structure.couplings = [vtb.Coupling("girder", "ground", "continuous", 1e5, 0.0, start=10.0, end=30.0)]
    cfg.accept_implausible = ["structure.layers[0].density", "structure.layers[0].area", "structure.layers[0].youngs_modulus",
                              "structure.layers[0].inertia", "structure.couplings[0].stiffness"]
    static = vtb.receptance(cfg, 20.0, [0.0], layer="girder")[0].real
    assert static == pytest.approx(1.0 / (1e5 * 20.0), rel=1e-4)


def _off_structure_case(**solver) -> vtb.Config:
    cfg = vtb.paper_config()
    cfg.irregularity = vtb.Irregularity()
    cfg.solver.fade_in = 0.0
    cfg.vehicles[0].x_front = -30.0
    for k, v in solver.items():
        setattr(cfg.solver, k, v)
    return cfg


def test_wheels_off_the_structure_run_on_a_rigid_track():
    """Before any wheel is within edge_ramp of the structure, the car stands in its static
    equilibrium on a rigid track: every wheel force is the static wheel load
    (M_c/4 + M_t/2 + M_w)·g / rails exactly, and the structure is not loaded."""
    cfg = _off_structure_case(t_end=0.2)
    cfg.accept_implausible = ["vehicles[0].x_front"]  # a run that never reaches the structure, as meant
    r = vtb.simulate(cfg)
    v = cfg.vehicles[0]
    static = (v.m_c / 4 + v.m_t / 2 + v.m_w) * cfg.solver.gravity / v.rails
    x_lead = v.x_front + cfg.speed * r.t
    away = x_lead < -cfg.solver.edge_ramp
    assert away.sum() > 100
    np.testing.assert_allclose(r.contact_force[away], static, rtol=1e-9)
    assert np.all(r.disp[away] == 0.0)


def test_the_tail_ends_the_run_after_the_last_wheel_leaves():
    """solver.tail: the run ends tail seconds after the rearmost wheel passes x = L, i.e. at
    (L − x_rear)/v + tail (whole steps)."""
    cfg = vtb.paper_config()
    cfg.solver.tail = 0.05
    cfg.solver.edge_step = True  # the hybrid's wheels leave the rail without a hand-over
    v = cfg.vehicles[0]
    want = (cfg.structure.length - (v.x_front - v.length)) / cfg.speed + 0.05
    dt = cfg.solver.dt
    cfg.irregularity = vtb.Irregularity()
    cfg.output.indices = ["rail_disp_max"]
    r = vtb.simulate(cfg)
    assert r.t[-1] == pytest.approx(round(want / dt) * dt, abs=1e-12)


@pytest.mark.parametrize("edit, field", [
    (lambda c: setattr(c.structure.layers[3], "start", 170.0), "structure.layers[3].start"),
    (lambda c: (setattr(c.structure.layers[3], "start", 50.0), setattr(c.structure.layers[3], "end", 40.0)), "structure.layers[3]"),
    (lambda c: setattr(c.structure.couplings[2], "start", -1.0), "structure.couplings[2].start"),
    (lambda c: setattr(c.structure.couplings[0], "end", 10.0), "structure.couplings[0].end"),
    (lambda c: (setattr(c.solver, "tail", 0.1), setattr(c.solver, "t_end", 0.5)), "solver.tail"),
    (lambda c: setattr(c.solver, "edge_ramp", -1.0), "solver.edge_ramp"),
])
def test_bad_extents_are_refused_naming_the_field(edit, field):
    cfg = vtb.paper_config(model="converged")
    edit(cfg)
    with pytest.raises(ConfigError, match=field.replace("[", r"\[").replace("]", r"\]")):
        cfg.validate()


def test_a_modal_layer_cannot_cover_part_of_the_structure():
    cfg = vtb.paper_config()
    cfg.structure.layers[3].start = 10.0
    with pytest.raises(ConfigError, match=r"structure\.layers\[3\]\.start.*finite elements"):
        cfg.validate()


def test_points_and_dampers_must_lie_on_their_layers():
    cfg = vtb.track_zones(vtb.paper_config(model="converged"), approach=20.0, exit=20.0)
    cfg.output.points = [5.0]  # on the approach: no bridge there
    with pytest.raises(ConfigError, match=r"output\.points\[0\].*layer \"bridge\""):
        cfg.validate()
    cfg.output.indices = ["rail_acc_max"]  # only the rail is recorded: fine
    cfg.validate()


def test_train_lengths_and_spacing_are_the_published_ones():
    """8 cars of either library train: 200.32 m over the bodies (Velaro E: 200.3 m, Goicolea
    2014); wheelsets of neighbouring cars 2·3.70 − 2·1.25 = 4.9 m apart."""
    for name, info in vtb.trains().items():
        assert sum(info.lengths) == pytest.approx(200.32, abs=0.01), name
        cars = vtb.train(name, x_front=0.0)
        assert len(cars) == 8
        for a, b in zip(cars, cars[1:]):
            assert (a.x_front - a.length) - b.x_front == pytest.approx(4.9, abs=1e-9)
    crh3 = vtb.train("crh3")
    assert [c.m_c for c in crh3] == [4.4e4, 4.8e4, 4.4e4, 4.8e4, 4.8e4, 4.4e4, 4.8e4, 4.4e4]
    assert vtb.crh3_car(0.0) == dataclasses.replace(vtb.paper_config().vehicles[0], x_front=0.0)
    assert len(vtb.train("velaro_e", cars=20)) == 20


@pytest.mark.parametrize("kwargs, field", [({"name": "tgv"}, "name"), ({"cars": 0}, "cars"), ({"cars": 2.5}, "cars"),
                                           ({"mass": 1.0}, "mass")])
def test_bad_train_arguments_are_refused(kwargs, field):
    with pytest.raises(ConfigError, match=field):
        vtb.train(**kwargs)


def test_track_zones_move_everything_by_the_approach():
    base = vtb.paper_config(model="converged")
    base.dampers = [vtb.DamperGroup(kind="tmd", inertance=500.0, stiffness=1.2e6, damping=800.0, positions=[40.0, 120.0],
                                    upper="bridge", lower="ground")]
    base.tids = vtb.tids_around(base)  # the article's group joins the others (first)
    z = vtb.track_zones(base, approach=25.0, exit=15.0)
    assert z.structure.length == pytest.approx(200.0)
    assert vtb.bridge_extent(z) == (25.0, 185.0)
    assert z.vehicles[0].x_front == pytest.approx(base.vehicles[0].x_front + 25.0)
    assert z.tids.x0 == pytest.approx(base.tids.x0 + 25.0)
    assert z.dampers[1].positions == [pytest.approx(65.0), pytest.approx(145.0)]
    assert z.output.points == [pytest.approx(105.0)]
    fasteners = np.array(z.structure.couplings[0].positions)
    np.testing.assert_allclose(np.diff(fasteners), 0.64, atol=1e-9)
    assert fasteners[0] < 0.64 and fasteners[-1] > 200.0 - 0.64
    ground = [c for c in z.structure.couplings if c.lower == "ground" and c.kind == "continuous"]
    assert [(c.upper, c.start, c.end) for c in ground] == [("base", 0.0, 25.0), ("base", 185.0, 200.0)]
    z.validate()
    with pytest.raises(ConfigError, match="discretisation.method"):
        vtb.track_zones(vtb.paper_config())
    with pytest.raises(ConfigError, match="approach"):
        vtb.track_zones(base, approach=-1.0)
    with pytest.raises(ConfigError, match="re-span it before"):
        vtb.spans(z, [32.0])


def test_a_joint_cuts_a_layer_into_independent_simply_supported_spans():
    """Two 20 m girders, cut at x = 20 m, each on bearings 0.5 m inside its ends: a load at
    the middle of the first span deflects it by ℓ³/(48EI) with ℓ = 19 m between its bearings
    (the overhangs carry nothing) and leaves the second span at rest — the same layer without
    the joint is a continuous beam whose second span moves."""
    cfg = _beam_config(start=0.0, end=40.0)
    cfg.structure.couplings = [vtb.Coupling("girder", "ground", "discrete", 1e14, 0.0, [0.5, 19.5, 20.5, 39.5])]
    cfg.output.points = [10.0]
    cut = cfg.copy()
    cut.structure.layers[0].joints = [20.0]
    compliance = vtb.receptance(cut, 10.0, [0.0], layer="girder", response_x=[10.0, 30.0])[0].real
    assert compliance[0] == pytest.approx(19.0**3 / (48 * EI), rel=1e-6)
    assert abs(compliance[1]) < 1e-9 * compliance[0]
    whole = vtb.receptance(cfg, 10.0, [0.0], layer="girder", response_x=[10.0, 30.0])[0].real
    assert abs(whole[1]) > 1e-2 * whole[0]  # continuous: the far span moves


def test_simply_supported_spans_have_their_own_girders():
    """vtb.spans(simply_supported=True): the bridge is cut at the inner span ends, each girder
    on two bearings 0.55 m inside its ends; its first mode is that of a girder simply
    supported over ℓ = 32 − 2·0.55 = 30.9 m, (π/ℓ)²·sqrt(EI/ρA)/2π (its 0.55 m overhangs lower
    it by under 0.01 %)."""
    base = vtb.paper_config(model="converged")
    base.output.points = []
    ss = vtb.spans(base, [32.0, 32.0, 32.0], simply_supported=True)
    bridge = ss.structure.layers[-1]
    assert bridge.joints == [32.0, 64.0]
    bearings = [c for c in ss.structure.couplings if c.upper == "bridge" and c.lower == "ground"][0].positions
    np.testing.assert_allclose(bearings, [0.55, 31.45, 32.55, 63.45, 64.55, 95.45])
    ei = bridge.youngs_modulus * bridge.inertia
    rho_a = bridge.density * bridge.area
    # The girders alone (the track above would add its mass and stiffness).
    girder = vtb.Config(structure=vtb.Structure(96.0, [bridge], [c for c in ss.structure.couplings if c.upper == "bridge"]),
                        discretisation=ss.discretisation, forces=[vtb.MovingForce(1e4, 0.0, "bridge")], speed=10.0,
                        output=vtb.Output(points=[16.0]))
    f1 = vtb.modes(girder, fmax=8.0).frequencies[0]
    assert f1 == pytest.approx((math.pi / 30.9) ** 2 * math.sqrt(ei / rho_a) / (2 * math.pi), rel=2e-4)
    with pytest.raises(ConfigError, match="bearing_offset"):
        vtb.spans(base, [32.0], simply_supported=True, bearing_offset=20.0)
    with pytest.raises(ConfigError, match="discretisation.method"):
        vtb.spans(vtb.paper_config(), [32.0], simply_supported=True)


def test_a_point_on_a_joint_is_refused():
    cfg = vtb.spans(vtb.paper_config(model="converged"), [32.0, 32.0], simply_supported=True)
    cfg.output.points = [32.0]
    with pytest.raises(ConfigError, match=r"output\.points\[0\].*joint"):
        cfg.validate()


def test_a_passage_by_synthesis_matches_the_finite_elements():
    """The train passage run by the synthesis at a passage-grade cut-off (300 Hz) against the
    same structure stepped in finite elements: a Velaro E car starting before the track, over
    a 32 m bridge between 20 m embankments, off the track again and a 0.3 s tail, under a
    long-wave irregularity. The wheels leave and join the structure (their ports are skipped
    while off it); the deck acceleration, the car's comfort and the wheel forces agree."""
    cfg = vtb.paper_config(model="fast")
    cfg.discretisation.synthesis_cutoff = 300.0
    cfg.output.band_limit = 150.0
    cfg.solver.dt = 2e-4
    cfg.output.points = []
    cfg = vtb.track_zones(vtb.spans(cfg, [32.0]), approach=20.0, exit=20.0, tail=0.3)
    cfg.vehicles = vtb.train("velaro_e", cars=1, x_front=-2.0, contact_patch=True)
    cfg.irregularity = vtb.Irregularity(kind="german_low", wavelength_min=2.0, wavelength_max=80.0, seed=7)
    cfg.solver.fade_in = 20.0
    fem = cfg.copy()
    fem.discretisation.synthesis_cutoff = None
    with pytest.warns(vtb.IrregularityWarning):
        a, b = (vtb.simulate(c, progress=False).metrics() for c in (cfg, fem))
    for k in ("deck_acc_max", "car_comfort_aw", "contact_force_max", "contact_force_min", "bridge_disp_max"):
        assert a[k] == pytest.approx(b[k], rel=0.03), k


def test_a_wheel_crossing_a_rail_end_needs_a_hand_over():
    """A train started before a bare structure crosses the rail's start. Without a hand-over its
    wheels meet the track's static deflection as a step: on a smooth rail the second car's
    wheels all but lose contact and strike back at 1.46–1.65 × their static load, an
    artefact. So with no hand-over (solver.edge_ramp = 0, the default) such a run is refused,
    naming the vehicle; a 10 m hand-over keeps every wheel within 6.5 % of its static load
    (here on the bridge itself; vtb.track_zones puts it on an embankment); solver.edge_step
    keeps the step on request."""
    cfg = vtb.paper_config(model="fast")
    cfg.irregularity = vtb.Irregularity()
    cfg.vehicles = vtb.train("crh3", cars=2, x_front=cfg.vehicles[0].x_front)
    assert cfg.vehicles[1].x_front < 0
    with pytest.raises(vtb.ConfigError, match=r"vehicles\[1\]\.x_front.*crosses the rail's start.*edge_ramp"):
        cfg.validate()
    static = np.repeat([(v.m_c / 4 + v.m_t / 2 + v.m_w) * cfg.solver.gravity / v.rails for v in cfg.vehicles], 4)
    forces = {}
    for ramp, step in ((10.0, False), (0.0, True)):
        cfg.solver.edge_ramp, cfg.solver.edge_step = ramp, step
        forces[ramp] = vtb.simulate(cfg, progress=False).contact_force / static
    assert np.all(np.abs(forces[10.0] - 1.0) < 0.08)
    assert forces[0.0][:, 4:].min() < 0.05 and forces[0.0][:, 4:].max() > 1.4
