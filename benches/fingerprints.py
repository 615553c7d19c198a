"""Bit-for-bit fingerprints of named runs: a refactoring that must not change a result runs this
with the old build and the new one and compares the two files.

    python benches/fingerprints.py --out new.json [--compare old.json] [--only NAME ...] [--drop-indices NAME ...]

Each case hashes (SHA-256) every array of its results and its metrics' exact bits, so two
builds agree on a case only if they give the same bits. The cases cover both engines (Newmark
on modal, hybrid and finite-element structures; the synthesis), every load kind (vehicles of
both models, trains, moving forces, treads), every damper kind, lockstep batches, a robust sweep
and an optimiser killed and resumed. The synthesis cases build a one-span reduction in a cache
folder of their own (``--cache``; shared by the two builds, so both run on the same file).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import vtb


def digest(*items) -> str:
    h = hashlib.sha256()

    def feed(x):
        if isinstance(x, dict):
            for k in sorted(x):
                h.update(str(k).encode())
                feed(x[k])
        elif isinstance(x, (list, tuple)):
            h.update(f"[{len(x)}".encode())
            for v in x:
                feed(v)
        elif isinstance(x, np.ndarray):
            h.update(str(x.shape).encode())
            h.update(np.ascontiguousarray(x, dtype=float).tobytes())
        elif isinstance(x, float):
            h.update(np.float64(x).tobytes())
        else:
            h.update(repr(x).encode())

    for it in items:
        feed(it)
    return h.hexdigest()


#: Indices left out of the metrics' digest (``--drop-indices``): those the old build does not
#: have, so that the rest compare bit for bit.
DROPPED = set()


def metrics_digest(batch: list) -> str:
    """A batch's metric dicts, without the dropped indices."""
    return digest([{k: v for k, v in m.items() if k not in DROPPED} for m in batch])


def result_digest(r) -> str:
    metrics = {k: v for k, v in r.metrics().items() if k not in DROPPED}
    return digest(r.t, r.disp, r.acc, r.vehicle_disp, r.vehicle_acc, r.contact_force,
                  [tuple(e) for e in r.contact_loss], metrics)


def short(t_end=0.04, **kw):
    c = vtb.paper_config(calibrated=True, **kw)
    c.solver.t_end = t_end
    c.output.points = [79.68, 80.0]
    return c


def one_span(cutoff=4000.0, t_end=0.04):
    c = vtb.paper_config(model="fast", calibrated=True)
    c.structure.length = 32.0
    for cp in c.structure.couplings:
        if cp.positions:
            cp.positions = [x for x in cp.positions if x <= 32.0 + 1e-9]
    c.solver.t_end = t_end
    c.output.points = [12.8, 13.12]
    c.discretisation.synthesis_cutoff = cutoff
    return c


def with_dampers(c):
    c = c.copy()
    tids = vtb.tids_around(c, count=3)
    tmd = vtb.DamperGroup(kind="tmd", inertance=500.0, stiffness=2e6, damping=3e3, positions=[c.structure.length / 2],
                          upper=c.structure.layers[-1].name, lower="ground")
    tvmd = vtb.DamperGroup(**{**vars(vtb.tids_around(c, count=2, x=c.structure.length / 2 + 3.0)), "kind": "tvmd"})
    c.dampers = [tmd, tvmd]
    c.tids = tids  # first: the article's group leads the node order in every vtb
    return c


def case_article_hybrid():
    c = vtb.paper_config(calibrated=True)
    return result_digest(vtb.simulate(c, progress=False))


def case_article_hybrid_dampers_movers():
    c = with_dampers(short(0.05))
    c.forces = [vtb.MovingForce(magnitude=5e4, x0=3.0), vtb.MovingForce(magnitude=1e5, x0=10.0, layer="slab")]
    c.output.band_limit = 2000.0
    c.output.band_levels = [500.0, 1000.0]
    return result_digest(vtb.simulate(c, progress=False))


def case_modal():
    c = short(0.05)
    c.discretisation.method = "modal"
    c.structure.layers[0].local_modes = 0
    return result_digest(vtb.simulate(c, progress=False))


def case_converged_fem():
    c = vtb.paper_config(model="converged", calibrated=True)
    c.solver.t_end = 0.02
    c.output.points = [79.68, 80.0]
    return result_digest(vtb.simulate(c, progress=False))


def case_converged_fem_dampers():
    c = with_dampers(vtb.paper_config(model="converged", calibrated=True))
    c.solver.t_end = 0.01
    return result_digest(vtb.simulate(c, progress=False))


def case_three_car_train():
    c = short(0.05)
    c.vehicles = vtb.train("crh3", cars=3, x_front=76.0)
    c.output.indices = None
    return result_digest(vtb.simulate(c, progress=False))


def case_quarter_cars_fem_zones():
    c = vtb.paper_config(model="converged")
    c = vtb.spans(c, [20.0])
    c = vtb.track_zones(c, approach=15.0, exit=15.0, tail=0.05)
    c.vehicles = [vtb.Vehicle.quarter_car(8000.0, 900.0, 1e6, 2e4, x_front=-1.0), vtb.Vehicle.quarter_car(8000.0, 900.0, 1e6, 2e4, x_front=-4.0)]
    c.solver.dt = 1e-4
    c.output.points = [25.0, 30.0]
    c.irregularity = vtb.Irregularity(kind="german_low", wavelength_min=1.0, wavelength_max=30.0, seed=4)
    return result_digest(vtb.simulate(c, progress=False))


def case_moving_load_modal():
    # Frýba's beam: a 25 m simply supported girder under two moving axles.
    forces = [vtb.MovingForce(1.7e5, 0.0), vtb.MovingForce(1.7e5, -3.0)]
    c = vtb.moving_load_config(25.0, 2500.0, 6.0, 3.5e10, 4.0, forces, 60.0, modes=30, dt=2e-4, points=[12.5, 6.0])
    return result_digest(vtb.simulate(c, progress=False))


def case_wheel_flat():
    c = short(0.05)
    c.irregularity = vtb.Irregularity(kind="wheel_flat", length=0.05, position=80.2, wheel=1,
                                      parts=[vtb.Irregularity(kind="rail_joint", depth=5e-4, length=0.3, position=79.0)])
    return result_digest(vtb.simulate(c, progress=False))


def case_batch_three_lanes():
    c = short(0.05)
    c.tids = vtb.tids_around(c, count=3)
    cs = []
    for b, k, d in ((3.0, 1e8, 1e3), (7.0, 5e8, 10.0), (1.0, 2e7, 1e4)):
        x = c.copy()
        x.tids.inertance, x.tids.stiffness, x.tids.damping = b, k, d
        cs.append(x)
    return metrics_digest(vtb.simulate_batch(cs, progress=False, lanes=4))


def case_batch_histories():
    c = short(0.03)
    c.tids = vtb.tids_around(c, count=3)
    cs = []
    for b in (2.0, 4.0):
        x = c.copy()
        x.tids.inertance = b
        cs.append(x)
    return digest([result_digest(r) for r in vtb.simulate_batch(cs, progress=False, histories=True)])


def case_synthesis():
    c = with_dampers(one_span())
    c.forces = [vtb.MovingForce(magnitude=2e4, x0=2.0)]
    return result_digest(vtb.simulate(c, progress=False))


def case_synthesis_load_train():
    c = with_dampers(one_span())
    c.forces = [vtb.MovingForce(magnitude=m, x0=x) for m, x in ((9e4, -1.0), (6e4, 2.0), (8e4, 17.0), (7e4, 31.0))]
    return result_digest(vtb.simulate(c, progress=False))


def case_synthesis_batch():
    c = one_span()
    c.tids = vtb.tids_around(c, count=3)
    cs = []
    for b in (1.0, 3.0, 5.0, 7.0, 9.0):
        x = c.copy()
        x.tids.inertance = b
        cs.append(x)
    return metrics_digest(vtb.simulate_batch(cs, progress=False))


def case_synthesis_train_zones():
    c = vtb.paper_config(model="fast")
    c.discretisation.synthesis_cutoff = 300.0
    c.output.band_limit = 150.0
    c.solver.dt = 2e-4
    c.output.points = []
    c = vtb.spans(c, [24.0])
    c = vtb.track_zones(c, approach=20.0, exit=20.0, tail=0.05)
    c.vehicles = vtb.train("velaro_e", cars=2, x_front=-2.0, contact_patch=True)
    c.irregularity = vtb.Irregularity(kind="german_low", wavelength_min=2.0, wavelength_max=40.0, seed=7)
    c.solver.fade_in = 20.0
    return result_digest(vtb.simulate(c, progress=False))


def case_robust_sweep():
    c = short(0.03)
    c.tids = vtb.tids_around(c, count=2)
    with tempfile.TemporaryDirectory() as d:
        s = vtb.sweep(c, [2.0, 5.0], [1e8], [1e3], samples=2, speeds=[70.0, 80.0], out=Path(d) / "j", progress=False)
    return digest([(v, seed, {k: np.asarray(x) for k, x in sw.columns.items() if k != "error"}) for v, seed, sw in s.sweeps])


def case_optimiser_resume():
    c = short(0.03)
    c.tids = vtb.tids_around(c, count=2)
    try:
        import vtb.run.scaleout as so
    except ImportError:  # a build before the packages by purpose
        import vtb.scaleout as so

    class Killed(Exception):
        pass

    real, calls = so.simulate_batch, []

    def killing(configs, **kw):
        calls.append(len(configs))
        if len(calls) == 3:
            raise Killed
        return real(configs, **kw)

    with tempfile.TemporaryDirectory() as d:
        ck = Path(d) / "ck.npz"
        so.simulate_batch = killing
        try:
            vtb.optimize(c, pop_size=6, n_gen=3, seed=3, progress=False, checkpoint=ck)
        except Killed:
            pass
        finally:
            so.simulate_batch = real
        resumed = vtb.optimize(c, pop_size=6, n_gen=3, seed=3, progress=False, checkpoint=ck)
    return digest({k: np.asarray(v) for k, v in resumed.pareto.items()}, resumed.moga.pop.X, resumed.moga.pop.F, calls)


CASES = {name[5:]: f for name, f in sorted(globals().items()) if name.startswith("case_")}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--compare")
    ap.add_argument("--only", nargs="*")
    ap.add_argument("--drop-indices", nargs="*", default=[], help="indices added since the old build (e.g. deck_disp_max)")
    ap.add_argument("--cache", default=os.path.join(tempfile.gettempdir(), "vtb-fingerprint-cache"))
    a = ap.parse_args(argv)
    DROPPED.update(a.drop_indices)
    os.environ.setdefault("VTB_CACHE", a.cache)
    try:
        try:
            from vtb.run import synthesis
        except ImportError:  # a build before the packages by purpose
            from vtb import synthesis

        os.environ[synthesis.CACHE_ENV] = a.cache
    except (ImportError, AttributeError):
        pass
    out = {}
    for name, f in CASES.items():
        if a.only and name not in a.only:
            continue
        t = time.perf_counter()
        try:
            out[name] = f()
        except Exception as e:  # noqa: BLE001 - a case that fails is a fingerprint too
            out[name] = f"error: {type(e).__name__}: {e}"
        print(f"{name:36s} {time.perf_counter() - t:7.1f} s  {out[name][:16]}", flush=True)
    Path(a.out).write_text(json.dumps(out, indent=1))
    if a.compare:
        old = json.loads(Path(a.compare).read_text())
        bad = [k for k in out if k in old and old[k] != out[k]]
        for k in bad:
            print(f"DIFFERS: {k}: {old[k][:40]} → {out[k][:40]}")
        print(f"{len(out) - len(bad)} of {len(out)} cases identical")
        return 1 if bad else 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
