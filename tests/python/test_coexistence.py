"""sweep.coexistence against `bistable coexistence`: the same table value for value, locally
and on a Dask LocalCluster of two workers; bad boxes and start counts refused naming the
argument."""

import subprocess

import pytest

import bistable_impact as bi

pd = pytest.importorskip("pandas")

OMEGAS = [1.40, 1.45, 1.50]
VELOCITIES = [0.04, 0.05]
OPTIONS = dict(starts=(8, 8), max_periods=2000.0)


@pytest.fixture(scope="module")
def cli_table(cli, tmp_path_factory):
    out = tmp_path_factory.mktemp("coexistence") / "co.csv"
    subprocess.run(
        [
            str(cli), "coexistence", "--omega-range", "1.40:1.50:3",
            "--velocity-range", "0.04:0.05:2", "--starts", "8x8", "--max-periods", "2000",
            "--out", str(out),
        ],
        check=True,
        capture_output=True,
    )
    return bi.coexistence.read_csv(out)


def test_coexistence_equals_the_cli(cli_table):
    df = bi.sweep.coexistence(OMEGAS, VELOCITIES, threads=2, **OPTIONS)
    assert list(df.columns) == list(bi.coexistence.COLUMNS)
    pd.testing.assert_frame_equal(df, cli_table, check_exact=True)
    # One paper start per point; the fractions of a point add up to 1.
    per_point = df.groupby(["omega", "velocity"])
    assert (per_point["paper_start"].sum() == 1).all()
    assert ((per_point["fraction"].sum() - 1.0).abs() < 1e-12).all()
    assert df["branch"].notna().all()


def test_coexistence_on_dask_equals_the_cli(cli_table):
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None
    ) as cluster, distributed.Client(cluster) as client:
        df = bi.sweep.coexistence(OMEGAS, VELOCITIES, client=client, chunk=2, **OPTIONS)
    pd.testing.assert_frame_equal(df, cli_table, check_exact=True)


def test_random_starts_are_seeded():
    a = bi.sweep.coexistence([1.45], [0.05], starts=40, seed=3, max_periods=2000.0, threads=1)
    b = bi.sweep.coexistence([1.45], [0.05], starts=40, seed=3, max_periods=2000.0, threads=2)
    c = bi.sweep.coexistence([1.45], [0.05], starts=40, seed=4, max_periods=2000.0, threads=1)
    pd.testing.assert_frame_equal(a, b)
    assert set(a["starts"]) == {"random:40:3"} and set(c["starts"]) == {"random:40:4"}
    assert int(a["count"].sum()) == 40


@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(box=(-0.1, 1.2, -0.6, 0.6)), "box"),
        (dict(box=(0.5, 0.5, -0.6, 0.6)), "box"),
        (dict(box=(0.0, 1.2, 0.6, -0.6)), "box"),
        (dict(starts=0), "starts"),
        (dict(starts=(0, 10)), "starts"),
        (dict(starts=(2000, 2000)), "starts"),
        (dict(aperiodic_hits=0), "aperiodic_hits"),
        (dict(match_distance=float("nan")), "match_distance"),
    ],
)
def test_bad_arguments_are_named(kwargs, name):
    with pytest.raises(ValueError, match=name):
        bi.sweep.coexistence([1.45], [0.05], **kwargs)


def test_bad_types_are_refused():
    with pytest.raises(TypeError, match="box"):
        bi.sweep.coexistence([1.45], [0.05], box=(0.0, 1.0))
    with pytest.raises(TypeError, match="starts"):
        bi.sweep.coexistence([1.45], [0.05], starts=True)
