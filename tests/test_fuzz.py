"""The bounded fuzz test: generated bad configurations, TOML texts and attribute assignments
(tests/fuzz_cases.py), and bad arguments of every newer surface (tests/fuzz_surfaces.py), get a documented exception naming the field, or a run whose every index
and history is finite. ``benches/fuzz_config.py`` runs the same generator for ≥ 10 000 cases
in worker processes, counting aborts and hangs too."""

import warnings

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import fuzz_cases


@settings(max_examples=250, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.randoms(use_true_random=False))
def test_generated_bad_input_gets_a_named_error_or_a_finite_run(rng):
    label, thunk = fuzz_cases.make_case(rng)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        verdict, detail = fuzz_cases.verdict(thunk)
    assert verdict == "ok", f"{label}: {verdict}: {detail}"


import fuzz_surfaces
import pytest


@pytest.mark.parametrize("surface", fuzz_surfaces.SURFACES[1:])
@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(rng=st.randoms(use_true_random=False))
def test_every_newer_surface_gets_a_named_vtb_error_or_a_finite_result(surface, rng):
    label, thunk, inputs = fuzz_surfaces.make_case(rng, surface)
    verdict, detail = fuzz_surfaces.verdict(label, thunk, inputs)
    assert verdict in ("ok", "refused"), f"{label}: {verdict}: {detail}"
