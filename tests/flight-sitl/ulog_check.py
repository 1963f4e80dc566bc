#!/usr/bin/env python3
"""pyulog against our ULog files (issue 31): each FILE.ulg must parse with pyulog without a
word printed (pyulog prints its warnings) and without corruption, and every value ulog2csv
writes must equal the one in EXPECTED/ (written by `flight-sitl ulog-csv FILE.ulg --out
EXPECTED`, with this project's reader): same files, same columns, same rows, floats equal
as float32 (NaN equal to NaN).

    python ulog_check.py EXPECTED_DIR FILE.ulg...

Exit 0 when all agree, 1 with the differences listed otherwise."""

import contextlib
import io
import math
import os
import subprocess
import sys
import tempfile

import numpy as np
from pyulog import ULog


def cell(text):
    """A CSV cell as a comparable number (numpy's True/False as 1/0)."""
    if text in ("True", "False"):
        return 1 if text == "True" else 0
    try:
        return int(text)
    except ValueError:
        return float(np.float32(float(text)))


def same(a, b):
    a, b = cell(a), cell(b)
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return a == b


def compare(ours, theirs, name):
    problems = []
    with open(ours, encoding="utf-8") as f:
        want = [line.rstrip("\n").split(",") for line in f]
    with open(theirs, encoding="utf-8") as f:
        have = [line.rstrip("\n").split(",") for line in f]
    if want[:1] != have[:1]:
        return [f"{name}: columns {have[:1]} != {want[:1]}"]
    if len(want) != len(have):
        return [f"{name}: {len(have) - 1} rows, {len(want) - 1} logged"]
    for i, (w, h) in enumerate(zip(want[1:], have[1:]), start=1):
        bad = [c for c, x, y in zip(want[0], w, h) if not same(x, y)]
        if bad:
            problems.append(f"{name} row {i}: {bad[0]} {h[want[0].index(bad[0])]} != logged "
                            f"{w[want[0].index(bad[0])]}")
            if len(problems) > 5:
                break
    return problems


def check(expected, path):
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed), contextlib.redirect_stderr(printed):
        log = ULog(path)
    problems = []
    if printed.getvalue():
        problems.append(f"{path}: pyulog printed: {printed.getvalue().strip()[:300]}")
    if log.file_corruption:
        problems.append(f"{path}: pyulog found corruption")
    stem = os.path.splitext(os.path.basename(path))[0]
    ours = sorted(f for f in os.listdir(expected) if f.startswith(stem + "_"))
    with tempfile.TemporaryDirectory() as out:
        subprocess.run(["ulog2csv", "-o", out, path], check=True, stdout=subprocess.DEVNULL)
        theirs = sorted(os.listdir(out))
        if ours != theirs:
            problems.append(f"{path}: ulog2csv wrote {theirs}, we logged {ours}")
        for name in sorted(set(ours) & set(theirs)):
            problems += compare(os.path.join(expected, name), os.path.join(out, name), name)
        rows = sum(len(d.data["timestamp"]) for d in log.data_list)
    print(f"{path}: {len(theirs)} topics, {rows} rows, {len(log.logged_messages)} strings, "
          f"{len(log.initial_parameters)} parameters, {len(log.dropouts)} dropouts: "
          + ("agree" if not problems else "DIFFER"))
    return problems


def main():
    if len(sys.argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    problems = []
    for path in sys.argv[2:]:
        problems += check(sys.argv[1], path)
    for p in problems:
        print(p, file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
