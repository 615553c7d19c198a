"""Lockstep batches: jobs of one model (differing in damper parameters or irregularity) run
together, and each gives the bits it gives alone; a failing job never spoils its group."""

import math
import os
import signal
import sys
import threading
import time

import numpy as np
import pytest

import vtb
from vtb.article.tid_problem import case_config


@pytest.fixture(scope="module")
def group():
    """One model, eleven jobs: damper parameter sets across the article's grid, the same
    design on two other irregularity samples, one on a 4 mm dip that throws the wheels off
    the rail, and one with damper parameters beyond the physical bounds (refused alone; the
    core's test `a_failing_lane_leaves_its_group_unharmed` fails a lane mid-run)."""
    base = vtb.paper_config()
    base.solver.t_end = 0.3
    base.output.points = [30.0, 8.0]
    base.tids = vtb.tids_around(base, count=3, x=30.0)
    params = [(1, 2e7, 10), (4, 7e8, 10), (7, 3e8, 1e3), (10, 1e4, 1e4), (2, 1e9, 100), (5, 5e5, 1e3)]
    cfgs = [case_config(base, *p) for p in params]
    for seed in (11, 12):
        c = case_config(base, 3, 1e8, 1e3)
        c.irregularity.seed = seed
        cfgs.append(c)
    dip = case_config(base, 3, 1e8, 1e3)
    dip.irregularity = vtb.Irregularity(kind="cosine_dip", depth=-4e-3, length=0.2, position=30.0, dx=0.002)
    cfgs.append(dip)
    cfgs.append(case_config(base, 1e300, 1e300, 1.0))
    return cfgs


def _bits_equal(a: dict, b: dict) -> bool:
    return a.keys() == b.keys() and all(np.float64(a[k]).tobytes() == np.float64(b[k]).tobytes() for k in a)


def test_lockstep_jobs_give_the_bits_of_single_runs(group):
    """Every metric of every job of mixed lockstep groups (widths 8, 2, 1 over 10 jobs on one
    thread, and the default widths on two threads) equals the job run alone, bit for bit
    (the requirement is 1e-10 relative); contact loss included, and the refused job gets the
    error it gets alone."""
    alone = []
    for c in group:
        try:
            alone.append(vtb.simulate(c).metrics())
        except vtb.VtbError as e:
            alone.append(e)
    assert isinstance(alone[-1], vtb.ConfigError), alone[-1]
    assert alone[-2]["contact_loss_events"] > 0
    for lanes, threads in ((8, 1), (4, 2), (2, 1), (1, 1)):
        out = vtb.simulate_batch(group, threads=threads, lanes=lanes, on_error="return")
        for i, (a, b) in enumerate(zip(alone, out)):
            if isinstance(a, Exception):
                assert type(b) is type(a) and str(b) == str(a)
            else:
                assert _bits_equal(a, b), (lanes, i, {k: (a[k], b[k]) for k in a if a[k] != b[k]})


def test_histories_give_full_results_equal_to_single_runs(group):
    jobs = group[:3] + group[-2:-1]
    out = vtb.simulate_batch(jobs, threads=1, histories=True)
    for c, r in zip(jobs, out):
        alone = vtb.simulate(c)
        assert isinstance(r, vtb.Result) and r.config is c
        for name in ("disp", "acc", "vehicle_disp", "vehicle_acc", "contact_force"):
            assert np.array_equal(getattr(alone, name), getattr(r, name)), name
        assert r.contact_loss == alone.contact_loss and r.points == alone.points


def test_lanes_must_be_a_compiled_width(group):
    for bad in (0, 3, 16, True, 2.0):
        with pytest.raises(vtb.ConfigError) as e:
            vtb.simulate_batch(group[:1], lanes=bad)
        assert e.value.field == "lanes"


def test_ctrl_c_stops_a_long_batch_within_a_second(default_sigint):
    """SIGINT 0.4 s into a batch of converged-preset jobs (the slowest model: lockstep groups
    of four, ≈ 70 000 steps each) raises KeyboardInterrupt within 1 s of the signal."""
    base = vtb.paper_config(model="converged")
    base.tids = vtb.tids_around(base)
    cfgs = [case_config(base, b, 1e8, 1e3) for b in range(1, 9)]
    sent = []

    def interrupt():
        sent.append(time.perf_counter())
        os.kill(os.getpid(), signal.SIGINT)

    timer = threading.Timer(0.4, interrupt)
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        vtb.simulate_batch(cfgs, threads=2)
    assert sent and time.perf_counter() - sent[0] < 1.0


def test_runs_on_one_sample_share_its_profile_which_is_the_sample_drawn_afresh(monkeypatch):
    from vtb.config.prepare import irregularity_profile

    a = vtb.paper_config()
    a.irregularity.seed = 11
    b = a.copy()
    b.tids = vtb.tids_around(b, count=2, x=8.0)
    b.speed = a.speed * 1.1  # the wheels stay on the structure: the same stretch
    c = a.copy()
    c.irregularity.seed = 12
    pa, pb, pc = irregularity_profile(a), irregularity_profile(b), irregularity_profile(c)
    assert pa is pb and pc is not pa and not np.array_equal(pa.values, pc.values)
    assert not pa.values.flags.writeable  # shared: nobody may change it
    x0, dx, values, _ = a.irregularity.sample(0.0, a.structure.length)  # drawn afresh, no cache
    assert (pa.x0, pa.dx) == (x0, dx) and np.array_equal(pa.values, values)
    # a cache too small for two keeps the newest only, and gives the same profiles
    monkeypatch.setattr(sys.modules["vtb.config.prepare"], "PROFILE_CACHE_BYTES", pa.values.nbytes)
    d = a.copy()
    d.irregularity.seed = 13
    irregularity_profile(d)  # inserting d's leaves it alone in the cache
    fresh = irregularity_profile(a.copy())
    assert fresh is not pa and np.array_equal(fresh.values, values)


def test_a_shared_profile_gives_its_warning_at_every_run():
    """A sample too short for its band warns when it is drawn, and again when a later run
    takes it from the process's cache."""
    from vtb.config.prepare import irregularity_profile

    c = vtb.paper_config()
    c.irregularity = vtb.Irregularity(kind="german_low", wavelength_min=2.0, wavelength_max=400.0, seed=5)
    for _ in range(2):
        with pytest.warns(vtb.IrregularityWarning, match="of the variance"):
            irregularity_profile(c.copy())
