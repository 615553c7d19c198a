"""Fronts, crowding, quality indicators and trade-off choices on objective vectors (all
minimised): :func:`non_dominated_sort`, :func:`crowding_distance`, :func:`hypervolume_2d`,
:func:`igd`, :func:`igd_plus`, :func:`hypervolume_settled` and the selectors
:func:`knee_point`, :func:`min_distance_to_ideal` and :func:`asf`."""

from __future__ import annotations

from typing import Optional

import numpy as np

from ..errors import config_error


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


def hypervolume_settled(hypervolumes, tol: float, window: int) -> bool:
    """The ``stop_hv=(tol, window)`` test on a run's hypervolumes, one per generation: the
    last ``window`` + 1 of them span less than ``tol`` relative to the last."""
    if len(hypervolumes) <= window:
        return False
    hv = np.asarray(hypervolumes[-(window + 1):], dtype=float)
    return bool(hv[-1] > 0 and (hv.max() - hv.min()) / hv[-1] < tol)
