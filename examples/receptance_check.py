"""Receptance check: the rail's point receptance above a fastener and at mid-bay, and its decay
rate, on the article's Euler–Bernoulli rail and on the converged Timoshenko rail; the
pinned–pinned peak of each against the closed form of an Euler–Bernoulli rail.

    python examples/receptance_check.py [--out DIR]   # DIR: also write the receptance and decay-rate figures
"""

import argparse
from pathlib import Path

import numpy as np

import vtb

FREQUENCIES = np.geomspace(100.0, 3000.0, 120)  # Hz


def _rail_points(cfg):
    fast = next(c for c in cfg.structure.couplings if c.upper == "rail" and c.kind == "discrete")
    pos = np.array(sorted(fast.positions))
    above = pos[np.argmin(np.abs(pos - cfg.structure.length / 2))]
    return above, above + 0.5 * (pos[1] - pos[0])


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", help="directory for the figures")
    args = parser.parse_args(argv)

    models = {"article (Euler–Bernoulli FEM)": vtb.paper_config(), "converged (Timoshenko)": vtb.paper_config(model="converged")}
    models["article (Euler–Bernoulli FEM)"].discretisation.method = "fem"  # receptance needs a nodal mesh or modes; FEM is the article's referee
    f_pp_eb = vtb.pinned_pinned_frequency(models["article (Euler–Bernoulli FEM)"])
    print(f"closed form, Euler–Bernoulli rail between fasteners: f_pp = {f_pp_eb:.0f} Hz")
    print(f"closed form, Timoshenko rail (shear and rotary inertia): f_pp,T = {vtb.pinned_pinned_frequency(models['converged (Timoshenko)']):.0f} Hz")
    curves, rates = {}, {}
    for name, cfg in models.items():
        above, mid = _rail_points(cfg)
        a_above = vtb.receptance(cfg, above, FREQUENCIES)
        a_mid = vtb.receptance(cfg, mid, FREQUENCIES)
        # pinned–pinned: the mid-bay receptance peaks where the rail between two fasteners
        # resonates with nodes on them, while above a fastener it dips
        band = FREQUENCIES > 500.0
        f_peak = FREQUENCIES[band][np.argmax(np.abs(a_mid[band]) / np.abs(a_above[band]))]
        print(f"{name}: mid-bay / above-fastener receptance ratio peaks at {f_peak:.0f} Hz "
              f"({f_peak / f_pp_eb:.2f} × the Euler–Bernoulli f_pp); |α| at 1 kHz mid-bay {abs(np.interp(1000.0, FREQUENCIES, np.abs(a_mid))):.3g} m/N")
        curves[name] = (a_above, a_mid)
        rates[name] = vtb.decay_rate(cfg, FREQUENCIES[::6], x0=mid)

    if args.out:
        from vtb.analysis import plotting

        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        labels = [f"{n}, {where}" for n in curves for where in ("above a fastener", "mid-bay")]
        for suffix in ("png", "pdf"):
            plotting.plot_receptance(FREQUENCIES, [a for pair in curves.values() for a in pair], labels, path=out / f"fig_receptance.{suffix}", pinned_pinned=f_pp_eb)
            plotting.plot_decay_rate(FREQUENCIES[::6], list(rates.values()), list(rates), path=out / f"fig_decay_rate.{suffix}")


if __name__ == "__main__":
    main()
