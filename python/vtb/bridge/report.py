"""The bridge check's report: :func:`bridge_check` runs :func:`~vtb.bridge.assess.assess` and
writes, in ``out``, ``report.md`` (inputs, assumptions with their clauses, the envelopes'
figures, the governing cases, pass or fail), ``envelopes.csv`` (and ``envelopes.parquet`` when
pandas and pyarrow are installed) and the figures ``acceleration.png``, ``deflection.png`` and
``moment.png`` (one column wide, matplotlib)."""

from __future__ import annotations

import json
import math
from concurrent.futures import Executor
from pathlib import Path
from typing import Optional, Union

import numpy as np

from ..config.fields import Config
from ..config.gateway import __version__
from ..errors import config_error, make_folder
from .assess import Assessment, assess
from .checks import n0_limits
from .damping import BRIDGE_TYPE_TITLES
from .settings import BridgeCheck

KMH = 3.6
#: The figures' scale and unit of each envelope column (m → mm, N·m → MN·m).
SCALES = {"acc": (1.0, "m/s²"), "disp": (1e3, "mm"), "moment": (1e-6, "MN·m")}


def bridge_check(config: Config, settings: Union[BridgeCheck, dict], out: Union[str, Path], executor: Optional[Executor] = None,
                 threads: Optional[int] = None, progress: bool = True, figures: bool = True) -> Assessment:
    """The EN 1991-2 §6.4.6 dynamic check of ``config``'s bridge (``settings``: a
    :class:`BridgeCheck` or its table), written to the directory ``out`` (report.md,
    envelopes.csv/.parquet, figures; the scan's journals in out/journals, so a re-run resumes).
    Returns the :class:`~vtb.bridge.assess.Assessment`."""
    check = settings if isinstance(settings, BridgeCheck) else BridgeCheck.from_dict(settings)
    if not isinstance(config, Config):
        raise config_error("config", type(config).__name__, "expected a vtb.Config")
    directory = Path(out)
    if directory.exists() and not directory.is_dir():
        raise config_error("out", str(directory), "is a file, not a directory")
    make_folder(directory, "out")
    result = assess(config, check, out=directory, executor=executor, threads=threads, progress=progress)
    write(result, directory, figures=figures)
    return result


def write(a: Assessment, directory: Path, figures: bool = True) -> dict:
    """Writes the report's files; returns their paths by kind."""
    paths = {"csv": directory / "envelopes.csv"}
    a.scan.to_csv(paths["csv"])
    try:
        a.scan.to_parquet(directory / "envelopes.parquet")
        paths["parquet"] = directory / "envelopes.parquet"
    except ImportError:
        pass
    if a.interaction is not None:
        paths["interaction"] = directory / "interaction.csv"
        a.interaction.to_csv(paths["interaction"])
    if figures:
        paths.update(draw(a, directory))
    (directory / "config.json").write_text(json.dumps({"config": a.config.to_dict(), "bridge_check": a.settings.to_dict()}, indent=1))
    paths["report"] = directory / "report.md"
    paths["report"].write_text(markdown(a, {k: p.name for k, p in paths.items()}))
    return paths


def draw(a: Assessment, directory: Path) -> dict:
    """acceleration.png, deflection.png and moment.png: each train's envelope against speed
    (km/h), the limits drawn. Needs matplotlib (else no figure, and the report says so)."""
    try:
        from ..analysis.plotting import STYLES, figure, styled
    except ImportError:
        return {}
    from .checks import acceleration_limit

    @styled
    def one(column: str, ylabel: str, limits: list, path: Path):
        fig = figure(70.0)
        ax = fig.add_subplot()
        scale, unit = SCALES[column]
        names = list(dict.fromkeys(a.scan.columns["train"]))
        bounds = list(dict.fromkeys(a.scan.columns["bound"]))
        for i, name in enumerate(names):
            for j, bound in enumerate(bounds):
                sel = a.scan.select(train=name, bound=bound)
                label = name if len(bounds) == 1 else f"{name} ({bound})"
                ax.plot(sel["speed"] * KMH, sel[column] * scale, STYLES[(i + j) % len(STYLES)], label=label, lw=0.8)
        for i, name in enumerate(dict.fromkeys(a.interaction.columns["train"]) if a.interaction is not None else ()):
            sel = a.interaction.select(train=name, bound=bounds[0])
            ax.plot(sel["speed"] * KMH, sel[column] * scale, color="k", ls=(0, (1 + i, 1)), lw=1.0,
                    label=f"{name}, interaction")
        top = max([float(np.nanmax(a.scan.columns[column] * scale))] + [v for v, _, _ in limits[:1]])
        for value, text, style in limits:
            if value <= 3 * top:
                ax.axhline(value, color="k", ls=style, lw=1.0, label=text)
            else:  # far above the curves: named, not drawn, so that they stay readable
                ax.set_title(f"{text}: {value:.3g} {unit} (off scale)", loc="right")
        ax.axvline(a.settings.line_speed * KMH, color="0.5", lw=0.6, ls=":", label="line speed")
        ax.set_xlabel("speed (km/h)")
        ax.set_ylabel(ylabel)
        ax.grid(True, alpha=0.3)
        ax.legend(ncol=3 if len(names) > 4 else 1, loc="upper left", fontsize=5.0)
        fig.savefig(path)
        return path

    acc = one("acc", f"deck acceleration ≤ {a.band:.3g} Hz (m/s²)",
              [(acceleration_limit(a.settings.track), f"limit {acceleration_limit(a.settings.track):g} m/s² (EN 1990 A2.4.4.2.1)", "-")],
              directory / "acceleration.png")
    disp = one("disp", "deck deflection (mm)",
               [(1e3 * a.phi * a.lm71, "Φ·α·LM71 static", "--"), (1e3 * a.settings.span / 600.0, "L/600 (EN 1990 A2.4.4.2.3)", "-")],
               directory / "deflection.png")
    moment = one("moment", "deck bending moment (MN·m)", [(1e-6 * a.phi * a.lm71_moment, "Φ·α·LM71 static", "--")], directory / "moment.png")
    return {"acceleration": acc, "deflection": disp, "moment": moment}


def beyond(a: Assessment) -> list:
    """The report's section "beyond the code": each vehicle train's peaks with full interaction
    beside the same train's as moving loads (when it is among the load trains)."""
    if a.interaction is None:
        return []
    from .damping import code_damping

    plain = code_damping(a.settings.bridge_type, a.settings.span, False)
    lines = ["## Beyond the code: full vehicle–track–bridge interaction", "",
             f"The trains {', '.join(a.settings.vehicles)} as vehicles (car bodies, bogies, wheelsets on their suspensions, "
             f"Hertz contact) on a smooth rail over the same speeds, with {plain.describe()} — no Δζ, since the interaction it "
             "stands for is modelled. The moving-load column is the same train's axles as constant forces with the check's damping. "
             "Dotted lines in the figures; values in `interaction.csv`.", "",
             "| train | bound | max acc, interaction (m/s²) | at (km/h) | max acc, moving loads (m/s²) | at (km/h) | ratio | "
             "max δ, interaction (mm) | max δ, moving loads (mm) |", "|---|---|---|---|---|---|---|---|---|"]
    for name in dict.fromkeys(a.interaction.columns["train"]):
        for bound in dict.fromkeys(a.interaction.columns["bound"]):
            it, ml = a.interaction.select(train=name, bound=bound), a.scan.select(train=name, bound=bound)
            i, j = _peak(it["acc"]), _peak(ml["acc"])
            acc_ml = ml["acc"][j] if j is not None else math.nan
            lines.append(f"| {name} | {bound} | {_fmt(it['acc'][i]) if i is not None else '—'} | "
                         f"{_fmt(it['speed'][i] * KMH, 4) if i is not None else '—'} | {_fmt(acc_ml)} | "
                         f"{_fmt(ml['speed'][j] * KMH, 4) if j is not None else '—'} | "
                         f"{_fmt(it['acc'][i] / acc_ml, 3) if i is not None else '—'} | "
                         f"{_fmt(1e3 * np.nanmax(it['disp'])) if i is not None else '—'} | "
                         f"{_fmt(1e3 * np.nanmax(ml['disp'])) if j is not None else '—'} |")
    return lines + [""]


def _peak(values: np.ndarray) -> Optional[int]:
    ok = np.isfinite(values)
    return int(np.argmax(np.where(ok, values, -np.inf))) if ok.any() else None


def _fmt(v: float, digits: int = 4) -> str:
    return "—" if v is None or (isinstance(v, float) and not math.isfinite(v)) else f"{v:.{digits}g}"


def markdown(a: Assessment, files: dict) -> str:
    """The report's text."""
    s = a.settings
    verdict = {True: "**PASS**", False: "**FAIL**", None: "not evaluated"}
    lines = [f"# Dynamic check of the bridge: EN 1991-2 §6.4.6 — {verdict[a.passed]}", "",
             f"Written by vtb {__version__} in {a.seconds:.0f} s: {len(a.scan)} moving-load runs "
             f"({len(set(a.scan.columns['train']))} trains × {len(set(a.scan.columns['bound']))} mass bound(s) × speeds).", "",
             "## Checks", "", "| check | clause | value | limit | margin | governing | verdict |", "|---|---|---|---|---|---|---|"]
    for c in a.checks:
        gov = c.train + (f" at {c.speed * KMH:.0f} km/h" if math.isfinite(c.speed) else "")
        lines.append(f"| {c.name} | {c.clause} | {_fmt(c.value)} {c.unit} | {_fmt(c.limit)} {c.unit} | "
                     f"{_fmt(100 * c.margin, 3)} % | {gov} | {verdict[c.passed]} |")
    lines += [""] + [f"- {c.name}: {c.note}" for c in a.checks if c.note]
    lower, upper = n0_limits(s.span)
    lines += ["", "## Inputs", "",
              f"- Span L = {s.span:g} m; {BRIDGE_TYPE_TITLES[s.bridge_type]}; {s.track.replace('_', ' ')} track; "
              f"line speed {s.line_speed * KMH:.0f} km/h, scanned {s.v_min * KMH:.0f}–{1.2 * s.line_speed * KMH:.0f} km/h "
              f"(1.2 × line speed, EN 1991-2 §6.4.6.2(1)) every {s.step * KMH:.3g} km/h, 5 times finer around each resonance n0·D/i.",
              f"- Structure: {a.config.structure.length:g} m, layers {', '.join(l.name for l in a.config.structure.layers)} "
              f"(deck: {a.config.structure.layers[-1].name}), {a.config.discretisation.method} discretisation; "
              f"observation points x = {', '.join(f'{x:g}' for x in (a.config.output.points or [a.config.structure.length / 2]))} m"
              + (" (the quarter, middle and three-quarter points of every span; the largest response governs)." if len(a.config.structure.layers) > 1 else "."),
              f"- Trains: {', '.join(s.trains)}; each axle's share on the model {s.share:g}; mass bounds "
              + ", ".join(f"{k} × {v:g}" for k, v in s.mass_bounds.items()) + ".",
              f"- Time step {a.config.solver.dt:.3g} s; {s.tail:g} s recorded after the last axle.",
              "", "## Assumptions and their clauses", "",
              f"- Deck frequencies (Hz): {', '.join(f'{f:.3f}' for f in a.frequencies[:6])}; n0 = {a.n0:.3f} Hz"
              + (" (given)" if s.n0 is not None else " (computed)") + f"; Fig. 6.10 limits for L = {s.span:g} m: "
              f"[{_fmt(lower)}, {_fmt(upper)}] Hz.",
              "- Fig. 6.9 (is a dynamic analysis required?): " + "; ".join(a.flow_chart.reasons) + ".",
              f"- Acceleration band: max(30 Hz, 1.5·n0, n3) = {a.band:.3g} Hz (EN 1990 A2.4.4.2.1(4)P), zero-phase 8th-order Butterworth low-pass.",
              f"- Damping: {a.damping.describe()}; Rayleigh's law fitted to it at n0 = {a.n0:.3g} Hz and {a.band:.3g} Hz, "
              "so that every mode between has at most the code's ratio: achieved "
              + ", ".join(f"{f:.2f} Hz: {100 * z:.3f} %" for f, z in zip(a.frequencies, a.achieved)) + ".",
              f"- LM71 (EN 1991-2 §6.3.2) × α = {s.alpha:g}, static, on the same structure: {1e3 * a.lm71:.4g} mm, the largest over the points; "
              f"Φ{'2' if s.maintenance == 'careful' else '3'} = {a.phi:.4g} (§6.4.5.2, LΦ = {s.l_phi or s.span:g} m).",
              f"- LM71's static bending moment on the same structure: {1e-6 * a.lm71_moment:.4g} MN·m, the largest over the points.",
              "- φ'dyn (EN 1991-2 §6.4.6.5(3)) from both responses: max dynamic / static − 1 of the deflection and of the bending moment, each at the point "
              "where the train's dynamic effect is largest; the larger governs, and the envelope (1 + φ'dyn + kφ'')·static of each effect is checked "
              "against Φ·α·LM71's. The moment is −EI·w″ of the model's deck at the point, static and dynamic alike (docs/bridge-check.md). "
              "φ'' of Annex C at the line speed, halved for carefully maintained track (eq. 6.15).",
              "- Moving loads: the axles are constant forces on the top layer; the vehicles' own dynamics are left out, "
              "for which Δζ (eq. 6.13) stands in below 30 m.", "",
              "## Envelopes per train", "",
              "| train | static δ (mm) | max dynamic δ (mm) | at (km/h) | φ'dyn, δ | static M (MN·m) | max dynamic M (MN·m) | at (km/h) | "
              "φ'dyn, M | φ'dyn | φ'' | (1 + φ'dyn + kφ'')·δ (mm) | (1 + φ'dyn + kφ'')·M (MN·m) | max acc (m/s²) | at (km/h) |",
              "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for e in a.envelopes:
        sel = a.scan.select(train=e.train)
        i = _peak(sel["acc"])
        d, m = e.deflection, e.moment
        lines.append(f"| {e.train} | {_fmt(1e3 * d.static)} | {_fmt(1e3 * d.dynamic)} | {_fmt(d.speed * KMH, 4)} | {_fmt(d.phi_dyn, 3)} | "
                     f"{_fmt(1e-6 * m.static)} | {_fmt(1e-6 * m.dynamic)} | {_fmt(m.speed * KMH, 4)} | {_fmt(m.phi_dyn, 3)} | "
                     f"{_fmt(e.phi_dyn, 3)} | {_fmt(e.phi_irr, 3)} | {_fmt(1e3 * d.design)} | {_fmt(1e-6 * m.design)} | "
                     f"{_fmt(sel['acc'][i]) if i is not None else '—'} | {_fmt(sel['speed'][i] * KMH, 4) if i is not None else '—'} |")
    lines += ["", f"Φ·α·LM71: {1e3 * a.phi * a.lm71:.4g} mm, {1e-6 * a.phi * a.lm71_moment:.4g} MN·m. Envelopes against speed: `{files['csv']}`"
              + (f" and `{files['parquet']}`" if "parquet" in files else "") + " (speed in m/s, acc in m/s², disp in m, moment in N·m).", ""]
    if "acceleration" in files:
        lines += ["![Deck acceleration against speed](acceleration.png)", "", "![Deck deflection against speed](deflection.png)", "",
                  "![Deck bending moment against speed](moment.png)", ""]
    else:
        lines += ["(No figures: matplotlib is not installed.)", ""]
    lines += beyond(a)
    lines += ["## Not covered", "",
              "- The deck is searched at the quarter, middle and three-quarter points of every span, not between them"
              + ("." if len(a.config.structure.layers) > 1 else "; a single-layer model is observed at its first observation point only."),
              "- HSLM-B's N and d (Fig. 6.13), Fig. A2.3's L/δ and Annex F's (v/n0)lim are not encoded: they are inputs.",
              "- The bending moment is sagging, at the observation points: hogging moments over the supports of continuous decks are not "
              "searched.", ""]
    return "\n".join(lines)
