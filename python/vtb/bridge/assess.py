"""The bridge check from end to end: :func:`assess` takes a configuration and a
:class:`~vtb.bridge.settings.BridgeCheck`, finds the deck's frequencies and band, damps it by
the code, scans the trains over the speeds, computes the static responses, and returns the
:class:`Assessment` — every check with its clause, governing case and margin."""

from __future__ import annotations

import math
import time
from concurrent.futures import Executor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional, Union

import numpy as np

from ..config.fields import Config
from ..errors import config_error
from .checks import (SAFETY_DEFLECTION_RATIO, Check, FlowChart, acceleration_limit, dynamic_analysis_required, phi_2, phi_3,
                     phi_irregularity, verdict)
from .damping import CodeDamping, achieved_ratios, apply_code_damping, code_damping
from .interaction import interaction_scan
from .load_trains import load_train, resonant_speeds
from .scan import ScanResult, scan_speeds, span_points, speed_scan, with_band
from .settings import BridgeCheck
from .static import QUANTITIES, deck_frequencies, influence_line

#: Resonance orders i of v_i = n0·D/i the scan refines around.
ORDERS = range(1, 6)
#: Time steps per period of the band's top frequency, by default.
STEPS_PER_BAND_PERIOD = 100


@dataclass
class Response:
    """One effect of one train over the scan, deflection (m) or mid-span bending moment (N·m):
    ``static`` (the train's static effect at the point), ``dynamic`` (the largest dynamic one)
    at ``speed`` (m/s), ``phi_dyn`` (dynamic/static − 1, at least 0), ``x`` (the observation
    point, m, where the dynamic effect is largest; the static ones are taken there), ``lm71``
    (the static effect of α·LM71 there) and ``design`` ((1 + φ'dyn + k·φ'')·static with the
    train's governing φ'dyn, :attr:`TrainEnvelope.phi_dyn`)."""

    static: float
    dynamic: float
    speed: float
    phi_dyn: float
    x: float
    lm71: float
    design: float = math.nan


@dataclass
class TrainEnvelope:
    """One train's result over the scan, EN 1991-2 §6.4.6.5(3): ``deflection`` and ``moment``
    (each a :class:`Response`), ``phi_dyn`` (φ'dyn, −: the larger of the two responses', which
    governs), ``phi_irr`` (φ'', −, at the line's maximum speed) and ``k_irr`` (k = ½ for
    carefully maintained track, 1 otherwise); each response's ``design`` is (1 + φ'dyn +
    k·φ'')·static."""

    train: str
    deflection: Response
    moment: Response
    phi_dyn: float
    phi_irr: float
    k_irr: float

    def __post_init__(self):
        for r in (self.deflection, self.moment):
            r.design = (1.0 + self.phi_dyn + self.k_irr * self.phi_irr) * r.static


@dataclass
class Assessment:
    """A finished bridge check. ``settings`` and ``config`` (the damped, banded configuration
    the scan ran); ``n0`` (Hz), ``frequencies`` (the deck's distinct natural frequencies, Hz),
    ``band`` (Hz); ``damping`` (the code's) with its ``achieved`` ratios (−) at ``frequencies``
    in the band; ``flow_chart``; ``scan``; ``lm71`` (largest static deflection under α·LM71
    over the observation points, m), ``lm71_moment`` (largest static bending moment under
    α·LM71 over them, N·m) and ``phi`` (Φ, −); ``envelopes`` per train; ``checks``; ``seconds`` of run time;
    ``interaction``: the scan of ``settings.vehicles`` with full interaction (Table 6.6's
    damping without Δζ), or None."""

    settings: BridgeCheck
    config: Config
    n0: float
    frequencies: np.ndarray
    band: float
    damping: CodeDamping
    achieved: np.ndarray
    flow_chart: FlowChart
    scan: ScanResult
    lm71: float
    lm71_moment: float
    phi: float
    envelopes: list
    checks: list = field(default_factory=list)
    seconds: float = 0.0
    interaction: Optional[ScanResult] = None

    @property
    def passed(self) -> Optional[bool]:
        """True when every evaluated check passed, False when one failed."""
        states = [c.passed for c in self.checks if c.passed is not None]
        return all(states) if states else None


def deck_band_of(frequencies: np.ndarray, n0: float) -> float:
    """max(30 Hz, 1.5·n0, n3) of EN 1990 A2.4.4.2.1(4)P (n3: the deck's third frequency)."""
    third = frequencies[2] if len(frequencies) >= 3 else 0.0
    return float(max(30.0, 1.5 * n0, third))


def _frequencies(config: Config) -> np.ndarray:
    f = deck_frequencies(config, 120.0)
    if len(f) < 3 and len(f) >= 1:
        f = deck_frequencies(config, 12.0 * f[0])
    if len(f) == 0:
        raise config_error("structure", "no deck mode below 120 Hz", "the deck's first bending frequency cannot be found: give bridge_check.n0")
    return f


def prepare(config: Config, settings: BridgeCheck) -> tuple:
    """(configuration to scan, n0, deck frequencies, band, damping, achieved ratios)."""
    settings.validate()
    if not config.structure.layers:
        raise config_error("structure.layers", [], "the bridge check needs a deck")
    freqs = _frequencies(config)
    n0 = float(settings.n0) if settings.n0 is not None else float(freqs[0])
    band = float(settings.band) if settings.band is not None else deck_band_of(freqs, n0)
    damping = code_damping(settings.bridge_type, settings.span, settings.interaction)
    cfg = apply_code_damping(with_band(config, band), damping, n0, band)
    if len(cfg.structure.layers) > 1:
        cfg.output.points = span_points(cfg)  # the deck searched along its length
    cfg.solver.dt = float(settings.dt) if settings.dt is not None else 1.0 / (STEPS_PER_BAND_PERIOD * band)
    if len(cfg.structure.layers) > 1:
        cfg.output.band_limit = None  # the scan records the deck's indices only, low-passed at output.deck_band
    in_band = freqs[freqs <= band]
    return cfg, n0, freqs, band, damping, achieved_ratios(cfg.structure.layers[-1].damping, in_band)


def assess(config: Config, settings: BridgeCheck, out: Union[str, Path, None] = None, executor: Optional[Executor] = None,
           threads: Optional[int] = None, progress: bool = True) -> Assessment:
    """Runs the check (``out``: a directory the scan journals in, so a re-run resumes)."""
    t0 = time.perf_counter()
    cfg, n0, freqs, band, damping, achieved = prepare(config, settings)
    trains = [load_train(t) for t in settings.trains]
    v_max = 1.2 * settings.line_speed
    resonances = [v for t in trains if t.spacing for f in mass_frequencies(n0, settings.mass_bounds) for v in resonant_speeds(f, t.spacing, v_max, ORDERS)]
    speeds = scan_speeds(settings.v_min, v_max, settings.step, resonances)
    scan = speed_scan(cfg, trains, speeds, band=band, mass_bounds=settings.mass_bounds, share=settings.share, tail=settings.tail,
                      out=None if out is None else Path(out) / "journals", executor=executor, threads=threads, progress=progress)
    lines = {}  # the influence lines at each observation point that governs an effect

    def line_at(x: float, quantity: str):
        if (x, quantity) not in lines:
            lines[x, quantity] = influence_line(cfg, point=x, quantity=quantity)
        return lines[x, quantity]

    points = cfg.output.points or [cfg.structure.length / 2]
    l_phi = float(settings.l_phi or settings.span)
    phi = phi_2(l_phi) if settings.maintenance == "careful" else phi_3(l_phi)
    lm71 = {q: max(line_at(float(x), q).lm71(settings.alpha, settings.share) for x in points) for q in QUANTITIES}
    k_irr = 0.5 if settings.maintenance == "careful" else 1.0
    irr = phi_irregularity(l_phi, n0, settings.line_speed)
    envelopes = []
    for t in trains:
        sel = scan.select(train=t.name)
        responses = [response(sel, column, lambda x, q=q: line_at(x, q), t, settings) for column, q in zip(("disp", "moment"), QUANTITIES)]
        phi_dyn = max(r.phi_dyn for r in responses)  # the larger governs, EN 1991-2 §6.4.6.5(3)
        envelopes.append(TrainEnvelope(t.name, *responses, phi_dyn, irr if math.isfinite(phi_dyn) else math.nan, k_irr))
    result = Assessment(settings, cfg, n0, freqs, band, damping, achieved,
                        dynamic_analysis_required(settings.span, n0, settings.line_speed, settings.simple_structure, settings.continuous),
                        scan, lm71["deflection"], lm71["moment"], phi, envelopes)
    if settings.vehicles:
        plain = apply_code_damping(cfg, code_damping(settings.bridge_type, settings.span, False), n0, band)
        result.interaction = interaction_scan(plain, settings.vehicles, speeds, band=band, mass_bounds=settings.mass_bounds,
                                              tail=settings.tail, out=None if out is None else Path(out) / "interaction",
                                              executor=executor, threads=threads, progress=progress)
    result.checks = checks_of(result)
    result.seconds = time.perf_counter() - t0
    return result


def response(sel: dict, column: str, line, train, settings: BridgeCheck) -> Response:
    """The :class:`Response` of one train's scan ``sel`` in ``column`` (``"disp"`` or
    ``"moment"``), its static values from ``line(x)``, the influence line at x: NaN when every
    run failed."""
    ok = np.isfinite(sel[column])
    if not ok.any():
        return Response(*[math.nan] * 6)
    i = int(np.argmax(np.where(ok, sel[column], -np.inf)))
    x = float(sel[column + "_x"][i])
    static = line(x).train(train, settings.share)
    dynamic = float(sel[column][i])
    return Response(static, dynamic, float(sel["speed"][i]), max(0.0, dynamic / static - 1.0), x,
                    line(x).lm71(settings.alpha, settings.share))


def mass_frequencies(n0: float, bounds: dict) -> list:
    """n0 of each mass bound: n0/√factor (the deck's stiffness kept)."""
    return [n0 / math.sqrt(f) for f in bounds.values()]


def checks_of(a: Assessment) -> list:
    """The checks of an assessment, each with its clause."""
    s = a.settings
    out = []
    failed = int(np.sum(a.scan.columns["error"] != ""))
    if failed:
        out.append(Check("runs", "—", float(failed), 0.0, "runs", False, note=f"{failed} of {len(a.scan)} runs failed; see the envelopes' error column"))
    if failed == len(a.scan):
        return out
    gov = a.scan.governing("acc")
    out.append(verdict("deck acceleration", "EN 1990 A2.4.4.2.1(4)P; EN 1991-2 §6.4.6.5", gov["acc"], acceleration_limit(s.track), "m/s²",
                       f"{gov['train']} ({gov['bound']})", gov["speed"], note=f"in the band up to {a.band:.3g} Hz, largest at x = {gov['acc_x']:g} m"))
    limit = a.phi * a.lm71
    for effect, unit, what in (("deflection", "m", "deflection"), ("moment", "N·m", "bending moment")):
        finite = [e for e in a.envelopes if math.isfinite(getattr(e, effect).design)]
        if not finite:
            continue
        worst = max(finite, key=lambda e: getattr(e, effect).design / getattr(e, effect).lm71)
        r = getattr(worst, effect)
        out.append(verdict(f"dynamic envelope within Φ·LM71, {what}", "EN 1991-2 §6.4.6.5(3), eq. (6.15)", r.design, a.phi * r.lm71, unit,
                           worst.train, r.speed, note=f"{what} at x = {r.x:g} m, where the train's dynamic {what} is largest, with "
                           f"φ'dyn = {worst.phi_dyn:.3g} (the larger of the deflection's {worst.deflection.phi_dyn:.3g} and the moment's "
                           f"{worst.moment.phi_dyn:.3g}); where it exceeds Φ·α·LM71 the dynamic envelope governs the design"))
    out.append(verdict("deck deflection, traffic safety", "EN 1990 A2.4.4.2.3(1)", limit, s.span / SAFETY_DEFLECTION_RATIO, "m", "LM71 × Φ × α",
                       note="δ ≤ L/600"))
    if s.comfort_ratio is not None:
        comfort = a.phi * a.lm71 / s.alpha
        out.append(verdict("deck deflection, passenger comfort", "EN 1990 A2.4.4.3.2 (Fig. A2.3)", comfort, s.span / s.comfort_ratio, "m", "LM71 × Φ (α = 1)",
                           note=f"L/δ = {s.comfort_ratio:g} read from Fig. A2.3"))
    else:
        out.append(Check("deck deflection, passenger comfort", "EN 1990 A2.4.4.3.2 (Fig. A2.3)", a.phi * a.lm71 / s.alpha, math.nan, "m", None,
                         "LM71 × Φ (α = 1)", note="not evaluated: give bridge_check.comfort_ratio (L/δ of Fig. A2.3 for the span and speed)"))
    return out
