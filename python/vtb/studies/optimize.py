"""Multi-objective optimisation over any fields and indices, and the article's TID problem
(§4.4, docs/model.md §9) as its preset.

``vtb.optimize(config, variables={path: (low, high, "log"|"linear")}, objectives=[index, ...],
constraints=[(index, bound), ...])`` minimises the named indices (:func:`vtb.index_names`) over
configuration fields named by their paths (:func:`vtb.set_field`), a bound being a number or
``"reference"`` (the value of the run with the ``reference`` fields set, e.g. ``{"tids":
None}``), written normalised as X/bound − 1 ≤ 0. Without ``variables`` it solves the article's
problem:

Objectives: the rail and slab acceleration amplitudes (a_rm, a_sm); constraints: a_rm, a_sm,
a_rRMS and a_rst below their uncontrolled values, written normalised as X/X0 − 1 ≤ 0; bounds
1 ≤ b_t ≤ 10 kg, 1e7 ≤ k_t ≤ 8e8 N/m, 10 ≤ c_t ≤ 5e3 N·s/m, k_t and c_t searched on a log scale
(they span decades). Each generation is one Rust batch call (all cores, GIL released).

Hypervolumes (history, ``stop_hv``) are those of the feasible first front in (a_rm, a_sm)
with the uncontrolled values (a_rm0, a_sm0) as reference point: every feasible design lies
below it, and it depends on the configuration only, so the hypervolumes of a cold and a
warm-started run of one configuration are comparable.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
from pathlib import Path
from typing import Optional, Union

import numpy as np

from .. import optim as moga
from ..config.fields import Config
from ..errors import VtbError, config_error, stale_file_error
from ..config.presets import tids_around
from ..run.scaleout import run_cases
from ..run.simulate import Result, simulate
from .grid import with_tids, get_field, index_names, set_field
from .journal import same_config
from ..article.tid_sweep import METRICS, REFERENCE, SweepResult, case_config, config_stamp, read_journal

#: (lower, upper) of b_t (kg), k_t (N/m), c_t (N·s/m): the article's bounds.
BOUNDS = ((1.0, 10.0), (1e7, 8e8), (10.0, 5e3))
LOG_SCALE = (False, True, True)
#: Constraint indices: (metric, against the uncontrolled value).
CONSTRAINTS = ("rail_acc_max", "slab_acc_max", "rail_acc_rms", "rail_acc_settle")
#: The article's problem in the terms of the generic one (what :func:`optimize` solves by default).
ARTICLE_VARIABLES = {"tids.b_t": (*BOUNDS[0], "linear"), "tids.k_t": (*BOUNDS[1], "log"), "tids.c_t": (*BOUNDS[2], "log")}
ARTICLE_OBJECTIVES = ("rail_acc_max", "slab_acc_max")
ARTICLE_CONSTRAINTS = tuple((m, "reference") for m in CONSTRAINTS)


def tid_problem(evaluate) -> moga.Problem:
    """The optimisation problem over (b_t, k_t, c_t) within :data:`BOUNDS`: two objectives and
    the :data:`CONSTRAINTS`, evaluated a generation at a time by ``evaluate``."""
    return moga.Problem(
        lower=[b[0] for b in BOUNDS], upper=[b[1] for b in BOUNDS], n_obj=2, n_constr=len(CONSTRAINTS),
        evaluate=evaluate, log_scale=np.array(LOG_SCALE),
    )


def checkpoint_identity(config: Config, baseline, checkpoint=None, **extra) -> dict:
    """What an optimisation's evaluations depend on, for its checkpoint: the configuration's
    stamp, a hash of its uncontrolled metrics (``baseline``) and any ``extra`` JSON values.
    When ``checkpoint`` (or its designs journal) already holds the stamp of the same
    configuration written by an earlier schema (:func:`vtb.journal.same_config`), that stamp is
    adopted, so a field added to the schema since does not make the checkpoint stale."""
    stamp = json.loads(config_stamp(config))
    if checkpoint is not None:
        saved = _saved_stamp(Path(checkpoint))
        if saved is not None and saved != stamp and same_config(saved, config):
            stamp = saved
    return {"vtb.optimize": {
        "config": stamp,
        "baseline": hashlib.sha256(json.dumps(baseline, sort_keys=True).encode()).hexdigest(),
        **extra,
    }}


def _saved_stamp(checkpoint: Path):
    """The configuration stamp of the identity a checkpoint (or, before its first generation,
    its designs journal) was written with; ``None`` if there is none to read (the optimiser
    then reports what is wrong with the file)."""
    identity = moga.saved_identity(checkpoint)
    journal = Path(str(checkpoint) + ".designs.jsonl")
    if identity is None and journal.exists():
        try:
            with open(journal) as f:
                identity = {"problem": json.loads(f.readline())}
        except (OSError, ValueError):
            return None
    try:
        return identity["problem"]["vtb.optimize"]["config"]
    except (TypeError, KeyError):
        return None


@dataclasses.dataclass
class DesignJournal:
    """The designs an optimisation has evaluated, by (b_t, k_t, c_t): ``cache`` in memory and,
    given ``path`` (JSON lines: the optimisation's identity, then one design per line with its
    rows), on disk, a design written as soon as all its runs finished, so that an interrupted
    generation resumes without running it again. A run is deterministic, so nothing depends on
    what the journal holds but the time it saves."""

    path: Optional[Path] = None
    cache: dict = dataclasses.field(default_factory=dict)

    def load(self, identity) -> None:
        """Reads ``path`` (its first line must be ``identity``) into the cache, or starts it."""
        if self.path is None:
            return
        if self.path.exists() and self.path.stat().st_size:
            lines = self.path.read_text().splitlines()
            if json.loads(lines[0]) != json.loads(json.dumps(identity)):
                raise stale_file_error("checkpoint", self.path, "holds the designs of another optimisation; delete it with its checkpoint to start afresh")
            for line in lines[1:]:
                try:
                    d = json.loads(line)
                except ValueError:  # a line cut short by a kill
                    continue
                self.cache[tuple(d["x"])] = d["rows"]
        else:
            self.path.write_text(json.dumps(identity) + "\n")

    def add(self, x, rows) -> None:
        self.cache[tuple(x)] = rows
        if self.path is not None:
            with open(self.path, "a") as f:
                f.write(json.dumps(dict(x=[float(v) for v in x], rows=rows)) + "\n")

    def run(self, X: np.ndarray, configs_of, row_of, threads: Optional[int], executor=None) -> None:
        """Runs every design of X not yet known, in one batch (or tasks on ``executor``,
        :mod:`vtb.scaleout`): ``configs_of(x)`` gives its configurations, ``row_of(k, result)``
        the row of its k-th run (a metrics dict or an exception); a design is added once all
        its runs are in."""
        todo = [x for x in dict.fromkeys(map(tuple, X)) if x not in self.cache]
        if not todo:
            return
        per = [configs_of(np.array(x)) for x in todo]
        owner = [(d, k) for d, cs in enumerate(per) for k in range(len(cs))]
        got = [[None] * len(cs) for cs in per]

        def done(i, r):
            d, k = owner[i]
            got[d][k] = row_of(k, r)
            if all(row is not None for row in got[d]):
                self.add(todo[d], got[d])

        run_cases([c for cs in per for c in cs], done, executor=executor, threads=threads)


@dataclasses.dataclass
class Objectives:
    """The evaluation of one generation (picklable, for executors): X rows (the variables'
    values, in the order of ``paths``) → F (the ``objectives``' indices), G = X/bound − 1 for
    each ``(index, bound)`` of ``constraints`` (X − bound for a bound ≤ 0). A failed run counts
    as infeasible (G = ∞) with F = ``failed``. ``designs`` keeps every evaluated design's
    ``record`` indices (``None`` for a failed run) and journals them beside a checkpoint."""

    config: Config
    paths: tuple
    objectives: tuple
    constraints: tuple
    record: tuple
    failed: tuple
    threads: Optional[int] = None
    designs: DesignJournal = dataclasses.field(default_factory=DesignJournal)
    executor: object = None

    @property
    def cache(self) -> dict:
        return self.designs.cache

    def config_of(self, x) -> Config:
        cfg = self.config.copy()
        for p, v in zip(self.paths, x):
            set_field(cfg, p, float(v))
        cfg.output.indices = list(self.record)
        return cfg

    def fg(self, m: Optional[dict]) -> tuple:
        """F and G of one run's recorded indices (``None``: a failed run)."""
        if m is None:
            return list(self.failed), [math.inf] * len(self.constraints)
        return [m[k] for k in self.objectives], [m[k] / b - 1.0 if b > 0 else m[k] - b for k, b in self.constraints]

    def __call__(self, X: np.ndarray):
        X = np.asarray(X, dtype=float)
        self.designs.run(X, lambda x: [self.config_of(x)],
                         lambda _, r: None if isinstance(r, BaseException) else {m: float(r[m]) for m in self.record}, self.threads, self.executor)
        F = np.empty((len(X), len(self.objectives)))
        G = np.empty((len(X), len(self.constraints)))
        for i, x in enumerate(X):
            F[i], G[i] = self.fg(self.cache[tuple(x)][0])
        return F, G


def tid_objectives(config: Config, baseline: dict, threads: Optional[int] = None, executor=None) -> Objectives:
    """The article's problem (:data:`ARTICLE_VARIABLES`, :data:`ARTICLE_OBJECTIVES`, the
    :data:`CONSTRAINTS` against the uncontrolled ``baseline``), recording :data:`METRICS`; a
    failed run scores 10 × the uncontrolled objectives."""
    return Objectives(config, tuple(ARTICLE_VARIABLES), ARTICLE_OBJECTIVES, tuple((m, baseline[m]) for m in CONSTRAINTS), METRICS,
                      tuple(10 * baseline[m] for m in ARTICLE_OBJECTIVES), threads, executor=executor)


def _problem_spec(config: Config, variables, objectives, constraints, reference) -> tuple:
    """Checked variables [(path, low, high, log)], objectives, constraints [(index, bound)]
    and the reference run's indices (or None); every bad entry raises ConfigError naming it."""
    if not isinstance(variables, dict) or not variables:
        raise config_error("variables", variables, "must be a non-empty mapping {field path: (low, high, 'log' | 'linear')}")
    spec = []
    for path, bounds in variables.items():
        get_field(with_tids(config, path), path)
        if not isinstance(bounds, (tuple, list)) or len(bounds) not in (2, 3):
            raise config_error(f"variables[{path!r}]", bounds, "must be (low, high) or (low, high, 'log' | 'linear')")
        lo, hi, scale = (*bounds, "linear") if len(bounds) == 2 else bounds
        if scale not in ("log", "linear"):
            raise config_error(f"variables[{path!r}]", scale, "the scale must be 'log' or 'linear'")
        for v in (lo, hi):
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise config_error(f"variables[{path!r}]", v, "bounds must be finite numbers")
        if not lo < hi or (scale == "log" and lo <= 0):
            raise config_error(f"variables[{path!r}]", (lo, hi), "needs low < high" + (" and low > 0 on a log scale" if scale == "log" else ""))
        spec.append((path, float(lo), float(hi), scale == "log"))
    names = index_names(config)
    if isinstance(objectives, str) or not objectives:
        raise config_error("objectives", objectives, "must be a non-empty list of index names")
    for m in objectives:
        if m not in names:
            raise config_error("objectives", m, f"not an index of this configuration (known: {', '.join(names)})")
    cons = []
    for c in constraints or ():
        if not isinstance(c, (tuple, list)) or len(c) != 2 or c[0] not in names:
            raise config_error("constraints", c, f"each must be (index, bound) with an index of this configuration (known: {', '.join(names)})")
        if not (c[1] == "reference" or (isinstance(c[1], (int, float)) and not isinstance(c[1], bool) and math.isfinite(c[1]))):
            raise config_error("constraints", c, "the bound must be a finite number or 'reference'")
        cons.append((c[0], c[1]))
    ref = None
    if reference is not None:
        cfg = config.copy()
        for path, value in reference.items():
            set_field(cfg, path, value)
        ref = simulate(cfg).metrics()
    elif any(b == "reference" for _, b in cons):
        raise config_error("reference", None, "a constraint bounded by 'reference' needs the reference run's fields, e.g. {'tids': None}")
    cons = [(m, ref[m] if b == "reference" else float(b)) for m, b in cons]
    return spec, tuple(objectives), tuple(cons), ref


@dataclasses.dataclass
class ParetoResult:
    """The returned (feasible, non-dominated) designs of :func:`optimize` over user-named
    variables: numpy columns in ``pareto`` — each variable by its path and every recorded index
    (SI units) —, ``objectives`` and ``constraints`` as solved, the ``reference`` run's indices
    (or None), the optimiser's :class:`vtb.moga.Result` and the ``config``."""

    pareto: dict
    variables: tuple
    objectives: tuple
    constraints: tuple
    reference: Optional[dict]
    moga: moga.Result
    config: Config

    def __len__(self) -> int:
        return len(self.pareto[self.variables[0]])

    def to_pandas(self):
        """The designs as a DataFrame, one row each, units in ``attrs["units"]`` (needs pandas)."""
        from ..run.tables import frame, units_of

        return frame(self.pareto, units_of(self.pareto))

    def to_parquet(self, path) -> None:
        """Parquet export of :meth:`to_pandas` (needs pyarrow)."""
        from ..run.tables import to_parquet

        to_parquet(self.to_pandas(), path)


def _optimize_fields(config, variables, objectives, constraints, reference, report, *, pop_size, n_gen, seed, algorithm, threads, executor,
                     progress, stop_hv, checkpoint, **options) -> ParetoResult:
    """:func:`optimize` over user-named variables and indices (see there)."""
    spec, objectives, cons, ref = _problem_spec(config, variables, objectives, constraints, reference)
    paths = tuple(p for p, *_ in spec)
    base = config
    if any(p.startswith("tids") for p in paths) and config.tids is None:
        base = with_tids(config, next(p for p in paths if p.startswith("tids")))
    record = tuple(dict.fromkeys([*objectives, *(m for m, _ in cons), *(report or ())]))
    names = index_names(config)
    for m in record:
        if m not in names:
            raise config_error("report", m, f"not an index of this configuration (known: {', '.join(names)})")
    failed = tuple(10 * abs(ref[m]) if ref and ref[m] else 1e300 for m in objectives)
    evaluate = Objectives(base, paths, objectives, tuple(cons), record, failed, threads, executor=executor)
    problem = moga.Problem(lower=[s[1] for s in spec], upper=[s[2] for s in spec], n_obj=len(objectives), n_constr=len(cons),
                           evaluate=evaluate, log_scale=np.array([s[3] for s in spec]))
    identity = checkpoint_identity(base, ref, checkpoint, paths=list(paths), objectives=list(objectives), constraints=[list(c) for c in cons], record=list(record))
    if checkpoint is not None:
        evaluate.designs.path = Path(str(checkpoint) + ".designs.jsonl")
        evaluate.designs.load(identity)
    hv_ref = tuple(ref[m] for m in objectives) if ref is not None and len(objectives) == 2 else None
    res = moga.minimize(problem, algorithm, pop_size=pop_size, n_gen=n_gen, seed=seed, progress=progress, hv_ref=hv_ref,
                        stop_hv=stop_hv, checkpoint=checkpoint, checkpoint_identity=identity, **options)
    X = res.X[res.feasible] if np.any(res.feasible) else res.X[:0]
    missing = [x for x in X if tuple(x) not in evaluate.cache]
    if missing:
        evaluate(np.array(missing))
    rows = [evaluate.cache[tuple(x)][0] for x in X]
    pareto = {p: X[:, j] for j, p in enumerate(paths)}
    pareto.update({m: np.array([r[m] for r in rows]) for m in record})
    order = np.argsort(pareto[objectives[0]], kind="stable")
    return ParetoResult({k: v[order] for k, v in pareto.items()}, paths, objectives, tuple(cons), ref, res, base)


@dataclasses.dataclass
class OptimizationResult:
    """``pareto``: numpy columns ``b_t``, ``k_t``, ``c_t`` and every metric of the returned
    (feasible, non-dominated) set, with reduction rates ``eta_<metric>`` = (X0 − X)/X0 and the
    comprehensive rail rate ``eta_r``; ``baseline``: the uncontrolled metrics; ``moga``: the
    optimiser's :class:`vtb.moga.Result` (history, final population); ``config``."""

    pareto: dict
    baseline: dict
    moga: moga.Result
    config: Config
    #: The pareto columns of the two objectives (what the trade-off choices compare).
    objective_columns = ("rail_acc_max", "slab_acc_max")

    def __len__(self) -> int:
        return len(self.pareto["b_t"])

    def trade_offs(self, weights=(0.5, 0.5)) -> dict:
        """Trade-off selection on the objectives (a_rm, a_sm): the knee, the point nearest the ideal, the
        weighted achievement-scalarising choice, and the best η_r. Returns
        ``{label: index into pareto}``."""
        if len(self) == 0:
            raise VtbError("the optimisation found no feasible solution: raise the budget (pop_size, n_gen)")
        F = np.column_stack([self.pareto[k] for k in self.objective_columns])
        return {
            "knee": moga.knee_point(F),
            "nearest to ideal": moga.min_distance_to_ideal(F),
            f"ASF {weights[0]:g}/{weights[1]:g}": moga.asf(F, weights),
            "best η_r": int(np.argmax(self.pareto["eta_r"])),
        }

    def to_pandas(self):
        """The returned set (:attr:`pareto`) as a DataFrame, one row per design, units in
        ``attrs["units"]`` (needs pandas)."""
        from ..run.tables import frame, units_of

        return frame(self.pareto, units_of(self.pareto))

    def to_parquet(self, path) -> None:
        """Parquet export of :meth:`to_pandas`, units in its metadata (needs pyarrow)."""
        from ..run.tables import to_parquet

        to_parquet(self.to_pandas(), path)

    def table(self) -> list:
        """Rows shaped like the article's Table 3, one per trade-off choice."""
        rows = []
        for label, i in self.trade_offs().items():
            p = self.pareto
            rows.append(dict(
                choice=label, b_t=p["b_t"][i], k_t=p["k_t"][i], c_t=p["c_t"][i],
                rail_acc_max=p["rail_acc_max"][i], eta_rail_acc_max=p["eta_rail_acc_max"][i],
                rail_acc_rms=p["rail_acc_rms"][i], eta_rail_acc_rms=p["eta_rail_acc_rms"][i],
                rail_acc_settle=p["rail_acc_settle"][i], eta_rail_acc_settle=p["eta_rail_acc_settle"][i],
                eta_r=p["eta_r"][i], slab_acc_max=p["slab_acc_max"][i], eta_slab_acc_max=p["eta_slab_acc_max"][i],
            ))
        return rows

    def chosen(self, label: str = "best η_r") -> dict:
        """(b_t, k_t, c_t) of a trade-off choice."""
        i = self.trade_offs()[label]
        return {k: float(self.pareto[k][i]) for k in ("b_t", "k_t", "c_t")}

    def histories(self, label: str = "best η_r") -> tuple[Result, Result]:
        """Full runs of the uncontrolled and the chosen controlled case (Fig. 8, car body)."""
        c = self.chosen(label)
        return simulate(case_config(self.config, math.nan, 0, 0)), simulate(case_config(self.config, c["b_t"], c["k_t"], c["c_t"]))


def warm_start_points(warm_start: Union[SweepResult, str, Path], config: Config, baseline: dict) -> tuple:
    """The successful TID cases of a sweep (a :class:`~vtb.tid_sweep.SweepResult` or a journal
    path) as ``(X, F, G, metrics)`` of this optimisation: X rows (b_t, k_t, c_t), F and G as
    :func:`tid_objectives` computes them against ``baseline``, and each case's metrics. The sweep
    must be of ``config`` (same stamp) and its uncontrolled run must equal ``baseline``; the
    optimiser keeps the points within :data:`BOUNDS`. The points come sorted by (b_t, k_t,
    c_t), so a journal read back and the sweep that wrote it give the same warm start."""
    sw = warm_start if isinstance(warm_start, SweepResult) else read_journal(warm_start, field="warm_start")
    label = "SweepResult" if isinstance(warm_start, SweepResult) else str(warm_start)
    if config_stamp(sw.config) != config_stamp(config):
        raise config_error("warm_start", label, "is a sweep of another configuration")
    if sw.baseline != {m: baseline[m] for m in METRICS}:
        reason = "its uncontrolled run differs from this configuration's (a sweep computed by another vtb version?)"
        if sw.journal is not None:  # the journal's results are stale: --force sets it aside and reruns it
            raise stale_file_error("warm_start", sw.journal, reason)
        raise config_error("warm_start", label, reason)
    c, ok = sw.columns, np.flatnonzero(sw.controlled)
    # In (b_t, k_t, c_t) order, whatever order the journal's lines are in: the first population
    # (and a checkpoint's identity) must not depend on which cases a sweep ran first.
    ok = ok[np.lexsort((c["c_t"][ok], c["k_t"][ok], c["b_t"][ok]))]
    X = np.column_stack([c["b_t"][ok], c["k_t"][ok], c["c_t"][ok]])
    metrics = [{m: float(c[m][i]) for m in METRICS} for i in ok]
    FG = [tid_objectives(config, baseline).fg(r) for r in metrics]
    return X, np.array([f for f, _ in FG]).reshape(-1, 2), np.array([g for _, g in FG]).reshape(-1, len(CONSTRAINTS)), metrics


def optimize(
    config: Config,
    *,
    pop_size: int = 100,
    n_gen: int = 100,
    seed: int = 0,
    algorithm: str = "nsga2",
    threads: Optional[int] = None,
    executor=None,
    progress: bool = True,
    warm_start: Union[SweepResult, str, Path, None] = None,
    stop_hv: Optional[tuple] = None,
    checkpoint: Union[str, Path, None] = None,
    samples=None,
    speeds=None,
    statistic: str = "mean",
    variables: Optional[dict] = None,
    objectives=None,
    constraints=None,
    reference: Optional[dict] = None,
    report=None,
    **options,
) -> Union[OptimizationResult, ParetoResult]:
    """**Over any fields and indices** (``variables`` given): minimises ``objectives`` (index
    names, :func:`vtb.index_names`) over ``variables`` = {field path: (low, high, "log" |
    "linear")} (paths as in :func:`vtb.study`) subject to ``constraints`` = [(index, bound)]
    (X/bound − 1 ≤ 0; a bound ``"reference"`` is the index of the run with the ``reference``
    fields set, e.g. ``{"tids": None}``); ``report`` names further indices to record for the
    returned designs. Every name, path and bound is checked before any run. The budget,
    algorithm, executor, ``stop_hv`` (two objectives and a reference run: its objectives are
    the hypervolume's reference point) and ``checkpoint`` (with its designs journal) work as
    below. Returns a :class:`ParetoResult`. The article's problem below is this one with
    :data:`ARTICLE_VARIABLES`, :data:`ARTICLE_OBJECTIVES`, :data:`ARTICLE_CONSTRAINTS` and the
    reference ``{"tids": None}``, and gives the same designs (tests/test_studies.py).

    **The article's problem** (no ``variables``): optimises the dampers of ``config`` (default
    :func:`vtb.tids_around`) for (a_rm, a_sm)
    under the article's constraints and bounds. ``algorithm``: ``"nsga2"`` or ``"gamultiobj"``
    (see :mod:`vtb.moga`); ``executor``: run each generation's designs as tasks on it
    (:mod:`vtb.scaleout`) instead of the in-process Rust batch; every design is journaled beside
    a ``checkpoint`` as soon as its runs are in, either way. The defaults are the article's cold budget:
    population 100 × 100 generations from a random start, no early stop.

    ``warm_start``: a sweep of the same configuration (a :class:`~vtb.tid_sweep.SweepResult`
    or the path of its journal). Its successful cases within :data:`BOUNDS` are the already
    evaluated points the first population is chosen from (``initial`` of
    :func:`vtb.moga.minimize`); they cost no run. ``stop_hv=(tol, window)``: stop once the
    hypervolume (module docstring) moved by less than ``tol`` relative over ``window``
    generations; ``n_gen`` stays the cap. The history (``result.moga.history``) always records
    the hypervolume and the evaluations, whatever the stop.

    ``checkpoint``: a file holding the optimiser's state after every generation; a run given an
    existing one resumes after its last generation and ends with the same result as an
    uninterrupted run (see :func:`vtb.moga.minimize`). It is tied to this problem — the
    algorithm, budget, options, seed, warm-start points, ``stop_hv``, and hashes of the
    configuration and of its uncontrolled metrics — and refused for another.

    **Over samples and speeds** (``samples=N`` or a list of seeds, ``speeds=[...]`` in m/s;
    docs/robust.md): every design runs on every case (the design seeds
    :data:`vtb.robust.DESIGN_SEED0` + i at each speed; ``samples`` None: the configuration's
    own seed), all of a generation in one batch. The objectives become the ``statistic``
    (``"mean"``, ``"max"``, ``"pNN"``, …) over the cases of a_rm/a_rm0 and a_sm/a_sm0, each
    against the uncontrolled run of the same case, and the constraints statistic(X/X0) − 1 ≤ 0
    (:func:`vtb.robust.robust_objectives`); the hypervolume's reference point is (1, 1).
    Returns a :class:`vtb.robust.RobustOptimizationResult`; ``warm_start`` must then be a
    :class:`vtb.robust.RobustSweep` of the same cases.
    """
    if variables is not None:
        if samples is not None or speeds is not None or warm_start is not None:
            raise config_error("variables", list(variables), "samples, speeds and warm_start belong to the article's problem; a study over other fields runs one case")
        return _optimize_fields(config, variables, objectives, constraints, reference, report, pop_size=pop_size, n_gen=n_gen, seed=seed,
                                algorithm=algorithm, threads=threads, executor=executor, progress=progress, stop_hv=stop_hv,
                                checkpoint=checkpoint, **options)
    if objectives is not None or constraints is not None or reference is not None or report is not None:
        raise config_error("variables", None, "objectives, constraints, reference and report need variables={path: (low, high, scale)}")
    if samples is not None or speeds is not None:
        from ..article import robust

        return robust.optimize_over(
            config, samples=samples, speeds=speeds, statistic_name=statistic, pop_size=pop_size, n_gen=n_gen, seed=seed,
            algorithm=algorithm, threads=threads, progress=progress, warm_start=warm_start, stop_hv=stop_hv, checkpoint=checkpoint,
            executor=executor, **options,
        )
    if config.tids is None:
        config = config.copy()
        config.tids = tids_around(config)
    base_run = simulate(case_config(config, math.nan, 0, 0))
    baseline = base_run.metrics()
    # Executor workers run one case at a time each.
    evaluate = tid_objectives(config, baseline, threads, executor)
    initial = None
    if warm_start is not None:
        X0, F0, G0, metrics = warm_start_points(warm_start, config, baseline)
        evaluate.cache.update((tuple(x), [m]) for x, m in zip(X0, metrics))
        initial = (X0, F0, G0)
    problem = tid_problem(evaluate)
    identity = checkpoint_identity(config, baseline, checkpoint)
    if checkpoint is not None:
        evaluate.designs.path = Path(str(checkpoint) + ".designs.jsonl")
        evaluate.designs.load(identity)
    res = moga.minimize(
        problem, algorithm, pop_size=pop_size, n_gen=n_gen, seed=seed, progress=progress,
        hv_ref=(baseline["rail_acc_max"], baseline["slab_acc_max"]), initial=initial, stop_hv=stop_hv,
        checkpoint=checkpoint, checkpoint_identity=identity, **options,
    )
    X = res.X[res.feasible] if np.any(res.feasible) else res.X[:0]
    missing = [x for x in X if tuple(x) not in evaluate.cache]
    if missing:
        evaluate(np.array(missing))
    rows = [evaluate.cache[tuple(x)][0] for x in X]
    pareto = {"b_t": X[:, 0], "k_t": X[:, 1], "c_t": X[:, 2]}
    for m in METRICS:
        pareto[m] = np.array([r[m] for r in rows])
        pareto["eta_" + m] = np.array([(baseline[m] - r[m]) / baseline[m] if baseline[m] else np.nan for r in rows])
    pareto["eta_r"] = (pareto["eta_rail_acc_max"] + pareto["eta_rail_acc_rms"] + pareto["eta_rail_acc_settle"]) / 3.0
    order = np.argsort(pareto["rail_acc_max"])
    pareto = {k: v[order] for k, v in pareto.items()}
    return OptimizationResult(pareto=pareto, baseline=baseline, moga=res, config=config)
