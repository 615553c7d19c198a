"""MATLAB's ``gamultiobj`` (a controlled elitist NSGA-II variant) with its defaults.

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
"""

from __future__ import annotations

import numpy as np

from .algorithm import _Algorithm, _descending, _front_crowding, _ranks, _stack, _topped_up
from .indicators import crowding_distance, non_dominated_sort
from .problem import Population

GAMULTIOBJ_DEFAULTS = dict(
    pareto_fraction=0.35, crossover_fraction=0.8, function_tolerance=1e-4, max_stall_generations=100,
    mutation_scale=1.0,
)


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
