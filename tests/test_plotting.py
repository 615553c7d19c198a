"""Figures: importing vtb.plotting leaves the user's matplotlib backend alone, and every
figure function draws with labelled axes and writes vector and raster files."""

import subprocess
import sys

import numpy as np
import pytest

import vtb
from fuzz_cases import small_config

pytest.importorskip("matplotlib")


def test_importing_plotting_keeps_the_users_backend(tmp_path):
    code = (
        "import matplotlib; matplotlib.use('svg'); import vtb.plotting, vtb.reproduce; "
        "import vtb.reproduce as r; f = r._plt().figure(); f.savefig(r'" + str(tmp_path / "x.svg") + "'); "
        "print(matplotlib.get_backend())"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert out == "svg"


@pytest.fixture(scope="module")
def runs():
    cfg = small_config(t_end=0.2, tids=False)
    ctl = cfg.copy()
    ctl.tids = vtb.tids_around(ctl)
    return vtb.simulate(cfg), vtb.simulate(ctl)


def test_figures_have_units_and_write_pdf_svg_png(runs, tmp_path):
    from vtb import plotting

    figs = {
        "histories": plotting.plot_histories(runs[0]),
        "bands": plotting.plot_third_octave(runs, ["uncontrolled", "TIDs"], "rail"),
        "receptance": plotting.plot_receptance([100, 300, 1000], [np.array([1e-9, 2e-9j, -1e-9])], ["point"], pinned_pinned=1000.0),
        "decay": plotting.plot_decay_rate([100, 300, 1000], [np.array([5.0, 2.0, 1.0])], ["rail"]),
    }
    for name, fig in figs.items():
        for ax in fig.axes:
            if ax.has_data():
                assert "(" in ax.get_ylabel(), (name, ax.get_ylabel())  # a unit in brackets
        for suffix in ("png", "pdf", "svg"):
            fig.savefig(tmp_path / f"{name}.{suffix}")
            assert (tmp_path / f"{name}.{suffix}").stat().st_size > 1000
    labels = [t.get_text() for t in figs["receptance"].axes[0].get_legend().get_texts()]
    assert "pinned–pinned $f_{pp}$" in labels  # reference lines have legend entries


def test_comparison_figure_zooms_on_the_peak_and_labels_every_trace(runs, tmp_path):
    from vtb import plotting

    fig = plotting.plot_comparison(runs, ["uncontrolled", "TIDs"], path=tmp_path / "cmp.pdf", layers=("rail", "car body"))
    assert (tmp_path / "cmp.pdf").stat().st_size > 1000
    main = [ax for ax in fig.axes if ax.get_ylabel()]
    assert len(main) == 4 and all("(" in ax.get_ylabel() for ax in main)
    insets = [c for ax in main for c in ax.child_axes if c.get_title().startswith("zoom")]
    assert len(insets) == 2  # one per acceleration panel
    # the inset is centred on the first run's largest |acceleration|
    t_peak = runs[0].t[np.argmax(np.abs(runs[0].acceleration("rail")))]
    lo, hi = insets[0].get_xlim()
    assert lo <= t_peak <= hi
    # the two traces differ in line style, not only in colour
    styles = {line.get_linestyle() for line in main[0].get_lines()}
    assert len(styles) == 2
