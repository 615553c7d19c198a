"""The generic optimiser: any configuration fields as variables, any indices as objectives and
constraints (``vtb.optimize(config, variables=..., objectives=..., constraints=...)``).

A problem is solved through an **evaluator** (pymoo's Evaluator role, :class:`DesignEvaluator`):
it turns a generation's designs into their configurations, runs them all in one batch (or as
tasks on an executor), keeps every design's rows in a journal beside the checkpoint and scores
them as objectives F and constraints G. :class:`CaseEvaluator` runs one case per design; the
article's robust evaluation over samples and speeds (:class:`vtb.article.robust.RobustEvaluator`)
is another. :func:`solve` is the optimisation itself, whatever the evaluator.

A constraint ``(index, bound)`` is written normalised as X/bound − 1 ≤ 0, a bound being a number
or ``"reference"``: the index of the run with the ``reference`` fields set (e.g. ``{"tids":
None}``). Hypervolumes (history, ``stop_hv``) are those of the feasible first front of two
objectives with the reference run's objectives as reference point.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
from pathlib import Path
from typing import Optional

import numpy as np

from ..config import args
from ..config.fields import Config
from ..errors import config_error, make_folder, stale_file_error, writing
from ..optim import Problem, minimize, saved_identity
from ..optim import Result as OptimResult
from ..optim.checkpoint import check_written_by, written_by
from ..run.indices import index_names
from ..run.scaleout import run_cases
from ..run.simulate import simulate
from ..run.tables import frame, to_parquet, units_of
from .grid import get_field, set_field, with_tids
from .journal import config_stamp, same_config


def checkpoint_identity(config: Config, baseline, checkpoint=None, **extra) -> dict:
    """What an optimisation's evaluations depend on, for its checkpoint: the configuration's
    stamp, a hash of its uncontrolled metrics (``baseline``) and any ``extra`` JSON values.
    When ``checkpoint`` (or its designs journal) already holds the stamp of the same
    configuration written by an earlier schema (:func:`vtb.studies.journal.same_config`), that stamp is
    adopted, so a field added to the schema since does not make the checkpoint stale."""
    stamp = json.loads(config_stamp(config))
    if checkpoint is not None:
        saved = _saved_stamp(Path(checkpoint))
        if saved is not None and saved != stamp and same_config(saved, config):
            stamp = saved
    return {"vtb.optimize": {
        "config": stamp,
        "baseline": hashlib.sha256(json.dumps(baseline, sort_keys=True).encode()).hexdigest(),
        **extra,
    }}


def _saved_stamp(checkpoint: Path):
    """The configuration stamp of the identity a checkpoint (or, before its first generation,
    its designs journal) was written with; ``None`` if there is none to read (the optimiser
    then reports what is wrong with the file)."""
    identity = saved_identity(checkpoint)
    journal = Path(str(checkpoint) + ".designs.jsonl")
    if identity is None and journal.exists():
        try:
            with open(journal) as f:
                identity = {"problem": _designs_header(json.loads(f.readline()))["identity"]}
        except (OSError, ValueError, TypeError):
            return None
    try:
        return identity["problem"]["vtb.optimize"]["config"]
    except (TypeError, KeyError):
        return None


#: The first line of a designs journal: ``{"format": DESIGNS_FORMAT, "vtb": version, "epoch":
#: results epoch, "identity": the optimisation's identity}``.
DESIGNS_FORMAT = "vtb designs journal 1"


def _designs_header(first) -> dict:
    """A designs journal's header from its parsed first line; a journal of a vtb before the
    header held the identity alone (no version, no epoch)."""
    if isinstance(first, dict) and isinstance(first.get("format"), str) and first["format"].startswith("vtb designs journal "):
        return first
    return {"identity": first}


@dataclasses.dataclass
class DesignJournal:
    """The designs an optimisation has evaluated, by (b_t, k_t, c_t): ``cache`` in memory and,
    given ``path`` (JSON lines: a header — :data:`DESIGNS_FORMAT`, the vtb version, the results
    epoch and the optimisation's identity —, then one design per line with its rows), on disk, a design written as soon as all its runs finished, so that an interrupted
    generation resumes without running it again. A run is deterministic, so nothing depends on
    what the journal holds but the time it saves."""

    path: Optional[Path] = None
    cache: dict = dataclasses.field(default_factory=dict)

    def load(self, identity) -> None:
        """Reads ``path`` (its first line must be ``identity``) into the cache, or starts it."""
        if self.path is None:
            return
        if self.path.exists() and self.path.stat().st_size:
            lines = self.path.read_text().splitlines()
            try:
                header = _designs_header(json.loads(lines[0]))
            except ValueError as e:
                raise config_error("checkpoint", str(self.path), f"line 1: not a vtb designs journal ({e})") from None
            fmt = header.get("format", DESIGNS_FORMAT)
            if fmt != DESIGNS_FORMAT:
                raise stale_file_error("checkpoint", self.path, f"line 1: a {fmt!r} file, written by a newer vtb ({header.get('vtb', 'unknown version')}) "
                                                                f"that this vtb reads as {DESIGNS_FORMAT!r}: upgrade vtb, or delete it to start afresh")
            check_written_by(header, "checkpoint", self.path, "line 1: ")
            if header["identity"] != json.loads(json.dumps(identity)):
                raise stale_file_error("checkpoint", self.path, "holds the designs of another optimisation; delete it with its checkpoint to start afresh")
            for line in lines[1:]:
                try:
                    d = json.loads(line)
                except ValueError:  # a line cut short by a kill
                    continue
                self.cache[tuple(d["x"])] = d["rows"]
        else:
            with writing("checkpoint", self.path):
                self.path.write_text(json.dumps({"format": DESIGNS_FORMAT, **written_by(), "identity": identity}) + "\n")

    def add(self, x, rows) -> None:
        self.cache[tuple(x)] = rows
        if self.path is not None:
            with writing("checkpoint", self.path), open(self.path, "a") as f:
                f.write(json.dumps(dict(x=[float(v) for v in x], rows=rows)) + "\n")

    def run(self, X: np.ndarray, configs_of, row_of, threads: Optional[int], executor=None) -> None:
        """Runs every design of X not yet known, in one batch (or tasks on ``executor``,
        :mod:`vtb.run.scaleout`): ``configs_of(x)`` gives its configurations, ``row_of(k, result)``
        the row of its k-th run (a metrics dict or an exception); a design is added once all
        its runs are in."""
        todo = [x for x in dict.fromkeys(map(tuple, X)) if x not in self.cache]
        if not todo:
            return
        per = [configs_of(np.array(x)) for x in todo]
        owner = [(d, k) for d, cs in enumerate(per) for k in range(len(cs))]
        got = [[None] * len(cs) for cs in per]

        def done(i, r):
            d, k = owner[i]
            got[d][k] = row_of(k, r)
            if all(row is not None for row in got[d]):
                self.add(todo[d], got[d])

        run_cases([c for cs in per for c in cs], done, executor=executor, threads=threads)


@dataclasses.dataclass
class DesignEvaluator:
    """What turns a generation's designs (X rows, natural units) into objectives F and
    constraints G (pymoo's Evaluator): every design not yet known runs its configurations
    (:meth:`configs_of`), all of a generation in one batch on ``threads`` cores or as tasks on
    ``executor`` (:mod:`vtb.run.scaleout`); the row of each run (:meth:`row_of`) is kept in
    ``designs``, a design journaled as soon as all its runs are in, and :meth:`score` makes its
    F and G. A subclass is a dataclass (it pickles to workers) that defines ``n_obj``,
    ``n_constr``, :meth:`configs_of`, :meth:`row_of` and :meth:`score`."""

    threads: Optional[int] = dataclasses.field(default=None, kw_only=True)
    designs: DesignJournal = dataclasses.field(default_factory=DesignJournal, kw_only=True)
    executor: object = dataclasses.field(default=None, kw_only=True)

    @property
    def cache(self) -> dict:
        """Every evaluated design's rows, by its X row as a tuple."""
        return self.designs.cache

    def configs_of(self, x: np.ndarray) -> list:
        """The configurations a design runs."""
        raise NotImplementedError

    def row_of(self, k: int, result):
        """What is kept of the k-th run of a design (its metrics, or the exception it failed with)."""
        raise NotImplementedError

    def score(self, rows: list) -> tuple:
        """A design's F and G from its rows."""
        raise NotImplementedError

    def __call__(self, X: np.ndarray):
        X = np.asarray(X, dtype=float)
        self.designs.run(X, self.configs_of, self.row_of, self.threads, self.executor)
        F, G = np.empty((len(X), self.n_obj)), np.empty((len(X), self.n_constr))
        for i, x in enumerate(X):
            F[i], G[i] = self.score(self.cache[tuple(x)])
        return F, G


@dataclasses.dataclass
class CaseEvaluator(DesignEvaluator):
    """One case per design: X rows (the variables' values, in the order of ``paths``) set on
    ``config`` → F (the ``objectives``' indices), G = X/bound − 1 for each ``(index, bound)`` of
    ``constraints`` (X − bound for a bound ≤ 0). A failed run counts as infeasible (G = ∞) with
    F = ``failed``. A design's row is its ``record`` indices (``None`` for a failed run)."""

    config: Config
    paths: tuple
    objectives: tuple
    constraints: tuple
    record: tuple
    failed: tuple

    @property
    def n_obj(self) -> int:
        return len(self.objectives)

    @property
    def n_constr(self) -> int:
        return len(self.constraints)

    def config_of(self, x) -> Config:
        cfg = self.config.copy()
        for p, v in zip(self.paths, x):
            set_field(cfg, p, float(v))
        cfg.output.indices = list(self.record)
        return cfg

    def fg(self, m: Optional[dict]) -> tuple:
        """F and G of one run's recorded indices (``None``: a failed run)."""
        if m is None:
            return list(self.failed), [math.inf] * len(self.constraints)
        return [m[k] for k in self.objectives], [m[k] / b - 1.0 if b > 0 else m[k] - b for k, b in self.constraints]

    def configs_of(self, x) -> list:
        return [self.config_of(x)]

    def row_of(self, k: int, result) -> Optional[dict]:
        return None if isinstance(result, BaseException) else {m: float(result[m]) for m in self.record}

    def score(self, rows: list) -> tuple:
        return self.fg(rows[0])


def solve(evaluator: DesignEvaluator, lower, upper, log_scale, *, algorithm: str, pop_size: int, n_gen: int, seed, progress,
          hv_ref, stop_hv, checkpoint, identity: dict, initial: Optional[tuple] = None, **options) -> tuple:
    """Minimises what ``evaluator`` scores over the box [``lower``, ``upper``] (``log_scale``:
    the variables searched in log10) with :func:`vtb.optim.minimize`, resuming from
    ``checkpoint`` when it exists; every evaluated design is journaled beside it
    (``<checkpoint>.designs.jsonl``, first line ``identity``). Returns the optimiser's result,
    the returned feasible designs X and the rows of each."""
    problem = Problem(lower=lower, upper=upper, n_obj=evaluator.n_obj, n_constr=evaluator.n_constr, evaluate=evaluator,
                      log_scale=np.array(log_scale))
    if checkpoint is not None:
        make_folder(Path(checkpoint).parent, "checkpoint")
        evaluator.designs.path = Path(str(checkpoint) + ".designs.jsonl")
    evaluator.designs.load(identity)
    res = minimize(problem, algorithm, pop_size=pop_size, n_gen=n_gen, seed=seed, progress=progress, hv_ref=hv_ref, initial=initial,
                   stop_hv=stop_hv, checkpoint=checkpoint, checkpoint_identity=identity, **options)
    X = res.X[res.feasible] if np.any(res.feasible) else res.X[:0]
    missing = [x for x in X if tuple(x) not in evaluator.cache]
    if missing:
        evaluator(np.array(missing))
    return res, X, [evaluator.cache[tuple(x)] for x in X]


def _problem_spec(config: Config, variables, objectives, constraints, reference) -> tuple:
    """Checked variables [(path, low, high, log)], objectives, constraints [(index, bound)]
    and the reference run's indices (or None); every bad entry raises ConfigError naming it."""
    if not isinstance(variables, dict) or not variables:
        raise config_error("variables", variables, "must be a non-empty mapping {field path: (low, high, 'log' | 'linear')}")
    spec = []
    for path, bounds in variables.items():
        get_field(with_tids(config, path), path)
        if not isinstance(bounds, (tuple, list)) or len(bounds) not in (2, 3):
            raise config_error(f"variables[{path!r}]", bounds, "must be (low, high) or (low, high, 'log' | 'linear')")
        lo, hi, scale = (*bounds, "linear") if len(bounds) == 2 else bounds
        if scale not in ("log", "linear"):
            raise config_error(f"variables[{path!r}]", scale, "the scale must be 'log' or 'linear'")
        for v in (lo, hi):
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise config_error(f"variables[{path!r}]", v, "bounds must be finite numbers")
        if not lo < hi or (scale == "log" and lo <= 0):
            raise config_error(f"variables[{path!r}]", (lo, hi), "needs low < high" + (" and low > 0 on a log scale" if scale == "log" else ""))
        spec.append((path, float(lo), float(hi), scale == "log"))
    names = index_names(config)
    if isinstance(objectives, str) or not objectives:
        raise config_error("objectives", objectives, "must be a non-empty list of index names")
    for m in objectives:
        if m not in names:
            raise config_error("objectives", m, f"not an index of this configuration (known: {', '.join(names)})")
    cons = []
    for c in constraints or ():
        if not isinstance(c, (tuple, list)) or len(c) != 2 or c[0] not in names:
            raise config_error("constraints", c, f"each must be (index, bound) with an index of this configuration (known: {', '.join(names)})")
        if not (c[1] == "reference" or (isinstance(c[1], (int, float)) and not isinstance(c[1], bool) and math.isfinite(c[1]))):
            raise config_error("constraints", c, "the bound must be a finite number or 'reference'")
        cons.append((c[0], c[1]))
    ref = None
    if args.mapping("reference", reference, none=True) is not None:
        cfg = config.copy()
        for path, value in reference.items():
            set_field(cfg, path, value)
        ref = simulate(cfg).metrics()
    elif any(b == "reference" for _, b in cons):
        raise config_error("reference", None, "a constraint bounded by 'reference' needs the reference run's fields, e.g. {'tids': None}")
    cons = [(m, ref[m] if b == "reference" else float(b)) for m, b in cons]
    return spec, tuple(objectives), tuple(cons), ref


@dataclasses.dataclass
class ParetoResult:
    """The returned (feasible, non-dominated) designs of :func:`optimize` over user-named
    variables: numpy columns in ``pareto`` — each variable by its path and every recorded index
    (SI units) —, ``objectives`` and ``constraints`` as solved, the ``reference`` run's indices
    (or None), the optimiser's :class:`vtb.optim.Result` and the ``config``."""

    pareto: dict
    variables: tuple
    objectives: tuple
    constraints: tuple
    reference: Optional[dict]
    moga: OptimResult
    config: Config

    def __len__(self) -> int:
        return len(self.pareto[self.variables[0]])

    def to_pandas(self):
        """The designs as a DataFrame, one row each, units in ``attrs["units"]`` (needs pandas)."""
        return frame(self.pareto, units_of(self.pareto))

    def to_parquet(self, path) -> None:
        """Parquet export of :meth:`to_pandas` (needs pyarrow)."""
        to_parquet(self.to_pandas(), path)


def optimize_fields(config: Config, variables: dict, objectives, constraints, reference: Optional[dict], report, *, pop_size: int,
                    n_gen: int, seed: int, algorithm: str, threads: Optional[int], executor, progress, stop_hv, checkpoint,
                    **options) -> ParetoResult:
    """:func:`vtb.optimize` over user-named ``variables`` and indices (see there): one
    :class:`CaseEvaluator` per design, solved by :func:`solve`."""
    spec, objectives, cons, ref = _problem_spec(config, variables, objectives, constraints, reference)
    paths = tuple(p for p, *_ in spec)
    base = config
    if any(p.startswith("tids") for p in paths) and config.tids is None:
        base = with_tids(config, next(p for p in paths if p.startswith("tids")))
    record = tuple(dict.fromkeys([*objectives, *(m for m, _ in cons), *(report or ())]))
    names = index_names(config)
    for m in record:
        if m not in names:
            raise config_error("report", m, f"not an index of this configuration (known: {', '.join(names)})")
    failed = tuple(10 * abs(ref[m]) if ref and ref[m] else 1e300 for m in objectives)
    evaluator = CaseEvaluator(base, paths, objectives, tuple(cons), record, failed, threads=threads, executor=executor)
    identity = checkpoint_identity(base, ref, checkpoint, paths=list(paths), objectives=list(objectives), constraints=[list(c) for c in cons], record=list(record))
    hv_ref = tuple(ref[m] for m in objectives) if ref is not None and len(objectives) == 2 else None
    res, X, design_rows = solve(evaluator, [s[1] for s in spec], [s[2] for s in spec], [s[3] for s in spec], algorithm=algorithm,
                                pop_size=pop_size, n_gen=n_gen, seed=seed, progress=progress, hv_ref=hv_ref, stop_hv=stop_hv,
                                checkpoint=checkpoint, identity=identity, **options)
    rows = [r[0] for r in design_rows]
    pareto = {p: X[:, j] for j, p in enumerate(paths)}
    pareto.update({m: np.array([r[m] for r in rows]) for m in record})
    order = np.argsort(pareto[objectives[0]], kind="stable")
    return ParetoResult({k: v[order] for k, v in pareto.items()}, paths, objectives, tuple(cons), ref, res, base)
