"""Complex-modal synthesis of a finite-element structure (docs/synthesis.md).

The track and bridge are linear and the same in every job of a study; only the wheel
contacts and the dampers are not, and they touch the structure at a few points. The
reduction of this module is therefore computed once per structure and reused:

* the complex (state-space) modes of the damped structure, (λ²M + λC + K)ψ = 0, with
  modulus below 2π·f_c (one of each conjugate pair), by Rayleigh–Ritz: the undamped modes up to
  :data:`BASIS_RATIO`·f_c (Sturm-checked spectrum slicing) and the static attachment vectors
  K⁻¹·(s_upper − s_lower) of every discrete dashpot (the fasteners), less their modal part,
  span the subspace; M, C and K are projected in full and the projected quadratic problem is
  solved exactly. The layers' Rayleigh damping and every discrete dashpot enter C exactly;
  nothing is diagonalised. Modes are normalised so that ψᵀ(2λM + C)ψ = 1, which makes each
  modal coordinate obey q̇ = λq + ψᵀf;
* the residual of the rail: the truncated modes' part of the receptance H(s) = (K + sC +
  s²M)⁻¹ expanded about s = 0, R(s) = R₀ + sR₁ + s²R₂, each R_k the full model's moment less the
  kept modes': R₀ = K⁻¹ − G₀, R₁ = −K⁻¹CK⁻¹ − G₁, R₂ = K⁻¹CK⁻¹CK⁻¹ − K⁻¹MK⁻¹ − G₂, with
  G_k = −Σ w·Re(ψψᵀ/λ^(k+1)) (w = 2 for a pair, 1 for a real mode), each stored as a band over
  the rail's DOFs. Under a wheel anywhere on an element, sᵀ(G₀ + R₀)s = sᵀK⁻¹s exactly, because
  s is the element's own shape vector. The engine realises the residual under a load as a
  passive second-order filter with the same three moments (docs/synthesis.md, "The dynamic
  residual"): the static residual alone leaves the point receptance over a fastener 1.5 % low
  at 2 kHz with a 4 kHz cut-off, the filter within 0.2 %.

The reduction is cached on disk (:func:`cache_dir`) keyed by everything it depends on, and
kept in memory for the process.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import math
import os
import sys
import tempfile
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import scipy.linalg
import scipy.sparse as sp
from threadpoolctl import threadpool_limits

from ..analysis.eigen import (SYNTHESIS_BASIS_RATIO, SYNTHESIS_RESIDUAL_REACH, SYNTHESIS_RESIDUAL_TAPER, SYNTHESIS_STEP_REACH,
                              EigshFailed, assemble, checked_frequencies, checked_positions, core_reduction, fix_signs, layer_index,
                              shape_matrix, sliced_eigsh, spd_solver, structure_estimate)
from ..config.fields import Config, Discretisation, Solver, structure_json
from ..errors import SolverError, config_error
from ..optim.checkpoint import clean_stale_temps

#: Version of the reduction's algorithm and file layout: part of every cache key.
FORMAT = 2
#: Environment variable that overrides the cache folder.
CACHE_ENV = "VTB_CACHE_DIR"
# The reduction's geometry lives in the core (rust/src/model/resolution.rs says why each
# value): the Ritz basis reaches BASIS_RATIO·f_c; the stored residual reaches RESIDUAL_REACH
# (m), whole to RESIDUAL_TAPER and faded out beyond; the modes' step compliance reaches
# STEP_REACH (m).
BASIS_RATIO = SYNTHESIS_BASIS_RATIO
RESIDUAL_REACH = SYNTHESIS_RESIDUAL_REACH
RESIDUAL_TAPER = SYNTHESIS_RESIDUAL_TAPER
STEP_REACH = SYNTHESIS_STEP_REACH


def cache_dir() -> Path:
    """The folder of cached reductions: ``$VTB_CACHE_DIR`` if set, else the platform's user
    cache folder (``$XDG_CACHE_HOME/vtb`` or ``~/.cache/vtb`` on Linux, ``~/Library/Caches/vtb``
    on macOS, ``%LOCALAPPDATA%\\vtb\\Cache`` on Windows)."""
    env = os.environ.get(CACHE_ENV)
    if env:
        return Path(env)
    home = Path.home()
    if os.name == "nt":
        return Path(os.environ.get("LOCALAPPDATA", home / "AppData" / "Local")) / "vtb" / "Cache"
    if os.uname().sysname == "Darwin":
        return home / "Library" / "Caches" / "vtb"
    return Path(os.environ.get("XDG_CACHE_HOME", home / ".cache")) / "vtb"




# ---------------------------------------------------------------------------- the reduction
@dataclass
class Reduction:
    """A structure's reduction: ``lam`` (complex, s⁻¹), ``psi`` (n_dofs × n_modes, complex,
    ψᵀ(2λM + C)ψ = 1), ``weight`` (2 for a pair, 1 for a real mode), the rail residual's
    moments R₀, R₁, R₂ as bands ``residual`` (3 × rail_dofs × (band + 1); m/N, m·s/N, m·s²/N),
    ``key`` (what it was built from), the build
    time ``seconds`` and, once handed to the core, ``core`` (the :class:`vtb._core.Reduction`).
    ψ then lives in the core alone (``psi`` is ``None``; :meth:`project` reads it there), so
    that a process holds one copy of it, not two."""

    key: str
    cutoff: float
    lam: np.ndarray
    psi: np.ndarray
    weight: np.ndarray
    rail_dofs: int
    band: int
    residual: np.ndarray
    seconds: float
    basis_modes: int
    attachments: int
    core: object = None

    @property
    def n_modes(self) -> int:
        return int(self.lam.size)

    nbytes: int = field(init=False, repr=False)
    """Memory of the arrays as built or loaded (bytes); the core's copy is the same size."""

    def __post_init__(self):
        self.nbytes = int(self.psi.nbytes + self.lam.nbytes + self.weight.nbytes + self.residual.nbytes)

    def to_core(self):
        """The core's copy (made once); ψ is then dropped here."""
        if self.core is None:
            step_band = min(self.band, math.ceil(self.band * STEP_REACH / RESIDUAL_REACH))
            self.core = core_reduction(self.lam, self.weight, self.psi, self.rail_dofs, self.band, step_band, self.residual)
            self.psi = None
        return self.core

    def project(self, shapes: np.ndarray) -> np.ndarray:
        """sᵀψ (complex, per mode) for a shape vector over the DOFs (n_dofs,), or for each
        column of shapes (n_dofs, k) → (k, n_modes); only the rows of ψ they touch are read."""
        s = shapes.reshape(shapes.shape[0], -1)
        rows = np.flatnonzero(np.any(s != 0.0, axis=1))
        re, im = self.to_core().psi_rows(rows.tolist())
        out = s[rows].T @ (re + 1j * im)
        return out[0] if shapes.ndim == 1 else out


def _structure_config(config: Config) -> Config:
    """The structure the reduction is of: the configuration without its dampers (they are
    physical elements on the reduced structure) and without the synthesis switch."""
    if not isinstance(config, Config):
        raise config_error("config", type(config).__name__, "expected a vtb.Config")
    c = config.copy()
    c.dampers = []
    c.discretisation.synthesis_cutoff = None
    return c


#: The discretisation's fields added since the cache format, with their defaults.
_ADDED = {"excitation_wavelengths": None}


def cache_key(config: Config) -> str:
    """The hex digest of everything a reduction depends on: the structure and discretisation
    (not the dampers, vehicles, excitation or solver), the cut-off, the basis ratio, the
    residual reach and the format."""
    cutoff = config.discretisation.synthesis_cutoff
    if cutoff is None:
        raise config_error("discretisation.synthesis_cutoff", None, "the configuration does not ask for the synthesis")
    structure = json.loads(structure_json(_structure_config(config)))
    structure.pop("accept_implausible", None)  # an opt-out changes no matrix
    # The neutral loads, solver and outputs the structure is assembled with are constants; left
    # in, every field added to them would orphan every cached reduction.
    for neutral in ("vehicles", "forces", "speed", "solver", "output"):
        structure.pop(neutral, None)
    # Fields the discretisation gained after this format, at their default, change no matrix.
    for name, default in _ADDED.items():
        if structure["discretisation"].get(name) == default:
            structure["discretisation"].pop(name)
    text = json.dumps({"format": FORMAT, "structure": structure,
                       "cutoff": float(cutoff), "basis_ratio": BASIS_RATIO, "reach": RESIDUAL_REACH,
                       "taper": RESIDUAL_TAPER}, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()


def _attachments(system, config: Config) -> np.ndarray:
    """n × a: s_upper − s_lower at every point of a discrete coupling with a dashpot
    (s_upper alone on the ground)."""
    cols = []
    for c in config.structure.couplings:
        if c.kind != "discrete" or not c.damping or not c.positions:
            continue
        xs = np.asarray(c.positions, float)
        up = shape_matrix(system, layer_index(system, c.upper), xs)
        cols.append(up if c.lower == "ground" else up - shape_matrix(system, layer_index(system, c.lower), xs))
    if not cols:
        return np.zeros((system.n, 0))
    return sp.hstack(cols).toarray()


def build(config: Config, progress=None) -> Reduction:
    """Computes the reduction of ``config``'s structure (no cache; see :func:`reduction`).
    ``progress``: ``f(stage, fraction)`` called as the build goes, stage 0 (the undamped modes),
    1 (the projected quadratic eigenproblem) or 2 (the rail residual) and the fraction of that
    stage done.

    Deterministic: the same configuration gives the same bits in every process. The eigensolver
    starts from a fixed vector, every mode's sign is fixed (:func:`vtb.analysis.eigen.fix_signs`)
    and the dense algebra runs on one BLAS thread: OpenBLAS splits its sums by thread count, so
    two threads and one gave reductions differing in the last bits."""
    with threadpool_limits(limits=1):
        return _build(config, progress)


def _build(config: Config, progress=None) -> Reduction:
    t0 = time.perf_counter()
    cfg = _structure_config(config)
    if cfg.discretisation.method != "fem":
        raise config_error("discretisation.method", cfg.discretisation.method, "the synthesis reduces a finite-element structure (\"fem\")")
    cutoff = float(config.discretisation.synthesis_cutoff)
    if not (math.isfinite(cutoff) and cutoff > 0):
        raise config_error("discretisation.synthesis_cutoff", cutoff, "must be a finite cut-off > 0 (Hz)")
    note = progress or (lambda _stage, _fraction: None)
    system = assemble(cfg)
    m, k, c = system.m.tocsc(), system.k.tocsc(), system.c.tocsc()
    hi = (2 * math.pi * BASIS_RATIO * cutoff) ** 2
    note(0, 0.0)
    try:
        # the slices' progress: the part of the band's frequencies covered
        w2, phi = sliced_eigsh(k, m, -1e-6 * hi, hi, lambda b: note(0, math.sqrt(max(b, 0.0) / hi)))
    except EigshFailed:
        raise SolverError("synthesis: the undamped eigensolver failed") from None
    solver = spd_solver(k)  # K is symmetric positive definite
    # Attachment vectors of the dashpots, less what the modes already hold (static part).
    b = _attachments(system, cfg)
    if b.shape[1]:
        x = solver.solve(b)
        x -= phi @ ((phi.T @ b) / w2[:, None])
        x -= phi @ (phi.T @ (m @ x))
        q, r = np.linalg.qr(x)
        q = q[:, np.abs(np.diag(r)) > 1e-12 * np.abs(np.diag(r)).max()]
        basis = np.hstack([phi, q])
    else:
        basis = phi
    note(1, 0.0)
    mr, kr, cr = (basis.T @ (a @ basis) for a in (m, k, c))
    p = basis.shape[1]
    minv = scipy.linalg.cho_solve(scipy.linalg.cho_factor(mr), np.eye(p))
    companion = np.block([[np.zeros((p, p)), np.eye(p)], [-minv @ kr, -minv @ cr]])
    lam, z = scipy.linalg.eig(companion, overwrite_a=True, check_finite=False)
    w_cut = 2 * math.pi * cutoff
    real = np.abs(lam.imag) <= 1e-9 * np.abs(lam)
    lam = np.where(real, lam.real + 0j, lam)
    keep = (np.abs(lam) < w_cut) & (lam.imag >= 0)
    lam, z = lam[keep], z[:p, keep]
    if np.any(lam.real >= 0):
        raise SolverError(f"synthesis: {int(np.sum(lam.real >= 0))} projected modes are not damped (Re λ ≥ 0)")
    order = np.lexsort((lam.imag, np.abs(lam)))
    lam, psi = lam[order], basis @ z[:, order]
    a = np.einsum("ij,ij->j", psi, 2.0 * lam[None, :] * (m @ psi) + c @ psi)
    psi = fix_signs(psi / np.sqrt(a)[None, :])  # the normalisation leaves a sign: fix it
    weight = np.where(lam.imag == 0, 1.0, 2.0)
    note(2, 0.0)
    rail = system.layers[0][2]
    band = max(1, int(math.ceil(RESIDUAL_REACH * rail / system.length)))
    residual = _rail_residual(solver, c, m, psi, lam, weight, rail, band, system.n, lambda f: note(2, f))
    residual *= _taper(band, system.length / rail)[None, None, :]
    note(2, 1.0)
    return Reduction(cache_key(config), cutoff, lam, psi, weight, rail, band, residual,
                     time.perf_counter() - t0, int(phi.shape[1]), int(basis.shape[1] - phi.shape[1]))


def _taper(band: int, spacing: float) -> np.ndarray:
    """The residual's weight at each DOF offset 0…band, ``spacing`` metres per DOF offset: 1 up
    to RESIDUAL_TAPER, a raised cosine down to 0 at RESIDUAL_REACH."""
    ramp = np.clip((np.arange(band + 1) * spacing - RESIDUAL_TAPER) / (RESIDUAL_REACH - RESIDUAL_TAPER), 0.0, 1.0)
    return 0.5 * (1.0 + np.cos(np.pi * ramp))


def _rail_residual(solver, c, m, psi, lam, weight, rail: int, band: int, n: int, done=None, chunk: int = 512) -> np.ndarray:
    """R_k[i, d] = (F_k − G_k)[i, i + d] for rail DOFs i, 0 ≤ d ≤ band (zero past the rail), k =
    0, 1, 2: the moments F₀ = K⁻¹, F₁ = −K⁻¹CK⁻¹, F₂ = K⁻¹CK⁻¹CK⁻¹ − K⁻¹MK⁻¹ of the full model
    less the kept modes' G_k = −Σ w·Re(ψψᵀ/λ^(k+1))."""
    out = np.zeros((3, rail, band + 1))
    for a in range(0, rail, chunk):
        b = min(rail, a + chunk)
        e = np.zeros((n, b - a))
        e[np.arange(a, b), np.arange(b - a)] = 1.0
        x0 = solver.solve(e)
        x1 = solver.solve(c @ x0)
        moments = (x0, -x1, solver.solve(c @ x1 - m @ x0))
        hi = min(rail, b + band)
        for k, x in enumerate(moments):
            scaled = psi[a:b] * (weight / lam ** (k + 1))[None, :]
            full = x[a:hi] + np.real(psi[a:hi] @ scaled.T)  # (rows a..hi) × (cols a..b)
            for d in range(band + 1):
                i = np.arange(a, min(b, rail - d))
                out[k, i, d] = full[i - a + d, i - a]
        if done is not None:
            done(b / rail)
    return out


#: Reductions built or loaded in this process, by key.
_MEMORY: dict = {}


def _path(key: str) -> Path:
    return cache_dir() / f"reduction-{key[:32]}.npz"


def _save(red: Reduction, path: Path) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    # A write a SIGKILL cut short leaves its temporary file: the next save clears those of dead writers.
    clean_stale_temps(path.parent, ".reduction.")
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".reduction.{os.getpid()}.", suffix=".tmp")
    os.close(fd)
    try:
        with open(tmp, "wb") as f:
            np.savez(f, key=np.array(red.key), format=np.array(FORMAT), cutoff=red.cutoff, lam=red.lam, psi=red.psi,
                     weight=red.weight, rail_dofs=red.rail_dofs, band=red.band, residual=red.residual,
                     seconds=red.seconds, basis_modes=red.basis_modes, attachments=red.attachments)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def _load(path: Path, key: str):
    """The cached reduction at ``path``, or (None, reason) when it is missing, stale or corrupt."""
    if not path.exists():
        return None, "not cached"
    try:
        with np.load(path, allow_pickle=False) as d:
            if int(d["format"]) != FORMAT or str(d["key"]) != key:
                return None, "stale (built for another structure or version)"
            red = Reduction(key, float(d["cutoff"]), d["lam"], d["psi"], d["weight"], int(d["rail_dofs"]), int(d["band"]),
                            d["residual"], float(d["seconds"]), int(d["basis_modes"]), int(d["attachments"]))
    except Exception as e:  # a truncated or foreign file
        return None, f"corrupt ({type(e).__name__}: {e})"
    if not (np.all(np.isfinite(red.psi)) and np.all(np.isfinite(red.residual)) and red.psi.shape == (red.psi.shape[0], red.lam.size)):
        return None, "corrupt (non-finite or misshapen arrays)"
    return red, "cached"


def in_memory(config: Config) -> bool:
    """Whether this process holds the reduction of ``config``'s structure."""
    return cache_key(config) in _MEMORY


def check_build(config: Config) -> None:
    """Before anything else of a run: when ``config``'s reduction is neither in this process
    nor in the cache, its build's estimate against ``solver.memory_budget`` (a
    :class:`~vtb.ConfigError` naming it), so that a build beyond the budget is refused before
    even the irregularity is sampled."""
    if not (isinstance(config.discretisation, Discretisation) and isinstance(config.solver, Solver)):
        return  # a part of the wrong type is named by the run's own checks
    if config.discretisation.synthesis_cutoff is None or config.discretisation.method != "fem":
        return
    key = cache_key(config)
    if key not in _MEMORY and not _path(key).exists():
        estimate(config, check=True)


def estimate(config: Config, check: bool = False) -> dict:
    """The core's estimate of what building ``config``'s reduction costs, from the
    configuration alone (docs/synthesis.md, "Before a build"): ``dofs``, ``basis_modes`` (a
    bound), ``attachments``, ``modes`` (kept), peak ``bytes``, ``seconds`` on one core and the
    ``stages``' seconds. ``check``: a build beyond ``solver.memory_budget`` raises
    :class:`~vtb.ConfigError` naming it, with the estimate."""
    return structure_estimate(config.to_core_json(), check)


def reduction(config: Config, progress="auto") -> Reduction:
    """The reduction of ``config``'s structure at its ``discretisation.synthesis_cutoff``:
    from this process's memory, else from the disk cache (:func:`cache_dir`), else built
    (:func:`build`) and cached. A cached file that is stale or corrupt is refused (with a
    warning naming why) and rebuilt. Its core copy is made once. Refused with a
    :class:`~vtb.ConfigError` naming ``solver.memory_budget`` when the reduction (its arrays and
    the core's copy) exceeds the configuration's budget, and, before a build starts, when the
    build's estimated memory (:func:`estimate`) does.

    A build announces itself on stderr with its estimated time and memory, and shows a tqdm bar
    of its stages (``progress``: ``"auto"`` the bar on a terminal only, ``True`` anywhere,
    ``False`` neither the bar nor the announcement). Processes that need the same reduction
    build it once: the first holds a lock file beside the cache file (:func:`build_lock`), the
    others wait for it (saying so) and load its file."""
    key = cache_key(config)
    if key in _MEMORY:
        return _within_budget(_MEMORY[key], config)
    path = _path(key)
    red, why = _load(path, key)
    if red is None:
        if why != "not cached":
            warnings.warn(f"the cached reduction {path} is {why}: rebuilding it", stacklevel=2)
        guess = estimate(config, check=True)  # refused here, before anything is built
        say = _say if progress is not False else (lambda _msg: None)
        with build_lock(path, say):
            red, _ = _load(path, key)  # another process built it while this one waited
            if red is None:
                red = _announced_build(config, path, guess, progress)
                try:
                    _save(red, path)
                except OSError as e:
                    warnings.warn(f"could not cache the reduction at {path} ({e})", stacklevel=2)
    _within_budget(red, config)
    red.to_core()
    _MEMORY[key] = red
    return red


def _say(msg: str) -> None:
    print(f"vtb: {msg}", file=sys.stderr, flush=True)


def _announced_build(config: Config, path: Path, guess: dict, progress) -> Reduction:
    """:func:`build`, announced on stderr with the estimate and followed by a tqdm bar whose
    total is the estimated time (s), each stage advancing it by its estimated share."""
    quiet = progress is False
    if not quiet:
        _say(f"building the synthesis reduction of this structure once (about {guess['dofs']:.0f} DOFs, cut-off "
             f"{config.discretisation.synthesis_cutoff:g} Hz, about {guess['modes']:.0f} modes): estimated "
             f"{_duration(guess['seconds'])} and {guess['bytes'] / 1e9:.2g} GB; later runs load it from {path}")
    show = progress is True or (progress == "auto" and hasattr(sys.stderr, "isatty") and sys.stderr.isatty())
    if not show:
        return build(config)
    from tqdm.auto import tqdm

    stages = [max(float(x), 1e-3) for x in guess["stages"]]
    starts = np.concatenate(([0.0], np.cumsum(stages)))
    names = ("undamped modes", "projected eigenproblem", "rail residual")
    total = float(starts[-1])
    with tqdm(total=total, desc="vtb reduction", unit="s est.", file=sys.stderr,
              bar_format="{desc}: {percentage:3.0f}%|{bar}| {elapsed}<{remaining} {postfix}") as bar:
        def note(stage: int, fraction: float) -> None:
            bar.set_postfix_str(names[stage], refresh=False)
            target = min(total, float(starts[stage] + min(max(fraction, 0.0), 1.0) * stages[stage]))
            bar.update(max(0.0, target - bar.n))

        red = build(config, note)
        bar.update(max(0.0, total - bar.n))
    return red


def _duration(seconds: float) -> str:
    return f"{seconds:.0f} s" if seconds < 120 else f"{seconds / 60:.0f} min" if seconds < 7200 else f"{seconds / 3600:.1f} h"


#: Seconds between two tries of a held build lock.
LOCK_POLL = 0.1


@contextlib.contextmanager
def build_lock(path: Path, say=_say):
    """Holds the build lock of the cache file ``path`` (``path`` with the suffix ``.lock``, an
    advisory lock of the operating system, released when its process ends however it ends)
    while the block runs; waits, saying so once through ``say``, while another process holds
    it. Where the lock file cannot be made (a read-only cache), the block runs without it."""
    lock = path.with_suffix(".lock")
    try:
        lock.parent.mkdir(parents=True, exist_ok=True)
        f = open(lock, "a+")
    except OSError as e:
        warnings.warn(f"could not open the build lock {lock} ({e}): building without it", stacklevel=3)
        yield
        return
    try:
        waited = False
        while not _try_lock(f):
            if not waited:
                f.seek(0)
                holder = f.read().strip() or "another process"
                say(f"waiting for {holder} building this reduction (lock {lock}) …")
                waited = True
            time.sleep(LOCK_POLL)
        f.seek(0)
        f.truncate()
        f.write(f"process {os.getpid()}\n")
        f.flush()
        yield
    finally:
        _unlock(f)
        f.close()


def _try_lock(f) -> bool:
    try:
        if os.name == "nt":
            import msvcrt

            f.seek(0)
            msvcrt.locking(f.fileno(), msvcrt.LK_NBLCK, 1)
        else:
            import fcntl

            fcntl.flock(f.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        return True
    except OSError:
        return False


def _unlock(f) -> None:
    try:
        if os.name == "nt":
            import msvcrt

            f.seek(0)
            msvcrt.locking(f.fileno(), msvcrt.LK_UNLCK, 1)
        else:
            import fcntl

            fcntl.flock(f.fileno(), fcntl.LOCK_UN)
    except OSError:
        pass


def _within_budget(red: Reduction, config: Config) -> Reduction:
    """``red``, or a ConfigError when it and its core copy exceed ``solver.memory_budget``."""
    need = 2 * red.nbytes
    if need > config.solver.memory_budget:
        raise config_error("solver.memory_budget", config.solver.memory_budget,
                           f"the synthesis reduction of this structure needs {need / 1e9:.3g} GB while it loads ({red.n_modes} modes' "
                           f"arrays and the core's copy); raise the budget or lower discretisation.synthesis_cutoff")
    return red


def receptance(config: Config, x: float, frequencies, response_x=None) -> np.ndarray:
    """The rail's point (or transfer) receptance (m/N) of the synthesis model of ``config``:
    Σ_j w-paired ψ_j(x_r)ψ_j(x)/(iω − λ_j) + R₀(x_r, x)·h_x(iω), the residual through the
    filter of the load point x as the engine steps it (docs/synthesis.md), the same
    quantity :func:`vtb.receptance` computes from the full finite-element matrices (which it
    verifies, docs/synthesis.md). Shape (n_freq,) or (n_freq, n_points) as there."""
    red = reduction(config)
    system = assemble(_structure_config(config))
    xf, _ = checked_positions(x, system.length, "x")
    freqs = checked_frequencies(frequencies)
    xr, scalar = (xf, True) if response_x is None else checked_positions(response_x, system.length, "response_x")
    sf = shape_matrix(system, 0, xf).toarray()[:, 0]
    sr = shape_matrix(system, 0, xr).toarray()
    pf, pr = red.project(sf), red.project(sr)  # (m,), (n_points, m)
    resid = np.array([_band_form(red.residual[0], red, sr[:, i], sf) for i in range(sr.shape[1])])
    nz = np.flatnonzero(sf[: red.rail_dofs])
    alpha, beta = red.to_core().residual_filter(int(nz[0]), sf[nz[0]: nz[-1] + 1].tolist()) or (0.0, 0.0)
    s = 2j * math.pi * freqs
    iw = s[:, None, None]
    pair = (red.weight == 2.0)[None, None, :]
    term = pr[None, :, :] * pf[None, None, :]
    modal = np.sum(term / (iw - red.lam) + np.where(pair, np.conj(term) / (iw - np.conj(red.lam)), 0.0), axis=2)
    out = modal + resid[None, :] / (1.0 + alpha * s + beta * s * s)[:, None]
    return out[:, 0] if scalar else out


def _band_form(band: np.ndarray, red: Reduction, a: np.ndarray, b: np.ndarray) -> float:
    """aᵀRb for two rail vectors, R a stored residual band (rail_dofs × (band + 1))."""
    total = 0.0
    n = red.rail_dofs
    for d in range(red.band + 1):
        r = band[: n - d, d]
        total += float(np.dot(a[: n - d] * r, b[d:n]))
        if d:
            total += float(np.dot(a[d:n] * r, b[: n - d]))
    return total
