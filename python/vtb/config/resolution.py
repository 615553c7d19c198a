"""The frequency band a configuration's discretisation resolves (docs/resolution.md).

Each layer is resolved up to the lower of two limits, computed by the core from the
configuration: its **basis** (the free bending wave of the shortest wavelength the layer's
sines or finite elements hold to 1 % in frequency) and its **time step** (Newmark's
average-acceleration rule is 1 % low at 2πfΔt = 0.3496). :func:`resolved_band` reports them;
the functions that answer at given frequencies (:func:`vtb.receptance`, :func:`vtb.decay_rate`,
:meth:`vtb.Result.third_octave`) and a band-limited index (``output.band_limit``) issue a
:class:`ResolutionWarning` when asked beyond the band of the layer concerned.
"""

from __future__ import annotations

import json
import math
import warnings
from dataclasses import dataclass
from typing import NamedTuple, Optional

import numpy as np

from . import gateway
from .gateway import SUBSTRUCTURE_BAND_SHARE, SYNTHESIS_BAND_SHARE
from .fields import Config, structure_json
from .irregularity import SPECTRA, band_variance
from ..errors import config_error


def real_or_none(v) -> Optional[float]:
    """``v`` as a float when it is a finite real number (not a bool), else ``None``."""
    if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)):
        return None
    v = float(v)
    return v if np.isfinite(v) else None


class ResolutionWarning(UserWarning):
    """A quantity was asked at frequencies the configuration's discretisation does not resolve
    (:func:`vtb.resolved_band`): the answer there is an artefact of the discretisation."""


@dataclass(frozen=True)
class LayerBand:
    """The band one layer resolves.

    ``f_max`` (Hz): the upper end, the lower of ``basis_f_max`` (Hz; the spatial basis) and
    ``time_f_max`` (Hz; the time step); ``shortest_wavelength`` (m): the shortest bending
    wavelength the basis holds to 1 %."""

    layer: str
    f_max: float
    basis_f_max: float
    time_f_max: float
    shortest_wavelength: float

    @property
    def limited_by(self) -> str:
        """``"basis"`` or ``"time step"``: which limit sets ``f_max``."""
        return "basis" if self.basis_f_max <= self.time_f_max else "time step"


@dataclass(frozen=True)
class ResolvedBand:
    """The band of every layer (``layers``, by name, top layer first) and whether the rail (the
    top layer) holds its first pinned–pinned mode: its basis holds the wavelength of twice the
    fastener bay and its band reaches the pinned–pinned frequency ``pinned_pinned`` (Hz;
    ``None`` without discrete fasteners on the top layer)."""

    layers: dict
    pinned_pinned: Optional[float]

    @property
    def rail(self) -> LayerBand:
        return next(iter(self.layers.values()))

    @property
    def holds_pinned_pinned(self) -> bool:
        if self.pinned_pinned is None:
            return False
        return self.rail.basis_f_max >= self.pinned_pinned and self.rail.f_max >= self.pinned_pinned

    def __str__(self) -> str:
        rows = [f"{b.layer}: resolved to {b.f_max:.0f} Hz ({b.limited_by}; basis {b.basis_f_max:.0f} Hz, "
                f"shortest wavelength {b.shortest_wavelength:.3g} m; time step {b.time_f_max:.0f} Hz)" for b in self.layers.values()]
        if self.pinned_pinned is not None:
            rows.append(f"pinned–pinned mode at {self.pinned_pinned:.0f} Hz: {'held' if self.holds_pinned_pinned else 'not held'}")
        return "\n".join(rows)


def _core_bands(config: Config, text: Optional[str] = None) -> tuple[list, Optional[float]]:
    """The core's bands and pinned–pinned frequency of ``config`` (its core JSON ``text`` when
    made): its structure and time step, as a structure-only configuration (what the
    frequency-domain tools assemble) with the run's Δt."""
    plain = json.loads(structure_json(config, text))
    dt = real_or_none(getattr(config.solver, "dt", None))
    if dt is not None and dt > 0:
        plain["solver"]["dt"] = plain["solver"]["t_end"] = dt
    return gateway.resolved_bands(json.dumps(plain))


def resolved_band(config: Config, text: Optional[str] = None) -> ResolvedBand:
    """The band each layer of ``config`` resolves (module docstring); ``text``: its core JSON
    when the caller has made it. Raises :class:`vtb.ConfigError` for an invalid structure."""
    bands, f_pp = _core_bands(config, text)
    return ResolvedBand({d["layer"]: LayerBand(**d) for d in bands}, f_pp)


def pinned_pinned_frequency(config: Config) -> float:
    """The rail's first pinned–pinned frequency (Hz): the top layer between two of its
    fasteners (the first discrete coupling under it), a simply supported span d with
    wavenumber k = π/d. Euler–Bernoulli: ω² = EI·k⁴/ρA; a Timoshenko rail (shear modulus set)
    gives the lower root of (κGAk² − ρAω²)(EIk² + κGA − ρIω²) = (κGAk)², the beam with shear
    and rotary inertia. Raises :class:`vtb.ConfigError` naming ``structure.couplings`` when the
    rail has no discrete supports."""
    f_pp = _core_bands(config)[1]
    if f_pp is None:
        raise config_error("structure.couplings", "[…]", "the top layer has no discrete coupling (fasteners) with two or more points")
    return f_pp


def warn_beyond(config: Config, layer: str, f_top: float, what: str, stepped: bool = True, band: Optional[ResolvedBand] = None) -> None:
    """A :class:`ResolutionWarning` if ``f_top`` (Hz) lies above the band ``layer`` resolves: its
    ``f_max`` for a time-stepped run (``stepped``), else its basis alone (a frequency-domain
    answer has no time step). ``band``: ``config``'s :func:`resolved_band` when known."""
    band = (band or resolved_band(config)).layers.get(layer)
    if band is None:
        return
    limit, by = (band.f_max, band.limited_by) if stepped else (band.basis_f_max, "basis")
    if f_top > limit:
        warnings.warn(
            f"{what} reaches {f_top:.0f} Hz, beyond the {limit:.0f} Hz that this discretisation "
            f"resolves for the {layer} (limited by its {by}; vtb.resolved_band(config))",
            ResolutionWarning,
            stacklevel=3,
        )


#: The r.m.s. (m) of a stationary irregularity part's roughness at wavelengths the model does not
#: resolve for the rail above which a run warns (:func:`check_excitation`): 4 % of the Hertz
#: compression of a 70 kN wheel (76 μm), where the contact force's fluctuation from the
#: unresolved part reaches about 6 % of the static load and its peaks can lift the wheel.
OUT_OF_BAND_RMS = 3e-6


class OutOfBand(NamedTuple):
    """A stationary irregularity part that excites the rail beyond the band the model resolves
    (:func:`out_of_band`): its path and field, its shortest wavelength and excitation v/λ_min
    (m, Hz), the shortest wavelength the band takes, v/f_max (m), and the r.m.s. of its
    roughness below it (m)."""

    path: str
    field: str
    wavelength_min: float
    excitation: float
    shortest: float
    rms: float
    #: ``beyond_band = "keep"``: the part is run whole.
    keep: bool = False


def out_of_band(config: Config, band: Optional[ResolvedBand] = None) -> list:
    """Every stationary irregularity part (a spectrum or a corrugation; the irregularity itself
    when it has no parts) whose excitation v/λ_min reaches beyond the rail's ``f_max`` and whose
    roughness at wavelengths shorter than v/f_max has an r.m.s. above :data:`OUT_OF_BAND_RMS`
    (docs/resolution.md, "The irregularity against the grade"), as :class:`OutOfBand`."""
    v = real_or_none(getattr(config, "speed", None))
    irr = getattr(config, "irregularity", None)
    if v is None or v <= 0 or irr is None:
        return []
    band = band or resolved_band(config)
    cut = v / band.rail.f_max  # the shortest wavelength the rail's band takes at this speed (m)
    parts = [(f"irregularity.parts[{i}]", q) for i, q in enumerate(irr.parts)] or [("irregularity", irr)]
    found = []
    for path, q in parts:
        if q.kind in SPECTRA:
            lam_min, lam_max = float(q.wavelength_min), float(q.wavelength_max)
            field = f"{path}.wavelength_min"
            if lam_min >= cut:
                continue
            rms = abs(q.scale) * math.sqrt(band_variance(q.kind, lam_min, min(lam_max, cut), sato_a=q.sato_a))
        elif q.kind == "corrugation":
            lam_min, field = float(q.wavelength), f"{path}.wavelength"
            if lam_min >= cut:
                continue
            rms = abs(q.scale * q.amplitude) / math.sqrt(2.0)
        else:
            continue
        if rms > OUT_OF_BAND_RMS:
            found.append(OutOfBand(path, field, lam_min, v / lam_min, cut, rms, getattr(q, "beyond_band", "filter") == "keep"))
    return found


def check_excitation(config: Config, band: Optional[ResolvedBand] = None) -> dict:
    """Each part :func:`out_of_band` finds gives a :class:`ResolutionWarning` naming the part,
    its band and what would take it (the grade — synthesis or substructure cut-off and time
    step, or time step — that resolves v/λ_min, or the wavelength_min this grade takes), and is
    run filtered to the grade: without its wavelengths below v/f_max (a spectrum's shorter
    components left out of the same draw, a corrugation left out), so that no contact force or
    loss of contact comes from excitation the model cannot carry. Returns what the run keeps of
    each such part: its path → the shortest wavelength (m), as
    :meth:`vtb.Irregularity.sample` takes it. A part with ``beyond_band = "keep"`` (the
    article's presets) warns and is run whole."""
    band = band or resolved_band(config)
    rail = band.rail
    f_rail = rail.f_max
    keep = {}
    for part in out_of_band(config, band):
        if not part.keep:
            keep[part.path] = part.shortest
        f_exc = part.excitation
        dt = real_or_none(getattr(config.solver, "dt", None))
        dt_need = dt * rail.time_f_max / f_exc if dt else None
        if config.discretisation.synthesis_cutoff is not None:
            grade = f"discretisation.synthesis_cutoff ≥ {f_exc / SYNTHESIS_BAND_SHARE:.0f} Hz"
        elif getattr(config.discretisation, "substructure_cutoff", None) is not None:
            grade = f"discretisation.substructure_cutoff ≥ {f_exc / SUBSTRUCTURE_BAND_SHARE:.0f} Hz"
        else:
            grade = "a rail basis that resolves it"
        step = f" with solver.dt ≤ {dt_need:.2g} s" if dt_need is not None and f_exc > rail.time_f_max else ""
        left = (f"the run leaves those wavelengths out of {part.path} (contact forces and losses of contact from them "
                f"would be artefacts of the model)")
        kept = (f"the run keeps them ({part.path}.beyond_band = \"keep\"): contact forces and losses of contact from them "
                f"are artefacts of the model")
        warnings.warn(
            f"{part.field} = {part.wavelength_min:g} m excites the rail up to v/λ = {f_exc:.0f} Hz, beyond the {f_rail:.0f} Hz "
            f"this model resolves for the rail (limited by its {rail.limited_by}; vtb.resolved_band(config)); its roughness "
            f"at wavelengths below v/{f_rail:.0f} Hz = {part.shortest:.3g} m has an r.m.s. of {part.rms * 1e6:.3g} μm (above "
            f"{OUT_OF_BAND_RMS * 1e6:g} μm): {kept if part.keep else left}. Take it on a grade that resolves {f_exc:.0f} Hz "
            f"({grade}{step}), or set {part.field} to {part.shortest:.3g} m on this one",
            ResolutionWarning,
            stacklevel=5,
        )
    return keep


