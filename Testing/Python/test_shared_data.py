"""The real volumes (../shared/data, or VTKSVDAG_SHARED_DATA) are optional on a fresh clone:
tests that need them skip, naming the missing folder. Under CI (CI=true) they must be there."""
import pytest
from conftest import SHARED_DATA, shared_data_missing_message, under_ci


def test_ci_has_the_shared_data():
    if SHARED_DATA.is_dir() and any(SHARED_DATA.glob("*.nrrd")):
        return
    if under_ci():
        pytest.fail(shared_data_missing_message() + " under CI (CI=true): CI must provide it")
    # Outside CI a missing folder is fine: the tests that need it skip with this message.
