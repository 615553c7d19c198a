"""The bridge engineer's check (EN 1991-2 §6.4.6): a 20 m prestressed-concrete span on a
250 km/h line, HSLM-A1 … A10 as moving loads, scanned to 1.2 × the line speed with the code's
damping, against the EN 1990 A2 limits; a Markdown report with envelopes and figures.

    python examples/bridge_check.py [--out DIR] [--quick]

``--quick``: two trains over a narrow range of speeds (seconds).
"""

import argparse
import math
import tempfile

import vtb

SPAN = 20.0         # m
MASS = 20000.0      # kg/m: girder and ballast
N0 = 6.0            # Hz: the span's first bending frequency (within Fig. 6.10's 4–10 Hz at 20 m)


def bridge() -> vtb.Config:
    """The span as one beam: EI from n0 = (π/2L²)·√(EI/m)."""
    ei = (2 * N0 * SPAN**2 / math.pi) ** 2 * MASS
    e = 3.5e10
    return vtb.moving_load_config(SPAN, 2500.0, MASS / 2500.0, e, ei / e, [vtb.MovingForce(1.0, 0.0)], 50.0, points=[SPAN / 2], modes=20)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", help="report directory (default: a temporary one)")
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args(argv)
    settings = vtb.BridgeCheck(span=SPAN, bridge_type="prestressed_concrete", track="ballasted", line_speed=250 / 3.6, dt=1e-3)
    if args.quick:
        settings.trains, settings.v_min = ["HSLM-A1", "HSLM-A4"], 240 / 3.6
    out = args.out or tempfile.mkdtemp(prefix="bridge_check_")
    result = vtb.bridge_check(bridge(), settings, out, progress=False)
    print(f"n0 = {result.n0:.3f} Hz, band {result.band:.1f} Hz, damping {result.damping.describe()}")
    for c in result.checks:
        state = {True: "pass", False: "FAIL", None: "not evaluated"}[c.passed]
        print(f"{c.name:<36} {c.value:10.4g} {c.unit:<5} limit {c.limit:10.4g}  {state}  {c.train}"
              + (f" at {3.6 * c.speed:.0f} km/h" if math.isfinite(c.speed) else ""))
    print(f"report: {out}/report.md ({len(result.scan)} runs in {result.seconds:.1f} s)")


if __name__ == "__main__":
    main()
