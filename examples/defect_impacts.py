"""Impacts at local defects on the fast converged model (docs/defects.md): a dipped rail joint,
a step-up joint, a dipped weld and a wheel flat, each alone and then all of them over a
random short-wave rail, against the smooth rail; the wheel–rail force extremes per case.

    python examples/defect_impacts.py
"""

import vtb
from vtb import Irregularity


def main():
    base = vtb.paper_config(model="fast")  # one CRH3 car at 80 m/s over five 32 m spans
    defects = {
        "dipped joint (2α = 4 mrad)": Irregularity(kind="rail_joint", position=40.0, depth=1e-3, length=1.0),
        "step-up joint (0.3 mm)": Irregularity(kind="rail_joint", position=60.0, step=-0.3e-3, length=0.2),
        "dipped weld (0.3 mm, crown 0.1 mm)": Irregularity(kind="dipped_weld", position=80.0, depth=0.3e-3, length=1.0, crown=0.1e-3),
        "wheel flat (30 mm, wheel 0)": Irregularity(kind="wheel_flat", wheel=0, length=0.03, position=100.0),
    }
    cases = {"smooth rail": Irregularity(), **defects,
             "all of them on a rough rail": Irregularity(kind="tbt3352", seed=2025, parts=list(defects.values()))}
    configs = []
    for irr in cases.values():
        cfg = vtb.paper_config(model="fast")
        cfg.irregularity = irr
        configs.append(cfg)
    runs = vtb.simulate_batch(configs, progress=False)
    p0 = (base.vehicles[0].m_c + 2 * base.vehicles[0].m_t + 4 * base.vehicles[0].m_w) * 9.81 / 8 / 1e3
    print(f"{'case':36s} {'max (kN)':>9s} {'min (kN)':>9s} {'max/P0':>7s} {'losses':>6s}")
    for name, m in zip(cases, runs):
        print(f"{name:36s} {m['contact_force_max'] / 1e3:9.1f} {m['contact_force_min'] / 1e3:9.1f} "
              f"{m['contact_force_max'] / 1e3 / p0:7.2f} {m['contact_loss_events']:6.0f}")


if __name__ == "__main__":
    main()
