#!/usr/bin/env python3
"""Every numeric option of every command, read from the command's own --help, against hostile values.

The option tables' test (option_table_test.cpp) covers the options of the library's option structs
with their documented ranges; this sweep covers the rest too (experiment, compare, view, lod,
verify-extraction, ...) without a list of options: a new numeric option is in it as soon as it is
in --help. Every command gets inputs that do not exist, so a value that is accepted ends in exit 2
(bad input) before any work, and a refused one in exit 1 with a one-line message naming the flag.

Outcome checked for each (command, option, value):
  - NaN, +inf, -inf: exit 1, naming the flag (no option of linesurf takes a non-finite number);
  - -1, 0, 1e-300, 1e300, the type's limits: exit 1 naming the flag, or exit 2 (accepted);
  - never a crash, a signal, a hang (10 s each) or another exit code.

usage: numeric_sweep.py LINESURF_CLI
"""
import os
import re
import subprocess
import sys
import tempfile

FLOAT_VALUES = ["nan", "inf", "-inf", "-1", "0", "1e-300", "1e300", "3.4028235e38", "-3.4028235e38", "1.8e308"]
INT_VALUES = ["nan", "inf", "-inf", "-1", "0", "1e-300", "1e300", "2147483647", "-2147483648", "2147483648",
              "9223372036854775807", "18446744073709551616"]
NON_FINITE = {"nan", "inf", "-inf"}


def commands(tmp):
    missing = os.path.join(tmp, "missing")
    empty = os.path.join(tmp, "empty_dir")
    os.makedirs(empty, exist_ok=True)
    out = os.path.join(tmp, "out")
    return [
        (["info"], [missing + ".ply"]),
        (["convert"], [missing + ".ply", out + ".ply"]),
        (["normals"], [missing + ".ply", "-o", out + ".ply"]),
        (["extract", "eps-delta"], [missing + ".ply", "-o", out + ".ply"]),
        (["extract", "shape-approx"], [missing + ".ply", "-o", out + ".ply"]),
        (["extract", "contour"], [missing + ".ply", "-o", out + ".ply"]),
        (["extract", "features"], [missing + ".ply", "-o", out + ".ply"]),
        (["mesh"], [missing + ".ply", "-o", out + ".ply"]),
        (["verify-extraction"], [missing + ".ply", missing + "_hybrid.ply"]),
        (["render"], [missing + ".ply", "-o", out + ".png"]),
        (["lod", "build"], [missing + ".ply", "-o", out + ".lod"]),
        (["view"], [missing + ".ply", "-o", out + ".html"]),
        (["compare"], [missing + "_a.png", missing + "_b.png"]),
        (["experiment"], [empty, "-o", os.path.join(tmp, "experiment_out")]),
    ]


OPTION_LINE = re.compile(r"^\s+((?:-\w,)?--[\w-]+(?:,(?:-\w|--[\w-]+|!--[\w-]+))*)\s+(FLOAT|INT|UINT)\b(.*)$")


def numeric_options(cli, sub):
    help_text = subprocess.run([cli] + sub + ["--help"], capture_output=True, text=True, timeout=30).stdout
    found = []
    for line in help_text.splitlines():
        m = OPTION_LINE.match(line)
        if not m:
            continue
        flags = [f for f in m.group(1).split(",") if f.startswith("--")]
        arity = 3 if re.search(r"\bx\s*3\b", m.group(3)) else 1
        found.append((flags[0], m.group(2), arity))
    return found


def main():
    cli = os.path.abspath(sys.argv[1])
    failures = []
    checked = 0
    with tempfile.TemporaryDirectory(prefix="linesurf_sweep_") as tmp:
        for sub, positionals in commands(tmp):
            options = numeric_options(cli, sub)
            if not options and sub not in (["info"], ["convert"]):  # these two take no number today
                failures.append(f"{' '.join(sub)}: no numeric option found in --help (parser out of date?)")
            for flag, kind, arity in options:
                for value in (FLOAT_VALUES if kind == "FLOAT" else INT_VALUES):
                    args = [cli, "-q"] + sub + positionals + [flag] + [value] * arity
                    where = f"{' '.join(sub)} {flag} {value}"
                    try:
                        r = subprocess.run(args, capture_output=True, text=True, timeout=10, cwd=tmp)
                    except subprocess.TimeoutExpired:
                        failures.append(f"{where}: still running after 10 s")
                        continue
                    checked += 1
                    text = (r.stdout + r.stderr).strip()
                    lines = [l for l in text.splitlines() if l.strip()]
                    if r.returncode < 0 or r.returncode not in (1, 2):
                        failures.append(f"{where}: exit {r.returncode}: {text[:200]}")
                    elif value in NON_FINITE and r.returncode != 1:
                        failures.append(f"{where}: a non-finite value was accepted (exit {r.returncode}): {text[:200]}")
                    elif r.returncode == 1 and flag not in text:
                        failures.append(f"{where}: refused without naming {flag}: {text[:200]}")
                    elif len(lines) != 1:
                        failures.append(f"{where}: {len(lines)} lines of message, not one: {text[:300]}")
    for f in failures:
        print(f)
    print(f"numeric_sweep: {checked} runs, {len(failures)} failing", file=sys.stderr)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
