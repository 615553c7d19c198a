"""Comfort check: ISO 2631-1 (Wk-weighted r.m.s. a_w, MTVV) and Sperling's Wz of the car body
on the article's case, with and without the start of the run, and what the record length
allows (the indices warn when it is short).

    python examples/comfort_check.py
"""

import warnings

import vtb
from vtb.analysis import comfort


def main():
    cfg = vtb.paper_config()
    res = vtb.simulate(cfg)
    duration = res.t[-1]
    print(f"record: {duration:.2f} s of car body acceleration at {1 / cfg.solver.dt:.0f} Hz")
    for label, window in (("whole run", None), ("after the fade-in and 0.1 s", (cfg.solver.fade_in / cfg.speed + 0.1, duration))):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", comfort.ComfortWarning)
            c = res.comfort(window=window)
        print(f"{label}: a_w = {c['a_w']:.4f} m/s², MTVV = {c['mtvv']:.4f} m/s² (ratio {c['mtvv_ratio']:.2f}), Wz = {c['wz']:.3f}")
        for w in caught:
            print(f"  warning: {w.message}")
    print(f"ISO 2631-1 wants about {comfort.MIN_RMS_RECORD:g} s for a_w, Sperling about {comfort.MIN_SPERLING_RECORD:g} s: "
          "a single crossing of a 160 m bridge rates that crossing, not a journey.")
    b = vtb.analysis.spectra.third_octave(res.car_body_acc, 1.0 / cfg.solver.dt)
    i = int(b["level"].argmax())
    print(f"car body: strongest one-third-octave band {b['nominal'][i]:g} Hz at {b['level'][i]:.1f} dB re 1e-6 m/s² "
          f"(bands from {b['nominal'][0]:g} Hz, the lowest this record resolves)")


if __name__ == "__main__":
    main()
