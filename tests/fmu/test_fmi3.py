"""The FMI 3.0 FMU (target/fmu/bistable_impact_fmi3.fmu) through fmpy: its model description is the
FMI 2.0 one in FMI 3.0 form, co-simulation with early return and event mode records every impact,
start and end of sticking and snap-through at its exact time (against the CLI's lists), without
early return it equals the FMI 2.0 FMU bit for bit, Model Exchange with CVode finds the same
impacts, and an FMU state taken between early returns replays the run exactly."""
import csv
import subprocess

import numpy as np
import pytest
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi3 import FMU3Slave
from fmpy.validation import validate_fmu

from cases import ROOT

FMU3 = ROOT / "target" / "fmu" / "bistable_impact_fmi3.fmu"

#: Event times found by the FMU must equal the CLI's to this (both run the same core; the
#: difference is the rounding of t = tau/omega0 and of the early return's restart).
EXACT = 1e-12


@pytest.fixture(scope="session")
def fmu3():
    if not FMU3.exists():
        pytest.fail(f"{FMU3} missing: run `make fmu` (make test-fmu does)")
    return str(FMU3)


def test_fmi3_fmu_passes_fmpy_validation(fmu3):
    assert validate_fmu(fmu3) == []


#: Variables whose description has its own FMI 3.0 text (FMI 3.0 has no input derivatives).
PER_VERSION_TEXTS = {"z_in", "zdot_in", "plate_reconstruction"}


def test_variables_are_those_of_the_fmi2_model_description(fmu3, md):
    """One source of truth: the FMI 3.0 variables are the FMI 2.0 ones (names, value references,
    causality, variability, start values, ranges, units, descriptions); Integer becomes Int32,
    Real Float64. The descriptions that speak of FMI 2.0's input derivatives have their FMI 3.0
    text (fmu/build_fmi3.rs, FMI3_TEXTS); the others are the same."""
    md3 = read_model_description(fmu3)
    assert md3.fmiVersion == "3.0" and md3.instantiationToken == md.guid
    types = {"Real": "Float64", "Integer": "Int32", "Boolean": "Boolean",
             "Enumeration": "Enumeration"}
    assert len(md3.modelVariables) == len(md.modelVariables) > 30
    for a, b in zip(md.modelVariables, md3.modelVariables):
        assert types[a.type] == b.type, a.name
        for attr in ["name", "valueReference", "causality", "variability", "start", "min", "max",
                     "unit", "description", "declaredType"]:
            va, vb = getattr(a, attr, None), getattr(b, attr, None)
            if attr == "declaredType" and va is not None:
                va, vb = va.name, vb.name
            if attr == "description" and a.name in PER_VERSION_TEXTS:
                assert va != vb and "FMI 3.0 has no input derivatives" in vb, (a.name, vb)
                assert "fmi2" not in vb, (a.name, vb)
                continue
            assert va == vb, (a.name, attr, va, vb)
    assert [u.variable.name for u in md3.eventIndicators] == ["contact_indicator",
                                                            "barrier_indicator"]
    assert md3.coSimulation.hasEventMode and md3.coSimulation.mightReturnEarlyFromDoStep
    assert md3.modelExchange.needsCompletedIntegratorStep


def cli_events(cli, tmp_path, omega, v, t_end):
    """The CLI's impact times, sticking intervals and snap-through times."""
    path = tmp_path / "impacts.csv"
    subprocess.run([cli, "simulate", "--omega", str(omega), "--velocity", str(v), "--t-end",
                    str(t_end), "--impacts", str(path)], check=True, capture_output=True)

    def rows(p):
        with open(p) as f:
            return list(csv.DictReader(f))

    impacts = [float(r["t"]) for r in rows(path)]
    sticking = rows(tmp_path / "impacts_sticking.csv")
    starts = [float(r["start"]) for r in sticking]
    ends = [float(r["end"]) for r in sticking if r["end"]]
    snaps = [float(r["t"]) for r in rows(tmp_path / "impacts_snaps.csv")]
    return impacts, starts, ends, snaps


def first_times(time, counter, k0=0):
    """For each value k > k0 that `counter` reaches, the first time it is reached."""
    out = []
    for k in range(int(counter[0]) + 1, int(counter[-1]) + 1):
        if k > k0:
            out.append(time[np.argmax(counter >= k)])
    return out


def sampled_at(r, t):
    """The last sample recorded at `t` (within EXACT); fails if there is none."""
    hits = np.flatnonzero(np.abs(r["time"] - t) <= EXACT)
    assert len(hits) > 0, f"no sample at t = {t}"
    return r[hits[-1]]


def transitions(time, flag, to):
    """Times of the first sample after each change of `flag` to `to`."""
    f = np.asarray(flag, dtype=int)
    return [time[i] for i in range(1, len(f)) if f[i] == to and f[i - 1] != to]


@pytest.mark.parametrize("omega,v,t_end", [(1.75, 0.07, 200.0), (0.2, 0.05, 60.0),
                                           (2.45, 0.1, 200.0)])
def test_early_return_records_every_event_at_its_time(fmu3, cli, tmp_path, omega, v, t_end):
    """fmpy with early return and event mode records a sample at each event: the first sample
    with impact_count = k+1 is at impact k's time (none late), and the changes of in_contact and
    snap_through_count are at the CLI's start and end of sticking and snap-through times."""
    r = simulate_fmu(fmu3, start_values={"Omega": omega, "V": v}, stop_time=t_end,
                     output_interval=1.0, early_return_allowed=True, use_event_mode=True,
                     output=["impact_count", "in_contact", "snap_through_count"])
    impacts, starts, ends, snaps = cli_events(cli, tmp_path, omega, v, t_end)
    got = first_times(r["time"], r["impact_count"])
    want = impacts[1:]  # impact 0 is at the start time, counted at initialization
    assert len(want) > 20 and len(got) == len(want)
    assert np.max(np.abs(np.array(got) - want)) <= EXACT
    # Sticking: an early return at each start (the accumulation point of a chatter sequence; the
    # mass rides the plate from the sequence's last resolved impact, less than the chatter
    # horizon 1e-7 before it) and at each release.
    got_starts = transitions(r["time"], r["in_contact"], 1)
    got_ends = transitions(r["time"], r["in_contact"], 0)
    assert len(got_starts) == len(starts) and len(got_ends) == len(ends)
    for g, w in zip(got_starts, starts):
        assert w - 1e-7 <= g <= w + EXACT, (g, w)
        assert sampled_at(r, w)["in_contact"] == 1
    for g, w in zip(got_ends, ends):
        assert abs(g - w) <= EXACT, (g, w)
    got_snaps = first_times(r["time"], r["snap_through_count"])
    assert len(got_snaps) == len(snaps)
    for g, w in zip(got_snaps, snaps):
        assert abs(g - w) <= EXACT, (g, w)
    if omega == 0.2:
        assert len(starts) >= 2 and len(ends) >= 2
    if omega == 2.45:
        assert len(snaps) >= 10


def test_without_early_return_the_outputs_equal_the_fmi2_fmu(fmu3, fmu_path, md):
    names = [v.name for v in md.modelVariables if v.causality == "output"]
    a = simulate_fmu(fmu3, stop_time=100, output_interval=0.05, output=names)
    b = simulate_fmu(fmu_path, stop_time=100, output_interval=0.05, output=names)
    assert len(a) == len(b) == 2001
    for n in ["time"] + names:
        np.testing.assert_array_equal(a[n], b[n], err_msg=n)
    assert b["impact_count"][-1] > 25


def test_sampled_inputs_equal_the_fmi2_fmu(fmu3, fmu_path):
    """External mode: the plate rebuilt from sampled inputs as in FMI 2.0, bit for bit."""
    from cases import sinusoid_input
    signal = sinusoid_input(1.75, 0.07, 60.0, 0.01)
    runs = [simulate_fmu(f, start_values={"shaker_mode": 2}, input=signal, stop_time=60,
                         output_interval=0.01, output=["x", "v", "impact_count"])
            for f in (fmu3, fmu_path)]
    for n in ["x", "v", "impact_count"]:
        np.testing.assert_array_equal(runs[0][n], runs[1][n], err_msg=n)
    assert runs[0]["impact_count"][-1] > 10


def test_model_exchange_with_cvode_counts_the_impacts_of_co_simulation(fmu3):
    me = simulate_fmu(fmu3, fmi_type="ModelExchange", solver="CVode", relative_tolerance=1e-10,
                      stop_time=200, output_interval=1.0, output=["impact_count", "x"])
    cs = simulate_fmu(fmu3, stop_time=200, output_interval=1.0, output=["impact_count", "x"])
    assert me["impact_count"][-1] == cs["impact_count"][-1] > 40
    # Model Exchange records the events too: compare at the communication points.
    at = [np.flatnonzero(me["time"] == t)[-1] for t in cs["time"]]
    np.testing.assert_allclose(me["x"][at], cs["x"], atol=1e-5)


class EarlyReturn:
    """A co-simulation instance with early return and event mode, driven like a master would."""

    def __init__(self, fmu3, unzipdir, name):
        md3 = read_model_description(fmu3)
        self.vr = {v.name: v.valueReference for v in md3.modelVariables}
        self.fmu = FMU3Slave(guid=md3.instantiationToken, unzipDirectory=unzipdir,
                             modelIdentifier=md3.coSimulation.modelIdentifier, instanceName=name)
        self.fmu.instantiate(eventModeUsed=True, earlyReturnAllowed=True)
        self.fmu.enterInitializationMode(startTime=0.0)
        self.fmu.exitInitializationMode()
        self.settle()
        self.t = 0.0

    def settle(self):
        while self.fmu.updateDiscreteStates()[0]:
            pass
        self.fmu.enterStepMode()

    def step(self, t_end):
        """One fmi3DoStep towards `t_end` (it returns early at an event); (time, x, v,
        impact_count) after it."""
        handling, terminate, early, last = self.fmu.doStep(self.t, t_end - self.t)
        assert not terminate
        assert early == (last < t_end)
        self.t = last
        if handling:
            self.fmu.enterEventMode()
            self.settle()
        x, v = self.fmu.getFloat64([self.vr["x"], self.vr["v"]])
        return last, x, v, self.fmu.getInt32([self.vr["impact_count"]])[0]

    def advance(self, t_end):
        """Steps to `t_end` through every early return; the (time, x, v, impact_count) after each."""
        out = []
        while self.t < t_end:
            out.append(self.step(t_end))
        return out

    def close(self):
        self.fmu.terminate()
        self.fmu.freeInstance()


def test_fmu_state_between_early_returns_replays_the_run(fmu3, tmp_path):
    d = str(tmp_path / "fmu3")
    extract(fmu3, d)
    a = EarlyReturn(fmu3, d, "a")
    a.advance(37.3)
    assert a.t == 37.3
    state = a.fmu.getFMUState()
    data = a.fmu.serializeFMUState(state)
    first = a.advance(80.0)
    assert len(first) > 10 and first[-1][3] > first[0][3]
    # Back to 37.3 s in the same instance, and in another one from the serialized bytes.
    a.fmu.setFMUState(state)
    a.t = 37.3
    assert a.advance(80.0) == first
    b = EarlyReturn(fmu3, d, "b")
    b.fmu.setFMUState(b.fmu.deserializeFMUState(data))
    b.t = 37.3
    assert b.advance(80.0) == first
    # A state taken at an event (right after an early return) restores too.
    a.fmu.setFMUState(state)
    a.t = 37.3
    at_event = a.step(80.0)[0]
    assert 37.3 < at_event < 80.0
    a.fmu.freeFMUState(state)
    state = a.fmu.getFMUState()
    rest = a.advance(80.0)
    a.fmu.setFMUState(state)
    a.t = at_event
    assert a.advance(80.0) == rest
    a.fmu.freeFMUState(state)
    a.close()
    b.close()
