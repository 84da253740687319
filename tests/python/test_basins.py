"""`bistable_impact.sweep.basins` against `bistable basins`: the same cells get the same
classification and the same attractors, locally and on a Dask cluster."""

import csv
import json
import subprocess

import pytest

import bistable_impact as bi

OMEGA, VELOCITY = 1.45, 0.05
X_RANGE, V_RANGE = (0.0, 1.2, 10), (-0.6, 0.6, 10)


def _values(a, b, n):
    # As the CLI's A:B:N ranges: exactly A and B at the ends.
    return [a] + [a + (b - a) * (i / (n - 1)) for i in range(1, n - 1)] + [b]


@pytest.fixture(scope="module")
def cli_cells(cli, tmp_path_factory):
    out = tmp_path_factory.mktemp("basins") / "b.csv"
    subprocess.run(
        [
            str(cli), "basins", "--omega", str(OMEGA), "--velocity", str(VELOCITY),
            "--x-range", "0:1.2:10", "--v-range", "-0.6:0.6:10",
            "--uncertainty-samples", "0", "--out", str(out), "--threads", "2", "--json",
        ],
        check=True,
        capture_output=True,
    )
    with open(out) as f:
        return {(float(r["x0"]), float(r["v0"])): r for r in csv.DictReader(f)}


def _same(row, cell):
    def opt(text, cast):
        return None if text == "" else cast(text)

    assert cell["class"] == row["class"]
    assert cell["period"] == opt(row["period"], int)
    assert cell["chaotic"] == (row["chaotic"] == "true")
    assert cell["final_well"] == opt(row["final_well"], int)
    assert cell["at_rest_in_second_well"] == (row["at_rest_in_second_well"] == "true")
    for k in ("anchor_x", "anchor_v"):
        want = opt(row[k], float)
        got = cell[k]
        assert (got is None) == (want is None) and (want is None or got == want), k
    assert cell["periods_simulated"] == float(row["periods_simulated"])


def test_basins_match_the_cli(cli_cells):
    pytest.importorskip("pandas")
    xs, vs = _values(*X_RANGE), _values(*V_RANGE)
    df, attractors = bi.sweep.basins(OMEGA, VELOCITY, xs, vs, threads=2)
    assert len(df) == 100 and len(cli_cells) == 100
    for cell in df.to_dict("records"):
        cell = {k: (None if v is None or v != v else v) for k, v in cell.items()}
        for k in ("period", "final_well"):
            cell[k] = None if cell[k] is None else int(cell[k])
        _same(cli_cells[(cell["x0"], cell["v0"])], cell)
    # Rest in well 2 and P-1 in well 1 coexist here; the fractions add up.
    labels = [a["label"] for a in attractors]
    assert "rest in well 2" in labels
    assert any(l.startswith("P-1 in well 1") for l in labels)
    assert abs(sum(a["fraction"] for a in attractors) - 1.0) < 1e-12
    assert sorted(df["attractor"].unique()) == list(range(1, len(attractors) + 1))


def test_basins_refuse_starts_below_the_plate():
    pytest.importorskip("pandas")
    # At a quarter cycle the plate is at its top, V/Ω.
    with pytest.raises(ValueError, match="for 'x0': x0 must not be below the plate"):
        bi.sweep.basins(OMEGA, VELOCITY, [0.0, 0.5], [0.0], phase=0.25)
    with pytest.raises(ValueError, match="phase"):
        bi.sweep.basins(OMEGA, VELOCITY, [0.5], [0.0], phase=1.5)


def test_basins_on_dask_match_the_cli(cli_cells):
    pytest.importorskip("pandas")
    distributed = pytest.importorskip("distributed")
    xs, vs = _values(*X_RANGE)[:4], _values(*V_RANGE)[:3]
    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None
    ) as cluster, distributed.Client(cluster) as client:
        df, _ = bi.sweep.basins(OMEGA, VELOCITY, xs, vs, client=client, chunk=5)
    assert len(df) == 12
    for cell in df.to_dict("records"):
        cell = {k: (None if v is None or v != v else v) for k, v in cell.items()}
        for k in ("period", "final_well"):
            cell[k] = None if cell[k] is None else int(cell[k])
        _same(cli_cells[(cell["x0"], cell["v0"])], cell)


@pytest.fixture(scope="module")
def cli_uncertainty(cli, tmp_path_factory):
    out = tmp_path_factory.mktemp("basins") / "u.csv"
    r = subprocess.run(
        [
            str(cli), "basins", "--omega", str(OMEGA), "--velocity", str(VELOCITY),
            "--x-range", "0:1.2:10", "--v-range", "-0.6:0.6:10",
            "--uncertainty-samples", "30", "--out", str(out), "--threads", "2", "--json",
        ],
        check=True,
        capture_output=True,
        text=True,
    )
    return json.loads(r.stdout)


def test_uncertainty_exponent_matches_the_cli(cli_uncertainty):
    pytest.importorskip("pandas")
    distributed = pytest.importorskip("distributed")
    xs, vs = _values(*X_RANGE), _values(*V_RANGE)
    cells, _ = bi.sweep.basins(OMEGA, VELOCITY, xs, vs, threads=2)
    fractions, alpha = bi.sweep.basin_uncertainty(OMEGA, VELOCITY, xs, cells, samples=30)
    assert fractions.to_dict("records") == cli_uncertainty["uncertainty"]
    assert alpha == cli_uncertainty["uncertainty_exponent"]
    # Fractal boundaries here: some uncertain starts at every ε, fewer at smaller ε, α < 1.
    f = list(fractions["fraction"])
    assert all(x > 0 for x in f) and f == sorted(f, reverse=True) and 0 < alpha < 1
    # The displaced starts classified on a Dask cluster give the same.
    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None
    ) as cluster, distributed.Client(cluster) as client:
        on_dask = bi.sweep.basin_uncertainty(
            OMEGA, VELOCITY, xs, cells, samples=30, client=client, chunk=7
        )
    assert on_dask[0].equals(fractions) and on_dask[1] == alpha
    # No samples: nothing measured, as `--uncertainty-samples 0`.
    none = bi.sweep.basin_uncertainty(OMEGA, VELOCITY, xs, cells, samples=0)
    assert len(none[0]) == 0 and list(none[0].columns) == list(fractions.columns)
    assert none[1] is None
    with pytest.raises(ValueError, match="'samples'"):
        bi.sweep.basin_uncertainty(OMEGA, VELOCITY, xs, cells, samples=-1)
