"""External shaker inputs against the internal sinusoid, FMU states (rollback, serialization,
another process), tunable parameters, and refused calls through fmpy."""
import json
import math
import subprocess
import sys

import pytest
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import fmi2Terminated

from cases import ROOT

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


def test_inputs_without_derivatives_are_a_coarser_plate(slave):
    internal = slave().start(Omega=OMEGA, V=V)
    internal.run_to(60.0, 0.01)
    external = slave().start(shaker_mode=2, Omega=OMEGA, zdot_in=V)
    drive_external(external, 60.0, 0.01, orders=1)
    (x_int,), (x_ext,) = internal.get("x"), external.get("x")
    assert 1e-9 < abs(x_int - x_ext) < 1e-2


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
    bad = FMU2Slave(guid="{not-the-guid}", unzipDirectory=unzipped,
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName="bad")
    with pytest.raises(Exception):
        bad.instantiate()
    s = slave()
    s.fmu.setupExperiment(startTime=0.0)
    for name, value in [("e", 1.5), ("zeta", math.nan), ("omega0", 0.0), ("tol", 1.0)]:
        with pytest.raises(FMICallException):
            s.set(**{name: value})
    with pytest.raises(FMICallException):
        s.fmu.doStep(currentCommunicationPoint=0.0, communicationStepSize=1.0)
