"""The ``vtb`` command."""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import shlex
import sys
import tempfile
import time
from pathlib import Path

from .article import reproduce, robust_study, validation
from .article.tid_optimize import optimize
from .article.tid_sweep import ARTICLE_B, ARTICLE_C, ARTICLE_K, sweep, sweep_report
from .config.fields import Config
from .config.gateway import __version__
from .config.presets import ARTICLE_RAIL_ACC, PAPER_CALIBRATED_SCALE, example_config, example_text, examples, paper_config, tids_around
from .config.resolution import resolved_band
from .errors import StaleFileError, VtbError, config_error, make_folder, writing
from .studies.journal import lock
from .run.indices import A_RM, A_SM, metric_unit, rate
from .run.simulate import simulate
from .studies.grid import study

#: What each command writes into its ``--out`` directory (refused when present, unless
#: ``--force``).
SIMULATE_FILES = ("result.npz", "metrics.json", "config.toml", "histories.png")
REPRODUCE_FILES = ("report.md",)


def _writable_dir(path: Path, option: str) -> None:
    """Creates ``path`` (a directory; only the last folder, :func:`vtb.errors.make_folder`) if
    needed and proves it writable, or raises a :class:`~vtb.errors.VtbError` naming ``option``."""
    if path.exists() and not path.is_dir():
        raise config_error(option, str(path), "is a file, not a directory")
    make_folder(path, option)
    try:
        with tempfile.TemporaryFile(dir=path):
            pass
    except OSError as e:
        raise config_error(option, str(path), f"is not writable ({e.strerror or e})") from None


def check_out_dir(path, option: str, results, force: bool, hint: str = "") -> None:
    """An output directory must be writable and, unless ``force``, hold none of ``results``."""
    path = Path(path)
    _writable_dir(path, option)
    clash = [f for f in results if (path / f).exists()]
    if clash and not force:
        raise config_error(option, str(path), f"holds the results of an earlier run ({', '.join(clash)}): pass --force to overwrite{hint}")


def check_out_file(path, option: str, force: bool) -> None:
    """An output file must not be a directory, its folder must be writable and, unless
    ``force``, it must not exist."""
    path = Path(path)
    if path.is_dir():
        raise config_error(option, str(path), "is a directory, not a file")
    _writable_dir(path.parent if str(path.parent) else Path("."), option)
    if path.exists() and not force:
        raise config_error(option, str(path), "exists: pass --force to overwrite")


def run_setting_aside_stale(run, force: bool):
    """``run()``; with ``force``, each journal or checkpoint it refuses as written for another
    configuration (:class:`~vtb.errors.StaleFileError`) is renamed ``<name>.stale`` (noted on
    stderr) and ``run()`` called again. The journals and checkpoints that match are still
    reused, so nothing valid is repeated; a journal in use by another process is a plain
    :class:`~vtb.errors.ConfigError` and never set aside."""
    set_aside = set()
    while True:
        try:
            return run()
        except StaleFileError as e:
            path = Path(e.path)
            if not force or not path.is_file() or path in set_aside:
                raise
            path.replace(path.with_name(path.name + ".stale"))
            set_aside.add(path)
            print(f"# set aside {path} as {path.name}.stale: {e.reason.split(';')[0]}", file=sys.stderr)


def check_config_file(path) -> None:
    """``--config`` names a readable file or a shipped example."""
    if path is None:
        return
    p = Path(path)
    if p.is_dir():
        raise config_error("--config", path, "is a directory, not a TOML file")
    if not p.is_file() and path not in examples():
        raise config_error("--config", path, f"no such file, and no example of that name (vtb examples lists: {', '.join(examples())})")
    if p.is_file() and not os.access(p, os.R_OK):
        raise config_error("--config", path, "is not readable")


def require_matplotlib(command: str) -> None:
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        raise VtbError(f"{command} draws figures and needs matplotlib: pip install 'vtb[plot]'") from None


def _load_config(path: str | None):
    """The article's case, a TOML file, or a shipped example by name (``vtb examples``)."""
    if path is None:
        return paper_config()
    check_config_file(path)
    if not Path(path).is_file() and path in examples():
        return example_config(path)
    return Config.from_toml(Path(path))


def _print_metrics(metrics: dict, out=None) -> None:
    out = out or sys.stdout
    width = max(len(k) for k in metrics)
    for k, v in metrics.items():
        print(f"{k:<{width}}  {v:<12.6g} {metric_unit(k)}", file=out)


def _rounded(cfg) -> str:
    """A configuration's JSON with every number to 12 significant digits: the shipped TOML
    examples write the presets' fastener positions (i·0.64 m) rounded."""
    import dataclasses

    def walk(v):
        if isinstance(v, float):
            return float(f"{v:.12g}")
        if isinstance(v, dict):
            return {k: walk(x) for k, x in v.items()}
        if isinstance(v, (list, tuple)):
            return [walk(x) for x in v]
        return v

    return json.dumps(walk(dataclasses.asdict(cfg)), sort_keys=True)


def _describe(cfg, label: str) -> list[str]:
    """What a run is: its model and what it resolves, its excitation, and how its numbers
    relate to the article's published ones (``#`` lines printed before the metrics)."""
    d = cfg.discretisation
    rail = cfg.structure.layers[0]
    if d.method == "fem":
        shear = "Timoshenko" if rail.shear_modulus is not None else "Euler–Bernoulli"
        model = f"finite elements ({shear} rail, elements ≤ {rail.element_length or cfg.structure.length / d.fem_elements:.3g} m)"
    elif d.method == "hybrid":
        model = f"the FE–SEA hybrid ({rail.modes} global + {rail.local_modes} local sines on the rail)"
    else:
        model = f"modal ({rail.modes} sines on the rail)"
    lines = [f"# {label}: {model}, Δt = {cfg.solver.dt:g} s, {cfg.speed:g} m/s, {len(cfg.vehicles)} car{'' if len(cfg.vehicles) == 1 else 's'}, observed at x = {', '.join(f'{x:g}' for x in cfg.output.points)} m"]
    band = resolved_band(cfg)
    held = ", ".join(f"{b.layer} to {b.f_max:.0f} Hz" for b in band.layers.values())
    pp = "" if band.pinned_pinned is None else (
        f"; it {'holds' if band.holds_pinned_pinned else 'does not hold'} the rail's pinned–pinned mode ({band.pinned_pinned:.0f} Hz)")
    limit = cfg.output.band_limit
    lines.append(f"# it resolves {held}{pp}; "
                 + (f"accelerations low-passed at {limit:g} Hz" if limit else "indices of the unfiltered records"))
    irr = cfg.irregularity
    if irr is not None:
        lines.append(f"# irregularity: {irr.kind}, wavelengths {irr.wavelength_min:g}–{irr.wavelength_max:g} m, seed {irr.seed}, level ×{irr.scale:g}")
    for model_name in ("article", "converged"):
        for calibrated in (False, True):
            if _rounded(cfg) != _rounded(paper_config(calibrated=calibrated, model=model_name)):
                continue
            if not calibrated:
                lines.append(f"# this is the raw spectrum level (×1). The article does not state its level; its published "
                             f"{A_RM} {ARTICLE_RAIL_ACC} m/s² needs vtb's calibrated level ×{PAPER_CALIBRATED_SCALE}: "
                             f"vtb simulate --config article{'_converged' if model_name == 'converged' else ''}. No number below is the article's.")
            else:
                published = ", ".join(f"{k} {v[0]:g}" for k, v in reproduce.ARTICLE_33.items())
                lines.append(f"# the level ×{PAPER_CALIBRATED_SCALE} is fitted so that the article model's {A_RM} is the article's "
                             f"{ARTICLE_RAIL_ACC} m/s² (the one fitted number); the article publishes {published} (SI units), "
                             "out-of-sample comparisons" + (" for its hybrid model: this converged model differs by design (docs/validation.md)" if model_name == "converged" else ""))
    return lines


def cmd_simulate(args) -> int:
    if not args.out:
        return _simulate(args)
    check_out_dir(args.out, "--out", SIMULATE_FILES, args.force)
    # A second `vtb simulate --out DIR` into the same folder is refused while this one runs
    # (a lock the kernel drops when its holder dies), so no run's results are silently lost.
    with lock(Path(args.out) / "vtb-simulate", "--out", "another vtb simulate"):
        return _simulate(args)


def _simulate(args) -> int:
    cfg = _load_config(args.config)
    t0 = time.perf_counter()
    res = simulate(cfg)
    elapsed = time.perf_counter() - t0
    label = "the article's case (vtb.paper_config())" if args.config is None else args.config
    print("\n".join(_describe(cfg, label)))
    print(f"# {len(res.t) - 1} steps in {elapsed:.2f} s")
    _print_metrics(res.metrics())
    if args.out:
        out = Path(args.out)
        with writing("--out", out / "result.npz"):
            res.save(out / "result.npz")
        with writing("--out", out / "metrics.json"):
            (out / "metrics.json").write_text(json.dumps(res.metrics(), indent=2))
        with writing("--out", out / "config.toml"):
            cfg.to_toml(out / "config.toml")
        if not args.no_plot:
            try:
                from .analysis.plotting import plot_histories
            except ImportError:
                print("matplotlib is not installed: no plot (pip install 'vtb[plot]')", file=sys.stderr)
            else:
                with writing("--out", out / "histories.png"):
                    plot_histories(res, out / "histories.png")
        print(f"# wrote {out}/result.npz, metrics.json, config.toml" + ("" if args.no_plot else ", histories.png"))
    return 0


@contextlib.contextmanager
def study_executor(args):
    """The executor a study command's runs go to: a Dask cluster's (``--scheduler ADDRESS``),
    else None (this process; :mod:`vtb.run.scaleout`)."""
    address = getattr(args, "scheduler", None)
    if not address:
        yield None
        return
    try:
        from dask.distributed import Client
    except ImportError:
        raise config_error("--scheduler", address, "needs Dask: pip install 'vtb[dask]'") from None
    try:
        client = Client(address, timeout="30s")
    except (OSError, TimeoutError) as e:
        raise config_error("--scheduler", address, f"no Dask scheduler answers there ({type(e).__name__}: {e})") from None
    with client:
        yield client.get_executor(pure=False)  # a study never repeats a task: no content hashing


def cmd_validate(args) -> int:
    from concurrent.futures import ProcessPoolExecutor

    check_out_file(args.out, "--out", args.force)
    with contextlib.ExitStack() as stack:
        pool = stack.enter_context(study_executor(args)) if args.scheduler else stack.enter_context(ProcessPoolExecutor(max_workers=args.workers))
        cases = validation.run_study(progress=not args.no_progress, executor=pool)
    command = shlex.join(["vtb", *args.argv])
    validation.write_report(cases, args.out, command=command)
    ref = next(c for c in cases if c.label == validation.REFERENCE)
    for c in cases:
        e = validation.errors(c.values[("raw", None)], ref.values[("raw", None)])
        print(f"{c.label:<52} {c.seconds[('raw', None)]:6.1f} s  rail acc ≤2 kHz {e['rail_acc_lp']:+6.1f} %  "
              f"bands {e['bands_max']:+6.1f} %  rail disp {e['rail_disp']:+5.1f} %  slab acc {e['slab_acc_lp']:+5.1f} %")
    print(f"# wrote {args.out}")
    return 0


def _floats(text: str) -> list:
    return [float(v) for v in text.split(",") if v.strip()]


def _tid_config(args):
    cfg = _load_config(args.config) if args.config else paper_config(calibrated=args.calibrated)
    if cfg.tids is None:
        cfg.tids = tids_around(cfg)
    return cfg


def cmd_sweep(args) -> int:
    check_config_file(args.config)
    if Path(args.out).is_dir():
        raise config_error("--out", args.out, "is a directory, not a journal file")
    _writable_dir(Path(args.out).parent, "--out")
    if args.report:
        check_out_file(args.report, "--report", args.force)
    cfg = _tid_config(args)
    t0 = time.perf_counter()
    with study_executor(args) as executor:
        res = sweep(
            cfg,
            _floats(args.b) if args.b else ARTICLE_B,
            _floats(args.k) if args.k else ARTICLE_K,
            _floats(args.c) if args.c else ARTICLE_C,
            out=args.out,
            threads=args.threads,
            progress=not args.no_progress,
            executor=executor,
        )
    text = sweep_report(res, args.report, seconds=time.perf_counter() - t0)
    print(text)
    print(f"# journal {args.out}" + (f", report {args.report}" if args.report else ""))
    return 0


def cmd_optimize(args) -> int:
    check_config_file(args.config)
    if args.out:
        check_out_file(args.out, "--out", args.force)
    if args.checkpoint:
        if Path(args.checkpoint).is_dir():
            raise config_error("--checkpoint", args.checkpoint, "is a directory, not a file")
        _writable_dir(Path(args.checkpoint).parent, "--checkpoint")
    cfg = _tid_config(args)
    with study_executor(args) as executor:
        res = optimize(
            cfg, pop_size=args.pop, n_gen=args.gen, seed=args.seed, algorithm=args.algorithm, threads=args.threads,
            progress=not args.no_progress, warm_start=args.warm_start, stop_hv=args.stop_hv, checkpoint=args.checkpoint, executor=executor,
        )
    h = res.moga.history[-1]
    print(f"# {res.moga.n_gen} generations, {res.moga.n_evals} evaluations ({res.moga.message}); hypervolume {h.hypervolume:.6g} (m/s²)² against (a_rm0, a_sm0)")
    rows = res.table()
    print(f"# {len(res)} feasible non-dominated solutions; uncontrolled a_rm0 = {res.baseline[A_RM]:.2f}, a_sm0 = {res.baseline[A_SM]:.3f} m/s²")
    for r in rows:
        print(f"{r['choice']:<18} b_t {r['b_t']:.3f} kg  k_t {r['k_t']:.4g} N/m  c_t {r['c_t']:.4g} N·s/m  "
              f"a_rm {r[A_RM]:.2f} ({100 * r[rate(A_RM)]:+.2f} %)  a_sm {r[A_SM]:.3f} ({100 * r[rate(A_SM)]:+.2f} %)  η_r {100 * r['eta_r']:+.2f} %")
    if args.out:
        import csv

        out = Path(args.out)
        with open(out, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(list(res.pareto))
            w.writerows(zip(*res.pareto.values()))
        print(f"# wrote the Pareto set to {out}")
    return 0


def cmd_examples(args) -> int:
    if args.name:
        sys.stdout.write(example_text(args.name))
        return 0
    import textwrap

    ex = examples()
    width = max(len(k) for k in ex)
    for name, text in ex.items():
        print(f"{name:<{width}}  {textwrap.shorten(text, 100)}")
    print("# vtb examples NAME > my.toml  writes one; --config NAME runs it")
    return 0


def cmd_reproduce(args) -> int:
    require_matplotlib("vtb reproduce")
    check_out_dir(args.out, "--out", REPRODUCE_FILES, args.force, hint=" (its sweep journal and optimiser checkpoints are reused when they match)")
    t0 = time.perf_counter()
    with study_executor(args) as executor:
        report = run_setting_aside_stale(lambda: reproduce.run(args.out, quick=args.quick, progress=not args.no_progress, seed=args.seed, pop_size=args.pop,
                                                     n_gen=args.gen, optimiser=args.optimiser, executor=executor), args.force)
    print(f"# wrote {report} in {time.perf_counter() - t0:.1f} s")
    return 0


def cmd_study(args) -> int:
    require_matplotlib("vtb study")
    check_out_dir(args.out, "--out", REPRODUCE_FILES, args.force, hint=" (its journals and optimiser checkpoints are reused when they match)")
    t0 = time.perf_counter()
    with study_executor(args) as executor:
        report = run_setting_aside_stale(lambda: robust_study.run(args.out, quick=args.quick, progress=not args.no_progress, executor=executor), args.force)
    print(f"# wrote {report} in {time.perf_counter() - t0:.1f} s")
    return 0


def cmd_study_grid(args) -> int:
    cfg = _load_config(args.config)
    grid = {}
    for item in args.vary:
        path, sep, values = item.partition("=")
        if not sep or not path or not values:
            raise config_error("--vary", item, "write PATH=V1,V2,... (e.g. speed=60,70,80 or tids.k_t=1e8,2e8)")
        try:
            grid[path] = _floats(values)
        except ValueError:
            raise config_error("--vary", item, "values must be comma-separated numbers") from None
    if Path(args.out).is_dir():
        raise config_error("--out", args.out, "is a directory, not a journal file")
    _writable_dir(Path(args.out).parent, "--out")
    indices = [s for s in args.indices.split(",") if s] if args.indices else None
    reference = {"tids": None} if args.uncontrolled else None
    t0 = time.perf_counter()
    with study_executor(args) as executor:
        res = study(cfg, grid, indices=indices, reference=reference, out=args.out, threads=args.threads,
                    progress=not args.no_progress, executor=executor)
    print(res.to_pandas().drop(columns="error").to_string(index=False, float_format="%.6g"))
    failed = int((res.columns["error"] != "").sum())
    print(f"# {len(res)} cases ({failed} failed) in {time.perf_counter() - t0:.1f} s; journal {args.out}")
    return 0


def cmd_bridge_check(args) -> int:
    """The EN 1991-2 §6.4.6 dynamic check of a configuration's bridge (docs/bridge-check.md)."""
    from .bridge.report import bridge_check
    from .bridge.settings import split_toml

    cfg, check = split_toml(args.config)
    _writable_dir(Path(args.out), "--out")
    with study_executor(args) as executor:
        res = bridge_check(cfg, check, args.out, executor=executor, threads=args.threads, progress=not args.no_progress,
                           figures=not args.no_plot)
    for c in res.checks:
        state = {True: "pass", False: "FAIL", None: "not evaluated"}[c.passed]
        print(f"{c.name:<38} {c.value:<10.4g} {c.unit:<5} limit {c.limit:<10.4g} {state}")
    print(f"# {len(res.scan)} runs in {res.seconds:.1f} s; report {Path(args.out) / 'report.md'}")
    return 0 if res.passed is not False else 1


def scheduler(sp) -> None:
    """The ``--scheduler`` option of a study command."""
    sp.add_argument("--scheduler", metavar="ADDRESS", help="run on the Dask cluster whose scheduler is at ADDRESS (tcp://host:8786; docs/scaleout.md); "
                    "its workers find the synthesis reduction in VTB_CACHE_DIR, which should be shared storage")


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="vtb", description="Vehicle–track–bridge vertical dynamics.")
    p.add_argument("--version", action="version", version=f"vtb {__version__}")
    sub = p.add_subparsers(dest="command", required=True)
    s = sub.add_parser("simulate", help="run one configuration (default: the article's case) and print its metrics")
    s.add_argument("--config", help="TOML configuration, or a shipped example's name (vtb examples) (default: vtb.paper_config())")
    s.add_argument("--out", help="directory for result.npz, metrics.json, config.toml and a plot")
    s.add_argument("--no-plot", action="store_true", help="do not write histories.png")
    s.add_argument("--force", action="store_true", help="overwrite the results of an earlier run in --out")
    s.set_defaults(func=cmd_simulate)
    v = sub.add_parser("validate", help="the convergence study: the article's case on every discretisation against a refined reference, as a Markdown page (about 15 minutes on two cores)")
    v.add_argument("--out", default="docs/validation.md", help="Markdown page to write (default: docs/validation.md)")
    v.add_argument("--workers", type=int, default=2, help="runs at a time in local processes (default: 2)")
    scheduler(v)
    v.add_argument("--no-progress", action="store_true", help="no progress bar")
    v.add_argument("--force", action="store_true", help="overwrite an existing --out page")
    v.set_defaults(func=cmd_validate)

    def tid_case(sp):
        scheduler(sp)
        sp.add_argument("--config", help="TOML configuration or a shipped example's name (default: the article's case with vtb.tids_around dampers)")
        sp.add_argument("--calibrated", action="store_true", help="the article's case with the irregularity calibrated to a_rm0 = 1005.6 m/s²")
        sp.add_argument("--threads", type=int, help="worker threads (default: all cores)")
        sp.add_argument("--no-progress", action="store_true", help="no progress bar")
        sp.add_argument("--force", action="store_true", help="overwrite existing output files")

    w = sub.add_parser("sweep", help="the TID parameter sweep (default: the article's 1 840-case grid) with its analyses")
    tid_case(w)
    w.add_argument("--b", help="comma-separated b_t values (kg); default 1..10")
    w.add_argument("--k", help="comma-separated k_t values (N/m); default 1..9e4..1e8 and 1e9")
    w.add_argument("--c", help="comma-separated c_t values (N·s/m); default 10,100,1000,10000")
    w.add_argument("--out", default="sweep.csv", help="CSV journal (resumable; .parquet also writes Parquet) (default: sweep.csv)")
    w.add_argument("--report", help="Markdown report to write")
    w.set_defaults(func=cmd_sweep)

    o = sub.add_parser("optimize", help="multi-objective TID optimisation (NSGA-II or gamultiobj) of the article's problem")
    tid_case(o)
    o.add_argument("--pop", type=int, default=100, help="population size (default 100)")
    o.add_argument("--gen", type=int, default=100, help="generations (default 100)")
    o.add_argument("--seed", type=int, default=0)
    o.add_argument("--algorithm", choices=["nsga2", "gamultiobj"], default="nsga2")
    o.add_argument("--out", help="CSV file for the Pareto set")
    o.add_argument("--warm-start", metavar="JOURNAL", help="start from the cases of this sweep journal (same configuration) within the bounds instead of a random population")
    o.add_argument("--stop-hv", nargs=2, type=float, metavar=("TOL", "WINDOW"), help="stop once the front's hypervolume moved by less than TOL (relative) over WINDOW generations (default: run all --gen)")
    o.add_argument("--checkpoint", metavar="PATH", help="save the optimiser's state after every generation; an existing checkpoint of the same run is resumed")
    o.set_defaults(func=cmd_optimize)

    e = sub.add_parser("examples", help="list the example configurations shipped with vtb, or print one as TOML")
    e.add_argument("name", nargs="?", help="example to print (e.g. article)")
    e.set_defaults(func=cmd_examples)

    r = sub.add_parser("reproduce", help="the article's whole chain: §3.3 histories, sweep, optimisation; figures, tables, report")
    r.add_argument("--out", required=True, help="output directory")
    r.add_argument("--quick", action="store_true", help="reduced chain (about a minute)")
    r.add_argument("--seed", type=int, default=0, help="optimiser seed")
    r.add_argument("--pop", type=int, help="optimiser population (default: 100; --quick 8)")
    r.add_argument("--gen", type=int, help="optimiser generations (default: 100; --quick 3)")
    r.add_argument("--optimiser", choices=("warm", "cold", "both"), default=reproduce.DEFAULT_OPTIMISER,
                   help=f"warm: first population from the sweep; cold: a random one; both: the two, compared; each stops on the hypervolume (default {reproduce.DEFAULT_OPTIMISER}, chosen over seeds in docs/optimiser-choice)")
    r.add_argument("--no-progress", action="store_true", help="no progress bars")
    r.add_argument("--force", action="store_true", help="write into an --out that holds an earlier report (its sweep journal and optimiser checkpoints are reused when they match; those of another configuration are renamed *.stale and their stage runs afresh)")
    scheduler(r)
    r.set_defaults(func=cmd_reproduce)

    st = sub.add_parser("study", help="a study over any fields (grid), or the robust study of the article's chain (robust)")
    kinds = st.add_subparsers(dest="study", required=True)
    rb = kinds.add_parser("robust", help="robust damper design over irregularity samples and speeds on the fast converged model (NSGA-II 20 × 15 over 8 samples × 4 speeds), and the article's conclusions re-examined (about two hours on two cores; --quick about a minute)")
    rb.add_argument("--out", required=True, help="output directory")
    rb.add_argument("--quick", action="store_true", help="the same stages on a short record with tiny budgets (about a minute; shows the pipeline, not findings)")
    rb.add_argument("--no-progress", action="store_true", help="no progress bars")
    rb.add_argument("--force", action="store_true", help="write into an --out that holds an earlier report (its journals and checkpoints are reused when they match; those of another configuration are renamed *.stale and their stage runs afresh)")
    scheduler(rb)
    rb.set_defaults(func=cmd_study)
    gr = kinds.add_parser("grid", help="any configuration fields over a grid of values, any indices (vtb.study; docs/studies.md)")
    gr.add_argument("--config", help="TOML configuration or a shipped example's name (default: vtb.paper_config())")
    gr.add_argument("--vary", action="append", required=True, metavar="PATH=V1,V2,...",
                    help="a field and its values, e.g. speed=60,70,80 or tids.k_t=1e8,2e8 or structure.couplings[0].stiffness=4e7,6e7; repeat for a product")
    gr.add_argument("--indices", help="comma-separated index names (default: every index; vtb.index_names)")
    gr.add_argument("--uncontrolled", action="store_true", help="add the run without dampers as case 0")
    gr.add_argument("--out", default="study.csv", help="CSV journal (resumable; .parquet also writes Parquet) (default: study.csv)")
    gr.add_argument("--threads", type=int, help="worker threads (default: all cores)")
    gr.add_argument("--no-progress", action="store_true", help="no progress bar")
    scheduler(gr)
    gr.set_defaults(func=cmd_study_grid)

    bc = sub.add_parser("bridge-check", help="the EN 1991-2 §6.4.6 dynamic check of a bridge: HSLM and real trains over a speed scan, code damping, "
                        "the EN 1990 A2 limits, a Markdown report with envelopes and figures (docs/bridge-check.md)")
    bc.add_argument("config", metavar="CONFIG", help="TOML configuration with a [bridge_check] table (span, bridge_type, track, line_speed, …)")
    bc.add_argument("--out", required=True, help="output directory (report.md, envelopes.csv/.parquet, figures; the scan's journals, so a re-run resumes)")
    bc.add_argument("--threads", type=int, help="worker threads (default: all cores)")
    bc.add_argument("--no-progress", action="store_true", help="no progress bars")
    bc.add_argument("--no-plot", action="store_true", help="no figures")
    scheduler(bc)
    bc.set_defaults(func=cmd_bridge_check)
    return p


def main(argv=None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    args = build_parser().parse_args(argv)
    args.argv = argv
    try:
        return args.func(args)
    except VtbError as e:
        print(f"vtb: {type(e).__name__}: {' '.join(str(e).split())}", file=sys.stderr)
        return 2
    except OSError as e:  # a file no vtb error wrapped: still one line naming it, and the cause
        where = f" {e.filename!r}" if e.filename else ""
        print(f"vtb: {type(e).__name__}:{where} {e.strerror or e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("vtb: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
