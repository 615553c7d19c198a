"""The ``vtb`` command."""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from .errors import VtbError


def _load_config(path: str | None):
    from .presets import paper_config

    if path is None:
        return paper_config()
    from .config import Config

    return Config.from_toml(Path(path))


def _print_metrics(metrics: dict, out=sys.stdout) -> None:
    width = max(len(k) for k in metrics)
    for k, v in metrics.items():
        print(f"{k:<{width}}  {v:.6g}", file=out)


def cmd_simulate(args) -> int:
    cfg = _load_config(args.config)
    from .simulate import simulate

    t0 = time.perf_counter()
    res = simulate(cfg)
    elapsed = time.perf_counter() - t0
    print(f"# {'article case (paper_config)' if args.config is None else args.config}: {len(res.t) - 1} steps in {elapsed:.2f} s")
    _print_metrics(res.metrics())
    if args.out:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        res.save(out / "result.npz")
        (out / "metrics.json").write_text(json.dumps(res.metrics(), indent=2))
        cfg.to_toml(out / "config.toml")
        if not args.no_plot:
            try:
                from .plotting import plot_histories
            except ImportError:
                print("matplotlib is not installed: no plot (pip install 'vtb[plot]')", file=sys.stderr)
            else:
                plot_histories(res, out / "histories.png")
        print(f"# wrote {out}/result.npz, metrics.json, config.toml" + ("" if args.no_plot else ", histories.png"))
    return 0


def cmd_validate(args) -> int:
    from .validation import run_study, write_report

    cases = run_study(progress=not args.no_progress)
    write_report(cases, args.out)
    for c in cases:
        print(f"{c.label:<42} {c.seconds:6.2f} s  rail {c.values['rail_disp'] * 1e3:.4f} mm {c.values['rail_acc']:.1f} m/s²  "
              f"slab {c.values['slab_disp'] * 1e3:.4f} mm {c.values['slab_acc']:.3f} m/s²")
    print(f"# wrote {args.out}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="vtb", description="Vehicle–track–bridge vertical dynamics.")
    sub = p.add_subparsers(dest="command", required=True)
    s = sub.add_parser("simulate", help="run one configuration (default: the article's case) and print its metrics")
    s.add_argument("--config", help="TOML configuration (default: vtb.paper_config())")
    s.add_argument("--out", help="directory for result.npz, metrics.json, config.toml and a plot")
    s.add_argument("--no-plot", action="store_true", help="do not write histories.png")
    s.set_defaults(func=cmd_simulate)
    v = sub.add_parser("validate", help="the FE–SEA validation study: hybrid, modal and FEM runs of the article's case, as a Markdown table")
    v.add_argument("--out", default="docs/validation.md", help="Markdown page to write (default: docs/validation.md)")
    v.add_argument("--no-progress", action="store_true", help="no progress bar")
    v.set_defaults(func=cmd_validate)
    return p


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except VtbError as e:
        print(f"vtb: {type(e).__name__}: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("vtb: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
