"""The TID parameter sweep of the article (§4.2–4.3, docs/model.md §9) and its analyses.

``vtb.sweep(config)`` runs the uncontrolled baseline and the Cartesian grid of (b_t, k_t, c_t)
with the dampers of ``config.tids`` (default :func:`vtb.tids_around`): the study of
:func:`vtb.study` over the aliases ``b_t, k_t, c_t`` with the uncontrolled run (``tids =
None``) as its reference case and the indices :data:`METRICS`. With ``out=`` finished cases
are appended to a CSV journal (:mod:`vtb.studies.journal`) as each lockstep group completes;
re-running with the same path skips them. Rows are keyed by their parameters (``nan`` for the
baseline), not by a case number, so that a changed grid reuses every row it shares.
"""

from __future__ import annotations

import os
from concurrent.futures import Executor
from pathlib import Path
from typing import Optional, Sequence, Union

import numpy as np

from . import robust
from ..config.fields import Config
from ..config.resolution import pinned_pinned_frequency
from ..errors import make_folder
from ..run.indices import A_RM, A_RRMS, A_RST, A_SM, METRICS
from ..studies.grid import study
from .tid_problem import REFERENCE, SweepResult, plan

__all__ = ["sweep", "SweepResult", "pinned_pinned_frequency"]

#: The article's grid: b_t = 1..10 kg; k_t = 1..9 × 10^4..10^8 and 1e9 N/m; c_t = 10..1e4 N·s/m.
ARTICLE_B = tuple(float(b) for b in range(1, 11))
ARTICLE_K = tuple(float(m * 10**e) for e in range(4, 9) for m in range(1, 10)) + (1e9,)
ARTICLE_C = (10.0, 100.0, 1e3, 1e4)


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
    :data:`vtb.article.robust.DESIGN_SEED0` + i at each speed; ``samples`` None: the configuration's
    own seed), each case against its own uncontrolled run, and the answer is a
    :class:`vtb.article.robust.RobustSweep` ranking the designs by ``statistic`` of X/X0 over the
    cases, with the standard errors. ``out`` is then a directory holding one journal per case.

    ``config.tids`` gives the dampers' count and positions (default: :func:`vtb.tids_around`).
    In-process (default) every case goes to one Rust batch call on ``threads`` cores (all when
    None), and each lockstep group's cases are journaled and counted by the progress bar as
    soon as the group finishes, so that Ctrl-C or a kill keeps them; with ``executor`` (a
    process pool, or Dask's ``client.get_executor()``) tasks of ``chunk`` cases (default one
    lockstep group) run there, each journaled when it returns (:mod:`vtb.run.scaleout`). A failing
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
        f"Uncontrolled: a_rm0 = {base[A_RM]:.2f} m/s², a_rRMS0 = {base[A_RRMS]:.3f} m/s², "
        f"a_rst0 = {base[A_RST]:.4f} s, a_sm0 = {base[A_SM]:.3f} m/s² "
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
            f"| {t['b_t'][j]:g} | {t['k_t'][j]:.0e} | {t['c_t'][j]:g} | {t['working_frequency'][j]:.0f} | {t[A_RM][j]:.2f} | "
            f"{100 * t[f'eta_{A_RM}'][j]:+.2f} % | {100 * t[f'eta_{A_RRMS}'][j]:+.2f} % | {100 * t[f'eta_{A_RST}'][j]:+.2f} % | "
            f"{100 * t['eta_r'][j]:+.2f} % | {t[A_SM][j]:.3f} | {t['slab_increase'][j]:+.3f} ({100 * t['slab_increase'][j] / base[A_SM]:+.1f} %) | "
            f"{t['slab_acc_min'][j]:.3f} | {'(%.0e, %g)' % art if art else ''} |"
        )
    lines += [
        "",
        "## Headline against the article",
        "",
        "| quantity | vtb | article |",
        "|---|---|---|",
        f"| best case (b_t, k_t, c_t) | ({best['b_t']:g} kg, {best['k_t']:.0e} N/m, {best['c_t']:g} N·s/m) | (5 kg, 2e8 N/m, 1e3 N·s/m) |",
        f"| reduction of a_rm there | {100 * best[f'eta_{A_RM}']:.2f} % ({base[A_RM]:.1f} → {best[A_RM]:.1f} m/s²) | {100 * ARTICLE_BEST_RAIL_CUT:.2f} % (1005.6 → 841.0) |",
        f"| TID working frequency of the best case | {best['working_frequency']:.0f} Hz | 1006.6 Hz |",
        f"| rail first pinned–pinned frequency (computed, Euler–Bernoulli, d = fastener spacing) | {f_pp:.0f} Hz | \"near\" the working frequency |",
        f"| worst rise of a_sm at a rail-optimal TID | {worst['increase']:+.3f} m/s² ({100 * worst['relative']:+.1f} %) at b_t = {worst['b_t']:g} kg | +4.93 m/s² (+11.22 %) |",
        f"| min a_sm per b_t below the uncontrolled a_sm0 for every b_t | {'yes' if np.all(t['slab_acc_min'] < base[A_SM]) else 'no'} | yes |",
        "",
    ]
    text = "\n".join(lines) + "\n"
    if path is not None:
        make_folder(Path(path).parent, "path")
        Path(path).write_text(text)
    return text
