"""External shaker inputs against the internal sinusoid (with derivatives, and sampled: the
Hermite reconstruction, its order, its sensitivity, inputs that are not smooth), FMU states (rollback, serialization,
another process), tunable parameters, and refused calls through fmpy."""
import json
import math
import subprocess
import sys

import numpy as np
import pytest
from fmpy import simulate_fmu
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import fmi2Terminated

from cases import FMU, ROOT, sinusoid_input

OMEGA, V = 1.75, 0.07


def plate_derivative(k, t):
    """d^k z/dt^k of z = (V/Omega) sin(Omega t)."""
    return V / OMEGA * OMEGA ** k * math.sin(OMEGA * t + k * math.pi / 2)


def drive_external(s, t_end, h, orders):
    """Feeds the internal sinusoid through z_in, zdot_in and derivatives up to `orders`."""
    while s.t < t_end - 1e-9:
        s.set(z_in=plate_derivative(0, s.t), zdot_in=plate_derivative(1, s.t))
        ks = list(range(2, orders + 1))
        if ks:
            s.fmu.setRealInputDerivatives([s.vr["z_in"]] * len(ks), ks,
                                          [plate_derivative(k, s.t) for k in ks])
        s.step(min(h, t_end - s.t))


# Stated tolerance: the plate over a step is the inputs' degree-5 Taylor polynomial, off by
# about V Omega^5 h^6 / 720 per step; over t <= 60 the trajectories agree within `tol`.
@pytest.mark.parametrize("h,tol", [(0.01, 1e-9), (0.05, 5e-8)])
def test_external_inputs_with_derivatives_reproduce_the_internal_sinusoid(slave, h, tol):
    names = ("x", "v", "impact_count", "last_impact_time", "last_impact_phase")
    internal = slave().start(Omega=OMEGA, V=V)
    internal.run_to(60.0, h)
    want = internal.get(*names)
    external = slave().start(shaker_mode=2, Omega=OMEGA, z_in=0.0, zdot_in=V)
    drive_external(external, 60.0, h, orders=5)
    got = external.get(*names)
    assert got[2] == want[2] and want[2] > 10
    for a, b in zip(got[:2] + got[3:], want[:2] + want[3:]):
        assert abs(a - b) < tol, (got, want)


def sampled_run(h, t_end=100.0, scheme=None, perturb=None, output=("x", "v", "z", "impact_count")):
    """The baseline sinusoid fed through z_in, zdot_in only (fmpy input table sampled every h)."""
    signal = sinusoid_input(OMEGA, V, t_end, h)
    if perturb is not None:
        signal["z_in"] = perturb(signal["z_in"])
    start = {"shaker_mode": 2, "Omega": OMEGA, "zdot_in": V}
    if scheme is not None:
        start["plate_reconstruction"] = scheme
    return simulate_fmu(str(FMU), start_values=start, stop_time=t_end, output_interval=h,
                        input=signal, output=list(output))


def internal_run(h, t_end=100.0):
    return simulate_fmu(str(FMU), start_values={"Omega": OMEGA, "V": V}, stop_time=t_end,
                        output_interval=h, output=["x", "v", "z", "impact_count"])


# Stated tolerances (acceptance of the sampled-input reconstruction): the quintic Hermite
# extrapolation through three samples is off by at most h^6 V Omega^5 / 20 in plate position and
# O(h^5) in velocity per step; over t <= 100 (27 impacts, a transient that amplifies an impact's
# error about 50-fold) the mass stays within 1e-8 of the internal sinusoid at h = 0.01 (measured
# 1.3e-10) and 1e-6 at h = 0.05 (measured 4.5e-7).
@pytest.mark.parametrize("h,tol", [(0.01, 1e-8), (0.05, 1e-6)])
def test_sampled_inputs_reproduce_the_internal_sinusoid(h, tol):
    internal, sampled = internal_run(h), sampled_run(h)
    assert np.array_equal(sampled["impact_count"], internal["impact_count"])
    assert internal["impact_count"][-1] == 27
    assert np.max(np.abs(sampled["x"] - internal["x"])) <= tol
    # The plate itself, once four samples check the quintic (the first three steps are of
    # lower order: fewer samples): the extrapolation error h^6 V Omega^5 / 20 of the module docs
    # of bistable_core::sampled, plus at most as much from the previous step's mismatch that the
    # blend removes.
    later = sampled["time"] >= 4 * h - 1e-12
    dz = np.abs(sampled["z"] - internal["z"])[later]
    assert np.max(dz) <= 2 * h ** 6 * V * OMEGA ** 5 / 20


def test_sampled_inputs_converge_at_high_order():
    # Measured orders between successive halvings are 4 to 6 (velocity error O(h^5) at the
    # impacts); the first-order scheme, kept as plate_reconstruction = 1, does not converge.
    hs = [0.1, 0.05, 0.025, 0.0125]
    errors = [np.max(np.abs(sampled_run(h)["x"] - internal_run(h)["x"])) for h in hs]
    orders = [np.log2(a / b) for a, b in zip(errors, errors[1:])]
    assert min(orders) >= 3.5, (errors, orders)
    taylor = [np.max(np.abs(sampled_run(h, scheme=1)["x"] - internal_run(h)["x"])) for h in hs[1::2]]
    assert taylor[1] > 1e-3, taylor


def test_one_ulp_in_every_sample_changes_x_by_at_most_1e_9():
    # The external_shaker regression case (h = 0.05): every z_in sample after the start one ulp
    # lower (the start sample places the plate under the mass at x0 = 0; one ulp lower there
    # would leave the mass 5e-324 above it and count the t = 0 impact in the first step instead).
    # The plate acceleration interpolated from the samples must not amplify such a change (one
    # wrong by O(1) would move x by about 1e-2 by t = 100).
    def lower(z):
        z = z.copy()
        z[1:] = np.nextafter(z[1:], -np.inf)
        return z

    base = sampled_run(0.05)
    moved = sampled_run(0.05, perturb=lower)
    assert np.array_equal(base["impact_count"], moved["impact_count"])
    assert np.max(np.abs(base["x"] - moved["x"])) <= 1e-9


def drive_sampled(s, times, signal=None):
    """Steps the slave through `times` (absolute), setting z_in, zdot_in at each point from
    `signal(t)` (default: the baseline sinusoid)."""
    signal = signal or (lambda t: (plate_derivative(0, t), plate_derivative(1, t)))
    rows = []
    for t_next in times:
        z, zd = signal(s.t)
        s.set(z_in=z, zdot_in=zd)
        s.fmu.doStep(currentCommunicationPoint=s.t, communicationStepSize=t_next - s.t)
        s.t = t_next
        rows.append((s.t,) + s.get("x", "v", "z", "zdot", "impact_count"))
    return np.array(rows)


def test_a_host_accumulating_time_gets_the_same_result(slave):
    # OMSimulator and the Compliance Checker step with t += h, reaching points up to 1e-11 away
    # from k*h: the plate samples move by as much, and x must not notice beyond 1e-9.
    h, n = 0.05, 2000
    exact = drive_sampled(slave().start(shaker_mode=2, Omega=OMEGA, zdot_in=V),
                          [k * h for k in range(1, n + 1)])
    acc, t = [], 0.0
    for _ in range(n):
        t += h
        acc.append(t)
    assert abs(acc[-1] - n * h) > 1e-13
    accumulated = drive_sampled(slave().start(shaker_mode=2, Omega=OMEGA, zdot_in=V), acc)
    assert np.array_equal(exact[:, 5], accumulated[:, 5])
    assert np.max(np.abs(exact[:, 1] - accumulated[:, 1])) <= 1e-9


def test_a_step_in_z_in_moves_the_plate_continuously_to_the_new_level(slave):
    # Plate at rest, mass in flight above it; z_in jumps from 0 to 0.05 at t = 2. The samples
    # are not joined, so the history restarts: within the next step the plate moves (C1) to 0.05,
    # then stays there; the mass is hit and thrown up, never below the plate.
    s = slave().start(shaker_mode=2, x0=0.1, v0=0.0, zdot_in=0.0)
    h = 0.01
    times = [k * h for k in range(1, 801)]
    rows = drive_sampled(s, times, lambda t: (0.05 if t >= 2.0 - 1e-12 else 0.0, 0.0))
    t, x, z = rows[:, 0], rows[:, 1], rows[:, 3]
    assert np.all(z[t < 2.0 - 1e-9] == 0.0)
    assert np.all(z[t > 2.0 + h + 1e-9] == 0.05)
    assert np.all((z >= 0.0) & (z <= 0.05 + 1e-16))  # no overshoot beyond rounding
    assert np.all(x >= z - 1e-12)
    assert rows[-1, 5] > 1  # the rising plate hit the mass


def test_noisy_samples_give_a_bounded_plate_and_no_penetration(slave):
    rng = np.random.default_rng(7)
    noise = 1e-4 * V / OMEGA
    s = slave().start(shaker_mode=2, Omega=OMEGA, zdot_in=V)
    times = [k * 0.01 for k in range(1, 3001)]
    rows = drive_sampled(s, times, lambda t: (plate_derivative(0, t) + noise * rng.standard_normal(),
                                              plate_derivative(1, t) + noise * rng.standard_normal()))
    t, x, z, zd = rows[:, 0], rows[:, 1], rows[:, 3], rows[:, 4]
    clean = np.array([plate_derivative(0, tt) for tt in t])
    # Noise of 1e-4 of the amplitude: the plate stays within a few hundred times of it, its
    # velocity within the sinusoid's amplitude plus margin, and never above the mass.
    assert np.max(np.abs(z - clean)) < 1e-2 * V / OMEGA
    assert np.max(np.abs(zd)) < 1.5 * V
    assert np.all(x >= z - 1e-12)


def test_restoring_a_state_restores_the_sample_history(slave):
    # The last three samples are part of the FMU state: a rolled-back stretch with the same
    # inputs is reproduced bit for bit, and one with other inputs goes on from the restored plate.
    s = slave().start(shaker_mode=2, Omega=OMEGA, zdot_in=V)
    h = 0.05
    drive_sampled(s, [k * h for k in range(1, 401)])
    state = s.fmu.getFMUstate()
    first = drive_sampled(s, [20.0 + k * h for k in range(1, 201)])
    s.fmu.setFMUstate(state)
    s.t = 20.0
    again = drive_sampled(s, [20.0 + k * h for k in range(1, 201)])
    assert np.array_equal(first, again)
    s.fmu.setFMUstate(state)
    s.t = 20.0
    (z0,) = s.get("z")
    other = drive_sampled(s, [20.0 + k * h for k in range(1, 201)],
                          lambda t: (plate_derivative(0, t) + 0.01, plate_derivative(1, t)))
    assert abs(other[0, 3] - z0) < 0.02 and np.all(other[:, 1] >= other[:, 3] - 1e-12)
    s.fmu.freeFMUstate(state)


def test_rollback_reproduces_a_step_bit_for_bit(slave):
    s = slave().start(Omega=0.3, V=0.05)
    s.run_to(20.0, 0.5)
    state = s.fmu.getFMUstate()
    s.step(7.3)
    first = s.get("x", "v", "impact_count", "in_contact")
    s.fmu.setFMUstate(state)
    s.t = 20.0
    s.step(7.3)
    assert s.get("x", "v", "impact_count", "in_contact") == first
    s.fmu.freeFMUstate(state)


STATE_SCRIPT = r"""
import json, sys
sys.path.insert(0, sys.argv[1])
from conftest import Slave
from fmpy import read_model_description
md = read_model_description(sys.argv[2])
s = Slave(md, sys.argv[3])
s.fmu.setupExperiment(startTime=0.0)
s.fmu.enterInitializationMode()
s.fmu.exitInitializationMode()
state = s.fmu.deSerializeFMUstate(open(sys.argv[4], "rb").read())
s.fmu.setFMUstate(state)
s.t = float(sys.argv[5])
s.run_to(60.0, 0.25)
print(json.dumps([repr(v) for v in s.get("x", "v", "z", "impact_count", "last_impact_time")]))
"""


def test_serialized_state_restores_in_another_process(slave, fmu_path, unzipped, tmp_path):
    s = slave().start(Omega=0.3, V=0.05)
    s.run_to(25.0, 0.25)
    state = s.fmu.getFMUstate()
    data = s.fmu.serializeFMUstate(state)
    (tmp_path / "state.bin").write_bytes(bytes(data))
    s.run_to(60.0, 0.25)
    want = [repr(v) for v in s.get("x", "v", "z", "impact_count", "last_impact_time")]
    out = subprocess.run([sys.executable, "-c", STATE_SCRIPT, str(ROOT / "tests" / "fmu"),
                          fmu_path, unzipped, str(tmp_path / "state.bin"), "25.0"],
                         capture_output=True, text=True, check=True).stdout
    assert json.loads(out) == want


def test_corrupt_and_truncated_states_are_refused(slave):
    s = slave().start()
    s.run_to(5.0, 1.0)
    data = bytes(s.fmu.serializeFMUstate(s.fmu.getFMUstate()))
    for bad in [data[:-1], data[:40], data[:8] + b"\x07" + data[9:],
                data[:100] + bytes([data[100] ^ 4]) + data[101:]]:
        with pytest.raises(FMICallException):
            s.fmu.deSerializeFMUstate(bad)


def test_tunable_shaker_change_between_steps(slave):
    s = slave().start(Omega=1.75, V=0.07)
    s.run_to(10.0, 0.1)
    (z,) = s.get("z")
    s.set(Omega=2.5, V=0.1)
    s.step(1e-6)
    (z2, zdot2) = s.get("z", "zdot")
    assert abs(z2 - z) < 1e-6 and abs(zdot2) <= 0.1 + 1e-12
    with pytest.raises(FMICallException):
        s.set(zeta=0.1)  # fixed parameter


def test_terminated_status_after_a_step_that_cannot_finish(slave):
    s = slave().start(shaker_mode=2)
    s.fmu.setRealInputDerivatives([s.vr["z_in"]], [5], [1e300])
    with pytest.raises(FMICallException) as failure:
        s.step(10.0)
    assert failure.value.status == 2  # fmi2Discard
    assert s.fmu.getBooleanStatus(fmi2Terminated)
    assert 0.0 <= s.fmu.getRealStatus(2) < 10.0  # fmi2LastSuccessfulTime


def test_wrong_guid_and_bad_values_are_refused(md, unzipped, slave):
    from fmpy.fmi2 import FMU2Slave

    from conftest import Callbacks
    bad = FMU2Slave(guid="{not-the-guid}", unzipDirectory=unzipped,
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName="bad")
    callbacks = Callbacks()
    with pytest.raises(Exception):
        bad.instantiate(callbacks=callbacks.struct)
    assert any("guid" in m for _, _, m in callbacks.messages), callbacks.messages
    s = slave()
    s.fmu.setupExperiment(startTime=0.0)
    for name, value in [("e", 1.5), ("zeta", math.nan), ("omega0", 0.0), ("tol", 1.0)]:
        with pytest.raises(FMICallException):
            s.set(**{name: value})
    with pytest.raises(FMICallException):
        s.fmu.doStep(currentCommunicationPoint=0.0, communicationStepSize=1.0)
