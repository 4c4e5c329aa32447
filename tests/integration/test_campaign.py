"""Campaigns end to end: run, resume, failures, exact reruns, the exported scenario, the CLI,
and the same metrics from every backend."""

import json
import math
from pathlib import Path

import numpy as np
import pytest

from motosim.campaign import load_campaign, load_results, plan_campaign, rerun, run_campaign
from motosim.campaign.export import export_run
from motosim.cli.main import main
from motosim.io.runs import load_run, run_to_folder

BASE = """
[scenario]
name = "base"
duration = 0.3
[measurement]
current_noise = 0.05
[rider]
kind = "torque"
profile = { kind = "square", low = -10.0, high = 10.0, period = 0.1 }
[controller]
kind = "paper"
"""

CAMPAIGN = """
[campaign]
name = "tiny"
scenario = "base.toml"
sampling = "lhs"
runs = 6
seed = 3
metrics = ["rms_tau_r_error", "rms_tracking_error", "max_abs_i_m"]
[factors]
"handlebar.inertia_factor" = {{ distribution = "uniform", low = 0.5, high = 1.5 }}
"true_handlebar.beta_s" = {{ distribution = "uniform", low = 0.0, high = 3.0 }}
"measurement.encoder_bits" = [10, 14]
{extra}
"""


def _write(folder: Path, extra: str = "") -> Path:
    (folder / "base.toml").write_text(BASE)
    path = folder / "tiny.toml"
    path.write_text(CAMPAIGN.format(extra=extra))
    return path


def _same(a: dict[str, np.ndarray], b: dict[str, np.ndarray], names: list[str]) -> bool:
    return all(np.array_equal(a[n], b[n], equal_nan=a[n].dtype.kind == "f") for n in names)


def test_run_resume_and_rerun_bit_identical(tmp_path: Path) -> None:
    campaign = load_campaign(_write(tmp_path))
    out = tmp_path / "out"
    summary = run_campaign(campaign, out, jobs=1)
    assert (summary.runs, summary.computed, summary.failed, summary.designs) == (6, 6, 0, 1)
    results = load_results(out)
    assert list(results["index"]) == list(range(6))
    assert set(results["status"]) == {"ok"}
    assert np.all(results["rms_tau_r_error"] > 0)
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["status"] == "complete" and manifest["written"] == 6
    # an interrupted campaign: drop one part, run again, only its runs are computed
    parts = sorted((out / "parts").glob("part-*.parquet"))
    lost = len(load_results(out)["run_id"])
    parts[0].unlink()
    left = len(load_results(out)["run_id"])
    again = run_campaign(campaign, out, jobs=1)
    assert again.skipped == left and again.computed == lost - left
    assert _same(load_results(out), results, ["run_id", *campaign.metrics])
    # a rerun is bit-identical to the stored run
    plan = plan_campaign(campaign)
    for j in (0, 5):
        row = rerun(plan, str(results["run_id"][j]))
        assert all(row[m] == results[m][j] for m in campaign.metrics)
    # and so is `motosim simulate` of the run written as a scenario file
    run_id = str(results["run_id"][2])
    files = export_run(plan, run_id, tmp_path / "rerun" / "run.toml")
    assert len(files) == 2  # the scenario and its true handlebar (beta_s varies)
    metrics = run_to_folder(load_run(files[0]), tmp_path / "sim")
    assert metrics["rms_tau_r_error"] == results["rms_tau_r_error"][2]
    assert metrics["rms_tracking_error"] == results["rms_tracking_error"][2]


def test_a_folder_of_another_campaign_is_refused(tmp_path: Path) -> None:
    campaign = load_campaign(_write(tmp_path))
    run_campaign(campaign, tmp_path / "out", jobs=1)
    other = load_campaign(_write(tmp_path, '"duration" = [0.2]'))
    with pytest.raises(Exception, match="another campaign"):
        run_campaign(other, tmp_path / "out", jobs=1)


def test_invalid_combinations_are_recorded_failures(tmp_path: Path) -> None:
    # N^2 J_m must stay below J_eq (Table I handlebar: N = 12): J_eq = 0.02 kg*m^2 and
    # J_m = 2e-4 kg*m^2 are each valid, together not (144 * 2e-4 = 0.0288 > 0.02)
    extra = '"true_handlebar.J_eq" = [0.0415, 0.02]\n"true_handlebar.J_m" = [1e-4, 2e-4]'
    path = _write(tmp_path, extra)
    text = path.read_text().replace('sampling = "lhs"', 'sampling = "grid"')
    text = (
        text.replace("runs = 6", "runs = 16")
        .replace('{ distribution = "uniform", low = 0.5, high = 1.5 }', "[1.0]")
        .replace('{ distribution = "uniform", low = 0.0, high = 3.0 }', "[1.0]")
    )
    path.write_text(text)
    summary = run_campaign(load_campaign(path), tmp_path / "out", jobs=1)
    results = load_results(tmp_path / "out")
    bad = (results["true_handlebar.J_eq"] == 0.02) & (results["true_handlebar.J_m"] == 2e-4)
    assert summary.failed == int(bad.sum()) == 4
    assert set(results["status"][bad]) == {"failed"}
    assert all("N^2 J_m" in r for r in results["reason"][bad])
    assert all(math.isnan(v) for v in results["rms_tau_r_error"][bad])


def test_runs_beyond_a_limit_are_failures_with_their_metrics(tmp_path: Path) -> None:
    path = _write(tmp_path)
    free = run_campaign(load_campaign(path), tmp_path / "free", jobs=1)
    assert free.failed == 0
    values = load_results(tmp_path / "free")["max_abs_i_m"]
    limit = float(np.median(values))
    text = path.read_text().replace(
        "[factors]", f"limits = {{ max_abs_i_m = {limit!r} }}\n[factors]"
    )
    path.write_text(text)
    run_campaign(load_campaign(path), tmp_path / "limited", jobs=1)
    limited = load_results(tmp_path / "limited")
    beyond = limited["max_abs_i_m"] > limit
    assert beyond.sum() == 3  # half of the six runs, by the median
    assert set(limited["status"][beyond]) == {"failed"} and set(limited["status"][~beyond]) == {
        "ok"
    }
    assert all(r.startswith("beyond the limit: max_abs_i_m") for r in limited["reason"][beyond])
    assert np.array_equal(limited["max_abs_i_m"], values)


FALLING = """
[scenario]
name = "push"
duration = 3.0
[rider]
kind = "torque"
profile = { kind = "constant", value = 1.0 }
hands = "off"    # a pure torque push: the hands' spring would hold the steer against it
[controller]
kind = "paper"
"""


def test_a_run_that_falls_stops_there_and_is_a_failure(tmp_path: Path) -> None:
    # a steady 20 N*m push with the paper's loose controller capsizes the motorcycle in
    # about 1.9 s (roll beyond 45 deg), a 1 N*m push does not in 3 s: as `motosim simulate`
    # does, the campaign stops the first at the fall and records it as a failure
    (tmp_path / "push.toml").write_text(FALLING)
    (tmp_path / "c.toml").write_text(
        '[campaign]\nname = "push"\nscenario = "push.toml"\nsampling = "grid"\nruns = 2\n'
        'metrics = ["max_abs_phi"]\n[factors]\n"rider.profile.value" = [1.0, 20.0]\n'
    )
    summary = run_campaign(load_campaign(tmp_path / "c.toml"), tmp_path / "out", jobs=1)
    results = load_results(tmp_path / "out")
    fell = results["rider.profile.value"] == 20.0
    assert summary.failed == int(fell.sum()) == 1
    assert set(results["status"][fell]) == {"failed"}
    assert all(r.startswith("the motorcycle fell at t = ") for r in results["reason"][fell])
    assert np.all((results["failed_at"][fell] > 1.0) & (results["failed_at"][fell] < 3.0))
    # stopped at the first row beyond 45 deg, not integrated on
    assert np.all(np.degrees(results["max_abs_phi"][fell]) < 46.0)
    assert set(results["status"][~fell]) == {"ok"}


def test_joblib_and_dask_give_the_serial_metrics(tmp_path: Path) -> None:
    campaign = load_campaign(_write(tmp_path))
    run_campaign(campaign, tmp_path / "serial", jobs=1)
    run_campaign(campaign, tmp_path / "joblib", backend="joblib", jobs=2)
    serial, joblib = load_results(tmp_path / "serial"), load_results(tmp_path / "joblib")
    names = ["run_id", "seed", *campaign.metrics]
    assert _same(serial, joblib, names)
    pytest.importorskip("dask.distributed", reason="the Dask backend needs dask[distributed]")
    run_campaign(campaign, tmp_path / "dask", backend="dask", jobs=2)
    assert _same(serial, load_results(tmp_path / "dask"), names)


def test_cli_runs_reports_reruns_and_refuses_bad_files(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _write(tmp_path)
    out = tmp_path / "out"
    assert main(["campaign", str(path), "--out", str(out), "--jobs", "1", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["computed"] == 6 and Path(summary["report"]).is_file()
    html = Path(summary["report"]).read_text()
    assert "Worst runs" in html and "--rerun" in html
    run_id = str(load_results(out)["run_id"][1])
    scenario = tmp_path / "one.toml"
    argv = ["campaign", str(path), "--out", str(out), "--rerun", run_id]
    assert main([*argv, "--write-scenario", str(scenario), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["identical_to_stored"] is True
    assert scenario.is_file()
    path.write_text(path.read_text().replace("runs = 6", "runs = -1"))
    assert main(["campaign", str(path), "--out", str(out)]) == 2
    assert "runs = -1" in capsys.readouterr().err


def test_series_in_zarr_equal_a_plain_simulate_and_resume_skips_them(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    zarr = pytest.importorskip("zarr", reason="the series store needs zarr (the campaign group)")
    from motosim.campaign import load_series
    from motosim.sim import simulate

    names = ["theta_h", "delta", "tau_r", "tau_r_hat", "i_m"]
    path = _write(tmp_path)
    text = path.read_text().replace("[factors]", f"series = {names}\nevery = 3\n[factors]")
    path.write_text(text.replace("'", '"'))
    campaign = load_campaign(path)
    out = tmp_path / "out"
    run_campaign(campaign, out, backend="joblib", jobs=2)  # two processes write the store
    results = load_results(out)
    store = zarr.open_group(str(out / "series.zarr"), mode="r")
    assert sorted(store.group_keys()) == sorted(results["run_id"].tolist())
    # run 2 read back with zarr equals `motosim simulate` of the run's scenario file
    plan = plan_campaign(campaign)
    run_id = str(results["run_id"][2])
    group = store[run_id]
    files = export_run(plan, run_id, tmp_path / "rerun" / "run.toml")
    inputs = load_run(files[0])
    ts = simulate(inputs, rng=np.random.default_rng(inputs.scenario.seed))
    assert np.array_equal(group["t"][:], ts.t[::3])
    for name in names:
        assert np.array_equal(group[name][:], ts[name][::3]), name
    assert group["tau_r"].attrs["unit"] == "N*m" and group.attrs["every"] == 3
    # resume: the runs of a lost part are computed again, the others' series left alone
    parts = sorted((out / "parts").glob("part-*.parquet"))

    def written(r: str) -> int:
        return (out / "series.zarr" / r / "t" / "zarr.json").stat().st_mtime_ns

    kept = {r: written(r) for r in store.group_keys()}
    parts[0].unlink()
    again = run_campaign(campaign, out, jobs=1)
    assert again.computed + again.skipped == 6 and again.skipped > 0
    unchanged = [r for r, m in kept.items() if written(r) == m]
    assert len(unchanged) == again.skipped
    assert np.array_equal(load_series(out, run_id)["theta_h"], ts["theta_h"][::3])
    # --rerun compares the series too
    argv = ["campaign", str(path), "--out", str(out), "--rerun", run_id, "--json"]
    assert main(argv) == 0
    assert json.loads(capsys.readouterr().out)["identical_to_stored"] is True


def test_an_exported_scenario_that_does_not_fit_leaves_no_cut_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from motosim.errors import MotosimError

    plan = plan_campaign(load_campaign(_write(tmp_path)))
    real = Path.write_text

    def half_then_full(self: Path, text: str, **kwargs: object) -> int:
        real(self, text[: len(text) // 2], **kwargs)  # type: ignore[arg-type]
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(Path, "write_text", half_then_full)
    target = tmp_path / "one.toml"
    with pytest.raises(MotosimError, match=r"one(_true_handlebar)?\.toml: No space left on device"):
        export_run(plan, plan.runs[0].run_id, target)
    # no half scenario is left under its name (which --write-scenario would refuse to replace)
    assert not list(tmp_path.glob("one*"))
    assert not list(tmp_path.glob(".one*"))
