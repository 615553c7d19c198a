"""The results epoch (vtb.RESULTS_EPOCH): journals, checkpoints and designs journals carry the
vtb version and the epoch; a resume is refused only across two epochs, and a file of a newer
vtb says so. A fingerprint of a few cheap runs' indices (tests/data/results_fingerprint.json)
fails when a change alters results without raising the epoch.

``python tests/test_results_epoch.py`` regenerates the fingerprint (after raising the epoch)."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest

import vtb
from vtb.studies.journal import _OPENING
from fuzz_cases import small_config

FINGERPRINT = Path(__file__).parent / "data" / "results_fingerprint.json"
GRID = {"speed": [60.0, 70.0]}


def _cases() -> dict:
    """A handful of cheap runs: the article's hybrid for 10 ms, a quarter car on a
    finite-element rail, two moving forces on a modal beam, and a moving force on the
    synthesis of the converged track (one span, 1 kHz cut-off: a build of about 2 s)."""
    hybrid = small_config(0.01)
    qc = small_config(0.01, tids=False)
    qc.discretisation.method = "fem"
    qc.vehicles = [vtb.Vehicle.quarter_car(11000.0, 1200.0, 1.2e6, 3e4, x_front=30.0)]
    force = vtb.moving_load_config(20.0, 2500.0, 4.8, 3.5e10, 0.1, [vtb.MovingForce(1e5, 0.0), vtb.MovingForce(1e5, -3.0)], 50.0,
                                   points=[10.0], modes=10, dt=1e-3)
    fast = vtb.paper_config(model="fast", calibrated=True)
    fast.structure.length = 32.0
    for cp in fast.structure.couplings:
        cp.positions = [x for x in cp.positions if x <= 32.0 + 1e-9] if cp.positions else cp.positions
    fast.vehicles, fast.forces = [], [vtb.MovingForce(magnitude=70e3, x0=14.0)]
    fast.solver.t_end, fast.output.points = 0.05, [15.0]
    fast.discretisation.synthesis_cutoff = 1000.0
    return {"article hybrid": hybrid, "quarter car on fem": qc, "moving forces": force, "moving force on the synthesis": fast}


@pytest.fixture(autouse=True)
def _own_cache(tmp_path, monkeypatch):
    """The synthesis case builds its reduction in a cache of its own."""
    from vtb.run import synthesis
    monkeypatch.setenv(synthesis.CACHE_ENV, str(tmp_path / "cache"))


def _indices() -> dict:
    return {name: {k: float(v) for k, v in vtb.simulate(cfg, progress=False).metrics().items()} for name, cfg in _cases().items()}


def test_the_results_match_the_fingerprint_of_this_epoch():
    stored = json.loads(FINGERPRINT.read_text())
    assert stored["epoch"] == vtb.RESULTS_EPOCH, (
        f"tests/data/results_fingerprint.json is of results epoch {stored['epoch']}, vtb's is {vtb.RESULTS_EPOCH}: "
        "regenerate it (python tests/test_results_epoch.py)")
    now = _indices()
    changed = []
    for case, want in stored["indices"].items():
        for k, v in want.items():
            got = now[case].get(k, math.nan)
            if not (got == v or (math.isnan(got) and math.isnan(v)) or abs(got - v) <= 1e-9 * abs(v)):
                changed.append(f"{case}: {k} = {got!r}, stored {v!r}")
    assert not changed, (
        "this change alters results: raise RESULTS_EPOCH in rust/src/lib.rs (so that journals and checkpoints of the "
        "old results are not resumed with the new ones) and regenerate tests/data/results_fingerprint.json "
        "(python tests/test_results_epoch.py). Changed: " + "; ".join(changed[:10]))


def _stamp(path, **changes):
    lines = path.read_text().split("\n")
    m = _OPENING.match(lines[0])
    head = json.loads(lines[0][m.end():])
    head.update(changes)
    lines[0] = m.group(0) + json.dumps(head, sort_keys=True)
    path.write_text("\n".join(lines))
    return head


def _study(out):
    return vtb.study(small_config(), GRID, out=out, progress=False)


def test_a_journal_is_refused_across_epochs_not_across_versions(tmp_path):
    out = tmp_path / "s.csv"
    _study(out)
    head = _stamp(out)
    assert head["vtb"] == vtb.__version__ and head["epoch"] == vtb.RESULTS_EPOCH
    _stamp(out, vtb="0.0.1")  # another version, the same results: resumed
    assert len(_study(out)) == 2
    _stamp(out, epoch=vtb.RESULTS_EPOCH - 1)
    with pytest.raises(vtb.StaleFileError, match="differ from the file's") as e:
        _study(out)
    assert e.value.field == "out" and e.value.path == str(out) and "older vtb" in str(e.value)
    _stamp(out, vtb="9.0.0", epoch=vtb.RESULTS_EPOCH + 1)
    with pytest.raises(vtb.StaleFileError, match=r"written by a newer vtb \(9.0.0") as e:
        _study(out)
    assert "upgrade" in str(e.value) and "damaged" not in str(e.value)
    _stamp(out, vtb="9.0.0", format=99)
    with pytest.raises(vtb.ConfigError, match="newer vtb") as e:
        _study(out)
    assert "damaged" not in str(e.value)


def test_a_journal_from_before_the_epochs_is_refused_only_for_another_version(tmp_path):
    out = tmp_path / "s.csv"
    _study(out)
    head = _stamp(out)
    lines = out.read_text().split("\n")
    m = _OPENING.match(lines[0])
    del head["epoch"]
    lines[0] = m.group(0) + json.dumps(head, sort_keys=True)
    out.write_text("\n".join(lines))
    assert len(_study(out)) == 2  # this version wrote it
    _stamp(out, vtb="0.0.1")
    with pytest.raises(vtb.StaleFileError, match="carried no results epoch"):
        _study(out)


def _rewrite_checkpoint(path, **changes):
    with np.load(path, allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files}
    header = json.loads(str(arrays.pop("header")))
    header.update(changes)
    with open(path, "wb") as f:
        np.savez(f, header=np.array(json.dumps(header)), **arrays)


def test_a_checkpoint_and_its_designs_journal_are_refused_across_epochs_only(tmp_path):
    ck = tmp_path / "opt.npz"
    designs = Path(str(ck) + ".designs.jsonl")
    kw = dict(variables={"k_t": (1e7, 1e9, "log")}, objectives=["rail_acc_rms", "slab_acc_rms"], pop_size=4, seed=1, progress=False, checkpoint=ck)
    vtb.optimize(small_config(), n_gen=1, **kw)
    header = json.loads(designs.read_text().split("\n", 1)[0])
    assert header["format"] == "vtb designs journal 1" and header["vtb"] == vtb.__version__ and header["epoch"] == vtb.RESULTS_EPOCH
    _rewrite_checkpoint(ck, vtb="0.0.1")  # another version, the same epoch: resumed
    vtb.optimize(small_config(), n_gen=1, **kw)
    _rewrite_checkpoint(ck, epoch=vtb.RESULTS_EPOCH - 1)
    with pytest.raises(vtb.StaleFileError, match="differ from the file's") as e:
        vtb.optimize(small_config(), n_gen=2, **kw)
    assert e.value.field == "checkpoint"
    _rewrite_checkpoint(ck, vtb="9.0.0", format="vtb.moga checkpoint 2")
    with pytest.raises(vtb.StaleFileError, match="newer vtb") as e:
        vtb.optimize(small_config(), n_gen=2, **kw)
    assert "damaged" not in str(e.value)
    ck.unlink()
    lines = designs.read_text().split("\n")
    lines[0] = json.dumps(dict(header, vtb="9.0.0", epoch=vtb.RESULTS_EPOCH + 1))
    designs.write_text("\n".join(lines))
    with pytest.raises(vtb.StaleFileError, match=r"written by a newer vtb \(9.0.0") as e:
        vtb.optimize(small_config(), n_gen=1, **kw)
    assert e.value.path == str(designs)


if __name__ == "__main__":
    import os
    import tempfile

    from vtb.run import synthesis

    os.environ[synthesis.CACHE_ENV] = tempfile.mkdtemp()
    FINGERPRINT.parent.mkdir(exist_ok=True)
    FINGERPRINT.write_text(json.dumps({"epoch": vtb.RESULTS_EPOCH, "indices": _indices()}, indent=1, sort_keys=True) + "\n")
    print(f"wrote {FINGERPRINT} (results epoch {vtb.RESULTS_EPOCH})", file=sys.stderr)
