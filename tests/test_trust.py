"""Trust on the newer surfaces (issue 41): every bad argument of trains, zones, spans, profile
parts, studies and optimisation is refused by a documented vtb error naming a usable field,
before any work and in well under a second; silent nulls (a defect off the structure, a force
in kN) are refused like a speed in km/h; a failed write names its path and cause."""

from __future__ import annotations

import errno
import math
import time

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import vtb
from vtb.errors import ConfigError, OutputError, VtbError
from fuzz_cases import small_config

UNNAMED = {None, "", "<config>", "<json>"}


def refused(fn, field=None, match=None, within=1.0, cls=ConfigError):
    """``fn()`` raises ``cls`` naming ``field`` (a non-empty string) within ``within`` s."""
    t0 = time.perf_counter()
    with pytest.raises(cls, match=match) as e:
        fn()
    took = time.perf_counter() - t0
    assert took < within, f"refused after {took:.2f} s"
    f = getattr(e.value, "field", None)
    assert isinstance(f, str) and f not in UNNAMED, f
    if field is not None:
        assert f == field, f
    return e.value


def _simulate(mod):
    def run():
        c = small_config()
        mod(c)
        return vtb.simulate(c, progress=False)
    return run


# silent nulls -------------------------------------------------------------------------------

def test_a_rail_joint_beyond_the_structure_is_refused():
    joint = vtb.Irregularity(kind="rail_joint", position=500.0, depth=1e-3, length=0.3)
    refused(_simulate(lambda c: setattr(c, "irregularity", joint)), "irregularity.position", match="outside the rail")
    weld = vtb.Irregularity(kind="dipped_weld", position=-80.0, depth=1e-3, length=1.0)
    refused(_simulate(lambda c: setattr(c.irregularity, "parts", [weld])), "irregularity.parts[0].position")
    # on the structure it runs and changes the answer
    near = vtb.Irregularity(kind="rail_joint", position=21.0, depth=1e-3, length=0.3)
    c = small_config(0.02)
    smooth = vtb.simulate(c, progress=False).metrics()
    c.irregularity = near
    assert vtb.simulate(c, progress=False).metrics() != smooth


def test_a_moving_force_in_kn_is_refused_with_its_likely_unit():
    def kn(c):
        c.vehicles, c.forces = [], [vtb.MovingForce(170.0, 1.0)]
    e = refused(_simulate(kn), "forces[0].magnitude", match="in kN, that is 170000.0000 N")
    assert "accept_implausible" in str(e)
    c = small_config()
    c.vehicles, c.forces = [], [vtb.MovingForce(170e3, 1.0)]
    assert math.isfinite(vtb.simulate(c, progress=False).metrics()["rail_disp_max"])


def test_a_force_that_never_reaches_the_structure_is_refused():
    def far(c):
        c.vehicles, c.forces = [], [vtb.MovingForce(1e5, 500.0)]
    refused(_simulate(far), "forces[0].x0", match="never reaches")


def test_a_vehicle_that_never_reaches_the_structure_is_refused():
    far = refused(_simulate(lambda c: setattr(c.vehicles[0], "x_front", 1e6)), "vehicles[0].x_front", match="never reach the rail")
    assert "1000000" in str(far)

    def behind(c):  # 60 m behind at 60 m/s for 0.2 s: 12 m of travel
        c.vehicles[0].x_front, c.solver.t_end, c.solver.edge_step = -60.0, 0.2, True
    refused(_simulate(behind), "vehicles[0].x_front", match="lengthen the run")

    def last_car(c):  # a train of two whose second car stays behind
        c.vehicles = vtb.train("crh3", cars=2, x_front=c.vehicles[0].x_front)
        c.vehicles[1].x_front = -500.0
    refused(_simulate(last_car), "vehicles[1].x_front", match="never reach")


def test_a_band_limit_below_the_filters_precision_is_a_config_error():
    refused(_simulate(lambda c: setattr(c.output, "band_limit", 1e-9)), "output.band_limit", match="double precision")


# raw exceptions -----------------------------------------------------------------------------

@pytest.mark.parametrize("kwargs, field", [
    (dict(x_front="x"), "x_front"), (dict(x_front=float("nan")), "x_front"), (dict(cars=10**9), "cars"),
    (dict(cars=2.5), "cars"), (dict(name=["crh3"]), "name"), (dict(rails="x"), "rails"),
])
def test_train_arguments_are_named(kwargs, field):
    refused(lambda: vtb.train(**kwargs), field)


@pytest.mark.parametrize("lengths, field", [([20, "x"], "lengths[1]"), ([1e8], "lengths"), ("20", "lengths"), ([], "lengths"),
                                            ([20, True], "lengths[1]"), ([20, float("inf")], "lengths[1]")])
def test_span_arguments_are_named_before_any_fastener_is_laid(lengths, field):
    refused(lambda: vtb.spans(small_config(), lengths), field)


def test_zones_of_implausible_length_are_refused_at_once():
    base = vtb.paper_config(model="fast")
    refused(lambda: vtb.track_zones(base, approach=1e8), "approach", match="plausible")
    refused(lambda: vtb.track_zones(base, exit="x"), "exit")
    refused(lambda: vtb.track_zones(base, tail="x"), "tail")
    refused(lambda: vtb.track_zones("config"), "config")


@pytest.mark.parametrize("kwargs, field", [(dict(seed="x"), "seed"), (dict(seed=-1), "seed"), (dict(pop_size=10**9), "pop_size"),
                                           (dict(n_gen="x"), "n_gen"), (dict(algorithm="ga"), "algorithm"), (dict(threads=0), "threads")])
def test_optimize_arguments_are_named_before_any_run(kwargs, field):
    refused(lambda: vtb.optimize(small_config(), progress=False, **kwargs), field)


@pytest.mark.parametrize("key", [None, ("speed",), "", " ", 3])
def test_a_study_grid_key_that_is_no_field_path_names_a_usable_field(key):
    e = refused(lambda: vtb.study(small_config(), {key: [50.0]}, progress=False))
    assert e.field.startswith("grid") or e.field == "study variable"


def test_study_arguments_are_named():
    c = small_config()
    refused(lambda: vtb.study(c, {"speed": [50.0]}, reference="tids", progress=False), "reference")
    refused(lambda: vtb.study(c, {"speed": [50.0]}, reference={"spede": 1.0}, progress=False), "spede")
    refused(lambda: vtb.study(c, {"speed": [50.0]}, indices=3, progress=False), "indices")
    refused(lambda: vtb.study(c, {"speed": [50.0]}, out=3, progress=False), "out")
    refused(lambda: vtb.study(c, {"speed": [50.0]}, threads="x", progress=False), "threads")
    refused(lambda: vtb.study(c, {"speed": list(range(1, 1001)), "solver.dt": list(range(1, 1002))}, progress=False), "grid")


def test_a_study_whose_out_cannot_be_written_names_the_path(tmp_path):
    blocker = tmp_path / "not-a-folder"
    blocker.write_text("")
    out = blocker / "s.csv"
    e = refused(lambda: vtb.study(small_config(), {"speed": [50.0]}, out=out, progress=False), "out", cls=OutputError)
    assert str(blocker) in str(e) and e.reason


def test_a_full_disk_during_a_study_is_an_output_error_naming_the_journal(tmp_path, monkeypatch):
    from vtb.studies import journal

    def full(*a, **k):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(journal, "append", full)
    out = tmp_path / "s.csv"
    e = refused(lambda: vtb.study(small_config(), {"speed": [50.0]}, out=out, progress=False), "out", cls=OutputError, within=30)
    assert e.errno == errno.ENOSPC and e.path == str(out) and "disk is full" in str(e)
    assert isinstance(e, VtbError) and isinstance(e, OSError)


# caps before work ---------------------------------------------------------------------------

def test_a_run_too_long_for_the_budget_is_refused_before_its_profile_is_drawn():
    """On the fast model the reduction's build is weighed first (it would be the costliest
    part); on the finite elements a run of more steps than the limit is refused before its
    1.9 km profile is drawn."""
    c = vtb.track_zones(vtb.paper_config(model="fast"))
    c.solver.t_end = 1000.0
    refused(lambda: vtb.simulate(c, progress=False), "solver.memory_budget", match="GB")
    c = vtb.track_zones(vtb.paper_config(model="converged"))
    c.solver.t_end = 10_000.0
    refused(lambda: vtb.simulate(c, progress=False), "solver.dt", match="steps exceeds")


# properties ---------------------------------------------------------------------------------

_junk = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-10**12, 10**12), st.text(max_size=3),
                  st.none(), st.booleans(), st.lists(st.floats(0, 100), max_size=2))


@settings(max_examples=60, deadline=None)
@given(st.lists(_junk, max_size=4))
def test_spans_take_any_list_or_name_the_bad_entry(lengths):
    try:
        out = vtb.spans(small_config(), lengths)
    except ConfigError as e:
        assert isinstance(e.field, str) and e.field.startswith("lengths")
    else:
        assert out.structure.length == pytest.approx(math.fsum(lengths))


@settings(max_examples=60, deadline=None)
@given(cars=_junk, x_front=_junk)
def test_train_takes_any_arguments_or_names_the_bad_one(cars, x_front):
    try:
        out = vtb.train("crh3", cars=cars, x_front=x_front)
    except ConfigError as e:
        assert e.field in ("cars", "x_front")
    else:
        assert len(out) == (8 if cars is None else cars) and all(math.isfinite(v.x_front) for v in out)


# files: the command line, concurrent writers, leftovers, versions -------------------------

def _tiny_toml(tmp_path):
    path = tmp_path / "tiny.toml"
    small_config().to_toml(path)
    return str(path)


def test_a_full_disk_in_vtb_simulate_is_one_line_and_exit_2(tmp_path, monkeypatch, capsys):
    from vtb import cli

    def full(self, path):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(vtb.Result, "save", full)
    out = tmp_path / "out"
    assert cli.main(["simulate", "--config", _tiny_toml(tmp_path), "--out", str(out), "--no-plot"]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "OutputError" in err and str(out / "result.npz") in err and "disk is full (ENOSPC)" in err


def test_a_second_vtb_simulate_into_one_folder_is_refused(tmp_path, capsys):
    from pathlib import Path

    from vtb import cli
    from vtb.studies.journal import lock

    out = tmp_path / "out"
    out.mkdir()
    with lock(Path(out) / "vtb-simulate", "--out", "another vtb simulate"):  # the first run, still going
        t0 = time.perf_counter()
        assert cli.main(["simulate", "--config", _tiny_toml(tmp_path), "--out", str(out), "--no-plot"]) == 2
        assert time.perf_counter() - t0 < 1.0
    err = capsys.readouterr().err
    assert "in use by another vtb simulate" in err and "--out" in err
    assert not (out / "result.npz").exists()
    assert cli.main(["simulate", "--config", _tiny_toml(tmp_path), "--out", str(out), "--no-plot"]) == 0  # the lock went with its holder
    assert (out / "result.npz").exists() and not (out / "vtb-simulate.lock").exists()


def test_temporary_files_of_a_killed_writer_are_cleaned_by_the_next_write(tmp_path):
    from vtb.optim.checkpoint import write_atomically

    dead = tmp_path / ".ck.npz.4194305.abcd1234.tmp"  # above Linux's pid_max: no such process
    dead.write_bytes(b"half")
    mine = tmp_path / f".ck.npz.{__import__('os').getpid()}.ffff0000.tmp"
    mine.write_bytes(b"in progress")
    write_atomically(tmp_path / "ck.npz", lambda f: f.write(b"x"))
    assert not dead.exists() and mine.exists() and (tmp_path / "ck.npz").read_bytes() == b"x"


def test_a_journal_reads_back_in_grid_order_whatever_the_completion_order(tmp_path):
    from vtb.studies.grid import read_journal

    out = tmp_path / "s.csv"
    vtb.study(small_config(), {"speed": [60.0, 70.0], "k_t": [1e8, 2e8]}, out=out, progress=False)
    before = read_journal(out)
    lines = out.read_text().split("\n")
    rows = [line for line in lines[2:] if line]
    out.write_text("\n".join(lines[:2] + rows[::-1]) + "\n")  # finished in the other order (resumed, on Dask)
    after = read_journal(out)
    for k in before.columns:
        assert (before.columns[k] == after.columns[k]).all(), k
    assert list(after.columns["speed"]) == [60.0, 60.0, 70.0, 70.0] and list(after.columns["k_t"]) == [1e8, 2e8, 1e8, 2e8]


# figures and warnings -----------------------------------------------------------------------

def test_band_levels_on_the_hybrid_warn_once_per_cause_in_a_batch():
    import warnings

    cfgs = []
    for seed in (1, 2, 3):
        c = small_config(0.02)
        c.irregularity.seed = seed
        c.output.band_levels = [2000]
        cfgs.append(c)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        vtb.simulate_batch(cfgs, progress=False)
    said = [str(w.message) for w in caught if issubclass(w.category, vtb.ResolutionWarning)]
    # three runs differing only in their seed: each cause (the band levels, and the
    # irregularity's band beyond the rail's) said once for the batch, not once per run or layer
    assert said and len(said) == len(set(said)) <= 2, said
    assert sum(m.startswith("output.band_levels") for m in said) == 1, said


def test_what_the_long_fuzz_run_found_is_named():
    """Cases benches/fuzz_config.py found raising non-vtb exceptions, each now a named refusal."""
    c = small_config()
    refused(lambda: vtb.study(c, {"dampers": [60.0]}, progress=False), "dampers", match="not a number field")
    refused(lambda: vtb.study(c, {"speed": [60.0]}, reference={"speed": float("nan")}, progress=False), "reference['speed']")
    weld = vtb.Irregularity(kind="dipped_weld", position=21.0, depth=1e300, length=1.0)
    refused(_simulate(lambda c: setattr(c, "irregularity", weld)), "irregularity.depth", match="no irregularity")
    refused(_simulate(lambda c: setattr(c, "irregularity", -1e-300)), "irregularity")
    d = small_config().to_dict()
    d["irregularity"]["kind"] = {"a": 1}
    refused(lambda: vtb.simulate(vtb.Config.from_dict(d), progress=False), "irregularity.kind")


def test_a_defect_seen_through_an_implausible_wheel_is_refused_at_once():
    """Found by the long fuzz run (seed 1): a wheel radius of 1e300 m hung the wheel-path
    envelope; the radius is held to the wheels' plausible range."""
    joint = vtb.Irregularity(kind="rail_joint", position=21.0, depth=1e-4, length=0.3, wheel_radius=1e300)
    refused(_simulate(lambda c: setattr(c, "irregularity", joint)), "irregularity.wheel_radius", match="plausible wheel radius")


# folders of user paths ----------------------------------------------------------------------

def test_make_folder_creates_only_the_last_folder(tmp_path):
    from vtb.errors import make_folder

    assert make_folder(tmp_path / "new", "out").is_dir()
    assert make_folder(tmp_path / "new", "out").is_dir()  # an existing folder is fine
    e = refused(lambda: make_folder(tmp_path / "typo" / "deeper", "out"), "out", match="parent folder", cls=OutputError)
    assert e.path == str(tmp_path / "typo" / "deeper") and e.errno == errno.ENOENT and not (tmp_path / "typo").exists()
    (tmp_path / "file").write_text("x")
    e = refused(lambda: make_folder(tmp_path / "file" / "sub", "out"), "out", match="is a file", cls=OutputError)
    assert e.errno == errno.ENOTDIR


def _typo(tmp_path):
    return tmp_path / "typo" / "results"


def _bridge_check(tmp_path):
    cfg = vtb.moving_load_config(20.0, 2500.0, 4.8, 3.5e10, 0.1, [vtb.MovingForce(1.0, 0.0)], 50.0, points=[10.0], modes=10, dt=1e-3)
    settings = dict(span=20.0, bridge_type="prestressed_concrete", track="ballasted", line_speed=60.0, trains=["HSLM-A1"], dt=1e-3)
    return vtb.bridge_check(cfg, settings, _typo(tmp_path), progress=False)


@pytest.mark.parametrize("write, field", [
    (lambda p: vtb.study(small_config(), {"speed": [60.0]}, out=_typo(p) / "s.csv", progress=False), "out"),
    (lambda p: vtb.study(small_config(), {"speed": [60.0]}, out=_typo(p) / "s.parquet", progress=False), "out"),
    (lambda p: vtb.optimize(small_config(), pop_size=4, n_gen=1, seed=1, progress=False, checkpoint=_typo(p) / "ck.npz"), "checkpoint"),
    (_bridge_check, "out"),
    (lambda p: vtb.speed_scan(small_config(), ["HSLM-A1"], [60.0], out=_typo(p), progress=False), "out"),
])
def test_a_mistyped_folder_tree_is_refused_before_any_run(tmp_path, write, field):
    refused(lambda: write(tmp_path), field, match="parent folder", cls=OutputError)
    assert not (tmp_path / "typo").exists()


def test_vtb_simulate_refuses_a_mistyped_folder_tree_in_one_line(tmp_path, capsys):
    from vtb import cli

    assert cli.main(["simulate", "--config", _tiny_toml(tmp_path), "--out", str(_typo(tmp_path)), "--no-plot"]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "parent folder" in err and "--out" in err and not (tmp_path / "typo").exists()
    assert cli.main(["simulate", "--config", _tiny_toml(tmp_path), "--out", str(tmp_path / "results"), "--no-plot"]) == 0


def test_a_section_given_as_a_table_is_refused_naming_it():
    """A table (dict) in place of a section reached the core, which read it with defaults,
    while the Python checks met an AttributeError (the fuzzer's find)."""
    for section in ("discretisation", "solver", "output", "structure"):
        cfg = small_config()
        setattr(cfg, section, {})
        with pytest.raises(ConfigError) as e:
            vtb.simulate(cfg, progress=False)
        assert e.value.field == section


def test_a_thread_count_beyond_any_machine_is_refused_before_work():
    """`threads=10**6` started thousands of worker threads before anything failed (the bridge
    fuzzer's find); now every door that takes a thread count refuses it at once, naming it."""
    from vtb.config.args import MAX_THREADS

    cfg = small_config()
    for call in (lambda t: vtb.simulate_batch([cfg], threads=t), lambda t: vtb.study(cfg, {"speed": [50.0]}, threads=t, progress=False)):
        for bad in (10**6, MAX_THREADS + 1, 0, "2", 2.0):
            start = time.perf_counter()
            with pytest.raises(ConfigError) as e:
                call(bad)
            assert e.value.field == "threads" and time.perf_counter() - start < 1.0


def test_an_optimisation_reference_that_is_not_a_mapping_is_refused_naming_it():
    """`optimize(..., reference="tids")` met an AttributeError (the long fuzz run's find)."""
    with pytest.raises(ConfigError) as e:
        vtb.optimize(small_config(), variables={"tids.stiffness": (1e7, 1e9, "log")}, objectives=["rail_acc_rms"],
                     constraints=[("rail_acc_max", "reference")], reference="tids", pop_size=4, n_gen=1, seed=0, progress=False)
    assert e.value.field == "reference"
