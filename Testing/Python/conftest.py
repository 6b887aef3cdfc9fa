"""Shared fixtures for the Python test suites."""
import os
import pathlib

import numpy as np
import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
SHARED_DATA = REPO.parent / "shared" / "data"


def shared_volumes():
    """Names of the real segmentation volumes in ../shared/data (see its README)."""
    return sorted(p.name[: -len(".nrrd")] for p in SHARED_DATA.glob("*.nrrd"))


@pytest.fixture(scope="session")
def shared_data():
    if not SHARED_DATA.is_dir():
        pytest.fail(f"the shared test data folder {SHARED_DATA} is missing")
    return SHARED_DATA


@pytest.fixture
def rng():
    return np.random.default_rng(12345)
