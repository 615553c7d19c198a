"""The convergence study script: runs, tables, errors and the CLI entry."""

import numpy as np
import pytest

from vtb import cli
from vtb.article.validation import (
    BAND_CENTRES,
    CONVERGED,
    DESIGN_CASES,
    REFERENCE,
    Case,
    _fem,
    _modal,
    band_mean_squares,
    default_cases,
    errors,
    run_study,
    write_report,
)


def test_band_mean_squares_of_a_sine_land_in_its_band_and_sum_to_its_mean_square():
    """A 1 kHz sine of amplitude 2 (whole number of periods): all its mean square, 2, lies in
    the 1 kHz band (Parseval)."""
    dt, n = 5e-5, 20000
    t = np.arange(n) * dt
    ms = band_mean_squares(2.0 * np.sin(2 * np.pi * 1000.0 * t), dt)
    k = int(np.argmin(np.abs(np.array(BAND_CENTRES) - 1000.0)))
    assert abs(ms[k] - 2.0) < 1e-9 and abs(ms.sum() - 2.0) < 1e-9


def test_study_writes_amplitudes_errors_and_times(tmp_path):
    cases = [Case("modal 120", _modal("modal")), Case("FEM 251", _fem(None, timoshenko=False, elements=251))]
    cases = run_study(cases, progress=False, designs=False, levels=("raw",))
    text = write_report(cases, tmp_path / "validation.md", command="pytest")
    assert (tmp_path / "validation.md").read_text() == text
    assert "| modal 120 |" in text and "Referee: **FEM 251**" in text and "`pytest`" in text
    modal, fem = cases
    assert modal.seconds[("raw", None)] > 0
    e = errors(modal.values[("raw", None)], fem.values[("raw", None)])
    # The error column is (case − reference)/reference of the printed amplitudes.
    exp = 100 * (modal.values[("raw", None)]["rail_disp"] / fem.values[("raw", None)]["rail_disp"] - 1)
    assert f"{exp:+.1f} %" in text and abs(e["rail_disp"] - exp) < 1e-12
    # Band-limiting can only lower a peak by the removed content; it stays positive.
    assert 0 < modal.values[("raw", None)]["rail_acc_lp"] and 0 < modal.values[("raw", None)]["slab_acc_lp"]


def test_default_study_covers_the_issue():
    labels = [c.label for c in default_cases()]
    for needed in ["article hybrid 120+100 (EB)", "modal 120 (EB)", "FEM 251 uniform (EB)", "FEM 502 uniform (EB)", CONVERGED, REFERENCE]:
        assert needed in labels
    assert all(d in labels for d in DESIGN_CASES)
    assert any("1.25e-5" in l and "converged" in l for l in labels) and any("no element flexibility" in l for l in labels)


def test_validate_command_has_help(capsys):
    with pytest.raises(SystemExit) as e:
        cli.main(["validate", "--help"])
    assert e.value.code == 0
    assert "--out" in capsys.readouterr().out
