"""The packaged FMU: fmpy's validation, archive layout, exported symbols, guid."""
import pathlib
import re
import subprocess
import sys
import zipfile

from cases import FMU, ROOT

FMI2_FUNCTIONS = sorted("""
fmi2GetTypesPlatform fmi2GetVersion fmi2SetDebugLogging fmi2Instantiate fmi2FreeInstance
fmi2SetupExperiment fmi2EnterInitializationMode fmi2ExitInitializationMode fmi2Terminate fmi2Reset
fmi2GetReal fmi2GetInteger fmi2GetBoolean fmi2GetString fmi2SetReal fmi2SetInteger fmi2SetBoolean
fmi2SetString fmi2GetFMUstate fmi2SetFMUstate fmi2FreeFMUstate fmi2SerializedFMUstateSize
fmi2SerializeFMUstate fmi2DeSerializeFMUstate fmi2GetDirectionalDerivative
fmi2SetRealInputDerivatives fmi2GetRealOutputDerivatives fmi2DoStep fmi2CancelStep fmi2GetStatus
fmi2GetRealStatus fmi2GetIntegerStatus fmi2GetBooleanStatus fmi2GetStringStatus
fmi2EnterEventMode fmi2NewDiscreteStates fmi2EnterContinuousTimeMode fmi2CompletedIntegratorStep
fmi2SetTime fmi2SetContinuousStates fmi2GetDerivatives fmi2GetEventIndicators
fmi2GetContinuousStates fmi2GetNominalsOfContinuousStates
""".split())


def test_fmpy_validate_finds_no_problems(fmu_path):
    fmpy = ROOT / ".venv" / "bin" / "fmpy"
    r = subprocess.run([str(fmpy), "validate", fmu_path], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "No problems found." in r.stdout


def test_archive_layout_and_model_description(fmu_path):
    with zipfile.ZipFile(fmu_path) as z:
        names = set(z.namelist())
        assert {"modelDescription.xml", "binaries/linux64/bistable_impact.so",
                "documentation/index.html", "extra/README.md", "extra/baseline.csv"} <= names
        assert z.read("modelDescription.xml") == (ROOT / "modelDescription.xml").read_bytes()
        assert b"<h1>bistable_impact</h1>" in z.read("documentation/index.html")


def fmi3_functions():
    """Every function of the FMI 3.0 standard, from its header (shipped with fmpy)."""
    import fmpy
    header = pathlib.Path(fmpy.__file__).parent / "c-code" / "fmi3FunctionTypes.h"
    return sorted(set(re.findall(r"\b(fmi3\w+)TYPE\b", header.read_text())))


def test_exactly_the_44_fmi2_and_75_fmi3_functions_are_exported(unzipped):
    assert len(FMI2_FUNCTIONS) == 44 and len(fmi3_functions()) == 75
    so = f"{unzipped}/binaries/linux64/bistable_impact.so"
    out = subprocess.run(["nm", "-D", "--defined-only", so], capture_output=True, text=True,
                         check=True).stdout
    exported = sorted(line.split()[-1] for line in out.splitlines() if line.strip())
    assert exported == sorted(FMI2_FUNCTIONS + fmi3_functions())


def test_guid_is_derived_from_the_model_description(md):
    r = subprocess.run([sys.executable, str(ROOT / "fmu" / "guid.py"), "--check"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert md.guid in r.stdout


def test_variables_units_and_defaults(md):
    v = {x.name: x for x in md.modelVariables}
    for name in ["x", "v", "z", "zdot", "impact_count", "last_impact_time", "last_impact_phase",
                 "last_impact_v_before", "last_impact_v_after", "kinetic_energy",
                 "potential_energy", "well", "in_contact"]:
        assert v[name].causality == "output", name
    assert (v["z_in"].causality, v["zdot_in"].causality) == ("input", "input")
    assert (v["omega0"].unit, float(v["omega0"].start)) == ("rad/s", 1.0)
    assert (v["delta_x"].unit, float(v["delta_x"].start)) == ("m", 1.0)
    assert v["x"].unit == "m" and v["v"].unit == "m/s" and v["kinetic_energy"].unit == "J"
    assert md.coSimulation.canInterpolateInputs and md.coSimulation.canSerializeFMUstate
