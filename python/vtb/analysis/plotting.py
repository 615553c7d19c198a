"""Figures (matplotlib is an optional extra: ``pip install 'vtb[plot]'``).

Every figure of the package is built here, at the size a journal prints it: one column,
:data:`COLUMN_MM` wide, in the type sizes of :data:`STYLE` (panels stack rather than sit side
by side). Each function builds a :class:`matplotlib.figure.Figure` directly (no pyplot state),
so importing this module never changes the user's backend; each returns the figure and, given
``path``, also writes it (the format from the suffix: ``.png``, ``.pdf``, ``.svg``). Axes carry
units; reference lines carry legend entries; traces drawn over each other differ in line style
as well as colour, the reference (first) trace drawn on top in black, the others beneath it;
log axes label their ticks in plain numbers; band levels shade the bands the model does not
resolve (:func:`vtb.resolved_band`).
"""

from __future__ import annotations

import functools
import warnings
from typing import Optional, Sequence

import numpy as np
from matplotlib.figure import Figure

from ..config.resolution import resolved_band
from ..errors import config_error
from ..run.indices import A_RM, A_RRMS, A_RST, A_SM, rate

#: Width of a journal's single column (mm), the width of every figure.
COLUMN_MM = 85.0
#: Type and line sizes for print at that width (matplotlib rcParams).
STYLE = {
    "font.size": 7.0,
    "axes.titlesize": 7.0,
    "axes.labelsize": 7.0,
    "xtick.labelsize": 6.5,
    "ytick.labelsize": 6.5,
    "legend.fontsize": 6.0,
    "figure.titlesize": 7.5,
    "lines.linewidth": 0.9,
    "lines.markersize": 3.5,
    "axes.linewidth": 0.5,
    "grid.linewidth": 0.4,
    "xtick.major.width": 0.5,
    "ytick.major.width": 0.5,
    "xtick.minor.width": 0.4,
    "ytick.minor.width": 0.4,
    "legend.handlelength": 2.6,
    "legend.borderaxespad": 0.3,
    "savefig.dpi": 300,
    # Plain tick labels: an offset ("+1.229" above ticks of 0.00054) hides the values read.
    "axes.formatter.useoffset": False,
}
#: Line styles of the traces after the first, so overlapping traces stay distinguishable in print.
STYLES = ("-", "--", "-.", ":")


def styled(fn):
    """Draws ``fn``'s figure in :data:`STYLE` (the settings apply while its artists are made)."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        import matplotlib

        with matplotlib.rc_context(STYLE):
            return fn(*args, **kwargs)

    return wrapper


def figure(height_mm: float) -> Figure:
    """An empty figure one column wide and ``height_mm`` high."""
    return Figure(figsize=(COLUMN_MM / 25.4, height_mm / 25.4), layout="constrained")


def power_of_ten(x: float) -> str:
    """``x`` (a power of ten) as mathtext, e.g. 1e-06 → $10^{-6}$."""
    return f"$10^{{{int(round(np.log10(x)))}}}$"


def plain_log_ticks(ax, axis: str = "both") -> None:
    """Clean tick labels on a log axis: plain numbers at 1, 2, 5 × 10ⁿ (100, 200, 500) where the
    values are ordinary (1e-3 to 1e5), else decades only (10⁻⁹); never 3×10² on a minor tick."""
    from matplotlib.ticker import FuncFormatter, LogFormatterSciNotation, LogLocator, NullFormatter

    for name in ("x", "y") if axis == "both" else (axis,):
        a = getattr(ax, f"{name}axis")
        if a.get_scale() != "log":
            continue
        lo, hi = sorted(a.get_view_interval())
        if 1e-3 <= lo and hi <= 1e5:
            a.set_major_locator(LogLocator(base=10.0, subs=(1.0, 2.0, 5.0)))
            a.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        else:
            a.set_major_locator(LogLocator(base=10.0))
            a.set_major_formatter(LogFormatterSciNotation())
        a.set_minor_formatter(NullFormatter())


def _trace_style(i: int) -> dict:
    """The i-th trace: the first thin, solid and black on top; the others wider, coloured and
    in their own line styles beneath it, so that each shows where they coincide."""
    if i == 0:
        return dict(color="k", linestyle="-", linewidth=0.7, zorder=3)
    return dict(color=f"C{i - 1}", linestyle=STYLES[i % len(STYLES)], linewidth=1.5, alpha=0.85, zorder=2)


def legend_above(fig: Figure, ax) -> None:
    """The legend of ``ax``'s labelled artists above the figure's panels, clear of the data."""
    handles, labels = ax.get_legend_handles_labels()
    if not handles:
        return
    # As many columns as fit the width: about 1.25 mm per character at 6 pt, 9 mm per handle.
    widest = sorted((len(lab) for lab in labels), reverse=True)
    ncols = max(n for n in range(1, min(len(labels), 3) + 1) if 1.25 * sum(widest[:n]) + 9.0 * n <= COLUMN_MM - 5.0)
    fig.legend(handles, labels, loc="outside upper center", ncols=ncols, frameon=False)


def _finish(fig: Figure, path) -> Figure:
    if path is not None:
        fig.savefig(path)
    return fig


def _known_band(resolved, series) -> Optional[float]:
    """The top of the resolved band to shade above: ``resolved`` (Hz or None), or for
    ``"auto"`` the lowest ``resolved`` the series carry (:class:`vtb.analysis.track.Spectrum`)."""
    if isinstance(resolved, str) and resolved == "auto":
        known = [s.resolved for s in series if getattr(s, "resolved", None) is not None]
        return min(known) if known else None
    if resolved is not None and (isinstance(resolved, bool) or not isinstance(resolved, (int, float)) or not resolved > 0):
        raise config_error("resolved", resolved, 'must be "auto", a frequency > 0 (Hz) or None')
    return resolved


def shade_unresolved(ax, f_max: float, label: bool = True) -> None:
    """Greys the frequencies above ``f_max`` (Hz), the top of the band a model resolves."""
    lo, hi = ax.get_xlim()
    if f_max < hi:
        ax.axvspan(max(f_max, lo), hi, color="0.88", zorder=0, lw=0, label=f"not resolved (> {f_max:.0f} Hz)" if label else None)
        ax.set_xlim(lo, hi)


@styled
def plot_histories(result, path=None, layers=("rail", "slab")) -> Figure:
    """Displacement and acceleration histories of the given layers at the first observation
    point (the article's Fig. 3 layout, stacked), plus the car body."""
    names = [n for n in layers if n in result.layer_names]
    rows = 2 * len(names) + 2
    fig = figure(24.0 * rows)
    axes = fig.subplots(rows, 1, sharex=True)
    k = 0
    # Each panel names its part inside the axes and keeps its y-label short (symbol and unit),
    # so that the labels of 24 mm high panels do not run into each other.
    for name in names:
        axes[k].plot(result.t, result.displacement(name) * 1e3, color="k", lw=0.6)
        _panel(axes[k], name, "$w$ (mm)")
        axes[k + 1].plot(result.t, result.acceleration(name), color="k", lw=0.4)
        _panel(axes[k + 1], name, "$\\ddot w$ (m/s²)")
        k += 2
    if result.vehicle_disp.shape[1]:
        axes[k].plot(result.t, result.car_body_disp * 1e3, color="k", lw=0.7)
        axes[k + 1].plot(result.t, result.car_body_acc, color="k", lw=0.6)
    _panel(axes[k], "car body", "$Z_c$ (mm)")
    _panel(axes[k + 1], "car body", "$\\ddot Z_c$ (m/s²)")
    fig.align_ylabels(axes)
    for ax in axes:
        ax.grid(True, alpha=0.3)
    axes[-1].set_xlabel("time $t$ (s)")
    fig.suptitle(f"x = {result.points[0]:g} m (displacement positive down)")
    return _finish(fig, path)


def _panel(ax, part: str, label: str) -> None:
    """A stacked panel: ``part`` written in its top-left corner, ``label`` its y-label."""
    ax.set_ylabel(label)
    ax.text(0.01, 0.95, part, transform=ax.transAxes, ha="left", va="top", fontsize=6.0,
            bbox=dict(facecolor="white", edgecolor="none", pad=0.5, alpha=0.8))


def _resolved(result, layer: str) -> Optional[float]:
    """The top of the band ``result``'s model resolves for ``layer`` (Hz), if it can tell."""
    config = getattr(result, "config", None)
    if config is None:
        return None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        band = resolved_band(config).layers.get(layer)
    return None if band is None else band.f_max


@styled
def plot_third_octave(results: Sequence, labels: Sequence[str], layers: Sequence[str] = ("rail",), quantity: str = "acc", path=None,
                      window: Optional[tuple] = None) -> Figure:
    """One-third-octave band levels (IEC 61260-1, :meth:`vtb.Result.third_octave`) of each of
    ``layers`` for several runs (e.g. uncontrolled vs a damper) as stepped lines over the band
    edges, one panel per layer; the bands above the first run's resolved band are shaded."""
    if isinstance(layers, str):
        layers = (layers,)
    fig = figure(48.0 * len(layers) + 8.0)
    axes = np.atleast_1d(fig.subplots(len(layers), 1, sharex=True))
    unit = "m/s²" if quantity == "acc" else "m"
    for ax, layer in zip(axes, layers):
        ref = None
        for i, (res, label) in enumerate(zip(results, labels)):
            b = res.third_octave(layer, quantity=quantity, window=window)
            ref = b["reference"]
            edges = np.append(b["lower"], b["upper"][-1])
            ax.stairs(b["level"], edges, label=label, baseline=None, **_trace_style(i))
        ax.set_xscale("log")
        ax.set_xlim(edges[0], edges[-1])
        f_max = _resolved(results[0], layer)
        if f_max is not None:
            shade_unresolved(ax, f_max, label=ax is axes[0])
        plain_log_ticks(ax, "x")
        ax.set_ylabel(f"{layer} $L_{{{'a' if quantity == 'acc' else 'd'}}}$ (dB re {power_of_ten(ref)} {unit})")
        ax.grid(True, which="major", alpha=0.3)
    axes[-1].set_xlabel("one-third-octave band (Hz)")
    legend_above(fig, axes[0])
    return _finish(fig, path)


@styled
def plot_receptance(frequencies, receptances: Sequence, labels: Sequence[str], path=None, pinned_pinned: Optional[float] = None,
                    resolved="auto") -> Figure:
    """Magnitude and phase of point or transfer receptances (m/N, :func:`vtb.analysis.track.receptance`)
    against frequency (Hz); ``pinned_pinned`` marks the first pinned–pinned frequency (Hz).
    The frequencies above the band the model resolves are shaded: ``resolved`` = ``"auto"``
    (default) takes it from the receptances :func:`vtb.receptance` returned (the lowest of
    theirs), a number (Hz) gives it, ``None`` shades nothing."""
    resolved = _known_band(resolved, receptances)
    fig = figure(80.0)
    mag, ph = fig.subplots(2, 1, sharex=True, height_ratios=(2, 1))
    f = np.asarray(frequencies)
    for i, (a, label) in enumerate(zip(receptances, labels)):
        a = np.asarray(a)
        mag.loglog(f, np.abs(a), label=label, **_trace_style(i))
        ph.semilogx(f, np.degrees(np.angle(a)), **_trace_style(i))
    if pinned_pinned is not None:
        for ax in (mag, ph):
            ax.axvline(pinned_pinned, color="0.3", lw=0.7, ls=":", label="pinned–pinned $f_{pp}$" if ax is mag else None)
    if resolved is not None:
        for ax in (mag, ph):
            shade_unresolved(ax, resolved, label=ax is mag)
    mag.set_ylabel("receptance $|\\alpha|$ (m/N)")
    ph.set_ylabel("phase (°)")
    ph.set_yticks([-180, -90, 0, 90, 180])
    ph.set_xlabel("frequency $f$ (Hz)")
    for ax in (mag, ph):
        ax.grid(True, which="major", alpha=0.3)
    plain_log_ticks(mag, "y")
    plain_log_ticks(ph, "x")
    legend_above(fig, mag)
    return _finish(fig, path)


@styled
def plot_decay_rate(frequencies, decay_rates: Sequence, labels: Sequence[str], path=None, resolved="auto") -> Figure:
    """Track decay rates (dB/m, :func:`vtb.analysis.track.decay_rate`) against frequency (Hz);
    the frequencies above the model's resolved band are shaded (``resolved`` as in
    :func:`plot_receptance`: ``"auto"`` from the decay rates :func:`vtb.decay_rate` returned)."""
    resolved = _known_band(resolved, decay_rates)
    fig = figure(55.0)
    ax = fig.subplots()
    for i, (dr, label) in enumerate(zip(decay_rates, labels)):
        ax.loglog(frequencies, dr, label=label, **_trace_style(i))
    if resolved is not None:
        shade_unresolved(ax, resolved)
    ax.set_xlabel("frequency $f$ (Hz)")
    ax.set_ylabel("decay rate $\\Delta$ (dB/m)")
    ax.grid(True, which="major", alpha=0.3)
    plain_log_ticks(ax)
    legend_above(fig, ax)
    return _finish(fig, path)


#: Symbols of the series :func:`plot_comparison` draws: (quantity, scale to the plotted unit,
#: axis label).
_SERIES = {
    "disp": (1e3, "$w$ (mm)"),
    "acc": (1.0, "$\\ddot w$ (m/s²)"),
}


def _series(result, layer: str, quantity: str) -> np.ndarray:
    if layer == "car body":
        return result.car_body_disp if quantity == "disp" else result.car_body_acc
    return result.displacement(layer) if quantity == "disp" else result.acceleration(layer)


@styled
def plot_comparison(results: Sequence, labels: Sequence[str], path=None, layers=("rail", "slab"), zoom: float = 0.01) -> Figure:
    """Displacement and acceleration histories of several runs on common axes (e.g. two
    discretisations, or uncontrolled vs a damper), stacked: per layer (``"car body"`` for the
    first car body) its displacement, its acceleration and, below them, the acceleration
    ±``zoom`` s around the first run's peak (0: none). The first run is drawn on top in black,
    the others beneath it in colour and their own line styles."""
    per_layer = 3 if zoom > 0 else 2
    fig = figure(30.0 * per_layer * len(layers) + 8.0)
    axes = fig.subplots(per_layer * len(layers), 1)
    t = results[0].t
    for row, layer in enumerate(layers):
        base = per_layer * row
        axes[base].sharex(axes[base + 1])
        axes[base].tick_params(labelbottom=False)
        who = "car" if layer == "car body" else layer
        for col, quantity in enumerate(("disp", "acc")):
            ax = axes[base + col]
            scale, label = _SERIES[quantity]
            if layer == "car body":
                label = "$Z_c$ (mm)" if quantity == "disp" else "$\\ddot Z_c$ (m/s²)"
            traces = [_series(r, layer, quantity) * scale for r in results]
            for i, (y, lab) in enumerate(zip(traces, labels)):
                ax.plot(t, y, label=lab, **_trace_style(i))
            ax.set_ylabel(f"{who} {label}")
            ax.grid(True, alpha=0.3)
            if quantity == "acc":
                ax.set_xlabel("time $t$ (s)")
            if quantity == "acc" and zoom > 0:
                i = int(np.argmax(np.abs(traces[0])))
                keep = (t >= t[i] - zoom) & (t <= t[i] + zoom)
                z = axes[base + 2]
                for j, y in enumerate(traces):
                    z.plot(t[keep], y[keep], **_trace_style(j))
                ax.axvspan(t[keep][0], t[keep][-1], color="0.85", zorder=0, lw=0)
                z.set_xlim(t[keep][0], t[keep][-1])
                z.set_ylabel(f"{who} {label}")
                z.set_xlabel(f"time $t$ (s), ±{zoom:g} s around the peak (shaded above)")
                z.grid(True, alpha=0.3)
    legend_above(fig, axes[0])
    return _finish(fig, path)


@styled
def plot_rail_indices(table: dict, baseline: dict, path=None) -> Figure:
    """The article's Fig. 5: the rail indices a_rm, a_rRMS, a_rst at the a_rm-optimal (k_t, c_t)
    of each inertance (``table``: :meth:`vtb.SweepResult.best_per_inertance`), against the
    uncontrolled ``baseline``."""
    fig = figure(110.0)
    axes = fig.subplots(3, 1, sharex=True)
    for i, (ax, key, sym, unit) in enumerate(zip(axes, (A_RM, A_RRMS, A_RST),
                                                 ("a_{rm}", "a_{r\\mathrm{RMS}}", "a_{rst}"), ("m/s²", "m/s²", "s"))):
        ax.plot(table["b_t"], table[key], "o-", color="k", label="best case per $b_t$")
        ax.axhline(baseline[key], color="C0", ls="--", lw=0.8, label="uncontrolled")
        ax.set_ylabel(f"${sym}$ ({unit})")
        ax.grid(True, alpha=0.3)
    legend_above(fig, axes[0])
    axes[-1].set_xlabel("inertance $b_t$ (kg)")
    return _finish(fig, path)


@styled
def plot_slab_indices(table: dict, baseline: dict, path=None) -> Figure:
    """The article's Fig. 6: the slab amplitude at the rail optimum and its minimum per
    inertance, against the uncontrolled ``baseline``."""
    fig = figure(55.0)
    ax = fig.subplots()
    ax.plot(table["b_t"], table[A_SM], "o-", color="k", label="$a_{sm}$ at the rail optimum")
    ax.plot(table["b_t"], table["slab_acc_min"], "s--", color="C1", label="minimum $a_{sm}$ per $b_t$")
    ax.axhline(baseline[A_SM], color="C0", ls=":", lw=0.8, label="uncontrolled $a_{sm}^0$")
    ax.set_xlabel("inertance $b_t$ (kg)")
    ax.set_ylabel("slab amplitude $a_{sm}$ (m/s²)")
    ax.grid(True, alpha=0.3)
    legend_above(fig, ax)
    return _finish(fig, path)


@styled
def plot_hypervolume(histories, path=None) -> Figure:
    """The feasible front's hypervolume against the evaluations, one trace per optimisation
    run (``{label: [MogaGeneration, …]}``), or one style per label for several runs (``{label:
    [[MogaGeneration, …], …]}``, e.g. one per seed). A result :func:`vtb.optimize` returns
    (:class:`vtb.OptimizationResult`, :class:`vtb.ParetoResult`, :class:`vtb.optim.Result`), a
    list of them or a dict of them by label is taken as its history."""
    histories = _histories(histories)
    fig = figure(50.0)
    ax = fig.subplots()
    for i, (label, runs) in enumerate(histories.items()):
        several = bool(runs) and isinstance(runs[0], list)
        for j, h in enumerate(runs if several else [runs]):
            ax.plot([g.n_evals for g in h], [g.hypervolume for g in h], marker="." if i == 0 else "x", ms=3 if not several else 1.5,
                    label=label if j == 0 else None, **_trace_style(i))
    ax.set_xlabel("evaluations")
    ax.set_ylabel("hypervolume $H$ ((m/s²)²)")
    ax.grid(True, alpha=0.3)
    legend_above(fig, ax)
    return _finish(fig, path)


def _history(run) -> list:
    """The generations of one optimisation run (a result of :func:`vtb.optimize` or of
    :func:`vtb.optim.minimize`, or the list itself)."""
    moga = getattr(run, "moga", run)
    history = getattr(moga, "history", run)
    if not isinstance(history, list):
        raise config_error("histories", type(run).__name__, "expected an optimisation result or a list of its generations")
    return history


def _histories(histories) -> dict:
    if not isinstance(histories, dict):
        histories = {"optimisation": histories}
    out = {}
    for label, runs in histories.items():
        if isinstance(runs, list) and runs and not hasattr(runs[0], "n_evals"):
            out[label] = [_history(r) for r in runs]  # several runs
        else:
            out[label] = _history(runs)
    return out


@styled
def plot_pareto(population, pareto: Optional[dict] = None, baseline: Optional[dict] = None, reference: Optional[tuple] = None,
                path=None) -> Figure:
    """The article's Fig. 7: the final population and the Pareto set in (a_rm, a_sm), the
    uncontrolled values and the article's solution 1 (``reference``). ``population``: the
    final population's objectives (n × 2), or the :class:`vtb.OptimizationResult`
    :func:`vtb.optimize` returned — its population, Pareto set and baseline then come from it."""
    if hasattr(population, "moga") and hasattr(population, "pareto"):
        result = population
        population = result.moga.pop.F
        pareto = result.pareto if pareto is None else pareto
        baseline = getattr(result, "baseline", None) if baseline is None else baseline
    if pareto is None or baseline is None:
        raise config_error("pareto" if pareto is None else "baseline", None,
                           "needed unless the first argument is the OptimizationResult vtb.optimize returned")
    population = np.asarray(population, dtype=float)
    fig = figure(62.0)
    ax = fig.subplots()
    ax.scatter(population[:, 0], population[:, 1], s=5, c="0.7", lw=0, label="final population")
    ax.plot(pareto[A_RM], pareto[A_SM], "o", color="k", ms=3, label="Pareto set")
    if reference is not None:
        ax.plot([reference[0]], [reference[1]], "*", color="C3", ms=8, label="article, solution 1")
    ax.axvline(baseline[A_RM], color="C0", ls="--", lw=0.8, label="uncontrolled $a_{rm}^0$")
    ax.axhline(baseline[A_SM], color="C0", ls=":", lw=0.8, label="uncontrolled $a_{sm}^0$")
    ax.set_xlabel("rail amplitude $a_{rm}$ (m/s²)")
    ax.set_ylabel("slab amplitude $a_{sm}$ (m/s²)")
    ax.grid(True, alpha=0.3)
    legend_above(fig, ax)
    return _finish(fig, path)


@styled
def plot_baselines(baselines: dict, path=None) -> Figure:
    """The uncontrolled rail peak of every (speed, sample) case a robust design is judged on."""
    fig = figure(50.0)
    ax = fig.subplots()
    for (v, _), b in baselines.items():
        ax.plot(v, b[A_RM], "o", color="k", ms=3, alpha=0.7)
    ax.set_xlabel("speed $v$ (m/s)")
    ax.set_ylabel("uncontrolled $a_{rm}^0$ (m/s²)")
    ax.grid(True, alpha=0.3)
    return _finish(fig, path)


@styled
def plot_robust_designs(table: dict, chosen: dict, path=None) -> Figure:
    """Every evaluated design's mean ratios a_rm/a_rm0 and a_sm/a_sm0 over the cases with their
    standard errors, the ``chosen`` one marked."""
    fig = figure(62.0)
    ax = fig.subplots()
    ax.errorbar(table[f"mean_{A_RM}"], table[f"mean_{A_SM}"], xerr=table[f"sem_{A_RM}"], yerr=table[f"sem_{A_SM}"],
                fmt="o", ms=2.5, lw=0.6, color="0.55", label="evaluated designs (mean ± s.e.)")
    ax.plot([chosen[f"mean_{A_RM}"]], [chosen[f"mean_{A_SM}"]], "*", color="C3", ms=9, label="robust optimum (all speeds)")
    ax.axvline(1.0, color="k", ls="--", lw=0.8, label="uncontrolled")
    ax.axhline(1.0, color="k", ls=":", lw=0.8)
    ax.set_xlabel("$a_{rm}/a_{rm}^0$ over the cases (–)")
    ax.set_ylabel("$a_{sm}/a_{sm}^0$ over the cases (–)")
    ax.grid(True, alpha=0.3)
    legend_above(fig, ax)
    return _finish(fig, path)


@styled
def plot_held_out(series: dict, speeds: Sequence[float], path=None) -> Figure:
    """Reduction rates per speed on held-out samples, mean ± standard error: ``series`` is
    ``{design: {rate(A_RM): [(mean, sem) per speed], rate(A_SM): …}}``."""
    fig = figure(95.0)
    axes = fig.subplots(2, 1, sharex=True)
    v = np.asarray(speeds, float)
    for ax, key, sym in zip(axes, (rate(A_RM), rate(A_SM)), ("a_{rm}", "a_{sm}")):
        for j, (label, s) in enumerate(series.items()):
            ms = np.asarray(s[key], float)
            ax.errorbar(v + (j - 0.5) * 1.2, 100 * ms[:, 0], yerr=100 * ms[:, 1], marker="o" if j == 0 else "s", ms=3, capsize=2,
                        label=label, **_trace_style(j))
        ax.axhline(0.0, color="0.4", lw=0.6)
        ax.set_ylabel(f"reduction $\\eta_{{{sym}}}$ (%)")
        ax.grid(True, alpha=0.3)
    axes[-1].set_xlabel("speed $v$ (m/s)")
    legend_above(fig, axes[0])
    return _finish(fig, path)
