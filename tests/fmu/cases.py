"""Regression cases of the bistable_impact FMU (co-simulation, and one Model Exchange case), run
through fmpy.

Shared by the regression test (test_regression.py) and the regeneration script
(regenerate.py, `make fmu-reference`), so both simulate exactly the same way.
"""
import math
import pathlib

import numpy as np
from fmpy import simulate_fmu

ROOT = pathlib.Path(__file__).resolve().parents[2]
FMU = ROOT / "target" / "fmu" / "bistable_impact.fmu"
REFERENCE = pathlib.Path(__file__).resolve().parent / "reference"

#: Columns stored in the reference CSVs (time first).
COLUMNS = [
    "time", "x", "v", "z", "zdot", "kinetic_energy", "potential_energy", "impact_count",
    "last_impact_time", "last_impact_phase", "last_impact_v_before", "last_impact_v_after",
    "well", "snap_through_count", "in_contact",
]


def sinusoid_input(omega, v, stop, dt):
    """Plate of the internal shaker, z = (V/Omega) sin(Omega t), as an fmpy input table."""
    t = np.arange(0.0, stop + dt / 2, dt)
    signal = np.zeros(len(t), dtype=[("time", float), ("z_in", float), ("zdot_in", float)])
    signal["time"] = t
    signal["z_in"] = v / omega * np.sin(omega * t)
    signal["zdot_in"] = v * np.cos(omega * t)
    return signal


#: name -> (description, simulate_fmu keyword arguments)
CASES = {
    "baseline": (
        "paper baseline Omega=1.75, V=0.07: period-1 impacts",
        dict(start_values={"Omega": 1.75, "V": 0.07}, stop_time=200.0, output_interval=0.1),
    ),
    "chatter_sticking": (
        "low frequency Omega=0.2, V=0.05: chatter sequences ending in sticking",
        dict(start_values={"Omega": 0.2, "V": 0.05}, stop_time=100.0, output_interval=0.1),
    ),
    "escape_well2": (
        "Omega=0.85, V=0.15: the impact at t=0 throws the mass into well 2, where it stays",
        dict(start_values={"Omega": 0.85, "V": 0.15}, stop_time=100.0, output_interval=0.1),
    ),
    "external_shaker": (
        "external mode: the baseline sinusoid sampled every 0.05 s through z_in, zdot_in "
        "(fmpy input table, no input derivatives; fmpy 0.3.32's set_input_derivatives only "
        "works with 9 inputs): the plate is the default quintic Hermite extrapolation of the "
        "samples",
        dict(
            start_values={"shaker_mode": 2, "Omega": 1.75, "zdot_in": 0.07},
            stop_time=100.0,
            output_interval=0.05,
            input=sinusoid_input(1.75, 0.07, 100.0, 0.05),
        ),
    ),
    "external_shaker_taylor": (
        "the external_shaker inputs with plate_reconstruction = taylor (first order: "
        "z_in + zdot_in*s over each step, blended to stay continuous); its reference is the "
        "external_shaker result from before the Hermite scheme, unchanged",
        dict(
            start_values={"shaker_mode": 2, "Omega": 1.75, "zdot_in": 0.07,
                          "plate_reconstruction": 1},
            stop_time=100.0,
            output_interval=0.05,
            input=sinusoid_input(1.75, 0.07, 100.0, 0.05),
        ),
    ),
    "model_exchange_baseline": (
        "the paper baseline through Model Exchange: fmpy's CVode (BDF) at relative tolerance "
        "1e-10, every impact and snap-through located by CVode's root finding on the FMU's event "
        "indicators and applied in fmi2NewDiscreteStates",
        dict(fmi_type="ModelExchange", solver="CVode", relative_tolerance=1e-10,
             start_values={"Omega": 1.75, "V": 0.07}, stop_time=200.0, output_interval=0.1),
    ),
}

#: Tolerances of the comparison (reals); integers and booleans must match exactly.
RTOL, ATOL = 1e-9, 1e-10


def simulate(name, fmu=FMU):
    """Runs one case through fmpy and returns its result as a structured array."""
    _, kwargs = CASES[name]
    return simulate_fmu(str(fmu), output=COLUMNS[1:], **kwargs)


def write_csv(result, path):
    """Writes the COLUMNS of `result` with full precision."""
    with open(path, "w") as f:
        f.write(",".join(COLUMNS) + "\n")
        for row in result:
            f.write(",".join(repr(float(row[c])) if c in ("time",) or result.dtype[c].kind == "f"
                             else str(int(row[c])) for c in COLUMNS) + "\n")


def read_csv(path):
    """Reads a reference CSV into a structured array of floats."""
    return np.genfromtxt(path, delimiter=",", names=True)


def finite(a):
    return all(math.isfinite(float(x)) for x in a)
