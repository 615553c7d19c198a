"""Track irregularities: power spectral densities, random profiles and deterministic shapes.

Conventions
-----------
* r(x) is the deviation of the rail top from its ideal line in metres, **positive downward (a
  dip)**.
* Every PSD function here returns the **one-sided** density ``S(f)`` in **m²/(1/m) = m³** of
  the spatial frequency ``f`` in **cycles/m** (1/m, wavelength λ = 1/f), so that the variance is
  ∫ S(f) df. Spectra published per angular wavenumber Ω = 2πf (rad/m) are converted with
  S_f(f) = 2π·S_Ω(2πf); spectra published in mm² or cm² are converted to m².

Families (their published forms; docs/model.md §4):

``tbt3352``     TB/T 3352-2014 ballastless-track vertical profile, S = A/fⁿ in mm²/(1/m),
                four segments; its last segment is extrapolated to short wavelengths (the
                standard covers 2–120 m; vtb's paper preset uses it for 0.01–1 m, as the
                article's "standard Chinese spectrum" suggests).
``sato``        Sato (RTRI 1977) wheel–rail roughness S(Ω) = A/Ω³ in m²/(rad/m), Ω in rad/m
                (A = 4.15e−8 … 5e−7; default 4.15e−8).
``iso3095``     ISO 3095:2013 / EN 15610 rail-roughness limit, from 1/3-octave band levels
                L = 10·lg(r²/r₀²), r₀ = 1 µm, λ = 0.315–40 cm: S(f_c) = r₀²·10^(L/10)/Δf with
                Δf = 0.2308·f_c; log–log interpolation between band centres and extrapolation
                with the end slopes outside the table.
``german_low``, ``german_high``   German high-speed spectra (vertical), S(Ω) = A_v·Ω_c² /
                ((Ω² + Ω_r²)(Ω² + Ω_c²)) in m²/(rad/m), taken as one-sided.
``fra1`` … ``fra6``   US FRA track classes (vertical), S(Ω) = k·A_v·Ω_c²/(Ω²(Ω² + Ω_c²)) in
                cm²/(rad/m), k = 0.25, taken as one-sided.

Generation from a seed (:class:`numpy.random.Generator`), restricted to the wavelength band
[``wavelength_min``, ``wavelength_max``]:

``ifft``        inverse FFT with deterministic amplitudes |X_k| = N·sqrt(S(f_k)·Δf/2) and random
                phases (Chen & Zhai 1999): the sample variance equals Σ S(f_k)·Δf exactly.
``spectral``    spectral representation (Shinozuka & Jan 1972): Σ sqrt(2·S(f_k)·Δf)·cos(2πf_k·x
                + φ_k) with jittered frequencies f_k = f_min + (k − ½ + u_k)Δf.

Deterministic shapes: ``cosine_dip`` (a single (depth/2)(1 − cos) dip of given length),
``corrugation`` ((amplitude/2)(1 − cos(2πx/λ)) over an interval) and ``sampled`` (a profile
given by the user). ``none`` is a perfectly smooth rail.

Local defects (docs/defects.md): ``rail_joint`` (a step and a V-shaped dip of total angle 2α =
4·depth/length at the joint, Jenkins et al. 1974), ``dipped_weld`` (a cosine dip with a short
cosine crown at its centre, after Zhai) and ``wheel_flat`` (on one wheel, repeating every
wheel circumference 2πR: a rounded flat of length L and depth L²/(16R), Wu & Thompson 2002,
or a new flat, the chord of length L with sharp edges). Every defect is seen through the
wheel: the wheel centre rides the upper envelope of circles of the wheel's radius rolled over
the geometry (the rail's, or the flat's dent in the tread rolled on a flat rail), so a step,
a kink or a flat's edge gives the finite contact slope a real wheel meets, not one set by the
sampling, and a hollow narrower than the wheel's curvature is bridged.

A profile is its own ``kind`` plus any number of ``parts`` (each an :class:`Irregularity`),
superposed: a long-wave spectrum for the car body, a short-wave one for the track, and local
defects by position.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field, replace
from typing import Callable, Optional, Sequence

import numpy as np

from ..errors import config_error
from .schema import StrictFields, properties

# --------------------------------------------------------------------------------------------
# PSD families: one-sided S(f) in m³ for f in 1/m
# --------------------------------------------------------------------------------------------

#: TB/T 3352-2014 vertical profile: (A, n) per segment and break frequencies (1/m);
#: S in mm²/(1/m).
TBT3352_VERTICAL = ((1.0544e-5, 3.3891), (3.5588e-3, 1.9271), (1.9784e-2, 1.3643), (3.9488e-4, 3.4516))
TBT3352_BREAKS = (0.0187, 0.0474, 0.1533)


def psd_tbt3352(f: np.ndarray) -> np.ndarray:
    """TB/T 3352 vertical profile, one-sided, m³ (f in 1/m)."""
    f = np.asarray(f, dtype=float)
    seg = np.searchsorted(np.asarray(TBT3352_BREAKS), f, side="right")
    a = np.array([c[0] for c in TBT3352_VERTICAL])[seg]
    n = np.array([c[1] for c in TBT3352_VERTICAL])[seg]
    return a / f**n * 1e-6


def psd_sato(f: np.ndarray, a: float = 4.15e-8) -> np.ndarray:
    """Sato: S(Ω) = A/Ω³ (m²/(rad/m)) → S_f = A/(4π²f³), one-sided, m³."""
    f = np.asarray(f, dtype=float)
    return a / (4.0 * math.pi**2 * f**3)


#: ISO 3095 / EN 15610 limit: wavelength (cm) and 1/3-octave band level (dB re 1 µm).
ISO3095_LIMIT = (
    (40, 17.1), (31.5, 15.0), (25, 13.0), (20, 11.0), (16, 9.0), (12.5, 7.0), (10, 4.9), (8, 2.9),
    (6.3, 0.9), (5, -1.1), (4, -3.2), (3.15, -5.0), (2.5, -5.6), (2, -6.2), (1.6, -6.8), (1.25, -7.4),
    (1, -8.0), (0.8, -8.6), (0.63, -9.2), (0.5, -9.8), (0.4, -10.4), (0.315, -11.0),
)


def psd_iso3095(f: np.ndarray) -> np.ndarray:
    """ISO 3095 rail-roughness limit as a one-sided PSD (m³), log–log interpolated."""
    f = np.asarray(f, dtype=float)
    fc = np.array([100.0 / lam for lam, _ in ISO3095_LIMIT])
    s = np.array([1e-12 * 10 ** (lev / 10.0) / (0.2308 * c) for c, (_, lev) in zip(fc, ISO3095_LIMIT)])
    lf, ls = np.log(fc), np.log(s)
    x = np.log(f)
    out = np.interp(x, lf, ls)
    lo, hi = x < lf[0], x > lf[-1]
    out[lo] = ls[0] + (x[lo] - lf[0]) * (ls[1] - ls[0]) / (lf[1] - lf[0])
    out[hi] = ls[-1] + (x[hi] - lf[-1]) * (ls[-1] - ls[-2]) / (lf[-1] - lf[-2])
    return np.exp(out)


GERMAN = {"low": 4.032e-7, "high": 10.80e-7}
GERMAN_OMEGA_C, GERMAN_OMEGA_R = 0.8246, 0.0206


def psd_german(f: np.ndarray, level: str = "low") -> np.ndarray:
    """German high-speed vertical spectrum (low/high interference), one-sided, m³."""
    w = 2.0 * math.pi * np.asarray(f, dtype=float)
    av = GERMAN[level]
    s_omega = av * GERMAN_OMEGA_C**2 / ((w**2 + GERMAN_OMEGA_R**2) * (w**2 + GERMAN_OMEGA_C**2))
    return 2.0 * math.pi * s_omega


#: FRA vertical A_v (cm²·rad/m) for classes 1..6; Ω_c (rad/m), k.
FRA_AV = (1.2107, 1.0181, 0.6816, 0.5376, 0.2095, 0.0339)
FRA_OMEGA_C, FRA_K = 0.8245, 0.25


def psd_fra(f: np.ndarray, track_class: int = 6) -> np.ndarray:
    """US FRA vertical profile of a track class (1–6), one-sided, m³."""
    w = 2.0 * math.pi * np.asarray(f, dtype=float)
    av = FRA_AV[track_class - 1]
    s_omega_cm2 = FRA_K * av * FRA_OMEGA_C**2 / (w**2 * (w**2 + FRA_OMEGA_C**2))
    return 2.0 * math.pi * s_omega_cm2 * 1e-4


def psd(kind: str, **params) -> Callable[[np.ndarray], np.ndarray]:
    """The one-sided PSD function S(f) (m³, f in 1/m) of a family name."""
    if kind == "tbt3352":
        return psd_tbt3352
    if kind == "sato":
        a = params.get("sato_a", 4.15e-8)
        return lambda f: psd_sato(f, a)
    if kind == "iso3095":
        return psd_iso3095
    if kind in ("german_low", "german_high"):
        return lambda f: psd_german(f, kind.split("_")[1])
    if kind.startswith("fra") and kind[3:].isdigit() and 1 <= int(kind[3:]) <= 6:
        c = int(kind[3:])
        return lambda f: psd_fra(f, c)
    raise config_error("irregularity.kind", kind, f"unknown spectrum (known: {', '.join(SPECTRA)})")


SPECTRA = ("tbt3352", "sato", "iso3095", "german_low", "german_high", "fra1", "fra2", "fra3", "fra4", "fra5", "fra6")
SHAPES = ("none", "cosine_dip", "corrugation", "sampled")
#: Local defects of the rail (seen through the wheel's radius) and of a wheel's tread.
DEFECTS = ("rail_joint", "dipped_weld", "wheel_flat")
#: Default sampling step of a local defect (m): it resolves the ~30 mm over which a wheel of
#: radius 0.46 m meets a 1 mm step (√(2Rh)).
DEFECT_DX = 5e-4
#: The shapes of a wheel flat: worn round (Wu & Thompson 2002) or new, with sharp edges.
FLAT_SHAPES = ("rounded", "new")


@functools.lru_cache(maxsize=4)
def _gauss_legendre(n: int) -> tuple:
    """Gauss–Legendre nodes and weights on [-1, 1], made once: numpy finds them by a dense
    eigenproblem (tens of ms), which would otherwise be paid at every run's band check."""
    x, w = np.polynomial.legendre.leggauss(n)
    x.setflags(write=False)
    w.setflags(write=False)
    return x, w


def band_variance(kind: str, wavelength_min: float, wavelength_max: float, **params) -> float:
    """∫ S(f) df over the band (m²), by Gauss–Legendre in log f (exact to round-off for the
    smooth power-law families)."""
    s = psd(kind, **params)
    lo, hi = math.log(1.0 / wavelength_max), math.log(1.0 / wavelength_min)
    x, w = _gauss_legendre(200)
    u = 0.5 * (hi - lo) * (x + 1.0) + lo
    f = np.exp(u)
    return float(np.sum(w * s(f) * f) * 0.5 * (hi - lo))


# --------------------------------------------------------------------------------------------
# Random generation
# --------------------------------------------------------------------------------------------


def generate_ifft(s: Callable[[np.ndarray], np.ndarray], n: int, dx: float, f_min: float, f_max: float, rng: np.random.Generator,
                  f_keep: Optional[float] = None) -> np.ndarray:
    """n samples (spacing dx) with one-sided PSD s restricted to [f_min, f_max]: inverse FFT with
    deterministic amplitudes N·sqrt(S·Δf/2) and uniform random phases; the components above
    ``f_keep`` (cycles/m) left out of the same draw."""
    df = 1.0 / (n * dx)
    k = np.arange(n // 2 + 1)
    f = k * df
    top = f_max if f_keep is None else min(f_max, f_keep)
    band = (f >= f_min) & (f <= top) & (k > 0) & (k < (n + 1) // 2)
    amp = np.zeros(n // 2 + 1)
    amp[band] = n * np.sqrt(s(f[band]) * df / 2.0)
    phase = rng.uniform(0.0, 2.0 * math.pi, n // 2 + 1)
    return np.fft.irfft(amp * np.exp(1j * phase), n=n)


def generate_spectral(s: Callable[[np.ndarray], np.ndarray], x: np.ndarray, f_min: float, f_max: float, n_freq: int, rng: np.random.Generator,
                      f_keep: Optional[float] = None) -> np.ndarray:
    """Spectral representation Σ sqrt(2·S(f_k)·Δf)·cos(2πf_k·x + φ_k), jittered f_k; the
    components above ``f_keep`` (cycles/m) left out of the same draw."""
    df = (f_max - f_min) / n_freq
    fk = f_min + (np.arange(n_freq) + rng.uniform(0.0, 1.0, n_freq)) * df
    amp = np.sqrt(2.0 * s(fk) * df)
    if f_keep is not None:
        amp[fk > f_keep] = 0.0
    phase = rng.uniform(0.0, 2.0 * math.pi, n_freq)
    out = np.zeros_like(x)
    for i in range(0, n_freq, 256):  # bounded memory
        sl = slice(i, i + 256)
        out += (amp[sl, None] * np.cos(2.0 * math.pi * fk[sl, None] * x[None, :] + phase[sl, None])).sum(axis=0)
    return out


#: Bytes per profile sample held at once while generating (positions, amplitudes, phases,
#: the complex spectrum and the result).
_PROFILE_BYTES_PER_SAMPLE = 64.0
#: Relative error of the realised band variance beyond which a profile warns.
REALISED_TOLERANCE = 0.02


class IrregularityWarning(UserWarning):
    """A generated irregularity does not realise its band (see :meth:`Irregularity.profile`)."""


def wheel_centre_path(r: np.ndarray, dx: float, radius: float) -> np.ndarray:
    """The irregularity (m, dip positive) the centre of a rigid wheel of ``radius`` (m)
    follows over the rail geometry ``r`` sampled at ``dx``: the upper envelope of the circles
    it can touch, z(x) = max_s [−r(s) + √(R² − (x − s)²)] − R. A wheel bridges a kink or the
    edge of a step instead of following it, so the contact input has the slope and curvature a
    real wheel meets, independent of the sampling once dx resolves √(2Rh)."""
    e = -np.asarray(r, dtype=float)
    z = e.copy()
    h = float(e.max() - e.min())
    reach = math.sqrt(2.0 * radius * h + h * h)
    for j in range(1, min(int(math.ceil(reach / dx)), e.size - 1) + 1):
        if j * dx >= radius:
            break
        drop = radius - math.sqrt(radius * radius - (j * dx) ** 2)
        np.maximum(z[:-j], e[j:] - drop, out=z[:-j])
        np.maximum(z[j:], e[:-j] - drop, out=z[j:])
    return -z


def _grid_size(x_min: float, x_max: float, dx: float, memory_budget: Optional[float], name: str) -> int:
    """Samples of a grid of step dx over [x_min, x_max]; a count beyond the memory budget
    (bytes; default the core's ``solver.memory_budget``) raises naming ``name``."""
    samples = (x_max - x_min) / dx + 1.0
    budget = properties("SolverConfig")["memory_budget"]["default"] if memory_budget is None else memory_budget
    if not samples * _PROFILE_BYTES_PER_SAMPLE <= budget:
        raise config_error(
            name, dx,
            f"{samples:.3e} samples over {x_max - x_min:g} m would need about {samples * _PROFILE_BYTES_PER_SAMPLE / 1e9:.3g} GB, "
            f"beyond solver.memory_budget = {budget / 1e9:.3g} GB",
        )
    return int(math.ceil((x_max - x_min) / dx)) + 1


# --------------------------------------------------------------------------------------------
# The configuration object
# --------------------------------------------------------------------------------------------


#: The largest depth, step, crown or amplitude (m) of a shape or defect: a rail defect is
#: millimetres deep; beyond this the value is a unit mistake, not a track.
MAX_HEIGHT = 0.1
_HEIGHTS = ("depth", "step", "crown", "amplitude")


@dataclass
class Irregularity(StrictFields):
    """Irregularity of the rail top, r(x) (m, dip positive): a random profile drawn from a
    spectrum, or a deterministic shape. Only the fields of the chosen ``kind`` are used.

    Attributes
    ----------
    kind
        A spectrum (``"tbt3352"``, ``"sato"``, ``"iso3095"``, ``"german_low"``,
        ``"german_high"``, ``"fra1"`` … ``"fra6"``), a shape (``"none"``, ``"cosine_dip"``,
        ``"corrugation"``, ``"sampled"``) or a local defect (``"rail_joint"``,
        ``"dipped_weld"``, ``"wheel_flat"``). Default ``"none"``.
    wavelength_min, wavelength_max
        Band of a random profile (m). Defaults 0.01 and 1.0.
    method
        ``"ifft"`` (inverse FFT of the spectrum with random phases) or ``"spectral"`` (a sum of
        ``n_freq`` harmonics).
    seed
        Seed (non-negative integer) of the random phases; a realisation is fixed by it.
    dx
        Sampling step of a generated profile (m); ``None``: λ_min/10 for a spectrum, 0.5 mm
        for a local defect. For ``"sampled"``: the grid step of ``values``.
    scale
        Factor (−) on the generated profile (for calibration). Default 1.
    n_freq
        Number of harmonics (count) of the ``"spectral"`` method. Default 2000.
    sato_a
        Sato's roughness constant A (rad²; S(Ω) = A/Ω³), the level of the ``"sato"`` spectrum.
    depth, length, position
        ``"cosine_dip"``: depth (m), length (m) and start (m) of the dip. ``"rail_joint"``:
        depth (m) of the V-shaped dip at the joint, its length (m, both rail ends together)
        and the joint's position (m). ``"dipped_weld"``: depth (m) and length (m, typically
        1) of the dip and the weld's position (m, its centre). ``"wheel_flat"``: depth (m;
        0 gives L²/(16R) for a rounded flat; a new flat's is R − √(R² − L²/4) and must be
        left at 0) and length L (m) of the flat, and the position (m) at which its centre
        meets the rail (once every 2πR before and after).
    flat_shape
        ``"wheel_flat"``: ``"rounded"`` (default; the worn cosine dent (d/2)(1 + cos 2πs/L),
        s from the flat's centre, −L/2 ≤ s ≤ L/2) or ``"new"`` (the chord of length L, sharp-edged,
        as a flat is just after it forms). The wheel centre's path over either is the
        small-slope envelope: within 0.1 % of the depth of the exact rolling for flats up to
        50 mm, 0.4 % at 100 mm.
    step
        ``"rail_joint"``: height (m) by which the rail after the joint lies lower (positive:
        a step down in the running direction; negative: a step up, the impact case).
    crown, crown_length
        ``"dipped_weld"``: height (m, ≥ 0) and length (m) of the weld's crown, a cosine hump
        at the dip's centre. Defaults 0 and 0.1.
    wheel
        ``"wheel_flat"``: the wheel that carries the flat, counted over the run's wheels
        (vehicles in order, wheelsets front to rear from 0).
    wheel_radius
        Rolling radius (m) of the wheel a defect is seen through; ``None``: that of the run's
        first vehicle (``"rail_joint"``, ``"dipped_weld"``) or of the flat wheel's vehicle
        (``"wheel_flat"``). 0 applies a rail defect's raw geometry.
    amplitude, wavelength, start, end
        ``"corrugation"``: peak-to-peak amplitude (m), wavelength (m), and the stretch
        [start, end] (m) it covers.
    x0, values
        ``"sampled"``: position of the first sample (m) and the samples r(x0 + i·dx) (m).
    parts
        Further irregularities (each an :class:`Irregularity` without parts of its own)
        superposed on this one.
    beyond_band
        What a run does with a spectrum or a corrugation that excites the rail beyond the band
        its model resolves (:func:`vtb.config.resolution.check_excitation`): ``"filter"``
        (default) leaves its wavelengths below v/f_max out, ``"keep"`` runs it whole (the
        article's presets: its excitation as published). Both warn.
    """

    kind: str = "none"
    wavelength_min: float = 0.01
    wavelength_max: float = 1.0
    method: str = "ifft"
    seed: int = 0
    dx: Optional[float] = None
    scale: float = 1.0
    n_freq: int = 2000
    sato_a: float = 4.15e-8
    depth: float = 0.0
    length: float = 0.0
    position: float = 0.0
    amplitude: float = 0.0
    wavelength: float = 0.0
    start: float = 0.0
    end: float = 0.0
    x0: float = 0.0
    values: list = field(default_factory=list)
    step: float = 0.0
    crown: float = 0.0
    crown_length: float = 0.1
    flat_shape: str = "rounded"
    wheel: int = 0
    wheel_radius: Optional[float] = None
    parts: list = field(default_factory=list)
    beyond_band: str = "filter"

    def validate(self, speed: Optional[float] = None, dt: Optional[float] = None, wheel_radii: Optional[Sequence[float]] = None, path: str = "irregularity",
                 extent: Optional[tuple] = None) -> None:
        """Raises :class:`~vtb.errors.ConfigError` for an unusable setting. With ``speed`` and
        ``dt``, also rejects wavelengths the time step cannot resolve: the shortest wavelength
        must be at least 2·v·Δt (the Nyquist limit of the excitation f = v/λ). With
        ``wheel_radii`` (m, one per wheel of the run), a flat's wheel must be one of the run's
        and the flat must fit on it. With ``extent`` = (start, end) (m; the structure and the
        wheels' travel), a rail defect, a dip, a corrugation or a sampled stretch that lies
        wholly outside it is refused: the run would silently return the smooth rail's answer."""
        p = path
        if not isinstance(self.parts, (list, tuple)):
            raise config_error(f"{p}.parts", self.parts, "expected a list of vtb.Irregularity")
        for i, part in enumerate(self.parts):
            if not isinstance(part, Irregularity):
                raise config_error(f"{p}.parts[{i}]", part, "expected a vtb.Irregularity")
            if part.parts:
                raise config_error(f"{p}.parts[{i}].parts", part.parts, "a part has no parts of its own")
            part.validate(speed, dt, wheel_radii, f"{p}.parts[{i}]", extent)

        def finite(name, v, positive=False):
            if not isinstance(v, (int, float)) or not math.isfinite(v) or (positive and v <= 0):
                raise config_error(f"{p}.{name}", v, "must be a finite number" + (" > 0" if positive else ""))
            if name in _HEIGHTS and abs(v) > MAX_HEIGHT:
                raise config_error(f"{p}.{name}", v, f"a height of the rail or wheel tread beyond {MAX_HEIGHT:g} m is no "
                                                     "irregularity (a value in mm given in m?)")

        if self.kind not in SPECTRA + SHAPES + DEFECTS:
            raise config_error(f"{p}.kind", self.kind, f"unknown kind (known: {', '.join(SPECTRA + SHAPES + DEFECTS)})")
        finite("scale", self.scale)
        if self.scale < 0:
            raise config_error(f"{p}.scale", self.scale, "must be >= 0")
        if self.dx is not None:
            finite("dx", self.dx, positive=True)
        if self.beyond_band not in ("filter", "keep"):
            raise config_error(f"{p}.beyond_band", self.beyond_band, "must be \"filter\" or \"keep\"")
        if self.kind in SPECTRA:
            finite("wavelength_min", self.wavelength_min, True)
            finite("wavelength_max", self.wavelength_max, True)
            if self.wavelength_max <= self.wavelength_min:
                raise config_error(f"{p}.wavelength_max", self.wavelength_max, f"must exceed wavelength_min = {self.wavelength_min}")
            if self.method not in ("ifft", "spectral"):
                raise config_error(f"{p}.method", self.method, "must be \"ifft\" or \"spectral\"")
            if not isinstance(self.seed, (int, np.integer)) or isinstance(self.seed, bool) or self.seed < 0:
                raise config_error(f"{p}.seed", self.seed, "must be a non-negative integer")
            if self.method == "spectral" and (not isinstance(self.n_freq, int) or self.n_freq < 1):
                raise config_error(f"{p}.n_freq", self.n_freq, "must be a positive integer")
            if self.kind == "sato":
                finite("sato_a", self.sato_a, True)
            dx = self.sample_spacing()
            if dx > self.wavelength_min / 4.0:
                raise config_error(f"{p}.dx", dx, f"must be at most wavelength_min/4 = {self.wavelength_min / 4} to represent the shortest wavelength")
            if speed is not None and dt is not None and speed > 0 and self.wavelength_min < 2.0 * speed * dt * (1 - 1e-12):
                raise config_error(
                    f"{p}.wavelength_min",
                    self.wavelength_min,
                    f"shorter than 2·v·Δt = {2 * speed * dt:.4g} m: the excitation frequency v/λ would exceed the Nyquist frequency of the time step",
                )
        elif self.kind == "cosine_dip":
            finite("depth", self.depth)
            finite("length", self.length, True)
            finite("position", self.position)
        elif self.kind == "corrugation":
            finite("amplitude", self.amplitude)
            finite("wavelength", self.wavelength, True)
            finite("start", self.start)
            finite("end", self.end)
            if self.end <= self.start:
                raise config_error(f"{p}.end", self.end, f"must exceed start = {self.start}")
            if speed is not None and dt is not None and speed > 0 and self.wavelength < 2.0 * speed * dt:
                raise config_error(f"{p}.wavelength", self.wavelength, f"shorter than 2·v·Δt = {2 * speed * dt:.4g} m (Nyquist)")
        elif self.kind in DEFECTS:
            finite("position", self.position)
            finite("depth", self.depth)
            finite("length", self.length, True)
            if self.depth < 0:
                raise config_error(f"{p}.depth", self.depth, "must be >= 0 (a dip or a flat; a step's sign is in step)")
            if self.wheel_radius is not None:
                finite("wheel_radius", self.wheel_radius)
                if self.wheel_radius < 0 or (self.kind == "wheel_flat" and self.wheel_radius == 0):
                    raise config_error(f"{p}.wheel_radius", self.wheel_radius, "must be > 0" if self.kind == "wheel_flat" else "must be >= 0")
                from . import gateway  # the wheels' plausible range is the core's

                top = next(hi for f, _, hi, *_ in gateway.plausible_ranges() if f == "vehicles[*].wheel_radius")
                if self.wheel_radius > top:
                    raise config_error(f"{p}.wheel_radius", self.wheel_radius, f"beyond the plausible wheel radius of {top:g} m "
                                                                              "(vehicles[*].wheel_radius, docs/limits.md)")
            if self.kind == "rail_joint":
                finite("step", self.step)
            elif self.kind == "dipped_weld":
                finite("crown", self.crown)
                finite("crown_length", self.crown_length, True)
                if self.crown < 0:
                    raise config_error(f"{p}.crown", self.crown, "must be >= 0 (the crown's height above the dip)")
                if self.crown_length > self.length:
                    raise config_error(f"{p}.crown_length", self.crown_length, f"must not exceed the dip's length {self.length}")
            else:
                if not isinstance(self.wheel, (int, np.integer)) or isinstance(self.wheel, bool) or self.wheel < 0:
                    raise config_error(f"{p}.wheel", self.wheel, "must be a non-negative integer")
                if wheel_radii is not None and self.wheel >= len(wheel_radii):
                    raise config_error(f"{p}.wheel", self.wheel, f"the run has {len(wheel_radii)} wheels (0 to {len(wheel_radii) - 1})")
                if self.flat_shape not in FLAT_SHAPES:
                    raise config_error(f"{p}.flat_shape", self.flat_shape, f"must be one of {', '.join(FLAT_SHAPES)}")
                if self.flat_shape == "new" and self.depth != 0:
                    raise config_error(f"{p}.depth", self.depth, "a new flat's depth follows from its length, R − √(R² − L²/4): leave depth at 0")
                radius = self.wheel_radius if self.wheel_radius is not None else (wheel_radii[self.wheel] if wheel_radii else None)
                if isinstance(radius, (int, float)) and radius > 0:  # a bad radius is refused where it is set
                    self._check_flat_length(radius, p)
        elif self.kind == "sampled":
            finite("x0", self.x0)
            if self.dx is None:
                raise config_error(f"{p}.dx", None, "a sampled profile needs its spacing dx")
            v = np.asarray(self.values, dtype=float)
            if v.ndim != 1 or v.size < 2:
                raise config_error(f"{p}.values", f"array of shape {v.shape}", "needs a 1-D array of at least 2 samples")
            bad = np.flatnonzero(~np.isfinite(v))
            if bad.size:
                raise config_error(f"{p}.values[{bad[0]}]", float(v[bad[0]]), "must be finite")

        if extent is not None:
            self._check_within(extent, p)

    def _check_within(self, extent: tuple, p: str) -> None:
        """The shape's stretch meets ``extent`` (see :meth:`validate`)."""
        if self.kind == "cosine_dip":
            name, lo, hi = "position", self.position, self.position + self.length
        elif self.kind in ("rail_joint", "dipped_weld"):
            name, lo, hi = "position", self.position - self.length / 2, self.position + self.length / 2
        elif self.kind == "corrugation":
            name, lo, hi = "start", self.start, self.end
        elif self.kind == "sampled":
            name, lo, hi = "x0", self.x0, self.x0 + (len(self.values) - 1) * float(self.dx)
        else:
            return
        a, b = extent
        if hi < a or lo > b:
            raise config_error(f"{p}.{name}", getattr(self, name),
                               f"the {self.kind.replace('_', ' ')} over [{lo:g}, {hi:g}] m lies outside the rail the wheels roll over, "
                               f"[{a:g}, {b:g}] m (the structure and the wheels' travel): the run would return the smooth rail's answer")

    def sample_spacing(self) -> float:
        if self.dx is not None:
            return float(self.dx)
        if self.kind in SPECTRA:
            return self.wavelength_min / 10.0
        if self.kind == "corrugation":
            return self.wavelength / 20.0
        if self.kind == "cosine_dip":
            return self.length / 50.0
        if self.kind in DEFECTS:
            return DEFECT_DX
        return 1.0

    def profile(self, x_min: float, x_max: float, memory_budget: Optional[float] = None, wheel_radius: Optional[float] = None) -> tuple[float, float, np.ndarray]:
        """Samples the rail's r(x) (m) on [x_min, x_max]: returns (x0, dx, values); the rail
        defects are seen through a wheel of radius ``wheel_radius`` (m; ``None`` or 0: their
        raw geometry, unless a part names its own). Wheel flats are not the rail's and are left
        out; see :meth:`sample` for the parts and the wheels' treads."""
        rail = replace(self, kind="none" if self.kind == "wheel_flat" else self.kind, parts=[q for q in self.parts if q.kind != "wheel_flat"])
        x0, dx, values, _ = rail.sample(x_min, x_max, memory_budget, [wheel_radius or 0.0])
        return x0, dx, values

    def sample(self, x_min: float, x_max: float, memory_budget: Optional[float] = None, wheel_radii: Sequence[float] = (),
               shortest: Optional[dict] = None) -> tuple[float, float, np.ndarray, list]:
        """Samples what the wheels roll on over [x_min, x_max]: returns (x0, dx, rail, treads),
        the rail's r(x) (m) and, when a part is a wheel flat, one tread row per wheel (m, an
        empty array for a round wheel; ``wheel_radii`` gives each wheel's radius, the first
        also the radius the rail defects are seen through). The parts are superposed on the
        finest part's grid, each realised on its own grid and interpolated linearly (so a
        random part's realisation is fixed by its own seed and spacing). A sample count whose
        arrays would exceed ``memory_budget`` bytes (default: the core's
        ``solver.memory_budget``) raises :class:`~vtb.errors.ConfigError`; an inverse-FFT
        spectrum whose band the sampled length cannot realise (λ_max beyond it) warns with
        the realised fraction of the band's variance (:class:`IrregularityWarning`).

        ``shortest`` maps a stationary part's path (``"irregularity"``,
        ``"irregularity.parts[i]"``) to the shortest wavelength (m) it keeps: a spectrum's
        realisation without its components at shorter wavelengths (the same draws, so the rest
        is unchanged), a corrugation of a shorter wavelength left out (what a run does with a
        part beyond the band its model resolves, :func:`vtb.config.resolution.check_excitation`)."""
        named = [("irregularity", self)] + [(f"irregularity.parts[{i}]", q) for i, q in enumerate(self.parts)]
        named = [(path, q) for path, q in named if q.kind != "none"]
        rail = [(path, q) for path, q in named if q.kind != "wheel_flat"]
        flats = [(path, q) for path, q in named if q.kind == "wheel_flat"]
        radius = float(wheel_radii[0]) if len(wheel_radii) else 0.0
        keep = shortest or {}
        if not named:
            return 0.0, 1.0, np.zeros(0), []
        if len(rail) == 1 and not flats:
            path, q = rail[0]
            x0, dx, values = q._own(x_min, x_max, memory_budget, radius, keep.get(path))
            return x0, dx, values, []
        dx = min(q.sample_spacing() for _, q in named)
        n = _grid_size(x_min, x_max, dx, memory_budget, f"irregularity.dx")
        x = x_min + dx * np.arange(n)
        values = np.zeros(n)
        for path, q in rail:
            x0q, dxq, v = q._own(x_min, x_max, memory_budget, radius, keep.get(path))
            values += np.interp(x, x0q + dxq * np.arange(v.size), v)
        treads = [np.zeros(0) for _ in wheel_radii] if flats else []
        for path, q in flats:
            r = q.wheel_radius if q.wheel_radius is not None else float(wheel_radii[q.wheel])
            q._check_flat_length(r, path)
            row = treads[q.wheel] if treads[q.wheel].size else np.zeros(n)
            treads[q.wheel] = row + q._flat(x, r) * q.scale
        return float(x_min), float(dx), values, treads

    def _own(self, x_min: float, x_max: float, memory_budget: Optional[float], radius: float,
             shortest: Optional[float] = None) -> tuple[float, float, np.ndarray]:
        """This irregularity's rail profile alone (without its parts) on its own grid; a
        stationary part without its wavelengths below ``shortest`` (m, :meth:`sample`)."""
        if self.kind == "sampled":
            return float(self.x0), float(self.dx), np.asarray(self.values, dtype=float) * self.scale
        dx = self.sample_spacing()
        n = _grid_size(x_min, x_max, dx, memory_budget, "irregularity.dx")
        x = x_min + dx * np.arange(n)
        if self.kind in SPECTRA:
            s = psd(self.kind, sato_a=self.sato_a)
            rng = np.random.default_rng(self.seed)
            f_min, f_max = 1.0 / self.wavelength_max, 1.0 / self.wavelength_min
            f_keep = f_max if shortest is None else min(f_max, 1.0 / shortest)
            if self.method == "ifft":
                self._check_realised_band(s, n, dx)
                r = generate_ifft(s, n, dx, f_min, f_max, rng, f_keep)
            else:
                r = generate_spectral(s, x - x_min, f_min, f_max, self.n_freq, rng, f_keep)
        elif self.kind == "cosine_dip":
            u = (x - self.position) / self.length
            r = np.where((u >= 0) & (u <= 1), 0.5 * self.depth * (1.0 - np.cos(2.0 * math.pi * u)), 0.0)
        elif self.kind == "corrugation":
            inside = (x >= self.start) & (x <= self.end) & (shortest is None or self.wavelength >= shortest)
            r = np.where(inside, 0.5 * self.amplitude * (1.0 - np.cos(2.0 * math.pi * (x - self.start) / self.wavelength)), 0.0)
        else:
            r = self._rail_defect(x, self.wheel_radius if self.wheel_radius is not None else radius)
        return float(x_min), float(dx), r * self.scale

    def _rail_defect(self, x: np.ndarray, radius: float) -> np.ndarray:
        """A rail joint or dipped weld on the grid x, seen through a wheel of ``radius`` (m):
        the raw geometry over its stretch plus the wheel's reach, then the wheel centre's path."""
        half = 0.5 * self.length
        if self.kind == "rail_joint":
            raw = lambda u: np.where(u >= 0.0, self.step, 0.0) + self.depth * np.clip(1.0 - np.abs(u) / half, 0.0, None)
            height = self.depth + abs(self.step)
        else:
            def raw(u):
                dip = np.where(np.abs(u) <= half, 0.5 * self.depth * (1.0 + np.cos(math.pi * u / half)), 0.0)
                c = 0.5 * self.crown_length
                crown = np.where(np.abs(u) <= c, 0.5 * self.crown * (1.0 + np.cos(math.pi * u / c)), 0.0)
                return dip - crown
            height = self.depth + self.crown
        reach = math.sqrt(max(2.0 * radius * height, 0.0)) if radius > 0 else 0.0
        u = x - self.position
        r = raw(u)
        near = np.flatnonzero(np.abs(u) <= half + 2.0 * reach + 2.0 * (x[1] - x[0] if x.size > 1 else 0.0))
        if radius > 0 and near.size > 2:
            r[near] = wheel_centre_path(r[near], float(x[1] - x[0]), radius)
        return r

    def _check_flat_length(self, radius: float, path: str) -> None:
        """A rounded flat shorter than half the circumference, a new flat's chord than the
        diameter."""
        limit, what = (math.pi * radius, "half the circumference π·R") if self.flat_shape == "rounded" else (2.0 * radius, "the diameter 2R")
        if self.length >= limit:
            raise config_error(f"{path}.length", self.length, f"must be shorter than {what} = {limit:.4g} m (R = {radius:g} m)")

    def _flat_dent(self, s: np.ndarray, radius: float) -> np.ndarray:
        """The flat's dent in the tread (m, inward) at arc length s (m) from its centre."""
        if self.flat_shape == "new":
            # The chord's radial gap to the circle: R − R·cos θ0 / cos(s/R), θ0 = asin(L/2R).
            t0 = math.asin(0.5 * self.length / radius)
            t = np.clip(s / radius, -t0, t0)
            return np.where(np.abs(s) <= radius * t0, radius - radius * math.cos(t0) / np.cos(t), 0.0)
        depth = self.depth if self.depth > 0 else self.length**2 / (16.0 * radius)
        return np.where(np.abs(s) <= 0.5 * self.length, 0.5 * depth * (1.0 + np.cos(2.0 * math.pi * s / self.length)), 0.0)

    def _flat(self, x: np.ndarray, radius: float) -> np.ndarray:
        """The wheel flat at ``position`` and every circumference 2πR from it, as the
        irregularity under its wheel at x (m): the path of the wheel's centre as the dented
        tread rolls on a flat rail, i.e. :func:`wheel_centre_path` of the dent (for small
        slopes a dent in the wheel and the same dent in the rail under a round wheel give the
        same path). The path is built once on a grid four times finer than x's and placed at
        every revolution, so a new flat's kink stays sharp to x's spacing."""
        h = 0.25 * (float(x[1] - x[0]) if x.size > 1 else DEFECT_DX)
        half = radius * math.asin(min(1.0, 0.5 * self.length / radius)) + 4.0 * h
        s = h * np.arange(-math.ceil(half / h), math.ceil(half / h) + 1)
        path = wheel_centre_path(self._flat_dent(s, radius), h, radius)
        u = np.mod(x - self.position + s[-1], 2.0 * math.pi * radius) - s[-1]
        return np.interp(u, s, path, left=0.0, right=0.0)

    def _check_realised_band(self, s, n: int, dx: float) -> None:
        """Warns when the inverse FFT's frequency grid (spacing 1/(n·dx)) realises the band's
        variance to worse than :data:`REALISED_TOLERANCE` (a band longer than the profile)."""
        df = 1.0 / (n * dx)
        k = np.arange(1, (n + 1) // 2)
        f = k * df
        band = (f >= 1.0 / self.wavelength_max) & (f <= 1.0 / self.wavelength_min)
        realised = float(np.sum(s(f[band])) * df)
        target = band_variance(self.kind, self.wavelength_min, self.wavelength_max, sato_a=self.sato_a)
        fraction = realised / target if target > 0 else 1.0
        if abs(fraction - 1.0) > REALISED_TOLERANCE:
            import warnings

            warnings.warn(
                f"irregularity: the {n * dx:g} m profile realises {fraction:.1%} of the variance of the band "
                f"[{self.wavelength_min:g}, {self.wavelength_max:g}] m (its frequency spacing is 1/{n * dx:g} 1/m); "
                "shorten wavelength_max or lengthen the structure",
                IrregularityWarning, stacklevel=3,
            )

    def target_variance(self) -> float:
        """Variance (m²) the spectrum assigns to the band, including ``scale``."""
        if self.kind not in SPECTRA:
            raise config_error("irregularity.kind", self.kind, "only spectra have a target variance")
        return self.scale**2 * band_variance(self.kind, self.wavelength_min, self.wavelength_max, sato_a=self.sato_a)
