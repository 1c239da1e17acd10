#!/usr/bin/python3
"""bench/orientation_scenes.py [N]: which side `linesurf normals` turns the normals of open scenes to.

For each synthetic scene of `linesurf_gen_scan --scene` (terrain from the air, a room from its
scanner, a facade from the street; N points each, default 500000, noise 0.1 spacing), runs
`linesurf normals` with the default rule and with `--orient` choices, and prints per class the share
of normals with n . n_true > 0 (n_true from the generator's truth file). Also runs the rule the
default replaced when OLD_LINESURF names an older binary. Figures in docs/results.md.
Environment: LINESURF_BUILD (build), OLD_LINESURF, SCENE_DIR (a temporary folder).
"""
import os
import subprocess
import sys
import tempfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BUILD = os.environ.get("LINESURF_BUILD", os.path.join(ROOT, "build"))
CLI = os.path.join(BUILD, "linesurf")
GEN = os.path.join(BUILD, "linesurf_gen_scan")
CLASSES = ["ground", "roof", "wall", "vegetation", "object"]


def read_ply(path):
    """Binary little-endian PLY vertices as a structured array (float and uchar properties)."""
    with open(path, "rb") as f:
        header = b""
        while not header.endswith(b"end_header\n"):
            header += f.readline()
        fields, count = [], 0
        for line in header.decode().splitlines():
            w = line.split()
            if w[:2] == ["element", "vertex"]:
                count = int(w[2])
            elif w and w[0] == "element":
                break
            elif w[:1] == ["property"]:
                fields.append((w[2], {"float": "<f4", "uchar": "u1", "uint": "<u4"}[w[1]]))
        return np.frombuffer(f.read(), dtype=np.dtype(fields), count=count)


def shares(out, truth):
    n = np.stack([out["nx"], out["ny"], out["nz"]], 1)
    t = np.stack([truth["nx"], truth["ny"], truth["nz"]], 1)
    agree = (n * t).sum(1) > 0
    cls = truth["class"].astype(int)
    return {CLASSES[c]: (agree[cls == c].mean(), int((cls == c).sum())) for c in sorted(set(cls))}


def main():
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 500000
    d = os.environ.get("SCENE_DIR") or tempfile.mkdtemp(prefix="linesurf_scenes_")
    old = os.environ.get("OLD_LINESURF")
    sensors = {"terrain": None, "room": "0.8 -0.6 1.5", "facade": "0 -10 2.5"}
    print(f"{'scene':8} {'rule':28} " + " ".join(f"{c:>16}" for c in CLASSES))
    for scene, sensor in sensors.items():
        scan, truth = os.path.join(d, scene + ".ply"), os.path.join(d, scene + "_truth.ply")
        subprocess.run([GEN, "--scene", scene, "--truth", truth, scan, str(n), "1", "0.1"], check=True, stdout=subprocess.DEVNULL)
        t = read_ply(truth)
        runs = [("default (auto)", CLI, []), ("--orient outward", CLI, ["--orient", "outward"]), ("--orient up", CLI, ["--orient", "up"])]
        if sensor:
            runs.append((f"--orient towards {sensor}", CLI, ["--orient", "towards", "--viewpoint"] + sensor.split()))
        if old:
            runs.insert(0, ("previous rule", old, []))
        for name, cli, extra in runs:
            out = os.path.join(d, scene + "_n.ply")
            subprocess.run([cli, "-q", "normals", scan, "-o", out] + extra, check=True)
            s = shares(read_ply(out), t)
            cells = " ".join(f"{100 * s[c][0]:7.2f}% ({s[c][1]:6d})" if c in s else f"{'-':>16}" for c in CLASSES)
            print(f"{scene:8} {name:28} {cells}")


if __name__ == "__main__":
    main()
