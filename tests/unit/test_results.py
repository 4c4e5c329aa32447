"""Result files: writer/loader round trip, interrupted runs, CSV format, one-line errors."""

import csv
from dataclasses import dataclass
from pathlib import Path

import h5py
import numpy as np
import pytest

from motosim.errors import MotosimError
from motosim.io.results import ResultWriter, SimResult, load_result, partial_folder

NAMES = ("t", "tau_r", "tau_r_hat", "theta_h", "delta", "phi")


@dataclass(frozen=True, slots=True)
class _Params:
    J_h: float
    gains: np.ndarray


def _block(start: int, m: int, dt: float = 1e-3) -> np.ndarray:
    t = (start + np.arange(m)) * dt
    rng = np.random.default_rng(start)
    return np.column_stack([t, rng.standard_normal((m, len(NAMES) - 1)) / 3.0])


def test_round_trip(tmp_path: Path) -> None:
    metadata = {
        "scenario": {"name": "slalom", "duration": 2.0},
        "seed": 7,
        "version": "0.1.0",
        "parameters": _Params(0.0205, np.array([1.0, 2.5])),
        "speed": np.float64(20.0),
    }
    blocks = [_block(0, 5), _block(5, 300), _block(305, 1)]
    with ResultWriter(tmp_path / "run", NAMES, metadata) as writer:
        for block in blocks:
            writer.append(block)
        assert writer.rows == 306
        writer.close({"rms_tau_r_error": 0.25, "note": "ok"})
    result = load_result(tmp_path / "run")
    expected = np.vstack(blocks)
    assert result.names == NAMES[1:]
    np.testing.assert_array_equal(result.t, expected[:, 0])
    np.testing.assert_array_equal(result.data, expected[:, 1:])
    np.testing.assert_array_equal(result["phi"], expected[:, -1])
    assert result.metadata == {
        "scenario": {"name": "slalom", "duration": 2.0},
        "seed": 7,
        "version": "0.1.0",
        "parameters": {"J_h": 0.0205, "gains": [1.0, 2.5]},
        "speed": 20.0,
    }
    assert result.summary == {"rms_tau_r_error": 0.25, "note": "ok"}
    assert result.complete is True


def test_leaving_the_block_completes_without_summary(tmp_path: Path) -> None:
    with ResultWriter(tmp_path, NAMES, {}) as writer:
        writer.append(_block(0, 3))
    result = load_result(tmp_path)
    assert result.complete and result.summary == {} and result.t.size == 3


def _interrupted_run(folder: Path, blocks: list[np.ndarray]) -> None:
    with ResultWriter(folder, NAMES, {"seed": 1}) as writer:
        for block in blocks:
            writer.append(block)
        raise KeyboardInterrupt


def test_interrupted_run_keeps_its_rows(tmp_path: Path) -> None:
    blocks = [_block(0, 40), _block(40, 40)]
    with pytest.raises(KeyboardInterrupt):
        _interrupted_run(tmp_path, blocks)
    result = load_result(tmp_path)
    assert result.complete is False and result.summary == {}
    np.testing.assert_array_equal(result.data, np.vstack(blocks)[:, 1:])
    # the CSV says it is partial by its name; a rerun replaces it without overwrite
    assert not (tmp_path / "result.csv").exists()
    assert len((tmp_path / "result.partial.csv").read_text().splitlines()) == 81
    with ResultWriter(tmp_path, NAMES, {}) as writer:
        writer.append(_block(0, 3))
    assert load_result(tmp_path).complete and (tmp_path / "result.csv").exists()


def test_file_is_readable_while_the_run_goes(tmp_path: Path) -> None:
    with ResultWriter(tmp_path, NAMES, {}) as writer:
        writer.append(_block(0, 10))
        assert writer.location == partial_folder(tmp_path)
        partial = load_result(writer.location)
        writer.append(_block(10, 10))
    assert partial.t.size == 10 and not partial.complete
    assert load_result(tmp_path).t.size == 20


def test_reserved_but_unwritten_rows_are_dropped(tmp_path: Path) -> None:
    # A crash between resizing the dataset and writing its rows leaves NaN-filled rows.
    with ResultWriter(tmp_path, NAMES, {}) as writer:
        writer.append(_block(0, 10))
    with h5py.File(tmp_path / "result.h5", "r+") as h5:
        h5["signals"].resize(15, axis=0)
        h5.attrs["complete"] = False
    assert load_result(tmp_path).t.size == 10


def test_csv_header_precision_and_increasing_time(tmp_path: Path) -> None:
    blocks = [_block(0, 50), _block(50, 50)]
    with ResultWriter(tmp_path, NAMES, {}) as writer:
        for block in blocks:
            writer.append(block)
    with (tmp_path / "result.csv").open(newline="") as handle:
        rows = list(csv.reader(handle))
    assert tuple(rows[0]) == NAMES
    values = np.array(rows[1:], dtype=float)
    np.testing.assert_array_equal(values, np.vstack(blocks))  # repr round-trips exactly
    assert np.all(np.diff(values[:, 0]) > 0)


@pytest.mark.parametrize(
    ("block", "message"),
    [
        (np.zeros((2, 3)), "block of shape (2, 3); expected (m, 6)"),
        (np.zeros(6), "block of shape (6,); expected (m, 6)"),
        (np.column_stack([[0.1, 0.1], np.zeros((2, 5))]), "expected strictly increasing t"),
        (np.column_stack([[0.001], np.zeros((1, 5))]), "t = 0.001 s after 0.004 s"),
        (np.column_stack([[np.nan], np.zeros((1, 5))]), "t = nan; expected finite"),
    ],
)
def test_bad_blocks(tmp_path: Path, block: np.ndarray, message: str) -> None:
    with ResultWriter(tmp_path, NAMES, {}) as writer:
        writer.append(_block(0, 5))
        with pytest.raises(MotosimError) as info:
            writer.append(block)
    assert message in str(info.value) and "\n" not in str(info.value)


@pytest.mark.parametrize(
    ("names", "metadata", "message"),
    [
        (("tau_r", "t"), {}, "expected 't' first"),
        (("t", "a", "a"), {}, "'a' appears twice"),
        (("t", "a,b"), {}, "without commas"),
        (("t", "a"), {"when": object()}, "metadata.when: value of type object cannot be stored"),
    ],
)
def test_bad_writer_arguments(
    tmp_path: Path, names: tuple[str, ...], metadata: dict[str, object], message: str
) -> None:
    with pytest.raises(MotosimError) as info:
        ResultWriter(tmp_path, names, metadata)
    assert message in str(info.value) and "\n" not in str(info.value)


def test_existing_result_is_not_overwritten_unless_asked(tmp_path: Path) -> None:
    with ResultWriter(tmp_path, NAMES, {}) as writer:
        writer.append(_block(0, 5))
    with pytest.raises(MotosimError, match="a result is already there"):
        ResultWriter(tmp_path, NAMES, {})
    with ResultWriter(tmp_path, NAMES, {}, overwrite=True) as writer:
        writer.append(_block(0, 2))
    assert load_result(tmp_path).t.size == 2


def test_append_after_close(tmp_path: Path) -> None:
    writer = ResultWriter(tmp_path, NAMES, {})
    writer.close()
    writer.close()  # closing twice does nothing
    with pytest.raises(MotosimError, match="the result is closed"):
        writer.append(_block(0, 1))


def test_unwritable_folder(tmp_path: Path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(MotosimError) as info:
        ResultWriter(blocker / "run", NAMES, {})
    assert str(blocker / "run") in str(info.value) and "\n" not in str(info.value)


def _text_file(tmp_path: Path) -> Path:
    (tmp_path / "result.h5").write_text("t,x\n0,1\n")
    return tmp_path


def _not_a_result(tmp_path: Path) -> Path:
    with h5py.File(tmp_path / "result.h5", "w") as h5:
        h5["x"] = np.zeros(3)
    return tmp_path


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda p: p / "missing", "no such result folder"),
        (lambda p: p, "no result.h5"),
        (_text_file, "not a readable HDF5 file"),
        (_not_a_result, "not a motosim result"),
    ],
)
def test_load_errors(tmp_path: Path, make: object, message: str) -> None:
    assert callable(make)
    with pytest.raises(MotosimError) as info:
        load_result(make(tmp_path))
    assert message in str(info.value) and "\n" not in str(info.value)


def test_sim_result_checks_shapes() -> None:
    with pytest.raises(MotosimError, match="expected t"):
        SimResult(np.zeros(3), np.zeros((2, 1)), ("phi",), {}, {}, True)
    result = SimResult(np.zeros(1), np.zeros((1, 1)), ("phi",), {}, {}, True)
    with pytest.raises(KeyError, match="no signal 'psi'"):
        result["psi"]
