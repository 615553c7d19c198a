"""What both algorithms share: the internal search box (log10 for log-scale variables), the
evaluation of a generation (in process or in chunks on an executor), the population they keep
and the state a checkpoint saves."""

from __future__ import annotations

import os
from typing import Optional

import numpy as np

from .indicators import crowding_distance
from .problem import Problem, constraint_violation

# Offspring closer than this to an existing point (Euclidean, in box-normalised coordinates)
# are duplicates: they would only waste an evaluation.
_DUPLICATE_TOL = 1e-12
# pymoo gives up filling the offspring after this many mating rounds that produced only duplicates.
_MAX_MATING_ROUNDS = 100


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
