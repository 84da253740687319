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
    fmpy = pathlib.Path(sys.executable).parent / "fmpy"
    print(f"fmpy: default experiment t = {ex.startTime}..{ex.stopTime} s, stepSize {ex.stepSize} s")
    # fmpy does not use stepSize for co-simulation: without --output-interval it picks its own
    # communication interval (stop time / 625 here).
    for extra in [[], ["--output-interval", str(ex.stepSize)]]:
        cmd = [str(fmpy), "simulate", fmu, "--output-file", "/dev/null", *extra]
        wall = best(lambda: subprocess.run(cmd, check=True, capture_output=True))
        r = simulate_fmu(fmu, output_interval=float(extra[1]) if extra else None)
        inproc = best(lambda: simulate_fmu(fmu, output_interval=float(extra[1]) if extra else None))
        steps = len(r) - 1
        print(f"fmpy: `fmpy simulate {' '.join(extra) or '(defaults)'}`: {steps} steps, "
              f"{wall:.3f} s wall for the command, {inproc:.3f} s in-process simulate_fmu "
              f"({inproc / steps * 1e6:.1f} us per step; best of 5)")


if __name__ == "__main__":
    main()
