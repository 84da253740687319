"""simulate(): results against the high-precision reference, result layout, consistency."""

import csv
import io
import subprocess

import numpy as np
import pytest

import bistable_impact as bi


def test_baseline_impact_times_match_the_reference(reference):
    # (Ω, V) = (1.75, 0.07), τ <= 1000: every impact time within 1e-12 of the 128-bit reference.
    out = subprocess.run(
        [str(reference), "--omega", "1.75", "--velocity", "0.07", "--t-end", "1000"],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    rows = [r for r in csv.DictReader(io.StringIO(out)) if r["kind"] == "impact"]
    ref_t = np.array([float(r["t"]) for r in rows])
    ref_va = np.array([float(r["v_after"]) for r in rows])
    r = bi.simulate(1.75, 0.07, t_end=1000.0)
    t = r.impacts["t"]
    assert len(t) == len(ref_t) == 278
    dt = np.max(np.abs(t - ref_t))
    dv = np.max(np.abs(r.impacts["v_after"] - ref_va))
    print(f"278 impacts: max |Δt| = {dt:.2e}, max |Δv_after| = {dv:.2e}")
    assert dt <= 1e-12
    assert dv <= 1e-12
    assert np.array_equal(r.impacts["index"], np.arange(278))


def test_result_layout_and_summary():
    r = bi.simulate(0.2, 0.05, t_end=60.0, trace_dt=0.5)
    assert r.impacts.columns == list(bi.IMPACT_COLUMNS)
    assert r.impacts["t"].dtype == np.float64 and r.impacts["index"].dtype == np.int64
    assert r.sticking.columns == ["start", "end", "x_start", "x_end"]
    assert r.snaps.columns == ["t", "v", "to_well"]
    assert len(r.sticking) >= 1  # the chatter case sticks
    assert r.trace.columns == ["t", "x", "v", "z", "zdot"]
    assert np.array_equal(r.trace["t"], np.arange(121) * 0.5)
    assert r.summary["impacts"] == len(r.impacts)
    assert r.summary["t_end"] == 60.0
    assert r.final_state["t"] == 60.0
    assert r.final_state["mode"] in ("free", "sticking")
    e = r.impacts
    dk = 0.5 * (e["v_after"] ** 2 - e["v_before"] ** 2)
    assert np.allclose(dk, e["delta_k"], rtol=0, atol=1e-15)
    assert bi.simulate(1.75, 0.07, t_end=10.0).trace is None


def test_periods_equal_t_end_and_match_the_cli_summary(cli):
    a = bi.simulate(1.75, 0.07, periods=10)
    b = bi.simulate(1.75, 0.07, t_end=20 * np.pi)
    assert np.array_equal(a.impacts["t"], b.impacts["t"])
    import json

    out = subprocess.run(
        [str(cli), "simulate", "--omega", "1.75", "--velocity", "0.07", "--periods", "10", "--json"],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    js = json.loads(out)
    for k in ("impacts", "sticking_intervals", "snap_throughs", "final_well", "t_end", "steps"):
        assert a.summary[k] == js[k], k
    for k in ("x", "v", "z", "zdot"):
        assert a.final_state[k] == js["final_state"][k], k
    assert a.summary["last_impact"] == js["last_impact"]


def test_trace_does_not_change_the_run():
    a = bi.simulate(2.45, 0.07, t_end=300.0)
    b = bi.simulate(2.45, 0.07, t_end=300.0, trace_dt=0.013)
    assert np.array_equal(a.impacts["t"], b.impacts["t"])


def test_thresholds():
    t = bi.thresholds(0.85)
    assert t["single_impact"] == pytest.approx(1 / 7.4, abs=1e-15)
    assert t["interwell"] == pytest.approx(0.15 / 3.7, abs=1e-15)
    assert t["quasi_static"] is None
    assert bi.thresholds(0.7, omega=0.3)["quasi_static"] == 0.15
