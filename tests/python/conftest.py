"""Shared fixtures of the Python suite (run by ctest as PythonModule, with /usr/bin/python3)."""
import os
import pathlib
import subprocess

import numpy as np
import pytest

SOURCE_DIR = pathlib.Path(os.environ.get("LINESURF_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))
DATA = SOURCE_DIR / "data"

try:
    import linesurf  # noqa: F401
except ImportError as e:  # a clear message instead of a wall of collection errors
    raise pytest.UsageError(f"cannot import linesurf ({e}): build it and set PYTHONPATH=build/python")


@pytest.fixture(scope="session")
def cli():
    """Runs the built `linesurf` CLI: cli(*args) -> CompletedProcess (text)."""
    exe = os.environ.get("LINESURF_CLI") or str(SOURCE_DIR / "build" / "linesurf")
    if not pathlib.Path(exe).exists():
        pytest.skip(f"CLI not found at {exe} (set LINESURF_CLI)")

    def run(*args):
        return subprocess.run([exe, *map(str, args)], capture_output=True, text=True)

    return run


@pytest.fixture(scope="session")
def igea():
    return linesurf.read(str(DATA / "igea_points.ply"))


@pytest.fixture(scope="session")
def santa_path():
    return DATA / "santa_points.ply"


def fibonacci_sphere(n, radius=1.0):
    i = np.arange(n) + 0.5
    z = 1 - 2 * i / n
    r = np.sqrt(1 - z * z)
    a = i * np.pi * (3 - np.sqrt(5))
    return radius * np.stack([r * np.cos(a), r * np.sin(a), z], axis=1)
