"""Writes the irregularity of vtb.paper_config() to benches/data/ for `cargo bench`, which
runs without Python: paper_profile.f64 (little-endian float64 samples, m) and
paper_profile.json (x0, dx). Re-run after changing the paper preset's irregularity."""

import json
from pathlib import Path

import numpy as np

import vtb

here = Path(__file__).parent / "data"
here.mkdir(exist_ok=True)
cfg = vtb.paper_config()
x0, dx, values, _ = vtb.irregularity_profile(cfg)
np.asarray(values, dtype="<f8").tofile(here / "paper_profile.f64")
(here / "paper_profile.json").write_text(json.dumps({"x0": x0, "dx": dx, "n": int(values.size), "irregularity": repr(cfg.irregularity)}, indent=1))
print(f"wrote {values.size} samples")
