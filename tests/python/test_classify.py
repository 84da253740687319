"""classify() and sweep.map() against the CLI's `bistable classify` on a small grid."""

import json
import subprocess

import pytest

import bistable_impact as bi

OMEGAS = [0.5, 0.85, 1.5, 2.0, 2.45]
VELOCITIES = [0.03, 0.07, 0.11, 0.15]
# Short runs keep the suite fast; the same options go to both sides.
OPTS = {"max_periods": 300.0, "lyapunov_periods": 50}


# Settings of the sensitivity test other than the defaults; all but perturbation and
# repeat_periods show in the records of SENS_POINTS (checked below).
SENS = {
    "repeats": 3,
    "efoldings": 5.0,
    "perturbation": 1e-9,
    "horizon": 100.0,
    "repeat_periods": 30.0,
    "lyapunov_windows": 2,
}
SENS_POINTS = [(2.45, 0.03), (2.45, 0.07), (1.5, 0.11), (0.85, 0.11)]


def cli_flags(options):
    """`bistable classify` flags for keyword arguments of `bi.classify`."""
    return [x for k, v in options.items() for x in ("--" + k.replace("_", "-"), repr(v))]


def cli_classify(cli, omega, velocity, options=None):
    out = subprocess.run(
        [
            str(cli), "classify", "--omega", repr(omega), "--velocity", repr(velocity),
            "--max-periods", "300", "--lyapunov-periods", "50", *cli_flags(options or {}),
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


def test_sensitivity_settings_as_in_the_cli(cli):
    pd = pytest.importorskip("pandas")
    got = {(w, v): bi.classify(w, v, **OPTS, **SENS) for w, v in SENS_POINTS}
    for (w, v), r in got.items():
        assert without_time(r) == without_time(cli_classify(cli, w, v, SENS)), (w, v)
        assert r["efoldings_threshold"] == SENS["efoldings"]
    # Decided after `horizon` natural periods: repeated `repeats` times.
    assert (got[(2.45, 0.03)]["sensitivity_trigger"], got[(2.45, 0.03)]["runs"]) == ("late", 4)
    # Aperiodic: `repeats` runs and `lyapunov_windows` further chaos verdicts.
    assert (got[(2.45, 0.07)]["sensitivity_trigger"], got[(2.45, 0.07)]["runs"]) == (
        "aperiodic",
        1 + SENS["repeats"] + SENS["lyapunov_windows"],
    )
    # A transient growth of `efoldings`: repeated; with the default threshold a single run.
    assert got[(1.5, 0.11)]["sensitivity_trigger"] == "growth"
    assert bi.classify(2.0, 0.11, **OPTS)["sensitivity_trigger"] == "none"
    assert bi.classify(2.0, 0.11, **OPTS, efoldings=5.0)["sensitivity_trigger"] == "growth"
    # The map passes them on too.
    ws, vs = [2.45, 1.5], [0.03, 0.11]
    df = bi.sweep.map(ws, vs, threads=2, **OPTS, **SENS)
    for row in df.to_dict("records"):
        expected = bi.classify(row["omega"], row["velocity"], **OPTS, **SENS)
        got_row = {k: (None if pd.isna(x) else x) for k, x in without_time(row).items()}
        assert got_row == without_time(expected), (row["omega"], row["velocity"])
    # repeats=0: no test, every point a single run.
    off = bi.sweep.map(ws, vs, threads=2, **OPTS, repeats=0)
    assert set(off["runs"]) == {1} and set(off["sensitivity_trigger"]) == {"none"}


def test_sensitivity_defaults_are_the_librarys():
    """The signatures show the defaults that the Rust side applies (and the CLI, see its
    unit test `sensitivity_defaults_are_the_librarys`)."""
    import inspect

    assert set(bi.SENSITIVITY_DEFAULTS) == set(SENS)
    for f in (bi.classify, bi.sweep.map):
        params = inspect.signature(f).parameters
        for name, value in bi.SENSITIVITY_DEFAULTS.items():
            assert params[name].default == value, (f.__name__, name)
    assert bi.SENSITIVITY_DEFAULTS["repeats"] > 0  # the test is on by default


def test_classify_at_the_papers_sensitive_point(cli):
    """(0.85, 0.13): rounding decides between rest in well 2 and continuous interwell P-1."""
    r = bi.classify(0.85, 0.13)
    assert r["sensitive"] is True
    outcomes = r["outcomes"]
    assert isinstance(outcomes, list) and all(isinstance(o, dict) for o in outcomes)
    assert [list(o) for o in outcomes] == [
        ["class", "period", "chaotic", "final_well", "count", "fraction"]
    ] * len(outcomes)
    shown = {(o["class"], o["period"], o["chaotic"], o["final_well"]) for o in outcomes}
    assert shown == {
        ("transient_interwell", 1, False, 2),
        ("continuous_interwell", 1, False, None),
    }, outcomes
    assert sum(o["count"] for o in outcomes) == r["runs"]
    assert [o["fraction"] for o in outcomes] == [o["count"] / r["runs"] for o in outcomes]
    assert outcomes[0]["fraction"] == r["majority_fraction"] and outcomes[0]["class"] == r["class"]
    expected = json.loads(
        subprocess.run(
            [str(cli), "classify", "--omega", "0.85", "--velocity", "0.13"],
            check=True,
            capture_output=True,
            text=True,
        ).stdout
    )
    assert without_time(r) == without_time(expected)  # the CLI's JSON has the same objects
    assert expected["outcomes"] == outcomes
    assert [list(o) for o in expected["outcomes"]] == [list(o) for o in outcomes]  # key order


def test_outcomes_text_is_the_map_csv_form(tmp_path):
    """sweep.map: outcomes as lists of dicts in the DataFrame, as text in the CSV (store=,
    to_csv_frame), read back by read_csv into the same lists."""
    pd = pytest.importorskip("pandas")
    store = tmp_path / "map.csv"
    df = bi.sweep.map([0.85], [0.13], store=str(store), max_periods=2000.0)
    got = df["outcomes"][0]
    assert isinstance(got, list) and {o["class"] for o in got} == {
        "transient_interwell", "continuous_interwell"}
    assert df["runs"].dtype == "Int64" and df["sensitive"].dtype == bool
    text = pd.read_csv(store)["outcomes"][0]
    assert text == bi._native.outcomes_text(got)
    assert text.startswith("transient_interwell:P-1:2=0.") and ";continuous_interwell:P-1:-=0." in text
    back = bi.sweep.read_csv(store)
    assert back["outcomes"][0] == got
    assert bi.sweep.to_csv_frame(df)["outcomes"][0] == text
    # The store is read back into lists too (not recomputed: same wall time).
    again = bi.sweep.map([0.85], [0.13], store=str(store), max_periods=2000.0)
    assert again["outcomes"][0] == got and again["wall_time_s"][0] == df["wall_time_s"][0]
    for bad in ("intrawell:P-1:1", "sideways:P-1:1=1.000", "intrawell:P-1:7=1.000"):
        with pytest.raises(ValueError, match="'outcomes'"):
            bi._native.outcomes_from_text(bad, 1)
    broken = tmp_path / "broken.csv"
    broken.write_text(store.read_text().replace("transient_interwell:P-1:2=", "x:P-1:2="))
    with pytest.raises(ValueError, match="'outcomes'"):
        bi.sweep.read_csv(broken)
    (tmp_path / "other.csv").write_text("a,b\n1,2\n")
    with pytest.raises(ValueError, match="map columns"):
        bi.sweep.read_csv(tmp_path / "other.csv")


def test_classify_paper_examples():
    r = bi.classify(0.85, 0.11)
    assert (r["class"], r["period"]) == ("intrawell", 4)
    assert bi.classify(0.85, 0.15)["at_rest_in_second_well"] is True
    assert bi.classify(0.85, 0.15)["at_rest"] is True


def test_a_mass_that_never_leaves_the_plate_is_at_rest(cli):
    """V = 0: the plate stands still and the mass rests on it; at rest, on the plate
    (sticking), no impacts, as the CLI says."""
    r = bi.classify(0.85, 0.0)
    assert (r["at_rest"], r["sticking"], r["impacts_per_period"]) == (True, True, 0)
    assert (r["class"], r["final_well"], r["at_rest_in_second_well"]) == ("intrawell", 1, False)
    assert without_time(r) == without_time(cli_classify(cli, 0.85, 0.0))
    moving = bi.classify(0.85, 0.01)
    assert (moving["at_rest"], moving["sticking"]) == (False, False)


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


def test_dask_tasks_are_cut_for_about_eight_per_worker_thread():
    """chunk=None: 16 to 256 points per task, about 8 tasks per worker thread of the client;
    the tasks hold every point once, in order; an explicit chunk is kept."""
    from bistable_impact import _check

    class Client:  # what dask.distributed.Client.nthreads() reports: threads per worker
        def nthreads(self):
            return {"tcp://a": 1, "tcp://b": 1}

    points = list(range(2400))
    parts = _check.tasks(points, None, Client())
    assert [len(p) for p in parts] == [150] * 16 and sum(parts, []) == points
    assert {len(p) for p in _check.tasks(list(range(60000)), None, Client())[:-1]} == {256}
    assert [len(p) for p in _check.tasks(list(range(40)), None, Client())] == [16, 16, 8]
    assert [len(p) for p in _check.tasks(points[:20], 7, Client())] == [7, 7, 6]
    # A client-like object that cannot say how many threads it has counts as one.
    assert len(_check.tasks(list(range(800)), None, object())[0]) == 100


def test_sweep_map_arguments():
    with pytest.raises(ValueError, match="'chunk'"):
        bi.sweep.map([1.0], [0.1], chunk=0)
    with pytest.raises(ValueError, match="'lyapunov_periods'"):
        bi.sweep.map([1.0], [0.1], lyapunov_periods=0)
    with pytest.raises(ValueError, match="'omega'"):
        bi.sweep.map([-1.0], [0.1])
    with pytest.raises(ValueError, match="'lyapunov_windows'"):
        bi.sweep.map([1.0], [0.1], lyapunov_windows=1025)


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
        [sys.executable, "-m", "bistable_impact", "map", "--omega-range", "1.5:2.45:2",
         "--velocity-range", "0.11:0.11:1", "--max-periods", "300", "--lyapunov-periods", "50",
         "--efoldings", "5", "--repeats", "2", "--out", str(tmp_path / "s.csv")],
        capture_output=True, text=True,
    )
    assert r.returncode == 0, r.stderr
    import pandas as pd

    s = pd.read_csv(tmp_path / "s.csv")
    assert set(s["sensitivity_trigger"]) == {"growth"} and set(s["runs"]) == {3}
    r = subprocess.run(
        [sys.executable, "-m", "bistable_impact", "map", "--omega-range=-1:1:2",
         "--velocity-range", "0.07:0.07:1"],
        capture_output=True, text=True,
    )
    assert r.returncode == 2 and "'omega'" in r.stderr
