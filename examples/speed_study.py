"""Speed study: the article's car over the article's bridge at 60, 70, 80 and 90 m/s.

Runs the four speeds as one batch (the core groups and parallelises them) and prints the rail,
slab and car-body responses at mid-span with their units, and the car body's ride comfort.
It runs the article's own model, which the README's table trusts for rail and slab
displacements; its rail acceleration is the article's index, not converged in the rail's
0.3–2 kHz band (docs/resolution.md). For rail vibration use ``vtb.paper_config(model="fast")``,
with the rail refined below 80 m/s so that v/h stays above 2.5 kHz (docs/track-models.md).

    python examples/speed_study.py [--out DIR]     # DIR: also write fig_speed_study.png/.pdf
"""

import argparse
import warnings

import vtb
from vtb.analysis.comfort import ComfortWarning

SPEEDS = [60.0, 70.0, 80.0, 90.0]  # m/s


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", help="directory for the figure")
    args = parser.parse_args(argv)

    configs = []
    for v in SPEEDS:
        cfg = vtb.paper_config()  # Table 1 structure, CRH3 trailer, TB/T 3352 short-wave sample
        cfg.speed = v  # the end time follows the speed (the car crosses the whole bridge)
        configs.append(cfg)
    results = vtb.simulate_batch(configs, histories=True)

    keys = ["rail_acc_max", "slab_acc_max", "rail_disp_max", "car_acc_max"]
    print("speed (m/s) | " + " | ".join(f"{k} ({vtb.metric_unit(k)})" for k in keys) + " | car a_w (m/s²) | Sperling Wz")
    for v, res in zip(SPEEDS, results):
        m = res.metrics()
        with warnings.catch_warnings():
            # one 2 s passage is shorter than a comfort index wants (docs/spectra.md)
            warnings.simplefilter("ignore", ComfortWarning)
            c = res.comfort()
        print(f"{v:11.0f} | " + " | ".join(f"{m[k]:.4g}" for k in keys) + f" | {c['a_w']:.4f} | {c['wz']:.3f}")

    if args.out:
        from pathlib import Path

        import matplotlib

        from vtb.analysis import plotting

        # One journal column (85 mm) in the package's type sizes (vtb.plotting).
        with matplotlib.rc_context(plotting.STYLE):
            fig = plotting.figure(height_mm=55)
            ax = fig.subplots()
            ax.plot(SPEEDS, [r.metrics()["rail_acc_max"] for r in results], "o-", color="k", lw=0.8, label="rail $a_{rm}$")
            ax.plot(SPEEDS, [r.metrics()["slab_acc_max"] for r in results], "s--", color="C0", label="slab $a_{sm}$")
            ax.set_yscale("log")
            ax.set_xlabel("speed $v$ (m/s)")
            ax.set_ylabel("acceleration amplitude (m/s²)")
            ax.grid(True, which="both", alpha=0.3)
            plotting.plain_log_ticks(ax, "y")
            plotting.legend_above(fig, ax)
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        for suffix in ("png", "pdf"):
            fig.savefig(out / f"fig_speed_study.{suffix}", dpi=plotting.STYLE["savefig.dpi"])


if __name__ == "__main__":
    main()
