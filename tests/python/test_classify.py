"""classify() and sweep.map() against the CLI's `bistable classify` on a small grid."""

import json
import subprocess

import pytest

import bistable_impact as bi

OMEGAS = [0.5, 0.85, 1.5, 2.0, 2.45]
VELOCITIES = [0.03, 0.07, 0.11, 0.15]
# Short runs keep the suite fast; the same options go to both sides.
OPTS = {"max_periods": 300.0, "lyapunov_periods": 50}


def cli_classify(cli, omega, velocity):
    out = subprocess.run(
        [
            str(cli), "classify", "--omega", repr(omega), "--velocity", repr(velocity),
            "--max-periods", "300", "--lyapunov-periods", "50",
        ],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    return json.loads(out)


@pytest.fixture(scope="module")
def cli_grid(cli):
    return {(w, v): cli_classify(cli, w, v) for v in VELOCITIES for w in OMEGAS}


def without_time(d):
    return {k: v for k, v in d.items() if k != "wall_time_s"}


def test_classify_equals_the_cli_on_a_grid(cli_grid):
    classes = set()
    for (w, v), expected in cli_grid.items():
        got = bi.classify(w, v, **OPTS)
        assert list(got) == list(expected), "same keys in the same order"
        assert without_time(got) == without_time(expected), (w, v)
        classes.add(got["class"])
    assert len(classes) >= 2, classes


def test_sweep_map_equals_the_cli(cli_grid):
    pd = pytest.importorskip("pandas")
    df = bi.sweep.map(OMEGAS, VELOCITIES, threads=2, **OPTS)
    assert isinstance(df, pd.DataFrame)
    assert list(df.columns) == list(bi.sweep.COLUMNS)
    assert len(df) == len(OMEGAS) * len(VELOCITIES)
    for row in df.to_dict("records"):
        expected = without_time(cli_grid[(row["omega"], row["velocity"])])
        got = {k: (None if pd.isna(v) else v) for k, v in without_time(row).items()}
        assert got == expected, (row["omega"], row["velocity"])


def test_classify_paper_examples():
    r = bi.classify(0.85, 0.11)
    assert (r["class"], r["period"]) == ("intrawell", 4)
    assert bi.classify(0.85, 0.15)["at_rest_in_second_well"] is True


def test_sweep_map_store_skips_points_already_computed(tmp_path):
    pytest.importorskip("pandas")
    store = str(tmp_path / "map.csv")
    a = bi.sweep.map([0.85, 1.5], [0.07], store=store, **OPTS)
    b = bi.sweep.map([0.85, 1.5, 2.0], [0.07], store=store, **OPTS)
    assert list(b["wall_time_s"][:2]) == list(a["wall_time_s"])  # read back, not recomputed
    assert len(b) == 3
    import pandas as pd

    assert len(pd.read_csv(store)) == 3


def test_sweep_map_on_a_dask_client_equals_the_cli(cli_grid):
    pd = pytest.importorskip("pandas")
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None
    ) as cluster, distributed.Client(cluster) as client:
        df = bi.sweep.map(OMEGAS[:3], VELOCITIES[:2], client=client, chunk=2, **OPTS)
    assert len(df) == 6
    for row in df.to_dict("records"):
        expected = without_time(cli_grid[(row["omega"], row["velocity"])])
        got = {k: (None if pd.isna(v) else v) for k, v in without_time(row).items()}
        assert got == expected, (row["omega"], row["velocity"])


def test_sweep_map_arguments():
    with pytest.raises(ValueError, match="'chunk'"):
        bi.sweep.map([1.0], [0.1], chunk=0)
    with pytest.raises(ValueError, match="'lyapunov_periods'"):
        bi.sweep.map([1.0], [0.1], lyapunov_periods=0)
    with pytest.raises(ValueError, match="'omega'"):
        bi.sweep.map([-1.0], [0.1])


def test_module_entry_point(tmp_path):
    import subprocess
    import sys

    out = tmp_path / "m.csv"
    r = subprocess.run(
        [sys.executable, "-m", "bistable_impact", "map", "--omega-range", "0.85:1.5:2",
         "--velocity-range", "0.07:0.07:1", "--max-periods", "300", "--lyapunov-periods", "50",
         "--out", str(out)],
        capture_output=True, text=True,
    )
    assert r.returncode == 0, r.stderr
    assert out.read_text().splitlines()[0] == ",".join(bi.sweep.COLUMNS)
    r = subprocess.run(
        [sys.executable, "-m", "bistable_impact", "map", "--omega-range=-1:1:2",
         "--velocity-range", "0.07:0.07:1"],
        capture_output=True, text=True,
    )
    assert r.returncode == 2 and "'omega'" in r.stderr
