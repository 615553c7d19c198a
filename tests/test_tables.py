"""Results that compare and export: Result equality by value, histories and metrics as
pandas DataFrames, Parquet export of runs, batches and study results (with units)."""

import numpy as np
import pytest

import vtb

pd = pytest.importorskip("pandas")
pytest.importorskip("pyarrow")


@pytest.fixture(scope="module")
def short():
    c = vtb.paper_config()
    c.solver.t_end = 0.05
    c.output.points = [5.0, 6.0]
    return c


@pytest.fixture(scope="module")
def runs(short):
    other = short.copy()
    other.speed = 70.0
    return vtb.simulate(short), vtb.simulate(short), vtb.simulate(other)


def test_results_compare_by_value(runs, tmp_path):
    a, b, c = runs
    assert a == b and not (a != b)
    assert a != c
    a.save(tmp_path / "r.npz")
    assert vtb.load(tmp_path / "r.npz") == a
    changed = vtb.load(tmp_path / "r.npz")
    changed.acc[3, 0, 0] += 1e-12
    assert changed != a
    assert (a == "not a result") is False
    with pytest.raises(TypeError):
        hash(a)


def test_histories_frame_and_parquet_round_trip(runs, tmp_path):
    a = runs[0]
    df = a.to_pandas()
    assert df.index.name == "t" and np.array_equal(df.index.to_numpy(), a.t)
    assert np.array_equal(df["rail_acc@5"].to_numpy(), a.acc[:, 0, 0])
    assert np.array_equal(df["slab_disp@6"].to_numpy(), a.disp[:, 1, 1])
    assert np.array_equal(df["car0_beta_c"].to_numpy(), a.vehicle_disp[:, 0, 1])
    assert np.array_equal(df["contact_force_3"].to_numpy(), a.contact_force[:, 3])
    assert df.attrs["units"]["rail_acc@5"] == "m/s²" and df.attrs["units"]["car0_beta_c"] == "rad"
    a.to_parquet(tmp_path / "h.parquet")
    back = vtb.read_parquet(tmp_path / "h.parquet")
    assert np.array_equal(back.to_numpy(), df.to_numpy()) and back.attrs["units"] == df.attrs["units"]


def test_metrics_table_of_a_batch_with_a_failed_job(short, tmp_path):
    bad = short.copy()
    bad.tids = vtb.tids_around(bad, count=2, x=6.0)
    bad.tids.inertance = 1e300  # fails at run time in its own lane
    res = vtb.simulate_batch([short, bad], on_error="return")
    df = vtb.metrics_table(res)
    assert len(df) == 2 and df["error"].iloc[0] == ""
    assert df["rail_acc_max"].iloc[0] == res[0]["rail_acc_max"]
    assert df.attrs["units"]["rail_acc_max"] == "m/s²"
    assert "tids.inertance" in df["error"].iloc[1] and np.isnan(df["rail_acc_max"].iloc[1])
    from vtb.tables import to_parquet

    to_parquet(df, tmp_path / "m.parquet")
    back = vtb.read_parquet(tmp_path / "m.parquet")
    assert back.attrs["units"]["rail_disp_max"] == "m"
    with pytest.raises(vtb.ConfigError, match=r"results\[0\]"):
        vtb.metrics_table(["nope"])


def test_sweep_exports_with_units(short, tmp_path):
    c = short.copy()
    c.tids = vtb.tids_around(c, count=2, x=6.0)
    sw = vtb.sweep(c, b_t=[5.0], k_t=[1e8], c_t=[1e3], progress=False)
    df = sw.to_pandas()
    assert df.attrs["units"]["k_t"] == "N/m" and df.attrs["units"]["rail_acc_max"] == "m/s²"
    sw.to_parquet(tmp_path / "s.parquet")
    back = vtb.read_parquet(tmp_path / "s.parquet")
    assert back["k_t"].equals(df["k_t"]) and back.attrs["units"]["c_t"] == "N·s/m"
