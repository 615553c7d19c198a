"""Results that compare and export: Result equality by value, histories and metrics as
pandas DataFrames, Parquet export of runs, batches and study results (with units)."""

import numpy as np
import pytest

import vtb
from fuzz_cases import small_config

pd = pytest.importorskip("pandas")
pytest.importorskip("pyarrow")


def _same_frame(back, df):
    """``back`` (read from Parquet) holds exactly ``df``'s values, dtypes and units."""
    pd.testing.assert_frame_equal(back, df, check_exact=True)
    assert back.attrs["units"] == df.attrs["units"]
    return back


def _round_trip(result, tmp_path, name):
    """``result.to_parquet`` and ``vtb.to_parquet(result)`` both read back as ``to_pandas()``."""
    df = result.to_pandas()
    result.to_parquet(tmp_path / f"{name}.parquet")
    _same_frame(vtb.read_parquet(tmp_path / f"{name}.parquet"), df)
    vtb.to_parquet(result, tmp_path / f"{name}2.parquet")
    _same_frame(vtb.read_parquet(tmp_path / f"{name}2.parquet"), df)
    return df


@pytest.fixture(scope="module")
def tiny():
    """The cut-down article case (8 modes per layer) for 0.01 s = 200 steps, four dampers."""
    c = small_config(t_end=0.01)
    assert c.solver.t_end / c.solver.dt == pytest.approx(round(c.solver.t_end / c.solver.dt), abs=1e-9)
    return c


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
    vtb.to_parquet(df, tmp_path / "m.parquet")
    back = _same_frame(vtb.read_parquet(tmp_path / "m.parquet"), df)
    assert back.attrs["units"]["rail_disp_max"] == "m"
    vtb.to_parquet(res, tmp_path / "batch.parquet")  # the batch itself: its metrics table
    _same_frame(vtb.read_parquet(tmp_path / "batch.parquet"), df)
    assert vtb.to_parquet is vtb.run.tables.to_parquet and "to_parquet" in vtb.__all__
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


def test_study_result_exports_with_units(tiny, tmp_path):
    st = vtb.study(tiny, {"speed": [70.0, 80.0]}, reference={"tids": None},
                   indices=["rail_acc_max", "slab_disp_max"], progress=False)
    assert len(st) == 3
    df = _round_trip(st, tmp_path, "study")
    assert df["speed"].iloc[1:].tolist() == [70.0, 80.0] and np.isnan(df["speed"].iloc[0])
    np.testing.assert_array_equal(df["rail_acc_max"].to_numpy(), st.columns["rail_acc_max"])
    assert df.attrs["units"] == {"case": "–", "speed": "m/s", "rail_acc_max": "m/s²", "slab_disp_max": "m"}


def test_optimization_results_export_with_units(tiny, tmp_path):
    article = vtb.optimize(tiny, pop_size=4, n_gen=1, seed=1, progress=False)
    df = _round_trip(article, tmp_path, "opt")
    assert len(df) == len(article)
    for k in ("k_t", "rail_acc_max", "eta_r"):
        np.testing.assert_array_equal(df[k].to_numpy(), article.pareto[k])
    u = df.attrs["units"]
    assert (u["b_t"], u["k_t"], u["c_t"], u["rail_acc_max"], u["eta_r"]) == ("kg", "N/m", "N·s/m", "m/s²", "–")
    generic = vtb.optimize(tiny, variables={"tids.stiffness": (1e7, 8e8, "log"), "speed": (60.0, 90.0)},
                           objectives=["rail_acc_max"], report=["slab_disp_max"], pop_size=4, n_gen=1, seed=1, progress=False)
    assert isinstance(generic, vtb.ParetoResult) and len(generic) >= 1
    df = _round_trip(generic, tmp_path, "pareto")
    np.testing.assert_array_equal(df["tids.stiffness"].to_numpy(), generic.pareto["tids.stiffness"])
    assert df.attrs["units"] == {"tids.stiffness": "N/m", "speed": "m/s", "rail_acc_max": "m/s²", "slab_disp_max": "m"}


def test_robust_results_export_with_units(tiny, tmp_path):
    rs = vtb.sweep(tiny, b_t=[5.0], k_t=[2e8], c_t=[1e3, 2e3], samples=[3], speeds=[80.0], progress=False)
    assert len(rs.designs) == 2
    df = _round_trip(rs, tmp_path, "robust")
    assert df["c_t"].tolist() == [1e3, 2e3]
    u = df.attrs["units"]
    assert (u["b_t"], u["k_t"], u["c_t"]) == ("kg", "N/m", "N·s/m")
    ratios = [c for c in df.columns if c.startswith(("ratio_", "mean_", "sem_"))] + ["satisfaction_rate"]
    assert len(ratios) > 3 and all(u[c] == "–" for c in ratios)  # X/X0, not the metric's unit
    rs.to_parquet(tmp_path / "robust_max.parquet", statistic_name="max")
    _same_frame(vtb.read_parquet(tmp_path / "robust_max.parquet"), rs.to_pandas("max"))
    evs = vtb.evaluate_designs(tiny, [dict(b_t=5.0, k_t=2e8, c_t=c) for c in (1e3, 2e3)], samples=[3], speeds=[80.0])
    for i, ev in enumerate(evs):
        df = _round_trip(ev, tmp_path, f"design{i}")
        assert df["speed"].tolist() == [80.0] and df["seed"].tolist() == [3] and df["error"].tolist() == [""]
        assert df["rail_acc_max"].iloc[0] == ev.rows[0]["rail_acc_max"] and df["feasible"].dtype == bool
        u = df.attrs["units"]
        assert (u["speed"], u["seed"], u["rail_acc_max"], u["rail_acc_max_0"]) == ("m/s", "–", "m/s²", "m/s²")


def test_to_parquet_refuses_what_is_not_a_table(tmp_path):
    with pytest.raises(vtb.ConfigError, match="data"):
        vtb.to_parquet(3.0, tmp_path / "x.parquet")
    with pytest.raises(vtb.ConfigError, match="directory"):
        vtb.to_parquet(pd.DataFrame({"a": [1.0]}), tmp_path)
