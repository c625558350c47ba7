#!/usr/bin/env python3
"""Compare two output tables of tests/c_host/host.c (a header of names,
then the time and every output, one row per step): the same names and
times, and every output equal within TOL of its scale. The scale of an
output is the largest magnitude, over the run in REFERENCE, of the outputs
of its kind (the name before its first '[' or '.': every vertex
coordinate, every crease angle, every energy), so that a coordinate that
stays near 0 is measured against the sheet's size. Prints the largest
difference relative to the scale; exit status 1 when it is over TOL.

Usage: compare_outputs.py REFERENCE.csv OTHER.csv [TOL, default 1e-9]
"""

import csv
import re
import sys


def read(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], [[float(x) for x in row] for row in rows[1:]]


def main():
    if len(sys.argv) not in (3, 4):
        sys.exit(__doc__)
    (names, ref), (other_names, other) = read(sys.argv[1]), read(sys.argv[2])
    tol = float(sys.argv[3]) if len(sys.argv) == 4 else 1e-9
    if names != other_names or not ref or len(ref) != len(other):
        sys.exit(f"the tables differ in names or rows: {sys.argv[1]}, {sys.argv[2]}")
    for i, (a, b) in enumerate(zip(ref, other)):
        if len(a) != len(names) or len(b) != len(names) or a[0] != b[0]:
            sys.exit(f"row {i + 1} differs in length or time")
    kind = [re.split(r"[\[.]", n, maxsplit=1)[0] for n in names]
    scale = {}
    for j, k in enumerate(kind):
        scale[k] = max([scale.get(k, 0.0)] + [abs(row[j]) for row in ref])
    worst, where = 0.0, "none"
    for j in range(1, len(names)):
        s = scale[kind[j]] or 1.0  # a kind that is 0 throughout: absolute
        for i, (a, b) in enumerate(zip(ref, other)):
            d = abs(a[j] - b[j]) / s
            if not d <= worst:
                worst, where = d, f"{names[j]} at t = {a[0]:g}"
    print(
        f"{len(ref)} steps x {len(names) - 1} outputs: largest difference {worst:.3g} "
        f"of the scale ({where})"
    )
    if not worst <= tol:
        sys.exit(f"over the tolerance {tol:g}")


if __name__ == "__main__":
    main()
