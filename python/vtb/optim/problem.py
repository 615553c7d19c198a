"""A box-bounded multi-objective problem, its population and the result of a run.

Everything minimises. A :class:`Problem` evaluates a **whole generation** at once,
``evaluate(X) -> (F, G)`` with ``X`` of shape (n, n_var), ``F`` of shape (n, n_obj) and ``G``
of shape (n, n_constr) (or ``None`` without constraints). ``G <= 0`` is feasible and the
constraint violation of a point is ``CV = sum(max(0, g_i))``. Variables flagged in
``Problem.log_scale`` are searched in log10 space (their bounds must be > 0); the evaluate
function and every result always see natural values.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Optional

import numpy as np

from ..errors import config_error


@dataclass
class Problem:
    """A box-bounded problem evaluated one generation at a time.

    ``evaluate(X)`` receives an (n, n_var) array in natural units and returns ``(F, G)``:
    F of shape (n, n_obj) and G of shape (n, n_constr), or ``None`` when ``n_constr == 0``
    (returning F alone is accepted too). ``G <= 0`` is feasible. F must be finite: map a
    failed evaluation to a large objective or a violated constraint instead (a NaN in G counts
    as an infinite violation and is stored as ``inf``). ``lower == upper`` fixes a variable.

    ``log_scale`` (optional boolean mask of length n_var, or one bool for all) makes those
    variables searched in log10 space: sampling, crossover and mutation act on log10(x)
    within [log10(lower), log10(upper)], which suits parameters spanning decades
    (stiffnesses, damping ratios). Their bounds must be > 0.

    With an ``executor`` in :func:`minimize` the evaluate function is pickled to the workers,
    so it must then be a module-level function (or another picklable callable).
    """

    lower: np.ndarray
    upper: np.ndarray
    n_obj: int
    evaluate: Callable
    n_constr: int = 0
    log_scale: Optional[np.ndarray] = None

    def __post_init__(self):
        self.lower = np.atleast_1d(np.asarray(self.lower, dtype=float))
        self.upper = np.atleast_1d(np.asarray(self.upper, dtype=float))
        if self.lower.ndim != 1 or self.lower.shape != self.upper.shape or self.lower.size == 0:
            raise config_error("Problem.lower/upper", (self.lower.shape, self.upper.shape), "must be equal-length 1-D arrays")
        if not (np.all(np.isfinite(self.lower)) and np.all(np.isfinite(self.upper))):
            raise config_error("Problem.lower/upper", "non-finite", "bounds must be finite")
        if np.any(self.lower > self.upper):
            raise config_error("Problem.lower", self.lower.tolist(), "must not exceed upper")
        if int(self.n_obj) < 1:
            raise config_error("Problem.n_obj", self.n_obj, "must be >= 1")
        if int(self.n_constr) < 0:
            raise config_error("Problem.n_constr", self.n_constr, "must be >= 0")
        self.n_obj, self.n_constr = int(self.n_obj), int(self.n_constr)
        if self.log_scale is None:
            self.log_scale = np.zeros(self.n_var, dtype=bool)
        self.log_scale = np.broadcast_to(np.asarray(self.log_scale, dtype=bool), (self.n_var,)).copy()
        if np.any(self.lower[self.log_scale] <= 0):
            raise config_error("Problem.log_scale", self.log_scale.tolist(), "log-scale variables need lower bounds > 0")

    @property
    def n_var(self) -> int:
        return self.lower.size


@dataclass
class Population:
    """Points with their objectives, constraints (shape (n, 0) without constraints),
    violation and front index ``rank`` (0 = the non-dominated set that :class:`Result`
    returns; infeasible points come after all feasible fronts, ordered by CV)."""

    X: np.ndarray
    F: np.ndarray
    G: np.ndarray
    CV: np.ndarray
    rank: np.ndarray


@dataclass
class Generation:
    """Per-generation summary: generation number (1 = initial population), evaluations so far,
    feasible points in the population, size of its first front, smallest violation,
    hypervolume of the feasible first front (when :func:`minimize` got ``hv_ref``), the
    gamultiobj spread (``None`` for NSGA-II) and the run's wall time up to the end of this
    generation (s), summed over the sessions of a resumed run (``None`` after a checkpoint
    written before vtb kept it)."""

    gen: int
    n_evals: int
    n_feasible: int
    n_front: int
    cv_min: float
    hypervolume: Optional[float] = None
    spread: Optional[float] = None
    seconds: Optional[float] = field(default=None, compare=False)  # a timing: runs alike compare equal


@dataclass
class Result:
    """Outcome of :func:`minimize`.

    ``X, F, G, CV, feasible``: the returned set, i.e. the rank-0 points of the final
    population (the feasible non-dominated points, or the least-violating points when none is
    feasible). ``pop``: the final population. ``history``: one :class:`Generation` per
    generation. ``message``: why the run stopped.
    """

    X: np.ndarray
    F: np.ndarray
    G: np.ndarray
    CV: np.ndarray
    feasible: np.ndarray
    pop: Population
    history: list = field(default_factory=list)
    n_evals: int = 0
    n_gen: int = 0
    algorithm: str = "nsga2"
    message: str = ""


def constraint_violation(G: Optional[np.ndarray], n: Optional[int] = None) -> np.ndarray:
    """CV = sum(max(0, g_i)) per row of G (zeros for ``G is None``, then ``n`` is the count)."""
    if G is None or np.size(G) == 0:
        return np.zeros(n if G is None else np.shape(G)[0])
    return np.maximum(np.asarray(G, dtype=float), 0.0).sum(axis=1)
