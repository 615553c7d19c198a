"""Spectra and one-third-octave band levels of a sampled signal (docs/spectra.md).

* :func:`third_octave`: the **energy-true** IEC 61260-1 base-10 one-third-octave levels of a
  record taken whole (a passage, a transient): the band powers of its periodogram over the
  analysis window, which sum with the power below and above the bands to the record's mean
  square (Parseval, exactly); with the equivalent level L_eq over the window and the exposure
  level L_E (re 1 s).
* :func:`psd` and :func:`welch_third_octave`: Welch's estimator for **stationary** records —
  Hann window, segments of ``nperseg`` samples overlapping by half, each segment's mean
  removed, density scaling — so that the PSD integrates to the variance (units: signal²/Hz);
  its band powers integrate the PSD over each band. On a transient the segments' window
  weights an event by where it falls, so its levels are not the record's energy.
* :func:`low_pass`: the core's zero-phase low-pass of the band-limited indices
  (``output.band_limit``): an 8th-order Butterworth run forwards and backwards, gain
  1/(1 + (f/f_b)¹⁶), −6 dB at the band limit f_b (docs/model.md §8).

Bands: exact midband frequencies f_m = 1000 Hz · 10^(x/10), edges f_m · 10^(∓1/20), levels
10·log10(power / ref²) dB against the standard references 1e−6 m/s² for acceleration, 1e−9 m
for displacement (:data:`REFERENCE`). Only bands at least :data:`MIN_BINS_PER_BAND` frequency
bins wide are reported by default: narrower bands hold too few bins for a level.
"""

from __future__ import annotations

import math
from typing import Optional

import numpy as np

from .. import _core
from ..errors import config_error

#: Level references (IEC / ISO conventions for vibration): acceleration 1e−6 m/s²,
#: velocity 1e−9 m/s, displacement 1e−9 m.
REFERENCE = {"acc": _core.ACC_REFERENCE, "vel": 1e-9, "disp": 1e-9}
def low_pass(x, band_limit: float, dt: float) -> np.ndarray:
    """``x`` (a 1-D record sampled every ``dt`` s) low-passed at ``band_limit`` Hz with zero
    phase: the filter every band-limited index of a run is taken after, so a record filtered
    here gives the run's band-limited peak (same units as ``x``). Raises
    :class:`vtb.ConfigError` naming ``x``, ``band_limit`` or ``dt``."""
    a = np.asarray(x, dtype=float)
    if a.ndim != 1 or a.size < 2:
        raise config_error("x", f"shape {a.shape}", "must be a 1-D record of at least 2 samples")
    return _core.low_pass(np.ascontiguousarray(a), float(band_limit), float(dt))


#: A band is reported when it spans at least this many frequency bins (the core's rule for its
#: band-level indices, ``output.band_levels``).
MIN_BINS_PER_BAND: int = _core.MIN_BINS_PER_BAND
#: IEC 61260-1 nominal midband frequencies of the one-third-octave bands 10 Hz … 8 kHz per
#: decade (the labels; levels use the exact base-10 midbands).
NOMINAL = (1.0, 1.25, 1.6, 2.0, 2.5, 3.15, 4.0, 5.0, 6.3, 8.0)


def _signal(x, name: str = "signal") -> np.ndarray:
    a = np.asarray(x, dtype=float)
    if a.ndim != 1 or a.size < 8:
        raise config_error(name, f"shape {a.shape}", "must be a 1-D series of at least 8 samples")
    if not np.isfinite(a).all():
        raise config_error(name, "non-finite values", "must be finite")
    return a


def _rate(fs) -> float:
    if isinstance(fs, bool) or not isinstance(fs, (int, float)) or not math.isfinite(fs) or fs <= 0:
        raise config_error("fs", fs, "sampling rate must be a finite number > 0 (Hz)")
    return float(fs)


def default_nperseg(n: int) -> int:
    """The default Welch segment: the largest power of two not above n/2 (so that at least
    three half-overlapping segments are averaged)."""
    return max(8, 1 << int(math.floor(math.log2(max(n // 2, 8)))))


def psd(x, fs: float, nperseg: Optional[int] = None) -> tuple[np.ndarray, np.ndarray]:
    """One-sided PSD of ``x`` sampled at ``fs`` Hz by Welch's method (module docstring).
    Returns (f in Hz, PSD in units²/Hz)."""
    from scipy.signal import welch

    x = _signal(x)
    fs = _rate(fs)
    n = default_nperseg(x.size) if nperseg is None else nperseg
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not 8 <= n <= x.size:
        raise config_error("nperseg", nperseg, f"must be an integer within [8, {x.size}] (the series' length)")
    f, p = welch(x, fs=fs, window="hann", nperseg=int(n), noverlap=int(n) // 2, detrend="constant", scaling="density")
    return f, p


def band_centres(f_lo: float, f_hi: float) -> np.ndarray:
    """Band indices x with exact base-10 midbands 1000·10^(x/10) Hz whose whole band lies in
    [f_lo, f_hi]."""
    x_lo = math.ceil(10.0 * math.log10(f_lo / 1000.0) + 0.5)
    x_hi = math.floor(10.0 * math.log10(f_hi / 1000.0) - 0.5)
    return np.arange(x_lo, x_hi + 1)


def nominal_frequency(fm: float) -> float:
    """The IEC 61260-1 nominal label of an exact midband frequency (1.25, 31.5, 1000 …)."""
    decade = 10.0 ** math.floor(math.log10(fm) + 1e-9)
    mant = fm / decade
    label = min(NOMINAL + (10.0,), key=lambda v: abs(math.log10(v / mant)))
    return round(label * decade, 10)


def band_power(f: np.ndarray, p: np.ndarray, f1: float, f2: float) -> float:
    """∫ PSD df over [f1, f2] with the PSD linear between bins (edges interpolated)."""
    inside = (f > f1) & (f < f2)
    ff = np.concatenate(([f1], f[inside], [f2]))
    pp = np.concatenate(([np.interp(f1, f, p)], p[inside], [np.interp(f2, f, p)]))
    return float(np.trapezoid(pp, ff) if hasattr(np, "trapezoid") else np.trapz(pp, ff))


def _bands(df: float, f_top: float, quantity: str, f_min: Optional[float], f_max: Optional[float]) -> tuple:
    """The bands for bins of width ``df`` up to ``f_top`` (module docstring): (centre, lower,
    upper, reference)."""
    if quantity not in REFERENCE:
        raise config_error("quantity", quantity, f"must be one of {sorted(REFERENCE)}")
    half_width = 10.0 ** (1 / 20) - 10.0 ** (-1 / 20)  # band width / midband
    lo = max(MIN_BINS_PER_BAND * df / half_width * 10.0 ** (-1 / 20), df) if f_min is None else f_min
    hi = f_top if f_max is None else min(f_max, f_top)
    x_idx = band_centres(lo, hi)
    if x_idx.size == 0:
        raise config_error("f_min", lo, f"no whole one-third-octave band fits in [{lo:g}, {hi:g}] Hz: use a longer record or a wider range")
    centre = 1000.0 * 10.0 ** (x_idx / 10.0)
    return centre, centre * 10.0 ** (-1 / 20), centre * 10.0 ** (1 / 20), REFERENCE[quantity]


def _levels(centre, lower, upper, power, ref, **extra) -> dict:
    with np.errstate(divide="ignore"):
        level = 10.0 * np.log10(power / ref**2)
    return dict(centre=centre, nominal=np.array([nominal_frequency(c) for c in centre]), lower=lower, upper=upper, power=power,
                level=level, reference=ref, **extra)


def third_octave(x, fs: float, quantity: str = "acc", f_min: Optional[float] = None, f_max: Optional[float] = None) -> dict:
    """Energy-true one-third-octave band levels of the record ``x`` taken whole (module
    docstring): the one-sided periodogram of the record (no window, no averaging) puts each
    frequency bin's power — ``|X_k|²/N²``, doubled but for 0 and the Nyquist frequency — wholly in
    the band holding its frequency, so that the band powers, ``below`` (the bins under the
    first band, the mean included) and ``above`` sum to the mean square. ``quantity``:
    ``"acc"``, ``"vel"`` or ``"disp"`` picks the reference (:data:`REFERENCE`); ``f_min``,
    ``f_max`` (Hz) limit the bands (default: from the first band at least
    :data:`MIN_BINS_PER_BAND` bins of 1/T wide to the last one below the Nyquist frequency).

    Returns numpy columns ``centre`` (exact midband, Hz), ``nominal`` (Hz), ``lower`` and
    ``upper`` (band edges, Hz), ``power`` (units², each band's share of the mean square) and
    ``level`` (dB re the reference); ``reference``; ``mean_square`` (units²), ``below`` and
    ``above`` (units²); ``duration`` T (s); ``leq``, the equivalent level 10·log10(mean square /
    ref²) over T, and ``exposure``, L_E = L_eq + 10·log10(T / 1 s) (dB).
    """
    x = _signal(x)
    fs = _rate(fs)
    n = x.size
    f = np.fft.rfftfreq(n, 1.0 / fs)
    p = np.abs(np.fft.rfft(x)) ** 2 / n**2
    p[1:n // 2 + (n % 2)] *= 2.0  # the one-sided spectrum; 0 Hz and an even record's Nyquist bin once
    centre, lower, upper, ref = _bands(f[1], f[-1], quantity, f_min, f_max)
    # Each bin wholly in the band [lower, upper) holding its frequency (the bands touch).
    index = np.searchsorted(np.append(lower, upper[-1]), f, side="right") - 1
    inside = (index >= 0) & (index < centre.size)
    power = np.bincount(index[inside], weights=p[inside], minlength=centre.size)
    mean_square = float(np.mean(x**2))
    duration = n / fs
    with np.errstate(divide="ignore"):
        leq = 10.0 * math.log10(mean_square / ref**2) if mean_square > 0 else -math.inf
    return _levels(centre, lower, upper, power, ref, mean_square=mean_square, below=float(p[f < lower[0]].sum()),
                   above=float(p[f >= upper[-1]].sum()), duration=duration, leq=leq, exposure=leq + 10.0 * math.log10(duration))


def welch_third_octave(x, fs: float, quantity: str = "acc", nperseg: Optional[int] = None, f_min: Optional[float] = None,
                       f_max: Optional[float] = None) -> dict:
    """One-third-octave band levels of a **stationary** record by Welch's PSD (module
    docstring): each band's power is the PSD integrated over it. Arguments and columns as
    :func:`third_octave` (without its energy totals); the bins are Welch's (``nperseg``)."""
    f, p = psd(x, fs, nperseg)
    centre, lower, upper, ref = _bands(f[1] - f[0], f[-1], quantity, f_min, f_max)
    power = np.array([band_power(f, p, a, b) for a, b in zip(lower, upper)])
    return _levels(centre, lower, upper, power, ref)
