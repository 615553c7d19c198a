"""The assembled structure of a configuration and its eigensolutions: the one place the
analyses and the synthesis reach the core's matrices, shape vectors, SPD solver and reduction.

:func:`assemble` gives the sparse M, K, C of a configuration's structure alone (its loads,
speed, solver and outputs neutral: :func:`vtb.config.fields.structure_json`), in the DOF
numbering of :mod:`vtb.analysis.track`; :func:`shape_matrix` reads the core's shape vectors at
points of a layer; :func:`sliced_eigsh` finds every eigenpair in a band by spectrum slicing.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .. import _core
from ..config.fields import Config, structure_json
from ..errors import config_error

#: The synthesis reduction's geometry, held by the core (rust/src/model/resolution.rs says
#: why each value): the Ritz basis's reach as a multiple of the cut-off, the stored residual's
#: reach and the distance it is whole to (m), the modes' step compliance reach (m).
SYNTHESIS_BASIS_RATIO = _core.SYNTHESIS_BASIS_RATIO
SYNTHESIS_RESIDUAL_REACH = _core.SYNTHESIS_RESIDUAL_REACH
SYNTHESIS_RESIDUAL_TAPER = _core.SYNTHESIS_RESIDUAL_TAPER
SYNTHESIS_STEP_REACH = _core.SYNTHESIS_STEP_REACH


@dataclass
class System:
    """The assembled structure of one configuration (sparse CSC matrices)."""

    json: str
    n: int
    m: sp.csc_matrix
    k: sp.csc_matrix
    c: sp.csc_matrix
    layers: list  # [(name, offset, n_dofs)]
    length: float
    #: Each layer's node positions (m; node j holds DOFs offset + 2j, 2j + 1), None for a modal layer.
    nodes: Optional[list] = None


def assemble(config: Config) -> System:
    js = structure_json(config)
    out = _core.matrices(js)
    n = int(out["n"])
    mats = {}
    for name in ("m", "k", "c"):
        r, c, v = out[name]
        # COO → CSC sums duplicate entries (both halves of the symmetric matrices are stored).
        mats[name] = sp.coo_matrix((np.asarray(v, float), (np.asarray(r), np.asarray(c))), shape=(n, n)).tocsc()
    nodes = [None if x is None else np.asarray(x, float) for x in out["layer_nodes"]]
    return System(js, n, mats["m"], mats["k"], mats["c"], [tuple(l) for l in out["layer_offsets"]], float(config.structure.length), nodes)


def layer_index(system: System, layer, field_name: str = "layer") -> int:
    names = [l[0] for l in system.layers]
    if isinstance(layer, (bool, np.bool_)):
        raise config_error(field_name, layer, f"expected a layer name or index (layers: {names})")
    if isinstance(layer, (int, np.integer)):
        if 0 <= int(layer) < len(names):
            return int(layer)
        raise config_error(field_name, layer, f"no layer with that index (0 … {len(names) - 1}; layers: {names})")
    if isinstance(layer, str):
        if layer in names:
            return names.index(layer)
        raise config_error(field_name, layer, f"no layer of that name (layers: {names})")
    raise config_error(field_name, layer, f"expected a layer name or index (layers: {names})")


def _float_array(value, field_name: str) -> np.ndarray:
    if isinstance(value, (str, bytes)) or value is None:
        raise config_error(field_name, value, "must be a number or a 1-D array of numbers")
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise config_error(field_name, value, "must be a number or a 1-D array of numbers") from None
    if a.ndim > 1:
        raise config_error(field_name, value, f"must be a number or a 1-D array (got shape {a.shape})")
    return a


def checked_positions(value, length: float, field_name: str) -> tuple[np.ndarray, bool]:
    """(1-D float array, was_scalar), every entry finite and within [0, L]."""
    a = _float_array(value, field_name)
    scalar = a.ndim == 0
    a = np.atleast_1d(a)
    if a.size == 0:
        raise config_error(field_name, value, "needs at least one position")
    for i, x in enumerate(a):
        sub = field_name if scalar else f"{field_name}[{i}]"
        if not math.isfinite(x):
            raise config_error(sub, float(x), "must be a finite position (m)")
        if not 0.0 <= x <= length:
            raise config_error(sub, float(x), f"must lie on the structure, 0 ≤ x ≤ L = {length} m")
    return a, scalar


def checked_frequencies(value, field_name: str = "frequencies") -> np.ndarray:
    """A 1-D float array of frequencies (Hz), each finite and ≥ 0; at least one."""
    a = np.atleast_1d(_float_array(value, field_name))
    if a.size == 0:
        raise config_error(field_name, value, "needs at least one frequency (Hz)")
    for i, f in enumerate(a):
        if not math.isfinite(f) or f < 0.0:
            raise config_error(f"{field_name}[{i}]", float(f), "frequencies must be finite and ≥ 0 (Hz)")
    return a


def shape_matrix(system: System, layer: int, xs: np.ndarray, moment: bool = False) -> sp.csc_matrix:
    """The n × len(xs) sparse matrix whose column i is layer ``layer``'s shape vector at xs[i]
    (with ``moment``: its bending-moment vector, N·m per unit DOF, sagging positive, as the
    core's ``deck_moment_max`` reads it)."""
    starts, values = _core.shapes(system.json, layer, np.ascontiguousarray(xs, dtype=float), moment)
    starts = np.asarray(starts, dtype=np.int64)
    values = np.asarray(values, dtype=float)
    p, width = values.shape
    rows = (starts[:, None] + np.arange(width)[None, :]).ravel()
    cols = np.repeat(np.arange(p), width)
    return sp.csc_matrix((values.ravel(), (rows, cols)), shape=(system.n, p))
#: Eigenpairs requested per shift-invert slice of :func:`modes`.
EIGEN_BLOCK = 40


class EigshFailed(Exception):
    pass


def sliced_eigsh(k: sp.csc_matrix, m: sp.csc_matrix, start: float, hi: float, covered=None):
    """Every eigenpair of K φ = λ M φ with start ≤ λ ≤ hi, by spectrum slicing.

    Each slice factorises K − σM at a shift σ = b, the lower edge of the part not yet covered,
    and asks ARPACK for the ``EIGEN_BLOCK`` eigenvalues nearest σ; their radius r = max|λ − σ|
    guarantees that every eigenvalue in [σ − r, σ + r] is among them. The eigenvalues at or above
    b are accepted up to a boundary placed in the middle of the widest gap between consecutive
    found eigenvalues in the upper half of the slice — a true gap, since the slice is complete
    there — so no eigenvalue is counted twice or missed at a boundary, and the next shift never
    sits on an eigenvalue. The slice that reaches beyond ``hi`` ends the search; ``covered(b)``,
    when given, is told the lower edge b of the part not yet covered after each slice. Raises
    :class:`EigshFailed` when ARPACK fails or a slice would need n − 1 eigenpairs.

    Deterministic: every slice starts ARPACK from the same seeded vector (:func:`start_vector`;
    ARPACK's own default is a random one, which made two builds of one structure differ at the
    level of its convergence tolerance), and each eigenvector's sign is fixed by
    :func:`fix_signs`, so the same matrices give the same bits in every process.
    """
    n = k.shape[0]
    block = min(EIGEN_BLOCK, n - 2)
    if block < 1:
        raise EigshFailed
    lams, phis = [], []
    b = start
    while True:
        try:
            lam, phi = spla.eigsh(k, k=block, M=m, sigma=b, which="LM", v0=start_vector(n))
        except (spla.ArpackError, spla.ArpackNoConvergence, RuntimeError, ValueError):
            raise EigshFailed from None
        top = b + float(np.max(np.abs(lam - b)))
        order = np.argsort(lam)
        lam, phi = lam[order], phi[:, order]
        up = lam >= b
        u = lam[up]
        if top > hi:
            sel = up & (lam <= hi)
            lams.append(lam[sel])
            phis.append(phi[:, sel])
            break
        if u.size < 2:
            if block >= n - 2:
                raise EigshFailed
            block = min(2 * block, n - 2)
            continue
        j0 = max(0, u.size // 2 - 1)
        gaps = np.diff(u[j0:])
        j = j0 + int(np.argmax(gaps))
        boundary = 0.5 * (u[j] + u[j + 1])
        sel = up & (lam < boundary)
        lams.append(lam[sel])
        phis.append(phi[:, sel])
        b = boundary
        if covered is not None:
            covered(b)
    return np.concatenate(lams), fix_signs(np.concatenate(phis, axis=1))


#: Seed of :func:`start_vector`.
START_SEED = 20240607


def start_vector(n: int) -> np.ndarray:
    """ARPACK's start vector for an n-DOF problem: the same pseudo-random vector every time."""
    return np.random.default_rng(START_SEED).standard_normal(n)


def fix_signs(vectors: np.ndarray) -> np.ndarray:
    """``vectors`` (n × k, real or complex) with each column multiplied by ±1 so that its entry of
    largest modulus (the first such) has a positive real part (or, if that is zero, a positive
    imaginary part): an eigenvector's sign is arbitrary, this picks one in every process."""
    if vectors.size == 0:
        return vectors
    rows = np.argmax(np.abs(vectors), axis=0)
    lead = vectors[rows, np.arange(vectors.shape[1])]
    flip = np.where(lead.real != 0.0, lead.real < 0.0, np.imag(lead) < 0.0)
    vectors[:, flip] *= -1.0
    return vectors


def spd_solver(k: sp.spmatrix):
    """The core's sparse LDLᵀ of a symmetric positive definite K: ``.solve(b)`` for a vector or
    the columns of a matrix (8 per pass)."""
    kc = k.tocoo()
    return _core.SpdSolver(int(k.shape[0]), kc.row.astype(np.int64), kc.col.astype(np.int64), kc.data)


def structure_estimate(text: str, check: bool = False) -> dict:
    """The core's estimate of a synthesis build of the configuration whose core JSON is ``text``
    (:func:`vtb.run.synthesis.estimate`)."""
    out = _core.synthesis_build(text, check)
    if out is None:
        raise config_error("discretisation.synthesis_cutoff", None, "the configuration does not ask for the synthesis of a finite-element structure")
    return dict(out)


def core_reduction(lam: np.ndarray, weight: np.ndarray, psi: np.ndarray, rail_dofs: int, band: int, step_band: int,
                   residual: np.ndarray):
    """The core's copy of a modal reduction (:class:`vtb.run.synthesis.Reduction`), ψ read in
    place: no copy on this side."""
    flat = lambda a: np.ascontiguousarray(a, dtype=float).ravel()  # noqa: E731
    return _core.Reduction(flat(lam.real), flat(lam.imag), flat(weight), np.ascontiguousarray(psi, dtype=complex),
                           int(rail_dofs), int(band), int(step_band), flat(residual))


def core_substructures(sub, c: sp.spmatrix):
    """The core's copy of a substructuring (:class:`vtb.analysis.substructures.Substructuring`)
    whose reduced damping is ``c`` (TᵀCT): what the substructured engine steps."""
    pieces = [p for p in sub.pieces if p.inner.size]
    dof_piece = np.full(sub.n, -1, dtype=np.int64)
    dof_index = np.full(sub.n, -1, dtype=np.int64)
    for i, p in enumerate(pieces):
        dof_piece[p.inner] = i
        dof_index[p.inner] = np.arange(p.inner.size)
    dof_index[sub.interface] = sub.interface_cols
    bound_ptr = np.concatenate([[0], np.cumsum([p.bound.size for p in pieces])]).astype(np.int64)
    flat = lambda a: np.ascontiguousarray(np.concatenate([x.ravel() for x in a]) if a else np.zeros(0), dtype=float)  # noqa: E731

    def triplets(a):
        a = a.tocoo()
        return (a.row.astype(np.int64).tolist(), a.col.astype(np.int64).tolist(), np.ascontiguousarray(a.data, dtype=float))

    return _core.Substructures(
        dof_piece, dof_index,
        [p.group for p in pieces], [p.modes.start for p in pieces], bound_ptr.tolist(),
        [int(c) for p in pieces for c in p.bound_cols],
        [g.phi.shape[0] for g in sub.groups], [g.phi.shape[1] for g in sub.groups], [g.psi.shape[1] for g in sub.groups],
        flat([g.phi for g in sub.groups]), flat([g.psi for g in sub.groups]),
        int(sub.reduced_dofs), (triplets(sub.m), triplets(c), triplets(sub.k)),
        flat([g.residual if g.residual is not None else np.zeros((3, g.phi.shape[0], 1)) for g in sub.groups]),
        max((g.residual.shape[-1] - 1 for g in sub.groups if g.residual is not None), default=0))
