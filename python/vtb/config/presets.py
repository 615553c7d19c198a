"""Ready-made configurations.

The numbers of the article's case live in the Rust core (``rust/src/presets.rs``); this
module turns them into :class:`~vtb.config.Config` objects and adds the Python-side
irregularity. Every choice the article leaves open is documented in ``docs/model-choices.md``.
"""

from __future__ import annotations

import math
from typing import Optional, Sequence

from . import gateway
from ..errors import config_error
from .fields import TIDs, Config, Coupling, Layer, MovingForce, Output, RayleighCoefficients, Solver, Structure, Vehicle
from .irregularity import Irregularity
from .trains import train

#: Seed of the paper preset's irregularity sample.
PAPER_SEED = 2025
#: The article's uncontrolled rail acceleration amplitude (m/s², §3.3), the one number the
#: calibrated preset is fitted to (the article does not state its irregularity level).
ARTICLE_RAIL_ACC = 1005.6
#: Amplitude scale of the TB/T 3352 sample that gives ARTICLE_RAIL_ACC with the default
#: discretisation (``calibrate_irregularity(paper_config())``; docs/reproduction/report.md).
PAPER_CALIBRATED_SCALE = 9.704


def paper_irregularity(seed: int = PAPER_SEED, scale: float = 1.0) -> Irregularity:
    """The paper preset's irregularity: the TB/T 3352 vertical spectrum extrapolated to the
    0.01–1 m band (the article: "based on the standard Chinese spectrum"), inverse-FFT sample,
    1 mm sampling, run whole on every model (``beyond_band="keep"``: the article's excitation as
    published, which reaches beyond the band its own model resolves)."""
    return Irregularity(kind="tbt3352", wavelength_min=0.01, wavelength_max=1.0, method="ifft", seed=seed, dx=0.001, scale=scale,
                        beyond_band="keep")


#: Discretisations of :func:`paper_config`: the article's own, and the converged one.
PAPER_MODELS = ("article", "converged", "fast", "deck")

#: The deck grade's irregularity: the long-wave German spectrum over the wavelengths its 150 Hz
#: band takes at the article's 80 m/s (v/λ ≤ 80 Hz), the longest an eighth of its 160 m.
DECK_IRREGULARITY = {"kind": "german_low", "wavelength_min": 1.0, "wavelength_max": 20.0}


def paper_config(seed: int = PAPER_SEED, calibrated: bool = False, model: str = "article") -> Config:
    """The article's §3.3 validation case (Appl. Sci. 2025, 15, 8675).

    Table 1 track–bridge: rail (one CHN60 rail with its fasteners every 0.64 m) on a CRTS II
    slab, base layer and five 32 m spans continuous over rigid piers (k = 1e15 N/m), 160 m in
    all; the article's hybrid FE–SEA discretisation: rail 120 global + 100 local sines, slab
    120, base 120, girder 50, each plus 4 boundary functions, ω_r at the centre of the
    irregularity band (800 Hz); one CRH3 trailer car (parameter set A) whose rear wheelset starts
    1 m onto the bridge; 80 m/s; Newmark Δt = 5e−5 s until the leading wheelset is 1 m from
    the end (34 531 steps); observation at mid-length; TB/T 3352 irregularity 0.01–1 m.
    ``calibrated=True`` scales the irregularity by :data:`PAPER_CALIBRATED_SCALE` so that the
    uncontrolled rail acceleration amplitude is the article's 1005.6 m/s².

    ``model="converged"``: the same structure, vehicle, excitation and run on the converged
    discretisation (docs/validation.md, docs/track-models.md): a Timoshenko rail
    (G = 8.1e10 Pa, κ = 0.4) in finite elements at 20 per fastener bay (0.032 m) with the
    element flexibility under the wheels, slab, base and girder at 0.32 m, nodes on every
    fastener and pier, Δt = 2.5e-5 s. Its element-passing frequency v/h is 2.5 kHz at 80 m/s, above the band
    it is converged in (rail acceleration up to 2 kHz); at lower speeds refine the rail so that
    v/h stays above 2.5 kHz. Its wheels rest on their Hertz contact patches
    (``vehicles[0].contact_patch``) and its acceleration indices are band-limited at 2 kHz
    (``output.band_limit``; the raw peak stays as ``rail_acc_max_raw``), the band it is verified
    and converged in (docs/contact-patch.md). The article's model (the default)
    is not converged in the rail's 0.3–2 kHz band; use the converged one for rail vibration
    and damper design.

    ``model="fast"``: the converged model run by complex-modal synthesis (:mod:`vtb.run.synthesis`,
    docs/synthesis.md): its finite elements reduced once to the complex modes below 4 kHz plus
    the rail's residual (cached on disk), each mode stepped exactly at Δt = 5e-5 s. It
    is verified against the converged model (rail and slab indices within 3 %) at a fraction
    of its cost; the first run builds the reduction (about two and a half minutes). It is the
    **rail grade**: rail vibration and damper design.

    ``model="deck"``: the **deck grade** — the converged structure and car on the substructured
    engine (:mod:`vtb.run.substructures`, docs/substructures.md): each substructure's
    fixed-interface modes below 1 200 Hz and the DOFs on the cuts, Newmark at Δt = 1e-4 s, the
    acceleration indices band-limited at 150 Hz, under the long-wave German spectrum
    (:data:`DECK_IRREGULARITY`, 1–20 m; ``calibrated`` does not apply). Deck, ride comfort
    and contact force, for long viaducts and trains (re-span it with :func:`vtb.spans` and
    :func:`vtb.track_zones`); not the rail's vibration.
    """
    if model not in PAPER_MODELS:
        raise config_error("model", model, f"must be one of {PAPER_MODELS}")
    cfg = Config.from_dict(gateway.preset({"article": "paper", "converged": "paper_converged", "fast": "paper_fast", "deck": "paper_deck"}[model]))
    if model == "deck":
        cfg.irregularity = Irregularity(seed=seed, **DECK_IRREGULARITY)
    else:
        cfg.irregularity = paper_irregularity(seed, PAPER_CALIBRATED_SCALE if calibrated else 1.0)
    # ω_r follows the irregularity band and speed (800 Hz here) when either is changed.
    cfg.discretisation.omega_r = None
    return cfg


#: Default number of dampers: one per fastener bay over the ten bays centred on the
#: observation point (docs/model-choices.md).
TID_COUNT = 10


def tids_around(config: Config, inertance: float = 5.0, stiffness: float = 2e8, damping: float = 1e3, count: int = TID_COUNT, x: Optional[float] = None) -> TIDs:
    """``count`` rail–slab TIDs, one in the middle of each fastener bay, over the bays centred
    on ``x`` (default: the first observation point, else mid-length). The defaults of b_t,
    k_t, c_t are the article's best sweep case (5 kg, 2e8 N/m, 1e3 N·s/m).

    The article states neither the number nor the spacing of its TIDs; rail vibration near
    1 kHz decays within a few metres along the fastened rail, so dampers beyond ±3 m of the
    observation point change the rail amplitude there by under 1 % (10 → 50 dampers) while
    each damper adds to every time step."""
    rail = config.structure.layers[0].name
    fast = next((c for c in config.structure.couplings if c.upper == rail and c.kind == "discrete"), None)
    if fast is None or len(fast.positions) < 2:
        raise config_error("structure.couplings", "[…]", "tids_around needs discrete fasteners under the top layer")
    pos = sorted(fast.positions)
    bays = len(pos) - 1
    if isinstance(count, bool) or not isinstance(count, int) or not 1 <= count <= bays:
        raise config_error("count", count, f"must be a whole number of bays, 1 … {bays}")
    if x is None:
        x = config.output.points[0] if config.output.points else config.structure.length / 2
    if not (isinstance(x, (int, float)) and math.isfinite(x) and pos[0] <= x <= pos[-1]):
        raise config_error("x", x, f"must lie on the fastened rail, {pos[0]:g} ≤ x ≤ {pos[-1]:g} m")
    spacing = pos[1] - pos[0]
    # Bays [pos[j], pos[j+1]]: the one containing x, then count bays centred on it; dampers
    # that would not fit are refused, never moved.
    j = min(range(bays), key=lambda i: abs(0.5 * (pos[i] + pos[i + 1]) - x))
    first = j - count // 2 + (1 if x >= 0.5 * (pos[j] + pos[j + 1]) else 0)
    if first < 0 or first + count > bays:
        lo, hi = pos[count // 2], pos[bays - count + count // 2]
        raise config_error("x", x, f"{count} dampers centred here would reach beyond the fastened rail "
                           f"[{pos[0]:g}, {pos[-1]:g}] m: centre them within about [{lo:g}, {hi:g}] m or use fewer")
    return TIDs(inertance=inertance, stiffness=stiffness, damping=damping, count=count, x0=0.5 * (pos[first] + pos[first + 1]), spacing=spacing, upper=rail, lower=config.structure.layers[1].name)


def crh3_car(x_front: float, motor: bool = False) -> Vehicle:
    """A CRH3 car, parameter set A (trailer, or motor car), leading wheelset at ``x_front``."""
    v = train("crh3", cars=2)[1 if motor else 0]  # the formation starts trailer, motor
    v.x_front = x_front
    return v


def moving_load_config(
    length: float,
    density: float,
    area: float,
    youngs_modulus: float,
    inertia: float,
    forces: Sequence[MovingForce],
    speed: float,
    supports: str = "simply_supported",
    support_stiffness: float = 0.0,
    support_damping: float = 0.0,
    support_spacing: Optional[float] = None,
    modes: int = 50,
    dt: Optional[float] = None,
    t_end: Optional[float] = None,
    points: Sequence[float] = (),
    damping: Optional[RayleighCoefficients] = None,
    initial_state: str = "static",
) -> Config:
    """A single beam under constant moving forces (bridge checks; no vehicle).

    ``supports``: ``"simply_supported"`` (rigid point supports at both ends),
    ``"winkler"`` (continuous elastic foundation ``support_stiffness`` N/m² with damping) or
    ``"discrete"`` (springs of ``support_stiffness`` N/m every ``support_spacing`` m).

    ``initial_state``: ``"static"`` (default) starts the structure at rest in equilibrium under
    the forces at their start positions. A force entering over a support (``x0 = 0`` on a
    simply supported beam) is carried by that support, so this is Frýba's start — the beam
    undeformed and at rest — up to the support's compression (about 1e−6 of the midspan
    deflection). ``"rest"`` starts undeformed with the forces applied suddenly: a step on the
    stiff supports, whose mode (ω·Δt ≫ 1) the undamped Newmark scheme never lets go of, so
    the accelerations carry that start for the whole run (docs/model-choices.md).

    Values beyond a railway's plausible ranges (an academic speed ratio v/v_cr above
    150 m/s, a beam given as EI with I = 1) are refused as likely unit mistakes unless listed
    in ``accept_implausible`` of the returned configuration (docs/limits.md).
    """
    if supports == "simply_supported":
        # Point supports 10⁶ times stiffer than the beam's midspan stiffness 48EI/L³: the end
        # deflection then changes the midspan response by about 1e−6.
        couplings = [Coupling("beam", "ground", "discrete", 1e6 * 48.0 * youngs_modulus * inertia / length**3, 0.0, [0.0, length])]
    elif supports == "winkler":
        couplings = [Coupling("beam", "ground", "continuous", support_stiffness, support_damping)]
    elif supports == "discrete":
        if support_spacing is None:
            raise config_error("support_spacing", None, "needed for discrete supports")
        couplings = [Coupling.grid("beam", "ground", support_stiffness, support_damping, support_spacing, length)]
    else:
        raise config_error("supports", supports, "must be \"simply_supported\", \"winkler\" or \"discrete\"")
    layer = Layer("beam", density, area, youngs_modulus, inertia, modes, damping or RayleighCoefficients(0.0, 0.0))
    solver = Solver(initial_state=initial_state, t_end=t_end)
    if dt is not None:
        solver.dt = dt
    return Config(structure=Structure(length, [layer], couplings), speed=speed, forces=list(forces), solver=solver, output=Output(list(points)))


def _example_files() -> dict:
    from importlib.resources import files

    return {p.name[: -len(".toml")]: p for p in files("vtb").joinpath("examples").iterdir() if p.name.endswith(".toml")}


def examples() -> dict:
    """The example configurations shipped with the package (``vtb/examples/*.toml``): name →
    the first paragraph of the file's header comment."""
    out = {}
    for name, p in sorted(_example_files().items()):
        lines = []
        for line in p.read_text().splitlines():
            if line.rstrip() == "#" or not line.startswith("#"):
                break
            lines.append(line[1:].strip())
        out[name] = " ".join(lines)
    return out


def example_text(name: str) -> str:
    """The TOML text of a shipped example (header comments included)."""
    files = _example_files()
    if name not in files:
        raise config_error("example", name, f"no such example; shipped: {', '.join(sorted(files))}")
    return files[name].read_text()


def example_config(name: str) -> Config:
    """A shipped example configuration (see :func:`examples`), e.g. ``"article"``: the
    article's case with the calibrated irregularity, as ``vtb simulate --config article``."""
    return Config.from_toml_text(example_text(name))
