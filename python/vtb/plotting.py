"""Figures (matplotlib is an optional extra: ``pip install 'vtb[plot]'``)."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def plot_histories(result, path, layers=("rail", "slab")) -> None:
    """Displacement and acceleration histories of the given layers at the first observation
    point (the article's Fig. 3 layout), plus the car body, written to ``path``."""
    names = [n for n in layers if n in result.layer_names]
    fig, axes = plt.subplots(len(names) + 1, 2, figsize=(11, 2.6 * (len(names) + 1)), sharex=True, constrained_layout=True)
    x = result.points[0]
    for row, name in enumerate(names):
        axes[row, 0].plot(result.t, result.displacement(name) * 1e3, lw=0.6)
        axes[row, 0].set_ylabel(f"{name} disp. (mm)")
        axes[row, 1].plot(result.t, result.acceleration(name), lw=0.4)
        axes[row, 1].set_ylabel(f"{name} acc. (m/s²)")
    if result.vehicle_disp.shape[1]:
        axes[-1, 0].plot(result.t, result.car_body_disp * 1e3, lw=0.8)
        axes[-1, 1].plot(result.t, result.car_body_acc, lw=0.6)
    axes[-1, 0].set_ylabel("car body disp. (mm)")
    axes[-1, 1].set_ylabel("car body acc. (m/s²)")
    for ax in axes[-1]:
        ax.set_xlabel("t (s)")
    fig.suptitle(f"observation point x = {x:g} m (displacement positive down)")
    fig.savefig(path, dpi=130)
    plt.close(fig)
