"""Figures (matplotlib is an optional extra: ``pip install 'vtb[plot]'``).

Every function builds a :class:`matplotlib.figure.Figure` directly (no pyplot state), so
importing this module never changes the user's backend; each returns the figure and, given
``path``, also writes it (the format from the suffix: ``.png``, ``.pdf``, ``.svg``). Axes carry
units, reference lines carry legend entries, and traces drawn over each other differ in line
style as well as colour.
"""

from __future__ import annotations

from typing import Optional, Sequence

import numpy as np
from matplotlib.figure import Figure

#: Line styles cycled with the colours, so overlapping traces stay distinguishable in print.
STYLES = ("-", "--", "-.", ":")


def power_of_ten(x: float) -> str:
    """``x`` (a power of ten) as mathtext, e.g. 1e-06 → $10^{-6}$."""
    return f"$10^{{{int(round(np.log10(x)))}}}$"


def _finish(fig: Figure, path) -> Figure:
    if path is not None:
        fig.savefig(path, dpi=150)
    return fig


def plot_histories(result, path=None, layers=("rail", "slab")) -> Figure:
    """Displacement and acceleration histories of the given layers at the first observation
    point (the article's Fig. 3 layout), plus the car body."""
    names = [n for n in layers if n in result.layer_names]
    fig = Figure(figsize=(11, 2.6 * (len(names) + 1)), layout="constrained")
    axes = fig.subplots(len(names) + 1, 2, sharex=True)
    x = result.points[0]
    for row, name in enumerate(names):
        axes[row, 0].plot(result.t, result.displacement(name) * 1e3, lw=0.6)
        axes[row, 0].set_ylabel(f"{name} displacement $w$ (mm)")
        axes[row, 1].plot(result.t, result.acceleration(name), lw=0.4)
        axes[row, 1].set_ylabel(f"{name} acceleration $\\ddot w$ (m/s²)")
    if result.vehicle_disp.shape[1]:
        axes[-1, 0].plot(result.t, result.car_body_disp * 1e3, lw=0.8)
        axes[-1, 1].plot(result.t, result.car_body_acc, lw=0.6)
    axes[-1, 0].set_ylabel("car body $Z_c$ (mm)")
    axes[-1, 1].set_ylabel("car body $\\ddot Z_c$ (m/s²)")
    for ax in axes[-1]:
        ax.set_xlabel("time $t$ (s)")
    fig.suptitle(f"observation point x = {x:g} m (displacement positive down)")
    return _finish(fig, path)


def plot_third_octave(results: Sequence, labels: Sequence[str], layer: str = "rail", quantity: str = "acc", path=None, window: Optional[tuple] = None) -> Figure:
    """One-third-octave band levels (IEC 61260-1, :meth:`vtb.Result.third_octave`) of a layer
    for several runs, e.g. uncontrolled vs a damper, as stepped lines over the band edges."""
    fig = Figure(figsize=(7, 3.8), layout="constrained")
    ax = fig.subplots()
    ref = None
    for i, (res, label) in enumerate(zip(results, labels)):
        b = res.third_octave(layer, quantity=quantity, window=window)
        ref = b["reference"]
        edges = np.append(b["lower"], b["upper"][-1])
        ax.stairs(b["level"], edges, label=label, linestyle=STYLES[i % len(STYLES)], lw=1.3, baseline=None)
    ax.set_xscale("log")
    ax.set_xlabel("one-third-octave band (Hz)")
    unit = "m/s²" if quantity == "acc" else "m"
    ax.set_ylabel(f"{layer} {'acceleration' if quantity == 'acc' else 'displacement'} level (dB re {power_of_ten(ref)} {unit})")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    return _finish(fig, path)


def plot_receptance(frequencies, receptances: Sequence, labels: Sequence[str], path=None, pinned_pinned: Optional[float] = None) -> Figure:
    """Magnitude and phase of point or transfer receptances (m/N, :func:`vtb.track.receptance`)
    against frequency (Hz); ``pinned_pinned`` marks the first pinned–pinned frequency (Hz)."""
    fig = Figure(figsize=(7, 5), layout="constrained")
    mag, ph = fig.subplots(2, 1, sharex=True)
    f = np.asarray(frequencies)
    for i, (a, label) in enumerate(zip(receptances, labels)):
        a = np.asarray(a)
        mag.loglog(f, np.abs(a), STYLES[i % len(STYLES)], label=label, lw=1.2)
        ph.semilogx(f, np.degrees(np.angle(a)), STYLES[i % len(STYLES)], lw=1.0)
    if pinned_pinned is not None:
        for ax in (mag, ph):
            ax.axvline(pinned_pinned, color="k", lw=0.7, ls=":", label="pinned–pinned $f_{pp}$" if ax is mag else None)
    mag.set_ylabel("receptance $|\\alpha|$ (m/N)")
    ph.set_ylabel("phase (°)")
    ph.set_xlabel("frequency $f$ (Hz)")
    for ax in (mag, ph):
        ax.grid(True, which="both", alpha=0.3)
    mag.legend()
    return _finish(fig, path)


def plot_decay_rate(frequencies, decay_rates: Sequence, labels: Sequence[str], path=None) -> Figure:
    """Track decay rates (dB/m, :func:`vtb.track.decay_rate`) against frequency (Hz)."""
    fig = Figure(figsize=(7, 3.6), layout="constrained")
    ax = fig.subplots()
    for i, (dr, label) in enumerate(zip(decay_rates, labels)):
        ax.loglog(frequencies, dr, STYLES[i % len(STYLES)], label=label, lw=1.2)
    ax.set_xlabel("frequency $f$ (Hz)")
    ax.set_ylabel("decay rate $\\Delta$ (dB/m)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    return _finish(fig, path)


#: Symbols of the series :func:`plot_comparison` draws: (quantity, scale to the plotted unit,
#: axis label).
_SERIES = {
    "disp": (1e3, "displacement $w_\\mathrm{{{l}}}$ (mm)"),
    "acc": (1.0, "acceleration $\\ddot w_\\mathrm{{{l}}}$ (m/s²)"),
}


def _series(result, layer: str, quantity: str) -> np.ndarray:
    if layer == "car body":
        return result.car_body_disp if quantity == "disp" else result.car_body_acc
    return result.displacement(layer) if quantity == "disp" else result.acceleration(layer)


def _zoom(ax, t: np.ndarray, traces: Sequence[np.ndarray], styles, half_width: float) -> None:
    """An inset on the largest |value| of the first trace, ±``half_width`` s around it."""
    i = int(np.argmax(np.abs(traces[0])))
    keep = (t >= t[i] - half_width) & (t <= t[i] + half_width)
    if keep.sum() < 4:
        return
    inset = ax.inset_axes([0.62, 0.55, 0.36, 0.4])
    for y, (style, colour) in zip(traces, styles):
        inset.plot(t[keep], y[keep], style, color=colour, lw=0.9)
    inset.set_xlim(t[keep][0], t[keep][-1])
    inset.tick_params(labelsize=6)
    inset.set_title(f"zoom at $t$ = {t[i]:.3f} s", fontsize=7)
    ax.indicate_inset_zoom(inset, edgecolor="0.4")


def plot_comparison(results: Sequence, labels: Sequence[str], path=None, layers=("rail", "slab"), zoom: float = 0.01) -> Figure:
    """Displacement and acceleration histories of several runs on common axes (e.g. two
    discretisations, or uncontrolled vs a damper): one row per layer (``"car body"`` for the
    first car body), the traces in distinct line styles and colours, the later ones
    translucent, and on each acceleration panel an inset zooming ±``zoom`` s on the first
    run's peak (0: none)."""
    fig = Figure(figsize=(11, 2.7 * len(layers)), layout="constrained")
    axes = fig.subplots(len(layers), 2, sharex=True, squeeze=False)
    colours = [f"C{i}" for i in range(len(results))]
    styles = list(zip((STYLES[i % len(STYLES)] for i in range(len(results))), colours))
    t = results[0].t
    for row, layer in enumerate(layers):
        for col, quantity in enumerate(("disp", "acc")):
            ax = axes[row, col]
            scale, label = _SERIES[quantity]
            traces = [_series(r, layer, quantity) * scale for r in results]
            for i, (y, lab) in enumerate(zip(traces, labels)):
                ax.plot(t, y, styles[i][0], color=colours[i], lw=0.7 if i == 0 else 0.6, alpha=1.0 if i == 0 else 0.75, label=lab)
            if layer == "car body":
                label = "displacement $Z_c$ (mm)" if quantity == "disp" else "acceleration $\\ddot Z_c$ (m/s²)"
            ax.set_ylabel(f"{layer} {label.format(l=layer)}")
            ax.grid(True, alpha=0.3)
            if quantity == "acc" and zoom > 0:
                _zoom(ax, t, traces, styles, zoom)
    for ax in axes[-1]:
        ax.set_xlabel("time $t$ (s)")
    axes[0, 0].legend(loc="lower left", fontsize=8)
    return _finish(fig, path)
