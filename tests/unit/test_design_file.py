"""A design file is refused in one line unless its gains are finite and its loops stable."""

from pathlib import Path

import pytest

from motosim.errors import MotosimError
from motosim.io.design_file import read_design

DESIGN = Path(__file__).parents[1] / "data" / "design_simacom.toml"


def test_the_written_design_reads_back() -> None:
    design = read_design(DESIGN)
    assert design.rate == 1000.0 and design.controller.n_states == 2


def test_observer_factors_default_to_one_and_read_back(tmp_path: Path) -> None:
    """A design file written before the observer's beta_eq and J_eq factors existed is read
    with factors 1 (the observer it was written with); given factors are kept."""
    text = DESIGN.read_text(encoding="utf-8")
    old = tmp_path / "old.toml"
    old.write_text(
        text.replace("damping_factor = 1.0\n", "").replace("inertia_factor = 1.0\n", ""),
        encoding="utf-8",
    )
    settings = read_design(old).observer
    assert (settings.damping_factor, settings.inertia_factor) == (1.0, 1.0)
    path = tmp_path / "d.toml"
    path.write_text(
        text.replace("damping_factor = 1.0", "damping_factor = 0.85").replace(
            "inertia_factor = 1.0", "inertia_factor = 1.25"
        ),
        encoding="utf-8",
    )
    settings = read_design(path).observer
    assert (settings.damping_factor, settings.inertia_factor) == (0.85, 1.25)


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        ("eta = 150.0", "eta = nan", "observer.eta = nan; expected a finite number"),
        ("poles = [-0.1, -60.0]", "poles = [0.1, -60.0]", "poles[0] = 0.1; expected"),
        ("poles = [-0.1, -60.0]", "poles = 'fast'", "poles = 'fast'; expected two negative"),
        (
            "injection_bandwidth = 800.0",
            "injection_bandwidth = 100000.0",
            "the sampled injection loop is unstable",
        ),
        ("friction_compensation = true", "friction_compensation = 'yes'", "expected true or"),
        (
            "damping_factor = 1.0",
            "damping_factor = 0.0",
            "damping_factor = 0.0; expected a finite number > 0",
        ),
        ("rate = 1000.0", "rate = 1e300", "expected a number of magnitude <= 1e+15"),
        ("rate = 1000.0", "rate = 5.0", "rate = 5.0; expected a finite number >= 10"),
        ("J_eq = 0.0415", "J_eq = [0.0415]", "J_eq = [0.0415] is a list"),
        ("[observer]", "[observr]", "unknown table 'observr'; did you mean 'observer'?"),
        ("D = [[-375.6802750427942]]", "D = [[375.68]]", "the loop with the nominal handlebar"),
        ("D = [[-375.6802750427942]]", "D = [['x']]", "expected a matrix of numbers"),
        ("D = [[-375.6802750427942]]", "D = {a = 1}", "expected a matrix as a list"),
        (
            "A = [[0.6428256374832854, 0.0], [0.11236873797921235, 1.0]]",
            "A = [[0.6428256374832854, 0.0], [0.11236873797921235, 1.5]]",
            "[controller.zoh]: the loop sampled at 1000 Hz has a spectral radius",
        ),
    ],
)
def test_refused(tmp_path: Path, old: str, new: str, message: str) -> None:
    text = DESIGN.read_text(encoding="utf-8")
    assert old in text
    bad = tmp_path / "d.toml"
    bad.write_text(text.replace(old, new, 1), encoding="utf-8")
    with pytest.raises(MotosimError) as info:
        read_design(bad)
    assert message in str(info.value) and "\n" not in str(info.value)
