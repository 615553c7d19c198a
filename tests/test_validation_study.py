"""The validation study script (issue 3): runs, tables and the CLI entry."""

import pytest

from vtb import cli
from vtb.validation import Case, default_cases, run_study, write_report


def test_study_writes_amplitudes_errors_and_times(tmp_path):
    cases = run_study([Case("modal 120", "modal"), Case("FEM 251", "fem", fem_elements=251)], progress=False)
    text = write_report(cases, tmp_path / "validation.md")
    assert (tmp_path / "validation.md").read_text() == text
    assert "| modal 120 |" in text and "Errors against **FEM 251**" in text
    modal, fem = cases
    assert modal.seconds > 0 and fem.seconds > 0
    # The error column is (case − reference)/reference of the printed amplitudes.
    err = 100 * (modal.values["rail_disp"] - fem.values["rail_disp"]) / fem.values["rail_disp"]
    assert f"{err:+.1f} %" in text
    # Band-limiting can only lower a peak by the removed content; it stays positive.
    assert 0 < modal.values["car_acc_lp"] and 0 < modal.values["slab_acc_lp"]


def test_default_study_covers_the_issue():
    labels = [c.label for c in default_cases()]
    for needed in ["modal 120", "hybrid 120+100", "modal 220", "FEM 251", "FEM 502"]:
        assert needed in labels
    assert sum("ω_r" in l for l in labels) == 2 and any("2.5e-5" in l for l in labels)


def test_validate_command_has_help(capsys):
    with pytest.raises(SystemExit) as e:
        cli.main(["validate", "--help"])
    assert e.value.code == 0
    assert "--out" in capsys.readouterr().out
