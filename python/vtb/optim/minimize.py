"""Multi-objective genetic optimisation: NSGA-II and a MATLAB-``gamultiobj``-like controlled GA.

Everything minimises. A :class:`Problem` evaluates a **whole generation** at once,
``evaluate(X) -> (F, G)`` with ``X`` of shape (n, n_var), ``F`` of shape (n, n_obj) and ``G``
of shape (n, n_constr) (or ``None`` without constraints). ``G <= 0`` is feasible and the
constraint violation of a point is ``CV = sum(max(0, g_i))``. Variables flagged in
``Problem.log_scale`` are searched in log10 space (their bounds must be > 0); the evaluate
function and every result always see natural values.

Algorithms (:func:`minimize`):

``"nsga2"``
    NSGA-II (Deb et al. 2002) with pymoo 0.6 defaults: population 100, as many offspring,
    uniform random initialisation, binary tournament (a feasible point beats an infeasible
    one, the lower CV wins between infeasible ones, the lower rank and then the larger
    crowding distance between feasible ones, remaining ties at random), SBX crossover
    (eta 15, probability 0.9 per mating, 0.5 per variable, children swapped per variable with
    probability 0.5), polynomial mutation (eta 20, probability 0.9 per child and
    min(0.5, 1/n_var) per variable), rejection of offspring that duplicate a population member
    or another offspring, and elitist rank-and-crowding survival of parents + offspring with
    constraint domination (feasible points first, infeasible ones by increasing CV; the last
    front that fits only partly keeps its largest crowding distances, ties at random).
``"gamultiobj"``
    MATLAB's ``gamultiobj`` (a controlled elitist NSGA-II variant) with its defaults:
    population 50 when n_var <= 5, else 200; MaxGenerations 200 * n_var; each generation
    ``round(0.8 * N)`` children (CrossoverFraction 0.8) by intermediate crossover of two
    tournament winners, child = p1 + u * (p2 - p1) with u uniform in [0, 1) per variable
    (Ratio 1), and the rest by mutating one winner; tournaments of two members drawn at random
    prefer the lower rank, then the larger crowding distance. Parents and children are merged,
    ranked (feasible points by dominance, then infeasible ones by violation, as MATLAB ranks
    them) and trimmed to N keeping a controlled number per front: the first front at most
    floor(ParetoFraction * N) (ParetoFraction 0.35) unless the other fronts are too small,
    the later fronts a geometric share of ratio 1 - ParetoFraction, each front its largest
    crowding distances (objective space, computed on the merged set). The run stops at the
    generation limit or when the spread stalls: MATLAB's spread (mu + sigma) / (mu + Q * dbar)
    of the first front, with sigma and dbar the standard deviation and mean of its Q finite
    crowding distances and mu the summed movement of its per-objective best points since the
    previous generation; it stalls when the relative change |s_k - s_(k-1)| / s_(k-1),
    averaged over the last MaxStallGenerations (100) generations with geometric weights (1/2
    per generation back), is below FunctionTolerance (1e-4) and the last spread is not above
    the window's mean. The result is the rank-0 points of the final population, so at most
    about ParetoFraction * N points.

    Deviations from MATLAB: (1) the mutation is not MATLAB's ``mutationadaptfeasible``
    (whose step adapts to the spread and whose directions come from a mesh-adaptive basis
    that keeps mutants inside the bounds) but a Gaussian step along a uniformly random
    direction of the box-normalised space, of standard deviation
    ``mutation_scale * (1 - (g - 2) / (n_gen - 1))**2`` for the children of generation g,
    clipped to the box. Its step does not shrink when progress stalls, so on continuous
    problems the spread keeps changing and the stall test rarely fires before the generation
    limit, where MATLAB typically stops after a few hundred generations. (2) The per-front
    quotas follow MATLAB's documented behaviour (geometric distribution, ParetoFraction cap),
    not its code, so their rounding may differ. (3) No linear constraints, no hybrid
    function; nonlinear constraints only through the ranking above. (4) The random streams
    differ: results agree with MATLAB statistically, not point by point.

Generation counts include the initial population: ``n_gen = 200`` evaluates the random
population and then 199 generations of offspring (pymoo's convention).

Both algorithms can start warm from points evaluated beforehand (``initial``: the first
population is chosen from them by the algorithm's own selection and they cost no evaluation),
stop when the hypervolume of the front stops moving (``stop_hv``), and save their whole state
after every generation to a checkpoint file from which a killed run resumes with a bitwise
identical result (``checkpoint``); see :func:`minimize`.

Building blocks usable on their own: :func:`non_dominated_sort`, :func:`crowding_distance`,
:func:`constraint_violation`, :func:`hypervolume_2d`, :func:`igd`, :func:`igd_plus` and the
trade-off selectors :func:`knee_point`, :func:`min_distance_to_ideal` and :func:`asf`.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import time
import uuid
import zipfile
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Callable, Optional, Union

import numpy as np

from ..errors import config_error, stale_file_error

__all__ = [
    "Problem", "Population", "Generation", "Result", "minimize", "non_dominated_sort",
    "crowding_distance", "constraint_violation", "hypervolume_2d", "igd", "igd_plus",
    "knee_point", "min_distance_to_ideal", "asf",
]

#: Options of each algorithm with their defaults (keyword arguments of :func:`minimize`).
NSGA2_DEFAULTS = dict(eta_c=15.0, prob_c=0.9, prob_var_c=0.5, eta_m=20.0, prob_m=0.9, prob_var_m=None)
GAMULTIOBJ_DEFAULTS = dict(
    pareto_fraction=0.35, crossover_fraction=0.8, function_tolerance=1e-4, max_stall_generations=100,
    mutation_scale=1.0,
)


# (lower, upper, lower bound excluded) of each option
_OPTION_RANGES = dict(
    eta_c=(0, np.inf, True), prob_c=(0, 1, False), prob_var_c=(0, 1, False), eta_m=(0, np.inf, True),
    prob_m=(0, 1, False), prob_var_m=(0, 1, False), pareto_fraction=(0, 1, True), crossover_fraction=(0, 1, False),
    function_tolerance=(0, np.inf, False), max_stall_generations=(1, np.inf, False), mutation_scale=(0, np.inf, False),
)

# Offspring closer than this to an existing point (Euclidean, in box-normalised coordinates)
# are duplicates: they would only waste an evaluation.
_DUPLICATE_TOL = 1e-12
# pymoo gives up filling the offspring after this many mating rounds that produced only duplicates.
_MAX_MATING_ROUNDS = 100


# --------------------------------------------------------------------------------------------
# Problem, population and result
# --------------------------------------------------------------------------------------------


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


# --------------------------------------------------------------------------------------------
# Building blocks
# --------------------------------------------------------------------------------------------


def constraint_violation(G: Optional[np.ndarray], n: Optional[int] = None) -> np.ndarray:
    """CV = sum(max(0, g_i)) per row of G (zeros for ``G is None``, then ``n`` is the count)."""
    if G is None or np.size(G) == 0:
        return np.zeros(n if G is None else np.shape(G)[0])
    return np.maximum(np.asarray(G, dtype=float), 0.0).sum(axis=1)


def _pareto_fronts(F: np.ndarray) -> list:
    """Fronts of plain Pareto dominance, by peeling off the points nobody remaining dominates."""
    n, m = F.shape
    if n == 0:
        return []
    # dom[i, j]: i dominates j (equal points dominate neither way); built objective by
    # objective, which is much faster than one (n, n, m) comparison for few objectives
    no_worse, better = np.ones((n, n), dtype=bool), np.zeros((n, n), dtype=bool)
    for j in range(m):
        col = F[:, j]
        no_worse &= col[:, None] <= col[None, :]
        better |= col[:, None] < col[None, :]
    dom = no_worse & better
    n_dominators = dom.sum(axis=0)
    remaining = np.ones(n, dtype=bool)
    fronts = []
    while remaining.any():
        front = np.flatnonzero(remaining & (n_dominators == 0))
        fronts.append(front)
        remaining[front] = False
        n_dominators -= dom[front].sum(axis=0)
    return fronts


def non_dominated_sort(F: np.ndarray, CV: Optional[np.ndarray] = None) -> list:
    """Fronts of ``F`` (n, n_obj) under constraint domination, best first.

    Returns a list of index arrays (ascending within a front) that partitions range(n). A
    point dominates another when it is no worse in every objective and better in one; equal
    points share a front. With ``CV``, feasible points (CV <= 0) are sorted by dominance and
    come first, then the infeasible ones by increasing CV, one front per distinct CV value.
    """
    F = np.asarray(F, dtype=float)
    if F.ndim == 1:
        F = F[:, None]
    if CV is None:
        return _pareto_fronts(F)
    CV = np.asarray(CV, dtype=float)
    feas = np.flatnonzero(CV <= 0)
    fronts = [feas[f] for f in _pareto_fronts(F[feas])]
    infeas = np.flatnonzero(CV > 0)
    if infeas.size:
        order = infeas[np.argsort(CV[infeas], kind="stable")]
        cuts = np.flatnonzero(np.diff(CV[order])) + 1
        fronts += [np.sort(g) for g in np.split(order, cuts)]
    return fronts


def crowding_distance(F: np.ndarray) -> np.ndarray:
    """Crowding distance of the points of one front (Deb et al. 2002).

    Convention: Deb's **sum** over objectives of the gap between a point's two neighbours in
    that objective, normalised by the objective's range over the front (pymoo 0.6 divides the
    same sum by n_obj; selection is unaffected). The extreme points of each objective get
    ``inf``; an objective whose range is zero contributes nothing; fronts of at most two points
    are all ``inf``. Repeated objective vectors count once: the first occurrence gets the
    value computed on the distinct points and the copies get 0, so clones never look isolated.
    """
    F = np.asarray(F, dtype=float)
    if F.ndim == 1:
        F = F[:, None]
    n, m = F.shape
    if n <= 2:
        return np.full(n, np.inf)
    _, first = np.unique(F, axis=0, return_index=True)
    first = np.sort(first)
    U = F[first]
    if len(U) <= 2:
        cd_unique = np.full(len(U), np.inf)
    else:
        order = np.argsort(U, axis=0, kind="mergesort")
        S = np.take_along_axis(U, order, axis=0)
        span = S[-1] - S[0]
        gaps = np.full(S.shape, np.inf)
        gaps[1:-1] = S[2:] - S[:-2]
        with np.errstate(invalid="ignore", divide="ignore"):
            gaps = np.where(span > 0, gaps / np.where(span > 0, span, 1.0), 0.0)
        contrib = np.empty_like(gaps)
        np.put_along_axis(contrib, order, gaps, axis=0)
        cd_unique = contrib.sum(axis=1)
    cd = np.zeros(n)
    cd[first] = cd_unique
    return cd


def hypervolume_2d(F: np.ndarray, ref) -> float:
    """Exact hypervolume (area) dominated by the 2-objective points ``F`` and bounded by
    ``ref`` (minimisation). Points not strictly better than ``ref`` in both objectives add
    nothing; dominated points and duplicates are allowed."""
    F = np.asarray(F, dtype=float).reshape(-1, 2)
    ref = np.asarray(ref, dtype=float)
    P = F[np.all(F < ref, axis=1)]
    if len(P) == 0:
        return 0.0
    P = P[np.lexsort((P[:, 1], P[:, 0]))]
    best_before = np.minimum.accumulate(P[:, 1])
    P = P[np.r_[True, P[1:, 1] < best_before[:-1]]]  # the staircase: f1 up, f2 strictly down
    widths = np.r_[P[1:, 0], ref[0]] - P[:, 0]
    return float(np.sum(widths * (ref[1] - P[:, 1])))


def igd(F: np.ndarray, pf: np.ndarray) -> float:
    """Inverted generational distance: mean over the reference front ``pf`` of the Euclidean
    distance to the nearest point of ``F``."""
    F, pf = np.atleast_2d(np.asarray(F, dtype=float)), np.atleast_2d(np.asarray(pf, dtype=float))
    d = np.sqrt(((pf[:, None, :] - F[None, :, :]) ** 2).sum(axis=2))
    return float(d.min(axis=1).mean())


def igd_plus(F: np.ndarray, pf: np.ndarray) -> float:
    """IGD+ (Ishibuchi et al. 2015): like :func:`igd` but counting only the amounts by which a
    point is worse than the reference point, sqrt(sum(max(f_i - z_i, 0)^2)); weakly Pareto
    compliant."""
    F, pf = np.atleast_2d(np.asarray(F, dtype=float)), np.atleast_2d(np.asarray(pf, dtype=float))
    d = np.sqrt((np.maximum(F[None, :, :] - pf[:, None, :], 0.0) ** 2).sum(axis=2))
    return float(d.min(axis=1).mean())


def _normalised(F: np.ndarray) -> np.ndarray:
    """``F`` scaled so that its ideal point (column minima) is 0 and its nadir (column maxima)
    is 1; constant objectives become 0."""
    F = np.atleast_2d(np.asarray(F, dtype=float))
    ideal, nadir = F.min(axis=0), F.max(axis=0)
    span = nadir - ideal
    return (F - ideal) / np.where(span > 0, span, 1.0)


def knee_point(F: np.ndarray) -> int:
    """Index of the knee of a 2-objective front: after normalising by ideal and nadir, the
    point farthest from the line through the two extreme points, measured towards the ideal
    point. On a front with no bulge towards the ideal (linear or concave) this is an extreme
    point. Ties go to the lowest index."""
    Fn = _normalised(F)
    if Fn.shape[1] != 2:
        raise config_error("F", f"shape {Fn.shape}", "knee_point needs exactly 2 objectives")
    a = np.lexsort((Fn[:, 1], Fn[:, 0]))[0]  # best f1 (then f2)
    b = np.lexsort((Fn[:, 0], Fn[:, 1]))[0]  # best f2 (then f1)
    u = Fn[b] - Fn[a]
    if not np.any(u):
        return int(a)
    normal = np.array([-u[1], u[0]])  # perpendicular to the line through the extremes
    dist = (Fn - Fn[a]) @ normal
    if -Fn[a] @ normal < 0:  # orient it towards the ideal point (the origin)
        dist = -dist
    return int(np.argmax(dist))


def min_distance_to_ideal(F: np.ndarray) -> int:
    """Index of the point nearest (Euclidean) to the ideal point after normalising by ideal
    and nadir (any number of objectives)."""
    return int(np.argmin(np.linalg.norm(_normalised(F), axis=1)))


def asf(F: np.ndarray, weights) -> int:
    """Index minimising the achievement scalarising function max_i (f_i - z_i*) / w_i on the
    front normalised by ideal (z*) and nadir. A larger weight tolerates more of that
    objective; weights must be positive."""
    Fn = _normalised(F)
    w = np.asarray(weights, dtype=float)
    if w.shape != (Fn.shape[1],) or np.any(w <= 0):
        raise config_error("weights", np.asarray(weights).tolist(), f"must be {Fn.shape[1]} positive numbers")
    return int(np.argmin(np.max(Fn / w, axis=1)))


# --------------------------------------------------------------------------------------------
# Search space and evaluation
# --------------------------------------------------------------------------------------------


class _Space:
    """The internal search box: natural bounds, log10 of them for log-scale variables."""

    def __init__(self, problem: Problem):
        self.problem = problem
        self.log = problem.log_scale
        self.lo, self.hi = problem.lower.copy(), problem.upper.copy()
        self.lo[self.log], self.hi[self.log] = np.log10(self.lo[self.log]), np.log10(self.hi[self.log])
        self.width = self.hi - self.lo

    def natural(self, Z: np.ndarray) -> np.ndarray:
        X = Z.copy()
        X[:, self.log] = 10.0 ** Z[:, self.log]
        # 10**log10(b) can miss the bound b by an ulp
        return np.clip(X, self.problem.lower, self.problem.upper)

    def internal(self, X: np.ndarray) -> np.ndarray:
        Z = X.copy()
        Z[:, self.log] = np.log10(X[:, self.log])
        return Z

    def sample(self, n: int, rng: np.random.Generator) -> np.ndarray:
        return self.lo + rng.random((n, self.lo.size)) * self.width

    def unit(self, Z: np.ndarray) -> np.ndarray:
        """Box-normalised coordinates (fixed variables map to 0)."""
        return (Z - self.lo) / np.where(self.width > 0, self.width, 1.0)


class _Evaluator:
    """Evaluates internal points, in process or in chunks on an executor, and checks shapes.
    Returns the points of a population: internal and natural coordinates, F, G, CV."""

    def __init__(self, problem: Problem, space: _Space, executor, n_chunks: Optional[int]):
        self.problem, self.space, self.executor = problem, space, executor
        self.n_chunks = n_chunks or os.cpu_count() or 1
        self.n_evals = 0

    def __call__(self, Z: np.ndarray):
        X = self.space.natural(Z)
        if self.executor is None:
            F, G = self._checked(self.problem.evaluate(X), len(X))
        else:
            chunks = np.array_split(X, min(self.n_chunks, len(X)))
            futures = [self.executor.submit(self.problem.evaluate, c) for c in chunks]
            parts = [self._checked(f.result(), len(c)) for f, c in zip(futures, chunks)]
            F, G = np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts])
        self.n_evals += len(X)
        return Z, X, F, G, constraint_violation(G, len(X))

    def _checked(self, out, n: int):
        p = self.problem
        F, G = out if isinstance(out, tuple) else (out, None)
        F = np.asarray(F, dtype=float)
        F = F.reshape(n, 1) if F.shape == (n,) and p.n_obj == 1 else F
        if F.shape != (n, p.n_obj):
            raise ValueError(f"evaluate returned F of shape {F.shape}, expected {(n, p.n_obj)}")
        if not np.isfinite(F).all():
            raise ValueError("evaluate returned non-finite objectives; return a large value or a violated constraint instead")
        if p.n_constr == 0:
            return F, np.zeros((n, 0))
        G = np.asarray(G, dtype=float)
        G = G.reshape(n, 1) if G.shape == (n,) and p.n_constr == 1 else G
        if G.shape != (n, p.n_constr):
            raise ValueError(f"evaluate returned G of shape {G.shape}, expected {(n, p.n_constr)}")
        return F, np.where(np.isnan(G), np.inf, G)  # an undefined constraint counts as violated


def _descending(values: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Indices sorting ``values`` in descending order with ties in random order."""
    perm = rng.permutation(len(values))
    return perm[np.argsort(-values[perm], kind="stable")]


def _front_crowding(F: np.ndarray, fronts: list) -> np.ndarray:
    cd = np.empty(len(F))
    for front in fronts:
        cd[front] = crowding_distance(F[front])
    return cd


def _ranks(n: int, fronts: list) -> np.ndarray:
    rank = np.empty(n, dtype=int)
    for k, front in enumerate(fronts):
        rank[front] = k
    return rank


def _stack(a: tuple, b: tuple) -> tuple:
    """The rows of two point tuples (Z, X, F, G, CV), those of ``a`` first."""
    return tuple(np.concatenate([u, v]) for u, v in zip(a, b))


def _topped_up(given: tuple, n: int, space: _Space, evaluate: _Evaluator, rng: np.random.Generator) -> tuple:
    """The already evaluated points ``given`` (Z, X, F, G, CV), with random samples evaluated
    after them when they are fewer than ``n``."""
    missing = n - len(given[0])
    return given if missing <= 0 else _stack(given, evaluate(space.sample(missing, rng)))


class _Algorithm:
    """The population both algorithms keep — internal and natural coordinates (the natural ones
    are those evaluated, so points given by the caller keep their exact values), F, G, CV, front
    rank and crowding — and the state a checkpoint saves (:func:`minimize`)."""

    _STATE = ("Z", "X", "F", "G", "CV", "rank", "crowd")

    def _points(self) -> tuple:
        return self.Z, self.X, self.F, self.G, self.CV

    def state(self) -> dict:
        return {k: np.asarray(getattr(self, k)) for k in self._STATE}

    def restore(self, state: dict) -> None:
        for k in _Algorithm._STATE:
            setattr(self, k, state[k])


# --------------------------------------------------------------------------------------------
# NSGA-II
# --------------------------------------------------------------------------------------------


class _NSGA2(_Algorithm):
    """NSGA-II state and generation step."""

    # pymoo-style fixed budget: no convergence test, hence no spread either
    spread = None

    def __init__(self, space, evaluate, rng, pop_size, opts):
        self.space, self.evaluate, self.rng, self.n = space, evaluate, rng, pop_size
        self.o = opts
        n_var = space.lo.size
        self.prob_var_m = min(0.5, 1.0 / n_var) if opts["prob_var_m"] is None else opts["prob_var_m"]

    def initialise(self, given: tuple):
        """The first population: the survivors of ``given`` topped up with random samples."""
        self._survive(*_topped_up(given, self.n, self.space, self.evaluate, self.rng))

    def step(self):
        off = self._offspring()
        if len(off):
            self._survive(*_stack(self._points(), self.evaluate(off)))

    def stalled(self) -> bool:
        return False

    def population(self) -> Population:
        rank = _ranks(len(self.F), non_dominated_sort(self.F, self.CV))
        return Population(self.X, self.F, self.G, self.CV, rank)

    def _survive(self, Z, X, F, G, CV):
        """Rank-and-crowding survival of the best ``n`` points, pymoo style: feasible points by
        front and crowding, then infeasible ones by CV. Rank and crowding are those of the
        merged set (the split front keeps its full-front crowding values), which the
        tournament then uses."""
        feas = np.flatnonzero(CV <= 0)
        # infeasible survivors keep rank 0 and crowding 0: their tournaments compare CV only
        rank, crowd = np.zeros(len(F), dtype=int), np.zeros(len(F))
        survivors = []
        for k, front in enumerate(_pareto_fronts(F[feas])):
            if len(survivors) >= self.n:
                break
            idx = feas[front]
            rank[idx], crowd[idx] = k, crowding_distance(F[idx])
            if len(survivors) + len(idx) > self.n:
                idx = idx[_descending(crowd[idx], self.rng)[: self.n - len(survivors)]]
            survivors.extend(idx)
        infeas = np.flatnonzero(CV > 0)
        survivors.extend(infeas[np.argsort(CV[infeas], kind="stable")][: self.n - len(survivors)])
        s = np.asarray(survivors, dtype=int)
        self.Z, self.X, self.F, self.G, self.CV, self.rank, self.crowd = Z[s], X[s], F[s], G[s], CV[s], rank[s], crowd[s]

    def _tournament(self, n_select: int) -> np.ndarray:
        """Binary tournaments over concatenated random permutations of the population."""
        n = len(self.Z)
        P = np.concatenate([self.rng.permutation(n) for _ in range(math.ceil(2 * n_select / n))])
        a, b = P[: 2 * n_select : 2], P[1 : 2 * n_select : 2]
        coin = self.rng.random(n_select) < 0.5
        cv_a, cv_b = self.CV[a], self.CV[b]
        by_cv = np.where(cv_a < cv_b, a, np.where(cv_b < cv_a, b, np.where(coin, a, b)))
        r_a, r_b, c_a, c_b = self.rank[a], self.rank[b], self.crowd[a], self.crowd[b]
        by_crowd = np.where(c_a > c_b, a, np.where(c_b > c_a, b, np.where(coin, a, b)))
        by_rank = np.where(r_a < r_b, a, np.where(r_b < r_a, b, by_crowd))
        return np.where((cv_a > 0) | (cv_b > 0), by_cv, by_rank)

    def _sbx(self, p1: np.ndarray, p2: np.ndarray) -> np.ndarray:
        """SBX (Deb & Agrawal 1995) in pymoo's bounded form; returns first then second children."""
        lo, hi, eta, rng = self.space.lo, self.space.hi, self.o["eta_c"], self.rng
        m, n_var = p1.shape
        mating = rng.random(m) < self.o["prob_c"]
        cross = (rng.random((m, n_var)) < self.o["prob_var_c"]) & mating[:, None]
        cross &= (np.abs(p1 - p2) > 1e-14) & (hi > lo)  # SBX is undefined for equal parents
        y1, y2 = np.minimum(p1, p2)[cross], np.maximum(p1, p2)[cross]
        xl, xu = np.broadcast_to(lo, p1.shape)[cross], np.broadcast_to(hi, p1.shape)[cross]
        u = rng.random(y1.size)
        delta = y2 - y1

        def betaq(beta):
            # the spread factor's distribution truncated so that the child stays in bounds
            alpha = 2.0 - beta ** -(eta + 1.0)
            return np.where(u <= 1.0 / alpha, (u * alpha) ** (1.0 / (eta + 1.0)), (1.0 / (2.0 - u * alpha)) ** (1.0 / (eta + 1.0)))

        c1 = 0.5 * (y1 + y2 - betaq(1.0 + 2.0 * (y1 - xl) / delta) * delta)
        c2 = 0.5 * (y1 + y2 + betaq(1.0 + 2.0 * (xu - y2) / delta) * delta)
        swap = rng.random(y1.size) < 0.5
        o1, o2 = p1.copy(), p2.copy()
        o1[cross], o2[cross] = np.where(swap, c2, c1), np.where(swap, c1, c2)
        return np.clip(np.vstack([o1, o2]), lo, hi)

    def _mutate(self, X: np.ndarray) -> np.ndarray:
        """Polynomial mutation (Deb & Goyal 1996) in pymoo's bounded form."""
        lo, hi, eta, rng = self.space.lo, self.space.hi, self.o["eta_m"], self.rng
        mut = (rng.random(X.shape) < self.prob_var_m) & (rng.random(len(X)) <= self.o["prob_m"])[:, None]
        mut &= hi > lo
        x = X[mut]
        xl, xu = np.broadcast_to(lo, X.shape)[mut], np.broadcast_to(hi, X.shape)[mut]
        d1, d2 = (x - xl) / (xu - xl), (xu - x) / (xu - xl)
        u = rng.random(x.size)
        p = 1.0 / (eta + 1.0)
        dq = np.where(
            u <= 0.5,
            (2.0 * u + (1.0 - 2.0 * u) * (1.0 - d1) ** (eta + 1.0)) ** p - 1.0,
            1.0 - (2.0 * (1.0 - u) + 2.0 * (u - 0.5) * (1.0 - d2) ** (eta + 1.0)) ** p,
        )
        out = X.copy()
        out[mut] = np.clip(x + dq * (xu - xl), xl, xu)
        return out

    def _offspring(self) -> np.ndarray:
        """``n`` new offspring; matings repeat while duplicates were rejected (pymoo)."""
        space = self.space
        pop_u = space.unit(self.Z)
        off = np.empty((0, space.lo.size))
        for _ in range(_MAX_MATING_ROUNDS + 1):
            n_mat = math.ceil((self.n - len(off)) / 2)
            parents = self._tournament(2 * n_mat).reshape(n_mat, 2)
            kids = self._mutate(self._sbx(self.Z[parents[:, 0]], self.Z[parents[:, 1]]))
            kids = kids[_new_points(space.unit(kids), np.vstack([pop_u, space.unit(off)]))]
            off = np.vstack([off, kids[: self.n - len(off)]])
            if len(off) >= self.n:
                break
        return off


def _new_points(U: np.ndarray, existing: np.ndarray) -> np.ndarray:
    """Mask of the rows of ``U`` farther than the duplicate tolerance from every row of
    ``existing`` and from every earlier row of ``U``. Only pairs that already agree in the
    first coordinate are compared in full, which keeps this cheap for many variables."""

    def close_pairs(A, B):
        i, j = np.nonzero(np.abs(A[:, 0][:, None] - B[:, 0][None, :]) <= _DUPLICATE_TOL)
        hit = ((A[i] - B[j]) ** 2).sum(axis=1) <= _DUPLICATE_TOL**2
        return i[hit], j[hit]

    new = np.ones(len(U), dtype=bool)
    new[close_pairs(U, existing)[0]] = False
    i, j = close_pairs(U, U)
    new[i[j < i]] = False
    return new


# --------------------------------------------------------------------------------------------
# gamultiobj
# --------------------------------------------------------------------------------------------


def _front_quota(sizes: np.ndarray, n: int, pareto_fraction: float) -> np.ndarray:
    """How many points each front keeps when trimming to ``n``.

    The first front keeps at most max(1, floor(pareto_fraction * n)) points. The rest is
    shared by the later fronts as a geometric series of ratio 1 - pareto_fraction, front by
    front: each takes its share of what is left (the last one all of it) or everything it has,
    so unused shares pass on to later fronts. If the later fronts run out, the shortfall is
    taken from fronts 2, 3, ... and only then from the first front beyond its cap.
    """
    r = 1.0 - pareto_fraction
    keep = np.zeros(len(sizes), dtype=int)
    keep[0] = min(sizes[0], max(1, int(pareto_fraction * n + 1e-9)))  # 0.29 * 100 = 28.999...
    left = n - keep[0]
    for i in range(1, len(sizes)):
        n_rest = len(sizes) - i
        share = left if n_rest == 1 or r == 0 else round(left * (1 - r) / (1 - r**n_rest))
        keep[i] = min(sizes[i], share)
        left -= keep[i]
    for i in [*range(1, len(sizes)), 0]:
        extra = min(left, sizes[i] - keep[i])
        keep[i] += extra
        left -= extra
    return keep


class _Gamultiobj(_Algorithm):
    """gamultiobj state and generation step."""

    _STATE = _Algorithm._STATE + ("gen", "spreads", "extremes")

    def __init__(self, space, evaluate, rng, pop_size, opts, max_gen):
        self.space, self.evaluate, self.rng, self.n = space, evaluate, rng, pop_size
        self.o, self.max_gen = opts, max_gen
        self.gen = 1
        self.spreads: list = []
        self.extremes = None

    def initialise(self, given: tuple):
        """The first population: ``given`` topped up with random samples, trimmed to ``n`` like
        every generation when there are more."""
        points = _topped_up(given, self.n, self.space, self.evaluate, self.rng)
        if len(points[0]) > self.n:
            self._trim(*points)
        else:
            self.Z, self.X, self.F, self.G, self.CV = points
            fronts = non_dominated_sort(self.F, self.CV)
            self.rank, self.crowd = _ranks(self.n, fronts), _front_crowding(self.F, fronts)
        self._record_spread()

    def restore(self, state: dict) -> None:
        super().restore(state)
        self.gen, self.spreads, self.extremes = int(state["gen"]), state["spreads"].tolist(), state["extremes"]

    def step(self):
        self.gen += 1
        n_x = round(self.o["crossover_fraction"] * self.n)
        parents = self._tournament(2 * n_x + self.n - n_x)
        p1, p2 = self.Z[parents[:n_x]], self.Z[parents[n_x : 2 * n_x]]
        xkids = p1 + self.rng.random(p1.shape) * (p2 - p1)  # intermediate, Ratio 1
        kids = np.vstack([xkids, self._mutate(self.Z[parents[2 * n_x :]])])
        self._trim(*_stack(self._points(), self.evaluate(kids)))
        self._record_spread()

    @property
    def spread(self) -> float:
        return self.spreads[-1]

    def population(self) -> Population:
        return Population(self.X, self.F, self.G, self.CV, self.rank)

    def _tournament(self, n_select: int) -> np.ndarray:
        """Tournaments of two players drawn with replacement: lower rank wins, then larger
        crowding distance, then a coin."""
        a, b = self.rng.integers(0, self.n, n_select), self.rng.integers(0, self.n, n_select)
        coin = self.rng.random(n_select) < 0.5
        r_a, r_b, c_a, c_b = self.rank[a], self.rank[b], self.crowd[a], self.crowd[b]
        by_crowd = np.where(c_a > c_b, a, np.where(c_b > c_a, b, np.where(coin, a, b)))
        return np.where(r_a < r_b, a, np.where(r_b < r_a, b, by_crowd))

    def _mutate(self, P: np.ndarray) -> np.ndarray:
        """Approximation of MATLAB's adaptive-feasible mutation (see :func:`minimize`): a
        Gaussian step along a uniformly random direction of the box-normalised space, with a
        standard deviation shrinking quadratically to zero over the run, clipped to the box."""
        width = self.space.width
        d = self.rng.standard_normal(P.shape) * (width > 0)
        d /= np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-300)
        sigma = self.o["mutation_scale"] * (1.0 - (self.gen - 2) / self.max_gen) ** 2
        step = sigma * self.rng.standard_normal((len(P), 1)) * d * width
        # clipping (rather than retrying) lets variables reach their bounds exactly, where
        # optima often sit
        return np.clip(P + step, self.space.lo, self.space.hi)

    def _trim(self, Z, X, F, G, CV):
        """Keep ``n`` of parents + children: a controlled number per front (see
        :func:`_front_quota`), within a front the largest crowding distances (ties at random).
        Ranks and distances are those of the merged set, as in MATLAB."""
        fronts = non_dominated_sort(F, CV)
        rank, crowd = _ranks(len(F), fronts), _front_crowding(F, fronts)
        quota = _front_quota(np.array([len(f) for f in fronts]), self.n, self.o["pareto_fraction"])
        keep = np.concatenate([f[_descending(crowd[f], self.rng)[:q]] for f, q in zip(fronts, quota)])
        self.Z, self.X, self.F, self.G, self.CV, self.rank, self.crowd = Z[keep], X[keep], F[keep], G[keep], CV[keep], rank[keep], crowd[keep]

    def _record_spread(self):
        """Appends MATLAB's spread of the first front (see the module docstring)."""
        Ff = self.F[self.rank == 0]
        cd = crowding_distance(Ff)
        cd = cd[np.isfinite(cd)]
        extremes = Ff[np.argmin(Ff, axis=0)]
        mu = 0.0 if self.extremes is None else float(np.linalg.norm(extremes - self.extremes, axis=1).sum())
        self.extremes = extremes
        sigma, dbar = (float(cd.std()), float(cd.mean())) if cd.size else (0.0, 0.0)
        denom = mu + cd.size * dbar
        self.spreads.append((mu + sigma) / denom if denom > 0 else 0.0)

    def stalled(self) -> bool:
        """The spread stall test described in the module docstring."""
        k = int(self.o["max_stall_generations"])
        if len(self.spreads) <= k:
            return False
        s = np.asarray(self.spreads[-(k + 1) :])
        change = np.abs(np.diff(s)) / np.maximum(np.abs(s[:-1]), np.finfo(float).eps)
        w = 0.5 ** np.arange(k)[::-1]
        # the margin absorbs the rounding of the mean of a frozen (constant) spread
        return bool(np.dot(w, change) / w.sum() < self.o["function_tolerance"] and s[-1] <= s[1:].mean() * (1 + 1e-9))


# --------------------------------------------------------------------------------------------
# Driver
# --------------------------------------------------------------------------------------------


def minimize(
    problem: Problem,
    algorithm: str = "nsga2",
    *,
    pop_size: Optional[int] = None,
    n_gen: Optional[int] = None,
    seed: Union[None, int, np.random.Generator] = None,
    callback: Optional[Callable] = None,
    progress: bool = False,
    executor=None,
    n_chunks: Optional[int] = None,
    hv_ref=None,
    initial: Optional[tuple] = None,
    stop_hv: Optional[tuple] = None,
    checkpoint: Union[str, os.PathLike, None] = None,
    checkpoint_identity=None,
    **options,
) -> Result:
    """Minimise ``problem`` with ``"nsga2"`` or ``"gamultiobj"`` (see the module docstring).

    ``pop_size``: default 100 for NSGA-II; 50 when n_var <= 5, else 200 for gamultiobj.
    ``n_gen``: generations including the initial population; default 200 for NSGA-II (which
    always runs them all unless the callback or ``stop_hv`` stops it) and 200 * n_var + 1 for
    gamultiobj (MATLAB's MaxGenerations after the initial population; the spread test may stop
    earlier). ``seed``: an int, ``None`` or a :class:`numpy.random.Generator`; the same seed
    gives the same result. ``callback(generation, population)`` runs after every generation
    with a :class:`Generation` and the :class:`Population`; returning ``True`` stops the run.
    ``progress=True`` shows a tqdm bar.

    ``executor``: an optional :class:`concurrent.futures.Executor`. Each generation is then
    split into ``n_chunks`` row blocks (default ``os.cpu_count()``), evaluated as
    ``executor.submit(problem.evaluate, block)`` and concatenated in order, so the result is
    identical to an in-process run with the same seed. For a process pool,
    ``problem.evaluate`` must be picklable (a module-level function).

    ``hv_ref``: a reference point (2 objectives) to record the hypervolume of the feasible
    first front in the history.

    ``initial=(X, F, G)``: points evaluated beforehand (natural units; ``G`` may be ``None``
    without constraints), e.g. the cases of a parameter sweep. The first population is chosen
    among those within the bounds (each distinct point once) by the algorithm's own selection —
    NSGA-II's rank-and-crowding survival, gamultiobj's front quotas and crowding — instead of
    being sampled, and topped up with random samples when fewer than ``pop_size`` are left.
    They cost no evaluation: ``n_evals`` counts only new ones, and keep their exact X.

    ``stop_hv=(tol, window)`` (needs ``hv_ref``): stop once the hypervolume of the feasible
    first front has moved by less than ``tol`` relative over the last ``window`` generations,
    i.e. (max − min) / last < tol over its last window + 1 values, the last one positive. For
    NSGA-II, whose elitism never loses hypervolume, that is (HV_g − HV_(g−window)) / HV_g.

    ``checkpoint``: a file to resume from. After every generation the optimiser's whole state
    (generation, population, gamultiobj's spreads, evaluation count, history, the random
    generator's state) is written to it atomically — a temporary file in the same directory,
    fsync, rename — as a NumPy ``.npz`` archive with a JSON header, read back without
    unpickling anything. A run given an existing checkpoint resumes after its last generation,
    and a run killed and resumed gives bitwise the result of an uninterrupted one; so it needs
    a ``seed``. The checkpoint records what it belongs to (algorithm, pop_size, n_gen, options,
    bounds, log scales, n_obj, n_constr, the seed's generator state, hv_ref, stop_hv, a hash of
    ``initial``, and ``checkpoint_identity``: any JSON value naming what ``problem.evaluate``
    computes) and one of another run is refused. A finished run's checkpoint gives its result
    again without evaluating; a run stopped by the callback resumes where it stopped. Delete
    the file to start afresh.

    ``options`` — NSGA-II (:data:`NSGA2_DEFAULTS`): SBX ``eta_c`` (15), ``prob_c`` (0.9 per
    mating), ``prob_var_c`` (0.5 per variable); polynomial mutation ``eta_m`` (20),
    ``prob_m`` (0.9 per child), ``prob_var_m`` (per variable, ``None`` = min(0.5, 1/n_var)).
    gamultiobj (:data:`GAMULTIOBJ_DEFAULTS`): ``pareto_fraction`` (0.35),
    ``crossover_fraction`` (0.8), ``function_tolerance`` (1e-4), ``max_stall_generations``
    (100) and ``mutation_scale`` (1.0: the initial standard deviation of the mutation step
    length, with every variable's range scaled to 1).
    """
    if not isinstance(problem, Problem):
        raise config_error("problem", type(problem).__name__, "must be a vtb.moga.Problem")
    defaults = {"nsga2": NSGA2_DEFAULTS, "gamultiobj": GAMULTIOBJ_DEFAULTS}.get(algorithm)
    if defaults is None:
        raise config_error("algorithm", algorithm, "must be \"nsga2\" or \"gamultiobj\"")
    unknown = sorted(set(options) - set(defaults))
    if unknown:
        raise config_error("options", unknown, f"unknown for {algorithm}; known: {sorted(defaults)}")
    opts = {**defaults, **options}
    n_var = problem.n_var
    if pop_size is None:
        pop_size = 100 if algorithm == "nsga2" else (50 if n_var <= 5 else 200)
    if n_gen is None:
        n_gen = 200 if algorithm == "nsga2" else 200 * n_var + 1
    if int(pop_size) < 2:
        raise config_error("pop_size", pop_size, "must be >= 2")
    if int(n_gen) < 1:
        raise config_error("n_gen", n_gen, "must be >= 1")
    pop_size, n_gen = int(pop_size), int(n_gen)
    for name, value in opts.items():
        lo, hi, open_lo = _OPTION_RANGES[name]
        if value is not None and not ((lo < value if open_lo else lo <= value) and value <= hi):
            raise config_error(name, value, f"must be in {'(' if open_lo else '['}{lo}, {hi}]")
    if hv_ref is not None and problem.n_obj != 2:
        raise config_error("hv_ref", hv_ref, "the recorded hypervolume needs 2 objectives")
    if stop_hv is not None:
        try:
            tol, window = float(stop_hv[0]), float(stop_hv[1])
            ok = len(stop_hv) == 2 and tol > 0 and window >= 1 and window.is_integer()
        except (TypeError, ValueError, IndexError):
            ok = False
        if not ok:
            raise config_error("stop_hv", stop_hv, "must be (tol > 0, window >= 1 generations)")
        if hv_ref is None:
            raise config_error("stop_hv", stop_hv, "needs hv_ref, the hypervolume's reference point")
        stop_hv = (tol, int(window))

    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
    space = _Space(problem)
    given = _given_points(problem, space, initial)
    evaluate = _Evaluator(problem, space, executor, n_chunks)
    if algorithm == "nsga2":
        algo = _NSGA2(space, evaluate, rng, pop_size, opts)
    else:
        algo = _Gamultiobj(space, evaluate, rng, pop_size, opts, max(n_gen - 1, 1))

    history, message = [], ""
    if checkpoint is not None:
        if seed is None:
            raise config_error("seed", None, "a checkpointed run needs a seed (an int or a Generator) to be resumable")
        checkpoint = Path(checkpoint)
        identity = _identity(problem, algorithm, pop_size, n_gen, opts, rng, hv_ref, stop_hv, given, checkpoint_identity)
        if checkpoint.exists():
            history, message = _resume(checkpoint, identity, algo, rng, evaluate, n_gen)
    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=n_gen, initial=len(history), desc=f"vtb {algorithm}", unit="gen")
    # wall time carries over a resume: the sessions before this one took history[-1].seconds
    before, t0 = (history[-1].seconds if history else 0.0), time.perf_counter()
    try:
        while not message:
            gen = len(history) + 1
            if gen == 1:
                algo.initialise(given)
            else:
                algo.step()
            pop = algo.population()
            history.append(_summary(gen, evaluate.n_evals, pop, hv_ref, algo.spread, None if before is None else before + time.perf_counter() - t0))
            message = _stop_reason(algo, history, n_gen, stop_hv)
            if checkpoint is not None:
                _save_checkpoint(checkpoint, identity, algo, rng, evaluate.n_evals, history, message)
            if bar is not None:
                bar.update(1)
            if callback is not None and callback(history[-1], pop):
                message = "stopped by callback"
    finally:
        if bar is not None:
            bar.close()

    pop = algo.population()
    best = pop.rank == 0
    return Result(
        X=pop.X[best], F=pop.F[best], G=pop.G[best], CV=pop.CV[best], feasible=pop.CV[best] <= 0,
        pop=pop, history=history, n_evals=evaluate.n_evals, n_gen=len(history), algorithm=algorithm,
        message=message,
    )


def _given_points(problem: Problem, space: _Space, initial) -> tuple:
    """``initial = (X, F, G)`` as population points (Z, X, F, G, CV): the rows within the
    bounds, each distinct point once (empty arrays without ``initial``)."""
    n_var, n_obj, n_constr = problem.n_var, problem.n_obj, problem.n_constr
    if initial is None:
        X, F, G = np.empty((0, n_var)), np.empty((0, n_obj)), np.empty((0, n_constr))
    else:
        if not (isinstance(initial, (tuple, list)) and len(initial) == 3):
            raise config_error("initial", type(initial).__name__, "must be (X, F, G) of already evaluated points")
        X, F, G = initial
        X, F = np.asarray(X, dtype=float), np.asarray(F, dtype=float)
        G = np.empty((len(X), 0)) if G is None and n_constr == 0 else np.asarray(G, dtype=float)
        for name, a, cols in (("X", X, n_var), ("F", F, n_obj), ("G", G, n_constr)):
            if a.shape != (len(X), cols):
                raise config_error(f"initial.{name}", a.shape, f"must have shape ({len(X)}, {cols})")
        inside = np.all((X >= problem.lower) & (X <= problem.upper), axis=1)
        X, F, G = X[inside], F[inside], np.where(np.isnan(G[inside]), np.inf, G[inside])
        if not np.isfinite(F).all():
            raise config_error("initial.F", "non-finite", "objectives within the bounds must be finite")
    Z = space.internal(X)
    new = _new_points(space.unit(Z), Z[:0])
    return Z[new], X[new], F[new], G[new], constraint_violation(G[new], int(new.sum()))


def hypervolume_settled(hypervolumes, tol: float, window: int) -> bool:
    """The ``stop_hv=(tol, window)`` test on a run's hypervolumes, one per generation: the
    last ``window`` + 1 of them span less than ``tol`` relative to the last."""
    if len(hypervolumes) <= window:
        return False
    hv = np.asarray(hypervolumes[-(window + 1):], dtype=float)
    return bool(hv[-1] > 0 and (hv.max() - hv.min()) / hv[-1] < tol)


def _stop_reason(algo, history: list, n_gen: int, stop_hv) -> str:
    """Why the run stops after the last generation of ``history`` ("" to go on)."""
    if algo.stalled():
        return "average change in the spread of Pareto solutions less than function_tolerance"
    if stop_hv is not None and hypervolume_settled([h.hypervolume for h in history], *stop_hv):
        return f"hypervolume moved by less than {stop_hv[0]:g} (relative) over the last {stop_hv[1]} generations"
    if len(history) >= n_gen:
        return f"reached n_gen = {n_gen}"
    return ""


def _summary(gen: int, n_evals: int, pop: Population, hv_ref, spread: Optional[float], seconds: Optional[float]) -> Generation:
    front = pop.rank == 0
    feasible = pop.CV <= 0
    hv = None if hv_ref is None else hypervolume_2d(pop.F[front & feasible], hv_ref)
    return Generation(
        gen=gen, n_evals=n_evals, n_feasible=int(feasible.sum()), n_front=int(front.sum()),
        cv_min=float(pop.CV.min()), hypervolume=hv, spread=spread, seconds=seconds,
    )


# --------------------------------------------------------------------------------------------
# Checkpoints
# --------------------------------------------------------------------------------------------

_CHECKPOINT_FORMAT = "vtb.moga checkpoint 1"


def _identity(problem, algorithm, pop_size, n_gen, opts, rng, hv_ref, stop_hv, given, extra) -> dict:
    """What a checkpoint belongs to, as plain JSON values (compared on resume)."""
    try:
        seed_state = json.loads(json.dumps(rng.bit_generator.state))
    except TypeError:
        raise config_error("seed", type(rng.bit_generator).__name__, "a checkpoint needs a bit generator whose state is plain integers (PCG64, numpy's default)") from None
    digest = hashlib.sha256()
    for a in given[1:4]:
        digest.update(repr(a.shape).encode() + np.ascontiguousarray(a).tobytes())
    identity = dict(
        algorithm=algorithm, pop_size=pop_size, n_gen=n_gen,
        options={k: None if v is None else float(v) for k, v in opts.items()},
        lower=problem.lower.tolist(), upper=problem.upper.tolist(), log_scale=problem.log_scale.tolist(),
        n_obj=problem.n_obj, n_constr=problem.n_constr, seed=seed_state,
        hv_ref=None if hv_ref is None else np.asarray(hv_ref, dtype=float).tolist(),
        stop_hv=None if stop_hv is None else list(stop_hv), initial=digest.hexdigest() if len(given[0]) else None,
    )
    try:
        identity["problem"] = json.loads(json.dumps(extra))
    except (TypeError, ValueError):
        raise config_error("checkpoint_identity", type(extra).__name__, "must be JSON-serialisable") from None
    return identity


def write_atomically(path: Path, write: Callable) -> None:
    """Replaces ``path`` by what ``write(binary file)`` writes, atomically: into a temporary file
    of the same directory, fsynced, renamed over ``path``, and the directory fsynced, so that a
    crash leaves either the old file or the new one, never a mixture."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.{uuid.uuid4().hex[:8]}.tmp")
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)  # the umask applies, unlike mkstemp's 0600
    try:
        with os.fdopen(fd, "wb") as f:
            write(f)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    dir_fd = os.open(path.parent, os.O_RDONLY)
    try:
        os.fsync(dir_fd)
    finally:
        os.close(dir_fd)


def _save_checkpoint(path: Path, identity: dict, algo, rng, n_evals: int, history: list, message: str) -> None:
    header = dict(
        format=_CHECKPOINT_FORMAT, identity=identity, rng=rng.bit_generator.state, n_evals=n_evals,
        message=message, history=[asdict(h) for h in history],
    )
    write_atomically(path, lambda f: np.savez(f, header=np.array(json.dumps(header)), **algo.state()))


def saved_identity(path: Path):
    """The identity a checkpoint was saved with, or ``None`` if ``path`` holds no readable one."""
    try:
        with np.load(path, allow_pickle=False) as z:
            return json.loads(str(z["header"])).get("identity")
    except (OSError, EOFError, ValueError, KeyError, AttributeError, TypeError, zipfile.BadZipFile):
        return None


def _resume(path: Path, identity: dict, algo, rng, evaluate, n_gen: int) -> tuple:
    """Restores ``algo``, ``rng`` and the evaluation count from the checkpoint ``path``;
    returns its history and stop message."""
    try:
        with np.load(path, allow_pickle=False) as z:
            header = json.loads(str(z["header"]))
            state = {k: z[k] for k in z.files if k != "header"}
    except (OSError, EOFError, ValueError, KeyError, TypeError, zipfile.BadZipFile) as e:
        raise config_error("checkpoint", str(path), f"is not a readable vtb.moga checkpoint ({type(e).__name__}: {e})") from None
    if not isinstance(header, dict) or header.get("format") != _CHECKPOINT_FORMAT:
        raise config_error("checkpoint", str(path), f"is not a {_CHECKPOINT_FORMAT!r} file")
    saved = header.get("identity")
    if saved != identity:
        differ = sorted(k for k in identity if not isinstance(saved, dict) or saved.get(k) != identity[k])
        raise stale_file_error("checkpoint", path, f"belongs to another run (it differs in {', '.join(differ) or 'its fields'}); delete it or choose another path")
    n, p = identity["pop_size"], algo.space.problem
    shapes = dict(Z=(n, p.n_var), X=(n, p.n_var), F=(n, p.n_obj), G=(n, p.n_constr), CV=(n,), rank=(n,), crowd=(n,))
    try:
        bad = [k for k in algo._STATE if k not in state] + [k for k, s in shapes.items() if state[k].shape != s]
        history = [Generation(**g) for g in header["history"]]
        if bad or not 1 <= len(history) <= n_gen or history[-1].gen != len(history):
            raise ValueError(f"arrays {bad}, {len(history)} generations")
        algo.restore(state)
        rng.bit_generator.state = header["rng"]
        evaluate.n_evals = int(header["n_evals"])
        return history, str(header["message"])
    except (KeyError, TypeError, ValueError, AttributeError) as e:
        raise config_error("checkpoint", str(path), f"is damaged ({type(e).__name__}: {e})") from None
