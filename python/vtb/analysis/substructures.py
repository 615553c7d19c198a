"""Natural modes of a long structure by substructuring: fixed-interface component mode synthesis
(Craig–Bampton), each distinct substructure reduced once.

The structure is cut across the track at positions where every layer that crosses has a mesh
node (the cuts): its DOFs split into the interiors I_s of the substructures between cuts and
the interfaces at the cuts (every DOF whose node lies on a cut), and no matrix entry joins two
interiors. Each interior is replaced by

- its fixed-interface modes below ``ratio × fmax``: K_II Φ = M_II Φ Λ, Φᵀ M_II Φ = 1;
- its constraint modes Ψ = −K_II⁻¹ K_IB: the static shape of the interior under a unit
  displacement of each interface DOF B it touches, the others held;

so u = T q, q = (each substructure's modal amplitudes, the interface DOFs), and the reduced
problem TᵀKT φ = ω² TᵀMT φ is banded along the track. The interfaces are kept whole (two DOFs
per layer crossing a cut). Interiors with equal matrices and node positions relative to their
left cut — the spans of a repetitive viaduct, the stretches of an embankment — share one
reduction, so the eigensolves cost as many distinct substructures as there are, not spans;
the rest (T, the reduced matrices, their eigensolve) grows with the length.

What it resolves: every frequency up to ``fmax`` from above (the reduced eigenvalues are upper
bounds of the structure's, the Rayleigh–Ritz property), converging as ``ratio`` grows;
tests/test_substructures.py holds it against the global eigensolve on 5 and 10 spans, and
docs/substructures.md tabulates the convergence in ``ratio`` and the cost against the length
(benches/substructures.py). Finite-element layers only: a modal layer's DOFs span the whole
length and cannot be cut.
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass
from typing import Optional

import numpy as np
import scipy.linalg
import scipy.sparse as sp

from .eigen import EigshFailed, System, sliced_eigsh, spd_solver

#: Fixed-interface modes kept per substructure: those below this multiple of the highest
#: frequency sought (docs/substructures.md: the deck's frequencies to 1e-6 at 3).
RATIO = 5.0

#: The longest substructure (m) between the natural cuts (joints and the layers' ends): longer
#: stretches are cut into equal pieces no longer than this.
SUBSTRUCTURE_LENGTH = 32.0

#: Positions are compared in whole nanometres (a mesh node on a cut is the cut).
_NM = 1e-9

#: Interiors up to this many DOFs are solved dense (ARPACK needs a few more than it returns).
_DENSE = 400


@dataclass
class Piece:
    """One substructure: its interior DOFs, the interface DOFs they touch (both in the
    structure's numbering, ordered along the track), the distinct reduction it uses, and where
    its modes and those interface DOFs sit among the reduced DOFs."""

    inner: np.ndarray
    bound: np.ndarray
    group: int
    modes: slice
    bound_cols: np.ndarray


@dataclass
class Group:
    """The reduction of a distinct interior: fixed-interface modes Φ (interior × modes,
    mass-normalised) with their ω² (rad²/s²), and constraint modes Ψ (interior × bound)."""

    omega2: np.ndarray
    phi: np.ndarray
    psi: np.ndarray
    #: The truncated interior modes' receptance moments R₀ (m/N), R₁ (m·s/N), R₂ (m·s²/N)
    #: between rows r and r + d, 0 ≤ d ≤ band, at ``[k, r, d]`` (:func:`residual_bands`; rows of
    #: the top layer only, zero elsewhere).
    residual: Optional[np.ndarray] = None


@dataclass
class Substructuring:
    """A structure cut into substructures and reduced (:func:`reduce`): u = T q.

    Attributes
    ----------
    cuts : numpy.ndarray
        The cuts' positions (m), ascending.
    pieces : list of Piece
        The substructures between the cuts, along the track.
    groups : list of Group
        The distinct substructures' reductions (the eigensolves done).
    interface : numpy.ndarray
        The DOFs on the cuts, and ``interface_cols`` their reduced DOFs.
    n, reduced_dofs : int
        The structure's DOFs and the reduced DOFs.
    m, k : scipy.sparse.csc_matrix
        TᵀMT (kg) and TᵀKT (N/m), symmetric, banded along the track.
    ratio : float
        Fixed-interface modes kept below ratio × fmax.
    """

    cuts: np.ndarray
    pieces: list
    groups: list
    interface: np.ndarray
    interface_cols: np.ndarray
    n: int
    reduced_dofs: int
    ratio: float
    m: Optional[sp.csc_matrix] = None
    k: Optional[sp.csc_matrix] = None

    @property
    def substructures(self) -> int:
        return len(self.pieces)

    @property
    def distinct(self) -> int:
        return len(self.groups)

    def project(self, a: sp.spmatrix, cache: Optional[dict] = None) -> sp.csc_matrix:
        """TᵀAT of a symmetric n × n sparse A whose entries never join two interiors, by
        blocks: per distinct interior Φᵀ A_II Φ, Φᵀ(A_II Ψ + A_IB) and Ψᵀ A_II Ψ + Ψᵀ A_IB +
        A_BI Ψ (computed once per group when ``cache`` is shared across its calls on one A —
        equal interiors have equal blocks), plus A's own entries between interface DOFs."""
        a = a.tocsr()
        rows, cols, vals = [], [], []

        def put(r, c, block):
            rows.append(np.repeat(r, len(c)))
            cols.append(np.tile(c, len(r)))
            vals.append(np.asarray(block).ravel())

        memo = {} if cache is None else cache
        for p in self.pieces:
            g = self.groups[p.group]
            if p.inner.size == 0:
                continue
            if p.group not in memo:
                aii = a[p.inner][:, p.inner]
                aib = a[p.inner][:, p.bound].toarray()
                aii_psi = aii @ g.psi
                memo[p.group] = (g.phi.T @ (aii @ g.phi), g.phi.T @ (aii_psi + aib),
                                 g.psi.T @ aii_psi + g.psi.T @ aib + aib.T @ g.psi)
            mm, mb, bb = memo[p.group]
            mcols = np.arange(p.modes.start, p.modes.stop)
            put(mcols, mcols, mm)
            put(mcols, p.bound_cols, mb)
            put(p.bound_cols, mcols, mb.T)
            put(p.bound_cols, p.bound_cols, bb)
        ab = a[self.interface][:, self.interface].tocoo()
        rows.append(self.interface_cols[ab.row])
        cols.append(self.interface_cols[ab.col])
        vals.append(ab.data)
        n = self.reduced_dofs
        out = sp.csc_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n))
        return 0.5 * (out + out.T)

    def transpose_apply(self, r: sp.spmatrix) -> np.ndarray:
        """rᵀT for a sparse n × p ``r`` (e.g. shape vectors as columns): p × reduced DOFs."""
        rt = r.T.tocsc()
        out = np.zeros((rt.shape[0], self.reduced_dofs))
        touched = np.flatnonzero(np.diff(rt.indptr))
        owner = np.full(self.n, -1)
        for i, p in enumerate(self.pieces):
            owner[p.inner] = i
        for i in np.unique(owner[touched]):
            if i < 0:
                continue
            p = self.pieces[i]
            g = self.groups[p.group]
            ri = rt[:, p.inner]
            out[:, p.modes] += ri @ g.phi
            out[:, p.bound_cols] += ri @ g.psi
        out[:, self.interface_cols] += rt[:, self.interface].toarray()
        return out

    def apply(self, z: np.ndarray) -> np.ndarray:
        """T z: the structure's DOFs of reduced vectors z (reduced DOFs × k)."""
        z = np.asarray(z)
        out = np.zeros((self.n,) + z.shape[1:])
        for p in self.pieces:
            if p.inner.size:
                g = self.groups[p.group]
                out[p.inner] = g.phi @ z[p.modes] + g.psi @ z[p.bound_cols]
        out[self.interface] = z[self.interface_cols]
        return out


def dof_positions(system: System) -> Optional[np.ndarray]:
    """Each DOF's position along the track (m): its node's for a finite-element layer, the mean
    of its neighbours' in K for an internal node (a damper's); None if a layer is modal."""
    if system.nodes is None or any(x is None for x in system.nodes):
        return None
    pos = np.full(system.n, np.nan)
    for (_, first, count), xs in zip(system.layers, system.nodes):
        pos[first:first + count] = np.repeat(xs, 2)
    k = system.k.tocsc()
    for i in np.flatnonzero(np.isnan(pos)):
        x = pos[k.indices[k.indptr[i]:k.indptr[i + 1]]]
        x = x[np.isfinite(x)]
        if x.size == 0:
            return None
        pos[i] = x.mean()
    return pos


def cut_positions(system: System, length: float = SUBSTRUCTURE_LENGTH) -> np.ndarray:
    """Where to cut (m): at every layer's joints and ends inside the structure (the girder ends
    of simply supported spans, the bridge's ends between embankments), and between those in
    equal pieces of at most ``length``. A cut goes where every layer that crosses it has a node
    if such a place lies within a quarter of a piece of its target, else on the top layer's
    nearest node (a layer without a node there then puts its element's two nodes on the
    interface, :func:`reduce`)."""
    meshes = [np.round(np.asarray(x) / _NM).astype(np.int64) for x in system.nodes]
    lo, hi = min(int(x[0]) for x in meshes), max(int(x[-1]) for x in meshes)
    candidates = np.unique(np.concatenate(meshes))
    full = (candidates > lo) & (candidates < hi)
    for x in meshes:
        full &= ~((candidates > x[0]) & (candidates < x[-1])) | np.isin(candidates, x)
    full = candidates[full]
    top = meshes[0][(meshes[0] > lo) & (meshes[0] < hi)]
    natural = sorted({int(v) for x in meshes for v in (x[0], x[-1], *x[1:][np.diff(x) == 0]) if lo < v < hi})
    edges = [lo, *natural, hi]
    step = length / _NM
    cuts = set(natural)
    for a, b in zip(edges[:-1], edges[1:]):
        pieces = math.ceil((b - a) / step - 1e-9)
        for i in range(1, pieces):
            target = a + (b - a) * i / pieces
            near = full[(full > a) & (full < b) & (np.abs(full - target) <= 0.25 * (b - a) / pieces)]
            pool = near if near.size else top[(top > a) & (top < b)]
            if pool.size:
                cuts.add(int(pool[np.argmin(np.abs(pool - target))]))
    return np.asarray(sorted(cuts), dtype=float) * _NM


def _fingerprint(*arrays) -> bytes:
    """A key equal for matrices equal to 1e-10 of their largest entry (and equal patterns)."""
    h = hashlib.sha256()
    for a in arrays:
        if sp.issparse(a):
            a = a.tocsr()
            a.sum_duplicates()
            a.sort_indices()
            h.update(np.asarray(a.shape, np.int64).tobytes())
            h.update(a.indptr.astype(np.int64).tobytes())
            h.update(a.indices.astype(np.int64).tobytes())
            a = a.data
        a = np.asarray(a, float)
        scale = float(np.max(np.abs(a))) if a.size else 0.0
        h.update(np.asarray([a.size], np.int64).tobytes())
        if scale > 0:
            h.update(np.round(a / scale * 1e10).astype(np.int64).tobytes())
            h.update(np.asarray([scale]).round(decimals=int(10 - math.floor(math.log10(scale)))).tobytes())
    return h.digest()


def _interior_modes(kii: sp.csc_matrix, mii: sp.csc_matrix, hi: float) -> tuple[np.ndarray, np.ndarray]:
    """The fixed-interface modes with ω² ≤ hi, mass-normalised."""
    n = kii.shape[0]
    if n <= _DENSE:
        lam, phi = scipy.linalg.eigh(kii.toarray(), mii.toarray(), subset_by_value=(-np.inf, hi))
    else:
        try:
            lam, phi = sliced_eigsh(kii, mii, -1e-6 * hi, hi)
        except EigshFailed:
            lam, phi = scipy.linalg.eigh(kii.toarray(), mii.toarray(), subset_by_value=(-np.inf, hi))
    phi = phi / np.sqrt(np.einsum("ij,ij->j", phi, mii @ phi))[None, :]
    return lam, phi


def reduce(system: System, fmax: float, ratio: float = RATIO, length: float = SUBSTRUCTURE_LENGTH,
           progress=None) -> Optional[Substructuring]:
    """The substructured reduction of ``system`` for modes up to ``fmax`` (Hz), or None when the
    structure cannot be cut (a modal layer or no mesh to cut by). ``progress(done, total)`` is
    told each substructure reduced (or recognised as one reduced already)."""
    pos = dof_positions(system)
    if pos is None:
        return None
    cuts = cut_positions(system, length)
    if cuts.size == 0:
        return None
    key = np.round(pos / _NM).astype(np.int64)
    cut_keys = np.round(cuts / _NM).astype(np.int64)
    on_cut = np.isin(key, cut_keys)
    # The substructure of each DOF (-1 on the interface): the DOFs on a cut, and the DOFs of
    # any matrix entry across one (an element of a layer with no node on the cut), are the
    # interface; each interface DOF belongs to its nearest cut.
    side = np.searchsorted(cut_keys, key)
    m, k, c = system.m.tocsr(), system.k.tocsr(), system.c.tocsr()
    pattern = (abs(m) + abs(k) + abs(c)).tocoo()
    owner = np.where(on_cut, -1, side)
    across = (owner[pattern.row] >= 0) & (owner[pattern.col] >= 0) & (owner[pattern.row] != owner[pattern.col])
    owner[pattern.row[across]] = -1
    owner[pattern.col[across]] = -1
    left = np.clip(side - 1, 0, cut_keys.size - 1)
    right = np.clip(side, 0, cut_keys.size - 1)
    cut_of = np.where(np.abs(key - cut_keys[left]) <= np.abs(key - cut_keys[right]), left, right)
    n_sub = cuts.size + 1
    # The reduced numbering along the track: substructure s's modes, then the DOFs on cut s.
    order = np.lexsort((np.arange(system.n), key))
    interiors = [[] for _ in range(n_sub)]
    for i in order[owner[order] >= 0]:
        interiors[owner[i]].append(i)
    on_cut = owner < 0
    interfaces = [order[(cut_of[order] == j) & on_cut[order]] for j in range(cut_keys.size)]
    hi = (2.0 * math.pi * ratio * fmax) ** 2
    layer_of = np.zeros(system.n, np.int64)
    for li, (_, first, count) in enumerate(system.layers):
        layer_of[first:first + count] = li + 1
    found: dict = {}
    groups: list = []
    raw = []
    for s in range(n_sub):
        inner = np.asarray(interiors[s], dtype=np.int64)
        if inner.size == 0:
            raw.append((inner, np.zeros(0, np.int64), -1))
            continue
        touched = np.unique(pattern.col[np.isin(pattern.row, inner)])
        bound = touched[owner[touched] < 0]
        bound = bound[np.lexsort((bound, key[bound]))]
        kii, mii = k[inner][:, inner].tocsc(), m[inner][:, inner].tocsc()
        kib, mib = k[inner][:, bound], m[inner][:, bound]
        x0 = key[inner[0]]
        # C_II too: a group's residual filter (residual_bands) is computed on its first piece.
        fp = _fingerprint(kii, mii, c[inner][:, inner], kib, mib, key[inner] - x0, key[bound] - x0, layer_of[inner], layer_of[bound])
        if fp not in found:
            omega2, phi = _interior_modes(kii, mii, hi)
            psi = -np.asarray(spd_solver(kii).solve(kib.toarray())) if bound.size else np.zeros((inner.size, 0))
            found[fp] = len(groups)
            groups.append(Group(omega2, phi, psi.reshape(inner.size, bound.size)))
        raw.append((inner, bound, found[fp]))
        if progress is not None:
            progress(s + 1, n_sub)
    # The reduced DOFs along the track: substructure s's modes, then the DOFs on cut s.
    col = np.full(system.n, -1)
    offset = 0
    spans = []
    for s, (_, _, g) in enumerate(raw):
        count = groups[g].phi.shape[1] if g >= 0 else 0
        spans.append(slice(offset, offset + count))
        offset += count
        if s < cuts.size:
            col[interfaces[s]] = offset + np.arange(interfaces[s].size)
            offset += interfaces[s].size
    pieces = [Piece(inner, bound, max(g, 0), spans[s], col[bound]) for s, (inner, bound, g) in enumerate(raw)]
    on = np.flatnonzero(on_cut)
    out = Substructuring(cuts, pieces, groups, on, col[on], system.n, offset, float(ratio))
    out.m, out.k = out.project(m), out.project(k)
    return out


#: Rows (of an interior's DOFs along the track) over which a wheel's residual flexibility is
#: kept: a contact patch spans at most two rail elements, whose DOFs lie within 12 rows.
RESIDUAL_ROWS = 16


def residual_bands(system: System, sub: Substructuring, band: int = RESIDUAL_ROWS) -> None:
    """Fills each group's ``residual``: the moments R₀, R₁, R₂ of its truncated fixed-interface
    modes' receptance between the top layer's (the rail's) interior DOFs within ``band`` rows.
    The interior's receptance (K + sC + s²M)⁻¹ about s = 0 has the moments F₀ = K⁻¹,
    F₁ = −K⁻¹CK⁻¹, F₂ = K⁻¹CK⁻¹CK⁻¹ − K⁻¹MK⁻¹; the kept modes' (Λ + sD + s²I, D = ΦᵀCΦ) hold
    ΦΛ⁻¹Φᵀ, −ΦΛ⁻¹DΛ⁻¹Φᵀ and Φ(Λ⁻¹DΛ⁻¹DΛ⁻¹ − Λ⁻²)Φᵀ; R_k is the difference. R₀ makes a wheel
    see the rail's whole static flexibility (constraint modes and kept modes hold the rest
    exactly); R₁ and R₂ give the core the filter that carries the truncated modes' damping and
    inertia (docs/substructures.md, "The wheel's residual"). Computed on the first piece of each
    group (its members share K, M and C)."""
    k, m, c = system.k.tocsr(), system.m.tocsr(), system.c.tocsr()
    _, first, count = system.layers[0]
    done = set()
    for p in sub.pieces:
        if p.inner.size == 0 or p.group in done:
            continue
        done.add(p.group)
        g = sub.groups[p.group]
        rows = np.flatnonzero((p.inner >= first) & (p.inner < first + count))
        kii, mii, cii = (a[p.inner][:, p.inner] for a in (k, m, c))
        e = np.zeros((p.inner.size, rows.size))
        e[rows, np.arange(rows.size)] = 1.0
        solver = spd_solver(kii)
        x0 = np.asarray(solver.solve(e))
        x1 = np.asarray(solver.solve(cii @ x0))
        x2 = np.asarray(solver.solve(cii @ x1 - mii @ x0))
        inv = 1.0 / g.omega2
        d = g.phi.T @ (cii @ g.phi)
        y0 = inv[:, None] * g.phi[rows].T  # Λ⁻¹Φᵀe
        y1 = inv[:, None] * (d @ y0)  # Λ⁻¹DΛ⁻¹Φᵀe
        y2 = inv[:, None] * (d @ y1) - inv[:, None] * y0  # (Λ⁻¹DΛ⁻¹DΛ⁻¹ − Λ⁻²)Φᵀe
        full = (x0 - g.phi @ y0, -(x1 - g.phi @ y1), x2 - g.phi @ y2)
        out = np.zeros((3, p.inner.size, band + 1))
        rail = np.zeros(p.inner.size, bool)
        rail[rows] = True
        for o, x in zip(out, full):
            for j, r in enumerate(rows):
                hi = min(p.inner.size, r + band + 1)
                o[r, :hi - r] = x[r:hi, j]
            # keep only pairs of rail rows (symmetric: R[r, r + d] from the column of r)
            for dd in range(band + 1):
                partner = np.arange(p.inner.size) + dd
                ok = partner < p.inner.size
                o[~rail, dd] = 0.0
                o[ok & rail, dd] *= rail[partner[ok & rail]]
                o[~ok, dd] = 0.0
        g.residual = out
