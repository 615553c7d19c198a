"""Hardening: every bad input is a documented exception naming its field; runs too large for
the memory budget are refused up front with their size; overflows never come back as
results; run lengths land on their end time; under-realised irregularity bands warn; typos
in attribute names raise; and the command line refuses bad files and folders before
computing (docs/limits.md)."""

import sys
import warnings

import numpy as np
import pytest

import vtb
from fuzz_cases import small_config
from vtb import cli


def _raises_on(mutate, field, *, match=None):
    cfg = small_config()
    mutate(cfg)
    with pytest.raises(vtb.ConfigError, match=match) as e:
        vtb.simulate(cfg)
    assert e.value.field == field, str(e.value)
    return e.value


@pytest.mark.parametrize(
    "mutate, field",
    [
        (lambda c: setattr(c.tids, "count", -1), "tids.count"),
        (lambda c: setattr(c.solver, "contact_max_iter", -5), "solver.contact_max_iter"),
        (lambda c: setattr(c.vehicles[0], "rails", -2), "vehicles[0].rails"),
        (lambda c: setattr(c.structure.layers[0], "local_modes", 10**20), "structure.layers[0].local_modes"),
        (lambda c: setattr(c.discretisation, "local_deflection", "yes"), "discretisation.local_deflection"),
        (lambda c: setattr(c.output, "points", np.ones((2, 2))), "output.points[0]"),
        (lambda c: setattr(c.structure.layers[1], "modes", 2.5), "structure.layers[1].modes"),
        (lambda c: setattr(c.discretisation, "method", "spectral"), "discretisation.method"),
        (lambda c: setattr(c.vehicles[0], "m_c", object()), "vehicles[0].m_c"),
        (lambda c: setattr(c, "speed", np.ones((2, 2))), "speed"),
    ],
)
def test_type_and_range_errors_name_their_field(mutate, field):
    _raises_on(mutate, field)


def test_toml_parse_errors_carry_the_path():
    text = small_config().to_toml().replace("rails = 2", "rails = -2")
    with pytest.raises(vtb.ConfigError) as e:
        vtb.Config.from_toml_text(text)
    assert e.value.field == "vehicles[0].rails"
    text = small_config().to_toml().replace("local_deflection = true", 'local_deflection = "true"')
    with pytest.raises(vtb.ConfigError) as e:
        vtb.Config.from_toml_text(text)
    assert e.value.field == "discretisation.local_deflection"


@pytest.mark.parametrize("path, name", [("", "sped"), ("solver", "time_step"), ("irregularity", "sead"), ("structure.layers[0]", "mode"), ("tids", "Count")])
def test_attribute_typos_raise_with_the_known_names(path, name):
    obj = small_config()
    for part in filter(None, path.replace("[", ".").replace("]", "").split(".")):
        obj = obj[int(part)] if part.isdigit() else getattr(obj, part)
    with pytest.raises(vtb.ConfigError, match="known: ") as e:
        setattr(obj, name, 1)
    assert e.value.field == (f"{path}.{name}" if path else name)  # the full dotted path
    assert name not in vars(obj)


def test_oversized_runs_are_refused_up_front_with_their_size():
    # matrices: a layer with 20 000 modes is ≈ 19 GB of dense modal matrices
    e = _raises_on(lambda c: setattr(c.structure.layers[1], "modes", 20_000), "structure.layers[1].modes", match="GB")
    assert "memory_budget" in e.reason
    # 10 000 dampers: refused with the reason (a dense 10⁴ × 10⁴ coupling per run and step)
    _raises_on(lambda c: (setattr(c.tids, "count", 10_000), setattr(c.tids, "x0", 1.0), setattr(c.tids, "spacing", 0.01)), "tids.count", match="dense")
    # a 500 km structure or a profile sample spacing of 1e-300 m: the profile would not fit
    _raises_on(lambda c: (setattr(c.structure, "length", 5e5), c.accept_implausible.append("structure.length")), "irregularity.dx", match="500000 m")
    _raises_on(lambda c: setattr(c.irregularity, "dx", 1e-300), "irregularity.dx", match="GB")
    # many observation points over a long run: the histories would not fit a small budget
    def long_record(c):
        c.irregularity = vtb.Irregularity()
        c.output.points = list(np.linspace(1.0, 159.0, 2000))
        c.solver.t_end = 1.0
        c.solver.memory_budget = 2e9

    e = _raises_on(long_record, "output.points", match="steps of histories")
    # the budget is the user's: the same run under a budget it fits runs
    cfg = small_config()
    cfg.output.points = list(np.linspace(1.0, 159.0, 50))
    cfg.solver.memory_budget = 1e9
    assert np.isfinite(vtb.simulate(cfg).acc).all()


def test_overflow_is_a_solver_error_never_a_result():
    cfg = small_config()
    # a 1e300 m rise: even the faded-in share of it overflows the Hertz force
    cfg.irregularity = vtb.Irregularity(kind="sampled", x0=0.0, dx=0.1, values=[-1e300] * 1601)
    with pytest.raises(vtb.SolverError, match="non-finite|not finite"):
        vtb.simulate(cfg)
    # in a batch the overflowing job fails alone
    good = small_config()
    out = vtb.simulate_batch([cfg, good], on_error="return")
    assert isinstance(out[0], vtb.SolverError) and np.isfinite(list(out[1].values())).all()


def test_the_last_step_lands_on_t_end():
    cfg = small_config()
    cfg.solver.t_end = 0.00203
    with pytest.raises(vtb.ConfigError, match=r"0\.002 and 0\.00205") as e:
        vtb.simulate(cfg)
    assert e.value.field == "solver.t_end"
    cfg.solver.t_end = 0.00205
    assert vtb.simulate(cfg).t[-1] == pytest.approx(0.00205, abs=1e-15)
    # without t_end: the whole step nearest to the leading wheel reaching L − end_margin
    cfg.irregularity = vtb.Irregularity()
    cfg.solver.t_end = None
    cfg.solver.dt = 5e-4
    res = vtb.simulate(cfg)
    v = cfg.vehicles[0]
    t_lead = (cfg.structure.length - cfg.solver.end_margin - v.x_front) / cfg.speed
    assert abs(res.t[-1] - t_lead) <= 0.5 * cfg.solver.dt
    assert res.t[-1] / cfg.solver.dt == pytest.approx(round(res.t[-1] / cfg.solver.dt), abs=1e-9)


def test_a_band_longer_than_the_profile_warns_with_the_realised_variance():
    irr = vtb.paper_irregularity()
    irr.wavelength_max = 500.0
    with pytest.warns(vtb.IrregularityWarning, match=r"realises (\d+\.\d)%") as w:
        _, _, values = irr.profile(0.0, 160.0)
    frac = float(str(w[0].message).split("realises ")[1].split("%")[0]) / 100
    # the generated sample's own variance (an independent measure) agrees with the fraction
    assert np.var(values) / irr.target_variance() == pytest.approx(frac, rel=0.05)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        vtb.paper_irregularity().profile(0.0, 160.0)  # the article's band is realised


def test_convergence_error_reports_the_iterations_it_took():
    cfg = small_config()
    cfg.irregularity.scale = 50.0  # hard contact
    cfg.solver.contact_max_iter = 1
    with pytest.raises(vtb.ConvergenceError) as e:
        vtb.simulate(cfg)
    assert e.value.iterations == 1
    assert f"after {e.value.iterations} iterations" in str(e.value)


# ------------------------------------------------------------------------- files and CLI
def test_from_toml_tells_a_path_from_text(tmp_path):
    text = small_config().to_toml()
    with pytest.raises(vtb.ConfigError, match="from_toml_text"):
        vtb.Config.from_toml(text)
    with pytest.raises(vtb.ConfigError, match="no such file") as e:
        vtb.Config.from_toml(str(tmp_path / "missing.toml"))
    assert e.value.field == "path"
    with pytest.raises(vtb.ConfigError, match="directory"):
        vtb.Config.from_toml(tmp_path)
    (tmp_path / "c.toml").write_text(text)
    assert vtb.Config.from_toml(tmp_path / "c.toml") == vtb.Config.from_toml_text(text)


def _one_line_error(capsys, argv, *needles):
    assert cli.main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    for n in needles:
        assert n in err, err
    return err


def test_cli_refuses_bad_files_and_folders_before_computing(tmp_path, capsys):
    cfg = tmp_path / "c.toml"
    small = small_config()
    small.tids = None
    small.to_toml(cfg)
    out = tmp_path / "run"
    assert cli.main(["simulate", "--config", str(cfg), "--out", str(out), "--no-plot"]) == 0
    capsys.readouterr()
    _one_line_error(capsys, ["simulate", "--config", str(cfg), "--out", str(out), "--no-plot"], "--out", "--force")
    assert cli.main(["simulate", "--config", str(cfg), "--out", str(out), "--no-plot", "--force"]) == 0
    capsys.readouterr()
    blocker = tmp_path / "file"
    blocker.write_text("x")
    _one_line_error(capsys, ["simulate", "--config", str(cfg), "--out", str(blocker / "sub")], "--out", "is a file, not a folder")
    _one_line_error(capsys, ["simulate", "--config", str(tmp_path / "none.toml")], "--config", "no such file")
    _one_line_error(capsys, ["simulate", "--config", str(tmp_path)], "--config", "directory")
    _one_line_error(capsys, ["optimize", "--config", str(cfg), "--out", str(tmp_path)], "--out", "directory")
    _one_line_error(capsys, ["sweep", "--config", str(cfg), "--out", str(tmp_path)], "--out", "directory")
    (tmp_path / "rep").mkdir()
    (tmp_path / "rep" / "report.md").write_text("earlier")
    _one_line_error(capsys, ["reproduce", "--quick", "--out", str(tmp_path / "rep")], "--out", "report.md", "--force")


def test_a_missing_plot_extra_is_named(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    _one_line_error(capsys, ["reproduce", "--quick", "--out", str(tmp_path / "r")], "pip install 'vtb[plot]'")
