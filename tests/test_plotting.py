"""Figures: importing vtb.plotting leaves the user's matplotlib backend alone; every figure
kind of the package renders one journal column wide (85 mm) with units on its axes, no text
overlapping other text or leaving the figure, traces told apart by line style, plain log tick
labels and the unresolved bands shaded; each writes vector and raster files."""

import itertools
import subprocess
import sys
from types import SimpleNamespace

import numpy as np
import pytest

import vtb
from fuzz_cases import small_config

pytest.importorskip("matplotlib")
from matplotlib.text import Text  # noqa: E402

from vtb.analysis import plotting  # noqa: E402


def test_importing_plotting_keeps_the_users_backend(tmp_path):
    code = (
        "import matplotlib; matplotlib.use('svg'); import vtb.analysis.plotting, vtb.reproduce, vtb.robust_study; "
        "import matplotlib.pyplot as plt; f = plt.figure(); f.savefig(r'" + str(tmp_path / "x.svg") + "'); "
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


def _texts(fig):
    """Every text a drawn figure shows, with its extent (pixels): the tick labels matplotlib
    draws (those within each axis' view) and every other visible, non-empty text."""
    r = fig.canvas.get_renderer()
    tick_labels, drawn = set(), []
    for ax in fig.axes:
        for axis in (ax.xaxis, ax.yaxis):
            for tick in axis.get_major_ticks() + axis.get_minor_ticks():
                tick_labels.update((id(tick.label1), id(tick.label2)))
            for tick in axis._update_ticks():  # the ticks the axis draws
                for label in (tick.label1, tick.label2):
                    if label.get_visible() and label.get_text().strip():
                        drawn.append(label)
    others = [t for t in fig.findobj(Text) if id(t) not in tick_labels and t.get_visible() and t.get_text().strip()]
    return [(t, t.get_window_extent(r)) for t in drawn + others]


def check_layout(fig, name):
    """85 mm wide, text within the figure and never over other text, a unit on every y label,
    clean tick labels on log axes."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    FigureCanvasAgg(fig)
    fig.canvas.draw()
    assert fig.get_figwidth() * 25.4 == pytest.approx(plotting.COLUMN_MM), name
    texts = _texts(fig)
    w, h = fig.canvas.get_width_height()
    for t, b in texts:
        assert b.x0 >= -1 and b.y0 >= -1 and b.x1 <= w + 1 and b.y1 <= h + 1, (name, t.get_text(), "leaves the figure")
    for (t1, b1), (t2, b2) in itertools.combinations(texts, 2):
        inter = b1.intersection(b1, b2)
        if inter is not None and inter.width > 1 and inter.height > 1:
            raise AssertionError(f"{name}: {t1.get_text()!r} overlaps {t2.get_text()!r}")
    for ax in fig.axes:
        if ax.has_data() and ax.get_ylabel():
            assert "(" in ax.get_ylabel(), (name, ax.get_ylabel())  # a unit in brackets
        for axis in (ax.xaxis, ax.yaxis):
            if axis.get_scale() == "log":
                labels = [t.label1.get_text() for t in axis._update_ticks() if t.label1.get_text()]
                # plain numbers, or decades alone (10⁻⁹): never a mantissa (3×10²)
                assert labels and not any("times" in s for s in labels), (name, labels)


def _sweep_table():
    b = np.arange(1.0, 11.0)
    return {"b_t": b, "rail_acc_max": 900 - 10 * b, "rail_acc_rms": 70 - b, "rail_acc_settle": 1.1 - 0.01 * b,
            "slab_acc_max": 30 + b, "slab_acc_min": 29 + 0.5 * b}


def _figures(runs):
    """Every figure kind of the package, built from small inputs."""
    f = np.geomspace(50, 5000, 60)
    alpha = 1e-9 / (1 - (f / 1000) ** 2 + 0.1j * f / 1000)
    base = dict(rail_acc_max=900.0, rail_acc_rms=70.0, rail_acc_settle=1.1, slab_acc_max=30.0)
    gens = [SimpleNamespace(n_evals=8 * (i + 1), hypervolume=100.0 * (1 - 0.5 ** i)) for i in range(6)]
    rng = np.random.default_rng(1)
    designs = {"mean_rail_acc_max": 0.9 + 0.05 * rng.random(12), "mean_slab_acc_max": 1.0 + 0.1 * rng.random(12),
               "sem_rail_acc_max": 0.01 * np.ones(12), "sem_slab_acc_max": 0.01 * np.ones(12)}
    return {
        "histories": plotting.plot_histories(runs[0]),
        "comparison": plotting.plot_comparison(runs, ["uncontrolled", "TIDs"], layers=("rail", "slab")),
        "comparison car body": plotting.plot_comparison(runs, ["uncontrolled", "TIDs"], layers=("car body",)),
        "third octave": plotting.plot_third_octave(runs, ["uncontrolled", "TIDs"], ("rail", "slab")),
        "receptance": plotting.plot_receptance(f, [alpha, 1.1 * alpha], ["a", "b"], pinned_pinned=1000.0, resolved=2000.0),
        "decay rate": plotting.plot_decay_rate(f, [6.0 * (f / 100) ** -0.3, 5.0 * (f / 100) ** -0.2], ["a", "b"], resolved=2000.0),
        "rail indices": plotting.plot_rail_indices(_sweep_table(), base),
        "slab indices": plotting.plot_slab_indices(_sweep_table(), base),
        "hypervolume": plotting.plot_hypervolume({"warm start": gens, "cold start": gens[::-1]}),
        "pareto": plotting.plot_pareto(np.c_[850 + 50 * rng.random(40), 30 + 5 * rng.random(40)],
                                       {"rail_acc_max": [840.0, 860.0], "slab_acc_max": [33.0, 31.0]}, base, (840.4, 41.5)),
        "baselines": plotting.plot_baselines({(v, s): {"rail_acc_max": 500 + 10 * s + v} for v in (60, 70, 80, 90) for s in range(4)}),
        "robust designs": plotting.plot_robust_designs(designs, {"mean_rail_acc_max": 0.91, "mean_slab_acc_max": 1.02}),
        "held out": plotting.plot_held_out({"single": {"eta_rail_acc_max": [(0.07, 0.02)] * 4, "eta_slab_acc_max": [(-0.1, 0.02)] * 4},
                                            "robust": {"eta_rail_acc_max": [(0.06, 0.02)] * 4, "eta_slab_acc_max": [(-0.05, 0.02)] * 4}},
                                           [60, 70, 80, 90]),
    }


def test_every_figure_kind_fits_a_journal_column(runs, tmp_path):
    for name, fig in _figures(runs).items():
        check_layout(fig, name)
        for suffix in ("png", "pdf"):
            fig.savefig(tmp_path / f"{name}.{suffix}")
            assert (tmp_path / f"{name}.{suffix}").stat().st_size > 1000


def test_overlaid_traces_differ_in_style_and_the_reference_is_on_top(runs):
    fig = plotting.plot_comparison(runs, ["uncontrolled", "TIDs"], layers=("rail",))
    ax = fig.axes[0]
    lines = [ln for ln in ax.get_lines() if ln.get_label() in ("uncontrolled", "TIDs")]
    assert {ln.get_linestyle() for ln in lines} == {"-", "--"}
    ref, other = lines
    assert ref.get_zorder() > other.get_zorder()  # the uncontrolled trace is not hidden


def test_the_zoom_panel_holds_the_first_runs_peak(runs):
    fig = plotting.plot_comparison(runs, ["uncontrolled", "TIDs"], layers=("rail",), zoom=0.01)
    zoom = fig.axes[2]
    t_peak = runs[0].t[np.argmax(np.abs(runs[0].acceleration("rail")))]
    lo, hi = zoom.get_xlim()
    assert lo <= t_peak <= hi and hi - lo <= 0.02 + 1e-12


def test_band_levels_shade_what_the_model_does_not_resolve():
    cfg = vtb.paper_config()  # the article's hybrid: the rail resolved to about 300 Hz
    cfg.solver.t_end = 0.6
    with pytest.warns(vtb.ResolutionWarning):
        fig = plotting.plot_third_octave([vtb.simulate(cfg)], ["article"], ("rail",))
    f_max = vtb.resolved_band(cfg).rail.f_max
    ax = fig.axes[0]
    spans = [p for p in ax.patches if p.get_label().startswith("not resolved")]
    assert len(spans) == 1
    assert spans[0].get_x() == pytest.approx(f_max) and ax.get_xlim()[0] < f_max


def test_reference_lines_have_legend_entries():
    f = np.geomspace(100, 3000, 20)
    fig = plotting.plot_receptance(f, [1e-9 * np.ones(20)], ["point"], pinned_pinned=1000.0)
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert "pinned–pinned $f_{pp}$" in labels


@pytest.fixture(scope="module")
def optimisation():
    """A real (tiny) article optimisation: what vtb.optimize returns."""
    return vtb.optimize(small_config(), pop_size=4, n_gen=2, seed=3, progress=False)


def test_every_plotting_function_takes_the_result_type_the_api_returns(runs, optimisation):
    import warnings

    cfg = small_config(tids=False)
    cfg.discretisation.method = "fem"
    cfg.discretisation.fem_elements = 80
    f = np.geomspace(50.0, 4000.0, 12)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", vtb.ResolutionWarning)
        alpha = vtb.receptance(cfg, 80.32, f)
        dr = vtb.decay_rate(cfg, f)
    assert isinstance(alpha, np.ndarray) and alpha.resolved is not None and dr.resolved == alpha.resolved
    assert isinstance(optimisation, vtb.OptimizationResult)
    figures = {
        "histories": plotting.plot_histories(runs[0]),
        "comparison": plotting.plot_comparison(list(runs), ["a", "b"]),
        "third octave": plotting.plot_third_octave(list(runs), ["a", "b"]),
        "receptance": plotting.plot_receptance(f, [alpha], ["point"]),
        "decay rate": plotting.plot_decay_rate(f, [dr], ["rail"]),
        "pareto": plotting.plot_pareto(optimisation),
        "hypervolume": plotting.plot_hypervolume(optimisation),
        "hypervolume by label": plotting.plot_hypervolume({"cold": optimisation, "again": [optimisation, optimisation]}),
    }
    for name, fig in figures.items():
        check_layout(fig, name)
    for name in ("receptance", "decay rate"):  # shaded by default: the model's band is known
        ax = figures[name].axes[0]
        spans = [p for p in ax.patches if p.get_label().startswith("not resolved")]
        assert len(spans) == 1 and spans[0].get_x() == pytest.approx(alpha.resolved), name
    assert len(plotting.plot_receptance(f, [alpha], ["point"], resolved=None).axes[0].patches) == 0
    with pytest.raises(vtb.ConfigError, match="baseline"):
        plotting.plot_pareto(optimisation.moga.pop.F, optimisation.pareto)


def test_no_axis_hides_its_values_behind_an_offset(runs):
    b = np.arange(1.0, 6.0)
    table = {"b_t": b, "rail_acc_max": 900 - b, "rail_acc_rms": 70 - b, "rail_acc_settle": 1.2290 + 0.00054 * b,
             "slab_acc_max": 30 + b, "slab_acc_min": 29 + b}
    base = dict(rail_acc_max=900.0, rail_acc_rms=70.0, rail_acc_settle=1.2293, slab_acc_max=30.0)
    for fig in (plotting.plot_rail_indices(table, base), plotting.plot_histories(runs[0])):
        fig.canvas.draw()
        for ax in fig.axes:
            assert ax.yaxis.get_major_formatter().get_offset() == "", ax.get_ylabel()
