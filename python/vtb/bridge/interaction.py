"""Beyond the code: the speed scan with full vehicle–track–bridge interaction.

:func:`interaction_scan` runs the library's trains (:func:`vtb.trains`) as vehicles — car
bodies, bogies and wheelsets on their suspensions, Hertz contact on the rail — over the same
structure and speeds as the moving-load scan (:func:`~vtb.bridge.scan.speed_scan`), on a smooth
rail by default or on a given irregularity, each (train, mass bound) a journaled, resumable
:func:`vtb.study`, and returns the same :class:`~vtb.bridge.scan.ScanResult`, so the two can be
drawn together. The damping is the structure's as given: for the comparison EN 1991-2 intends,
Table 6.6's without Δζ (Δζ stands in for the interaction this scan models).

The vehicles start ``gap`` m before the structure on a rigid track and step onto the rail at
x = 0 (``solver.edge_step``, unless the configuration hands the wheels over on a ramp,
``solver.edge_ramp``), as the moving loads do.
"""

from __future__ import annotations

import math
from concurrent.futures import Executor
from pathlib import Path
from typing import Mapping, Optional, Sequence, Union

from ..config.fields import Config
from ..config.irregularity import Irregularity
from ..config.trains import train as library_train
from ..config.trains import trains as library_trains
from ..errors import config_error
from .scan import ScanResult, _positive, run_scan, scan_inputs, with_mass


def with_vehicles(config: Config, name: str, gap: float = 1.0, tail: float = 0.5, cars: Optional[int] = None,
                  irregularity: Optional[Irregularity] = None) -> Config:
    """A copy of ``config`` carrying the library's train ``name`` (``cars`` of it; default one
    unit) as vehicles, its leading wheelset ``gap`` m before the structure at t = 0, on
    ``irregularity`` (default a smooth rail), recording ``tail`` s after the last wheel has
    left; no moving forces."""
    if not isinstance(name, str) or name not in library_trains():
        raise config_error("trains", name, f"unknown train for the interaction scan (the library's: {sorted(library_trains())})")
    if isinstance(tail, bool) or not isinstance(tail, (int, float)) or not math.isfinite(tail) or tail < 0:
        raise config_error("tail", tail, "must be a duration (s) >= 0")
    if irregularity is not None and not isinstance(irregularity, Irregularity):
        raise config_error("irregularity", irregularity, "must be a vtb.Irregularity, or None for a smooth rail")
    out = config.copy()
    out.forces = []
    out.vehicles = library_train(name, cars=cars, x_front=-_positive("gap", gap))
    out.irregularity = irregularity if irregularity is not None else Irregularity()
    out.solver.t_end = None
    out.solver.tail = float(tail)
    if not out.solver.edge_ramp:
        out.solver.edge_step = True
    return out


def interaction_scan(config: Config, trains: Sequence[str], speeds: Sequence[float], *, band: Optional[float] = None,
                     mass_bounds: Optional[Mapping[str, float]] = None, irregularity: Optional[Irregularity] = None,
                     cars: Optional[int] = None, tail: float = 0.5, gap: float = 1.0, out: Union[str, Path, None] = None,
                     executor: Optional[Executor] = None, threads: Optional[int] = None, progress: bool = True) -> ScanResult:
    """Runs every library train of ``trains`` (names of :func:`vtb.trains`; ``cars`` of each,
    default one unit) as vehicles over ``config`` at every speed of ``speeds`` (m/s), for each
    deck mass bound of ``mass_bounds`` (default ``{"nominal": 1.0}``), on ``irregularity``
    (default a smooth rail). ``band``, ``tail``, ``gap``, ``out``, ``executor``, ``threads``:
    as :func:`~vtb.bridge.scan.speed_scan`; the journals are ``{train}__{bound}.csv`` in
    ``out``."""
    if isinstance(trains, str) or not isinstance(trains, Sequence) or not trains:
        raise config_error("trains", trains, "needs a list of at least one train of the library")
    names = list(trains)
    grid, bounds, base, directory = scan_inputs(config, speeds, mass_bounds, band, out)
    runs = [(name, bound, with_vehicles(with_mass(base, factor), name, gap, tail, cars, irregularity))
            for bound, factor in bounds.items() for name in names]
    return run_scan(runs, grid, directory, executor=executor, threads=threads, progress=progress)
