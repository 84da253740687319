"""examples/paper.py --reduced: the three PNGs and their data, the data checked against the CLI
run with the same arguments (simulate's impacts, bifurcation's CSV, map's CSV) and Fig. 3
against the paper's two second-impact phases."""

import pathlib
import subprocess
import sys

import pandas as pd
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
PNG = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def out(tmp_path_factory):
    d = tmp_path_factory.mktemp("paper")
    subprocess.run([sys.executable, str(ROOT / "examples" / "paper.py"), str(d), "--reduced"],
                   check=True, capture_output=True)  # fmt: skip
    return d


def cli_csv(cli, tmp, name, *args):
    path = tmp / name
    subprocess.run([str(cli), *map(str, args), str(path)], check=True, capture_output=True)
    return pd.read_csv(path)


def test_pngs_are_written(out):
    for name in ("fig3_second_impact_phase", "fig6_bifurcation", "fig9_map"):
        data = (out / f"{name}.png").read_bytes()
        assert data[:8] == PNG and len(data) > 20_000, name


def test_fig3_second_impact_phases(out, cli, tmp_path):
    df = pd.read_csv(out / "fig3_second_impact_phase.csv")
    assert len(df) == 67 and df["phase"].between(0, 1).all()
    at = dict(zip(df["omega"].round(12), df["phase"]))
    # The paper's values (Sec. 5), to the 4 digits it gives.
    assert abs(at[1.75] - 0.0507) <= 5e-4 and abs(at[2.5] - 0.5943) <= 5e-4
    # The CLI's impacts CSV: row 1 is the second impact.
    for w in (0.2, 1.75, 2.5, 3.5):
        imp = cli_csv(cli, tmp_path, f"imp_{w}.csv", "simulate", "--omega", w, "--velocity", 0.07,
                      "--periods", 200, "--impacts")
        assert imp["phase"][1] == at[w], w


def test_fig6_data_equals_the_cli(out, cli, tmp_path):
    got = pd.read_csv(out / "fig6_bifurcation.csv")
    ref = cli_csv(cli, tmp_path, "bif.csv", "bifurcation", "--param", "omega", "--range",
                  "2.0:2.7:15", "--velocity", 0.07, "--transient", 200, "--record", 20,
                  "--threads", 2, "--out")
    pd.testing.assert_frame_equal(got, ref, check_exact=False, rtol=1e-12, atol=1e-15)
    got_orbits = pd.read_csv(out / "fig6_orbits.csv").drop(columns="cycle_max")
    ref_orbits = pd.read_csv(tmp_path / "bif_orbits.csv").drop(columns="cycle_max")
    pd.testing.assert_frame_equal(got_orbits, ref_orbits, check_exact=False, rtol=1e-12,
                                  atol=1e-15)
    # Period doubling on the way: periods 1, 2 and 4 among the stable orbits.
    assert {1, 2, 4} <= set(ref_orbits[ref_orbits["stable"]]["period"])


def test_fig9_map_equals_the_cli(out, cli, tmp_path):
    got = pd.read_csv(out / "fig9_map.csv").drop(columns="wall_time_s")
    ref = cli_csv(cli, tmp_path, "map.csv", "map", "--omega-range", "0.2:3.5:12",
                  "--velocity-range", "0.005:0.2:8", "--max-periods", 2000, "--threads", 2,
                  "--out").drop(columns="wall_time_s")
    key = ["omega", "velocity"]
    ref = ref.sort_values(["velocity", "omega"]).reset_index(drop=True)
    # A whole float (a fraction of 1, a threshold of 20) is written "1" by the CLI and "1.0" by
    # pandas: same number, other inferred dtype; the values are still compared exactly.
    floats = [c for c in got.columns if got[c].dtype == float and ref[c].dtype != float]
    ref[floats] = ref[floats].astype(float)
    assert len(got) == 96 and not got.duplicated(key).any()
    pd.testing.assert_frame_equal(got, ref, check_exact=True)
    assert set(got["class"]) == {"intrawell", "transient_interwell", "continuous_interwell"}
