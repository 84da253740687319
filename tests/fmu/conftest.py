"""Fixtures for the FMU tests: the packaged FMU (built by `make fmu`) and a small fmpy driver."""
import re
import shutil
from ctypes import CFUNCTYPE, c_char_p, c_int, c_void_p, cast

import pytest
from fmpy import calloc, extract, free, read_model_description
from fmpy.fmi2 import (FMU2Slave, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                       fmi2CallbackFunctions, fmi2CallbackLoggerTYPE)

from cases import FMU, ROOT

CLI = ROOT / "target" / "release" / "bistable"

IMPACT_LOG = re.compile(
    r"impact (\d+) at t=(\S+) s phase=(\S+) x=(\S+) m v_before=(\S+) m/s v_after=(\S+) m/s"
)


def parse_impacts(messages):
    """(index, t, phase, x, v_before, v_after) of each `impact` message logged under logEvents."""
    out = []
    for m in messages:
        hit = IMPACT_LOG.fullmatch(m)
        if hit:
            out.append((int(hit[1]),) + tuple(float(g) for g in hit.groups()[1:]))
    return out


#: The logger as this FMU calls it: `logger(env, name, status, category, "%s", message)`.
LOGGER = CFUNCTYPE(None, c_void_p, c_char_p, c_int, c_char_p, c_char_p, c_char_p)


class Callbacks:
    """FMI 2.0 callbacks whose logger appends `(status, category, message)` to `messages`.

    The logger is called directly, not through fmpy's logger proxy (its default callbacks and
    `simulate_fmu` use one): the proxy keeps a single process-wide pointer to the Python logger it
    wrapped last, which dangles once that call's callback object is collected, so a long-lived
    instance logging through it (a refused call logs an error) can crash the interpreter."""

    def __init__(self):
        self.messages = []
        self._logger = LOGGER(self._log)
        self.struct = fmi2CallbackFunctions()
        self.struct.logger = cast(self._logger, fmi2CallbackLoggerTYPE)
        self.struct.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        self.struct.freeMemory = fmi2CallbackFreeMemoryTYPE(free)

    def _log(self, env, name, status, category, fmt, message):
        self.messages.append((status, category.decode(), message.decode(errors="replace")))


@pytest.fixture(scope="session")
def fmu_path():
    if not FMU.exists():
        pytest.fail(f"{FMU} missing: run `make fmu` (make test-fmu does)")
    return str(FMU)


@pytest.fixture(scope="session")
def md(fmu_path):
    return read_model_description(fmu_path)


@pytest.fixture(scope="session")
def unzipped(fmu_path, tmp_path_factory):
    d = tmp_path_factory.mktemp("fmu")
    extract(fmu_path, str(d))
    yield str(d)
    shutil.rmtree(d, ignore_errors=True)


class Slave:
    """One FMU instance driven step by step through fmpy's FMU2Slave."""

    def __init__(self, md, unzipped, name="slave", logging=False):
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.types = {v.name: v.type for v in md.modelVariables}
        self.fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzipped,
                             modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
        self.callbacks = Callbacks()
        self.fmu.instantiate(callbacks=self.callbacks.struct, loggingOn=logging)
        self.t = 0.0

    def set(self, **values):
        for name, value in values.items():
            if self.types[name] == "Real":
                self.fmu.setReal([self.vr[name]], [value])
            else:
                self.fmu.setInteger([self.vr[name]], [int(value)])

    def start(self, **values):
        self.fmu.setupExperiment(startTime=0.0)
        self.set(**values)
        self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()
        return self

    def get(self, *names):
        out = []
        for n in names:
            if self.types[n] == "Real":
                out.append(self.fmu.getReal([self.vr[n]])[0])
            elif self.types[n] == "Boolean":
                out.append(self.fmu.getBoolean([self.vr[n]])[0])
            else:
                out.append(self.fmu.getInteger([self.vr[n]])[0])
        return tuple(out)

    def step(self, h):
        self.fmu.doStep(currentCommunicationPoint=self.t, communicationStepSize=h)
        self.t += h

    def run_to(self, t_end, h):
        n = max(1, round((t_end - self.t) / h))
        t0 = self.t
        for k in range(1, n + 1):
            nxt = t_end if k == n else t0 + k * h
            self.fmu.doStep(currentCommunicationPoint=self.t, communicationStepSize=nxt - self.t)
            self.t = nxt

    def close(self):
        self.fmu.terminate()
        self.fmu.freeInstance()


@pytest.fixture
def slave(md, unzipped):
    made = []

    def make(**kw):
        s = Slave(md, unzipped, name=f"slave{len(made)}", **kw)
        made.append(s)
        return s

    yield make
    for s in made:
        try:
            s.fmu.freeInstance()
        except Exception:
            pass


@pytest.fixture(scope="session")
def cli():
    if not CLI.exists():
        pytest.skip(f"{CLI} not built (make test-fmu builds it): CLI comparison skipped")
    return str(CLI)
