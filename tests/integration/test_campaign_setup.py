"""A campaign's per-run set-up built once per worker: the same runs bit for bit; ``--runs``."""

import json
from pathlib import Path

import pytest

from motosim.campaign import load_campaign, plan_campaign
from motosim.campaign.execute import Task, _run_one, design_for, run_task
from motosim.cli.main import main

BASE = """
[scenario]
name = "base"
duration = 0.5
[measurement]
current_noise = 0.05
[rider]
kind = "virtual"
path = { kind = "lane_change", offset = 3.5, length = 60.0, start = 2.0 }
probe = { kind = "square", low = -10.0, high = 10.0, period = 0.2 }
[controller]
kind = "paper"
"""

CAMPAIGN = """
[campaign]
name = "setup"
scenario = "base.toml"
sampling = "grid"
seed = 5
metrics = ["rms_tau_r_error", "rms_tracking_error", "max_abs_i_m", "max_abs_e_y"]
[factors]
"handlebar.inertia_factor" = [0.6, 1.4]
"true_handlebar.beta_s" = [0.5, 2.5]
"rider.path.length" = [40.0, 80.0]
"rider.lateral_tolerance" = [0.3, 0.5]
"""


def _write(folder: Path) -> Path:
    (folder / "base.toml").write_text(BASE)
    path = folder / "setup.toml"
    path.write_text(CAMPAIGN)
    return path


def test_runs_reusing_the_workers_set_up_equal_runs_built_alone(tmp_path: Path) -> None:
    plan = plan_campaign(load_campaign(_write(tmp_path)))
    c = plan.campaign
    task = Task(design_for(plan, plan.runs[0].design), plan.base, c.factors, plan.runs, c.metrics)
    columns, _, _ = run_task(task)  # one worker: the rig perturbed, paths and riders shared
    assert len(plan.runs) == 16 and set(columns["status"]) == {"ok"}
    for j, planned in enumerate(plan.runs):
        status, _, _, values, _ = _run_one(task, planned)  # everything built for this run
        assert status == "ok"
        assert values == [columns[m][j] for m in c.metrics], planned.values


def test_runs_n_runs_the_first_n_and_says_so(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _write(tmp_path)
    out = tmp_path / "out"
    assert (
        main(
            ["campaign", str(path), "--out", str(out), "--jobs", "1", "--runs", "3", "--no-report"]
        )
        == 0
    )
    printed = capsys.readouterr().out
    assert "--runs 3: the first 3 of the plan's 16" in printed
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["status"] == "shortened" and manifest["written"] == 3
    assert manifest["shortened_to"] == 3
    # without --runs the same command completes it
    assert main(["campaign", str(path), "--out", str(out), "--jobs", "1", "--no-report"]) == 0
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["status"] == "complete" and manifest["written"] == 16
    assert "(3 already there, 13 run now" in capsys.readouterr().out


@pytest.mark.parametrize("value", ["0", "-2"])
def test_runs_out_of_range_is_one_line(
    tmp_path: Path, value: str, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _write(tmp_path)
    code = main(["campaign", str(path), "--out", str(tmp_path / "o"), "--runs", value])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and f"--runs {value}" in err[0]
