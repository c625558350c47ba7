#!/usr/bin/env python3
"""Write the FOLD files of the CLI's size and frame limits (issue 38) into
DIR, for `origami-fmu check` to be timed on (docs/fold_files.md, "Large
files"):

  frames_10000.fold          a folded state with 9,999 more frames, every
                             other one a crease pattern (the refusal names
                             the first few)
  frames_10000_folded.fold   the same, every frame folded (each is tried)
  frames_10000_cp.fold       a crease pattern on top, 9,999 folded frames
  facets_2m.fold             a 1000 x 1000 grid of squares cut into
                             2,000,000 triangles, indented (105 MB): beyond
                             the size budget
  circle_40000.fold          one convex face of 40,000 corners (a disc)

Usage: python3 scripts/probe_files.py DIR
"""
import json
import math
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
SPEC = ROOT / "tests" / "data" / "fold-spec"


def frame(d, title):
    f = {k: v for k, v in d.items() if not k.startswith("file_") and ":" not in k}
    f["frame_title"] = title
    return f


def main(out):
    out.mkdir(parents=True, exist_ok=True)
    folded = json.loads((SPEC / "diagonal-folded.fold").read_text())
    cp = json.loads((SPEC / "diagonal-cp.fold").read_text())
    for name, top, other in [
        ("frames_10000.fold", folded, lambda k: cp if k % 2 == 0 else folded),
        ("frames_10000_folded.fold", folded, lambda k: folded),
        ("frames_10000_cp.fold", cp, lambda k: folded),
    ]:
        d = dict(top)
        d["file_frames"] = [frame(other(k), f"f{k}") for k in range(1, 10000)]
        (out / name).write_text(json.dumps(d))
    m = 1000
    coords = [[i, j] for j in range(m + 1) for i in range(m + 1)]
    faces = []
    for j in range(m):
        for i in range(m):
            a = j * (m + 1) + i
            faces += [[a, a + 1, a + m + 2], [a, a + m + 2, a + m + 1]]
    n = 40000
    disc = [[math.cos(2 * math.pi * k / n), math.sin(2 * math.pi * k / n)] for k in range(n)]
    (out / "circle_40000.fold").write_text(json.dumps(
        {"file_spec": 1.2, "frame_unit": "cm", "vertices_coords": disc,
         "faces_vertices": [list(range(n))]}))
    with open(out / "facets_2m.fold", "w") as f:
        json.dump({"file_spec": 1.2, "frame_unit": "mm", "vertices_coords": coords,
                   "faces_vertices": faces}, f, indent=1)


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(pathlib.Path(sys.argv[1]))
