"""Shared fixtures: the packaged reference parameter sets; deterministic property tests."""

from collections.abc import Iterator

import pytest
from hypothesis import settings

from motosim.params import HandlebarParameters, SharpParameters, load_parameters

# property tests draw the same examples on every run, so CI is reproducible
settings.register_profile("deterministic", derandomize=True, deadline=None)
settings.load_profile("deterministic")


@pytest.fixture(scope="session", autouse=True)
def _design_cache(tmp_path_factory: pytest.TempPathFactory) -> Iterator[None]:
    """A design cache of the test session's own (the commands run by the tests inherit it),
    never the user's (motosim.io.cache)."""
    patch = pytest.MonkeyPatch()
    patch.setenv("MOTOSIM_CACHE_DIR", str(tmp_path_factory.mktemp("design-cache")))
    yield
    patch.undo()


@pytest.fixture(scope="session")
def sharp() -> SharpParameters:
    """Sharp (1971) standard machine."""
    return load_parameters("sharp1971", "sharp")


@pytest.fixture(scope="session")
def handlebar() -> HandlebarParameters:
    """SIMACOM handlebar, Table I of Nehaoua, Arioui & Mammar (2012)."""
    return load_parameters("simacom_handlebar", "handlebar")
