"""The example configurations shipped in the package (``vtb/examples/*.toml``): present in the
installed package, loadable, and the article examples equal to the presets they document."""

import math

import numpy as np
import pytest

import vtb
from vtb import cli

NAMES = ["article", "article_converged", "article_fast", "article_fem", "article_tids", "passage_fast", "passage_long", "two_span_sato"]


def _close(a, b):
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(_close(a[k], b[k]) for k in a)
    if isinstance(a, list):
        return len(a) == len(b) and all(_close(x, y) for x, y in zip(a, b))
    if isinstance(a, float):
        return math.isclose(a, b, rel_tol=1e-12, abs_tol=1e-12)
    return a == b


def test_examples_are_shipped_and_described():
    ex = vtb.examples()
    assert sorted(ex) == NAMES
    assert all(len(text) > 40 for text in ex.values())


@pytest.mark.parametrize("name", NAMES)
def test_every_example_builds_its_model(name):
    import scipy.sparse

    cfg = vtb.example_config(name)
    mats = vtb._core.matrices(cfg.to_core_json())
    for key in ("m", "k"):
        r, c, v = mats[key]
        a = scipy.sparse.coo_matrix((v, (r, c)), shape=(mats["n"],) * 2).tocsr()
        assert np.all(np.isfinite(a.data))
        assert abs(a - a.T).max() <= 1e-9 * abs(a).max()


def test_article_examples_are_the_documented_presets():
    paper = vtb.paper_config(calibrated=True)
    assert _close(vtb.example_config("article").to_dict(), paper.to_dict())
    paper.tids = vtb.tids_around(paper)
    assert _close(vtb.example_config("article_tids").to_dict(), paper.to_dict())
    fem = vtb.example_config("article_fem")
    assert fem.discretisation.method == "fem" and fem.discretisation.fem_elements == 251
    fem.discretisation = vtb.paper_config().discretisation
    paper.tids = None
    assert _close(fem.to_dict(), paper.to_dict())


def test_converged_example_is_the_converged_preset():
    conv = vtb.paper_config(model="converged", calibrated=True)
    assert _close(vtb.example_config("article_converged").to_dict(), conv.to_dict())
    rail = conv.structure.layers[0]
    assert conv.discretisation.method == "fem" and rail.shear_modulus > 0 and rail.shear_coefficient > 0
    # Same structure, car, speed and excitation as the article's preset; only the model differs.
    art = vtb.paper_config(calibrated=True)
    assert [v.contact_patch for v in conv.vehicles] == [True] and conv.output.band_limit == 2000.0
    for v in conv.vehicles:
        v.contact_patch = False
    assert conv.vehicles == art.vehicles and conv.speed == art.speed and conv.irregularity == art.irregularity
    assert [c.positions for c in conv.structure.couplings] == [c.positions for c in art.structure.couplings]


def test_the_fast_examples_are_the_fast_preset_and_a_passage_on_it():
    """The recommended model at both grades: the rail grade is the fast preset; the passage
    runs the same structure by synthesis at 300 Hz over three spans between embankments."""
    assert _close(vtb.example_config("article_fast").to_dict(), vtb.paper_config(model="fast", calibrated=True).to_dict())
    p = vtb.example_config("passage_fast")
    assert p.discretisation.synthesis_cutoff == 300.0 and p.solver.dt == 2e-4
    assert vtb.resolved_band(p).rail.f_max >= p.output.band_limit
    assert p.vehicles[0].x_front < 0 and p.structure.length == 156.0


def test_the_long_passage_runs_on_the_substructured_engine_at_the_deck_grade():
    p = vtb.example_config("passage_long")
    deck = vtb.paper_config(model="deck")
    assert p.discretisation.substructure_cutoff == deck.discretisation.substructure_cutoff and p.discretisation.synthesis_cutoff is None
    assert p.structure.length == 840.0 and len(p.vehicles) == 8 and p.solver.dt == deck.solver.dt
    assert vtb.resolved_band(p).rail.f_max >= p.output.band_limit


def test_unknown_example_names_the_field():
    with pytest.raises(vtb.ConfigError) as e:
        vtb.example_config("nope")
    assert e.value.field == "example" and "article" in str(e.value)


def test_cli_lists_prints_and_runs_examples(tmp_path, capsys):
    assert cli.main(["examples"]) == 0
    listed = capsys.readouterr().out
    assert all(name in listed for name in NAMES)
    assert cli.main(["examples", "two_span_sato"]) == 0
    text = capsys.readouterr().out
    assert _close(vtb.Config.from_toml_text(text).to_dict(), vtb.example_config("two_span_sato").to_dict())
    assert cli.main(["examples", "nope"]) == 2
    assert "example" in capsys.readouterr().err
    out = tmp_path / "run"
    assert cli.main(["simulate", "--config", "two_span_sato", "--out", str(out), "--no-plot"]) == 0
    metrics = capsys.readouterr().out
    assert "rail_acc_max" in metrics and (out / "result.npz").is_file()
