"""Tables of results as pandas DataFrames and their Parquet export (the ``io`` extra:
``pip install 'vtb[io]'``). One place converts columns to a frame and writes Parquet, so every
result type exports the same way; units travel in ``DataFrame.attrs["units"]`` and in the
Parquet file's metadata."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Sequence

from ..errors import ConfigError, MissingExtraError, VtbError, config_error
from .indices import metric_unit


def require_pandas():
    """pandas, or a :class:`~vtb.errors.MissingExtraError` naming the extra ``vtb[io]``."""
    try:
        import pandas as pd
    except ImportError:
        raise MissingExtraError("tables need pandas: pip install 'vtb[io]'", "io") from None
    return pd


def frame(columns, units: dict | None = None):
    """A :class:`pandas.DataFrame` of ``columns`` (a dict of equal-length columns or a list of
    row dicts) with ``attrs["units"]`` = ``units``."""
    df = require_pandas().DataFrame(columns)
    df.attrs["units"] = dict(units or {})
    return df


def to_parquet(data, path) -> None:
    """Writes a table of results to ``path`` as one Parquet file (pyarrow, the ``io`` extra).

    ``data``: a :class:`pandas.DataFrame` (e.g. :func:`metrics_table`, or any result's
    ``to_pandas()``); a batch — the list :func:`vtb.simulate_batch` returns, or a list of
    :class:`vtb.Result` — written as its :func:`metrics_table`, one row per run (a failed job
    keeps its ``error``); or any vtb result with a ``to_pandas()`` (:class:`vtb.Result`'s
    histories, :class:`vtb.StudyResult`, :class:`vtb.SweepResult`,
    :class:`vtb.OptimizationResult`, …), written as that frame. Their own ``.to_parquet(path)``
    methods call this function.

    Units: values are SI; ``df.attrs["units"]`` (``{column: unit}``, e.g. ``"m/s²"``, ``"–"``
    for ratios and counts, text and flag columns left out) is stored as JSON in the file's key–value
    metadata under ``vtb.units``. A named index (e.g. ``t`` of the histories) is written as a
    column and restored. :func:`read_parquet` reads values and units back exactly."""
    pd = require_pandas()
    if isinstance(data, (list, tuple)):
        df = metrics_table(data)
    elif isinstance(data, pd.DataFrame):
        df = data
    elif callable(getattr(data, "to_pandas", None)):
        df = data.to_pandas()
    else:
        raise config_error("data", type(data).__name__, "expected a pandas DataFrame, a batch (list of results or metrics dicts) or a vtb result with to_pandas()")
    pa, pq = require_pyarrow()
    path = Path(path)
    if path.is_dir():
        raise config_error("path", str(path), "is a directory, not a file")
    table = pa.Table.from_pandas(df, preserve_index=df.index.name is not None)
    meta = dict(table.schema.metadata or {})
    meta[b"vtb.units"] = json.dumps(df.attrs.get("units", {})).encode()
    pq.write_table(table.replace_schema_metadata(meta), str(path))


def require_pyarrow():
    """pyarrow, or a :class:`~vtb.errors.MissingExtraError` naming the extra ``vtb[io]``."""
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        raise MissingExtraError("Parquet export needs pyarrow: pip install 'vtb[io]'", "io") from None
    return pa, pq


def read_parquet(path):
    """A DataFrame written by :func:`to_parquet` (or any ``.to_parquet`` of a vtb result),
    with its units back in ``attrs["units"]`` (``{}`` for a file without them)."""
    _, pq = require_pyarrow()
    table = pq.read_table(str(path))
    df = table.to_pandas()
    raw = (table.schema.metadata or {}).get(b"vtb.units")
    df.attrs["units"] = json.loads(raw) if raw else {}
    return df


def metrics_table(results: Sequence):
    """One row per result of a run or a batch (:class:`vtb.Result`, or the metrics dict
    :func:`vtb.simulate_batch` returns; ``None`` or an exception for a failed job gives a row of
    NaN with its ``error``), one column per metric, units (SI) in ``attrs["units"]``."""
    rows = []
    for i, r in enumerate(results):
        if isinstance(r, dict) or callable(getattr(r, "metrics", None)):  # a metrics dict or a vtb.Result
            rows.append({**(r if isinstance(r, dict) else r.metrics()), "error": ""})
        elif r is None or isinstance(r, BaseException):
            rows.append({"error": "" if r is None else f"{type(r).__name__}: {r}"})
        else:
            raise config_error(f"results[{i}]", type(r).__name__, "expected a vtb.Result, a metrics dict, or the error of a failed job")
    df = frame(rows)
    cols = [c for c in df.columns if c != "error"] + ["error"]
    df = df[cols]
    df.attrs["units"] = {c: metric_unit(c) for c in cols if c != "error"}
    return df


#: Units of the design and case columns of the studies' tables.
STUDY_UNITS = {"b_t": "kg", "k_t": "N/m", "c_t": "N·s/m", "speed": "m/s", "seed": "–", "case": "–", "sample": "–",
               "tids.inertance": "kg", "tids.stiffness": "N/m", "tids.damping": "N·s/m",
               "tids.b_t": "kg", "tids.k_t": "N/m", "tids.c_t": "N·s/m", "irregularity.seed": "–"}


def units_of(names) -> dict:
    """The unit of every column name a study table may hold: design and case columns, metrics
    (:func:`vtb.metric_unit`), a metric's uncontrolled value ``<metric>_0`` (its unit),
    reduction rates ``eta_*`` and the robust studies' ratios X/X0 ``ratio_*``, ``mean_*``,
    ``sem_*`` (–); others (text, flags) are left out."""
    def unit(name):
        try:
            return metric_unit(name)
        except ConfigError:
            return None

    out = {}
    for n in names:
        ratio = n.partition("_")[2] if n.startswith(("ratio_", "mean_", "sem_")) else None
        if n in STUDY_UNITS:
            out[n] = STUDY_UNITS[n]
        elif n.startswith("eta_") or n == "satisfaction_rate" or (ratio and unit(ratio)):
            out[n] = "–"
        elif n.endswith("_0") and unit(n[:-2]):
            out[n] = unit(n[:-2])
        elif unit(n):
            out[n] = unit(n)
    return out
