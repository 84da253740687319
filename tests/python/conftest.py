"""Shared fixtures of the Python package tests: the release binaries of the CLI and of the
high-precision reference (built by `make test-python`)."""

import os
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
RELEASE = ROOT / "target" / "release"


def _binary(name):
    path = RELEASE / name
    if not os.access(path, os.X_OK):
        pytest.fail(f"{path} is missing: run `cargo build --release -p bistable-cli -p bistable-reference`")
    return path


@pytest.fixture(scope="session")
def cli():
    return _binary("bistable")


@pytest.fixture(scope="session")
def reference():
    return _binary("bistable-reference")
