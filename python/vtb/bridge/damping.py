"""The bridge's damping for the dynamic analysis of EN 1991-2 §6.4.6.3.1.

:func:`table_6_6` is the lower limit of the critical damping ratio of Table 6.6 by bridge type
and span L; :func:`delta_zeta` the additional damping Δζ of eq. (6.13) that stands in for the
vehicle–bridge interaction on spans below 30 m (§6.4.6.3.1(4)); :func:`code_damping` their sum.

vtb's layers are damped by Rayleigh's law C = αM + βK. :func:`code_rayleigh` gives the deck
the code's ratio at the two ends of the check's band — its first bending frequency n0 and the
band's top max(30 Hz, 1.5·n0, n3) — so that ζ(f) = α/(4πf) + πβf equals the code's value at
both and lies below it between them: every mode of the band is damped at most as much as the
code allows (the check errs on the safe side), and :func:`achieved_ratios` gives each mode's
ratio for the report. :func:`apply_code_damping` puts it on the deck (the bottom layer).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional, Sequence

import numpy as np

from ..config.fields import Config, RayleighRatio
from ..errors import config_error

#: Table 6.6's bridge types: (ζ in % for L ≥ 20 m, its growth in % per metre below 20 m).
BRIDGE_TYPES = {
    "steel_composite": (0.5, 0.125),
    "prestressed_concrete": (1.0, 0.07),
    "reinforced_concrete": (1.5, 0.07),
}
#: What each type covers (Table 6.6's rows).
BRIDGE_TYPE_TITLES = {
    "steel_composite": "steel and composite",
    "prestressed_concrete": "prestressed concrete",
    "reinforced_concrete": "filler beam and reinforced concrete",
}
#: Δζ applies to spans below this length (m), §6.4.6.3.1(4).
DELTA_ZETA_SPAN = 30.0


def _span(span) -> float:
    if isinstance(span, bool) or not isinstance(span, (int, float, np.floating)) or not math.isfinite(span) or span <= 0:
        raise config_error("span", span, "must be a span length (m) > 0")
    return float(span)


def _kind(kind) -> str:
    if not isinstance(kind, str) or kind not in BRIDGE_TYPES:
        raise config_error("bridge_type", kind, f"must be one of {', '.join(BRIDGE_TYPES)} (EN 1991-2 Table 6.6)")
    return kind


def table_6_6(kind: str, span: float) -> float:
    """The lower limit of the critical damping ratio (%) of EN 1991-2 Table 6.6 for a bridge of
    type ``kind`` (``"steel_composite"``, ``"prestressed_concrete"`` or
    ``"reinforced_concrete"`` — filler beam and reinforced concrete) and span ``span`` (m):
    ζ + rate·(20 − L) below 20 m, ζ from 20 m on."""
    base, rate = BRIDGE_TYPES[_kind(kind)]
    length = _span(span)
    return base + rate * (20.0 - length) if length < 20.0 else base


def delta_zeta(span: float) -> float:
    """The additional damping Δζ (%) of EN 1991-2 eq. (6.13) for a span ``span`` (m):
    (0.0187 L − 0.00064 L²) / (1 − 0.0441 L − 0.0044 L² + 0.000255 L³) below 30 m, 0 from
    30 m on, and 0 where the fit dips below zero (just under 30 m)."""
    length = _span(span)
    if length >= DELTA_ZETA_SPAN:
        return 0.0
    value = (0.0187 * length - 0.00064 * length**2) / (1.0 - 0.0441 * length - 0.0044 * length**2 + 0.000255 * length**3)
    return max(0.0, value)


@dataclass(frozen=True)
class CodeDamping:
    """The damping of a span: ``table`` (Table 6.6, %), ``interaction`` (Δζ, %, 0 when not
    used), ``ratio`` (their sum as a fraction of critical, −), for ``kind`` and ``span`` (m)."""

    kind: str
    span: float
    table: float
    interaction: float

    @property
    def ratio(self) -> float:
        """ζ_total (−): (Table 6.6 + Δζ) / 100."""
        return (self.table + self.interaction) / 100.0

    def describe(self) -> str:
        return (f"ζ = {self.table:.3f} % (EN 1991-2 Table 6.6, {BRIDGE_TYPE_TITLES[self.kind]}, L = {self.span:g} m)"
                + (f" + Δζ = {self.interaction:.3f} % (eq. 6.13)" if self.interaction else "") + f" = {100 * self.ratio:.3f} %")


def code_damping(kind: str, span: float, interaction: bool = True) -> CodeDamping:
    """Table 6.6's ratio for ``kind`` and ``span`` plus, with ``interaction``, Δζ (§6.4.6.3.1:
    Δζ is the allowance for the vehicle–bridge interaction in a moving-load analysis; leave it
    out when the vehicles are modelled)."""
    return CodeDamping(_kind(kind), _span(span), table_6_6(kind, span), delta_zeta(span) if interaction else 0.0)


def code_rayleigh(ratio: float, f_low: float, f_high: float) -> RayleighRatio:
    """Rayleigh damping with ratio ``ratio`` (−) at ``f_low`` and ``f_high`` (Hz): below it in
    between, above it outside."""
    if isinstance(ratio, bool) or not isinstance(ratio, (int, float)) or not 0 <= ratio < 1:
        raise config_error("ratio", ratio, "must be a damping ratio in [0, 1) (a fraction of critical, not %)")
    for name, f in (("f_low", f_low), ("f_high", f_high)):
        if isinstance(f, bool) or not isinstance(f, (int, float, np.floating)) or not math.isfinite(f) or f <= 0:
            raise config_error(name, f, "must be a frequency (Hz) > 0")
    if not f_high > f_low:
        raise config_error("f_high", f_high, f"must exceed f_low = {f_low:g} Hz")
    return RayleighRatio(float(ratio), float(f_low), float(f_high))


def achieved_ratios(damping: RayleighRatio, frequencies: Sequence[float]) -> np.ndarray:
    """The ratio (−) Rayleigh damping gives at each frequency (Hz): α/(2ω) + βω/2, with α and β
    those that give ``damping.ratio`` at ``damping.f1`` and ``damping.f2``."""
    try:
        f = np.asarray(frequencies, dtype=float)
    except (TypeError, ValueError):
        f = None
    if f is None or f.ndim != 1 or not (np.isfinite(f) & (f > 0)).all():
        raise config_error("frequencies", frequencies, "must be a list of frequencies (Hz) > 0")
    w1, w2 = 2 * math.pi * damping.f1, 2 * math.pi * damping.f2
    alpha = 2 * damping.ratio * w1 * w2 / (w1 + w2)
    beta = 2 * damping.ratio / (w1 + w2)
    w = 2 * math.pi * f
    return alpha / (2 * w) + beta * w / 2


def apply_code_damping(config: Config, damping: CodeDamping, f_low: float, f_high: float, layer: Optional[str] = None) -> Config:
    """A copy of ``config`` whose deck (the bottom layer, or ``layer``) has the ratio of
    ``damping`` at ``f_low`` (its first bending frequency, Hz) and ``f_high`` (the top of the
    check's band, Hz) by :func:`code_rayleigh`."""
    out = config.copy()
    layers = out.structure.layers
    names = [l.name for l in layers]
    if layer is not None and layer not in names:
        raise config_error("layer", layer, f"no layer of that name (known: {', '.join(names)})")
    target = layers[-1] if layer is None else layers[names.index(layer)]
    target.damping = code_rayleigh(damping.ratio, f_low, f_high)
    return out
