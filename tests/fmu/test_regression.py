"""Regression: each case of cases.py re-simulated through fmpy and compared with
its reference CSV (regenerate with `make fmu-reference`)."""
import numpy as np
import pytest

from cases import CASES, COLUMNS, REFERENCE, RTOL, ATOL, read_csv, simulate


@pytest.mark.parametrize("name", sorted(CASES))
def test_case_matches_its_reference(fmu_path, name):
    ref = read_csv(REFERENCE / f"{name}.csv")
    got = simulate(name)
    assert len(got) == len(ref), f"{name}: {len(got)} rows, reference {len(ref)}"
    for c in COLUMNS:
        a, b = np.asarray(got[c], dtype=float), np.asarray(ref[c], dtype=float)
        if got.dtype[c].kind == "f" or c == "time":
            np.testing.assert_allclose(a, b, rtol=RTOL, atol=ATOL, err_msg=f"{name}.{c}")
        else:
            np.testing.assert_array_equal(a, b, err_msg=f"{name}.{c}")
