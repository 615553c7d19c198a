"""The Python configuration classes against the core's schema, the one definition of the
configuration: the same fields, the same required ones, the same defaults, the same kinds of
value and the same choices. A field added, renamed or re-defaulted on one side only fails
here."""

import dataclasses
import re
import typing

import pytest

import vtb
from vtb.config import fields as C
from vtb.config.schema import SCHEMA, description, node, properties

#: Python class → the core struct it serialises to (the two Rayleigh forms are the variants
#: of one tagged enum).
PAIRS = [
    (C.Config, "Config"),
    (C.Structure, "StructureConfig"),
    (C.Layer, "LayerConfig"),
    (C.Coupling, "CouplingConfig"),
    (C.Discretisation, "DiscretisationConfig"),
    (C.Vehicle, "VehicleConfig.car"),
    (C.QuarterCar, "VehicleConfig.quarter_car"),
    (C.MovingForce, "MovingForceConfig"),
    (C.Solver, "SolverConfig"),
    (C.Output, "OutputConfig"),
    (C.DamperGroup, "DamperGroup"),
]
#: Fields that live on the Python side only (generated here, sent to the core as a profile).
PYTHON_ONLY = {("Config", "irregularity")}


def _required(struct):
    return set(node(struct).get("required", []))


def _resolve(prop):
    ref = prop.get("$ref") or next((a["$ref"] for a in prop.get("anyOf", []) if "$ref" in a), None)
    return SCHEMA["$defs"][ref.split("/")[-1]] if ref else prop


def _json_types(prop):
    node = _resolve(prop)
    if "enum" in node or "oneOf" in node and all("const" in v or "enum" in v for v in node["oneOf"]):
        return {"enum"}
    if "oneOf" in node:  # a tagged enum of tables
        return {"object"}
    t = node.get("type", prop.get("type"))
    types = set(t) if isinstance(t, list) else {t}
    if "anyOf" in prop:
        types |= {a.get("type") for a in prop["anyOf"]}
    return types - {None}


def _choices(prop):
    node = _resolve(prop)
    if "enum" in node:
        return set(node["enum"])
    return {c for v in node.get("oneOf", []) for c in ([v["const"]] if "const" in v else v.get("enum", []))}


def _python_kind(hint):
    """The JSON kinds a Python annotation allows."""
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if origin is typing.Union:
        kinds = set()
        for a in args:
            kinds |= {"null"} if a is type(None) else _python_kind(a)
        return kinds
    if origin is typing.Literal:
        return {"enum"}
    return {float: {"number"}, int: {"integer"}, bool: {"boolean"}, str: {"string"}, list: {"array"}}.get(hint, {"object"})


@pytest.mark.parametrize("cls, struct", PAIRS, ids=[p[1] for p in PAIRS])
def test_python_classes_have_the_cores_fields_defaults_and_types(cls, struct):
    props = properties(struct)
    fields = {f.name: f for f in dataclasses.fields(cls)}
    py_names = {n for n in fields if (struct, n) not in PYTHON_ONLY}
    assert py_names == set(props), f"{cls.__name__}: only Python {py_names - set(props)}, only core {set(props) - py_names}"
    has_default = {n for n, f in fields.items() if f.default is not dataclasses.MISSING or f.default_factory is not dataclasses.MISSING}
    assert py_names - has_default == _required(struct)
    hints = typing.get_type_hints(cls)
    for name in py_names:
        prop = props[name]
        if name in has_default and "default" in prop:
            f = fields[name]
            value = f.default if f.default is not dataclasses.MISSING else f.default_factory()
            plain = C.to_plain(value)
            assert plain == prop["default"], f"{struct}.{name}: Python {plain!r}, core {prop['default']!r}"
        want = _json_types(prop)
        got = _python_kind(hints[name])
        if "enum" in want:
            assert got == {"enum"}, f"{struct}.{name}"
            assert set(typing.get_args(hints[name])) == _choices(prop), f"{struct}.{name}"
        elif "object" in want or "array" in want:
            assert got & want, f"{struct}.{name}: Python {got}, core {want}"
        else:
            # an integer is a number to JSON; every other kind must match exactly
            assert got <= want | ({"number"} if "integer" in want else set()), f"{struct}.{name}: Python {got}, core {want}"
            assert want - {"null"} <= got | ({"integer"} if "number" in got else set()), f"{struct}.{name}: Python {got}, core {want}"


def test_rayleigh_forms_are_the_cores_variants():
    variants = {v["properties"]["kind"]["const"]: v for v in SCHEMA["$defs"]["RayleighConfig"]["oneOf"]}
    for kind, cls in (("ratio", C.RayleighRatio), ("coefficients", C.RayleighCoefficients)):
        assert {f.name for f in dataclasses.fields(cls)} | {"kind"} == set(variants[kind]["properties"])
        assert {f.name for f in dataclasses.fields(cls)} | {"kind"} == set(variants[kind]["required"])


def test_defaults_instances_serialise_to_the_cores_defaults():
    """The sub-tables a Config creates by default are the core's defaults as a whole."""
    cfg = vtb.paper_config()
    for name, cls in (("discretisation", C.Discretisation), ("solver", C.Solver), ("output", C.Output)):
        assert C.to_plain(cls()) == properties("Config")[name]["default"], name
    assert cfg.to_dict()["solver"].keys() == properties("SolverConfig").keys()


#: How a description names its unit: an SI unit (or a combination) in parentheses, or the
#: words for values without one.
UNIT_TOKEN = re.compile(r"\b(m|s|kg|N|Pa|Hz|rad|bytes|count)\b|m²|m³|m⁴|−")
NO_UNIT = re.compile(r"\bname\b|true/false|`\"|no unit")


def _parenthesised(text):
    return re.findall(r"\((?:[^()]|\([^()]*\))*\)", text)


def _is_table(prop):
    """A field holding a table (or a list of tables): documented by its own struct's fields."""
    node = prop.get("items", prop)
    ref = node.get("$ref") or next((a["$ref"] for a in node.get("anyOf", []) if "$ref" in a), None)
    target = SCHEMA["$defs"][ref.split("/")[-1]] if ref else {}
    return "properties" in target or "oneOf" in target and all("properties" in v for v in target["oneOf"])


@pytest.mark.parametrize("cls,struct", PAIRS, ids=[s for _, s in PAIRS])
def test_every_field_is_documented_with_its_unit_in_one_place(cls, struct):
    """The core's doc comment is the one description of a field; the Python class's
    docstring carries it (vtb.config.schema.documented)."""
    for name, prop in properties(struct).items():
        text = description(struct, name)
        assert text, f"{struct}.{name} has no doc comment"
        assert text in " ".join(cls.__doc__.split()), f"{cls.__name__} docstring lacks {name}"
        if not _is_table(prop):
            unit = any(UNIT_TOKEN.search(g) for g in _parenthesised(text)) or NO_UNIT.search(text)
            assert unit, f"{struct}.{name}: no unit in {text!r}"
