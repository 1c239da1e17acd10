"""Overhead of the Python module, figures for docs/decisions.md:
  1. rendering igea through Python vs the same call in C++ (build/linesurf_python_overhead);
  2. passing a 1 M-point array in (float32/float64, C- and F-ordered, strided).
Run: cmake --build build --target linesurf_python linesurf_python_overhead
     PYTHONPATH=build/python /usr/bin/python3 bench/python_overhead.py [REPEATS]
Frames alternate C++ / Python runs so that load from other processes hits both alike."""
import json
import pathlib
import statistics
import subprocess
import sys
import time

import numpy as np

import linesurf

ROOT = pathlib.Path(__file__).resolve().parents[1]
MODEL = ROOT / "data" / "igea_points.ply"
CPP = ROOT / "build" / "linesurf_python_overhead"


def python_render(model, size, repeats):
    linesurf.render(model, size=size)  # warm-up
    ms = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        linesurf.render(model, size=size)
        ms.append(1000 * (time.perf_counter() - t0))
    return ms


def main(repeats=15, rounds=5):
    model = linesurf.prepare(linesurf.read(str(MODEL)))
    for size in ((512, 512), (1024, 1024)):
        cpp, py = [], []
        for _ in range(rounds):
            out = subprocess.run([str(CPP), str(MODEL), str(size[0]), str(size[1]), str(repeats)],
                                 capture_output=True, text=True, check=True).stdout
            cpp.append(json.loads(out)["median_ms"])
            py.append(statistics.median(python_render(model, size, repeats)))
        c, p = statistics.median(cpp), statistics.median(py)
        print(f"render igea {size[0]}x{size[1]} ({len(model.points)} points): C++ {c:.2f} ms, "
              f"Python {p:.2f} ms, overhead {100 * (p / c - 1):+.2f}% (medians of {rounds} x {repeats} frames)")

    rng = np.random.default_rng(0)
    base = rng.normal(size=(1_000_000, 3))
    arrays = {"float32 C": base.astype(np.float32), "float64 C": base,
              "float32 F": np.asfortranarray(base.astype(np.float32)), "float64 F": np.asfortranarray(base),
              "float32 strided view": np.repeat(base.astype(np.float32), 2, axis=0)[::2]}
    for name, a in arrays.items():
        ms = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            linesurf.Model(points=a)
            ms.append(1000 * (time.perf_counter() - t0))
        print(f"Model(points=1M x 3 {name}): median {statistics.median(ms):.2f} ms, min {min(ms):.2f} ms")


if __name__ == "__main__":
    main(*map(int, sys.argv[1:]))
