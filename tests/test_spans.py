"""Spans as data (vtb.spans): the layout it builds, the first deck mode against the closed
form of a span, and bad input."""

import math

import numpy as np
import pytest

import vtb


def test_spans_lay_out_piers_fasteners_and_the_observation_point():
    cfg = vtb.paper_config()
    assert cfg.output.points == [80.0]
    assert vtb.spans(cfg, [32.0] * 5).output.points == [80.0]  # the user's points stay
    cfg.output.points = []
    out = vtb.spans(cfg, [24.0, 32.0, 40.0, 32.0], pier_stiffness=[1e15, 2e9, 3e9, 2e9, 1e15], pier_damping=1e5)
    assert out.structure.length == 128.0 and cfg.structure.length == 160.0  # a copy
    piers = {c.stiffness: c.positions for c in out.structure.couplings if c.lower == "ground"}
    assert piers == {1e15: [0.0, 128.0], 2e9: [24.0, 96.0], 3e9: [56.0]}
    assert all(c.damping == 1e5 for c in out.structure.couplings if c.lower == "ground")
    pads = out.structure.couplings[0].positions
    assert pads[0] == 0.0 and np.allclose(np.diff(pads), 0.64) and pads[-1] <= 128.0 < pads[-1] + 0.64
    assert out.output.points == [56.0 + 20.0]  # the middle of the longer middle span
    assert out.structure.layers[0].modes == round(120 * 128 / 160)
    out.validate()


def test_equal_continuous_spans_have_the_span_frequency_first():
    """On rigid piers the first mode of a continuous beam of equal spans is that of one simply
    supported span, f₁ = (π/2ℓ²)·√(EI/m), with the track's mass carried along."""
    cfg = vtb.paper_config()
    cfg.discretisation.method = "fem"
    out = vtb.spans(cfg, [40.0, 40.0, 40.0])
    b = out.structure.layers[-1]
    mass = sum(l.density * l.area for l in out.structure.layers)
    f1 = math.pi / (2 * 40.0**2) * math.sqrt(b.youngs_modulus * b.inertia / mass)
    assert vtb.modes(out, 1.2 * f1).frequencies[0] == pytest.approx(f1, rel=0.01)
    soft = vtb.spans(cfg, [40.0, 40.0, 40.0], pier_stiffness=[1e15, 5e8, 5e8, 1e15])
    assert vtb.modes(soft, 1.2 * f1).frequencies[0] < 0.99 * f1  # soft piers lower it


@pytest.mark.parametrize("kwargs, field", [
    (dict(lengths=[]), "lengths"),
    (dict(lengths=[32.0, -1.0]), "lengths[1]"),
    (dict(lengths=[32.0, float("nan")]), "lengths[1]"),
    (dict(lengths=32.0), "lengths"),
    (dict(lengths=[32.0, 32.0], pier_stiffness=[1e15, 1e15]), "pier_stiffness"),
    (dict(lengths=[32.0], pier_stiffness=[1e15, 0.0]), "pier_stiffness[1]"),
    (dict(lengths=[32.0], pier_stiffness=-1.0), "pier_stiffness"),
    (dict(lengths=[32.0], pier_damping=[0.0, -1.0]), "pier_damping[1]"),
])
def test_bad_spans_name_the_argument(kwargs, field):
    with pytest.raises(vtb.ConfigError) as e:
        vtb.spans(vtb.paper_config(), **kwargs)
    assert e.value.field == field
