"""Studies over any field and any index: ``vtb.study(config, {path: values, ...})``.

A study runs the Cartesian product of the values given for configuration fields named by
their dotted paths (``"speed"``, ``"tids.stiffness"``, ``"structure.couplings[0].stiffness"``,
``"irregularity.seed"``; the aliases of :data:`ALIASES` name the dampers' b_t, k_t, c_t) and
reports the indices named (``output.indices``: every index the core computes for the
configuration, :func:`index_names`). Its runs are lockstep batches in Rust or tasks on any
:class:`concurrent.futures.Executor`, Dask's included (:mod:`vtb.run.scaleout`); with ``out=``
every finished case is journaled as soon as its group finishes (:mod:`vtb.studies.journal`), and a
re-run with the same path runs only the cases the journal lacks.

The article's TID sweep (:func:`vtb.sweep`) is this study over ``b_t, k_t, c_t`` with the
uncontrolled run (``tids = None``) as its reference case.
"""

from __future__ import annotations

import contextlib
import dataclasses
import itertools
import math
import numbers
import re
from concurrent.futures import Executor
from pathlib import Path
from typing import Mapping, Optional, Sequence, Union

import numpy as np

from . import journal as jr
from ..config import args
from ..config.fields import Config
from ..config.presets import tids_around
from ..errors import VtbError, check_folder, config_error, make_folder, writing
from ..run.indices import index_names
from ..run.scaleout import run_cases
from ..run.tables import frame, require_pandas, require_pyarrow, to_parquet, units_of

#: Short names of fields: the dampers' inertance, stiffness and damping as the article names them.
ALIASES = {
    "b_t": "tids.inertance", "k_t": "tids.stiffness", "c_t": "tids.damping",
    "tids.b_t": "tids.inertance", "tids.k_t": "tids.stiffness", "tids.c_t": "tids.damping",
}
#: The most cases one study runs (a grid's product, or the cases given); checked before any run.
MAX_CASES = 1_000_000
_PART = re.compile(r"\.?([A-Za-z_]\w*)|\[(\d+)\]")


def _parts(path: str) -> list:
    """``"a.b[0].c"`` → ``["a", "b", 0, "c"]``; a malformed path raises ConfigError naming it."""
    if not isinstance(path, str) or not path.strip():
        raise config_error("study variable", path, "must be a dotted field path such as 'speed' or 'tids.stiffness'")
    real = ALIASES.get(path, path)
    parts, at = [], 0
    while at < len(real):
        m = _PART.match(real, at)
        if m is None or (at == 0 and real.startswith(".")):
            raise config_error(path, real, f"is not a field path (bad at character {at + 1}); write e.g. 'structure.couplings[0].stiffness'")
        parts.append(m.group(1) if m.group(1) is not None else int(m.group(2)))
        at = m.end()
    return parts


def _step(obj, part, path: str):
    if isinstance(part, int):
        if not isinstance(obj, list) or part >= len(obj):
            raise config_error(path, part, f"index out of range (the list has {len(obj) if isinstance(obj, list) else 0} items)")
        return obj[part]
    if isinstance(obj, Config) and isinstance(part, str):
        # a damper group by its name (``tids`` is also a property: None without the group)
        group = next((g for g in obj.dampers if getattr(g, "name", None) == part), None)
        if group is not None or isinstance(getattr(Config, part, None), property):
            return group
    if not dataclasses.is_dataclass(obj) or part not in {f.name for f in dataclasses.fields(obj)}:
        known = sorted(f.name for f in dataclasses.fields(obj)) if dataclasses.is_dataclass(obj) else []
        raise config_error(path, part, f"no such field of {type(obj).__name__}" + (f" (known: {', '.join(known)})" if known else ""))
    return getattr(obj, part)


def get_field(config: Config, path: str):
    """The value of the field at ``path`` (dotted, with ``[i]`` list indices, or an alias)."""
    obj = config
    for part in _parts(path):
        obj = _step(obj, part, path)
    return obj


def set_field(config: Config, path: str, value) -> None:
    """Sets the field at ``path`` in place. An integer field takes an integral number as an int;
    a damper field of a configuration without dampers first gets :func:`vtb.tids_around`'s."""
    parts = _parts(path)
    if parts[0] == "tids" and len(parts) > 1 and config.tids is None:
        config.tids = tids_around(config)
    obj = config
    for part in parts[:-1]:
        obj = _step(obj, part, path)
    old = _step(obj, parts[-1], path)
    if isinstance(old, int) and not isinstance(old, bool) and isinstance(value, numbers.Real) and float(value).is_integer():
        value = int(value)
    if isinstance(parts[-1], int):
        obj[parts[-1]] = value
    else:
        setattr(obj, parts[-1], value)


def _values(path: str, values) -> list:
    if isinstance(values, (str, bytes)) or not isinstance(values, (Sequence, np.ndarray)) or len(values) == 0:
        raise config_error(path, values, "needs a non-empty list of values")
    out = []
    for v in values:
        if isinstance(v, bool) or not isinstance(v, numbers.Real) or not math.isfinite(v):
            raise config_error(path, v, "study values must be finite numbers")
        out.append(float(v))
    return out


@dataclasses.dataclass
class StudyResult:
    """A finished study: numpy ``columns`` — ``case`` (0: the reference case, if any, with NaN
    variables), one per variable (labelled as given), one per index (SI units, NaN where the
    case failed, :func:`vtb.metric_unit`) and ``error`` (empty, or the failure) —, the
    ``variables`` and ``indices`` in order, and the studied ``config``; ``journal``: the journal
    file its cases were read from or written to (None without one)."""

    columns: dict
    config: Config
    variables: tuple = ()
    indices: tuple = ()
    journal: Optional[str] = None

    def __len__(self) -> int:
        return len(self.columns["case"])

    @property
    def succeeded(self) -> np.ndarray:
        """Boolean mask of the successful cases (the reference case included)."""
        return self.columns["error"] == ""

    @property
    def reference(self) -> dict:
        """The indices of the reference case (case 0)."""
        i = np.flatnonzero(self.columns["case"] == 0)
        if i.size == 0 or self.columns["error"][i[0]]:
            raise VtbError("the study has no successful reference case (case 0): " + (str(self.columns["error"][i[0]]) if i.size else "missing"))
        return {k: float(self.columns[k][i[0]]) for k in self.indices}

    def best(self, index: str) -> dict:
        """The successful case (not the reference) with the lowest ``index``: its variables and
        indices."""
        if index not in self.indices:
            raise config_error("index", index, f"not an index of this study (known: {', '.join(self.indices)})")
        ok = self.succeeded & (self.columns["case"] > 0)
        if not ok.any():
            raise VtbError("the study has no successful case")
        i = np.flatnonzero(ok)[np.argmin(self.columns[index][ok])]
        return {k: float(self.columns[k][i]) for k in (*self.variables, *self.indices)}

    def to_pandas(self):
        """The columns as a DataFrame, index units in ``attrs["units"]`` (needs pandas)."""
        return frame(self.columns, units_of(self.columns))

    def to_csv(self, path) -> None:
        """CSV export of the columns (with the case numbers; not a journal)."""
        cols = ("case", *self.variables, *self.indices, "error")
        Path(path).write_text(jr.csv_text([dict(zip(cols, row)) for row in zip(*(self.columns[c] for c in cols))], cols, header=True))

    def to_parquet(self, path) -> None:
        """Parquet export of :meth:`to_pandas`, units in its metadata (needs pyarrow)."""
        to_parquet(self.to_pandas(), path)


def rows_of(cases: list, results: list, layout: jr.Layout) -> list:
    """The journal rows of cases (dicts with ``case`` and the variables) from their runs
    (metrics, or the exception a run failed with)."""
    rows = []
    for case, r in zip(cases, results):
        row = dict(case)
        if isinstance(r, BaseException):
            row.update({m: math.nan for m in layout.values}, error=" ".join(f"{type(r).__name__}: {r}".split()))
        else:
            row.update({m: float(r[m]) for m in layout.values}, error="")
        rows.append(row)
    return rows


def result_of(rows: list, config: Config, layout: jr.Layout, cls=StudyResult, journal=None):
    """Rows as a result (ordered by case), kept with their ``journal`` file if any."""
    rows = sorted(rows, key=lambda r: r["case"])
    cols = ("case",) + layout.columns
    columns = {k: np.array([r[k] for r in rows], dtype=str if k == "error" else float) for k in cols}
    columns["case"] = columns["case"].astype(int)
    return cls(columns=columns, config=config, variables=tuple(layout.keys), indices=tuple(layout.values),
               journal=None if journal is None else str(journal))


def read_journal(path: Union[str, Path], field: str = "path", layout: Optional[jr.Layout] = None, result_class=StudyResult) -> StudyResult:
    """A study journal as a result, without running anything: the configuration of its stamp,
    the variables and indices of its header (or ``layout``), one row per key (the last
    successful one), the reference case as case 0 and the others numbered in the order of their
    variables' values (the first variable slowest: a grid's own order for ascending values) —
    not in the order they finished, so the same study run twice, resumed or on Dask reads back
    equal. A malformed journal raises a :class:`ConfigError` naming ``field`` and the line."""
    path = args.path(field, path)
    if not path.is_file():
        raise config_error(field, str(path), "no such study journal")
    config, layout, rows = jr.parse(path, field, layout)
    if config is None:
        raise config_error(field, str(path), "is an empty file, not a study journal")
    ordered = sorted(rows.items(), key=lambda kv: (kv[0] is not None, kv[0] or ()))  # the reference first
    start = 0 if ordered and ordered[0][0] is None else 1
    return result_of([dict(r, case=start + i) for i, (_, r) in enumerate(ordered)], config, layout, result_class, journal=path)


def case_config(config: Config, case: dict, variables: Sequence[str], indices: Sequence[str], reference: Optional[Mapping] = None) -> Config:
    """The configuration of one case: ``config`` with its variables set (all NaN: the
    ``reference`` fields set instead), reporting ``indices``."""
    cfg = config.copy()
    if all(math.isnan(case[v]) for v in variables):
        for path, value in (reference or {}).items():
            set_field(cfg, path, value)
    else:
        for v in variables:
            set_field(cfg, v, case[v])
    cfg.output.indices = list(indices)
    return cfg


def plan(config: Config, grid: Optional[Mapping] = None, *, cases: Optional[Sequence[Mapping]] = None, reference: Optional[Mapping] = None,
         indices: Optional[Sequence[str]] = None) -> tuple:
    """The layout, the cases (dicts: ``case`` and each variable; the reference case 0 with NaN
    variables first, if any) and the configuration of each, checked before any run: a bad path,
    value or index raises :class:`ConfigError` naming it, and the first case is validated."""
    if not isinstance(config, Config):
        raise config_error("config", type(config).__name__, "expected a vtb.Config")
    if (grid is None) == (cases is None):
        raise config_error("grid", grid, "give either a grid {path: values} or cases [{path: value}, ...]")
    reference = args.mapping("reference", reference, none=True)
    if reference is not None:
        for p, v in reference.items():
            get_field(with_tids(config, p), p)  # the path exists
            if isinstance(v, numbers.Real) and not isinstance(v, bool) and not math.isfinite(v):
                raise config_error(f"reference[{p!r}]", v, "must be a finite number (or None, or a field's own value)")
    if grid is not None:
        if not isinstance(grid, Mapping) or not grid:
            raise config_error("grid", grid, "must be a non-empty mapping {field path: [values]}")
        args.mapping("grid", grid)
        variables = tuple(grid)
        size = math.prod(len(v) if isinstance(v, (Sequence, np.ndarray)) and not isinstance(v, (str, bytes)) else 1 for v in grid.values())
        if size > MAX_CASES:
            raise config_error("grid", f"{size} cases", f"at most {MAX_CASES} cases in one study (split it, or give cases=[...])")
        points = list(itertools.product(*(_values(p, grid[p]) for p in variables)))
    else:
        if isinstance(cases, (str, bytes, Mapping)) or not isinstance(cases, Sequence) or not cases or not all(isinstance(c, Mapping) for c in cases):
            raise config_error("cases", cases, "must be a non-empty list of {field path: value}")
        if len(cases) > MAX_CASES:
            raise config_error("cases", f"{len(cases)} cases", f"at most {MAX_CASES} cases in one study")
        for i, c in enumerate(cases):
            args.mapping(f"cases[{i}]", c)
        variables = tuple(cases[0])
        for i, c in enumerate(cases):
            if tuple(c) != variables:
                raise config_error(f"cases[{i}]", sorted(c), f"every case sets the same fields ({', '.join(variables)})")
        points = [tuple(_values(p, [c[p]])[0] for p in variables) for c in cases]
    for p in variables:
        old = get_field(with_tids(config, p), p)  # the path exists
        if old is not None and (isinstance(old, bool) or not isinstance(old, (int, float))):
            raise config_error(p, type(old).__name__, "is not a number field: a study varies numbers (e.g. 'speed', 'tids.stiffness')")
    names = index_names(config)
    if indices is None:
        indices = tuple(names)
    else:
        if isinstance(indices, str) or not isinstance(indices, (Sequence, np.ndarray)) or not len(indices):
            raise config_error("indices", indices, "must be a non-empty list of index names")
        for m in indices:
            if not isinstance(m, str) or m not in names:
                raise config_error("indices", m, f"not an index of this configuration (known: {', '.join(names)})")
        indices = tuple(indices)
    layout = jr.Layout(variables, indices)
    rows = ([{"case": 0, **{v: math.nan for v in variables}}] if reference is not None else [])
    rows += [{"case": i + 1, **dict(zip(variables, p))} for i, p in enumerate(points)]
    configs = [case_config(config, c, variables, indices, reference) for c in rows]
    configs[1 if reference is not None else 0].validate()
    return layout, rows, configs


def with_tids(config: Config, path: str) -> Config:
    """``config``, given :func:`vtb.tids_around`'s dampers if ``path`` is a damper field and it has none."""
    if _parts(path)[0] == "tids" and config.tids is None:
        cfg = config.copy()
        cfg.tids = tids_around(cfg)
        return cfg
    return config


def study(
    config: Config,
    grid: Optional[Mapping] = None,
    *,
    cases: Optional[Sequence[Mapping]] = None,
    reference: Optional[Mapping] = None,
    indices: Optional[Sequence[str]] = None,
    out: Union[str, Path, None] = None,
    executor: Optional[Executor] = None,
    threads: Optional[int] = None,
    chunk: Optional[int] = None,
    progress: Union[bool, object] = True,
    desc: str = "vtb study",
    result_class=StudyResult,
) -> StudyResult:
    """Runs ``config`` over the product of ``grid`` = {field path: [values]} (or the explicit
    ``cases`` = [{field path: value}, ...]) and reports ``indices`` (default: all of
    :func:`index_names`) per case.

    ``reference``: fields set for a reference case 0 run beside the grid (e.g. ``{"tids":
    None}``, the uncontrolled structure), its variables NaN. Paths: dotted, with ``[i]`` for
    list items, or an alias of :data:`ALIASES`; a damper field of a configuration without
    dampers gives it :func:`vtb.tids_around`'s first. Values are numbers (an integer field takes
    integral ones). Every path, value and index is checked, and the first case validated,
    before any run.

    Runs: one Rust batch on ``threads`` cores (lockstep groups, each group's cases reported as
    it finishes), or tasks of ``chunk`` cases on ``executor`` (:mod:`vtb.run.scaleout`). A failing
    case is recorded with its reason and the study goes on. ``progress``: a tqdm bar (True),
    none (False) or ``f(done, total)``.

    ``out``: a CSV journal (:mod:`vtb.studies.journal`; ``.parquet``: the journal is ``out + ".csv"``
    and the Parquet table is written at the end). Each finished case is appended as soon as its
    group finishes; a re-run with the same path runs only the cases the journal lacks (keyed by
    their values, so an extended grid runs only the new ones; failed cases are retried). The
    journal is stamped with the configuration and its header with the variables and indices:
    another study's journal is refused, as is one in use by a running study (a lock the kernel
    drops when its holder dies).
    """
    out = args.path("out", out, none=True)
    threads = args.threads(threads)
    chunk = args.whole("chunk", chunk, 1, none=True)
    if not (isinstance(progress, bool) or callable(progress)):
        raise config_error("progress", progress, "must be True, False or a callable f(done, total)")
    if executor is not None and not isinstance(executor, Executor):
        raise config_error("executor", type(executor).__name__, "must be a concurrent.futures.Executor (or a Dask client's)")
    if not isinstance(desc, str):
        raise config_error("desc", desc, "must be a string")
    if out is not None:
        check_folder(out.parent, "out")
    if out is not None and out.suffix == ".parquet":
        require_pandas(), require_pyarrow()  # the table written at the end: its extra is named before any run
    layout, todo_all, configs = plan(config, grid, cases=cases, reference=reference, indices=indices)
    config_of = {c["case"]: cfg for c, cfg in zip(todo_all, configs)}
    journal = None
    if out is not None:
        journal = out.with_name(out.name + ".csv") if out.suffix == ".parquet" else out
        make_folder(journal.parent, "out")
    with jr.lock(journal) if journal is not None else contextlib.nullcontext():
        with writing("out", journal):
            known = jr.open_rows(journal, config, layout) if journal is not None else {}
        rows, todo = jr.reuse(known, todo_all, layout)
        total, done = len(todo_all), len(rows)
        bar, report = None, (progress if callable(progress) else None)
        if progress is True:
            from tqdm.auto import tqdm

            bar = tqdm(total=total, initial=done, desc=desc, unit="run")

        def finish(i, r):
            nonlocal done
            new = rows_of([todo[i]], [r], layout)
            rows.extend(new)
            if journal is not None:
                with writing("out", journal):
                    jr.append(journal, new, layout)
            done += 1
            if bar is not None:
                bar.update(1)
            if report is not None:
                report(done, total)

        try:
            run_cases([config_of[c["case"]] for c in todo], finish,
                      executor=executor, threads=threads, chunk=chunk)
        finally:
            if bar is not None:
                bar.close()
    result = result_of(rows, config, layout, result_class, journal=journal)
    if out is not None and out.suffix == ".parquet":
        result.to_parquet(out)
    return result
