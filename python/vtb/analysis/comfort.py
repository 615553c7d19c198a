"""Ride comfort of a car body (docs/spectra.md): after ISO 2631-1:1997 the Wk frequency
weighting of vertical acceleration, the weighted r.m.s. a_w and the maximum transient
vibration value MTVV; and Sperling's ride index Wz for vertical vibration.

Wk is the product of the standard's four analogue filters (its Annex A): a band limit
(high pass at f1 = 0.4 Hz and low pass at f2 = 100 Hz, both Butterworth Q = 1/√2), the
acceleration–velocity transition (f3 = f4 = 12.5 Hz, Q4 = 0.63) and the upward step
(f5 = 2.37 Hz, Q5 = 0.91, f6 = 3.35 Hz, Q6 = 0.91). :func:`wk` is its exact magnitude;
:func:`weight` applies it to a sampled signal as a digital filter (bilinear transform of the
same poles and zeros, second-order sections, zero initial state); the transform's frequency
warping keeps it within 1 % of Wk up to 100 Hz for sampling rates of 4 kHz and more (vtb's
default step samples at 20 kHz), within about 3 % at 1 kHz.

Record length. MTVV is the largest running r.m.s. with the standard's integration time
τ = 1 s, so it needs at least 1 s of record. a_w converges slowly for the low frequencies Wk
passes (its pass band starts near 0.5 Hz): :data:`MIN_RMS_RECORD` = 20 s holds ten periods of
0.5 Hz. Shorter records get a :class:`ComfortWarning`; a vtb run over a 160 m bridge at 80
m/s lasts about 2 s, so its comfort indices describe that passage, not a journey.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from ..errors import config_error
from .spectra import _rate, _signal

#: (f1, f2, f3, f4, Q4, f5, Q5, f6, Q6) of Wk (Hz), ISO 2631-1 Annex A.
WK = dict(f1=0.4, f2=100.0, f3=12.5, f4=12.5, q4=0.63, f5=2.37, q5=0.91, f6=3.35, q6=0.91)
#: The running r.m.s. integration time of MTVV (s), ISO 2631-1 6.3.2.
TAU = 1.0
#: Record length (s) for a weighted r.m.s. that means something: ten periods of 0.5 Hz.
MIN_RMS_RECORD = 20.0
#: Sperling's vertical correction factor F(f): (upper band edge (Hz), F as a function of f).
SPERLING_F = ((5.9, lambda f: 0.325 * f**2), (20.0, lambda f: 400.0 / f**2), (math.inf, lambda f: np.ones_like(f)))
#: The frequency band (Hz) of the Sperling index.
SPERLING_BAND = (0.5, 40.0)
#: Record length (s) for a Sperling index: a line spacing of 0.2 Hz, five lines per hertz
#: around the car-body modes (about 1 Hz).
MIN_SPERLING_RECORD = 5.0


class ComfortWarning(UserWarning):
    """A comfort index from a record shorter than it needs (module docstring)."""


def _omegas():
    w = {k: 2.0 * math.pi * v for k, v in WK.items() if k.startswith("f")}
    return w, WK["q4"], WK["q5"], WK["q6"]


def wk(f) -> np.ndarray:
    """``|Wk(f)|``: the magnitude of the ISO 2631-1 weighting at frequencies ``f`` (Hz)."""
    (w, q4, q5, q6), s = _omegas(), 2j * math.pi * np.asarray(f, dtype=float)
    high = s**2 / (s**2 + math.sqrt(2) * w["f1"] * s + w["f1"] ** 2)
    low = w["f2"] ** 2 / (s**2 + math.sqrt(2) * w["f2"] * s + w["f2"] ** 2)
    transition = (w["f4"] ** 2 / w["f3"]) * (s + w["f3"]) / (s**2 + w["f4"] / q4 * s + w["f4"] ** 2)
    step = (s**2 + w["f5"] / q5 * s + w["f5"] ** 2) / (s**2 + w["f6"] / q6 * s + w["f6"] ** 2)
    return np.abs(high * low * transition * step)


def _zpk():
    """Analogue zeros, poles and gain of Wk."""
    w, q4, q5, q6 = _omegas()
    zeros = [0.0, 0.0, -w["f3"], *np.roots([1.0, w["f5"] / q5, w["f5"] ** 2])]
    poles = [
        *np.roots([1.0, math.sqrt(2) * w["f1"], w["f1"] ** 2]),
        *np.roots([1.0, math.sqrt(2) * w["f2"], w["f2"] ** 2]),
        *np.roots([1.0, w["f4"] / q4, w["f4"] ** 2]),
        *np.roots([1.0, w["f6"] / q6, w["f6"] ** 2]),
    ]
    gain = w["f2"] ** 2 * w["f4"] ** 2 / w["f3"]
    return np.array(zeros), np.array(poles), gain


def wk_sos(fs: float) -> np.ndarray:
    """Second-order sections of the digital Wk filter at sampling rate ``fs`` (Hz)."""
    from scipy.signal import bilinear_zpk, zpk2sos

    fs = _rate(fs)
    if fs < 400.0:
        raise config_error("fs", fs, "Wk extends to 100 Hz: sample at 400 Hz or more")
    z, p, k = bilinear_zpk(*_zpk(), fs)
    return zpk2sos(z, p, k)


def weight(a, fs: float) -> np.ndarray:
    """The Wk-weighted acceleration (m/s²) of ``a`` (m/s², vertical) sampled at ``fs`` Hz."""
    from scipy.signal import sosfilt

    return sosfilt(wk_sos(fs), _signal(a, "acceleration"))


def running_rms(a: np.ndarray, fs: float, tau: float = TAU) -> np.ndarray:
    """sqrt((1/τ)·∫ over the last τ of a²) at every sample (linear integration; the first τ
    integrates what exists)."""
    n = max(1, int(round(tau * fs)))
    c = np.concatenate(([0.0], np.cumsum(a * a)))
    idx = np.arange(1, a.size + 1)
    return np.sqrt((c[idx] - c[np.maximum(idx - n, 0)]) / n)


def _warn_if_short(duration: float, needed: float, index: str, why: str) -> None:
    """A :class:`ComfortWarning` for a record (s) shorter than ``index`` needs."""
    if duration < needed:
        warnings.warn(f"comfort: a {duration:.3g} s record is short for {index}, which needs about {needed:g} s ({why})", ComfortWarning, stacklevel=3)


def iso2631(a, fs: float) -> dict:
    """ISO 2631-1 indices of a vertical acceleration record (m/s², sampled at ``fs`` Hz):
    ``a_w`` (Wk-weighted r.m.s., m/s²), ``mtvv`` (maximum transient vibration value, τ = 1 s,
    m/s²; NaN for records shorter than τ), their ratio ``mtvv_ratio`` (above 1.5 the standard
    asks for the running methods) and ``duration`` (s). Warns (:class:`ComfortWarning`) for records shorter than they need."""
    fs = _rate(fs)
    aw = weight(a, fs)
    duration = aw.size / fs
    _warn_if_short(duration, MIN_RMS_RECORD, "ISO 2631-1 a_w", "ten periods of 0.5 Hz" + ("" if duration >= TAU else "; MTVV needs at least 1 s"))
    rms = float(np.sqrt(np.mean(aw**2)))
    mtvv = float(running_rms(aw, fs).max()) if duration >= TAU else math.nan
    return dict(a_w=rms, mtvv=mtvv, mtvv_ratio=mtvv / rms if rms > 0 else math.nan, duration=duration)


def sperling_f(f) -> np.ndarray:
    """Sperling's correction factor F(f) for vertical vibration at ``f`` Hz (module docstring;
    defined from 0.5 Hz up, zero below)."""
    f = np.asarray(f, dtype=float)
    out = np.zeros_like(f)
    lower = SPERLING_BAND[0]
    for upper, fn in SPERLING_F:
        band = (f >= lower) & (f < upper)
        out[band] = fn(f[band])
        lower = upper
    return out


def sperling(a, fs: float) -> dict:
    """Sperling's vertical ride index of an acceleration record (m/s², sampled at ``fs`` Hz):
    ``wz`` (dimensionless; about 1 just noticeable, 2 clearly noticeable, 2.5 more pronounced but
    not unpleasant, 3 strong, 3.25 very irregular, 3.5 extremely irregular, 4 extremely
    unpleasant, 4.5 not passable), ``line_spacing`` (Hz) and ``duration`` (s). Warns
    (:class:`ComfortWarning`) for records shorter than :data:`MIN_SPERLING_RECORD`."""
    fs = _rate(fs)
    x = _signal(a, "acceleration")
    duration = x.size / fs
    _warn_if_short(duration, MIN_SPERLING_RECORD, "the Sperling index", f"0.2 Hz lines around the car-body modes; this record resolves {1 / duration:.3g} Hz")
    spec = np.fft.rfft(x - x.mean())
    f = np.fft.rfftfreq(x.size, 1.0 / fs)
    amp = 2.0 * np.abs(spec) / x.size * 100.0  # peak amplitude of each harmonic, cm/s²
    if x.size % 2 == 0:
        amp[-1] /= 2.0  # the Nyquist line is not doubled
    keep = (f >= SPERLING_BAND[0]) & (f <= SPERLING_BAND[1])
    wz10 = 0.896**10 * np.sum(amp[keep] ** 3 * sperling_f(f[keep]) / f[keep])
    return dict(wz=float(wz10**0.1), line_spacing=fs / x.size, duration=duration)
