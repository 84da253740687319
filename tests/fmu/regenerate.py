"""Regenerates the co-simulation reference CSVs in tests/fmu/reference/ from the packaged FMU.

    make fmu-reference        (builds and packages the FMU first)
"""
import sys

from cases import CASES, FMU, REFERENCE, simulate, write_csv


def main():
    if not FMU.exists():
        sys.exit(f"{FMU} not found: run `make fmu` first")
    REFERENCE.mkdir(exist_ok=True)
    for name, (description, _) in CASES.items():
        result = simulate(name)
        path = REFERENCE / f"{name}.csv"
        write_csv(result, path)
        print(f"{path}: {len(result)} rows ({description})")


if __name__ == "__main__":
    main()
