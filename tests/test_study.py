"""The robust design study (vtb.robust_study): the quick variant end to end, what CI runs. Its numbers
are not findings; what is checked is that every stage ran, that its tables hold what the
report says, and that a held-out row is the run it claims to be."""

import csv
import json

import numpy as np
import pytest

import vtb
from vtb import cli
from vtb.run import scaleout
from vtb.article import robust_study as study


@pytest.fixture(scope="module")
def quick(tmp_path_factory):
    out = tmp_path_factory.mktemp("study")
    assert cli.main(["study", "robust", "--out", str(out), "--quick", "--no-progress"]) == 0
    return out


def _rows(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def test_the_quick_study_writes_every_stage(quick):
    for name in ["report.md", "article/report.md", "article/summary.json", "levels.csv", "converged_chains.csv", "robust_baselines.csv",
                 "robust_designs.csv", "robust_design_table.csv", "held_out.csv", "verdicts.csv"] + [
                 f"{f}.{s}" for f in ("fig_baselines", "fig_robust_designs", "fig_held_out") for s in ("png", "pdf")]:
        assert (quick / name).exists(), name
    plan = study.PLANS["quick"]
    n_cases = plan["samples"] * len(plan["speeds"])
    assert len(_rows(quick / "robust_baselines.csv")) == n_cases
    assert len(_rows(quick / "held_out.csv")) == 2 * plan["held_out"] * len(plan["speeds"])
    # the robust design table: one design for all speeds and one per speed
    assert [r["design"] for r in _rows(quick / "robust_design_table.csv")] == ["all speeds"] + [f"{v:g} m/s" for v in plan["speeds"]]
    # the level without contact loss is the largest factor whose run kept every wheel on the rail
    levels = _rows(quick / "levels.csv")
    ok = [float(r["factor"]) for r in levels if float(r["contact_loss_events"]) == 0]
    assert f"**The level without contact loss is {max(ok):.3g} × the calibrated scale**" in (quick / "report.md").read_text()


def test_every_conclusion_gets_a_verdict_with_evidence(quick):
    rows = _rows(quick / "verdicts.csv")
    assert [r["conclusion"] for r in rows] == list(study.CONCLUSIONS)
    for r in rows:
        assert r["verdict"] in ("holds", "does not hold", "holds under stated conditions", "holds on the article's model and sample only",
                                "holds between the article's two models only")
        assert any(ch.isdigit() for ch in r["evidence"])
    text = (quick / "report.md").read_text()
    for c in study.CONCLUSIONS:
        assert c in text


def test_a_held_out_row_is_the_run_it_names(quick):
    """Recomputed independently: one held-out case of the robust optimum as single runs."""
    row = next(r for r in _rows(quick / "held_out.csv") if r["design"] == "robust optimum")
    design = next(r for r in _rows(quick / "robust_design_table.csv") if r["design"] == "all speeds")
    levels = _rows(quick / "levels.csv")
    factor = max(float(r["factor"]) for r in levels if float(r["contact_loss_events"]) == 0)
    cfg = study._converged(study.PLANS["quick"], factor)
    cfg.speed, cfg.irregularity.seed = float(row["speed"]), int(row["seed"])
    unc = cfg.copy()
    unc.tids = None
    cfg.tids.inertance, cfg.tids.stiffness, cfg.tids.damping = (float(design[k]) for k in ("b_t", "k_t", "c_t"))
    m0, m1 = vtb.simulate(unc).metrics(), vtb.simulate(cfg).metrics()
    assert float(row["rail_acc_max_0"]) == pytest.approx(m0["rail_acc_max"], rel=1e-12)
    assert float(row["rail_acc_max"]) == pytest.approx(m1["rail_acc_max"], rel=1e-12)
    assert float(row["eta_slab_acc_max"]) == pytest.approx(1 - m1["slab_acc_max"] / m0["slab_acc_max"], rel=1e-9)


def test_the_article_chain_summary_matches_its_report(quick):
    s = json.loads((quick / "article" / "summary.json").read_text())
    assert f"a_rm cut {100 * s['sweep_best']['eta_rail_acc_max']:.2f} %" in (quick / "report.md").read_text()
    assert np.isfinite(s["pinned_pinned_frequency"]) and len(s["table_3_3"]) == 4


def test_the_study_refuses_to_overwrite_a_report(quick, capsys):
    assert cli.main(["study", "robust", "--out", str(quick), "--quick", "--no-progress"]) == 2
    assert "--force" in capsys.readouterr().err


def test_a_resumed_level_search_runs_nothing(quick, monkeypatch):
    def no_runs(*args, **kwargs):
        raise AssertionError("a resumed level search ran the model")

    monkeypatch.setattr(scaleout, "simulate_batch", no_runs)
    factor, rows = study.no_loss_level(study.PLANS["quick"], False, quick / "levels.json")
    saved = _rows(quick / "levels.csv")
    assert [float(r["rail_acc_max"]) for r in saved] == pytest.approx([r["rail_acc_max"] for r in rows], rel=1e-12)
    ok = [float(r["factor"]) for r in saved if float(r["contact_loss_events"]) == 0 and float(r["factor"]) > 0]
    assert factor == (max(ok) if ok else min(study.LEVEL_FACTORS))
