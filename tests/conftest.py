"""Shared fixtures: the packaged reference parameter sets."""

import pytest

from motosim.params import HandlebarParameters, SharpParameters, load_parameters


@pytest.fixture(scope="session")
def sharp() -> SharpParameters:
    """Sharp (1971) standard machine."""
    return load_parameters("sharp1971", "sharp")


@pytest.fixture(scope="session")
def handlebar() -> HandlebarParameters:
    """SIMACOM handlebar, Table I of Nehaoua, Arioui & Mammar (2012)."""
    return load_parameters("simacom_handlebar", "handlebar")
