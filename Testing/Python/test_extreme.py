"""The stiff and extreme cases (Testing/Python/extreme_cases.py, their one definition), each
asserting that it passed; bench/stability.py runs the same cases and writes docs/stability.md."""
import pytest
from extreme_cases import CASES, run_case


@pytest.mark.parametrize("function", CASES, ids=[f.case_name for f in CASES])
def test_extreme_case(function):
    outcome = run_case(function)
    assert outcome["passed"], (
        f"{outcome['name']} ({outcome['group']}): {outcome['checked']}; error {outcome['error']!r} "
        f"> tolerance {outcome['tolerance']!r}; {outcome['detail']}")
