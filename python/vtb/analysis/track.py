"""Frequency-domain track tools: receptances, the track decay rate and natural modes.

These functions work on the *structure* of a configuration alone — its layers, couplings,
discretisation and tuned inerter dampers. The vehicles, moving forces, speed, solver settings,
observation points and irregularity are ignored (except that a hybrid configuration's default
FE–SEA frequency ω_r is still resolved from the irregularity and speed, exactly as for a run).

Equations and units
-------------------
The assembled structure obeys M ü + C u̇ + K u = f (SI units: M in kg, C in N·s/m, K in N/m
in generalised coordinates). Under a harmonic force f·e^{iωt} (ω = 2πf_Hz rad/s) the
steady-state amplitude solves the complex sparse system

    (K + iωC − ω²M) u = f,

so a receptance (m/N) is the displacement amplitude per unit force amplitude. Displacements
and forces are **positive downward** (the package convention), so the static point
receptance of a restrained structure is positive real, and a response that lags the force
has a negative imaginary part.

DOF numbering
-------------
The structure's DOF vector stacks the layers' DOFs from the top layer to the bottom one; layer
j's DOFs are ``offset_j .. offset_j + n_j − 1`` (``vtb._core.matrices(...)["layer_offsets"]``
lists (name, offset, n) for every layer). After the last layer come the internal nodes of the
tuned inerter dampers, one displacement DOF (m, positive downward) per damper, in the order
of their positions. They are part of M, K and C and are kept in every solve.

* A finite-element layer (method ``"fem"``) numbers its nodes from x = 0 to x = L; node i
  has DOF 2i, the displacement w (m, positive downward), and DOF 2i + 1, the rotation (rad):
  dw/dx of that downward displacement for an Euler–Bernoulli layer, the cross-section's
  rotation for a Timoshenko layer. The node positions are those of the core's mesh (which
  may be nonuniform, e.g. with nodes on the coupling points); nothing here assumes a uniform
  spacing.
* A modal or hybrid layer has 4 cubic (Hermite-type) DOFs first — the amplitudes of the
  boundary functions 1 − x/L and x/L (the end displacements) and of the two cubic bending
  functions (docs/model-choices.md) — followed by the amplitudes of its N mass-normalised
  sines √(2/ρAL)·sin(nπx/L), n = 1..N. A hybrid top layer has the same DOFs (its local
  modes are condensed into the correction, not DOFs), and its shape vectors carry the
  FE–SEA correction exactly as the wheels see it.

Every point quantity goes through the core's shape vectors (``vtb._core.shapes``): the force
vector of a unit point force on layer j at x is the shape vector s_j(x), and the displacement
of layer j at x is s_j(x)·u. Nothing else in this module depends on the numbering above.

Limitations
-----------
* The model is that of the time-domain runs, linear and at rest: no vehicle, no contact, no
  preload; Rayleigh and coupling damping are viscous, so loss factors grow with frequency.
* A modal layer resolves wavelengths down to about 2L/N only; above that its receptances are
  meaningless. A hybrid configuration's FE–SEA correction is evaluated at its single ω_r,
  so its matrices are exact only near ω_r. Prefer ``method = "fem"`` for broadband work.
* A finite structure has end reflections; an "infinite track" result needs a structure long
  and damped enough that waves have decayed before they return (see docs/track.md).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from typing import Optional, Union

import numpy as np
import scipy.linalg
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..config.fields import Config
from ..config.resolution import resolved_band, warn_beyond
from ..errors import SolverError, VtbError, config_error
from . import substructures
from .eigen import EigshFailed, System, _float_array, assemble, checked_frequencies, checked_positions, fix_signs, layer_index, shape_matrix, sliced_eigsh
from .substructures import Substructuring

__all__ = ["receptance", "decay_rate", "modes", "Modes", "DEFAULT_DECAY_POSITIONS", "DENSE_EIGEN_LIMIT", "SUBSTRUCTURE_FROM"]

#: 10·log10(e) ≈ 4.343 dB: the numerator of the decay-rate estimator.
DB_PER_NEPER_ENERGY = 10.0 * math.log10(math.e)

#: Default decay-rate positions when the layer sits on discrete supports: distances from the
#: excitation point x0 in units of the support (fastener) spacing a. Dense (every a/2) near the
#: excitation, where the near field and the pinned–pinned structure matter, then widening.
#: This grid is vtb's choice, modelled on a standard measurement grid; it is not claimed to be
#: EN 15461's table.
DEFAULT_DECAY_POSITIONS = (0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0, 5.0, 6.0, 7.0, 8.0, 10.0, 12.0, 14.0, 16.0, 20.0, 24.0, 28.0, 32.0, 40.0, 48.0, 56.0, 66.0)

#: Default decay-rate positions on a layer without discrete supports: 0, then this many
#: geometrically spaced distances from d_max·1e−3 to d_max, where d_max is the room from x0
#: to the end of the structure in the chosen direction.
DEFAULT_GEOMETRIC_POINTS = 40

#: :func:`modes` may fall back to a dense generalised eigensolver only up to this many DOFs.
DENSE_EIGEN_LIMIT = 2000




#: A dynamic stiffness whose estimated 1-norm condition number exceeds this (≈ 1/(45·ε)) is
#: singular to working precision. Assembled track structures stay below ~1e14 (a modal
#: 160 m bridge on 1e15 N/m piers: 2e13); an unrestrained beam's K comes out near 1e18.
SINGULAR_CONDITION = 1e16


def _condition_1(a: sp.csc_matrix, lu) -> float:
    """‖A‖₁·‖A⁻¹‖₁ with ‖A⁻¹‖₁ from Hager's estimator (Higham's complex form; a few
    triangular solves with the existing factors, deterministic)."""
    n = a.shape[0]
    norm_a = float(abs(a).sum(axis=0).max())
    x = np.full(n, 1.0 / n, dtype=complex)
    est = 0.0
    for it in range(6):
        y = lu.solve(x)
        new = float(np.abs(y).sum())
        if not math.isfinite(new):
            return math.inf
        if it > 0 and new <= est:
            break
        est = new
        mag = np.abs(y)
        xi = np.where(mag > 0, y / np.where(mag > 0, mag, 1.0), 1.0)
        z = lu.solve(xi, trans="H")
        j = int(np.argmax(np.abs(z)))
        if it > 0 and abs(z[j]) <= np.real(np.vdot(z, x)):
            break
        x = np.zeros(n, dtype=complex)
        x[j] = 1.0
    return norm_a * est


def _harmonic_solve(system: System, freqs: np.ndarray, force: sp.csc_matrix, response: sp.csc_matrix, field_name: str = "frequencies") -> np.ndarray:
    """Rᵀ (K + iωC − ω²M)⁻¹ F for every frequency: shape (n_freq, n_response, n_force)."""
    k = system.k.astype(complex)
    c = system.c.astype(complex)
    m = system.m.astype(complex)
    f_dense = force.toarray().astype(complex)  # n × q force vectors (q small), never n × n
    rt = response.T.tocsr()
    out = np.empty((freqs.size, response.shape[1], force.shape[1]), dtype=complex)
    undamped = not np.any(system.c.data)
    for i, f in enumerate(freqs):
        w = 2.0 * math.pi * float(f)
        a = (k + (1j * w) * c - (w * w) * m).tocsc()
        reason = (
            "K is singular: the structure is not restrained against a rigid-body motion, so the "
            "static receptance is infinite"
            if w == 0.0
            else "the dynamic stiffness K + iωC − ω²M is singular here (an undamped natural frequency)"
        )
        try:
            lu = spla.splu(a)
            u = lu.solve(f_dense)
            # A damped dynamic stiffness is regular at ω > 0; check the static and undamped cases.
            singular = (w == 0.0 or undamped) and _condition_1(a, lu) > SINGULAR_CONDITION
        except RuntimeError:
            singular = True
        r = rt @ u if not singular else None
        if singular or not np.all(np.isfinite(r)):
            raise config_error(f"{field_name}[{i}]", float(f), reason) from None
        out[i] = r
    return out


# ---------------------------------------------------------------------------- receptance
def receptance(
    config: Config,
    x: float,
    frequencies,
    layer: Union[str, int] = "rail",
    response_x=None,
    response_layer: Union[str, int, None] = None,
) -> np.ndarray:
    """Point or transfer receptance of the structure (m/N).

    The displacement amplitude of ``response_layer`` at ``response_x`` per unit amplitude of a
    harmonic point force F·e^{iωt} applied downward on ``layer`` at ``x``: α = sᵣᵀ (K + iωC −
    ω²M)⁻¹ s_f, with s_f, sᵣ the shape vectors of the two points and ω = 2π·f. Displacements
    and forces are positive downward, so a restrained structure's static point receptance is
    positive real. The matrices are assembled once; each frequency is one sparse LU
    factorisation (SuperLU) solved for the force, and all response points are read from that
    one solution.

    Parameters
    ----------
    config : vtb.Config
        The configuration; only its structure, discretisation and dampers are used.
    x : float
        Position of the force along the structure (m), 0 ≤ x ≤ L.
    frequencies : float or array_like
        Frequencies f (Hz), each finite and ≥ 0. 0 Hz gives the static receptance (it needs a
        restrained structure, i.e. a nonsingular K).
    layer : str or int, default "rail"
        The loaded layer: a layer name or index (0 = top layer).
    response_x : float or array_like, optional
        Response position(s) (m). Default: ``x`` (a point receptance).
    response_layer : str or int, optional
        The layer whose displacement is returned. Default: ``layer``.

    Returns
    -------
    numpy.ndarray of complex
        Receptance in m/N: shape (n_freq,) for a scalar ``response_x`` (or none), else
        (n_freq, n_points). A scalar ``frequencies`` counts as n_freq = 1.

    Raises
    ------
    vtb.ConfigError
        Invalid configuration, unknown layer, a position off [0, L], a negative, NaN or
        infinite frequency, no frequencies, or a frequency at which the dynamic stiffness is
        singular (0 Hz on an unrestrained structure, an undamped natural frequency).

    Examples
    --------
    >>> cfg = vtb.paper_config(); cfg.discretisation.method = "fem"
    >>> a = vtb.receptance(cfg, 80.32, [100.0, 1000.0])           # point receptance of the rail
    >>> t = vtb.receptance(cfg, 80.32, 1000.0, response_x=[81.0, 82.0])   # shape (1, 2)
    """
    system = assemble(config)
    li = layer_index(system, layer, "layer")
    ri = li if response_layer is None else layer_index(system, response_layer, "response_layer")
    xf, _ = checked_positions(x, system.length, "x")
    if xf.size != 1:
        raise config_error("x", x, "must be a single position (m); use response_x for several responses")
    freqs = checked_frequencies(frequencies)
    if response_x is None:
        xr, scalar = xf, True
    else:
        xr, scalar = checked_positions(response_x, system.length, "response_x")
    warn_beyond(config, config.structure.layers[ri].name, float(freqs.max()), "the receptance", stepped=False)
    force = shape_matrix(system, li, xf)
    resp = shape_matrix(system, ri, xr)
    out = _harmonic_solve(system, freqs, force, resp)[:, :, 0]
    return Spectrum.of(out[:, 0] if scalar else out, config, config.structure.layers[ri].name)


class Spectrum(np.ndarray):
    """A frequency-domain answer (:func:`receptance`, :func:`decay_rate`): a numpy array that
    also carries ``resolved`` (Hz), the top of the band its model's basis resolves for the
    layer (``None`` when unknown), so that the figures shade the unresolved band by default."""

    resolved = None

    @classmethod
    def of(cls, values, config, layer: str) -> "Spectrum":
        out = np.asarray(values).view(cls)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                band = resolved_band(config).layers.get(layer)
            out.resolved = None if band is None else float(band.basis_f_max)
        except (VtbError, ValueError, TypeError):
            out.resolved = None
        return out

    def __array_finalize__(self, obj) -> None:
        self.resolved = getattr(obj, "resolved", None)


# ---------------------------------------------------------------------------- decay rate
def _support_spacing(config: Config, layer_name: str) -> Optional[float]:
    """The spacing (m) of the first discrete coupling hanging ``layer_name`` on supports."""
    for cp in config.structure.couplings:
        if cp.upper == layer_name and cp.kind == "discrete" and len(cp.positions) >= 2:
            pos = np.unique(np.asarray(cp.positions, dtype=float))
            if pos.size >= 2:
                return float(np.median(np.diff(pos)))
    return None


def _estimator_weights(d: np.ndarray) -> np.ndarray:
    """Δx_n: half the distance between each position's neighbours (the trapezoid weights;
    the first and last positions get half their one interval)."""
    w = np.empty_like(d)
    w[0] = 0.5 * (d[1] - d[0])
    w[-1] = 0.5 * (d[-1] - d[-2])
    w[1:-1] = 0.5 * (d[2:] - d[:-2])
    return w


def decay_rate(
    config: Config,
    frequencies,
    x0: Optional[float] = None,
    layer: Union[str, int] = "rail",
    positions=None,
    direction: Optional[int] = None,
) -> np.ndarray:
    """Track decay rate (dB/m) of a layer with the EN 15461 estimator.

    The estimator of EN 15461 (track decay rates from point and transfer functions) is::

        DR = 10·log10(e) / Σ_{n=0}^{N} (|A(x_n)|² / |A(x_0)|²)·Δx_n      (dB/m),

    where A(x_n) is the transfer function (here the receptance; the ratio is the same for
    mobility or accelerance) from a force at x_0 to the response at x_n, the positions x_n run
    from x_0 = the excitation point outward on one side, and Δx_n is the length of track each
    position represents: half the distance between its neighbours, (x_{n+1} − x_{n−1})/2,
    and half of the single interval at the two ends. For one wave e^{−βx} the sum tends to
    ∫₀^∞ e^{−2βx} dx = 1/(2β), and DR to 20·log10(e)·β, its decay rate. With the point
    receptance as the reference, a beam's near field (which the standard also includes)
    raises ``|A(x_0)|`` above the propagating wave's amplitude, so DR exceeds the propagating
    wave's decay rate; for a lightly damped Euler–Bernoulli beam well above its cut-on
    frequency, by a factor near 2 (docs/track.md).

    Parameters
    ----------
    config : vtb.Config
        The configuration; only its structure, discretisation and dampers are used.
    frequencies : float or array_like
        Frequencies (Hz), finite and ≥ 0.
    x0 : float, optional
        Excitation point (m). Default: the structure's mid-length L/2 (on a fastened rail this
        may be above a fastener or at mid-span, depending on the grid; pass x0 to choose).
    layer : str or int, default "rail"
        Layer name or index; force and responses are on this layer.
    positions : array_like, optional
        Distances d_n ≥ 0 (m) from x0, strictly increasing, at least two; 0 is prepended if
        absent (the normalisation needs A(x_0)). Default: if a discrete coupling carries the
        layer (fasteners), :data:`DEFAULT_DECAY_POSITIONS` times its spacing a (median of the
        support intervals), up to 66a, truncated at the end of the structure; otherwise 0 and
        :data:`DEFAULT_GEOMETRIC_POINTS` geometrically spaced distances from d_max·10⁻³ to
        d_max, d_max being the room from x0 to the end of the structure.
    direction : {+1, -1}, optional
        Side of x0 the positions lie on (+1: towards x = L). Default: the side with more room
        (+1 on a tie).

    Returns
    -------
    numpy.ndarray of float
        Decay rate in dB/m, shape (n_freq,).

    Raises
    ------
    vtb.ConfigError
        As :func:`receptance`; also for positions that do not fit on the structure, are not
        increasing, or fewer than two, and for an x0 where the point receptance vanishes.
    """
    system = assemble(config)
    li = layer_index(system, layer, "layer")
    L = system.length
    if x0 is None:
        x0v = 0.5 * L
    else:
        xa, scalar = checked_positions(x0, L, "x0")
        if not scalar and xa.size != 1:
            raise config_error("x0", x0, "must be a single position (m)")
        x0v = float(xa[0])
    freqs = checked_frequencies(frequencies)
    warn_beyond(config, config.structure.layers[li].name, float(freqs.max()), "the decay rate", stepped=False)
    if direction is not None and (isinstance(direction, bool) or direction not in (1, -1)):
        raise config_error("direction", direction, "must be +1 (towards x = L) or -1 (towards x = 0)")
    room = {1: L - x0v, -1: x0v}
    if direction is None:
        direction = 1 if room[1] >= room[-1] else -1

    if positions is None:
        spacing = _support_spacing(config, system.layers[li][0])
        dmax = room[direction]
        if spacing is not None:
            d = spacing * np.asarray(DEFAULT_DECAY_POSITIONS)
            d = d[d <= dmax * (1 + 1e-12)]
        else:
            d = np.concatenate(([0.0], np.geomspace(1e-3 * dmax, dmax, DEFAULT_GEOMETRIC_POINTS))) if dmax > 0 else np.zeros(1)
        if d.size < 2:
            raise config_error("x0", x0v, f"no room for decay-rate positions on the {'+' if direction > 0 else '-'}x side of x0")
    else:
        d = _float_array(positions, "positions")
        d = np.atleast_1d(d)
        for i, v in enumerate(d):
            if not math.isfinite(v) or v < 0:
                raise config_error(f"positions[{i}]", float(v), "distances from x0 must be finite and ≥ 0 (m)")
        if d.size and d[0] != 0.0:
            d = np.concatenate(([0.0], d))
        if d.size < 2:
            raise config_error("positions", positions, "needs at least one distance > 0 besides x0")
        if np.any(np.diff(d) <= 0):
            raise config_error("positions", positions, "distances must be strictly increasing")
        if d[-1] > room[direction] * (1 + 1e-12) + 1e-12:
            raise config_error("positions", positions, f"the farthest position x0 {'+' if direction > 0 else '-'} {d[-1]} m lies off the structure [0, {L}] m")
    xs = np.clip(x0v + direction * d, 0.0, L)
    force = shape_matrix(system, li, np.array([x0v]))
    resp = shape_matrix(system, li, xs)
    a = _harmonic_solve(system, freqs, force, resp)[:, :, 0]
    a0 = np.abs(a[:, 0]) ** 2
    if np.any(a0 == 0.0):
        raise config_error("x0", x0v, "the point receptance vanishes there (a rigid support?)")
    s = (np.abs(a) ** 2 / a0[:, None]) @ _estimator_weights(d)
    return Spectrum.of(DB_PER_NEPER_ENERGY / s, config, config.structure.layers[li].name)


# ---------------------------------------------------------------------------- modes
#: :func:`modes` substructures (``method="auto"``) a structure it can cut into at least this
#: many substructures: below it the global eigensolve is as fast (benches/substructures.py).
SUBSTRUCTURE_FROM = 6


@dataclass
class Modes:
    """Natural modes of the undamped structure (K φ = ω² M φ).

    Attributes
    ----------
    frequencies : numpy.ndarray
        Natural frequencies (Hz), ascending, shape (n_modes,).
    layers : list
        (name, first DOF, number of DOFs) of each layer.
    method : str
        ``"shift-invert"`` (sparse ARPACK, scipy.sparse.linalg.eigsh), ``"dense"`` or
        ``"substructured"`` (:mod:`vtb.analysis.substructures`).
    substructuring : Substructuring or None
        The cuts and the reduction, for ``"substructured"``.
    """

    frequencies: np.ndarray
    layers: list
    method: str
    substructuring: Optional[Substructuring] = None
    #: The eigenvectors: of the structure, or of the substructured reduction (u = T q).
    _vectors: np.ndarray = field(repr=False, default=None)
    _m: sp.csr_matrix = field(repr=False, default=None)
    _json: str = field(repr=False, default="")
    _length: float = field(repr=False, default=0.0)
    _n: int = field(repr=False, default=0)
    _shapes: Optional[np.ndarray] = field(repr=False, default=None)

    def __len__(self) -> int:
        return int(self.frequencies.size)

    @property
    def omega(self) -> np.ndarray:
        """Natural circular frequencies (rad/s)."""
        return 2.0 * math.pi * self.frequencies

    @property
    def shapes(self) -> np.ndarray:
        """Mode shapes, shape (n_dofs, n_modes), in the structure's DOF numbering (module
        docstring), mass-normalised: φᵢᵀ M φᵢ = 1 (kg⁻½ per generalised DOF; a displacement
        of 1/√m_modal metres). The sign of each mode is fixed so that its largest-magnitude
        entry is positive (of its reduced vector, for substructured modes). Substructured modes
        are expanded on first use (n_dofs × n_modes floats: prefer :meth:`displacement` and
        :meth:`layer_energy` on long structures)."""
        if self._shapes is None:
            self._shapes = np.asarray(self._to_dofs(self._vectors))
        return self._shapes

    def _to_dofs(self, vectors: np.ndarray) -> np.ndarray:
        return vectors if self.substructuring is None else self.substructuring.apply(vectors)

    def _projected(self, rows: sp.spmatrix) -> np.ndarray:
        """rowsᵀ·φ for a sparse n_dofs × p ``rows``, without expanding substructured modes."""
        if self.substructuring is None:
            return np.asarray(rows.T @ self._vectors)
        return self.substructuring.transpose_apply(rows) @ self._vectors

    def layer_energy(self, layer: Union[str, int]) -> np.ndarray:
        """The share (0–1) of each mode's kinetic energy in ``layer`` (name or index):
        φ_Lᵀ M_LL φ_L of the mass-normalised mode, shape (n_modes,)."""
        system = System(self._json, self._n, None, None, None, self.layers, self._length)
        _, first, count = self.layers[layer_index(system, layer, "layer")]
        sl = slice(first, first + count)
        mll = self._m[sl, sl]
        if self.substructuring is None:
            phi = self._vectors[sl]
            return np.einsum("ij,ij->j", phi, mll @ phi)
        mask = np.zeros(self._n)
        mask[sl] = 1.0
        only = sp.diags(mask) @ self._m @ sp.diags(mask)  # M_LL in place: TᵀM_LLT by blocks
        z = self._vectors
        return np.einsum("ij,ij->j", z, self.substructuring.project(only) @ z)

    def displacement(self, layer: Union[str, int], x, mode: Optional[int] = None) -> np.ndarray:
        """Displacement of ``layer`` along x (m) in the mass-normalised modes, s(x)ᵀφ.

        Parameters
        ----------
        layer : str or int
            Layer name or index.
        x : float or array_like
            Positions (m), 0 ≤ x ≤ L.
        mode : int, optional
            Mode index (0 = lowest). Default: all modes.

        Returns
        -------
        numpy.ndarray
            Shape (n_x, n_modes), or (n_x,) for one ``mode`` (a scalar x counts as n_x = 1).
        """
        system = System(self._json, self._n, None, None, None, self.layers, self._length)
        li = layer_index(system, layer, "layer")
        xs, _ = checked_positions(x, self._length, "x")
        if mode is not None:
            if isinstance(mode, bool) or not isinstance(mode, (int, np.integer)) or not -len(self) <= mode < len(self):
                raise config_error("mode", mode, f"must be an integer index below {len(self)}")
        out = self._projected(shape_matrix(system, li, xs))
        return out[:, int(mode)] if mode is not None else out


def _normalise_modes(lam: np.ndarray, phi: np.ndarray, m: sp.spmatrix):
    order = np.argsort(lam)
    lam, phi = lam[order], np.array(phi[:, order], dtype=float)
    mass = np.einsum("ij,ij->j", phi, np.asarray(m @ phi))
    return lam, phi / np.sqrt(mass)[None, :]


def modes(config: Config, fmax: float, fmin: float = 0.0, method: str = "auto") -> Modes:
    """All natural frequencies and mass-normalised mode shapes of the undamped structure with
    fmin ≤ f ≤ fmax.

    Solves the generalised symmetric problem K φ = ω² M φ (damping, including the dampers'
    dashpots, is ignored; the dampers' inerters and springs are kept).

    - ``method="global"``: ARPACK's shift-invert Lanczos (scipy.sparse.linalg.eigsh) on the
      whole structure, by spectrum slicing from a shift just below (2π·fmin)² until the band is
      covered (:func:`vtb.analysis.eigen.sliced_eigsh`); when ARPACK fails, a dense generalised
      eigensolver (scipy.linalg.eigh), but only for n ≤ :data:`DENSE_EIGEN_LIMIT` DOFs.
    - ``method="substructured"``: the structure cut at its joints and every
      :data:`~vtb.analysis.substructures.SUBSTRUCTURE_LENGTH` m and reduced by fixed-interface
      component mode synthesis (:mod:`vtb.analysis.substructures`), each distinct substructure
      once, then the same slicing on the reduced problem. Its frequencies are upper bounds of
      the global ones, within 5e-5 (relative) of them on the deck's modes and 3e-4 on every
      mode below fmax (docs/substructures.md; finite-element layers only).
    - ``method="auto"`` (default): substructured when the structure cuts into at least
      :data:`SUBSTRUCTURE_FROM` substructures, else global.

    Parameters
    ----------
    config : vtb.Config
        The configuration; only its structure, discretisation and dampers are used.
    fmax : float
        Upper frequency (Hz), > 0.
    fmin : float, default 0.0
        Lower frequency (Hz), 0 ≤ fmin < fmax. Rigid-body modes of an unrestrained structure
        (0 Hz, to round-off) are included when fmin = 0.
    method : {"auto", "global", "substructured"}

    Returns
    -------
    Modes
        Frequencies (Hz, ascending) and shapes (n_dofs × n_modes, φᵀMφ = 1); possibly no modes.

    Raises
    ------
    vtb.ConfigError
        Invalid configuration, fmax ≤ 0 or not finite, fmin < 0 or ≥ fmax, an unknown
        ``method``, or ``"substructured"`` on a structure that cannot be cut (a modal layer).
    vtb.SolverError
        The sparse eigensolver failed on a structure too large for the dense fallback.
    """
    for name, v in (("fmax", fmax), ("fmin", fmin)):
        if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)):
            raise config_error(name, v, "must be a number (Hz)")
        if not math.isfinite(v):
            raise config_error(name, v, "must be finite (Hz)")
    if fmax <= 0:
        raise config_error("fmax", fmax, "must be > 0 (Hz)")
    if fmin < 0:
        raise config_error("fmin", fmin, "must be ≥ 0 (Hz)")
    if fmin >= fmax:
        raise config_error("fmin", fmin, f"must be < fmax = {fmax} Hz")
    methods = ("auto", "global", "substructured")
    if not isinstance(method, str) or method not in methods:
        raise config_error("method", method, f"must be one of {methods}")
    system = assemble(config)
    lo, hi = (2.0 * math.pi * fmin) ** 2, (2.0 * math.pi * fmax) ** 2
    cut = None if method == "global" else substructures.reduce(system, fmax)
    if method == "substructured" and cut is None:
        raise config_error("method", method, "the structure cannot be cut: every layer must be finite elements with a node across the track somewhere")
    if method == "auto" and cut is not None and cut.substructures < SUBSTRUCTURE_FROM:
        cut = None
    k, m = (system.k, system.m) if cut is None else (cut.k, cut.m)
    name = "shift-invert" if cut is None else "substructured"
    try:
        lam, vec = sliced_eigsh(k, m, lo - 1e-6 * hi, hi)
    except EigshFailed:
        if k.shape[0] > DENSE_EIGEN_LIMIT:
            raise SolverError(f"the shift-invert eigensolver failed on {k.shape[0]} DOFs (the dense fallback is limited to {DENSE_EIGEN_LIMIT}); lower fmax or split the band with fmin") from None
        name = "dense" if cut is None else name
        lam, vec = scipy.linalg.eigh(k.toarray(), m.toarray())
    lam, vec = _normalise_modes(np.asarray(lam, float), vec, m)
    vec = fix_signs(vec)
    f = np.sqrt(np.clip(lam, 0.0, None)) / (2.0 * math.pi)
    keep = (f >= fmin) & (f <= fmax)  # f = 0 for round-off negative rigid-body eigenvalues
    return Modes(f[keep], system.layers, name, cut, vec[:, keep], system.m.tocsr(), system.json, system.length, system.n)


#: EN 1990 A2 (A2.4.4.2.1): the lowest frequency (Hz) up to which the deck acceleration counts.
DECK_BAND_FLOOR = 30.0

#: The bands (Hz) :func:`deck_band` searches for the deck's lowest three modes before ``fmax``.
DECK_BAND_TRIALS = (15.0, 40.0)


def deck_band(config: Config, fmax: float = 120.0) -> float:
    """The band (Hz) over which EN 1990 A2 (A2.4.4.2.1) checks the deck acceleration of a
    configuration: the greatest of 30 Hz, 1.5 times the deck's first natural frequency and its
    third. The deck is the bottom layer; its modes are the structure's modes below ``fmax``
    (Hz) whose kinetic energy lies mostly in it. Set the result as ``output.deck_band`` when it
    exceeds the default 30 Hz (short stiff spans).

    The modes are sought below :data:`DECK_BAND_TRIALS` first, then ``fmax``: the lowest three
    deck modes below a trial are the lowest three below ``fmax``, and a long viaduct's
    identical spans give three within a few hertz (its modes below 120 Hz number thousands).

    Raises :class:`vtb.ConfigError` when fewer than three deck modes lie below ``fmax``."""
    real = isinstance(fmax, (int, float, np.integer, np.floating)) and not isinstance(fmax, bool) and math.isfinite(fmax)
    for top in [t for t in DECK_BAND_TRIALS if real and t < fmax] + [fmax]:
        found = modes(config, top)
        share = found.layer_energy(len(found.layers) - 1)  # φᵀMφ = 1 over the whole structure
        f = found.frequencies[(share > 0.5) & (found.frequencies > 0)]
        if f.size >= 3:
            return float(max(DECK_BAND_FLOOR, 1.5 * f[0], f[2]))
    raise config_error("fmax", fmax, f"only {f.size} deck modes below it; raise it to reach the deck's third mode")
