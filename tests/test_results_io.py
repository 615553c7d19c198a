"""Results and configs a user handles: save/load round trips with the configuration that
made them, one-line representations, metric units, and the CLI's version and headers."""

import numpy as np
import pytest

import vtb
from fuzz_cases import small_config
from vtb import cli


def _short_run():
    cfg = small_config(t_end=0.05, tids=False)
    cfg.irregularity.scale = 30.0  # enough to lift the wheels: contact-loss periods to keep
    return cfg


def test_a_saved_result_loads_back_whole(tmp_path):
    res = vtb.simulate(_short_run())
    path = tmp_path / "r.npz"
    res.save(path)
    back = vtb.load(path)
    for name in ("t", "disp", "acc", "vehicle_disp", "vehicle_acc", "contact_force"):
        assert np.array_equal(getattr(back, name), getattr(res, name)), name
    assert back.metrics() == res.metrics()
    assert back.contact_loss == res.contact_loss and res.contact_loss
    assert back.config == res.config
    assert back.layer_names == res.layer_names and back.points == res.points


def test_load_refuses_other_files(tmp_path):
    np.savez(tmp_path / "other.npz", x=np.ones(3))
    with pytest.raises(vtb.ConfigError, match="vtb.Result.save"):
        vtb.load(tmp_path / "other.npz")
    with pytest.raises(vtb.ConfigError, match="no such file"):
        vtb.load(tmp_path / "missing.npz")


def test_short_reprs_and_metric_units():
    cfg = _short_run()
    text = repr(cfg)
    assert text.startswith("Config(hybrid: rail(8+8)") and "\n" not in text and len(text) < 300
    res = vtb.simulate(cfg)
    r = repr(res)
    assert "1000 steps" in r and "rail_acc_max" in r and "m/s²" in r and len(r) < 400
    units = {k: vtb.metric_unit(k) for k in res.metrics()}
    assert units["rail_acc_max"] == "m/s²" and units["slab_disp_max"] == "m" and units["rail_acc_settle"] == "s"
    assert units["contact_force_max"] == "N" and units["car_acc_rms"] == "m/s²"
    with pytest.raises(vtb.ConfigError):
        vtb.metric_unit("nope")


def test_cli_version_and_units(tmp_path, capsys):
    with pytest.raises(SystemExit) as e:
        cli.main(["--version"])
    assert e.value.code == 0 and capsys.readouterr().out.strip() == f"vtb {vtb.__version__}"
    cfg = _short_run()
    cfg.irregularity.scale = 1.0
    cfg.to_toml(tmp_path / "c.toml")
    assert cli.main(["simulate", "--config", str(tmp_path / "c.toml")]) == 0
    out = capsys.readouterr().out
    assert any(line.startswith("rail_acc_max") and line.rstrip().endswith("m/s²") for line in out.splitlines())


def test_validate_writes_its_real_command(tmp_path, monkeypatch):
    import types

    import vtb.article.validation as validation

    seen = {}
    case = types.SimpleNamespace(label=validation.REFERENCE, values={("raw", None): None}, seconds={("raw", None): 0.0})
    zero = dict(rail_acc_lp=0.0, bands_max=0.0, rail_disp=0.0, slab_acc_lp=0.0)
    monkeypatch.setattr(validation, "run_study", lambda **kw: [case])
    monkeypatch.setattr(validation, "errors", lambda a, b: zero)
    monkeypatch.setattr(validation, "write_report", lambda cases, path, command: seen.setdefault("command", command))
    out = tmp_path / "v.md"
    assert cli.main(["validate", "--out", str(out), "--workers", "1", "--no-progress"]) == 0
    assert seen["command"] == f"vtb validate --out {out} --workers 1 --no-progress"
