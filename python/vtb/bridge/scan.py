"""Speed scans of EN 1991-2 §6.4.6.2: every load train over a range of speeds, for each bound of
the deck's mass, as a study of vtb (journaled, resumable, on any executor).

:func:`scan_speeds` makes the speeds: from a low speed to 1.2 × the line's maximum
(§6.4.6.2(1)) in steps no coarser than ``step``, with a finer step around each resonant speed
v_i = n0·D/i of each train that falls in the range (§6.4.6.2(3): the peak responses at the
resonant speeds must be found). :func:`speed_scan` runs them: one :func:`vtb.study` per train
and mass bound, over the speed, reporting the deck's peak acceleration in the check's band, its
peak deflection and its peak bending moment. With a deck under a track (several layers) and
several observation points the deck is observed at each (the core's ``deck_acc_max_p{j}``,
``deck_disp_max_p{j}``, ``deck_moment_max_p{j}``) and the
largest governs: :func:`span_points` puts them at the quarter, middle and three-quarter point of
every span.
"""

from __future__ import annotations

import csv
import math
from concurrent.futures import Executor
from dataclasses import dataclass
from pathlib import Path
from typing import Mapping, Optional, Sequence, Union

import numpy as np

from ..config.fields import Config
from ..errors import check_folder, config_error, make_folder
from ..run.tables import frame, to_parquet
from ..studies.grid import study
from .load_trains import LoadTrain, apply_load_train, load_train

#: Largest speed step (m/s) of a scan: 10 km/h.
MAX_STEP = 10.0 / 3.6
#: The deck's indices a scan records: (acceleration in the band, deflection, bending moment).
DECK_INDICES = ("deck_acc_max", "deck_disp_max", "deck_moment_max")
#: The deck's indices at observation point j (the core's catalogue).
POINT_INDICES = ("deck_acc_max_p{j}", "deck_disp_max_p{j}", "deck_moment_max_p{j}")
#: Where :func:`span_points` observes each span, as fractions of its length.
SPAN_FRACTIONS = (0.25, 0.5, 0.75)


#: Most speeds of a scan: 10 000 steps of 0.1 km/h cover 0 to 1000 km/h; more is a mistyped
#: step or line speed, refused before a list of billions of speeds is built.
MAX_SPEEDS = 10_000


def _positive(name: str, v) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float, np.floating, np.integer)) or not math.isfinite(v) or v <= 0:
        raise config_error(name, v, "must be a finite number > 0")
    return float(v)


def speed_grid(speeds) -> list:
    """``speeds`` (a number or a list of them, m/s) as a list of floats > 0, or a ConfigError."""
    texts = [speeds] if not isinstance(speeds, (list, tuple)) else speeds
    try:
        if any(isinstance(v, (str, bytes, bool)) for v in texts):  # numpy would read "60" and True as numbers
            raise TypeError
        grid = np.atleast_1d(np.asarray(speeds, dtype=float))
    except (TypeError, ValueError):
        raise config_error("speeds", speeds, "must be a list of speeds (m/s)") from None
    if grid.ndim != 1 or not 1 <= grid.size <= MAX_SPEEDS:
        raise config_error("speeds", speeds, f"must be a flat list of 1 to {MAX_SPEEDS} speeds (m/s)")
    for i, v in enumerate(grid):
        _positive(f"speeds[{i}]", v)
    return [float(v) for v in grid]


def mass_factors(mass_bounds) -> dict:
    """``mass_bounds`` (None: nominal only) as a dict name → factor > 0, or a ConfigError."""
    if mass_bounds is None:
        return {"nominal": 1.0}
    if not isinstance(mass_bounds, Mapping) or not mass_bounds:
        raise config_error("mass_bounds", mass_bounds, "needs at least one bound (name → factor on the deck's density)")
    for k, v in mass_bounds.items():
        if not isinstance(k, str) or not k.strip():
            raise config_error("mass_bounds", k, "a bound's name must be a non-empty text")
        _positive(f"mass_bounds.{k}", v)
    return dict(mass_bounds)


def out_folder(out) -> Optional[Path]:
    """``out`` (a folder's path, or None) checked before any run (:func:`vtb.errors.check_folder`)."""
    if out is None:
        return None
    if not isinstance(out, (str, Path)):
        raise config_error("out", out, "must be a folder's path")
    return check_folder(out, "out")


def scan_speeds(v_min: float, v_max: float, step: float = MAX_STEP, resonances: Sequence[float] = (),
                fine_step: Optional[float] = None, fine_width: Optional[float] = None) -> np.ndarray:
    """Speeds (m/s) from ``v_min`` to ``v_max`` every ``step`` (at most 10 km/h), plus every
    ``fine_step`` (default step/5) within ``fine_width`` (default 2·step) of each resonant speed
    in range, and the resonant speeds themselves."""
    lo, hi, st = _positive("v_min", v_min), _positive("v_max", v_max), _positive("step", step)
    if hi <= lo:
        raise config_error("v_max", v_max, f"must exceed v_min = {v_min:g} m/s")
    if st > MAX_STEP + 1e-12:
        raise config_error("step", step, f"must be at most {MAX_STEP:.4g} m/s (10 km/h, EN 1991-2 §6.4.6.2)")
    fine = _positive("fine_step", fine_step) if fine_step is not None else st / 5
    width = _positive("fine_width", fine_width) if fine_width is not None else 2 * st
    if (hi - lo) / st > MAX_SPEEDS:
        raise config_error("step", step, f"makes more than {MAX_SPEEDS} speeds from {v_min:g} to {v_max:g} m/s")
    if (isinstance(resonances, (str, bytes)) or not hasattr(resonances, "__iter__")
            or not all(isinstance(r, (int, float)) and not isinstance(r, bool) and math.isfinite(r) for r in resonances)):
        raise config_error("resonances", resonances, "must be a list of speeds (m/s)")
    resonances = list(resonances)
    if len(resonances) * (2 * width / fine + 1) > MAX_SPEEDS:
        raise config_error("fine_step", fine_step, f"makes more than {MAX_SPEEDS} speeds around the {len(resonances)} resonances")
    n = int(math.floor((hi - lo) / st + 1e-9))
    speeds = [lo + i * st for i in range(n + 1)] + [hi]
    for r in resonances:
        if lo <= r <= hi:
            k = int(math.floor(width / fine))
            speeds += [r + j * fine for j in range(-k, k + 1) if lo <= r + j * fine <= hi]
    out = np.unique(np.round(np.asarray(speeds, dtype=float), 9))
    return out


def deck_indices(config: Config) -> tuple:
    """The (acceleration, deflection, bending moment) index names of the deck of ``config``: the
    deck's own (``deck_acc_max``, ``deck_disp_max``, ``deck_moment_max``: the bottom layer, the
    acceleration low-passed at ``output.deck_band``) when the structure has several layers, else
    the single layer's (``{layer}_acc_max`` low-passed at ``output.band_limit``,
    ``{layer}_disp_max``, and ``deck_moment_max``, which is the bottom layer's, its own)."""
    _deck(config)
    if len(config.structure.layers) > 1:
        return DECK_INDICES
    name = config.structure.layers[0].name
    return (f"{name}_acc_max", f"{name}_disp_max", DECK_INDICES[2])


def point_indices(config: Config) -> Optional[tuple]:
    """The (acceleration, deflection, bending moment) index names of the deck at every
    observation point of ``config`` (three lists), or None when it has one point or a single
    layer."""
    _deck(config)
    if not isinstance(config.output.points, (list, tuple)):
        raise config_error("output.points", config.output.points, "must be a list of positions (m)")
    n = len(config.output.points)
    if len(config.structure.layers) < 2 or n < 2:
        return None
    return tuple([p.replace("{j}", str(j)) for j in range(n)] for p in POINT_INDICES)


def span_points(config: Config) -> list:
    """The quarter, middle and three-quarter points (m) of every span of ``config``'s deck (its
    bottom layer): the deck is cut at its ``joints`` into girders, and each girder spans between
    its supports (discrete couplings to the ground) in it — the whole girder without two."""
    deck = _deck(config)
    length = _positive("structure.length", config.structure.length)
    if not isinstance(deck.joints, (list, tuple)) or not all(isinstance(j, (int, float)) and 0 < j < length for j in deck.joints):
        raise config_error(f"structure.layers[{len(config.structure.layers) - 1}].joints", deck.joints,
                           f"must be a list of positions (m) within the structure, 0 < x < {length:g}")
    cuts = [0.0] + sorted(float(j) for j in deck.joints) + [length]
    supports = sorted(float(x) for c in config.structure.couplings if c.upper == deck.name and c.lower == "ground"
                      and c.kind == "discrete" for x in c.positions)
    out = []
    for a, b in zip(cuts[:-1], cuts[1:]):
        inside = [x for x in supports if a <= x <= b]
        ends = inside if len(inside) >= 2 else [a, b]
        for lo, hi in zip(ends[:-1], ends[1:]):
            out += [lo + f * (hi - lo) for f in SPAN_FRACTIONS]
    return out


def _deck(config: Config):
    """The deck (bottom layer) of ``config``, or a ConfigError when it has no layer."""
    if not isinstance(config.structure.layers, list) or not config.structure.layers:
        raise config_error("structure.layers", config.structure.layers, "a bridge needs a deck: at least one layer")
    return config.structure.layers[-1]


def with_band(config: Config, band: float) -> Config:
    """``config`` whose deck acceleration is low-passed at ``band`` (Hz): ``output.deck_band``,
    and for a single layer ``output.band_limit`` too."""
    band = _positive("band", band)
    out = config.copy()
    out.output.deck_band = band
    if len(out.structure.layers) == 1:
        out.output.band_limit = float(band)
    return out


def with_mass(config: Config, factor: float) -> Config:
    """``config`` whose deck (bottom layer) is ``factor`` times as heavy (its density scaled;
    its stiffness kept): a bound of the deck's mass (ballast density and depth)."""
    factor = _positive("mass_bounds", factor)
    out = config.copy()
    _deck(out).density *= factor
    return out


#: A scan's columns, and those of them that are numbers.
COLUMNS = ("train", "bound", "speed", "acc", "disp", "moment", "acc_x", "disp_x", "moment_x", "error")
NUMBERS = ("speed", "acc", "disp", "moment", "acc_x", "disp_x", "moment_x")
#: The peaks a scan keeps, each with the point where it occurred (``{peak}_x``).
PEAKS = ("acc", "disp", "moment")


@dataclass
class ScanResult:
    """A finished scan. ``columns``: numpy arrays ``train`` (name), ``bound`` (the mass bound's
    name), ``speed`` (m/s), ``acc`` (the deck's peak acceleration in the check's band, m/s²),
    ``disp`` (its peak deflection, m, static part included), ``moment`` (its peak bending
    moment, N·m, static part included), ``acc_x``, ``disp_x`` and ``moment_x`` (the observation
    point, m, where each peak was found), ``error`` (empty, or why the run failed).
    ``indices``: the run indices ``acc``, ``disp`` and ``moment`` were read from (three lists,
    one name per observation point); ``journals``: the study journal of each (train, bound)."""

    columns: dict
    indices: tuple
    journals: dict

    def __len__(self) -> int:
        return len(self.columns["speed"])

    def select(self, train: Optional[str] = None, bound: Optional[str] = None) -> dict:
        """The columns of one train and/or bound, ordered by speed."""
        mask = np.ones(len(self), bool)
        if train is not None:
            mask &= self.columns["train"] == train
        if bound is not None:
            mask &= self.columns["bound"] == bound
        order = np.argsort(self.columns["speed"][mask], kind="stable")
        return {k: v[mask][order] for k, v in self.columns.items()}

    def governing(self, column: str) -> dict:
        """The run with the largest ``column`` (``"acc"``, ``"disp"`` or ``"moment"``): its train, bound,
        speed (m/s) and value."""
        ok = self.columns["error"] == ""
        if not ok.any():
            raise config_error("scan", "all runs failed", "no successful run to govern")
        i = np.flatnonzero(ok)[np.nanargmax(self.columns[column][ok])]
        return {k: (v[i].item() if hasattr(v[i], "item") else v[i]) for k, v in self.columns.items()}

    def to_pandas(self):
        """The columns as a DataFrame (units in ``attrs["units"]``; needs pandas)."""
        return frame(self.columns, {"speed": "m/s", "acc": "m/s²", "disp": "m", "moment": "N·m", "acc_x": "m", "disp_x": "m",
                                    "moment_x": "m"})

    def to_csv(self, path) -> None:
        """CSV of the columns (numbers by ``repr``: exact round trip)."""
        with open(path, "w", newline="") as f:
            w = csv.writer(f, lineterminator="\n")
            w.writerow(COLUMNS)
            for r in zip(*(self.columns[c] for c in COLUMNS)):
                w.writerow([repr(float(v)) if k in NUMBERS else str(v) for k, v in zip(COLUMNS, r)])

    def to_parquet(self, path) -> None:
        to_parquet(self.to_pandas(), path)


def speed_scan(config: Config, trains: Sequence[Union[str, LoadTrain]], speeds: Sequence[float], *, band: Optional[float] = None,
               mass_bounds: Optional[Mapping[str, float]] = None, share: float = 1.0, tail: float = 0.5, gap: float = 1.0,
               out: Union[str, Path, None] = None, executor: Optional[Executor] = None, threads: Optional[int] = None,
               progress: bool = True) -> ScanResult:
    """Runs every train of ``trains`` (names or :class:`LoadTrain` s) as moving forces over
    ``config`` at every speed of ``speeds`` (m/s), for each deck mass bound of ``mass_bounds``
    (name → factor on the deck's density; default ``{"nominal": 1.0}``).

    ``band``: the check's band (Hz) the deck acceleration is low-passed at (default: the
    configuration's ``output.deck_band``; a single-layer model's ``output.band_limit`` is set
    to it too, :func:`with_band`). ``share``: of each axle load on the modelled track
    (:meth:`LoadTrain.forces`). ``tail``: free vibration (s) recorded after the last axle has
    left. ``gap``: distance (m) of the first axle before the structure at t = 0 (the run starts
    unloaded, and each axle enters over the first support). ``out``: a directory; each (train, bound) study journals there as it runs
    (``{train}__{bound}.csv``) and a re-run resumes it. ``executor``/``threads``: as
    :func:`vtb.study` (Dask's client's executor included)."""
    if isinstance(trains, (str, LoadTrain)) or not isinstance(trains, Sequence) or not trains:
        raise config_error("trains", trains, "needs a list of at least one load train")
    loads = [load_train(t) for t in trains]
    grid, bounds, base, directory = scan_inputs(config, speeds, mass_bounds, band, out)
    runs = []
    for bound, factor in bounds.items():
        massed = with_mass(base, factor)
        for t in loads:
            runs.append((t.name, bound, apply_load_train(massed, t, share=share, tail=tail, gap=gap)))
    return run_scan(runs, grid, directory, executor=executor, threads=threads, progress=progress)


def scan_inputs(config: Config, speeds, mass_bounds, band, out) -> tuple:
    """A scan's checked inputs: the speeds (m/s, each positive), the mass bounds (default
    ``{"nominal": 1.0}``), the configuration low-passed at ``band`` (default its deck band) and
    the journals' directory (or None)."""
    grid, bounds = speed_grid(speeds), mass_factors(mass_bounds)
    base = with_band(config, band if band is not None else config.output.deck_band)
    return grid, bounds, base, out_folder(out)


def run_scan(runs: Sequence[tuple], speeds: Sequence[float], directory: Optional[Path], executor: Optional[Executor] = None,
             threads: Optional[int] = None, progress: bool = True) -> ScanResult:
    """Runs each (train name, bound name, configuration) of ``runs`` as one :func:`vtb.study`
    over ``speeds`` (m/s), journaled in ``directory`` (``{train}__{bound}.csv``; None: not
    journaled), and gathers the deck's peaks into a :class:`ScanResult`."""
    if directory is not None:
        make_folder(directory, "out")
    cols = {k: [] for k in COLUMNS}
    journals = {}
    names = None
    for train, bound, cfg in runs:
        per_point = point_indices(cfg)
        names = per_point if per_point is not None else tuple([i] for i in deck_indices(cfg))
        xs = np.asarray(cfg.output.points or [cfg.structure.length / 2], dtype=float)
        journal = directory / f"{_file_name(train)}__{_file_name(bound)}.csv" if directory is not None else None
        res = study(cfg, cases=[{"speed": v} for v in speeds], indices=sum(names, []), out=journal, executor=executor,
                    threads=threads, progress=progress, desc=f"{train} ({bound})")
        journals[(train, bound)] = None if journal is None else str(journal)
        n = len(res)
        cols["train"] += [train] * n
        cols["bound"] += [bound] * n
        cols["speed"] += list(res.columns["speed"])
        cols["error"] += list(res.columns["error"])
        for key, which in zip(PEAKS, names):
            table = np.column_stack([np.asarray(res.columns[i], dtype=float) for i in which])
            ok = np.isfinite(table).any(axis=1)
            j = np.argmax(np.where(np.isfinite(table), table, -np.inf), axis=1)
            cols[key] += list(np.where(ok, table[np.arange(n), j], np.nan))
            cols[key + "_x"] += list(np.where(ok, xs[j], np.nan))
    columns = {k: np.asarray(v, dtype=float if k in NUMBERS else str) for k, v in cols.items()}
    return ScanResult(columns, names, journals)


def _file_name(text: str) -> str:
    return "".join(c if c.isalnum() or c in "-_." else "_" for c in str(text))
