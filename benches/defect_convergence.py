"""The step-up joint's impact under refinement of the time step, seen through the wheel (the
default) and as the raw step (docs/defects.md): the fast model at 80 m/s, a 0.5 mm step up at
x = 80 m sampled at 0.25 mm. 34 s on the 2-core machine (2026-12-02, with a test run beside it).

    python benches/defect_convergence.py
"""

import time

import vtb


def peak(dt: float, **kw) -> float:
    cfg = vtb.paper_config(model="fast")
    cfg.solver.dt = dt
    cfg.irregularity = vtb.Irregularity(kind="rail_joint", position=80.0, step=-0.5e-3, length=0.2, dx=2.5e-4, **kw)
    return vtb.simulate(cfg, progress=False).contact_force[:, 0].max() / 1e3


def main():
    t0 = time.perf_counter()
    print("| 0.5 mm step up, peak wheel–rail force | " + " | ".join(f"Δt = {dt:g} s" for dt in (5e-5, 2.5e-5, 1.25e-5)) + " |")
    print("|---|---|---|---|")
    for name, kw in (("through the wheel (default)", {}), ("raw step (`wheel_radius = 0`)", {"wheel_radius": 0.0})):
        print(f"| {name} | " + " | ".join(f"{peak(dt, **kw):.1f} kN" for dt in (5e-5, 2.5e-5, 1.25e-5)) + " |")
    print(f"({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
