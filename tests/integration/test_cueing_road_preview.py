"""The MPC with the road preview against the washout on the lane changes and a swerve, by the score.

Issue 13's target on the training scenario the causal MPC missed, the lane change at 20 m/s,
and on the unseen one at 30 m/s that the preview first missed too (the comparison table of
docs/guide/cueing.md, ``python bench/bench_cueing.py RUNS``: with the road preview at 20 m/s
2.10 against 2.42 % false cues, 3.04 against 4.36 deg/s roll, 0.24 against 0.50 deg/s pitch;
at 30 m/s 2.49 against 2.73 %, 3.22 against 4.25 deg/s, 0.18 against 0.34 deg/s; from the
present motion only 2.6 and 3.2 % false cues, above the washout's). Run through ``motosim
cueing``, whose ``--preview road`` is the default: the test fails without the preview (the
``none`` run is checked to miss), and at 30 m/s without the preview's terminal force band
and its lean leading by a distance (3.22 % false cues: a counter-tilt held after the
manoeuvre, docs/guide/cueing.md).

Each claim is stated with the margins of :mod:`cueing_claims`: on the lane change at 30 m/s
the false cues with the preview are comparable to the washout's (0.92-1.01 of them across
CPUs' BLAS kernels), not fewer; its roll and pitch errors are lower.
"""

import json
import tomllib
from pathlib import Path

import numpy as np
import pytest
from cueing_claims import beats, comparable, misses

from motosim.cli.main import main
from motosim.sim.road import scenario_road
from motosim.sim.scenario import parse_scenario

ROOT = Path(__file__).parents[2]
CHANNELS = ("roll", "pitch", "yaw", "surge", "sway")


def _cue(result: Path, out: Path, capsys: pytest.CaptureFixture[str], *extra: str) -> dict:
    assert main(["cueing", str(result), "--out", str(out), "--json", *extra]) == 0
    return dict(json.loads(capsys.readouterr().out))


@pytest.mark.parametrize(
    "scenario", ["scenarios/lane_change_20.toml", "bench/scenarios/lane_change_30.toml"]
)
def test_lane_change_mpc_with_road_preview_beats_the_washout(
    scenario: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    pytest.importorskip("osqp", reason="the MPC needs the cueing extra (osqp)")
    run = tmp_path / "run"
    assert main(["simulate", str(ROOT / scenario), "--out", str(run), "--no-report"]) == 0
    capsys.readouterr()
    scores = {}
    for label, extra in (
        ("washout", ()),
        ("road", ("--algorithm", "mpc")),
        ("none", ("--algorithm", "mpc", "--preview", "none")),
    ):
        summary = _cue(run, tmp_path / label, capsys, *extra)
        assert summary["preview"] == ("none" if label != "road" else "road")
        s = summary["score"]
        assert s["violations"] == 0
        false = np.mean([s[f"{c}_false_cue_share"] for c in CHANNELS])
        scores[label] = (false, s["roll_rms_error"], s["pitch_rms_error"])
    road, washout, causal = scores["road"], scores["washout"], scores["none"]
    if "lane_change_20" in scenario:
        assert beats(road[0], washout[0]), scores
        assert misses(causal[0], washout[0]), scores  # the causal plan misses
    else:
        assert comparable(road[0], washout[0]), scores
    assert beats(road[1], washout[1]), scores
    assert beats(road[2], washout[2]), scores
    assert beats(road[1], causal[1]), scores  # the preview is what lowers the roll error


def test_a_rider_torque_scenario_has_no_road() -> None:
    path = ROOT / "scenarios" / "paper_controller_square.toml"
    scenario = parse_scenario(tomllib.loads(path.read_text()), origin=str(path))
    assert scenario_road(scenario) is None
    lane = ROOT / "scenarios" / "lane_change_20.toml"
    road = scenario_road(parse_scenario(tomllib.loads(lane.read_text()), origin=str(lane)))
    assert road is not None and float(np.max(np.abs(road.kappa))) > 0.0


def test_unseen_swerve_at_18_mps_mpc_with_road_preview_beats_the_washout(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Issue 13's target on an unseen swerve added with the diagnosis of the two misses,
    before its cueing was looked at (docs/guide/cueing.md table, ``python
    bench/bench_cueing.py RUNS``: 5.3 against 5.8 % false cues, 11.65 against 13.59 deg/s
    roll, 1.09 against 1.80 deg/s pitch)."""
    pytest.importorskip("osqp", reason="the MPC needs the cueing extra (osqp)")
    run = tmp_path / "run"
    scenario = ROOT / "bench/scenarios/avoidance_18.toml"
    assert main(["simulate", str(scenario), "--out", str(run), "--no-report"]) == 0
    capsys.readouterr()
    scores = {}
    for label, extra in (("washout", ()), ("road", ("--algorithm", "mpc"))):
        s = _cue(run, tmp_path / label, capsys, *extra)["score"]
        assert s["violations"] == 0
        false = np.mean([s[f"{c}_false_cue_share"] for c in CHANNELS])
        scores[label] = (false, s["roll_rms_error"], s["pitch_rms_error"])
    assert all(beats(r, w) for r, w in zip(scores["road"], scores["washout"], strict=True)), scores


def _against_the_washout(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    name: str,
    *changes: tuple[str, str, str],
) -> dict[str, tuple[float, float, float]]:
    """Mean false-cue share, roll and pitch RMS errors of ``bench/scenarios/NAME.toml`` cued
    by the washout, by the MPC with the road preview ("road") and by the MPC with, for each
    of ``changes`` ``(key, packaged, variant)``, the packaged platform file's ``key =
    packaged`` set to ``variant`` ("variant")."""
    pytest.importorskip("osqp", reason="the MPC needs the cueing extra (osqp)")
    run = tmp_path / "run"
    scenario = ROOT / f"bench/scenarios/{name}.toml"
    assert main(["simulate", str(scenario), "--out", str(run), "--no-report"]) == 0
    capsys.readouterr()
    text = (ROOT / "src/motosim/cueing/data/simacom_platform.toml").read_text()
    for key, packaged, variant in changes:
        assert f"{key} = {packaged}\n" in text
        text = text.replace(f"{key} = {packaged}\n", f"{key} = {variant}\n")
    changed = tmp_path / "variant.toml"
    changed.write_text(text)
    scores = {}
    for label, extra in (
        ("washout", ()),
        ("road", ("--algorithm", "mpc")),
        ("variant", ("--algorithm", "mpc", "--platform", str(changed))),
    ):
        s = _cue(run, tmp_path / label, capsys, *extra)["score"]
        assert s["violations"] == 0
        false = float(np.mean([s[f"{c}_false_cue_share"] for c in CHANNELS]))
        scores[label] = (false, s["roll_rms_error"], s["pitch_rms_error"])
    return scores


def test_long_curve_mpc_with_the_band_scheduled_by_persistence_beats_the_washout(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Issue 13's target on the OpenDRIVE curve at 25 m/s, an unseen run the preview missed
    on the roll error while its force band washed out the washout's sustained roll
    (docs/guide/cueing.md table, ``python bench/bench_cueing.py RUNS``: with the band
    scheduled by the curve's persistence 6.87 against 8.01 % false cues, 1.78 against 2.08
    deg/s roll, 0.90 against 0.94 deg/s pitch; not scheduled, the platform file's
    ``sustained_force_false_cue_weight`` set to the transient 1.5: 2.84 deg/s roll; with the
    transient weight 2.25, scheduled 6.88 % and 1.79 deg/s, not scheduled 3.04 deg/s)."""
    scores = _against_the_washout(
        tmp_path, capsys, "opendrive_curve_25", ("sustained_force_false_cue_weight", "0.0", "2.25")
    )
    assert all(beats(r, w) for r, w in zip(scores["road"], scores["washout"], strict=True)), scores
    assert misses(scores["variant"][1], scores["washout"][1]), scores  # the miss before


def test_unseen_swerve_at_22_mps_mpc_with_the_huber_roll_cost_beats_the_washout(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Issue 13's target on the unseen swerve at 22 m/s, which the preview missed on the false
    cues (the plan took false lateral cues for a roll rate of up to 67 deg/s the platform
    cannot render, its roll-rate error squared; docs/guide/cueing.md table, ``python
    bench/bench_cueing.py RUNS``: with the roll canal error's Huber cost, corner 4 thresholds
    chosen on the training runs, and the transient force band's weight chosen again with it,
    2.25: 3.11 against 4.18 % false cues, 14.91 against 15.99 deg/s roll; with the weight
    1.5 before it 3.64 %; squared, ``roll_canal_corner = 0.0``, with 1.5, 4.29 %). The
    variant sets both back, the design before both: its false cues are comparable to the
    washout's (0.97-1.03 of them across CPUs' BLAS kernels), and the two changes cut them by
    over a fifth."""
    scores = _against_the_washout(
        tmp_path,
        capsys,
        "avoidance_22",
        ("roll_canal_corner", "4.0", "0.0"),
        ("preview_force_false_cue_weight", "2.25", "1.5"),
    )
    assert all(beats(r, w) for r, w in zip(scores["road"], scores["washout"], strict=True)), scores
    assert beats(scores["road"][0], scores["variant"][0]), scores  # what the two changes win


def test_heldout_swerve_at_19_mps_mpc_with_the_band_weight_chosen_again_beats_the_washout(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Issue 13's target on the held-out swerve at 19 m/s (``bench/scenarios/heldout/``), which
    the MPC missed on the false cues with the transient force band's weight of 1.5 chosen for
    the squared roll canal error: the plan let the lateral force of each half's tilt linger
    after the lean, where the washout's return past neutral quenches it. With the weight
    chosen again on the training runs with the Huber cost, 2.25 (docs/guide/cueing.md, *The
    held-out swerve at 19 m/s*; table, ``python bench/bench_cueing.py RUNS``: 4.44 against
    4.93 % false cues, 12.73 against 14.10 deg/s roll, 1.09 against 1.66 deg/s pitch; with
    1.5, 5.20 %)."""
    scores = _against_the_washout(
        tmp_path, capsys, "heldout/avoidance_19", ("preview_force_false_cue_weight", "2.25", "1.5")
    )
    assert all(beats(r, w) for r, w in zip(scores["road"], scores["washout"], strict=True)), scores
    assert misses(scores["variant"][0], scores["washout"][0]), scores  # the miss before
