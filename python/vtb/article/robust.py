"""Designs judged over the excitation they cannot know in advance (docs/robust.md).

A damper design tuned on one irregularity sample at one speed is fitted to that sample. This
module evaluates a design over **irregularity samples** (realisations of the configuration's
own spectrum and level, differing only in their seed) and **speeds**, every index taken
relative to the uncontrolled run of the same sample and speed, and summarises each index over
the cases by a chosen **statistic**.

Seeds are documented, so a study can be repeated and design and check kept apart: sample i of
a design study uses seed ``DESIGN_SEED0 + i``, sample i of a held-out check
``HELD_OUT_SEED0 + i`` (an explicit list of seeds may be given instead).

Statistics (:func:`statistic`): ``"mean"``, ``"max"``, ``"min"``, ``"median"`` and quantiles
``"pNN"`` (0 < NN < 100, e.g. ``"p90"``: the value 90 % of the cases stay at or below; linear
interpolation between order statistics, numpy's default). The standard error of the mean,
s/√N with the sample standard deviation s, is reported beside every mean so a user can choose
N: it halves when N quadruples.
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
import re
from pathlib import Path
from typing import Mapping, Optional, Sequence, Union

import numpy as np

from ..config.fields import Config, TIDs
from ..config.presets import tids_around
from ..errors import VtbError, config_error, make_folder
from ..run.indices import A_RM, ARTICLE_OBJECTIVES, CONSTRAINTS, METRICS, RAIL_RATE, REDUCED
from ..run.scaleout import run_all, run_cases
from ..run.tables import frame, to_parquet, units_of
from ..studies import journal as jr
from ..studies.grid import result_of
from ..studies.journal import config_stamp
from ..studies.optimize import DesignEvaluator, checkpoint_identity
from .tid_problem import LAYOUT, OptimizationResult, Setup, SweepResult, case_config, case_rows, plan, recording_metrics, with_dampers

#: First seed of the samples a design is chosen on.
DESIGN_SEED0 = 1000
#: First seed of the held-out samples a design is checked on.
HELD_OUT_SEED0 = 2000

_QUANTILE = re.compile(r"^p(\d+(?:\.\d+)?)$")


def seeds(samples: Union[int, Sequence[int]], first: int) -> list:
    """The seeds of ``samples``: an int N gives ``first + i`` for i < N; a sequence is taken
    as the seeds themselves (non-negative integers, no repeats)."""
    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer, list, tuple, np.ndarray)):
        raise config_error("samples", samples, "must be a number of samples (int ≥ 1) or a list of seeds")
    if isinstance(samples, (int, np.integer)):
        if samples < 1:
            raise config_error("samples", samples, "must be at least 1")
        return [first + i for i in range(int(samples))]
    out = list(samples)
    if not out or any(isinstance(s, bool) or not isinstance(s, (int, np.integer)) or s < 0 for s in out) or len(set(out)) != len(out):
        raise config_error("samples", samples, "a list of seeds must hold distinct non-negative integers")
    return [int(s) for s in out]


def statistic(values, name: str) -> float:
    """``name`` (module docstring) of ``values`` (NaN entries, failed cases, make it NaN)."""
    v = np.asarray(values, dtype=float)
    if v.ndim != 1 or v.size == 0:
        raise config_error("values", f"shape {v.shape}", "must be a non-empty 1-D sequence")
    if name in ("mean", "max", "min", "median"):
        return float(getattr(np, name)(v))
    m = _QUANTILE.match(name) if isinstance(name, str) else None
    if m is None or not 0.0 < float(m.group(1)) < 100.0:
        raise config_error("statistic", name, 'must be "mean", "max", "min", "median" or a quantile "pNN" with 0 < NN < 100')
    return float(np.quantile(v, float(m.group(1)) / 100.0))


def standard_error(values) -> float:
    """Standard error of the mean, s/√N (sample standard deviation; NaN for one value)."""
    v = np.asarray(values, dtype=float)
    return float(np.std(v, ddof=1) / math.sqrt(v.size)) if v.size > 1 else math.nan


def _design_tids(config: Config, design) -> TIDs:
    base = config.tids if config.tids is not None else tids_around(config)
    if isinstance(design, TIDs):
        return design
    if not isinstance(design, Mapping) or not {"b_t", "k_t", "c_t"} <= set(design):
        raise config_error("design", design, "must be a vtb.TIDs or a mapping with b_t (kg), k_t (N/m) and c_t (N·s/m)")
    return dataclasses.replace(base, inertance=float(design["b_t"]), stiffness=float(design["k_t"]), damping=float(design["c_t"]))


def cases(config: Config, samples, speeds: Optional[Sequence[float]], first: int) -> list:
    """(speed, seed, configuration without dampers) of every case, speed-major. ``samples``
    None: the configuration's own seed; ``speeds`` None: its own speed."""
    if config.irregularity.kind in ("none", "sampled"):
        raise config_error("irregularity.kind", config.irregularity.kind, "samples need a random irregularity (a spectrum) to draw realisations from")
    speeds = [config.speed] if speeds is None else list(speeds)
    if not speeds or any(isinstance(v, bool) or not isinstance(v, (int, float, np.number)) or not math.isfinite(v) or v <= 0 for v in speeds):
        raise config_error("speeds", speeds, "must be a non-empty list of finite speeds > 0 (m/s)")
    out = []
    for v in speeds:
        for s in [config.irregularity.seed] if samples is None else seeds(samples, first):
            cfg = config.copy()
            cfg.speed = float(v)
            cfg.irregularity = dataclasses.replace(cfg.irregularity, seed=s)
            cfg.tids = None
            out.append((float(v), s, recording_metrics(cfg)))
    return out


def _case_row(speed: float, seed: int, m0: Optional[dict], m1: Optional[dict], error: str = "") -> dict:
    """One case of a design: every metric uncontrolled (``m0``) and controlled (``m1``), the
    reduction rates and the constraint check; ``error`` (a failed run): NaN indices,
    infeasible."""
    row = dict(speed=float(speed), seed=int(seed), error=error)
    if error:
        row.update({k: math.nan for m in METRICS for k in (m, f"{m}_0")})
        row.update({f"eta_{m}": math.nan for m in REDUCED})
        row["feasible"] = False
        return row
    for m in METRICS:
        row[f"{m}_0"], row[m] = float(m0[m]), float(m1[m])
    for m in REDUCED:
        row[f"eta_{m}"] = (m0[m] - m1[m]) / m0[m] if m0[m] != 0 else math.nan
    row["feasible"] = all(m1[m] <= m0[m] for m in CONSTRAINTS)
    return row


def _error_text(e: BaseException) -> str:
    return " ".join(f"{type(e).__name__}: {e}".split())


def _run_row(speed: float, seed: int, r0, r1) -> dict:
    """:func:`_case_row` of two runs' metrics, either of which may be the exception of a failed run."""
    failed = next((r for r in (r0, r1) if isinstance(r, BaseException)), None)
    return _case_row(speed, seed, None, None, _error_text(failed)) if failed is not None else _case_row(speed, seed, r0, r1)


def design_statistics(rows: list, statistic_name: str) -> dict:
    """What a design study ranks a design by, from its case rows: per index of
    :data:`REDUCED` the ``statistic_name`` of the relative index X/X0 over the cases
    (``ratio_<metric>``), its mean (``mean_<metric>``) and the standard error of that mean
    (``sem_<metric>``); ``satisfaction_rate`` (share of cases meeting every constraint); and
    ``feasible``: the statistic of X/X0 at or below 1 for every index of
    :data:`vtb.run.indices.CONSTRAINTS` (the optimiser's G = statistic(X/X0) − 1 ≤ 0). A design
    with a failed case has infinite ratios and is infeasible."""
    failed = any(r["error"] for r in rows)
    out = {}
    for m in REDUCED:
        ratio = np.array([1.0 - r[f"eta_{m}"] for r in rows])
        if failed:
            out[f"ratio_{m}"] = out[f"mean_{m}"] = math.inf
            out[f"sem_{m}"] = math.nan
        else:
            out[f"ratio_{m}"] = statistic(ratio, statistic_name)
            out[f"mean_{m}"] = float(np.mean(ratio))
            out[f"sem_{m}"] = standard_error(ratio)
    out["satisfaction_rate"] = float(np.mean([bool(r["feasible"]) for r in rows]))
    out["feasible"] = not failed and all(out[f"ratio_{m}"] <= 1.0 for m in CONSTRAINTS)
    return out


def robust_objectives(rows: list, statistic_name: str) -> tuple:
    """F = (statistic of a_rm/a_rm0, statistic of a_sm/a_sm0) and G = statistic(X/X0) − 1 of
    the :data:`~vtb.run.indices.CONSTRAINTS` over a design's case rows (a failed case: F = 10,
    G = ∞, as a failed run of a single-case optimisation)."""
    s = design_statistics(rows, statistic_name)
    if any(r["error"] for r in rows):
        return [10.0, 10.0], [math.inf] * len(CONSTRAINTS)
    return [s[f"ratio_{m}"] for m in ARTICLE_OBJECTIVES], [s[f"ratio_{m}"] - 1.0 for m in CONSTRAINTS]


def _rows_table(designs: list, rows_of: list, statistic_name: str, speed: Optional[float]) -> dict:
    """numpy columns b_t, k_t, c_t and :func:`design_statistics` of each design (the cases of
    one ``speed`` if given)."""
    out = {k: [] for k in ("b_t", "k_t", "c_t")}
    for d, rows in zip(designs, rows_of):
        sub = rows if speed is None else [r for r in rows if r["speed"] == speed]
        if not sub:
            raise config_error("speed", speed, f"not among the studied speeds {sorted({r['speed'] for r in rows})}")
        for k, v in zip(("b_t", "k_t", "c_t"), d):
            out[k].append(float(v))
        for k, v in design_statistics(sub, statistic_name).items():
            out.setdefault(k, []).append(v)
    return {k: np.array(v) for k, v in out.items()}


def _best_of(table: dict) -> dict:
    """The feasible design with the lowest statistic of a_rm/a_rm0 (``feasible`` False in the
    answer when no design is feasible: then the lowest one overall)."""
    if len(table["b_t"]) == 0:
        raise VtbError("no design was evaluated")
    ok = np.flatnonzero(table["feasible"])
    pool = ok if ok.size else np.arange(len(table["b_t"]))
    i = int(pool[np.argmin(table[f"ratio_{A_RM}"][pool])])
    return {k: (bool(v[i]) if k == "feasible" else float(v[i])) for k, v in table.items()}


@dataclasses.dataclass
class DesignEvaluation:
    """A design over samples and speeds. ``rows``: one dict per case with ``speed`` (m/s),
    ``seed``, every metric uncontrolled (``<metric>_0``) and with the design (``<metric>``, SI
    units), the reduction rates ``eta_<metric>`` = (X0 − X)/X0 of :data:`REDUCED`, and
    ``feasible`` (True when every constrained index of :data:`vtb.run.indices.CONSTRAINTS` is at or
    below its uncontrolled value); a failed case has ``error`` set and NaN indices.
    ``design``: the dampers evaluated."""

    rows: list
    design: TIDs

    def column(self, name: str) -> np.ndarray:
        return np.array([r[name] for r in self.rows], dtype=float)

    @property
    def satisfaction_rate(self) -> float:
        """Share of the cases in which the design meets every constraint (failed cases count
        as not meeting them)."""
        return float(np.mean([bool(r["feasible"]) for r in self.rows]))

    def summary(self, statistic_name: str = "mean", speed: Optional[float] = None) -> dict:
        """Per index: ``{eta_<metric>: (statistic, mean, standard error of the mean)}`` of the
        reduction rate over the cases (of one ``speed`` if given), and ``satisfaction_rate``."""
        rows = self.rows if speed is None else [r for r in self.rows if r["speed"] == speed]
        if not rows:
            raise config_error("speed", speed, f"not among the evaluated speeds {sorted({r['speed'] for r in self.rows})}")
        sub = DesignEvaluation(rows, self.design)
        out = {}
        for m in REDUCED:
            v = sub.column(f"eta_{m}")
            out[f"eta_{m}"] = (statistic(v, statistic_name), float(np.mean(v)), standard_error(v))
        out["satisfaction_rate"] = sub.satisfaction_rate
        return out

    def to_pandas(self):
        """One row per case, units in ``attrs["units"]`` (needs pandas)."""
        df = frame(self.rows)
        df.attrs["units"] = units_of(df.columns)
        return df

    def to_parquet(self, path) -> None:
        """Parquet export of :meth:`to_pandas`, units in its metadata (needs pyarrow)."""
        to_parquet(self.to_pandas(), path)


def evaluate_designs(
    config: Config,
    designs: Sequence,
    samples: Union[int, Sequence[int]] = 8,
    speeds: Optional[Sequence[float]] = None,
    first_seed: int = HELD_OUT_SEED0,
    threads: Optional[int] = None,
    progress: bool = False,
    executor=None,
) -> list:
    """:func:`evaluate_design` of several designs on the same cases, which run uncontrolled
    once for all of them; one :class:`DesignEvaluation` per design. ``executor``: see
    :mod:`vtb.run.scaleout`."""
    tids = [_design_tids(config, d) for d in designs]
    todo = cases(config, samples, speeds, first_seed)
    controlled = []
    for t in tids:
        for _, _, cfg in todo:
            c = cfg.copy()
            c.tids = t
            controlled.append(c)
    runs = run_all([c for _, _, c in todo] + controlled, executor=executor, threads=threads, progress=progress, desc="vtb designs")
    n = len(todo)
    out = []
    for j, t in enumerate(tids):
        rows = []
        for (v, s, _), r0, r1 in zip(todo, runs[:n], runs[n * (j + 1):n * (j + 2)]):
            rows.append(_run_row(v, s, r0, r1))
        out.append(DesignEvaluation(rows, t))
    return out


def evaluate_design(
    config: Config,
    design,
    samples: Union[int, Sequence[int]] = 8,
    speeds: Optional[Sequence[float]] = None,
    first_seed: int = HELD_OUT_SEED0,
    threads: Optional[int] = None,
    progress: bool = False,
) -> DesignEvaluation:
    """Evaluates ``design`` (a :class:`vtb.TIDs`, or b_t, k_t, c_t with the count and positions
    of ``config.tids``, default :func:`vtb.tids_around`) on irregularity samples and speeds.

    ``samples``: a number N (seeds ``first_seed + i``, by default the held-out seeds) or the
    seeds themselves; ``speeds`` (m/s): default the configuration's own. Each case runs
    uncontrolled and with the design, all in one batch (the samples of a speed share one
    assembled model and run in lockstep). Returns the table of every index per case and the
    constraint-satisfaction rate (:class:`DesignEvaluation`). Several designs on the same
    cases: :func:`evaluate_designs`."""
    return evaluate_designs(config, [design], samples, speeds, first_seed, threads, progress)[0]


# ---------------------------------------------------------------------------- robust sweeps
@dataclasses.dataclass
class RobustSweep:
    """A TID grid swept over samples and speeds. ``sweeps``: ``[(speed, seed, SweepResult)]``,
    one ordinary sweep per case (same grid, its own uncontrolled run); ``statistic``: the
    default statistic of :meth:`table`; ``config``: the configuration (its dampers' count and
    positions)."""

    sweeps: list
    statistic: str
    config: Config

    @property
    def designs(self) -> list:
        """The grid's (b_t, k_t, c_t), in case order."""
        c = self.sweeps[0][2].columns
        i = np.flatnonzero(c["case"] > 0)
        return [(float(c["b_t"][j]), float(c["k_t"][j]), float(c["c_t"][j])) for j in i]

    def _rows(self, index: int) -> list:
        rows = []
        for v, s, sw in self.sweeps:
            c = sw.columns
            j = int(np.flatnonzero(c["case"] == index + 1)[0])
            err = c["error"][j] or next((e for e in c["error"][c["case"] == 0] if e), "")
            m0 = {m: c[m][c["case"] == 0][0] for m in METRICS}
            rows.append(_case_row(v, s, None, None, err) if err else _case_row(v, s, m0, {m: c[m][j] for m in METRICS}))
        return rows

    def evaluation(self, index: int) -> DesignEvaluation:
        """Design ``index`` (into :attr:`designs`) as a :class:`DesignEvaluation`."""
        b, k, c = self.designs[index]
        return DesignEvaluation(self._rows(index), dataclasses.replace(self.config.tids, inertance=b, stiffness=k, damping=c))

    def table(self, statistic_name: Optional[str] = None, speed: Optional[float] = None) -> dict:
        """Per design: numpy columns b_t, k_t, c_t and :func:`design_statistics` over the cases
        (of one ``speed`` if given), with ``statistic_name`` (default :attr:`statistic`)."""
        n = len(self.designs)
        return _rows_table(self.designs, [self._rows(i) for i in range(n)], statistic_name or self.statistic, speed)

    def best(self, statistic_name: Optional[str] = None, speed: Optional[float] = None) -> dict:
        """The feasible design (statistic constraints, :func:`design_statistics`) with the
        lowest statistic of a_rm/a_rm0, with its statistics."""
        return _best_of(self.table(statistic_name, speed))

    def to_pandas(self, statistic_name: Optional[str] = None, speed: Optional[float] = None):
        """:meth:`table` as a DataFrame, one row per design, units in ``attrs["units"]``."""
        t = self.table(statistic_name, speed)
        return frame(t, units_of(t))

    def to_parquet(self, path, statistic_name: Optional[str] = None, speed: Optional[float] = None) -> None:
        """Parquet export of :meth:`to_pandas`, units in its metadata (needs pyarrow)."""
        to_parquet(self.to_pandas(statistic_name, speed), path)


def sweep_over(config: Config, b_t, k_t, c_t, *, samples, speeds, statistic_name: str = "mean",
               out=None, threads: Optional[int] = None, progress=True, executor=None, chunk: Optional[int] = None) -> RobustSweep:
    """:func:`vtb.sweep` over samples and speeds (what it calls when given ``samples`` or
    ``speeds``): the grid and an uncontrolled run on every case and, with ``out`` (a
    directory), one journal per case, ``out/v<speed>_seed<seed>.csv``, so an interrupted study
    resumes. Every case runs in one batch (a speed's uncontrolled runs share one model, its
    controlled runs another), in lockstep groups on every core or in tasks on ``executor``
    (:mod:`vtb.run.scaleout`): one batch, not one per speed, so that the groups of all speeds
    share out the cores or workers evenly. A case is journaled as soon as it is known."""
    statistic([1.0], statistic_name)  # a bad name fails before any run
    config, grid_cases = plan(config, b_t, k_t, c_t)
    todo = cases(config, samples, speeds, DESIGN_SEED0)
    out_dir = None if out is None else Path(out)
    bar, report = None, progress if callable(progress) else None
    with contextlib.ExitStack() as stack:
        state = []  # [speed, seed, case config, journal, rows, cases to run]
        for v, s, cfg in todo:
            cfg.tids = config.tids
            journal, known = None, {}
            if out_dir is not None:
                make_folder(out_dir, "out")
                journal = out_dir / f"v{v:g}_seed{s}.csv"
                stack.enter_context(jr.lock(journal))
                known = jr.open_rows(journal, cfg, LAYOUT, kind="robust sweep")
            rows, left = jr.reuse(known, grid_cases, LAYOUT)
            state.append([v, s, cfg, journal, rows, left])
        total = len(todo) * len(grid_cases)
        done = total - sum(len(st[5]) for st in state)
        if progress is True:
            from tqdm.auto import tqdm

            bar = stack.enter_context(tqdm(total=total, initial=done, desc="vtb robust sweep", unit="run"))
        jobs = [(st, case) for st in state for case in st[5]]

        def finished(i, r):
            # each case's row journaled as soon as its lockstep group finishes
            nonlocal done
            st, case = jobs[i]
            row = case_rows([case], [r])
            if st[3] is not None:
                jr.append(st[3], row, LAYOUT)
            st[4].extend(row)
            done += 1
            if bar is not None:
                bar.update(done - bar.n)
            if report is not None:
                report(done, total)

        run_cases([case_config(st[2], c["b_t"], c["k_t"], c["c_t"]) for st, c in jobs], finished, executor=executor, threads=threads, chunk=chunk)
    return RobustSweep([(v, s, result_of(rows, cfg, LAYOUT, SweepResult, journal=j)) for v, s, cfg, j, rows, _ in state], statistic_name, config)


# ---------------------------------------------------------------------- robust optimisation
@dataclasses.dataclass
class RobustEvaluator(DesignEvaluator):
    """The robust evaluation (picklable): a design (b_t, k_t, c_t) runs on every case of
    ``todo`` (every design of a generation in one batch), its rows are the cases' rows against
    their uncontrolled ``baselines`` (:func:`_run_row`) and its F and G are
    :func:`robust_objectives` of them with ``statistic``."""

    config: Config
    todo: list
    baselines: list
    statistic: str
    n_obj = len(ARTICLE_OBJECTIVES)
    n_constr = len(CONSTRAINTS)

    def configs_of(self, x) -> list:
        out = []
        for _, _, cfg in self.todo:
            c = cfg.copy()
            c.tids = self.config.tids
            out.append(case_config(c, *x))
        return out

    def row_of(self, k: int, result) -> dict:
        return _run_row(self.todo[k][0], self.todo[k][1], self.baselines[k], result)

    def score(self, rows: list) -> tuple:
        return robust_objectives(rows, self.statistic)


@dataclasses.dataclass
class RobustOptimizationResult(OptimizationResult):
    """A robust optimisation. ``pareto``: numpy columns b_t, k_t, c_t and, per index,
    ``ratio_<metric>`` (the statistic of X/X0 over the cases), ``mean_<metric>``,
    ``sem_<metric>`` (standard error of the mean ratio), ``eta_<metric>`` = 1 − ratio, the
    comprehensive rail rate ``eta_r`` and ``satisfaction_rate``; ``baseline``: ``{(speed,
    seed): uncontrolled metrics}``; ``statistic``; ``evaluated``: ``{(b_t, k_t, c_t): case
    rows}`` of every design the optimiser ran (the per-speed optima are chosen among them)."""

    statistic: str = "mean"
    evaluated: dict = dataclasses.field(default_factory=dict)
    objective_columns = tuple(f"ratio_{m}" for m in ARTICLE_OBJECTIVES)

    def table(self) -> list:
        """One row per trade-off choice: the design and its statistics."""
        rows = []
        for label, i in self.trade_offs().items():
            rows.append(dict(choice=label, **{k: float(v[i]) for k, v in self.pareto.items()}))
        return rows

    def speeds(self) -> list:
        """The speeds of the cases (m/s)."""
        return sorted({v for v, _ in self.baseline})

    def evaluated_table(self, speed: Optional[float] = None) -> dict:
        """:func:`design_statistics` of every evaluated design (the cases of one ``speed``)."""
        designs = list(self.evaluated)
        return _rows_table(designs, [self.evaluated[d] for d in designs], self.statistic, speed)

    def best(self, speed: Optional[float] = None) -> dict:
        """Among every evaluated design, the feasible one with the lowest statistic of
        a_rm/a_rm0 over the cases (of one ``speed``: the optimal design per speed)."""
        return _best_of(self.evaluated_table(speed))

    def evaluation(self, design) -> DesignEvaluation:
        """The case rows of an evaluated design ((b_t, k_t, c_t) or a mapping of them)."""
        key = tuple(float(design[k]) for k in ("b_t", "k_t", "c_t")) if isinstance(design, Mapping) else tuple(map(float, design))
        if key not in self.evaluated:
            raise config_error("design", design, "was not evaluated by this optimisation")
        return DesignEvaluation(self.evaluated[key], dataclasses.replace(self.config.tids, inertance=key[0], stiffness=key[1], damping=key[2]))

    def histories(self, label: str = "best η_r"):
        raise VtbError("a robust optimisation has no single case: run vtb.simulate on a case of your choice")


def _pareto_columns(X: np.ndarray, rows_of: list, statistic_name: str) -> dict:
    """The columns of :class:`RobustOptimizationResult` for the designs X, by rising
    statistic of a_rm/a_rm0."""
    stats = ("ratio", "mean", "sem")
    if len(X):
        pareto = _rows_table([tuple(x) for x in X], rows_of, statistic_name, None)
    else:
        pareto = {k: np.array([]) for k in ["b_t", "k_t", "c_t", "satisfaction_rate"] + [f"{p}_{m}" for p in stats for m in REDUCED]}
    pareto.pop("feasible", None)
    for m in REDUCED:
        pareto[f"eta_{m}"] = 1.0 - pareto[f"ratio_{m}"]
    a, b, c = (pareto[f"eta_{m}"] for m in RAIL_RATE)
    pareto["eta_r"] = (a + b + c) / 3.0
    order = np.argsort(pareto[f"ratio_{A_RM}"])
    return {k: v[order] for k, v in pareto.items()}


def setup(config: Config, samples, speeds, statistic_name: str, warm_start, threads: Optional[int], executor, checkpoint) -> Setup:
    """The article's problem over samples and speeds (what :func:`vtb.optimize` solves when given
    ``samples`` or ``speeds``): the :class:`RobustEvaluator` of the cases (design seeds
    :data:`DESIGN_SEED0` + i at each speed) against their uncontrolled runs, hypervolumes with
    the reference point (1, 1), the uncontrolled level of both objectives. ``warm_start``: a
    :class:`RobustSweep` of the same configuration and cases; its uncontrolled runs are then the
    baselines (the same deterministic runs, not repeated) and its designs the points the first
    population is chosen from."""
    statistic([1.0], statistic_name)
    config = with_dampers(config)
    todo = cases(config, samples, speeds, DESIGN_SEED0)
    if warm_start is not None and not isinstance(warm_start, RobustSweep):
        raise config_error("warm_start", type(warm_start).__name__, "must be a RobustSweep (vtb.sweep with samples/speeds) for an optimisation over samples and speeds")
    if warm_start is not None:
        if [(v, s) for v, s, _ in warm_start.sweeps] != [(v, s) for v, s, _ in todo] or config_stamp(warm_start.config) != config_stamp(config):
            raise config_error("warm_start", "RobustSweep", "is a sweep of other samples, speeds or configuration")
        baselines = [sw.baseline for _, _, sw in warm_start.sweeps]  # the same deterministic runs: not repeated
    else:
        runs = run_all([c for _, _, c in todo], executor=executor, threads=threads)
        for (v, s, _), r in zip(todo, runs):
            if isinstance(r, BaseException):
                raise VtbError(f"the uncontrolled run at speed {v:g} m/s, seed {s} failed: {_error_text(r)}")
        baselines = [{m: float(r[m]) for m in METRICS} for r in runs]
    identity = checkpoint_identity(config, baselines, checkpoint, cases=[(v, s) for v, s, _ in todo], statistic=statistic_name)
    evaluator = RobustEvaluator(config, todo, baselines, statistic_name, threads=threads, executor=executor)
    initial = None
    if warm_start is not None:
        X0 = np.array(warm_start.designs).reshape(-1, 3)
        FG = []
        for i, x in enumerate(X0):
            rows = warm_start._rows(i)
            evaluator.cache[tuple(x)] = rows
            FG.append(robust_objectives(rows, statistic_name))
        initial = (X0, np.array([f for f, _ in FG]).reshape(-1, 2), np.array([g for _, g in FG]).reshape(-1, len(CONSTRAINTS)))

    def result(res, X, rows) -> RobustOptimizationResult:
        return RobustOptimizationResult(
            pareto=_pareto_columns(X, rows, statistic_name), baseline={(v, s): b for (v, s, _), b in zip(todo, baselines)}, moga=res,
            config=config, statistic=statistic_name, evaluated=dict(evaluator.cache),
        )

    return Setup(evaluator, identity, (1.0, 1.0), initial, result)
