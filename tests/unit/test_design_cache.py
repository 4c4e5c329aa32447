"""The design cache (motosim.io.cache): what it promises.

A cached design is the design: a run from designs read back is bit for bit the run designed
afresh; the key changes with every input; concurrent writers leave one whole entry; an
entry that cannot be read is designed again, with a warning.
"""

import dataclasses
import multiprocessing
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from motosim.errors import MotosimWarning
from motosim.io.cache import DesignCache, cache_folder, cached_stack, design_key
from motosim.io.runs import resolve
from motosim.params import HandlebarParameters
from motosim.sim import parse_scenario, simulate
from motosim.sim.rider import RiderGains

LANE_CHANGE = {
    "scenario": {"name": "cache_lane_change", "duration": 1.0},
    "motorcycle": {"speed": 20.0},
    "rider": {
        "kind": "virtual",
        "path": {"kind": "lane_change", "offset": 3.5, "length": 60.0, "start": 5.0},
    },
}


def test_cached_designs_give_the_same_run_bit_for_bit(tmp_path: Path) -> None:
    scenario = parse_scenario(LANE_CHANGE, origin="test")
    fresh = resolve(scenario, ".")
    expected = simulate(fresh, rng=np.random.default_rng(0))
    designs: list[tuple[str, float | None]] = []
    cache = DesignCache(tmp_path, on_design=lambda label, s: designs.append((label, s)))
    for _ in range(2):  # designed and stored, then read back
        with cache.designing(scenario.name):
            inputs = resolve(scenario, ".", cache=cache)
            stack = cached_stack(cache, inputs)
        run = simulate(inputs, rng=np.random.default_rng(0), stack=stack)
        assert np.array_equal(run.data, expected.data) and np.array_equal(run.t, expected.t)
    assert fresh.controller is not None and inputs.controller is not None
    for m in "ABCD":
        assert np.array_equal(getattr(inputs.controller, m), getattr(fresh.controller, m))
    assert sorted(p.name.split("-")[0] for p in tmp_path.glob("*.npz")) == [
        "controller",
        "rider",
        "stack",
    ]
    # one announcement (start, end) for the first run, none for the second
    assert [label for label, _ in designs] == [scenario.name] * 2
    assert designs[0][1] is None and designs[1][1] is not None and designs[1][1] > 0


def test_a_disabled_cache_designs_and_stores_nothing(tmp_path: Path) -> None:
    calls = []
    cache = DesignCache(None)
    gains = RiderGains(np.ones(2), np.ones((2, 10)), np.ones((2, 8)), np.ones(2), 0.3, 70.0)
    for _ in range(2):
        cache.fetch("rider", {"x": 1.0}, lambda: calls.append(1) or gains, RiderGains)
    assert len(calls) == 2


def test_the_folder_follows_the_environment() -> None:
    assert cache_folder({"MOTOSIM_CACHE_DIR": "/a/b"}) == Path("/a/b")
    assert cache_folder({"XDG_CACHE_HOME": "/x"}) == Path("/x/motosim")
    assert cache_folder({}) == Path.home() / ".cache" / "motosim"


BASE = {"rate": 1000.0, "bandwidth": None, "order": 1, "integral_corner": 0.5, "n_starts": 4}


@given(
    field=st.sampled_from(["J_eq", "beta_eq", "beta_s", "k_t"]),
    factor=st.floats(0.5, 2.0).filter(lambda f: f != 1.0),
    setting=st.sampled_from(sorted(BASE)),
)
def test_the_key_changes_with_every_input(
    handlebar: HandlebarParameters, field: str, factor: float, setting: str
) -> None:
    hb = handlebar
    base = design_key("controller", {"handlebar": hb, **BASE})
    assert design_key("controller", {"handlebar": hb, **BASE}) == base
    other = dataclasses.replace(hb, **{field: getattr(hb, field) * factor})
    assert design_key("controller", {"handlebar": other, **BASE}) != base
    changed = {**BASE, setting: 2 if BASE[setting] is None else BASE[setting] * factor}
    assert design_key("controller", {"handlebar": hb, **changed}) != base
    assert design_key("rider", {"handlebar": hb, **BASE}) != base


def test_the_key_changes_with_the_version(monkeypatch: pytest.MonkeyPatch) -> None:
    import motosim.io.cache as cache_module

    base = design_key("stack", {"x": 1.0})
    monkeypatch.setattr(cache_module, "__version__", "0.0.0-other")
    assert design_key("stack", {"x": 1.0}) != base
    monkeypatch.setattr(cache_module, "source_hash", lambda: "other source")
    assert design_key("stack", {"x": 1.0}) != base


def _write_many(folder: str) -> None:
    cache = DesignCache(folder)
    path = cache.path("rider", "same")
    assert path is not None
    big = {
        "speeds": np.arange(200_000.0),
        "K": np.ones((3, 10)),
        "x_ss": np.ones((3, 8)),
        "tau_ss": np.ones(3),
        "preview": np.asarray(0.3),
        "max_torque": np.asarray(70.0),
    }
    for _ in range(20):
        cache._store(path, big)


def test_two_processes_writing_one_key_leave_one_whole_entry(tmp_path: Path) -> None:
    context = multiprocessing.get_context("spawn")
    workers = [context.Process(target=_write_many, args=(str(tmp_path),)) for _ in range(2)]
    for w in workers:
        w.start()
    for w in workers:
        w.join(120)
        assert w.exitcode == 0
    assert [p.name for p in tmp_path.iterdir()] == ["rider-same.npz"]  # no temporary left
    with np.load(tmp_path / "rider-same.npz", allow_pickle=False) as stored:
        assert np.array_equal(stored["speeds"], np.arange(200_000.0))


def test_a_corrupt_entry_is_designed_again_with_a_warning(tmp_path: Path) -> None:
    cache = DesignCache(tmp_path)
    gains = RiderGains(np.ones(2), np.ones((2, 10)), np.ones((2, 8)), np.ones(2), 0.3, 70.0)
    cache.fetch("rider", {"x": 1.0}, lambda: gains, RiderGains)
    (entry,) = tmp_path.glob("rider-*.npz")
    entry.write_bytes(entry.read_bytes()[:100])  # a truncated file
    calls = []
    with pytest.warns(MotosimWarning, match="cannot be read"):
        again = cache.fetch("rider", {"x": 1.0}, lambda: calls.append(1) or gains, RiderGains)
    assert calls == [1] and np.array_equal(again.K, gains.K)
    read = cache.fetch("rider", {"x": 1.0}, lambda: pytest.fail("designed again"), RiderGains)
    assert np.array_equal(read.K, gains.K) and read.preview == 0.3


def test_info_and_clear(tmp_path: Path) -> None:
    cache = DesignCache(tmp_path / "c")
    assert cache.info().entries == {} and cache.clear() == 0
    gains = RiderGains(np.ones(2), np.ones((2, 10)), np.ones((2, 8)), np.ones(2), 0.3, 70.0)
    cache.fetch("rider", {"x": 1.0}, lambda: gains, RiderGains)
    cache.fetch("rider", {"x": 2.0}, lambda: gains, RiderGains)
    info = cache.info()
    assert info.entries == {"rider": 2} and info.size > 0
    assert cache.clear() == 2 and cache.info().entries == {}


def test_the_commands_say_once_that_they_design_and_use_the_cache(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    import json

    from motosim.cli.main import main

    monkeypatch.setenv("MOTOSIM_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setattr("motosim.cli.cache.ANNOUNCE_AFTER", 0.0)  # however quick the design
    monkeypatch.setattr("motosim.cli.cache._on_a_terminal", lambda: True)
    scenario = tmp_path / "s.toml"
    scenario.write_text(
        '[scenario]\nname = "short"\nduration = 0.2\n[controller]\nkind = "paper"\n'
        '[rider]\nkind = "virtual"\n'
        'path = { kind = "lane_change", offset = 3.5, length = 60.0, start = 5.0 }\n'
    )
    args = ["simulate", str(scenario), "--out", str(tmp_path / "r"), "--no-report"]
    assert main([*args]) == 0
    err = capsys.readouterr().err
    assert err.count("short: designing") == 1 and " s\n" in err
    assert len(err.splitlines()) == 1
    assert main([*args, "--overwrite"]) == 0
    assert "designing" not in capsys.readouterr().err
    assert main([*args, "--overwrite", "--no-cache"]) == 0
    assert "designing" in capsys.readouterr().err
    assert main(["cache", "info", "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["folder"] == str(tmp_path / "cache") and info["entries"] == {"rider": 1, "stack": 1}
    assert main(["cache", "clear"]) == 0
    assert "removed 2 design(s)" in capsys.readouterr().out
    assert not list((tmp_path / "cache").glob("*.npz"))


SHORT_LANE_CHANGE = (
    '[scenario]\nname = "warmed"\nduration = 0.5\n'
    '[rider]\nkind = "virtual"\n'
    'path = { kind = "lane_change", offset = 3.5, length = 60.0, start = 5.0 }\n'
)


def test_warm_designs_a_scenario_so_that_its_run_designs_nothing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    import json

    from motosim.cli.main import main

    monkeypatch.setenv("MOTOSIM_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setattr("motosim.cli.cache.ANNOUNCE_AFTER", 0.0)
    monkeypatch.setattr("motosim.cli.cache._on_a_terminal", lambda: True)
    scenario = tmp_path / "s.toml"
    scenario.write_text(SHORT_LANE_CHANGE)
    assert main(["cache", "warm", str(scenario), "--json"]) == 0
    warmed = json.loads(capsys.readouterr().out)
    assert list(warmed["seconds"]) == [str(scenario)] and warmed["seconds"][str(scenario)] > 0
    entries = DesignCache(tmp_path / "cache").info().entries
    assert entries == {"controller": 1, "rider": 1, "stack": 1}
    args = ["simulate", str(scenario), "--out", str(tmp_path / "r"), "--no-report"]
    assert main(args) == 0
    assert "designing" not in capsys.readouterr().err


def test_warm_refuses_a_bad_file_before_designing_any(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    from motosim.cli.main import main

    monkeypatch.setenv("MOTOSIM_CACHE_DIR", str(tmp_path / "cache"))
    good = tmp_path / "s.toml"
    good.write_text(SHORT_LANE_CHANGE)
    bad = tmp_path / "bad.toml"
    bad.write_text(SHORT_LANE_CHANGE.replace("duration = 0.5", "duration = -1.0"))
    assert main(["cache", "warm", str(good), str(bad)]) == 2
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1 and "duration" in err and "Traceback" not in err
    assert DesignCache(tmp_path / "cache").info().entries == {}


def test_after_warm_a_new_process_compiles_nothing(tmp_path: Path) -> None:
    """The install's ``motosim cache warm`` leaves numba's cache holding the loop: a first
    run afterwards writes no new machine code (numba writes an index and a data file for
    each function it compiles, and rewrites the index of one it compiles again)."""
    import os
    import subprocess
    import sys

    env = {
        **os.environ,
        "NUMBA_CACHE_DIR": str(tmp_path / "numba"),
        "MOTOSIM_CACHE_DIR": str(tmp_path / "designs"),
    }
    scenario = tmp_path / "s.toml"
    scenario.write_text(SHORT_LANE_CHANGE)

    def motosim(*args: str) -> None:
        command = [sys.executable, "-m", "motosim", *args]
        subprocess.run(command, env=env, check=True, capture_output=True)

    motosim("cache", "warm", str(scenario))
    compiled = {p: p.stat().st_mtime_ns for p in (tmp_path / "numba").rglob("*.nb[ic]")}
    assert any("closed_loop" in p.name and "_run_chunk" in p.name for p in compiled)
    motosim("simulate", str(scenario), "--out", str(tmp_path / "r"), "--no-report")
    after = {p: p.stat().st_mtime_ns for p in (tmp_path / "numba").rglob("*.nb[ic]")}
    assert after == compiled
