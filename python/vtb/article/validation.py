"""The convergence study: the article's case on every discretisation, measured against a
refined reference, written as a Markdown page.

``vtb validate --out docs/validation.md`` (or :func:`run_study` and :func:`write_report`).

The referee is a Timoshenko rail refined until its acceleration up to 2 kHz stops moving
(:data:`REFERENCE`; the page shows the last refinements against it). Every case is compared
on rail and slab displacement amplitudes, the rail acceleration amplitude after a low-pass at
2 kHz and its one-third-octave band levels (100 Hz–5 kHz), the slab acceleration below
500 Hz, the number of contact losses, and the run time; at the raw and at the calibrated
irregularity level; and on the effect of four named dampers.
"""

from __future__ import annotations

import math
import platform
import time
from concurrent.futures import Executor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Optional

import numpy as np

from ..config.fields import Config
from ..config.presets import PAPER_CALIBRATED_SCALE, paper_config, tids_around
from ..errors import make_folder
from ..run.simulate import Result, simulate
from ..machine import describe
from ..run.indices import A_RM, D_RM, D_SM

#: Band limits (Hz): rail acceleration compared below RAIL_BAND_HZ (where the dampers act),
#: the slab below SLAB_BAND_HZ.
RAIL_BAND_HZ = 2000.0
SLAB_BAND_HZ = 500.0
#: One-third-octave bands (IEC 61260 base-10 centres 10^(n/10) Hz) of the rail acceleration.
BAND_CENTRES = tuple(10.0 ** (n / 10.0) for n in range(20, 38))  # 100 Hz … 5 kHz
BAY = 0.64


@dataclass
class Case:
    """One discretisation of the study: ``label`` and ``make``, which turns the article's
    configuration into this discretisation."""

    label: str
    make: Callable[[Config], Config]
    values: dict = field(default_factory=dict)  #: {(level, design): amplitudes}
    seconds: dict = field(default_factory=dict)  #: {(level, design): run time (s)}


def _fem(rail_per_bay: Optional[int], lower: Optional[float] = BAY, timoshenko: bool = True, flexibility: bool = True, dt: Optional[float] = None, elements: Optional[int] = None):
    def make(cfg: Config) -> Config:
        conv = paper_config(model="converged")
        cfg.discretisation.method = "fem"
        cfg.discretisation.element_flexibility = flexibility
        rail = cfg.structure.layers[0]
        rail.local_modes = 0
        if timoshenko:
            rail.shear_modulus = conv.structure.layers[0].shear_modulus
            rail.shear_coefficient = conv.structure.layers[0].shear_coefficient
        if elements is not None:
            cfg.discretisation.fem_elements = elements
        else:
            rail.element_length = BAY / rail_per_bay
            for layer in cfg.structure.layers[1:]:
                layer.element_length = lower
        if dt is not None:
            cfg.solver.dt = dt
        return cfg

    return make


def _modal(method: str):
    def make(cfg: Config) -> Config:
        cfg.discretisation.method = method
        if method != "hybrid":
            cfg.structure.layers[0].local_modes = 0
        return cfg

    return make


def _converged(flexibility: bool = True, dt: Optional[float] = None, model: str = "converged"):
    def make(cfg: Config) -> Config:
        conv = paper_config(model=model)
        conv.irregularity = cfg.irregularity
        conv.tids = cfg.tids
        # One contact model and one index definition for every case of the study: the base's.
        conv.vehicles = cfg.vehicles
        conv.output.band_limit = cfg.output.band_limit
        conv.discretisation.element_flexibility = flexibility
        if dt is not None:
            conv.solver.dt = dt
        return conv

    return make


#: Label of the refined reference and of the converged preset.
REFERENCE = "reference: Timoshenko 64/bay, lower 0.32 m, Δt = 2.5e-5 s"
CONVERGED = "converged preset"
FAST = "fast preset (synthesis of the converged preset, Δt = 5e-5 s)"
HYBRID = "article hybrid 120+100 (EB)"


def default_cases() -> list[Case]:
    """The article's discretisations, the finite-element meshes in between, the converged
    preset (with and without the element flexibility, and at half the time step), the fast
    preset that runs it by complex-modal synthesis, and the last refinement before the
    reference."""
    return [
        Case(HYBRID, _modal("hybrid")),
        Case("modal 120 (EB)", _modal("modal")),
        Case("FEM 251 uniform (EB)", _fem(None, timoshenko=False, elements=251)),
        Case("FEM 502 uniform (EB)", _fem(None, timoshenko=False, elements=502)),
        Case("FEM EB 8/bay, lower 0.64 m", _fem(8, timoshenko=False)),
        Case("FEM Timoshenko 8/bay, lower 0.64 m", _fem(8)),
        Case("FEM Timoshenko 16/bay, lower 0.32 m", _fem(16, lower=BAY / 2)),
        Case(CONVERGED, _converged()),
        Case(FAST, _converged(model="fast")),
        Case("converged preset, no element flexibility", _converged(flexibility=False)),
        Case("converged preset, Δt = 1.25e-5 s", _converged(dt=1.25e-5)),
        Case("Timoshenko 32/bay, lower 0.32 m, Δt = 2.5e-5 s", _fem(32, lower=BAY / 2, dt=2.5e-5)),
        Case(REFERENCE, _fem(64, lower=BAY / 2, dt=2.5e-5)),
    ]


#: The four named dampers (b_t kg, k_t N/m, c_t N·s/m), ten in the bays around mid-span.
DESIGNS = {
    "article best sweep case": (5.0, 2e8, 1e3),
    "article solution 1": (3.446, 1.20e8, 1750.0),
    "vtb best sweep case": (7.0, 1e8, 1e4),
    "vtb best optimisation": (4.618, 7.46e8, 10.0),
}
#: Cases the dampers are evaluated on.
DESIGN_CASES = (HYBRID, "FEM 251 uniform (EB)", "FEM EB 8/bay, lower 0.64 m", CONVERGED, FAST, REFERENCE)
LEVELS = {"raw": 1.0, "calibrated": PAPER_CALIBRATED_SCALE}


def _low_pass(a: np.ndarray, dt: float, fc: float) -> np.ndarray:
    spec = np.fft.rfft(a)
    spec[np.fft.rfftfreq(len(a), dt) > fc] = 0.0
    return np.fft.irfft(spec, len(a))


def band_mean_squares(a: np.ndarray, dt: float) -> np.ndarray:
    """Mean square of a record in each one-third-octave band of :data:`BAND_CENTRES` (band
    edges fc·10^(±1/20), FFT of the whole record, Parseval: the bands sum to the mean square
    of the record); (m/s²)² for an acceleration."""
    spec = np.abs(np.fft.rfft(a)) ** 2 / len(a) ** 2
    spec[1:] *= 2.0
    f = np.fft.rfftfreq(len(a), dt)
    return np.array([spec[(f >= fc * 10**-0.05) & (f < fc * 10**0.05)].sum() for fc in BAND_CENTRES])


def amplitudes(res: Result) -> dict:
    """The study's quantities (SI units) of one result at its first observation point."""
    m = res.metrics()
    dt = float(res.t[1] - res.t[0])
    ra = res.acceleration("rail")
    sa = res.acceleration("slab")
    ra = ra[:, 0] if ra.ndim > 1 else ra
    sa = sa[:, 0] if sa.ndim > 1 else sa
    return {
        "rail_disp": m[D_RM],
        "slab_disp": m[D_SM],
        "rail_acc": m[A_RM],
        "rail_acc_lp": float(np.abs(_low_pass(ra, dt, RAIL_BAND_HZ)).max()),
        "slab_acc_lp": float(np.abs(_low_pass(sa, dt, SLAB_BAND_HZ)).max()),
        "bands": band_mean_squares(ra, dt).tolist(),
        "contact_losses": len(res.contact_loss),
    }


def _job(case_index: int, level: str, design: Optional[str], base: Config):
    case = default_cases()[case_index] if isinstance(case_index, int) else case_index
    cfg = base.copy()
    cfg.irregularity.scale = LEVELS[level]
    if design is not None:
        b, k, c = DESIGNS[design]
        cfg.tids = tids_around(cfg, b, k, c)
    cfg = case.make(cfg)
    t0 = time.perf_counter()
    res = simulate(cfg, progress=False)  # the study has its own bar
    return amplitudes(res), time.perf_counter() - t0


def jobs(cases: list[Case], designs: bool = True, levels=tuple(LEVELS)) -> list[tuple[int, str, Optional[str]]]:
    """(case index, level, design) of every run of the study."""
    out = [(i, lv, None) for i in range(len(cases)) for lv in levels]
    if designs:
        out += [(i, "calibrated", d) for i, c in enumerate(cases) if c.label in DESIGN_CASES for d in DESIGNS]
    return out


def run_study(cases: Optional[list[Case]] = None, base: Optional[Config] = None, progress: bool = True, executor: Optional[Executor] = None, designs: bool = True, levels=tuple(LEVELS)) -> list[Case]:
    """Runs every job (in ``executor`` when given: run times then share the machine) and
    fills each case's values and run times."""
    base = base or paper_config()
    default = cases is None
    cases = default_cases() if default else cases
    todo = jobs(cases, designs, levels)
    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=len(todo), desc="validation runs", unit="run")
    if executor is not None and default:
        futures = [executor.submit(_job, i, lv, d, base) for i, lv, d in todo]
        results = []
        for f in futures:
            results.append(f.result())
            if bar is not None:
                bar.update(1)
    else:
        results = []
        for i, lv, d in todo:
            results.append(_job(cases[i], lv, d, base))
            if bar is not None:
                bar.update(1)
    for (i, lv, d), (vals, sec) in zip(todo, results):
        cases[i].values[(lv, d)] = vals
        cases[i].seconds[(lv, d)] = sec
    if bar is not None:
        bar.close()
    return cases


def _find(cases, label):
    return next((c for c in cases if c.label == label), None)


def band_errors(v: dict, ref: dict) -> np.ndarray:
    """Relative error (%) of each band's r.m.s. level, sqrt(E/E_ref) − 1."""
    e, r = np.asarray(v["bands"]), np.asarray(ref["bands"])
    return 100.0 * (np.sqrt(e / r) - 1.0)


def errors(v: dict, ref: dict) -> dict:
    """The study's errors (%) of one result against the reference."""
    be = band_errors(v, ref)
    upto = np.array(BAND_CENTRES) <= RAIL_BAND_HZ * 1.01
    return {
        "rail_disp": 100.0 * (v["rail_disp"] / ref["rail_disp"] - 1),
        "slab_disp": 100.0 * (v["slab_disp"] / ref["slab_disp"] - 1),
        "rail_acc_lp": 100.0 * (v["rail_acc_lp"] / ref["rail_acc_lp"] - 1),
        "bands_max": float(be[upto][np.argmax(np.abs(be[upto]))]),
        "slab_acc_lp": 100.0 * (v["slab_acc_lp"] / ref["slab_acc_lp"] - 1),
    }


#: Acceptance bounds of the converged preset (%): displacements, rail acceleration amplitude
#: and band levels up to 2 kHz, slab acceleration up to 500 Hz.
BOUNDS = {"rail_disp": 1.0, "slab_disp": 1.0, "rail_acc_lp": 3.0, "bands_max": 3.0, "slab_acc_lp": 3.0}


def _pct(x: float) -> str:
    return f"{x:+.1f} %"


def write_report(cases: list[Case], path, base: Optional[Config] = None, command: str = "vtb validate --out docs/validation.md") -> str:
    """Writes the Markdown page (and returns its text)."""
    base = base or paper_config()
    ref = _find(cases, REFERENCE) or cases[-1]
    conv = _find(cases, CONVERGED)
    lines = [
        "# Convergence of the discretisations against a refined reference",
        "",
        f"Generated by `{command}` (python/vtb/validation.py); do not edit by hand. "
        f"Machine: {platform.system()}, {describe()} when it finished; run times are "
        "single runs (one thread each, two runs at a time on two cores: read them as ratios), assembly and "
        "factorisation included.",
        "",
        f"Case: the article's §3.3 case (`paper_config()`: CRH3 car at {base.speed:g} m/s over five 32 m spans, "
        f"{base.irregularity.kind} irregularity {base.irregularity.wavelength_min:g}–{base.irregularity.wavelength_max:g} m, "
        f"seed {base.irregularity.seed}), observation at x = L/2, Δt = {base.solver.dt:g} s unless stated. "
        f"Levels: raw (scale 1) and calibrated (scale {PAPER_CALIBRATED_SCALE:g}, the article's uncontrolled rail "
        "acceleration on its own model). Referee: **" + ref.label + "**"
        + (" (Timoshenko rail, G = 8.1e10 Pa, κ = 0.4, 64 elements per 0.64 m fastener bay; slab, base and girder "
           "at 0.32 m; nodes on every fastener and pier; Δt = 2.5e-5 s). " if ref.label == REFERENCE else ". ")
        +
        f"Rail acceleration is compared after an ideal low-pass at {RAIL_BAND_HZ:.0f} Hz and in one-third-octave "
        f"bands; 'bands ≤ 2 kHz' is the largest error of a band's r.m.s. level over the bands 100 Hz–2 kHz. "
        f"Slab acceleration below {SLAB_BAND_HZ:.0f} Hz. EB: Euler–Bernoulli rail.",
        "",
    ]
    levels = [lv for lv in LEVELS if (lv, None) in ref.values]
    for level in levels:
        r = ref.values[(level, None)]
        lines += [
            f"## {level.capitalize()} irregularity level",
            "",
            "| case | time (s) | rail disp. (mm) | slab disp. (mm) | rail acc. ≤2 kHz (m/s²) | rail acc. raw peak (m/s²) | slab acc. ≤500 Hz (m/s²) | contact losses |",
            "|---|---|---|---|---|---|---|---|",
        ]
        for c in cases:
            v = c.values[(level, None)]
            lines.append(
                f"| {c.label} | {c.seconds[(level, None)]:.1f} | {v['rail_disp'] * 1e3:.4f} | {v['slab_disp'] * 1e3:.4f} | "
                f"{v['rail_acc_lp']:.1f} | {v['rail_acc']:.1f} | {v['slab_acc_lp']:.3f} | {v['contact_losses']} |"
            )
        lines += ["", "Errors against the reference:", "", "| case | rail disp. | slab disp. | rail acc. ≤2 kHz | bands ≤ 2 kHz (max) | slab acc. ≤500 Hz | within the bounds |", "|---|---|---|---|---|---|---|"]
        for c in cases:
            if c is ref:
                continue
            e = errors(c.values[(level, None)], r)
            ok = all(abs(e[k]) <= b for k, b in BOUNDS.items())
            lines.append(f"| {c.label} | " + " | ".join(_pct(e[k]) for k in ("rail_disp", "slab_disp", "rail_acc_lp", "bands_max", "slab_acc_lp")) + f" | {'yes' if ok else 'no'} |")
        lines += ["", "Rail acceleration band levels, error of each band's r.m.s. level against the reference (%):", ""]
        lines.append("| case | " + " | ".join(f"{fc:.0f}" for fc in BAND_CENTRES) + " |")
        lines.append("|" + "---|" * (1 + len(BAND_CENTRES)))
        lines.append("| reference level (dB re 1e-6 m/s²) | " + " | ".join(f"{10 * math.log10(max(e, 1e-300) / 1e-12):.1f}" for e in r["bands"]) + " |")
        for c in cases:
            if c is ref:
                continue
            lines.append(f"| {c.label} | " + " | ".join(f"{x:+.1f}" for x in band_errors(c.values[(level, None)], r)) + " |")
        lines.append("")
    if any(("calibrated", d) in c.values for c in cases for d in DESIGNS):
        lines += [
            "## Effect of four named dampers (calibrated level)",
            "",
            "Ten TIDs in the bays around mid-span (`vtb.tids_around`). η is the reduction (%) of an amplitude against the "
            "uncontrolled run of the same discretisation (positive: the damper lowers it). Rank: order of the four designs by η of the rail acceleration ≤ 2 kHz.",
            "",
            "| case | " + " | ".join(f"{d}: η rail acc. ≤2 kHz / raw / η slab acc. ≤500 Hz" for d in DESIGNS) + " | rank |",
            "|---|" + "---|" * (len(DESIGNS) + 1),
        ]
        ranks = {}
        for c in cases:
            if ("calibrated", next(iter(DESIGNS))) not in c.values:
                continue
            u = c.values[("calibrated", None)]
            cells, eta = [], {}
            for d in DESIGNS:
                v = c.values[("calibrated", d)]
                e_lp = 100 * (1 - v["rail_acc_lp"] / u["rail_acc_lp"])
                e_raw = 100 * (1 - v["rail_acc"] / u["rail_acc"])
                e_s = 100 * (1 - v["slab_acc_lp"] / u["slab_acc_lp"])
                eta[d] = e_lp
                cells.append(f"{e_lp:+.1f} / {e_raw:+.1f} / {e_s:+.1f}")
            order = sorted(DESIGNS, key=lambda d: -eta[d])
            ranks[c.label] = order
            lines.append(f"| {c.label} | " + " | ".join(cells) + " | " + " > ".join(str(list(DESIGNS).index(d) + 1) for d in order) + " |")
        lines += ["", "Designs: " + "; ".join(f"{i + 1} = {d} (b_t = {b:g} kg, k_t = {k:g} N/m, c_t = {cc:g} N·s/m)" for i, (d, (b, k, cc)) in enumerate(DESIGNS.items())) + ".", ""]
        if ref.label in ranks:
            same = [lab for lab, o in ranks.items() if o == ranks[ref.label] and lab != ref.label]
            differ = [lab for lab, o in ranks.items() if o != ranks[ref.label]]
            lines += [
                "**Does a design's ranking depend on the model?** "
                + (f"Same ranking as the reference: {', '.join(same)}. " if same else "")
                + (f"Different ranking: {', '.join(differ)}." if differ else "No discretisation changes the ranking."),
                "",
            ]
    hyb = _find(cases, HYBRID)
    if conv is not None:
        lines += ["## Verdict", ""]
        for level in levels:
            e = errors(conv.values[(level, None)], ref.values[(level, None)])
            bad = [k for k, b in BOUNDS.items() if abs(e[k]) > b]
            verdict = "within the bounds" if not bad else "outside the bounds in " + ", ".join(bad)
            timing = f"; run time {conv.seconds[(level, None)]:.1f} s" + (f" vs the article's hybrid {hyb.seconds[(level, None)]:.1f} s" if hyb else "")
            lines.append(
                f"* {level}: the converged preset is {verdict} (±{BOUNDS['rail_disp']:g} % displacements, "
                f"±{BOUNDS['rail_acc_lp']:g} % rail acceleration and its bands ≤ 2 kHz, ±{BOUNDS['slab_acc_lp']:g} % slab "
                f"acceleration ≤ 500 Hz){timing}."
            )
        lines.append("")
    lines += EXPLANATION
    text = "\n".join(lines) + "\n"
    make_folder(Path(path).parent, "path")
    Path(path).write_text(text)
    return text


EXPLANATION = [
    "## Reading the table",
    "",
    "* **Which discretisation to trust for what.** Displacements of rail and slab: every model here (the",
    "  hybrid's static deflection recovery included). Slab acceleration below 500 Hz: the finite-element",
    "  meshes; the modal slab sines stop near 0.6 kHz. Rail acceleration in the 0.3–2 kHz band where the",
    "  dampers act: only a Timoshenko rail meshed finely enough *and* with the element flexibility under the",
    "  wheels (the converged preset). The article's hybrid and the uniform FEM meshes are Euler–Bernoulli: their",
    "  pinned–pinned resonance sits at 1.28 kHz instead of ≈ 1.0 kHz, and their rail acceleration spectrum",
    "  differs band by band from the reference by tens of per cent.",
    "* **Why a Timoshenko rail needs care under a moving wheel.** A point load kinks a shear-deformable beam",
    "  (the slope jumps by P/κGA under it). An element's cubic interpolation cannot follow the kink between its",
    "  nodes, so the wheel sees a rail whose stiffness changes with its position in the element: a parametric",
    "  excitation at the element-passing frequency v/h (1 kHz at 8 elements per bay and 80 m/s, on the",
    "  pinned–pinned resonance). vtb adds, in series with the Hertz spring, the static deflection of the element",
    "  under the wheel with its nodes fixed (exact for a Timoshenko element); the wheel then sees the exact",
    "  static rail stiffness wherever it is ('element flexibility', `discretisation.element_flexibility`). The",
    "  element's own inertia is left out, so a residual line remains at v/h; the mesh must put v/h above the",
    "  band of interest.",
    "* **Raw (unfiltered) rail acceleration peaks** of a Timoshenko rail do not converge with the mesh: under a",
    "  point load the kink passes the observation point as a jump of velocity, and finer meshes resolve an ever",
    "  sharper pulse. They are shown for completeness only; compare band-limited values.",
]
