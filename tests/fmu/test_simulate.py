"""fmpy's simulate_fmu: default experiment, parameters, SI units, step-size independence, and the
impact list against the CLI."""
import csv
import math
import subprocess

import numpy as np
import pytest
from fmpy import simulate_fmu

from conftest import parse_impacts

TAU = 2 * math.pi


def test_default_experiment_runs_to_the_stop_time(fmu_path, md):
    r = simulate_fmu(fmu_path)
    assert r["time"][-1] == float(md.defaultExperiment.stopTime)
    counts = r["impact_count"]
    assert counts[0] == 1 and np.all(np.diff(counts) >= 0) and counts[-1] > 40
    assert set(np.unique(r["well"])) == {1}
    # The phase of impact 1 of the baseline (paper: about 0.05 cycles).
    first = r["last_impact_phase"][np.argmax(counts == 2)]
    assert abs(first - 0.0507) < 5e-4


def test_parameters_change_the_response_escape_to_well_two(fmu_path):
    r = simulate_fmu(fmu_path, start_values={"Omega": 0.85, "V": 0.15}, stop_time=100,
                     output_interval=0.5)
    # model.md: V = 0.15 escapes to the second well after the single impact at t = 0, and stays.
    assert r["impact_count"][-1] == 1
    assert r["well"][-1] == 2 and r["snap_through_count"][-1] == 1
    assert np.all(r["x"][r["time"] > 20] > 0.5)


def test_si_units_scale_the_nondimensional_run(fmu_path):
    w0, dx, m = TAU * 3.08, 0.02819, 0.3
    interval = 0.25
    base = simulate_fmu(fmu_path, stop_time=40, output_interval=interval)
    si = simulate_fmu(fmu_path, stop_time=40 / w0, output_interval=interval / w0,
                      start_values={"omega0": w0, "delta_x": dx, "mass": m})
    n = min(len(base), len(si))
    assert n > 150
    np.testing.assert_allclose(si["time"][:n] * w0, base["time"][:n], rtol=1e-12)
    np.testing.assert_allclose(si["x"][:n] / dx, base["x"][:n], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(si["v"][:n] / (w0 * dx), base["v"][:n], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(si["kinetic_energy"][:n] / (m * (w0 * dx) ** 2),
                               base["kinetic_energy"][:n], rtol=1e-8, atol=1e-15)
    np.testing.assert_array_equal(si["impact_count"][:n], base["impact_count"][:n])


def test_state_does_not_depend_on_the_communication_step(fmu_path):
    """h = 1e-3 ... 10 over t <= 200: x, v and the impact outputs agree to 1e-12 at t = 10k."""
    names = ["x", "v", "impact_count", "last_impact_time", "last_impact_v_after"]
    sampled = {}
    for h in [1e-3, 0.01, 0.1, 1.0, 10.0]:
        r = simulate_fmu(fmu_path, stop_time=200, output_interval=h, output=names)
        pick = [int(np.argmin(np.abs(r["time"] - t))) for t in range(10, 201, 10)]
        assert np.all(np.abs(r["time"][pick] - np.arange(10, 201, 10)) < 1e-9)
        sampled[h] = r[pick]
    ref = sampled[1e-3]
    assert ref["impact_count"][-1] > 50
    for h, r in sampled.items():
        np.testing.assert_array_equal(r["impact_count"], ref["impact_count"], err_msg=f"h={h}")
        for n in ["x", "v", "last_impact_time", "last_impact_v_after"]:
            assert np.max(np.abs(r[n] - ref[n])) <= 1e-12, f"h={h} {n}"


def cli_impacts(cli, tmp_path, omega, v, t_end):
    path = tmp_path / "impacts.csv"
    subprocess.run([cli, "simulate", "--omega", str(omega), "--velocity", str(v), "--t-end",
                    str(t_end), "--impacts", str(path)], check=True, capture_output=True)
    with open(path) as f:
        return [(int(r["index"]), float(r["t"]), float(r["phase"]), float(r["x"]),
                 float(r["v_before"]), float(r["v_after"])) for r in csv.DictReader(f)]


@pytest.mark.parametrize("omega,v,t_end", [(1.75, 0.07, 300.0), (0.2, 0.05, 60.0)])
def test_impact_list_matches_the_cli(fmu_path, cli, tmp_path, omega, v, t_end):
    messages = []
    simulate_fmu(fmu_path, start_values={"Omega": omega, "V": v}, stop_time=t_end,
                 output_interval=t_end / 7, debug_logging=True,
                 logger=lambda c, name, status, cat, msg: messages.append(msg.decode()))
    fmu = parse_impacts(messages)
    ref = cli_impacts(cli, tmp_path, omega, v, t_end)
    assert len(ref) > 20 and len(fmu) == len(ref)
    for a, b in zip(fmu, ref):
        assert a[0] == b[0]
        assert max(abs(p - q) for p, q in zip(a[1:], b[1:])) <= 1e-12, (a, b)


def test_impacts_read_through_the_outputs_match_the_cli(fmu_path, cli, tmp_path):
    names = ["impact_count", "last_impact_time", "last_impact_phase", "last_impact_v_before",
             "last_impact_v_after"]
    r = simulate_fmu(fmu_path, stop_time=150, output_interval=0.01, output=names)
    ref = {i[0]: i for i in cli_impacts(cli, tmp_path, 1.75, 0.07, 150.0)}
    seen = {int(row["impact_count"]) - 1: row for row in r}
    assert len(seen) >= 0.95 * len(ref)
    for index, row in seen.items():
        _, t, phase, _, vb, va = ref[index]
        got = (row["last_impact_time"], row["last_impact_phase"], row["last_impact_v_before"],
               row["last_impact_v_after"])
        assert max(abs(p - q) for p, q in zip(got, (t, phase, vb, va))) <= 1e-12
