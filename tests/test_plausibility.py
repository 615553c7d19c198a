"""Plausible ranges (docs/limits.md): every field of the core's table refuses a value outside
its range as a likely unit mistake, naming the field, unless the configuration accepts it."""

import re

import pytest

import vtb

ROWS = vtb.plausible_ranges()


def target(cfg, field):
    """(object, attribute, concrete path) of a table field in ``cfg`` (first matching index)."""
    base, _, qualifier = field.partition(" (")
    parts = base.split(".")
    obj, path = cfg, []
    for part in parts[:-1]:
        name, star = part.removesuffix("[*]"), part.endswith("[*]")
        obj = getattr(obj, name)
        if star:
            i = next(i for i, o in enumerate(obj) if not qualifier or getattr(o, "kind", None) == qualifier.rstrip(")"))
            obj, part = obj[i], f"{name}[{i}]"
        path.append(part)
    return obj, parts[-1], ".".join(path + [parts[-1]])


def config_for(field):
    c = vtb.paper_config()
    if field.startswith("tids."):
        c.tids = vtb.tids_around(c)
    if field.startswith("dampers["):
        c.dampers = [vtb.DamperGroup(kind="tvmd", inertance=5.0, stiffness=2e8, damping=1e3, positions=[40.0])]
    if field.startswith("forces["):
        c.forces = [vtb.MovingForce(70e3, 20.0)]
    return c


@pytest.mark.parametrize("row", ROWS, ids=[r["field"] for r in ROWS])
@pytest.mark.parametrize("side", ["above", "below"])
def test_a_value_outside_its_plausible_range_is_refused_unless_accepted(row, side):
    if side == "below" and row["min"] == 0:
        pytest.skip("no lower bound above zero")
    c = config_for(row["field"])
    obj, attr, path = target(c, row["field"])
    assert row["min"] <= getattr(obj, attr) <= row["max"], "the preset itself is plausible"
    setattr(obj, attr, row["max"] * 10 if side == "above" else row["min"] / 10)
    with pytest.raises(vtb.ConfigError) as e:
        vtb._core.check_plausible(c.to_core_json())
    assert e.value.field == path
    assert row["unit"] in str(e.value) and "accept_implausible" in str(e.value)
    c.accept_implausible = [path]
    vtb._core.check_plausible(c.to_core_json())


def test_the_likely_unit_mistakes_are_named():
    c = vtb.paper_config()
    c.speed = 300.0  # km/h
    with pytest.raises(vtb.ConfigError, match=r"km/h, that is 83\.3333 m/s") as e:
        vtb.simulate(c)
    assert e.value.field == "speed"
    c = vtb.paper_config()
    c.structure.couplings[0].stiffness = 6e4  # kN/m
    with pytest.raises(vtb.ConfigError, match=r"kN/m, that is 60000000"):
        vtb.simulate(c)
    c = vtb.paper_config()
    c.structure.layers[0].youngs_modulus = 210.0  # GPa
    with pytest.raises(vtb.ConfigError, match=r"GPa, that is 210000000000"):
        vtb.simulate(c)


def test_docs_list_the_cores_table():
    from pathlib import Path

    text = (Path(__file__).parents[1] / "docs" / "limits.md").read_text()
    for r in ROWS:
        assert re.search(rf"\| `{re.escape(r['field'])}` \| {re.escape(format(r['min'], 'g'))} \| {re.escape(format(r['max'], 'g'))} \| {re.escape(r['unit'])} \|", text), r["field"]


def test_a_misspelled_accept_implausible_entry_is_refused_by_name():
    c = vtb.paper_config()
    c.accept_implausible = ["speed", "speeed"]
    with pytest.raises(vtb.ConfigError, match=r"accept_implausible\[1\].*names no field"):
        vtb.simulate(c)


def test_damping_in_percent_and_dashpots_in_kn_are_named():
    c = vtb.paper_config()
    c.structure.layers[0].damping.ratio = 1.0  # 1 %
    with pytest.raises(vtb.ConfigError, match=r"structure\.layers\[0\]\.damping\.ratio.*in %, that is 0\.01"):
        vtb.simulate(c)
    c = vtb.paper_config()
    c.vehicles[0].c_s = 80.0  # kN·s/m
    with pytest.raises(vtb.ConfigError, match=r"vehicles\[0\]\.c_s.*kN·s/m, that is 80000"):
        vtb.simulate(c)
