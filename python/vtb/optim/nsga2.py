"""NSGA-II (Deb et al. 2002) with pymoo 0.6 defaults: population 100, as many offspring,
uniform random initialisation, binary tournament (a feasible point beats an infeasible
one, the lower CV wins between infeasible ones, the lower rank and then the larger
crowding distance between feasible ones, remaining ties at random), SBX crossover
(eta 15, probability 0.9 per mating, 0.5 per variable, children swapped per variable with
probability 0.5), polynomial mutation (eta 20, probability 0.9 per child and
min(0.5, 1/n_var) per variable), rejection of offspring that duplicate a population member
or another offspring, and elitist rank-and-crowding survival of parents + offspring with
constraint domination (feasible points first, infeasible ones by increasing CV; the last
front that fits only partly keeps its largest crowding distances, ties at random).
"""

from __future__ import annotations

import math

import numpy as np

from .algorithm import _MAX_MATING_ROUNDS, _Algorithm, _descending, _new_points, _ranks, _stack, _topped_up
from .indicators import _pareto_fronts, crowding_distance, non_dominated_sort
from .problem import Population

#: Options of each algorithm with their defaults (keyword arguments of :func:`minimize`).
NSGA2_DEFAULTS = dict(eta_c=15.0, prob_c=0.9, prob_var_c=0.5, eta_m=20.0, prob_m=0.9, prob_var_m=None)


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
