"""The article's optimisation (§4.4, docs/model.md §9) and :func:`vtb.optimize`, whose default
problem it is: the dampers' b_t, k_t, c_t (:mod:`~vtb.article.tid_problem`) for the rail and slab
acceleration amplitudes (a_rm, a_sm) under the article's constraints, each X/X0 − 1 ≤ 0 against
the uncontrolled run, solved by the generic optimiser (:func:`vtb.studies.optimize.solve`)
through one of two evaluators: one case per design, or the robust evaluation over samples and
speeds (:class:`vtb.article.robust.RobustEvaluator`). Given ``variables``, :func:`optimize` is
the generic optimisation over any fields and indices (:func:`vtb.studies.optimize.optimize_fields`).

Hypervolumes (history, ``stop_hv``) are those of the feasible first front in (a_rm, a_sm) with
the uncontrolled values (a_rm0, a_sm0) as reference point (over samples and speeds: (1, 1)):
every feasible design lies below it, and it depends on the configuration only, so the
hypervolumes of a cold and a warm-started run of one configuration are comparable.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Optional, Union

import numpy as np

from . import robust
from ..config import args
from ..config.fields import Config
from ..optim.driver import check_budget
from ..errors import check_folder, config_error, stale_file_error
from ..run.indices import ARTICLE_OBJECTIVES, CONSTRAINTS, METRICS, RAIL_RATE
from ..run.simulate import simulate
from ..studies.journal import config_stamp
from ..studies.optimize import ParetoResult, checkpoint_identity, optimize_fields, solve
from .tid_problem import BOUNDS, LOG_SCALE, OptimizationResult, Setup, SweepResult, case_config, read_journal, tid_objectives, with_dampers


def warm_start_points(warm_start: Union[SweepResult, str, Path], config: Config, baseline: dict) -> tuple:
    """The successful TID cases of a sweep (a :class:`~vtb.article.tid_problem.SweepResult` or a journal
    path) as ``(X, F, G, metrics)`` of this optimisation: X rows (b_t, k_t, c_t), F and G as
    :func:`tid_objectives` computes them against ``baseline``, and each case's metrics. The sweep
    must be of ``config`` (same stamp) and its uncontrolled run must equal ``baseline``; the
    optimiser keeps the points within :data:`~vtb.article.tid_problem.BOUNDS`. The points come sorted by (b_t, k_t,
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


def single_case(config: Config, warm_start, threads: Optional[int], executor, checkpoint) -> Setup:
    """The article's problem on the configuration's own case: one :func:`~vtb.article.tid_problem.tid_objectives`
    evaluation per design against the uncontrolled run, warm-started from a sweep
    (:func:`warm_start_points`)."""
    config = with_dampers(config)
    baseline = simulate(case_config(config, math.nan, 0, 0)).metrics()
    # Executor workers run one case at a time each.
    evaluator = tid_objectives(config, baseline, threads, executor)
    initial = None
    if warm_start is not None:
        X0, F0, G0, metrics = warm_start_points(warm_start, config, baseline)
        evaluator.cache.update((tuple(x), [m]) for x, m in zip(X0, metrics))
        initial = (X0, F0, G0)

    def result(res, X, rows) -> OptimizationResult:
        rows = [r[0] for r in rows]
        pareto = {"b_t": X[:, 0], "k_t": X[:, 1], "c_t": X[:, 2]}
        for m in METRICS:
            pareto[m] = np.array([r[m] for r in rows])
            pareto["eta_" + m] = np.array([(baseline[m] - r[m]) / baseline[m] if baseline[m] else np.nan for r in rows])
        a, b, c = (pareto[f"eta_{m}"] for m in RAIL_RATE)
        pareto["eta_r"] = (a + b + c) / 3.0
        order = np.argsort(pareto[ARTICLE_OBJECTIVES[0]])
        return OptimizationResult(pareto={k: v[order] for k, v in pareto.items()}, baseline=baseline, moga=res, config=config)

    return Setup(evaluator, checkpoint_identity(config, baseline, checkpoint), tuple(baseline[m] for m in ARTICLE_OBJECTIVES), initial, result)


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
    (see :mod:`vtb.optim`); ``executor``: run each generation's designs as tasks on it
    (:mod:`vtb.run.scaleout`) instead of the in-process Rust batch; every design is journaled beside
    a ``checkpoint`` as soon as its runs are in, either way. The defaults are the article's cold budget:
    population 100 × 100 generations from a random start, no early stop.

    ``warm_start``: a sweep of the same configuration (a :class:`~vtb.SweepResult`
    or the path of its journal). Its successful cases within :data:`BOUNDS` are the already
    evaluated points the first population is chosen from (``initial`` of
    :func:`vtb.optim.minimize`); they cost no run. ``stop_hv=(tol, window)``: stop once the
    hypervolume (module docstring) moved by less than ``tol`` relative over ``window``
    generations; ``n_gen`` stays the cap. The history (``result.moga.history``) always records
    the hypervolume and the evaluations, whatever the stop.

    ``checkpoint``: a file holding the optimiser's state after every generation; a run given an
    existing one resumes after its last generation and ends with the same result as an
    uninterrupted run (see :func:`vtb.optim.minimize`). It is tied to this problem — the
    algorithm, budget, options, seed, warm-start points, ``stop_hv``, and hashes of the
    configuration and of its uncontrolled metrics — and refused for another.

    **Over samples and speeds** (``samples=N`` or a list of seeds, ``speeds=[...]`` in m/s;
    docs/robust.md): every design runs on every case (the design seeds
    :data:`vtb.article.robust.DESIGN_SEED0` + i at each speed; ``samples`` None: the configuration's
    own seed), all of a generation in one batch. The objectives become the ``statistic``
    (``"mean"``, ``"max"``, ``"pNN"``, …) over the cases of a_rm/a_rm0 and a_sm/a_sm0, each
    against the uncontrolled run of the same case, and the constraints statistic(X/X0) − 1 ≤ 0
    (:func:`vtb.article.robust.robust_objectives`, the :class:`~vtb.article.robust.RobustEvaluator`
    in place of the single case's); the hypervolume's reference point is (1, 1).
    Returns a :class:`vtb.article.robust.RobustOptimizationResult`; ``warm_start`` must then be a
    :class:`vtb.article.robust.RobustSweep` of the same cases.
    """
    check_budget(pop_size, n_gen, seed, algorithm)
    if not isinstance(config, Config):
        raise config_error("config", type(config).__name__, "expected a vtb.Config")
    args.threads(threads)
    checkpoint_path = args.path("checkpoint", checkpoint, none=True)
    if checkpoint_path is not None:
        check_folder(checkpoint_path.parent, "checkpoint")  # before any run
    if not (isinstance(progress, bool) or callable(progress)):
        raise config_error("progress", progress, "must be True, False or a callable")
    if variables is not None:
        if samples is not None or speeds is not None or warm_start is not None:
            raise config_error("variables", list(variables), "samples, speeds and warm_start belong to the article's problem; a study over other fields runs one case")
        return optimize_fields(config, variables, objectives, constraints, reference, report, pop_size=pop_size, n_gen=n_gen, seed=seed,
                               algorithm=algorithm, threads=threads, executor=executor, progress=progress, stop_hv=stop_hv,
                               checkpoint=checkpoint, **options)
    if objectives is not None or constraints is not None or reference is not None or report is not None:
        raise config_error("variables", None, "objectives, constraints, reference and report need variables={path: (low, high, scale)}")
    if samples is not None or speeds is not None:
        problem = robust.setup(config, samples, speeds, statistic, warm_start, threads, executor, checkpoint)
    else:
        problem = single_case(config, warm_start, threads, executor, checkpoint)
    res, X, rows = solve(problem.evaluator, [b[0] for b in BOUNDS], [b[1] for b in BOUNDS], LOG_SCALE, algorithm=algorithm,
                         pop_size=pop_size, n_gen=n_gen, seed=seed, progress=progress, hv_ref=problem.hv_ref, initial=problem.initial,
                         stop_hv=stop_hv, checkpoint=checkpoint, identity=problem.identity, **options)
    return problem.result(res, X, rows)
