"""The driver: :func:`minimize` runs ``"nsga2"`` (:mod:`vtb.optim.nsga2`) or ``"gamultiobj"``
(:mod:`vtb.optim.gamultiobj`) on a :class:`~vtb.optim.problem.Problem`.

Generation counts include the initial population: ``n_gen = 200`` evaluates the random
population and then 199 generations of offspring (pymoo's convention).

Both algorithms can start warm from points evaluated beforehand (``initial``: the first
population is chosen from them by the algorithm's own selection and they cost no evaluation),
stop when the hypervolume of the front stops moving (``stop_hv``), and save their whole state
after every generation to a checkpoint file from which a killed run resumes with a bitwise
identical result (``checkpoint``); see :func:`minimize`.
"""

from __future__ import annotations

import math
import numbers
import os
import time
from pathlib import Path
from typing import Callable, Optional, Union

import numpy as np

from ..config import args
from ..errors import config_error, make_folder
from .algorithm import _Evaluator, _Space, _new_points
from .checkpoint import _identity, _resume, _save_checkpoint
from .gamultiobj import GAMULTIOBJ_DEFAULTS, _Gamultiobj
from .indicators import hypervolume_2d, hypervolume_settled
from .nsga2 import NSGA2_DEFAULTS, _NSGA2
from .problem import Generation, Population, Problem, Result, constraint_violation

# (lower, upper, lower bound excluded) of each option
_OPTION_RANGES = dict(
    eta_c=(0, np.inf, True), prob_c=(0, 1, False), prob_var_c=(0, 1, False), eta_m=(0, np.inf, True),
    prob_m=(0, 1, False), prob_var_m=(0, 1, False), pareto_fraction=(0, 1, True), crossover_fraction=(0, 1, False),
    function_tolerance=(0, np.inf, False), max_stall_generations=(1, np.inf, False), mutation_scale=(0, np.inf, False),
)


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
    pop_size, n_gen, opts, stop_hv = _settings(problem, algorithm, pop_size, n_gen, options, hv_ref, stop_hv)
    check_budget(pop_size, n_gen, seed)
    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
    space = _Space(problem)
    given = _given_points(problem, space, initial)
    evaluate = _Evaluator(problem, space, executor, n_chunks)
    if algorithm == "nsga2":
        algo = _NSGA2(space, evaluate, rng, pop_size, opts)
    else:
        algo = _Gamultiobj(space, evaluate, rng, pop_size, opts, max(n_gen - 1, 1))

    history, message, identity = [], "", None
    if checkpoint is not None:
        if seed is None:
            raise config_error("seed", None, "a checkpointed run needs a seed (an int or a Generator) to be resumable")
        checkpoint = make_folder(Path(checkpoint).parent, "checkpoint") / Path(checkpoint).name
        identity = _identity(problem, algorithm, pop_size, n_gen, opts, rng, hv_ref, stop_hv, given, checkpoint_identity)
        if checkpoint.exists():
            history, message = _resume(checkpoint, identity, algo, rng, evaluate, n_gen)
    history, message = _generations(algo, given, evaluate, rng, history, message, n_gen, hv_ref, stop_hv, callback,
                                    f"vtb {algorithm}" if progress else None, checkpoint, identity)
    pop = algo.population()
    best = pop.rank == 0
    return Result(
        X=pop.X[best], F=pop.F[best], G=pop.G[best], CV=pop.CV[best], feasible=pop.CV[best] <= 0,
        pop=pop, history=history, n_evals=evaluate.n_evals, n_gen=len(history), algorithm=algorithm,
        message=message,
    )


#: The largest population and generation count :func:`minimize` takes, and the most designs
#: (population × generations) one optimisation evaluates.
MAX_POP_SIZE, MAX_GENERATIONS, MAX_EVALUATIONS = 100_000, 1_000_000, 10_000_000


def check_budget(pop_size, n_gen, seed=None, algorithm=None) -> None:
    """The budget (``pop_size`` ≥ 2, ``n_gen`` ≥ 1, None: the algorithm's default), a ``seed``
    (an int ≥ 0, None or a numpy Generator) and the ``algorithm`` name, checked before any work
    (:func:`vtb.optimize` calls it first)."""
    args.whole("pop_size", pop_size, 2, MAX_POP_SIZE, none=True)
    args.whole("n_gen", n_gen, 1, MAX_GENERATIONS, none=True)
    if pop_size is not None and n_gen is not None and pop_size * n_gen > MAX_EVALUATIONS:
        raise config_error("n_gen", n_gen, f"pop_size × n_gen = {pop_size * n_gen} designs exceeds {MAX_EVALUATIONS}")
    if not isinstance(seed, np.random.Generator):
        args.whole("seed", seed, 0, none=True)
    if algorithm is not None and algorithm not in ("nsga2", "gamultiobj"):
        raise config_error("algorithm", algorithm, "must be \"nsga2\" or \"gamultiobj\"")


def _settings(problem, algorithm: str, pop_size, n_gen, options: dict, hv_ref, stop_hv) -> tuple:
    """The checked budget, options (with the algorithm's defaults) and ``stop_hv`` of :func:`minimize`."""
    if not isinstance(problem, Problem):
        raise config_error("problem", type(problem).__name__, "must be a vtb.optim.Problem")
    defaults = {"nsga2": NSGA2_DEFAULTS, "gamultiobj": GAMULTIOBJ_DEFAULTS}.get(algorithm)
    if defaults is None:
        raise config_error("algorithm", algorithm, "must be \"nsga2\" or \"gamultiobj\"")
    unknown = sorted(set(options) - set(defaults))
    if unknown:
        raise config_error("options", unknown, f"unknown for {algorithm}; known: {sorted(defaults)}")
    opts = {**defaults, **options}
    n_var = problem.n_var
    check_budget(pop_size, n_gen)
    if pop_size is None:
        pop_size = 100 if algorithm == "nsga2" else (50 if n_var <= 5 else 200)
    if n_gen is None:
        n_gen = 200 if algorithm == "nsga2" else 200 * n_var + 1
    pop_size, n_gen = int(pop_size), int(n_gen)
    for name, value in opts.items():
        lo, hi, open_lo = _OPTION_RANGES[name]
        if value is not None and (isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value)
                                  or not ((lo < value if open_lo else lo <= value) and value <= hi)):
            raise config_error(name, value, f"must be a number in {'(' if open_lo else '['}{lo}, {hi}]")
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
    return pop_size, n_gen, opts, stop_hv


def _generations(algo, given, evaluate, rng, history: list, message: str, n_gen: int, hv_ref, stop_hv, callback, bar_label,
                 checkpoint, identity) -> tuple:
    """Runs generations until a stop reason (:func:`_stop_reason`, or the callback's), each
    summarised into ``history`` and checkpointed; returns the history and the reason."""
    bar = None
    if bar_label is not None:
        from tqdm.auto import tqdm

        bar = tqdm(total=n_gen, initial=len(history), desc=bar_label, unit="gen")
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
    return history, message


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
