"""Multi-objective GA (vtb.moga): building blocks by hand, NSGA-II on standard benchmarks,
the gamultiobj mode, log-scale variables, reproducibility and the executor path."""

from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pytest

from vtb import optim as moga
from vtb.optim import gamultiobj
from vtb.errors import ConfigError
from vtb.optim import (
    Problem, asf, crowding_distance, hypervolume_2d, igd, igd_plus, knee_point, min_distance_to_ideal,
    minimize, non_dominated_sort,
)

# --------------------------------------------------------------------------------------------
# Benchmark problems (Zitzler, Deb & Thiele 2000; Tanaka 1995; Binh & Korn 1997). Module-level
# functions so that they pickle to worker processes.
# --------------------------------------------------------------------------------------------


def _zdt_g(X):
    return 1.0 + 9.0 * X[:, 1:].mean(axis=1)


def zdt1(X):
    f1, g = X[:, 0], _zdt_g(X)
    return np.c_[f1, g * (1.0 - np.sqrt(f1 / g))], None


def zdt2(X):
    f1, g = X[:, 0], _zdt_g(X)
    return np.c_[f1, g * (1.0 - (f1 / g) ** 2)], None


def zdt3(X):
    f1, g = X[:, 0], _zdt_g(X)
    return np.c_[f1, g * (1.0 - np.sqrt(f1 / g) - f1 / g * np.sin(10.0 * np.pi * f1))], None


def tnk(X):
    x1, x2 = X[:, 0], X[:, 1]
    g1 = -(x1**2 + x2**2 - 1.0 - 0.1 * np.cos(16.0 * np.arctan2(x1, x2)))
    g2 = (x1 - 0.5) ** 2 + (x2 - 0.5) ** 2 - 0.5
    return X.copy(), np.c_[g1, g2]


def bnh(X):
    x1, x2 = X[:, 0], X[:, 1]
    F = np.c_[4.0 * x1**2 + 4.0 * x2**2, (x1 - 5.0) ** 2 + (x2 - 5.0) ** 2]
    G = np.c_[(x1 - 5.0) ** 2 + x2**2 - 25.0, 7.7 - ((x1 - 8.0) ** 2 + (x2 + 3.0) ** 2)]
    return F, G


ZDT1 = Problem(np.zeros(30), np.ones(30), 2, zdt1)
BENCHMARKS = {
    "zdt1": (ZDT1, (1.1, 1.1), 0.86),
    "zdt2": (Problem(np.zeros(30), np.ones(30), 2, zdt2), (1.1, 1.1), 0.53),
    "zdt3": (Problem(np.zeros(30), np.ones(30), 2, zdt3), (1.1, 1.1), 1.32),
    "tnk": (Problem([0.0, 0.0], [np.pi, np.pi], 2, tnk, n_constr=2), (1.2, 1.2), 0.645),
    "bnh": (Problem([0.0, 0.0], [5.0, 3.0], 2, bnh, n_constr=2), (140.0, 50.0), 5240.0),
}


def _zdt1_front(n=2001):
    f1 = np.linspace(0.0, 1.0, n)
    return np.c_[f1, 1.0 - np.sqrt(f1)]


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("name", list(BENCHMARKS))
def test_nsga2_benchmarks(name, seed):
    """NSGA-II, N = 100, 200 generations: hypervolume close to the true front's (ZDT1
    0.876667, ZDT2 0.543333, ZDT3 1.33176, TNK 0.65506, BNH 5285.3) for every seed; ZDT1 also
    IGD <= 0.01; the constrained problems return feasible points only."""
    problem, ref, hv_min = BENCHMARKS[name]
    res = minimize(problem, "nsga2", pop_size=100, n_gen=200, seed=seed)
    assert res.n_gen == 200 and res.n_evals <= 200 * 100
    assert hypervolume_2d(res.F, ref) >= hv_min
    assert res.feasible.all()
    if name == "zdt1":
        assert igd(res.F, _zdt1_front()) <= 0.01
    assert np.all((res.pop.X >= problem.lower) & (res.pop.X <= problem.upper))


# --------------------------------------------------------------------------------------------
# Building blocks
# --------------------------------------------------------------------------------------------


def test_crowding_distance_by_hand():
    """Deb's sum convention: the middle point's neighbour gaps are 1 and 100 over ranges 1 and
    100, so 1 + 1 = 2; extremes are infinite."""
    cd = crowding_distance([[0, 0], [0.5, 50], [1, 100]])
    assert cd[0] == np.inf and cd[2] == np.inf
    assert cd[1] == pytest.approx(2.0)
    # unequal gaps: (0.75 - 0)/1 + (3 - 0)/4 for the second point, (1 - 0.25)/1 + (4 - 1)/4
    # for the third (objective 2 descends)
    cd = crowding_distance([[0, 4], [0.25, 3], [0.75, 1], [1, 0]])
    np.testing.assert_allclose(cd, [np.inf, 1.5, 1.5, np.inf])
    # copies get 0, the first occurrence the distinct-point value
    cd = crowding_distance([[0, 0], [0.5, 50], [0.5, 50], [1, 100]])
    np.testing.assert_allclose(cd, [np.inf, 2.0, 0.0, np.inf])
    # at most two points: all infinite; a constant objective contributes nothing
    assert np.all(crowding_distance([[0, 1], [1, 0]]) == np.inf)
    cd = crowding_distance([[0, 7], [0.2, 7], [1, 7]])
    np.testing.assert_allclose(cd, [np.inf, 1.0, np.inf])


def test_igd_and_igd_plus_by_hand():
    """pf = {(1, 0), (0, 10)}, A = (2, 5): IGD = (sqrt(26) + sqrt(29))/2 = 5.242 and
    IGD+ = (sqrt(1 + 25) + sqrt(4 + 0))/2 = 3.550."""
    pf, A = np.array([[1.0, 0.0], [0.0, 10.0]]), np.array([[2.0, 5.0]])
    assert igd(A, pf) == pytest.approx((np.sqrt(26) + np.sqrt(29)) / 2)
    assert igd(A, pf) == pytest.approx(5.242, abs=1e-3)
    assert igd_plus(A, pf) == pytest.approx(3.550, abs=1e-3)
    assert igd(pf, pf) == 0.0 and igd_plus(pf, pf) == 0.0
    # a point better than the front costs nothing in IGD+ but does in IGD
    assert igd_plus([[0.0, 0.0]], pf) == 0.0 and igd([[0.0, 0.0]], pf) > 0


def _fronts_as_lists(fronts):
    return [sorted(f.tolist()) for f in fronts]


def test_non_dominated_sort_by_hand():
    F = [[1, 4], [2, 2], [4, 1], [3, 3], [2, 2], [5, 5], [1, 4], [1, 5]]
    # duplicates share a front; (1, 5) ties (1, 4) in f1 and is dominated by it
    assert _fronts_as_lists(non_dominated_sort(F)) == [[0, 1, 2, 4, 6], [3, 7], [5]]
    assert _fronts_as_lists(non_dominated_sort([[1, 1], [1, 1], [1, 1]])) == [[0, 1, 2]]
    assert _fronts_as_lists(non_dominated_sort([[3.0], [1.0], [2.0], [1.0]])) == [[1, 3], [2], [0]]


def test_non_dominated_sort_constraint_domination():
    """Feasible points first (by dominance), then the infeasible ones by CV with equal CVs
    sharing a front, whatever their objectives."""
    F = [[0, 0], [1, 1], [2, 2], [3, 3], [4, 4], [0, 5]]
    CV = [0.5, 0.0, 0.1, 0.0, 0.5, 0.0]
    assert _fronts_as_lists(non_dominated_sort(F, CV)) == [[1, 5], [3], [2], [0, 4]]
    assert _fronts_as_lists(non_dominated_sort(F, np.ones(6))) == [[0, 1, 2, 3, 4, 5]]


def test_non_dominated_sort_properties_on_random_sets():
    """Every point is dominated by a point of the previous front and by none of its own or
    later fronts; coarse values make ties and duplicates common."""
    rng = np.random.default_rng(1)
    for _ in range(20):
        F = rng.integers(0, 5, size=(40, 3)).astype(float)
        fronts = non_dominated_sort(F)
        assert sorted(np.concatenate(fronts).tolist()) == list(range(40))

        def dominates(a, b):
            return np.all(a <= b) and np.any(a < b)

        for k, front in enumerate(fronts):
            later = np.concatenate(fronts[k:])
            for i in front:
                assert not any(dominates(F[j], F[i]) for j in later)
                if k:
                    assert any(dominates(F[j], F[i]) for j in fronts[k - 1])


def _hv_grid(F, ref):
    """Independent hypervolume: dominated cells of the grid spanned by all coordinates."""
    F = np.asarray(F, dtype=float)
    xs, ys = np.unique(np.r_[F[:, 0], ref[0]]), np.unique(np.r_[F[:, 1], ref[1]])
    area = 0.0
    for x0, x1 in zip(xs[:-1], xs[1:]):
        for y0, y1 in zip(ys[:-1], ys[1:]):
            if x1 <= ref[0] and y1 <= ref[1] and np.any((F[:, 0] <= x0) & (F[:, 1] <= y0)):
                area += (x1 - x0) * (y1 - y0)
    return area


def test_hypervolume_2d_by_hand_and_against_grid():
    assert hypervolume_2d([[0.5, 0.5]], (1, 1)) == pytest.approx(0.25)
    # two rectangles of area 2 overlapping on 1
    assert hypervolume_2d([[0, 1], [1, 0]], (2, 2)) == pytest.approx(3.0)
    # dominated points, duplicates and points beyond the reference add nothing
    assert hypervolume_2d([[0, 1], [1, 0], [1, 1], [0, 1], [3, -1], [2, 0]], (2, 2)) == pytest.approx(3.0)
    assert hypervolume_2d(np.empty((0, 2)), (1, 1)) == 0.0
    rng = np.random.default_rng(2)
    for _ in range(20):
        F = np.round(rng.random((12, 2)) * 1.2, 2)
        assert hypervolume_2d(F, (1.0, 1.0)) == pytest.approx(_hv_grid(F, (1.0, 1.0)), abs=1e-12)


def test_hypervolume_of_true_fronts():
    """The reference values quoted for the benchmarks: ZDT1 0.876667 = 1.21 - 1/3, ZDT2
    0.543333 = 1.21 - 2/3, ZDT3 ~1.33176 (dense samples of the true fronts)."""
    f1 = np.linspace(0.0, 1.0, 200001)
    assert hypervolume_2d(np.c_[f1, 1 - np.sqrt(f1)], (1.1, 1.1)) == pytest.approx(1.21 - 1 / 3, abs=2e-5)
    assert hypervolume_2d(np.c_[f1, 1 - f1**2], (1.1, 1.1)) == pytest.approx(1.21 - 2 / 3, abs=2e-5)
    zdt3_front = np.c_[f1, 1 - np.sqrt(f1) - f1 * np.sin(10 * np.pi * f1)]
    assert hypervolume_2d(zdt3_front, (1.1, 1.1)) == pytest.approx(1.33176, abs=2e-4)


def test_trade_off_selection_by_hand():
    """Front (0, 1), (0.1, 0.6), (0.25, 0.25), (0.6, 0.1), (1, 0): the knee is (0.25, 0.25) at
    0.5/sqrt(2) from the line f1 + f2 = 1, also the point nearest the ideal and the ASF
    minimiser with equal weights; weights (0.2, 0.8) tolerate f2 and pick (0.1, 0.6). Scaling
    an objective changes nothing (the front is normalised by ideal and nadir)."""
    F = np.array([[0, 1], [0.1, 0.6], [0.25, 0.25], [0.6, 0.1], [1, 0]])
    for G in (F, F * [1.0, 100.0] + [5.0, -3.0]):
        assert knee_point(G) == 2
        assert min_distance_to_ideal(G) == 2
        assert asf(G, [1, 1]) == 2
        assert asf(G, [0.2, 0.8]) == 1
        assert asf(G, [0.8, 0.2]) == 3
    # a linear front has no knee: an extreme wins (distance 0), the lowest index on ties
    assert knee_point([[0, 1], [0.5, 0.5], [1, 0]]) == 0
    with pytest.raises(ConfigError):
        asf(F, [1, 0])
    with pytest.raises(ConfigError):
        knee_point(np.ones((3, 3)))


def test_front_quota():
    """First front capped at floor(0.35 N), the rest shared geometrically; if the later fronts
    are too small the first front exceeds its cap."""
    quota = gamultiobj._front_quota(np.array([80, 50, 40, 30]), 100, 0.35)
    assert quota.sum() == 100 and quota[0] == 35
    assert np.all(np.diff(quota[1:]) <= 0) and np.all(quota <= [80, 50, 40, 30])
    quota = gamultiobj._front_quota(np.array([150, 10, 5]), 100, 0.35)
    assert quota.tolist() == [85, 10, 5]
    quota = gamultiobj._front_quota(np.array([20, 60, 60]), 100, 0.35)
    assert quota[0] == 20 and quota.sum() == 100


# --------------------------------------------------------------------------------------------
# Driver behaviour
# --------------------------------------------------------------------------------------------


def _result_arrays(res):
    return [res.X, res.F, res.G, res.CV, res.pop.X, res.pop.F, res.pop.rank, [h.n_front for h in res.history]]


@pytest.mark.parametrize("algorithm", ["nsga2", "gamultiobj"])
def test_same_seed_same_result(algorithm):
    problem = BENCHMARKS["tnk"][0]
    a = minimize(problem, algorithm, pop_size=30, n_gen=20, seed=7)
    b = minimize(problem, algorithm, pop_size=30, n_gen=20, seed=np.random.default_rng(7))
    c = minimize(problem, algorithm, pop_size=30, n_gen=20, seed=8)
    for x, y in zip(_result_arrays(a), _result_arrays(b)):
        np.testing.assert_array_equal(x, y)
    assert not np.array_equal(a.pop.X, c.pop.X)


def _log_objective(X):
    x, y = X[:, 0], X[:, 1]
    return ((x - 1e-6) / 1e-6) ** 2 + (y - 0.5) ** 2, None


def test_log_scale_variables():
    """x in [1e-8, 1] searched in log space: the initial sample is log-uniform (half of it
    below 1e-4, where a uniform sample would put 0.01 % of its points), every point stays in
    bounds, and the optimum x = 1e-6 is found; the linear variable y is unaffected."""
    seen = []

    def evaluate(X):
        seen.append(X.copy())
        return _log_objective(X)

    problem = Problem([1e-8, -1.0], [1.0, 1.0], 1, evaluate, log_scale=[True, False])
    res = minimize(problem, pop_size=40, n_gen=60, seed=3)
    first = seen[0]
    assert 0.3 < np.mean(first[:, 0] < 1e-4) < 0.7
    assert np.mean(first[:, 1] < 0) == pytest.approx(0.5, abs=0.2)
    allx = np.vstack(seen)
    assert np.all((allx >= problem.lower) & (allx <= problem.upper))
    assert res.X[0, 0] == pytest.approx(1e-6, rel=1e-2)
    assert res.X[0, 1] == pytest.approx(0.5, abs=1e-2)
    with pytest.raises(ConfigError):
        Problem([0.0], [1.0], 1, _log_objective, log_scale=[True])


def test_gamultiobj_solves_zdt1_and_returns_rank_one_points():
    """gamultiobj, N = 100 and 500 generations on ZDT1: HV >= 0.80 (seeds 0-4 give
    0.808-0.820); the returned points are the rank-0 members of the final population, mutually
    non-dominated and at most floor(0.35 N) of them."""
    res = minimize(ZDT1, "gamultiobj", pop_size=100, n_gen=500, seed=0)
    assert hypervolume_2d(res.F, (1.1, 1.1)) >= 0.80
    assert 1 <= len(res.X) <= 35
    assert len(non_dominated_sort(res.F)) == 1
    np.testing.assert_array_equal(res.X, res.pop.X[res.pop.rank == 0])
    assert all(h.n_front <= 35 for h in res.history)
    assert res.n_evals == 100 * 500


def test_gamultiobj_pareto_fraction_caps_first_front():
    small = minimize(ZDT1, "gamultiobj", pop_size=60, n_gen=80, seed=1)
    large = minimize(ZDT1, "gamultiobj", pop_size=60, n_gen=80, seed=1, pareto_fraction=0.7)
    assert max(h.n_front for h in small.history) <= 21
    assert max(h.n_front for h in large.history) <= 42
    assert len(large.X) > 21


def test_gamultiobj_constrained():
    """TNK with MATLAB's default population for 2 variables (50): feasible points only."""
    problem, ref, _ = BENCHMARKS["tnk"]
    res = minimize(problem, "gamultiobj", n_gen=200, seed=0)
    assert len(res.pop.X) == 50
    assert res.feasible.all() and np.all(res.CV == 0)
    assert hypervolume_2d(res.F, ref) >= 0.60


def _plateau(X):
    f1 = np.round(4 * X[:, 0]) / 4
    return np.c_[f1, 1 - f1 + np.round(X[:, 1])], None


def test_gamultiobj_stops_when_spread_stalls():
    """Objectives with five distinct optimal values: the front stops changing, the spread
    freezes and the run ends soon after max_stall_generations."""
    problem = Problem([0.0, 0.0], [1.0, 1.0], 2, _plateau)
    res = minimize(problem, "gamultiobj", n_gen=2000, seed=0)
    assert 100 < res.n_gen < 400
    assert "spread" in res.message
    spreads = [h.spread for h in res.history]
    assert spreads[-1] == spreads[-2]


def test_executor_gives_identical_results():
    serial = minimize(ZDT1, "nsga2", pop_size=40, n_gen=15, seed=5)
    with ProcessPoolExecutor(max_workers=2) as ex:
        parallel = minimize(ZDT1, "nsga2", pop_size=40, n_gen=15, seed=5, executor=ex)
        odd_chunks = minimize(ZDT1, "gamultiobj", pop_size=40, n_gen=15, seed=5, executor=ex, n_chunks=3)
    for x, y in zip(_result_arrays(serial), _result_arrays(parallel)):
        np.testing.assert_array_equal(x, y)
    for x, y in zip(_result_arrays(minimize(ZDT1, "gamultiobj", pop_size=40, n_gen=15, seed=5)), _result_arrays(odd_chunks)):
        np.testing.assert_array_equal(x, y)


def test_history_callback_and_progress():
    calls = []

    def callback(gen, pop):
        calls.append((gen.gen, len(pop.X)))
        return gen.gen == 12

    res = minimize(ZDT1, pop_size=20, n_gen=50, seed=0, callback=callback, progress=True, hv_ref=(1.1, 1.1))
    assert res.n_gen == 12 and calls[-1] == (12, 20) and res.message == "stopped by callback"
    assert [h.gen for h in res.history] == list(range(1, 13))
    assert res.history[0].n_evals == 20 and res.n_evals == res.history[-1].n_evals
    hv = [h.hypervolume for h in res.history]
    assert all(b >= a - 1e-12 for a, b in zip(hv, hv[1:]))  # elitism never loses the front
    assert res.history[-1].hypervolume == pytest.approx(hypervolume_2d(res.F, (1.1, 1.1)))


def test_nsga2_offspring_are_not_duplicates():
    """A 1-variable problem on a tiny box: duplicates would be frequent without elimination."""
    problem = Problem([0.0], [1.0], 2, lambda X: (np.c_[X[:, 0], (1 - X[:, 0]) ** 2], None))
    res = minimize(problem, pop_size=30, n_gen=30, seed=0)
    assert len(np.unique(res.pop.X, axis=0)) == len(res.pop.X)


def test_infeasible_only_returns_least_violating():
    problem = Problem([0.0, 0.0], [1.0, 1.0], 2, lambda X: (X.copy(), np.c_[1.5 - X.sum(axis=1) + 1.0]), n_constr=1)
    res = minimize(problem, pop_size=20, n_gen=30, seed=0)
    assert not res.feasible.any()
    assert np.all(res.CV == res.pop.CV.min())


def test_invalid_inputs():
    with pytest.raises(ConfigError):
        minimize(ZDT1, "nsga3")
    with pytest.raises(ConfigError):
        minimize(ZDT1, "nsga2", pareto_fraction=0.5)
    with pytest.raises(ConfigError):
        Problem([1.0], [0.0], 1, zdt1)
    bad_shape = Problem([0.0, 0.0], [1.0, 1.0], 2, lambda X: (X[:, :1], None))
    with pytest.raises(ValueError, match="shape"):
        minimize(bad_shape, pop_size=10, n_gen=2, seed=0)
    nan = Problem([0.0, 0.0], [1.0, 1.0], 2, lambda X: (np.full((len(X), 2), np.nan), None))
    with pytest.raises(ValueError, match="non-finite"):
        minimize(nan, pop_size=10, n_gen=2, seed=0)


# --------------------------------------------------------------------------------------------
# Warm start and the hypervolume stop
# --------------------------------------------------------------------------------------------

TNK, TNK_REF = BENCHMARKS["tnk"][0], BENCHMARKS["tnk"][1]


def _identity_objectives(X):
    return X.copy(), None


IDENTITY2 = Problem([0.0, 0.0], [1.0, 1.0], 2, _identity_objectives)


def _given_set():
    """30 points of [0, 1]² with F = X: a first front of 8 points on x + y = 1 and 22 points
    strictly above it (dominated)."""
    t = np.linspace(0.0, 1.0, 8)
    front = np.c_[t, 1.0 - t]
    rng = np.random.default_rng(4)
    behind = np.clip(front[rng.integers(0, 8, 22)] + 0.02 + 0.2 * rng.random((22, 2)), 0, 1)
    return front, np.vstack([behind[:11], front, behind[11:]])


def _first_population(problem, algorithm, **kw):
    seen = []
    res = minimize(problem, algorithm, callback=lambda g, pop: seen.append((g, pop)), **kw)
    return res, seen[0]


def _rows_in(A, B):
    return np.array([np.any(np.all(B == a, axis=1)) for a in A])


def test_nsga2_warm_start_selects_by_rank_and_crowding():
    """The 8 front points all survive into the population of 10, with 2 of the dominated ones;
    no evaluation is spent on generation 1, later generations count only their offspring."""
    front, X = _given_set()
    res, (gen1, pop1) = _first_population(IDENTITY2, "nsga2", pop_size=10, n_gen=4, seed=0, initial=(X, X.copy(), None))
    assert gen1.n_evals == 0
    assert _rows_in(pop1.X, X).all() and _rows_in(front, pop1.X).all()
    assert res.n_evals == 3 * 10


def test_gamultiobj_warm_start_selects_by_front_quota_and_crowding():
    """gamultiobj's own trimming: at most floor(0.35 * 10) = 3 points of the first front, its two
    extremes (infinite crowding) among them, the rest from the dominated points."""
    front, X = _given_set()
    _, (gen1, pop1) = _first_population(IDENTITY2, "gamultiobj", pop_size=10, n_gen=2, seed=0, initial=(X, X.copy(), None))
    assert gen1.n_evals == 0
    assert _rows_in(pop1.X, X).all()
    on_front = _rows_in(pop1.X, front)
    assert on_front.sum() == 3 and np.array_equal(np.flatnonzero(on_front), np.flatnonzero(pop1.rank == 0))
    assert _rows_in(front[[0, -1]], pop1.X).all()


@pytest.mark.parametrize("algorithm", ["nsga2", "gamultiobj"])
def test_warm_start_ignores_points_outside_the_bounds_and_tops_up(algorithm):
    """4 distinct points within the bounds (one given twice), 3 outside: the population of 10
    holds the 4 with their exact X (a log-scale variable included, whose log10 round trip is
    inexact) and 6 random points, the only evaluations of generation 1."""
    evaluated = []

    def evaluate(X):
        evaluated.append(X.copy())
        return np.c_[X[:, 0], 1.0 / X[:, 1]], None

    problem = Problem([0.0, 1e7], [1.0, 8e8], 2, evaluate, log_scale=[False, True])
    inside = np.array([[0.1, 2e7], [0.5, 3e7], [0.7, 7e8], [0.9, 9e7]])
    assert np.any(10 ** np.log10(inside[:, 1]) != inside[:, 1])
    outside = np.array([[0.5, 9e8], [-0.1, 1e8], [np.nan, np.nan]])
    X = np.vstack([inside, inside[:1], outside])
    F = np.c_[X[:, 0], 1.0 / X[:, 1]]
    _, (gen1, pop1) = _first_population(problem, algorithm, pop_size=10, n_gen=1, seed=0, initial=(X, F, None))
    assert gen1.n_evals == 6 and len(evaluated) == 1 and len(evaluated[0]) == 6
    assert _rows_in(inside, pop1.X).all() and not _rows_in(outside[:2], pop1.X).any()
    assert not _rows_in(evaluated[0], inside).any()


def _zdt1_3(X):
    f1, g = X[:, 0], 1.0 + 4.5 * X[:, 1:].sum(axis=1)
    return np.c_[f1, g * (1.0 - np.sqrt(f1 / g))], None


ZDT1_3 = Problem(np.zeros(3), np.ones(3), 2, _zdt1_3)


@pytest.mark.parametrize("seed", range(3))
def test_warm_start_reaches_the_cold_hypervolume_with_fewer_evaluations(seed):
    """ZDT1 with 3 variables and a sweep-like grid: x1 in 11 steps, x2 and x3 in
    {0.02, 0.3, 0.6, 1.5} (1.5 is outside the bounds, as are sweep cases outside the
    optimiser's), the optimum x2 = x3 = 0 not on it. The cold run: 40 × 80 generations. The
    warm run, same seed, from the grid (99 of its 176 points within the bounds) with the hypervolume stop
    (1e-3, 5): it stops earlier, ends with >= 99.5 % of the cold run's final hypervolume, and
    passes 99.5 % of it after fewer evaluations than the cold run."""
    x1, other = np.linspace(0, 1, 11), (0.02, 0.3, 0.6, 1.5)
    X = np.array([(a, b, c) for a in x1 for b in other for c in other])
    F, _ = _zdt1_3(X)
    ref = (1.1, 1.1)
    cold = minimize(ZDT1_3, pop_size=40, n_gen=80, seed=seed, hv_ref=ref)
    warm = minimize(ZDT1_3, pop_size=40, n_gen=80, seed=seed, hv_ref=ref, initial=(X, F, None), stop_hv=(1e-3, 5))
    hv_cold = cold.history[-1].hypervolume
    assert warm.history[0].n_evals == 0 and "hypervolume" in warm.message
    assert warm.n_evals < cold.n_evals
    assert warm.history[-1].hypervolume >= 0.995 * hv_cold
    reached = lambda r: next(h.n_evals for h in r.history if h.hypervolume >= 0.995 * hv_cold)
    assert reached(warm) < reached(cold)
    assert warm.history[0].hypervolume < 0.9 * hv_cold  # the grid alone is not the answer


def _first_stop(history, tol, window):
    """The generation the stop rule should end the run at, from the recorded hypervolumes."""
    hv = [h.hypervolume for h in history]
    for g in range(window + 1, len(hv) + 1):
        last = hv[g - window - 1 : g]
        if last[-1] > 0 and (max(last) - min(last)) / last[-1] < tol:
            return g
    return None


def _steps(X):
    """A front of 21 points, f1 = k/20 and f2 = 1 - f1, reached only with x2 < 0.1."""
    f1 = np.round(20 * X[:, 0]) / 20
    return np.c_[f1, 1 - f1 + np.floor(10 * X[:, 1]) / 10], None


def test_hv_stop_ends_the_run_when_the_front_stops_moving():
    """The front fills up over the first generations, then cannot move: the run stops at the
    first generation whose last 6 hypervolumes are equal, with the complete front, long before
    n_gen."""
    f1 = np.arange(21) / 20
    best = hypervolume_2d(np.c_[f1, 1 - f1], (1.1, 2.1))
    res = minimize(Problem([0.0, 0.0], [1.0, 1.0], 2, _steps), pop_size=30, n_gen=300, seed=0, hv_ref=(1.1, 2.1), stop_hv=(1e-9, 5))
    assert "hypervolume" in res.message and res.n_gen < 40
    assert res.n_gen == _first_stop(res.history, 1e-9, 5)
    assert res.history[-1].hypervolume == pytest.approx(best, rel=1e-12)
    assert len({h.hypervolume for h in res.history[-6:]}) == 1
    assert res.history[0].hypervolume < best - 0.1


def test_hv_stop_does_not_end_a_run_whose_front_still_moves():
    res = minimize(ZDT1, pop_size=30, n_gen=25, seed=0, hv_ref=(1.1, 1.1), stop_hv=(1e-3, 5))
    assert res.message == "reached n_gen = 25"
    assert _first_stop(res.history, 1e-3, 5) is None


def test_warm_start_and_stop_inputs_are_checked():
    X = np.full((3, 2), 0.5)
    with pytest.raises(ConfigError, match="initial.F"):
        minimize(IDENTITY2, pop_size=4, n_gen=1, initial=(X, X[:, :1], None))
    with pytest.raises(ConfigError, match="initial.G"):
        minimize(TNK, pop_size=4, n_gen=1, initial=(X, X, None))
    with pytest.raises(ConfigError, match="initial"):
        minimize(IDENTITY2, pop_size=4, n_gen=1, initial=X)
    with pytest.raises(ConfigError, match="hv_ref"):
        minimize(IDENTITY2, pop_size=4, n_gen=1, stop_hv=(1e-3, 5))
    for bad in [(0.0, 5), (1e-3, 0), (1e-3, 2.5), (1e-3, 5, 1), ("tight", 5), 1e-3]:
        with pytest.raises(ConfigError, match="stop_hv"):
            minimize(IDENTITY2, pop_size=4, n_gen=1, hv_ref=(2, 2), stop_hv=bad)


# --------------------------------------------------------------------------------------------
# Checkpoint and resume
# --------------------------------------------------------------------------------------------


class Killed(Exception):
    """Stands for the kill of a run."""


def _same_run(a, b):
    for x, y in zip(_result_arrays(a) + [a.pop.G, a.pop.CV], _result_arrays(b) + [b.pop.G, b.pop.CV]):
        assert np.array_equal(x, y)
    assert a.history == b.history  # every field of every generation, floats compared exactly
    assert (a.n_evals, a.n_gen, a.message) == (b.n_evals, b.n_gen, b.message)


def _counting(problem):
    """``problem`` with an evaluate that counts its calls and raises Killed at call ``kill_at``."""
    calls = []

    def evaluate(X):
        calls.append(len(X))
        if len(calls) == evaluate.kill_at:
            raise Killed
        return problem.evaluate(X)

    evaluate.kill_at = None
    return Problem(problem.lower, problem.upper, problem.n_obj, evaluate, problem.n_constr, problem.log_scale), calls


@pytest.mark.parametrize("algorithm", ["nsga2", "gamultiobj"])
def test_killed_run_resumes_bitwise_identical(algorithm, tmp_path):
    """Killed in the callback after generation 6, then killed again in the middle of generation
    11 (inside the evaluation): the run resumed from its checkpoint gives exactly the result,
    history and evaluation count of an uninterrupted run, and evaluates only the generations
    after the last checkpoint."""
    kw = dict(pop_size=24, n_gen=15, seed=11, hv_ref=TNK_REF)
    reference = minimize(TNK, algorithm, **kw)
    problem, calls = _counting(TNK)
    ck = tmp_path / "run.ckpt"

    def kill(gen, pop):
        if gen.gen == 6:
            raise Killed

    with pytest.raises(Killed):
        minimize(problem, algorithm, checkpoint=ck, callback=kill, **kw)
    assert len(calls) == 6
    problem.evaluate.kill_at = 11
    with pytest.raises(Killed):
        minimize(problem, algorithm, checkpoint=ck, **kw)
    problem.evaluate.kill_at = None
    calls.clear()
    resumed = minimize(problem, algorithm, checkpoint=ck, **kw)
    assert len(calls) == 15 - 10  # generations 11..15
    _same_run(reference, resumed)
    assert [p.name for p in tmp_path.iterdir()] == ["run.ckpt"]  # no temporary file left
    # a finished run's checkpoint gives the result again without evaluating
    calls.clear()
    _same_run(reference, minimize(problem, algorithm, checkpoint=ck, **kw))
    assert calls == []


def test_a_resumed_run_counts_the_wall_time_of_every_session(tmp_path):
    """Each generation records the run's wall time so far; a run killed after generation 3 and
    resumed goes on from the time its first session took, so its last generation holds at least
    the time its evaluations slept in both (0.02 s each); a checkpoint written before the record
    resumes with the time unknown."""
    import json
    import time

    def slow(X):
        time.sleep(0.02)
        return TNK.evaluate(X)

    problem = Problem(TNK.lower, TNK.upper, TNK.n_obj, slow, TNK.n_constr)
    kw = dict(pop_size=12, n_gen=6, seed=3, hv_ref=TNK_REF)
    ck = tmp_path / "run.ckpt"

    def kill(gen, pop):
        if gen.gen == 3:
            raise Killed

    with pytest.raises(Killed):
        minimize(problem, "nsga2", checkpoint=ck, callback=kill, **kw)
    with np.load(ck) as z:
        state = {k: z[k] for k in z.files}
    header = json.loads(str(state.pop("header")))
    first = header["history"][-1]["seconds"]
    assert first >= 3 * 0.02
    res = minimize(problem, "nsga2", checkpoint=ck, **kw)
    seconds = [g.seconds for g in res.history]
    assert seconds[2] == first and seconds == sorted(seconds) and seconds[-1] >= first + 3 * 0.02
    # the same checkpoint without the record: the time is unknown, not a guess
    header["history"] = [{k: v for k, v in g.items() if k != "seconds"} for g in header["history"]]
    np.savez(tmp_path / "old.npz", header=np.array(json.dumps(header)), **state)
    old = minimize(problem, "nsga2", checkpoint=tmp_path / "old.npz", **kw)
    assert all(g.seconds is None for g in old.history) and old.history == res.history


def test_gamultiobj_resumed_run_keeps_its_spread_memory(tmp_path):
    """The stall test looks back max_stall_generations spreads: a run killed after generation
    4 and resumed stalls at the generation the uninterrupted run stalls at."""
    problem = Problem([0.0, 0.0], [1.0, 1.0], 2, _plateau)
    kw = dict(pop_size=20, n_gen=200, seed=0, max_stall_generations=5)
    reference = minimize(problem, "gamultiobj", **kw)
    assert "spread" in reference.message and 6 < reference.n_gen < 30

    def kill(gen, pop):
        if gen.gen == 4:
            raise Killed

    with pytest.raises(Killed):
        minimize(problem, "gamultiobj", checkpoint=tmp_path / "c", callback=kill, **kw)
    _same_run(reference, minimize(problem, "gamultiobj", checkpoint=tmp_path / "c", **kw))


def test_warm_started_run_with_hv_stop_resumes_bitwise_identical(tmp_path):
    """Initial points and the hypervolume stop are part of the saved run too."""
    X = np.random.default_rng(0).random((40, 2)) * np.pi
    kw = dict(pop_size=20, n_gen=40, seed=2, hv_ref=TNK_REF, initial=(X, *tnk(X)), stop_hv=(1e-3, 3))
    reference = minimize(TNK, **kw)
    assert "hypervolume" in reference.message and 5 < reference.n_gen < 40

    def kill(gen, pop):
        if gen.gen == 4:
            raise Killed

    with pytest.raises(Killed):
        minimize(TNK, checkpoint=tmp_path / "c", callback=kill, **kw)
    _same_run(reference, minimize(TNK, checkpoint=tmp_path / "c", **kw))


def test_checkpoint_of_another_run_is_refused(tmp_path):
    ck = tmp_path / "run.ckpt"
    kw = dict(pop_size=10, n_gen=3, seed=1, checkpoint_identity={"model": "a"})
    minimize(TNK, checkpoint=ck, **kw)
    X = np.full((1, 2), 0.5)
    for change, differs in [
        (dict(seed=2), "seed"), (dict(pop_size=12), "pop_size"), (dict(n_gen=4), "n_gen"),
        (dict(eta_c=10.0), "options"), (dict(checkpoint_identity={"model": "b"}), "problem"),
        (dict(initial=(X, *tnk(X))), "initial"), (dict(hv_ref=TNK_REF), "hv_ref"),
    ]:
        with pytest.raises(ConfigError, match=differs) as e:
            minimize(TNK, checkpoint=ck, **{**kw, **change})
        assert e.value.field == "checkpoint"
    other_bounds = Problem([0.0, 0.0], [3.0, np.pi], 2, tnk, n_constr=2)
    with pytest.raises(ConfigError, match="upper"):
        minimize(other_bounds, checkpoint=ck, **kw)
    with pytest.raises(ConfigError, match="algorithm"):
        minimize(TNK, "gamultiobj", checkpoint=ck, **kw)
    minimize(TNK, checkpoint=ck, **kw)  # the same run is accepted
    with pytest.raises(ConfigError) as e:
        minimize(TNK, pop_size=10, n_gen=3, checkpoint=tmp_path / "x")
    assert e.value.field == "seed"


def test_damaged_checkpoints_are_refused_and_never_unpickled(tmp_path):
    kw = dict(pop_size=10, n_gen=3, seed=1)
    good = tmp_path / "good"
    minimize(TNK, checkpoint=good, **kw)
    data = good.read_bytes()
    truncated, text, pickled, foreign = (tmp_path / n for n in ("truncated", "text", "pickled", "foreign"))
    truncated.write_bytes(data[: len(data) // 2])
    text.write_text("not a checkpoint\n")
    with open(pickled, "wb") as f:
        np.savez(f, header=np.array([{"a": 1}], dtype=object))
    with open(foreign, "wb") as f:
        np.savez(f, header=np.array('{"format": "something else"}'))
    for path, reason in [(truncated, "readable"), (text, "readable"), (pickled, "readable"), (foreign, "not a")]:
        with pytest.raises(ConfigError, match=reason) as e:
            minimize(TNK, checkpoint=path, **kw)
        assert e.value.field == "checkpoint" and str(path) in str(e.value)


def test_a_crash_while_saving_keeps_the_previous_checkpoint(tmp_path, monkeypatch):
    """The save goes through a temporary file: a crash in the middle of writing generation 4
    leaves generation 3's checkpoint intact (and no temporary file), from which the run resumes
    to the uninterrupted result."""
    kw = dict(pop_size=16, n_gen=8, seed=5)
    reference = minimize(TNK, "gamultiobj", **kw)
    ck = tmp_path / "run.ckpt"
    real_savez, saves = np.savez, []

    def crashing_savez(f, **arrays):
        saves.append(1)
        if len(saves) == 4:
            f.write(b"PK\x03\x04 half an archive")
            raise Killed
        real_savez(f, **arrays)

    monkeypatch.setattr(np, "savez", crashing_savez)
    with pytest.raises(Killed):
        minimize(TNK, "gamultiobj", checkpoint=ck, **kw)
    monkeypatch.setattr(np, "savez", real_savez)
    assert [p.name for p in tmp_path.iterdir()] == ["run.ckpt"]
    with np.load(ck) as z:
        assert len(__import__("json").loads(str(z["header"]))["history"]) == 3
    _same_run(reference, minimize(TNK, "gamultiobj", checkpoint=ck, **kw))
