"""Designs judged over the excitation they cannot know in advance (docs/robust.md).

A damper design tuned on one irregularity sample at one speed is fitted to that sample. This
module evaluates a design over **irregularity samples** (realisations of the configuration's
own spectrum and level, differing only in their seed) and **speeds**, every index taken
relative to the uncontrolled run of the same sample and speed, and summarises each index over
the cases by a chosen **statistic**.

Seeds are documented, so a study can be repeated and design and check kept apart: sample i of
a design study uses seed ``DESIGN_SEED0 + i``, sample i of a held-out check
``HELD_OUT_SEED0 + i`` (an explicit list of seeds may be given instead).

Statistics (:func:`statistic`): ``"mean"``, ``"max"``, ``"min"``, ``"median"`` and quantiles
``"pNN"`` (0 < NN < 100, e.g. ``"p90"``: the value 90 % of the cases stay at or below; linear
interpolation between order statistics, numpy's default). The standard error of the mean,
s/√N with the sample standard deviation s, is reported beside every mean so a user can choose
N: it halves when N quadruples.
"""

from __future__ import annotations

import dataclasses
import math
import re
from typing import Mapping, Optional, Sequence, Union

import numpy as np

from .config import Config, TIDs
from .errors import config_error
from .optimize import CONSTRAINTS
from .presets import tids_around
from .simulate import simulate_batch
from .tid_sweep import METRICS

#: First seed of the samples a design is chosen on.
DESIGN_SEED0 = 1000
#: First seed of the held-out samples a design is checked on.
HELD_OUT_SEED0 = 2000
#: Indices whose reduction rate η = (X0 − X)/X0 is reported (the rest are counts or signed).
REDUCED = tuple(m for m in METRICS if m not in ("contact_force_min", "contact_loss_events"))

_QUANTILE = re.compile(r"^p(\d+(?:\.\d+)?)$")


def seeds(samples: Union[int, Sequence[int]], first: int) -> list:
    """The seeds of ``samples``: an int N gives ``first + i`` for i < N; a sequence is taken
    as the seeds themselves (non-negative integers, no repeats)."""
    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer, list, tuple, np.ndarray)):
        raise config_error("samples", samples, "must be a number of samples (int ≥ 1) or a list of seeds")
    if isinstance(samples, (int, np.integer)):
        if samples < 1:
            raise config_error("samples", samples, "must be at least 1")
        return [first + i for i in range(int(samples))]
    out = list(samples)
    if not out or any(isinstance(s, bool) or not isinstance(s, (int, np.integer)) or s < 0 for s in out) or len(set(out)) != len(out):
        raise config_error("samples", samples, "a list of seeds must hold distinct non-negative integers")
    return [int(s) for s in out]


def statistic(values, name: str) -> float:
    """``name`` (module docstring) of ``values`` (NaN entries, failed cases, make it NaN)."""
    v = np.asarray(values, dtype=float)
    if v.ndim != 1 or v.size == 0:
        raise config_error("values", f"shape {v.shape}", "must be a non-empty 1-D sequence")
    if name in ("mean", "max", "min", "median"):
        return float(getattr(np, name)(v))
    m = _QUANTILE.match(name) if isinstance(name, str) else None
    if m is None or not 0.0 < float(m.group(1)) < 100.0:
        raise config_error("statistic", name, 'must be "mean", "max", "min", "median" or a quantile "pNN" with 0 < NN < 100')
    return float(np.quantile(v, float(m.group(1)) / 100.0))


def standard_error(values) -> float:
    """Standard error of the mean, s/√N (sample standard deviation; NaN for one value)."""
    v = np.asarray(values, dtype=float)
    return float(np.std(v, ddof=1) / math.sqrt(v.size)) if v.size > 1 else math.nan


def _design_tids(config: Config, design) -> TIDs:
    base = config.tids if config.tids is not None else tids_around(config)
    if isinstance(design, TIDs):
        return design
    if not isinstance(design, Mapping) or not {"b_t", "k_t", "c_t"} <= set(design):
        raise config_error("design", design, "must be a vtb.TIDs or a mapping with b_t (kg), k_t (N/m) and c_t (N·s/m)")
    return dataclasses.replace(base, inertance=float(design["b_t"]), stiffness=float(design["k_t"]), damping=float(design["c_t"]))


def cases(config: Config, samples, speeds: Optional[Sequence[float]], first: int) -> list:
    """(speed, seed, configuration without dampers) of every case, speed-major."""
    if config.irregularity.kind in ("none", "sampled"):
        raise config_error("irregularity.kind", config.irregularity.kind, "samples need a random irregularity (a spectrum) to draw realisations from")
    speeds = [config.speed] if speeds is None else list(speeds)
    if not speeds or any(isinstance(v, bool) or not isinstance(v, (int, float, np.number)) or not math.isfinite(v) or v <= 0 for v in speeds):
        raise config_error("speeds", speeds, "must be a non-empty list of finite speeds > 0 (m/s)")
    out = []
    for v in speeds:
        for s in seeds(samples, first):
            cfg = config.copy()
            cfg.speed = float(v)
            cfg.irregularity = dataclasses.replace(cfg.irregularity, seed=s)
            cfg.tids = None
            out.append((float(v), s, cfg))
    return out


@dataclasses.dataclass
class DesignEvaluation:
    """A design over samples and speeds. ``rows``: one dict per case with ``speed`` (m/s),
    ``seed``, every metric uncontrolled (``<metric>_0``) and with the design (``<metric>``, SI
    units), the reduction rates ``eta_<metric>`` = (X0 − X)/X0 of :data:`REDUCED`, and
    ``feasible`` (True when every constrained index of :data:`vtb.optimize.CONSTRAINTS` is at or
    below its uncontrolled value); a failed case has ``error`` set and NaN indices.
    ``design``: the dampers evaluated."""

    rows: list
    design: TIDs

    def column(self, name: str) -> np.ndarray:
        return np.array([r[name] for r in self.rows], dtype=float)

    @property
    def satisfaction_rate(self) -> float:
        """Share of the cases in which the design meets every constraint (failed cases count
        as not meeting them)."""
        return float(np.mean([bool(r["feasible"]) for r in self.rows]))

    def summary(self, statistic_name: str = "mean", speed: Optional[float] = None) -> dict:
        """Per index: ``{eta_<metric>: (statistic, mean, standard error of the mean)}`` over the
        cases (of one ``speed`` if given), and ``satisfaction_rate``."""
        rows = self.rows if speed is None else [r for r in self.rows if r["speed"] == speed]
        if not rows:
            raise config_error("speed", speed, f"not among the evaluated speeds {sorted({r['speed'] for r in self.rows})}")
        sub = DesignEvaluation(rows, self.design)
        out = {}
        for m in REDUCED:
            v = sub.column(f"eta_{m}")
            out[f"eta_{m}"] = (statistic(v, statistic_name), float(np.mean(v)), standard_error(v))
        out["satisfaction_rate"] = sub.satisfaction_rate
        return out

    def to_pandas(self):
        import pandas as pd

        return pd.DataFrame(self.rows)


def evaluate_design(
    config: Config,
    design,
    samples: Union[int, Sequence[int]] = 8,
    speeds: Optional[Sequence[float]] = None,
    first_seed: int = HELD_OUT_SEED0,
    threads: Optional[int] = None,
    progress: bool = False,
) -> DesignEvaluation:
    """Evaluates ``design`` (a :class:`vtb.TIDs`, or b_t, k_t, c_t with the count and positions
    of ``config.tids``, default :func:`vtb.tids_around`) on irregularity samples and speeds.

    ``samples``: a number N (seeds ``first_seed + i``, by default the held-out seeds) or the
    seeds themselves; ``speeds`` (m/s): default the configuration's own. Each case runs
    uncontrolled and with the design, all in one batch (the samples of a speed share one
    assembled model and run in lockstep). Returns the table of every index per case and the
    constraint-satisfaction rate (:class:`DesignEvaluation`)."""
    tids = _design_tids(config, design)
    todo = cases(config, samples, speeds, first_seed)
    controlled = []
    for _, _, cfg in todo:
        c = cfg.copy()
        c.tids = tids
        controlled.append(c)
    runs = simulate_batch([c for _, _, c in todo] + controlled, threads=threads, on_error="return", progress=progress)
    n = len(todo)
    rows = []
    for (v, s, _), r0, r1 in zip(todo, runs[:n], runs[n:]):
        row = dict(speed=v, seed=s, error="")
        failed = next((r for r in (r0, r1) if isinstance(r, BaseException)), None)
        if failed is not None:
            row["error"] = f"{type(failed).__name__}: {failed}"
            row.update({k: math.nan for m in METRICS for k in (m, f"{m}_0")})
            row.update({f"eta_{m}": math.nan for m in REDUCED})
            row["feasible"] = False
        else:
            for m in METRICS:
                row[f"{m}_0"], row[m] = float(r0[m]), float(r1[m])
            for m in REDUCED:
                row[f"eta_{m}"] = (r0[m] - r1[m]) / r0[m] if r0[m] != 0 else math.nan
            row["feasible"] = all(r1[m] <= r0[m] for m in CONSTRAINTS)
        rows.append(row)
    return DesignEvaluation(rows, tids)
