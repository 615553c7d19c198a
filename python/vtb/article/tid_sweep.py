"""The TID parameter sweep of the article (§4.2–4.3, docs/model.md §9) and its analyses.

``vtb.sweep(config)`` runs the uncontrolled baseline and the Cartesian grid of (b_t, k_t, c_t)
with the dampers of ``config.tids`` (default :func:`vtb.tids_around`): the study of
:func:`vtb.study` over the aliases ``b_t, k_t, c_t`` with the uncontrolled run (``tids =
None``) as its reference case and the indices :data:`METRICS`. With ``out=`` finished cases
are appended to a CSV journal (:mod:`vtb.journal`) as each lockstep group completes;
re-running with the same path skips them. Rows are keyed by their parameters (``nan`` for the
baseline), not by a case number, so that a changed grid reuses every row it shares.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
import os
from concurrent.futures import Executor
from pathlib import Path
from typing import Optional, Sequence, Union

import numpy as np

from ..studies import journal as jr
from ..config.fields import Config
from ..errors import VtbError, config_error
from ..studies.journal import config_stamp
from ..config.presets import tids_around
from ..config.resolution import pinned_pinned_frequency
from ..studies import grid as studies
from ..run.indices import index_names
from ..studies.grid import StudyResult, rows_of, study

__all__ = ["sweep", "SweepResult", "config_stamp", "pinned_pinned_frequency"]

#: The article's grid: b_t = 1..10 kg; k_t = 1..9 × 10^4..10^8 and 1e9 N/m; c_t = 10..1e4 N·s/m.
ARTICLE_B = tuple(float(b) for b in range(1, 11))
ARTICLE_K = tuple(float(m * 10**e) for e in range(4, 9) for m in range(1, 10)) + (1e9,)
ARTICLE_C = (10.0, 100.0, 1e3, 1e4)

#: The metrics kept per case (SI units, see ``Result.metrics``).
METRICS = (
    "rail_acc_max", "rail_acc_rms", "rail_acc_settle", "rail_disp_max",
    "slab_acc_max", "slab_acc_rms", "slab_acc_settle", "slab_disp_max",
    "car_acc_max", "car_acc_rms", "car_disp_max", "contact_force_max", "contact_force_min",
    "contact_loss_events",
)
#: The journal's layout: the parameters (keys) and :data:`METRICS`.
LAYOUT = jr.Layout(("b_t", "k_t", "c_t"), METRICS)
COLUMNS = ("case",) + LAYOUT.columns
#: The columns of a sweep journal: those of a result but the case number (rows are keyed by
#: their parameters).
JOURNAL_COLUMNS = LAYOUT.columns
#: The uncontrolled reference case: the structure without dampers.
REFERENCE = {"tids": None}


@dataclasses.dataclass
class SweepResult(StudyResult):
    """A finished sweep (a :class:`vtb.studies.StudyResult` over b_t, k_t, c_t): numpy columns ``case`` (0 = the uncontrolled baseline), ``b_t`` (kg),
    ``k_t`` (N/m), ``c_t`` (N·s/m) (NaN for the baseline), every metric of :data:`METRICS`
    (SI units; NaN where the case failed) and ``error`` (empty, or the failure's type and
    message). ``config``: the swept configuration (its ``tids`` give count and positions)."""

    variables: tuple = LAYOUT.keys
    indices: tuple = METRICS

    @property
    def baseline(self) -> dict:
        """Metrics of the uncontrolled run (case 0)."""
        return self.reference

    def _require_controlled(self) -> np.ndarray:
        ok = self.controlled
        if not ok.any():
            raise VtbError("the sweep has no successful TID case")
        return ok

    @property
    def controlled(self) -> np.ndarray:
        """Boolean mask of the successful TID cases."""
        return (self.columns["case"] > 0) & (self.columns["error"] == "")

    # ------------------------------------------------------------------ analyses
    def best_per_inertance(self) -> dict:
        """Per b_t, the case minimising the rail acceleration amplitude a_rm (article Fig. 5,
        Table 2): numpy columns ``b_t``, ``k_t``, ``c_t``, ``rail_acc_max``, ``rail_acc_rms``,
        ``rail_acc_settle``, their reduction rates ``eta_*`` against the baseline, the
        comprehensive rate ``eta_r``, ``slab_acc_max`` there and its change against the
        baseline, ``slab_acc_min`` (the lowest a_sm of any case with that b_t) and
        ``working_frequency`` f_t = sqrt(k_t/b_t)/2π (Hz)."""
        c, ok, base = self.columns, self._require_controlled(), self.baseline
        rows = []
        for b in np.unique(c["b_t"][ok]):
            sel = np.flatnonzero(ok & (c["b_t"] == b))
            i = sel[np.argmin(c["rail_acc_max"][sel])]
            red = {k: (base[k] - c[k][i]) / base[k] for k in ("rail_acc_max", "rail_acc_rms", "rail_acc_settle")}
            rows.append(dict(
                b_t=b, k_t=c["k_t"][i], c_t=c["c_t"][i],
                rail_acc_max=c["rail_acc_max"][i], rail_acc_rms=c["rail_acc_rms"][i], rail_acc_settle=c["rail_acc_settle"][i],
                eta_rail_acc_max=red["rail_acc_max"], eta_rail_acc_rms=red["rail_acc_rms"], eta_rail_acc_settle=red["rail_acc_settle"],
                eta_r=sum(red.values()) / 3.0,
                slab_acc_max=c["slab_acc_max"][i], slab_increase=c["slab_acc_max"][i] - base["slab_acc_max"],
                slab_acc_min=np.min(c["slab_acc_max"][sel]),
                working_frequency=math.sqrt(c["k_t"][i] / b) / (2 * math.pi),
            ))
        return {k: np.array([r[k] for r in rows]) for k in (rows[0] if rows else {})}

    def best(self, index: str = "rail_acc_max") -> dict:
        """The case with the lowest a_rm (or ``index``) overall, with the reduction of a_rm
        against the baseline and the dampers' working frequency."""
        c, ok = self.columns, self._require_controlled()
        i = np.flatnonzero(ok)[np.argmin(c[index][ok])]
        out = {k: float(c[k][i]) for k in ("b_t", "k_t", "c_t") + METRICS}
        out["eta_rail_acc_max"] = 1 - out["rail_acc_max"] / self.baseline["rail_acc_max"]
        out["working_frequency"] = math.sqrt(out["k_t"] / out["b_t"]) / (2 * math.pi)
        return out

    def worst_slab_increase(self) -> dict:
        """Among the per-b_t rail optima, the largest rise of a_sm over the uncontrolled slab
        amplitude (article Fig. 6: +4.93 m/s², +11.22 %)."""
        t = self.best_per_inertance()
        j = int(np.argmax(t["slab_increase"]))
        base = self.baseline["slab_acc_max"]
        return dict(b_t=float(t["b_t"][j]), increase=float(t["slab_increase"][j]), relative=float(t["slab_increase"][j] / base))


def grid(b_t: Sequence[float], k_t: Sequence[float], c_t: Sequence[float]) -> list:
    """The Cartesian grid as (case, b_t, k_t, c_t), cases numbered from 1 (b_t slowest)."""
    return [(i + 1, float(b), float(k), float(c)) for i, (b, k, c) in enumerate((b, k, c) for b in b_t for k in k_t for c in c_t)]


def recording_metrics(config: Config) -> Config:
    """``config`` reporting only the indices of :data:`METRICS` it has (``output.indices``):
    its runs record only the layers those need."""
    names = set(index_names(config))
    config.output.indices = [m for m in METRICS if m in names]
    return config


def case_config(config: Config, b: float, k: float, c: float) -> Config:
    """``config`` with its dampers' b_t, k_t, c_t set (NaN: no dampers, the baseline),
    reporting the indices of :data:`METRICS` (:func:`recording_metrics`)."""
    cfg = config.copy()
    if math.isnan(b):
        cfg.tids = None
    else:
        cfg.tids = dataclasses.replace(cfg.tids, inertance=b, stiffness=k, damping=c)
    return recording_metrics(cfg)


def case_rows(cases: list, results: list) -> list:
    """The journal rows of cases (dicts: ``case``, b_t, k_t, c_t) from their runs."""
    return rows_of(cases, results, LAYOUT)


def plan(config: Config, b_t: Sequence[float], k_t: Sequence[float], c_t: Sequence[float]) -> tuple:
    """The swept configuration (dampers default :func:`vtb.tids_around`) and its cases (dicts:
    ``case``, b_t, k_t, c_t), the baseline (case 0, NaN parameters) and the grid; a bad grid
    value raises a :class:`ConfigError` naming b_t, k_t or c_t before any run."""
    for name, vals, low in (("b_t", b_t, 0.0), ("k_t", k_t, 0.0), ("c_t", c_t, None)):
        if len(vals) == 0:
            raise config_error(name, list(vals), "needs at least one value")
        for v in vals:
            ok = isinstance(v, numbers.Real) and not isinstance(v, bool) and math.isfinite(v) and (v >= 0 if low is None else v > low)
            if not ok:
                raise config_error(name, v, "must be finite and " + ("non-negative" if low is None else "positive"))
    if config.tids is None:
        config = config.copy()
        config.tids = tids_around(config)
    cases = [dict(case=i, b_t=b, k_t=k, c_t=c) for i, b, k, c in [(0, math.nan, math.nan, math.nan)] + grid(b_t, k_t, c_t)]
    return config, cases


def read_journal(path: Union[str, Path], field: str = "path") -> SweepResult:
    """A sweep journal as a :class:`SweepResult`, without running anything: the configuration
    of its stamp and one row per key (the rule of :func:`sweep` for repeated keys), the baseline
    as case 0 and the TID cases numbered in their order in the file. A malformed journal raises
    a :class:`ConfigError` naming ``field`` and the line."""
    return studies.read_journal(path, field, LAYOUT, SweepResult)


def sweep(
    config: Config,
    b_t: Sequence[float] = ARTICLE_B,
    k_t: Sequence[float] = ARTICLE_K,
    c_t: Sequence[float] = ARTICLE_C,
    *,
    out: Union[str, Path, None] = None,
    executor: Optional[Executor] = None,
    threads: Optional[int] = None,
    chunk: Optional[int] = None,
    progress: Union[bool, object] = True,
    samples=None,
    speeds=None,
    statistic: str = "mean",
) -> SweepResult:
    """Runs the baseline (no dampers) and every (b_t, k_t, c_t) of the grid.

    **Over samples and speeds** (``samples=N`` or a list of seeds, ``speeds=[...]`` in m/s;
    docs/robust.md): the grid is swept on every case (the design seeds
    :data:`vtb.robust.DESIGN_SEED0` + i at each speed; ``samples`` None: the configuration's
    own seed), each case against its own uncontrolled run, and the answer is a
    :class:`vtb.robust.RobustSweep` ranking the designs by ``statistic`` of X/X0 over the
    cases, with the standard errors. ``out`` is then a directory holding one journal per case.

    ``config.tids`` gives the dampers' count and positions (default: :func:`vtb.tids_around`).
    In-process (default) every case goes to one Rust batch call on ``threads`` cores (all when
    None), and each lockstep group's cases are journaled and counted by the progress bar as
    soon as the group finishes, so that Ctrl-C or a kill keeps them; with ``executor`` (a
    process pool, or Dask's ``client.get_executor()``) tasks of ``chunk`` cases (default one
    lockstep group) run there, each journaled when it returns (:mod:`vtb.scaleout`). A failing
    case (e.g. contact non-convergence) is recorded with its reason and the sweep goes on.
    ``progress``: a tqdm bar (True), none (False) or a callable ``f(done, total)``.

    ``out``: a CSV journal (``.parquet``: the journal is ``out + ".csv"`` and the Parquet table
    is written at the end). Finished runs are appended to it as they complete, and a re-run
    with the same path runs only what the journal lacks:

    * the journal carries its configuration in its first line (the stamp, see the module
      docstring); a journal of another configuration, or a file that is not a journal, is
      refused;
    * rows are keyed by (b_t, k_t, c_t) (the baseline by none of them), so a grid extended by
      new values runs only the new cases; rows outside the grid stay in the file, unused;
    * failed cases (non-empty ``error``) are retried; of several rows with one key the last
      successful one counts, or the last one when all failed;
    * the sweep holds ``<journal>.lock`` (an exclusive ``flock``) from start to end, so a
      second sweep on the same journal is refused with the holder's pid; the kernel drops the
      lock of a process that dies, so a lock file left by a killed sweep does not block;
    * a last line cut short by a kill is dropped; any other malformed line (a missing or
      unparsable stamp, a wrong header, a wrong number of fields, a value that is not a number)
      raises a :class:`ConfigError` naming ``out`` and the line number.
    """
    if samples is not None or speeds is not None:
        from . import robust

        return robust.sweep_over(config, b_t, k_t, c_t, samples=samples, speeds=speeds, statistic_name=statistic, out=out, threads=threads,
                                 progress=progress, executor=executor, chunk=chunk)
    config, _ = plan(config, b_t, k_t, c_t)
    return study(config, {"b_t": b_t, "k_t": k_t, "c_t": c_t}, reference=REFERENCE, indices=METRICS, out=out, executor=executor,
                 threads=threads, chunk=chunk, progress=progress, desc="vtb sweep", result_class=SweepResult)


#: The article's best sweep case's cut of the rail acceleration amplitude (1005.6 → 841.0 m/s²).
ARTICLE_BEST_RAIL_CUT = 0.1637
#: The article's Table 2 (optimal k_t, c_t per b_t) and headline numbers.
ARTICLE_TABLE2 = {1: (2e7, 10), 2: (1e8, 10), 3: (1e8, 1e3), 4: (7e8, 10), 5: (2e8, 1e3), 6: (7e8, 10), 7: (3e8, 1e3), 8: (6e7, 10), 9: (4e7, 10), 10: (3e8, 1e3)}


def sweep_report(result: SweepResult, path=None, seconds: Optional[float] = None) -> str:
    """Markdown page of a sweep beside the article: Table 2 analogue, best case, slab effect
    (Fig. 6), working frequency against the rail's pinned–pinned frequency."""
    base = result.baseline
    t = result.best_per_inertance()
    best = result.best()
    worst = result.worst_slab_increase()
    f_pp = pinned_pinned_frequency(result.config)
    tids = result.config.tids
    n_fail = int(np.sum(result.columns["error"] != ""))
    lines = [
        "# TID parameter sweep (article §4.2–4.3)",
        "",
        f"{len(result) - 1} TID cases + the uncontrolled baseline"
        + (f", {seconds / 60:.1f} min wall time on {os.cpu_count()} cores (machine load at the end "
           f"{'/'.join(f'{v:.2f}' for v in os.getloadavg())}, 1/5/15 min)" if seconds else "")
        + f"; {n_fail} failed cases. Dampers: {len(tids.locations())} between {tids.upper} and {tids.lower}, {tids.placement()} "
        "(one per fastener bay around the observation point). Rail and slab amplitudes at the first observation point.",
        "",
        f"Uncontrolled: a_rm0 = {base['rail_acc_max']:.2f} m/s², a_rRMS0 = {base['rail_acc_rms']:.3f} m/s², "
        f"a_rst0 = {base['rail_acc_settle']:.4f} s, a_sm0 = {base['slab_acc_max']:.3f} m/s² "
        "(article: 1005.6, ≈68.0, ≈1.080, 43.94 — the article's irregularity level is unstated; vtb calibrates only a_rm0, docs/reproduction/report.md).",
        "",
        "## Best (k_t, c_t) per b_t for the rail acceleration amplitude (Table 2, Fig. 5, Fig. 6)",
        "",
        "| b_t (kg) | k_t (N/m) | c_t (N·s/m) | f_t (Hz) | a_rm (m/s²) | η_arm | η_arRMS | η_arst | η_r | a_sm there | Δa_sm vs uncontrolled | min a_sm at this b_t | article (k_t, c_t) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for j in range(len(t["b_t"])):
        b = float(t["b_t"][j])
        art = ARTICLE_TABLE2.get(int(b)) if b.is_integer() else None
        lines.append(
            f"| {t['b_t'][j]:g} | {t['k_t'][j]:.0e} | {t['c_t'][j]:g} | {t['working_frequency'][j]:.0f} | {t['rail_acc_max'][j]:.2f} | "
            f"{100 * t['eta_rail_acc_max'][j]:+.2f} % | {100 * t['eta_rail_acc_rms'][j]:+.2f} % | {100 * t['eta_rail_acc_settle'][j]:+.2f} % | "
            f"{100 * t['eta_r'][j]:+.2f} % | {t['slab_acc_max'][j]:.3f} | {t['slab_increase'][j]:+.3f} ({100 * t['slab_increase'][j] / base['slab_acc_max']:+.1f} %) | "
            f"{t['slab_acc_min'][j]:.3f} | {'(%.0e, %g)' % art if art else ''} |"
        )
    lines += [
        "",
        "## Headline against the article",
        "",
        "| quantity | vtb | article |",
        "|---|---|---|",
        f"| best case (b_t, k_t, c_t) | ({best['b_t']:g} kg, {best['k_t']:.0e} N/m, {best['c_t']:g} N·s/m) | (5 kg, 2e8 N/m, 1e3 N·s/m) |",
        f"| reduction of a_rm there | {100 * best['eta_rail_acc_max']:.2f} % ({base['rail_acc_max']:.1f} → {best['rail_acc_max']:.1f} m/s²) | {100 * ARTICLE_BEST_RAIL_CUT:.2f} % (1005.6 → 841.0) |",
        f"| TID working frequency of the best case | {best['working_frequency']:.0f} Hz | 1006.6 Hz |",
        f"| rail first pinned–pinned frequency (computed, Euler–Bernoulli, d = fastener spacing) | {f_pp:.0f} Hz | \"near\" the working frequency |",
        f"| worst rise of a_sm at a rail-optimal TID | {worst['increase']:+.3f} m/s² ({100 * worst['relative']:+.1f} %) at b_t = {worst['b_t']:g} kg | +4.93 m/s² (+11.22 %) |",
        f"| min a_sm per b_t below the uncontrolled a_sm0 for every b_t | {'yes' if np.all(t['slab_acc_min'] < base['slab_acc_max']) else 'no'} | yes |",
        "",
    ]
    text = "\n".join(lines) + "\n"
    if path is not None:
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        Path(path).write_text(text)
    return text
