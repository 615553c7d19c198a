"""The vtb command: help on every subcommand, and the quick reproduction (what CI runs)."""

import json

import pytest

import vtb
from vtb import cli

COMMANDS = ["simulate", "validate", "sweep", "optimize", "reproduce", "examples", "study"]


@pytest.mark.parametrize("command", COMMANDS)
def test_every_command_has_help(command, capsys):
    with pytest.raises(SystemExit) as e:
        cli.main([command, "--help"])
    assert e.value.code == 0
    assert "usage: vtb " + command in capsys.readouterr().out


def test_bad_input_is_a_clean_error(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text("speed = -1\n")
    assert cli.main(["simulate", "--config", str(bad)]) == 2
    assert "vtb: ConfigError" in capsys.readouterr().err


def test_sweep_command_writes_journal_and_report(tmp_path, capsys):
    cfg = tmp_path / "short.toml"
    import vtb

    c = vtb.paper_config()
    c.solver.t_end = 0.1
    c.output.points = [6.0]
    c.tids = vtb.tids_around(c, count=2, x=6.0)
    c.to_toml(cfg)
    out, rep = tmp_path / "s.csv", tmp_path / "s.md"
    assert cli.main(["sweep", "--config", str(cfg), "--b", "5", "--k", "1e8,2e8", "--c", "1000", "--out", str(out), "--report", str(rep), "--no-progress"]) == 0
    assert len(out.read_text().splitlines()) == 2 + 3  # stamp, header, baseline and two cases
    assert "Best (k_t, c_t) per b_t" in rep.read_text()


def test_reproduce_quick(tmp_path):
    """The quick chain end to end: every figure, table and the report."""
    out = tmp_path / "rep"
    assert cli.main(["reproduce", "--out", str(out), "--quick", "--no-progress"]) == 0
    figures = ["fig3_histories", "fig5_sweep_rail", "fig6_sweep_slab", "fig7_pareto", "fig8_histories", "fig_car_body", "fig_hypervolume", "fig_third_octave"]
    for name in ["report.md", "table2.csv", "table_3_3.csv", "sweep.csv", "third_octave.csv"] + [f"{f}.{s}" for f in figures for s in ("png", "pdf")]:
        assert (out / name).exists(), name
    text = (out / "report.md").read_text()
    assert "article, solution 1" in text and "1005.6" in text
    assert str(tmp_path) not in text and "`vtb reproduce --out rep --quick`" in text  # relative to its folder
    # the frequency view and one evidence paragraph per gap
    assert "## Frequency view" in text and "![one-third-octave levels](fig_third_octave.png)" in text
    # the optimisation's start: why it is the default, and what the run took
    optimisation = text.split("## §4.4")[1].split("\n## ")[0]
    assert "* Why this start: the " in optimisation and "min) of wall time" in optimisation
    gaps = text.split("## The gaps between vtb and the article, and the evidence")[1].split("## Run times")[0]
    for gap in ("Rail displacement", "Slab acceleration", "Rail r.m.s. and stabilisation time", "The best sweep case", "The MOGA optimum", "Car body"):
        assert f"**{gap}" in gaps, gap
    # A designs journal stamped for another configuration (an earlier version): --force sets it
    # aside and reruns, reusing the sweep journal, which still matches.
    journal = next(out.glob("optimisation_warm_*.designs.jsonl"))
    identity, *rest = journal.read_text().splitlines()
    stamped = json.loads(identity)
    stamped["identity"]["vtb.optimize"]["config"]["speed"] += 1.0
    journal.write_text("\n".join([json.dumps(stamped), *rest]) + "\n")
    sweep = (out / "sweep.csv").read_text()
    assert cli.main(["reproduce", "--out", str(out), "--quick", "--no-progress", "--force"]) == 0
    assert journal.with_name(journal.name + ".stale").exists() and journal.exists()
    assert (out / "sweep.csv").read_text() == sweep


def test_simulate_says_what_it_runs_and_how_it_relates_to_the_article():
    """`vtb simulate` (the README's first command) names its model, what it resolves, its
    irregularity level, and that the article's published numbers need the calibrated level;
    `--config article` says which number is fitted and which are out-of-sample."""
    import vtb
    from vtb.config.presets import ARTICLE_RAIL_ACC, PAPER_CALIBRATED_SCALE, example_config

    raw = "\n".join(cli._describe(vtb.paper_config(), "default"))
    assert "FE–SEA hybrid" in raw and "level ×1" in raw
    assert "does not hold the rail's pinned–pinned mode" in raw
    assert f"{ARTICLE_RAIL_ACC} m/s² needs vtb's calibrated level ×{PAPER_CALIBRATED_SCALE}" in raw
    assert "vtb simulate --config article" in raw
    calibrated = "\n".join(cli._describe(example_config("article"), "article"))
    assert f"level ×{PAPER_CALIBRATED_SCALE}" in calibrated and "the one fitted number" in calibrated
    assert "out-of-sample" in calibrated
    converged = "\n".join(cli._describe(example_config("article_converged"), "article_converged"))
    assert "Timoshenko rail" in converged and "low-passed at 2000 Hz" in converged
    assert "this converged model differs by design" in converged
    other = "\n".join(cli._describe(example_config("two_span_sato"), "two_span_sato"))
    assert "article" not in other.split("irregularity")[1]


def test_study_grid_command_runs_the_generic_study(tmp_path, capsys):
    """`vtb study grid` gives, case for case, what vtb.study gives; bad --vary names itself."""
    import numpy as np

    import vtb

    c = vtb.paper_config()
    c.solver.t_end = 0.1
    c.output.points = [6.0]
    c.tids = vtb.tids_around(c, count=2, x=6.0)
    cfg = tmp_path / "short.toml"
    c.to_toml(cfg)
    out = tmp_path / "g.csv"
    args = ["study", "grid", "--config", str(cfg), "--vary", "speed=70,80", "--vary", "tids.k_t=1e8", "--indices", "rail_acc_max,car_comfort_aw",
            "--uncontrolled", "--out", str(out), "--no-progress"]
    assert cli.main(args) == 0
    printed = capsys.readouterr().out.splitlines()
    assert printed[0].split() == ["case", "speed", "tids.k_t", "rail_acc_max", "car_comfort_aw"] and len(printed) == 1 + 3 + 1
    want = vtb.study(vtb.Config.from_toml(cfg), {"speed": [70.0, 80.0], "tids.k_t": [1e8]}, indices=["rail_acc_max", "car_comfort_aw"],
                     reference={"tids": None}, progress=False)
    got = vtb.studies.read_journal(out)
    assert got.variables == ("speed", "tids.k_t") and got.indices == ("rail_acc_max", "car_comfort_aw")
    # The journal numbers its cases in the order they finished (threads vary it): compare by row.
    key = lambda r: [(-1.0 if np.isnan(s) else s, k) for s, k in zip(r.columns["speed"], r.columns["tids.k_t"])]
    og, ow = np.argsort([s for s, _ in key(got)], kind="stable"), np.argsort([s for s, _ in key(want)], kind="stable")
    for k in ("speed", "tids.k_t", "rail_acc_max", "car_comfort_aw"):
        np.testing.assert_array_equal(np.asarray(got.columns[k])[og], np.asarray(want.columns[k])[ow])
    assert np.isnan(got.columns["speed"][0])
    assert cli.main(["study", "grid", "--vary", "speed=fast", "--out", str(tmp_path / "x.csv"), "--no-progress"]) == 2
    assert "--vary" in capsys.readouterr().err


def test_force_sets_stale_journals_aside_and_keeps_the_rest(tmp_path):
    """A study's run refusing a journal of another configuration: with --force the journal is
    renamed *.stale and the run retried (matching journals stay); without it, or for a
    journal in use by another process, the refusal stands."""
    from vtb.cli import run_setting_aside_stale
    from vtb.errors import config_error, stale_file_error

    stale, kept = tmp_path / "opt.npz.designs.jsonl", tmp_path / "sweep.csv"
    stale.write_text("old\n")
    kept.write_text("mine\n")
    calls = []

    def run():
        calls.append(1)
        if stale.exists():
            raise stale_file_error("checkpoint", stale, "holds the designs of another optimisation; delete it with its checkpoint to start afresh")
        return "report"

    with pytest.raises(vtb.ConfigError, match="another optimisation"):
        run_setting_aside_stale(run, force=False)
    assert stale.exists()
    assert run_setting_aside_stale(run, force=True) == "report"
    assert len(calls) == 3 and not stale.exists() and (tmp_path / "opt.npz.designs.jsonl.stale").read_text() == "old\n"
    assert kept.read_text() == "mine\n"

    def busy():
        raise config_error("out", str(kept), "is in use by another sweep (pid 1; lock file x)")

    with pytest.raises(vtb.ConfigError, match="in use"):
        run_setting_aside_stale(busy, force=True)
    assert kept.exists()


def test_a_stale_file_error_pickles_with_its_path():
    import pickle

    from vtb.errors import stale_file_error

    e = pickle.loads(pickle.dumps(stale_file_error("checkpoint", "/x/opt.npz", "belongs to another run")))
    assert isinstance(e, vtb.StaleFileError) and isinstance(e, vtb.ConfigError)
    assert (e.path, e.field, e.reason) == ("/x/opt.npz", "checkpoint", "belongs to another run")
