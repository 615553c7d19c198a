"""Tuned inerter dampers (docs/model.md §5) against independent results."""

import math

import numpy as np
import pytest

import vtb
from fuzz_cases import accept_implausible
from vtb import Config, Coupling, Layer, MovingForce, RayleighRatio, Structure


def _sdof_with_tid(mu: float):
    """A rigid 100 kg beam on two springs (the primary, ω_s = 100 rad/s, force and TID at its
    centre, so its rocking mode stays unexcited) over a slab held by 1e14 N/m² to the ground,
    FEM with two elements so that x = 0.5 m is node 1. TID tuned by Den Hartog for μ = b/m."""
    m, k_s = 100.0, 1e6
    w_s = math.sqrt(k_s / m)
    b = mu * m
    w_d = w_s / (1 + mu)
    zeta = math.sqrt(3 * mu / (8 * (1 + mu)))
    rail = Layer("rail", density=m / 0.01, area=0.01, youngs_modulus=1e14, inertia=1.0, modes=1, damping=RayleighRatio(0.0, 1.0, 2.0))
    slab = Layer("slab", density=1000.0, area=1.0, youngs_modulus=1e14, inertia=1.0, modes=1, damping=RayleighRatio(0.0, 1.0, 2.0))
    couplings = [Coupling("rail", "ground", "discrete", k_s / 2, 0.0, [0.0, 1.0]), Coupling("slab", "ground", "continuous", 1e14, 0.0)]
    cfg = Config(structure=Structure(1.0, [rail, slab], couplings), speed=1.0, forces=[MovingForce(1.0, 0.0)])
    cfg.solver.t_end = 0.1
    cfg.discretisation.method = "fem"
    cfg.discretisation.fem_elements = 2
    cfg.tids = vtb.TIDs(inertance=b, stiffness=b * w_d**2, damping=2 * b * w_d * zeta, count=1, x0=0.5, spacing=1.0)
    return accept_implausible(cfg), w_s, k_s


@pytest.mark.parametrize("mu,published", [(0.01, 14.18), (0.05, 6.41), (0.10, 4.59), (0.20, 3.33)])
def test_tid_on_sdof_with_fixed_slab_is_den_hartog_tmd(mu, published):
    """Den Hartog: with the slab fixed, SDOF + TID = TMD of mass b; at Den Hartog's
    tuning the peak |X/X_st| is sqrt(1 + 2/μ) (the table's values)."""
    cfg, w_s, k_s = _sdof_with_tid(mu)
    mats = vtb.assembled_matrices(cfg)
    m, k, c = mats["m"], mats["k"], mats["c"]
    f = np.zeros(len(m))
    f[2] = 1.0  # rail node 1 (x = 0.5 m), displacement DOF
    w = np.linspace(0.6, 1.4, 4001) * w_s
    amp = np.array([abs(np.linalg.solve(k - wi**2 * m + 1j * wi * c, f)[2]) for wi in w]) * k_s
    assert amp.max() == pytest.approx(math.sqrt(1 + 2 / mu), rel=0.02)
    assert amp.max() == pytest.approx(published, rel=0.02)
    # Den Hartog's tuning makes the two peaks, either side of the damper frequency, equal.
    below, above = amp[w < w_s / (1 + mu)], amp[w > w_s / (1 + mu)]
    assert below.max() == pytest.approx(above.max(), rel=0.05)


def test_inertance_is_in_the_mass_matrix_and_the_spring_in_stiffness():
    cfg, _, _ = _sdof_with_tid(0.05)
    no = cfg.copy()
    no.tids = None
    a, b = vtb.assembled_matrices(cfg), vtb.assembled_matrices(no)
    node = len(a["m"]) - 1
    t = cfg.tids
    assert a["m"][node, node] == pytest.approx(t.inertance) and a["k"][node, node] == pytest.approx(t.stiffness)
    assert a["c"][node, node] == pytest.approx(t.damping)
    # The inerter acts on the slab (node 1 of the slab: DOF 6 + 2), the spring on the rail.
    assert a["m"][node, 8] == pytest.approx(-t.inertance) and a["k"][node, 2] == pytest.approx(-t.stiffness)
    assert a["m"][node, 2] == 0.0 and a["k"][node, 8] == 0.0
    assert np.allclose(a["m"][:node, :node] - b["m"], 0.0 * b["m"] + np.outer(np.eye(node)[8], np.eye(node)[8]) * t.inertance)


@pytest.fixture(scope="module")
def uncontrolled():
    return vtb.simulate(vtb.paper_config()).metrics()


@pytest.mark.parametrize("changes", [dict(inertance=1e-9), dict(stiffness=1e-6, damping=0.0)])
def test_vanishing_tid_recovers_the_uncontrolled_run(uncontrolled, changes):
    cfg = vtb.paper_config()
    cfg.tids = vtb.tids_around(cfg, **changes)
    m = vtb.simulate(accept_implausible(cfg)).metrics()
    for key in ("rail_acc_max", "rail_disp_max", "slab_acc_max", "car_acc_max"):
        assert m[key] == pytest.approx(uncontrolled[key], rel=1e-5), key


def test_tuned_tids_lower_rail_and_raise_slab_vibration(uncontrolled):
    """The article's two qualitative findings at its best sweep case (5 kg, 2e8 N/m, 1e3 N·s/m)."""
    cfg = vtb.paper_config()
    cfg.tids = vtb.tids_around(cfg)
    m = vtb.simulate(cfg).metrics()
    assert m["rail_acc_max"] < 0.95 * uncontrolled["rail_acc_max"]
    assert m["slab_acc_max"] > uncontrolled["slab_acc_max"]


def test_tids_work_with_the_fem_model():
    """The same dampers through the FEM's shape vectors: the FEM run changes like the hybrid."""
    cfg = vtb.paper_config()
    cfg.discretisation.method = "fem"
    base = vtb.simulate(cfg).metrics()
    cfg.tids = vtb.tids_around(cfg)
    m = vtb.simulate(cfg).metrics()
    assert m["rail_acc_max"] < 0.95 * base["rail_acc_max"]


def test_tids_around_places_one_per_bay_centred_on_the_observation_point():
    cfg = vtb.paper_config()
    t = vtb.tids_around(cfg, count=10)
    xs = t.x0 + t.spacing * np.arange(t.count)
    assert t.spacing == pytest.approx(0.64)
    assert np.mean(xs) == pytest.approx(80.0)
    assert np.allclose((xs - 0.32) / 0.64, np.round((xs - 0.32) / 0.64))


def test_tids_around_refuses_positions_off_the_rail_instead_of_moving_them():
    c = vtb.paper_config()
    with pytest.raises(vtb.ConfigError, match="must lie on the fastened rail") as e:
        vtb.tids_around(c, x=200.0)
    assert e.value.field == "x"
    with pytest.raises(vtb.ConfigError, match="would reach beyond the fastened rail") as e:
        vtb.tids_around(c, x=159.0)
    assert e.value.field == "x"
    with pytest.raises(vtb.ConfigError) as e:
        vtb.tids_around(c, count=0)
    assert e.value.field == "count"
    t = vtb.tids_around(c, x=156.5)  # the last ten bays fit exactly
    assert t.x0 - 0.32 >= 0 and t.x0 + (t.count - 1) * t.spacing + 0.32 <= 160.0 + 1e-9


def test_a_tuned_mass_damper_splits_the_mode_it_is_tuned_to():
    """A damper whose inerter goes to the ground is a tuned mass damper (mass b_t). Tuned to the
    bridge's first mode at a point of that mode, the full eigen-solution with the damper
    against the closed form of the mode reduced to one DOF plus the damper:
    (ω_s² + φ²k − ω²)(k − mω²) = φ²k², φ the mass-normalised mode at the damper."""
    cfg = vtb.paper_config()
    cfg.discretisation.method = "fem"
    plain = vtb.modes(cfg, 7.0)
    f1, x, m = plain.frequencies[0], 16.0, 200.0
    phi = float(np.ravel(plain.displacement("bridge", x, mode=0))[0])
    k = m * (2 * math.pi * f1) ** 2
    cfg.tids = vtb.TIDs(inertance=m, stiffness=k, damping=0.0, count=1, x0=x, spacing=0.64, upper="bridge", lower="ground")
    got = vtb.modes(cfg, 7.0).frequencies[:2]
    ws2 = (2 * math.pi * f1) ** 2
    w2 = np.sort(np.roots([m, -(m * (ws2 + phi**2 * k) + k), (ws2 + phi**2 * k) * k - phi**2 * k**2]).real)
    want = np.sqrt(w2) / (2 * math.pi)
    assert got == pytest.approx(want, rel=5e-4)  # the neighbouring modes (6.4 Hz) shift both a little
    assert got[1] - got[0] == pytest.approx(want[1] - want[0], rel=0.01)
    assert vtb.simulate(cfg.copy(), progress=False).metrics()["deck_acc_max"] > 0
    cfg.tids.upper = "ground"
    with pytest.raises(vtb.ConfigError, match="tids.upper"):
        cfg.validate()
