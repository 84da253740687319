"""Wall time of `fmpy simulate` for the FMU's default experiment (best of 5), as a command and
as simulate_fmu in this process.

    python tests/fmu/bench_fmpy.py target/fmu/bistable_impact.fmu
"""
import pathlib
import subprocess
import sys
import time

from fmpy import read_model_description, simulate_fmu


def best(f, n=5):
    times = []
    for _ in range(n):
        t0 = time.perf_counter()
        f()
        times.append(time.perf_counter() - t0)
    return min(times)


def main():
    fmu = sys.argv[1]
    ex = read_model_description(fmu).defaultExperiment
    steps = round((float(ex.stopTime) - float(ex.startTime)) / float(ex.stepSize))
    fmpy = pathlib.Path(sys.executable).parent / "fmpy"
    cmd = [str(fmpy), "simulate", fmu, "--output-file", "/dev/null"]
    wall = best(lambda: subprocess.run(cmd, check=True, capture_output=True))
    inproc = best(lambda: simulate_fmu(fmu))
    print(f"fmpy: default experiment t = {ex.startTime}..{ex.stopTime} s, "
          f"step {ex.stepSize} s ({steps} steps)")
    print(f"fmpy: `fmpy simulate` command {wall:.3f} s wall (best of 5)")
    print(f"fmpy: simulate_fmu in-process {inproc:.3f} s ({inproc / steps * 1e6:.1f} us per step)")


if __name__ == "__main__":
    main()
