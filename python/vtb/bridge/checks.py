"""The checks of the dynamic analysis, each with its clause: the arithmetic of EN 1991-2 §6.4
and EN 1990 Annex A2, apart from the runs that feed it.

- :func:`n0_limits`, :func:`dynamic_analysis_required`: EN 1991-2 §6.4.4, Fig. 6.9 and 6.10;
- :func:`phi_2`, :func:`phi_3`: the dynamic factors Φ of §6.4.5.2 for LM71;
- :func:`phi_irregularity`: φ'' of Annex C (track irregularities on the real trains' effect);
- :func:`acceleration_limit`: EN 1990 A2.4.4.2.1(4)P, the deck's peak acceleration;
- :class:`Check`: one check's verdict — value, limit, margin, governing train and speed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional

from ..errors import config_error

#: EN 1990 A2.4.4.2.1(4)P: the deck's peak acceleration limit (m/s²) by track type.
ACCELERATION_LIMITS = {"ballasted": 3.5, "direct_fastened": 5.0}
#: EN 1990 A2.4.4.2.3(1): the deck's total vertical deflection under the rail traffic ≤ L/600.
SAFETY_DEFLECTION_RATIO = 600.0
#: Speed (m/s) above which EN 1991-2 Fig. 6.9 always asks for a dynamic analysis: 200 km/h.
FLOW_CHART_SPEED = 200.0 / 3.6
#: LΦ (m) beyond which Annex C's φ'' is 0: e^−(LΦ/20)² underflows from about 550 m on.
LONG_L_PHI = 1000.0


def _positive(name: str, v) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0:
        raise config_error(name, v, "must be a finite number > 0")
    return float(v)


def n0_limits(span: float) -> tuple:
    """The (lower, upper) limits (Hz) of the first bending frequency n0 of EN 1991-2 Fig. 6.10
    for a span L (m), 4 ≤ L ≤ 100: upper 94.76·L^−0.748; lower 80/L up to 20 m, 23.58·L^−0.592
    beyond. Outside 4–100 m the figure gives none: ``(nan, nan)``."""
    length = _positive("span", span)
    if not 4.0 <= length <= 100.0:
        return (math.nan, math.nan)
    upper = 94.76 * length**-0.748
    lower = 80.0 / length if length <= 20.0 else 23.58 * length**-0.592
    return (lower, upper)


@dataclass(frozen=True)
class FlowChart:
    """The answer of EN 1991-2 Fig. 6.9 for a bridge: ``required`` (True, False, or None when
    the chart's remaining questions — Annex F's (v/n0)lim tables, torsion — are not answered
    here and the analysis is done anyway), and the ``reasons`` in the chart's order."""

    required: Optional[bool]
    reasons: tuple


def dynamic_analysis_required(span: float, n0: float, line_speed: float, simple_structure: bool = True,
                              continuous: bool = False) -> FlowChart:
    """Whether EN 1991-2 §6.4.4 (Fig. 6.9) asks for a dynamic analysis of a bridge of span L (m)
    and first bending frequency n0 (Hz) on a line of maximum speed ``line_speed`` (m/s).

    The chart's branches encoded: V > 200 km/h → required; n0 outside the limits of Fig. 6.10 →
    required; V ≤ 200 km/h with n0 within them and a continuous bridge or a simple structure of
    L ≥ 40 m → not required (Φ of §6.4.5 suffices). The other branch (simple structures below
    40 m: Annex F's (v/n0)lim, and the torsional frequency) is left open: ``required = None``."""
    length, n, v = _positive("span", span), _positive("n0", n0), _positive("line_speed", line_speed)
    lower, upper = n0_limits(length)
    reasons = []
    if v > FLOW_CHART_SPEED:
        reasons.append(f"V = {3.6 * v:.0f} km/h > 200 km/h: a dynamic analysis is required (Fig. 6.9)")
        return FlowChart(True, tuple(reasons))
    reasons.append(f"V = {3.6 * v:.0f} km/h ≤ 200 km/h")
    if math.isnan(lower):
        reasons.append(f"L = {length:g} m lies outside Fig. 6.10's 4–100 m: n0 cannot be placed; the analysis is done")
        return FlowChart(None, tuple(reasons))
    if not lower <= n <= upper:
        reasons.append(f"n0 = {n:.3g} Hz outside Fig. 6.10's limits [{lower:.3g}, {upper:.3g}] Hz: required")
        return FlowChart(True, tuple(reasons))
    reasons.append(f"n0 = {n:.3g} Hz within Fig. 6.10's limits [{lower:.3g}, {upper:.3g}] Hz")
    if continuous or (simple_structure and length >= 40.0):
        reasons.append("continuous bridge, or simple structure of L ≥ 40 m: not required (Φ of §6.4.5 applies)")
        return FlowChart(False, tuple(reasons))
    reasons.append("simple structure below 40 m: Annex F's (v/n0)lim and the torsional frequency decide (not encoded); the analysis is done")
    return FlowChart(None, tuple(reasons))


def phi_2(l_phi: float) -> float:
    """Φ2 of EN 1991-2 eq. (6.4), carefully maintained track: 1.44/(√LΦ − 0.2) + 0.82 within
    [1.00, 1.67], LΦ the determinant length (m)."""
    length = _positive("l_phi", l_phi)
    return min(1.67, max(1.0, 1.44 / (math.sqrt(length) - 0.2) + 0.82))


def phi_3(l_phi: float) -> float:
    """Φ3 of EN 1991-2 eq. (6.5), standard maintenance: 2.16/(√LΦ − 0.2) + 0.73 within
    [1.00, 2.00]."""
    length = _positive("l_phi", l_phi)
    return min(2.0, max(1.0, 2.16 / (math.sqrt(length) - 0.2) + 0.73))


def phi_irregularity(l_phi: float, n0: float, speed: float) -> float:
    """φ'' of EN 1991-2 Annex C (C.1): (a/100)·[56·e^−(LΦ/10)² + 50·(LΦ·n0/80 − 1)·e^−(LΦ/20)²],
    a = min(v/22, 1) (v in m/s), at least 0: the share of the track's irregularities in the
    real trains' dynamic effect (the ballast's carefully maintained track takes half of it)."""
    length, n, v = _positive("l_phi", l_phi), _positive("n0", n0), _positive("speed", speed)
    a = min(v / 22.0, 1.0)
    if length > LONG_L_PHI:
        return 0.0  # both terms' e^−(LΦ/10)², e^−(LΦ/20)² are 0 in floating point (and LΦ² would overflow)
    value = a / 100.0 * (56.0 * math.exp(-((length / 10.0) ** 2)) + 50.0 * (length * n / 80.0 - 1.0) * math.exp(-((length / 20.0) ** 2)))
    return max(0.0, value)


def acceleration_limit(track: str) -> float:
    """The deck's peak acceleration limit (m/s²) of EN 1990 A2.4.4.2.1(4)P: 3.5 for ballasted
    track, 5 for direct fastened track."""
    if not isinstance(track, str) or track not in ACCELERATION_LIMITS:
        raise config_error("track", track, f"must be one of {', '.join(ACCELERATION_LIMITS)}")
    return ACCELERATION_LIMITS[track]


@dataclass(frozen=True)
class Check:
    """One check's verdict. ``name`` and ``clause``; ``value`` and ``limit`` in ``unit``;
    ``passed`` (None: not evaluated, ``note`` says why); ``margin`` = 1 − value/limit (−,
    negative when failed); ``train`` and ``speed`` (m/s) of the governing case, if any."""

    name: str
    clause: str
    value: float
    limit: float
    unit: str
    passed: Optional[bool]
    train: str = ""
    speed: float = math.nan
    note: str = ""

    @property
    def margin(self) -> float:
        return 1.0 - self.value / self.limit if self.limit and math.isfinite(self.limit) else math.nan


def verdict(name: str, clause: str, value: float, limit: float, unit: str, train: str = "", speed: float = math.nan, note: str = "") -> Check:
    """A :class:`Check` of ``value ≤ limit`` (not evaluated when either is not finite)."""
    ok = None if not (math.isfinite(value) and math.isfinite(limit)) else bool(value <= limit)
    return Check(name, clause, float(value), float(limit), unit, ok, train, float(speed), note)
