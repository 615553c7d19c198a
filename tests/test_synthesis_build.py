"""Building the synthesis reduction (vtb.run.synthesis, docs/synthesis.md, "The first build"):
deterministic bits across processes, the lock that makes a second process wait for the first's
file, the announcement and progress of a build, and the memory budget checked before it starts.
A one-span structure at a 100 Hz cut-off keeps each build near a second."""

import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

import vtb
from vtb.run import synthesis

PYTHON = str(Path(__file__).resolve().parents[1] / "python")

#: The structure of every build here: the fast preset on one 32 m span at a 100 Hz cut-off.
CASE = textwrap.dedent("""
    import vtb
    def one_span(cutoff=100.0):
        c = vtb.paper_config(model="fast", calibrated=True)
        c.structure.length = 32.0
        for cp in c.structure.couplings:
            if cp.positions:
                cp.positions = [x for x in cp.positions if x <= 32.0 + 1e-9]
        c.solver.t_end = 0.05
        c.discretisation.synthesis_cutoff = cutoff
        return c
""")
exec(CASE)  # defines one_span here as in the child processes


def run_child(code: str, cache: Path, **env) -> subprocess.Popen:
    """A Python process running CASE then ``code`` with its own cache folder."""
    full = {**os.environ, "PYTHONPATH": PYTHON, synthesis.CACHE_ENV: str(cache), **env}
    return subprocess.Popen([sys.executable, "-c", CASE + textwrap.dedent(code)], env=full,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def finished(p: subprocess.Popen, timeout: float = 120.0) -> tuple[str, str]:
    out, err = p.communicate(timeout=timeout)
    assert p.returncode == 0, err
    return out, err


def arrays(cache: Path) -> dict:
    (path,) = cache.glob("reduction-*.npz")
    with np.load(path) as d:
        return {k: d[k] for k in ("lam", "psi", "weight", "residual", "basis_modes", "attachments")}


def test_two_builds_in_fresh_caches_and_processes_are_bit_identical(tmp_path):
    """Two processes, each with its own empty cache and a different BLAS thread count, build
    the same reduction: every array is equal bit for bit (ARPACK's random start vector and the
    thread count made them differ before)."""
    build = "vtb.run.synthesis.reduction(one_span())\n"
    a = run_child(build, tmp_path / "a", OPENBLAS_NUM_THREADS="1")
    finished(a)
    b = run_child(build, tmp_path / "b", OPENBLAS_NUM_THREADS="2")
    finished(b)
    ra, rb = arrays(tmp_path / "a"), arrays(tmp_path / "b")
    for k in ra:
        assert ra[k].dtype == rb[k].dtype and ra[k].shape == rb[k].shape, k
        assert ra[k].tobytes() == rb[k].tobytes(), k
    assert ra["lam"].size > 0
