"""The article's TID problem (§4.2–4.4, docs/model.md §9): the dampers' b_t, k_t, c_t on the
configuration's ``tids`` (default :func:`vtb.tids_around`), their bounds, the configuration of
one case, the journal layout of a sweep and its result, and the optimisation's single-case
evaluator and result. :mod:`~vtb.article.tid_sweep` and :mod:`~vtb.article.tid_optimize` solve
it; :mod:`~vtb.article.robust` judges its designs over samples and speeds.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
from pathlib import Path
from typing import Callable, NamedTuple, Optional, Sequence, Union

import numpy as np

from ..config.fields import Config
from ..config.presets import tids_around
from ..errors import VtbError, config_error
from ..optim import Result as OptimResult
from ..optim import asf, knee_point, min_distance_to_ideal
from ..run.indices import A_RM, A_SM, ARTICLE_OBJECTIVES, CONSTRAINTS, METRICS, RAIL_RATE, index_names
from ..run.simulate import Result, simulate
from ..run.tables import frame, to_parquet, units_of
from ..studies import grid as studies
from ..studies import journal as jr
from ..studies.grid import StudyResult, rows_of
from ..studies.optimize import CaseEvaluator, DesignEvaluator

#: (lower, upper) of b_t (kg), k_t (N/m), c_t (N·s/m): the article's bounds; k_t and c_t are
#: searched on a log scale (they span decades).
BOUNDS = ((1.0, 10.0), (1e7, 8e8), (10.0, 5e3))
LOG_SCALE = (False, True, True)
#: The article's problem in the terms of the generic one (what :func:`vtb.optimize` solves by default).
ARTICLE_VARIABLES = {"tids.b_t": (*BOUNDS[0], "linear"), "tids.k_t": (*BOUNDS[1], "log"), "tids.c_t": (*BOUNDS[2], "log")}
ARTICLE_CONSTRAINTS = tuple((m, "reference") for m in CONSTRAINTS)
#: The journal's layout: the parameters (keys) and :data:`~vtb.run.indices.METRICS`.
LAYOUT = jr.Layout(("b_t", "k_t", "c_t"), METRICS)
COLUMNS = ("case",) + LAYOUT.columns
#: The columns of a sweep journal: those of a result but the case number (rows are keyed by
#: their parameters).
JOURNAL_COLUMNS = LAYOUT.columns
#: The uncontrolled reference case: the structure without dampers.
REFERENCE = {"tids": None}


@dataclasses.dataclass
class SweepResult(StudyResult):
    """A finished sweep (a :class:`vtb.studies.StudyResult` over b_t, k_t, c_t): numpy columns ``case`` (0 = the uncontrolled baseline), ``b_t`` (kg),
    ``k_t`` (N/m), ``c_t`` (N·s/m) (NaN for the baseline), every metric of :data:`METRICS`
    (SI units; NaN where the case failed) and ``error`` (empty, or the failure's type and
    message). ``config``: the swept configuration (its ``tids`` give count and positions)."""

    variables: tuple = LAYOUT.keys
    indices: tuple = METRICS

    @property
    def baseline(self) -> dict:
        """Metrics of the uncontrolled run (case 0)."""
        return self.reference

    def _require_controlled(self) -> np.ndarray:
        ok = self.controlled
        if not ok.any():
            raise VtbError("the sweep has no successful TID case")
        return ok

    @property
    def controlled(self) -> np.ndarray:
        """Boolean mask of the successful TID cases."""
        return (self.columns["case"] > 0) & (self.columns["error"] == "")

    # ------------------------------------------------------------------ analyses
    def best_per_inertance(self) -> dict:
        """Per b_t, the case minimising the rail acceleration amplitude a_rm (article Fig. 5,
        Table 2): numpy columns ``b_t``, ``k_t``, ``c_t``, the rail's a_rm, a_rRMS and a_rst
        (:data:`~vtb.run.indices.RAIL_RATE`), their reduction rates ``eta_*`` against the
        baseline, the comprehensive rate ``eta_r``, a_sm there and its change against the
        baseline, ``slab_acc_min`` (the lowest a_sm of any case with that b_t) and
        ``working_frequency`` f_t = sqrt(k_t/b_t)/2π (Hz)."""
        c, ok, base = self.columns, self._require_controlled(), self.baseline
        rows = []
        for b in np.unique(c["b_t"][ok]):
            sel = np.flatnonzero(ok & (c["b_t"] == b))
            i = sel[np.argmin(c[A_RM][sel])]
            red = {k: (base[k] - c[k][i]) / base[k] for k in RAIL_RATE}
            row = dict(b_t=b, k_t=c["k_t"][i], c_t=c["c_t"][i])
            row.update({k: c[k][i] for k in RAIL_RATE})
            row.update({f"eta_{k}": red[k] for k in RAIL_RATE})
            row.update({"eta_r": sum(red.values()) / 3.0, A_SM: c[A_SM][i], "slab_increase": c[A_SM][i] - base[A_SM],
                        "slab_acc_min": np.min(c[A_SM][sel]), "working_frequency": math.sqrt(c["k_t"][i] / b) / (2 * math.pi)})
            rows.append(row)
        return {k: np.array([r[k] for r in rows]) for k in (rows[0] if rows else {})}

    def best(self, index: str = A_RM) -> dict:
        """The case with the lowest a_rm (or ``index``) overall, with the reduction of a_rm
        against the baseline and the dampers' working frequency."""
        c, ok = self.columns, self._require_controlled()
        i = np.flatnonzero(ok)[np.argmin(c[index][ok])]
        out = {k: float(c[k][i]) for k in ("b_t", "k_t", "c_t") + METRICS}
        out[f"eta_{A_RM}"] = 1 - out[A_RM] / self.baseline[A_RM]
        out["working_frequency"] = math.sqrt(out["k_t"] / out["b_t"]) / (2 * math.pi)
        return out

    def worst_slab_increase(self) -> dict:
        """Among the per-b_t rail optima, the largest rise of a_sm over the uncontrolled slab
        amplitude (article Fig. 6: +4.93 m/s², +11.22 %)."""
        t = self.best_per_inertance()
        j = int(np.argmax(t["slab_increase"]))
        base = self.baseline[A_SM]
        return dict(b_t=float(t["b_t"][j]), increase=float(t["slab_increase"][j]), relative=float(t["slab_increase"][j] / base))


def with_dampers(config: Config) -> Config:
    """``config``, or a copy with :func:`vtb.tids_around`'s dampers when it has none."""
    if config.tids is not None:
        return config
    config = config.copy()
    config.tids = tids_around(config)
    return config


class Setup(NamedTuple):
    """The article's problem made ready for :func:`vtb.studies.optimize.solve`: its evaluator,
    the checkpoint's identity, the hypervolume's reference point, the warm start's points
    (``initial``, or ``None``) and ``result(optimiser's result, X, rows)``, the answer."""

    evaluator: DesignEvaluator
    identity: dict
    hv_ref: tuple
    initial: Optional[tuple]
    result: Callable


def grid(b_t: Sequence[float], k_t: Sequence[float], c_t: Sequence[float]) -> list:
    """The Cartesian grid as (case, b_t, k_t, c_t), cases numbered from 1 (b_t slowest)."""
    return [(i + 1, float(b), float(k), float(c)) for i, (b, k, c) in enumerate((b, k, c) for b in b_t for k in k_t for c in c_t)]


def recording_metrics(config: Config) -> Config:
    """``config`` reporting only the indices of :data:`METRICS` it has (``output.indices``):
    its runs record only the layers those need."""
    names = set(index_names(config))
    config.output.indices = [m for m in METRICS if m in names]
    return config


def case_config(config: Config, b: float, k: float, c: float) -> Config:
    """``config`` with its dampers' b_t, k_t, c_t set (NaN: no dampers, the baseline),
    reporting the indices of :data:`METRICS` (:func:`recording_metrics`)."""
    cfg = config.copy()
    if math.isnan(b):
        cfg.tids = None
    else:
        cfg.tids = dataclasses.replace(cfg.tids, inertance=b, stiffness=k, damping=c)
    return recording_metrics(cfg)


def case_rows(cases: list, results: list) -> list:
    """The journal rows of cases (dicts: ``case``, b_t, k_t, c_t) from their runs."""
    return rows_of(cases, results, LAYOUT)


def plan(config: Config, b_t: Sequence[float], k_t: Sequence[float], c_t: Sequence[float]) -> tuple:
    """The swept configuration (dampers default :func:`vtb.tids_around`) and its cases (dicts:
    ``case``, b_t, k_t, c_t), the baseline (case 0, NaN parameters) and the grid; a bad grid
    value raises a :class:`ConfigError` naming b_t, k_t or c_t before any run."""
    for name, vals, low in (("b_t", b_t, 0.0), ("k_t", k_t, 0.0), ("c_t", c_t, None)):
        if len(vals) == 0:
            raise config_error(name, list(vals), "needs at least one value")
        for v in vals:
            ok = isinstance(v, numbers.Real) and not isinstance(v, bool) and math.isfinite(v) and (v >= 0 if low is None else v > low)
            if not ok:
                raise config_error(name, v, "must be finite and " + ("non-negative" if low is None else "positive"))
    config = with_dampers(config)
    cases = [dict(case=i, b_t=b, k_t=k, c_t=c) for i, b, k, c in [(0, math.nan, math.nan, math.nan)] + grid(b_t, k_t, c_t)]
    return config, cases


def read_journal(path: Union[str, Path], field: str = "path") -> SweepResult:
    """A sweep journal as a :class:`SweepResult`, without running anything: the configuration
    of its stamp and one row per key (the rule of :func:`sweep` for repeated keys), the baseline
    as case 0 and the TID cases numbered in the order of their (b_t, k_t, c_t), not of the file
    (:func:`vtb.studies.grid.read_journal`). A malformed journal raises a :class:`ConfigError`
    naming ``field`` and the line."""
    return studies.read_journal(path, field, LAYOUT, SweepResult)


def tid_objectives(config: Config, baseline: dict, threads: Optional[int] = None, executor=None) -> CaseEvaluator:
    """The article's problem (:data:`ARTICLE_VARIABLES`, :data:`ARTICLE_OBJECTIVES`, the
    :data:`CONSTRAINTS` against the uncontrolled ``baseline``), recording :data:`METRICS`; a
    failed run scores 10 × the uncontrolled objectives."""
    return CaseEvaluator(config, tuple(ARTICLE_VARIABLES), ARTICLE_OBJECTIVES, tuple((m, baseline[m]) for m in CONSTRAINTS), METRICS,
                         tuple(10 * baseline[m] for m in ARTICLE_OBJECTIVES), threads=threads, executor=executor)


@dataclasses.dataclass
class OptimizationResult:
    """``pareto``: numpy columns ``b_t``, ``k_t``, ``c_t`` and every metric of the returned
    (feasible, non-dominated) set, with reduction rates ``eta_<metric>`` = (X0 − X)/X0 and the
    comprehensive rail rate ``eta_r``; ``baseline``: the uncontrolled metrics; ``moga``: the
    optimiser's :class:`vtb.optim.Result` (history, final population); ``config``."""

    pareto: dict
    baseline: dict
    moga: OptimResult
    config: Config
    #: The pareto columns of the two objectives (what the trade-off choices compare).
    objective_columns = ARTICLE_OBJECTIVES

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
            "knee": knee_point(F),
            "nearest to ideal": min_distance_to_ideal(F),
            f"ASF {weights[0]:g}/{weights[1]:g}": asf(F, weights),
            "best η_r": int(np.argmax(self.pareto["eta_r"])),
        }

    def to_pandas(self):
        """The returned set (:attr:`pareto`) as a DataFrame, one row per design, units in
        ``attrs["units"]`` (needs pandas)."""
        return frame(self.pareto, units_of(self.pareto))

    def to_parquet(self, path) -> None:
        """Parquet export of :meth:`to_pandas`, units in its metadata (needs pyarrow)."""
        to_parquet(self.to_pandas(), path)

    def table(self) -> list:
        """Rows shaped like the article's Table 3, one per trade-off choice."""
        rows = []
        for label, i in self.trade_offs().items():
            p = self.pareto
            row = dict(choice=label, b_t=p["b_t"][i], k_t=p["k_t"][i], c_t=p["c_t"][i])
            for m in RAIL_RATE:
                row.update({m: p[m][i], f"eta_{m}": p[f"eta_{m}"][i]})
            row.update({"eta_r": p["eta_r"][i], A_SM: p[A_SM][i], f"eta_{A_SM}": p[f"eta_{A_SM}"][i]})
            rows.append(row)
        return rows

    def chosen(self, label: str = "best η_r") -> dict:
        """(b_t, k_t, c_t) of a trade-off choice."""
        i = self.trade_offs()[label]
        return {k: float(self.pareto[k][i]) for k in ("b_t", "k_t", "c_t")}

    def histories(self, label: str = "best η_r") -> tuple[Result, Result]:
        """Full runs of the uncontrolled and the chosen controlled case (Fig. 8, car body)."""
        c = self.chosen(label)
        return simulate(case_config(self.config, math.nan, 0, 0)), simulate(case_config(self.config, c["b_t"], c["k_t"], c["c_t"]))
