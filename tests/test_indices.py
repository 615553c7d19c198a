"""``output.indices``: a run reports the indices named, with the bits it gives when it reports
every index, on every engine; a batch then records only the layers they need; a name that is
not an index of the configuration is refused naming its place."""

import pytest

import vtb
from fuzz_cases import small_config


def _configs():
    hybrid = small_config(t_end=0.1, tids=True)
    fem = hybrid.copy()
    fem.discretisation.method = "fem"
    return {"hybrid": hybrid, "fem": fem}


@pytest.mark.parametrize("engine", ["hybrid", "fem"])
def test_named_indices_keep_their_bits(engine):
    cfg = _configs()[engine]
    full = vtb.simulate_batch([cfg])[0]
    some = cfg.copy()
    names = ["rail_acc_max", "slab_disp_max", "car_acc_rms", "contact_force_min"]
    some.output.indices = names
    got = vtb.simulate_batch([some])[0]
    assert sorted(got) == sorted(names)
    assert all(got[k] == full[k] for k in names)  # bit for bit
    assert vtb.simulate(some).metrics() == got  # a full record reports the same subset


def test_the_fast_model_reports_named_indices_with_their_bits():
    c = vtb.paper_config(model="fast")
    c.solver.t_end = 0.03
    full = vtb.simulate_batch([c])[0]
    c.output.indices = ["slab_acc_max", "rail_acc_rms"]
    got = vtb.simulate_batch([c])[0]
    assert got == {k: full[k] for k in c.output.indices}


def test_an_unknown_index_is_refused_naming_it():
    cfg = _configs()["hybrid"]
    cfg.output.indices = ["rail_acc_max", "deck_acc_rms"]
    with pytest.raises(vtb.ConfigError) as e:
        vtb.simulate(cfg)
    assert e.value.field == "output.indices[1]" and "deck_acc_rms" in str(e.value)


def test_the_docs_index_table_is_the_catalogue():
    """docs/indices.md's table is generated from the core's catalogue: every kind of index is
    documented, with the unit and band the core uses."""
    from pathlib import Path

    from vtb.run.indices import catalog_table

    page = (Path(__file__).resolve().parents[1] / "docs" / "indices.md").read_text()
    assert catalog_table() in page
