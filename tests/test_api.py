"""The public Python API: configs, results, batch runs, interruption."""

import dataclasses
import math
import os
import pickle
import signal
import threading
import time

import numpy as np
import pytest

import vtb

REQUIRED_METRICS = ["rail_disp_max", "rail_acc_max", "rail_acc_rms", "rail_acc_settle", "slab_disp_max", "slab_acc_max", "car_disp_max", "car_acc_max"]


@pytest.fixture(scope="module")
def paper_result():
    return vtb.simulate(vtb.paper_config())


def test_paper_config_describes_the_article_case():
    cfg = vtb.paper_config()
    s = cfg.structure
    assert s.length == 160.0 and [l.name for l in s.layers] == ["rail", "slab", "base", "bridge"]
    assert [l.modes for l in s.layers] == [120, 120, 120, 50] and s.layers[0].local_modes == 100
    assert (s.layers[0].area, s.layers[1].inertia, s.layers[3].youngs_modulus) == (7.745e-3, 1.7e-3, 3.945e10)
    fasteners = s.couplings[0]
    assert fasteners.kind == "discrete" and fasteners.stiffness == 6e7 and len(fasteners.positions) == 251
    assert fasteners.positions[1] == pytest.approx(0.64)
    assert s.couplings[3].lower == "ground" and s.couplings[3].stiffness == 1e15 and s.couplings[3].positions == [0, 32, 64, 96, 128, 160]
    assert cfg.speed == 80.0 and cfg.solver.dt == 5e-5 and len(cfg.vehicles) == 1
    assert cfg.irregularity.kind == "tbt3352" and (cfg.irregularity.wavelength_min, cfg.irregularity.wavelength_max) == (0.01, 1.0)


def test_paper_run_returns_histories_and_metrics(paper_result):
    r = paper_result
    n = len(r.t)
    assert 34000 <= n <= 35000 and r.t[1] == pytest.approx(5e-5)
    assert r.disp.shape == (n, 4, 1) and r.acc.shape == (n, 4, 1)
    assert r.vehicle_disp.shape == (n, 1, 10) and r.contact_force.shape == (n, 4)
    m = r.metrics()
    for k in REQUIRED_METRICS:
        assert k in m and math.isfinite(m[k])
    assert m["rail_acc_max"] == pytest.approx(np.abs(r.acceleration("rail")).max())
    assert m["rail_acc_rms"] == pytest.approx(np.sqrt(np.mean(r.acceleration("rail") ** 2)))
    # Static deflections of the article's order (0.97 mm rail, 0.46 mm slab).
    assert 0.6e-3 < m["rail_disp_max"] < 1.2e-3 and 0.3e-3 < m["slab_disp_max"] < 0.6e-3
    # The rail settles after the last wheelset passes mid-span (x = 80 m at t ≈ 0.99 s).
    assert 0.99 < m["rail_acc_settle"] < 1.3


def test_static_wheel_loads_and_vehicle_start_at_equilibrium(paper_result):
    r = paper_result
    # One wheel of a CRH3 trailer: (M_w + M_t/2 + M_c/4)·g / 2 rails = 71.6 kN.
    assert r.contact_force[0] == pytest.approx(np.full(4, 14600 * 9.81 / 2), rel=1e-9)
    assert np.all(r.vehicle_disp[0] == 0.0)


def test_results_are_reproducible_and_seed_dependent():
    cfg = vtb.paper_config()
    cfg.solver.t_end = 0.05
    a, b = vtb.simulate(cfg), vtb.simulate(cfg)
    assert np.array_equal(a.acc, b.acc)
    cfg2 = cfg.copy()
    cfg2.irregularity.seed += 1
    assert not np.array_equal(vtb.simulate(cfg2).acc, a.acc)


def test_toml_round_trip(tmp_path):
    cfg = vtb.paper_config()
    cfg.tids = vtb.TIDs(5.0, 2e8, 1e3, 10, 70.0, 0.64)
    path = tmp_path / "case.toml"
    cfg.to_toml(path)
    back = vtb.Config.from_toml(path)
    assert back == cfg
    assert vtb.Config.from_toml_text(path.read_text()) == cfg


def test_toml_errors_name_the_field():
    text = vtb.paper_config().to_toml().replace("speed = 80.0", "sped = 80.0")
    with pytest.raises(vtb.ConfigError) as e:
        vtb.Config.from_toml_text(text)
    assert e.value.field == "sped"
    text = vtb.paper_config().to_toml().replace("m_c = 44000.0", 'm_c = "heavy"')
    with pytest.raises(vtb.ConfigError) as e:
        vtb.Config.from_toml_text(text)
    assert e.value.field == "vehicles[0].m_c"


def test_configs_and_results_pickle(paper_result):
    cfg = vtb.paper_config()
    assert pickle.loads(pickle.dumps(cfg)) == cfg
    back = pickle.loads(pickle.dumps(paper_result))
    assert np.array_equal(back.acc, paper_result.acc) and back.metrics() == paper_result.metrics()
    err = vtb.ConfigError("msg", "a.b", "1", "bad")
    e2 = pickle.loads(pickle.dumps(err))
    assert (e2.field, e2.value, e2.reason) == ("a.b", "1", "bad")


def test_batch_matches_single_runs_and_records_failures():
    base = vtb.paper_config()
    base.solver.t_end = 0.1
    cfgs = []
    for seed in range(3):
        c = base.copy()
        c.irregularity.seed = seed
        cfgs.append(c)
    bad = base.copy()
    bad.vehicles[0].m_w = -1.0
    out = vtb.simulate_batch(cfgs + [bad], on_error="return")
    for c, m in zip(cfgs, out):
        assert m == vtb.simulate(c).metrics()
    assert isinstance(out[-1], vtb.ConfigError) and out[-1].field == "vehicles[0].m_w"
    with pytest.raises(vtb.ConfigError):
        vtb.simulate_batch(cfgs + [bad])
    seen = []
    vtb.simulate_batch(cfgs, threads=1, progress=seen.append)
    assert seen and seen[-1] <= 3


def test_loss_of_contact_is_reported():
    """A 4 mm, 0.2 m long dip at 80 m/s throws the wheels off the rail: the loss periods are
    reported, with zero force during them."""
    cfg = vtb.paper_config()
    cfg.irregularity = vtb.Irregularity(kind="cosine_dip", depth=-4e-3, length=0.2, position=30.0, dx=0.002)
    cfg.solver.t_end = 0.3
    r = vtb.simulate(cfg)
    assert r.contact_loss, "expected loss of contact"
    wheel, t0, t1 = r.contact_loss[0]
    i0 = int(round(t0 / cfg.solver.dt))
    assert r.contact_force[i0, wheel] == 0.0 and r.metrics()["contact_loss_events"] == len(r.contact_loss)


def test_moving_load_mode_with_full_stack():
    """Moving forces drive the whole stack without a vehicle (bridge checks)."""
    cfg = vtb.paper_config()
    cfg.vehicles = []
    cfg.forces = [vtb.MovingForce(70e3, 1.0), vtb.MovingForce(70e3, 3.5)]
    cfg.irregularity = vtb.Irregularity()
    cfg.solver.t_end = 0.2
    r = vtb.simulate(cfg)
    assert r.vehicle_disp.shape[1] == 0 and r.metrics()["rail_disp_max"] > 0


def test_ctrl_c_interrupts_a_batch(default_sigint):
    """SIGINT during a batch raises KeyboardInterrupt promptly (the GIL is released and the
    worker polls a cancel flag)."""
    cfgs = [vtb.paper_config() for _ in range(8)]
    timer = threading.Timer(0.5, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    t0 = time.perf_counter()
    with pytest.raises(KeyboardInterrupt):
        vtb.simulate_batch(cfgs, threads=2)
    assert time.perf_counter() - t0 < 5.0


def test_simulation_releases_the_gil():
    """While a run executes in another Python thread, this thread keeps running Python code
    (the core releases the GIL around the integration)."""
    cfg = vtb.paper_config()
    cfg.solver.t_end = 0.3
    worker = threading.Thread(target=vtb.simulate, args=(cfg,))
    ticks = 0
    worker.start()
    while worker.is_alive():
        ticks += 1
        time.sleep(0.001)
    assert ticks > 20


def test_two_cars_on_the_fem_model_run_past_the_column_cache():
    """Two cars on the FEM track for 0.5 s (40 m: more cached A⁻¹ columns than the cache keeps,
    which once dropped the other car's columns mid-step)."""
    cfg = vtb.paper_config()
    cfg.discretisation.method = "fem"
    cfg.solver.t_end = 0.5
    lead = cfg.vehicles[0]
    cfg.vehicles = [lead, vtb.crh3_car(lead.x_front + 25.0)]
    res = vtb.simulate(cfg)
    assert res.contact_force.shape[1] == 8
    assert np.all(np.isfinite(res.contact_force)) and np.all(res.contact_force > 0)


@pytest.mark.parametrize("target, name, path", [
    (lambda c: c, "sped", "sped"),
    (lambda c: c.solver, "time_step", "solver.time_step"),
    (lambda c: c.structure.layers[0], "densty", "structure.layers[0].densty"),
    (lambda c: c.structure.couplings[1], "stifness", "structure.couplings[1].stifness"),
    (lambda c: c.vehicles[0], "mass", "vehicles[0].mass"),
    (lambda c: c.copy().discretisation, "metod", "discretisation.metod"),
])
def test_an_attribute_typo_names_its_full_dotted_path(target, name, path):
    with pytest.raises(vtb.ConfigError) as e:
        setattr(target(vtb.paper_config()), name, 1)
    assert e.value.field == path


def test_a_single_run_reports_its_steps_and_stops_on_ctrl_c_within_a_second(default_sigint):
    """A single converged run (the slowest model, ≈ 70 000 steps) reports its progress in steps
    and SIGINT 3 s into it raises KeyboardInterrupt within 1 s of the signal."""
    cfg = vtb.paper_config(model="converged")
    seen, sent = [], []

    def interrupt():
        sent.append(time.perf_counter())
        os.kill(os.getpid(), signal.SIGINT)

    timer = threading.Timer(3.0, interrupt)
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        vtb.simulate(cfg, progress=lambda done, total: seen.append((done, total)))
    assert sent and time.perf_counter() - sent[0] < 1.0
    moving = [(d, t) for d, t in seen if t]
    assert len(moving) >= 5 and len({t for _, t in moving}) == 1 and moving[0][1] > 60_000
    done = [d for d, _ in moving]
    assert done == sorted(done) and done[-1] > done[0]


def test_a_single_runs_progress_argument_is_checked():
    with pytest.raises(vtb.ConfigError, match="progress"):
        vtb.simulate(vtb.paper_config(), progress="yes")
