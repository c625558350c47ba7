"""The main job's pictures on a small Miura-ori: the animation has more than
10 frames that differ and are not blank, the snapshot sheet is not blank,
and the ParaView series of both writers (Python from the FMU run, the CLI's
`simulate --pvd` from the Rust model) reads back with meshio with the right
point count, times and values."""

import subprocess
import sys

import meshio
import numpy as np
import pytest
from PIL import Image

from fmu_helpers import ROOT, build, cli

sys.path.insert(0, str(ROOT / "scripts"))
import fold_pictures  # noqa: E402
import simulate_fmu  # noqa: E402


@pytest.fixture(scope="module")
def miura(tmp_path_factory):
    """A 2x2-cell Miura FOLD file and its FMU, as the main job makes them."""
    d = tmp_path_factory.mktemp("pictures")
    fold = d / "miura.fold"
    r = subprocess.run([str(cli()), "pattern", "miura", "--nx", "2", "--ny", "2", "-o", str(fold)],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    fmu = d / "miura.fmu"
    r = build(fold, fmu)
    assert r.returncode == 0, r.stderr
    return d, fold, fmu


@pytest.fixture(scope="module")
def main_job(miura):
    d, _, fmu = miura
    out = {k: d / v for k, v in [("csv", "m.csv"), ("png", "m.png"), ("gif", "m.gif"),
                                 ("snapshots", "m_snap.png"), ("pvd", "pvd")]}
    args = [str(fmu), "--stop-time", "0.4", "--step", "0.01", "--ramp", "0.3"]
    for k, p in out.items():
        args += [f"--{k}", str(p)]
    assert simulate_fmu.main(args) == 0
    return out


def _rows(csv):
    with open(csv) as f:
        names = f.readline().strip().split(",")
    return names, np.loadtxt(csv, delimiter=",", skiprows=1)


def _not_blank(img):
    """Share of pixels that differ from the corner (background) colour."""
    a = np.asarray(img.convert("RGB"), dtype=int)
    return np.mean(np.any(a != a[0, 0], axis=-1))


def test_animation_has_many_frames_that_move(main_job):
    im = Image.open(main_job["gif"])
    assert im.n_frames > 10
    frames = []
    for k in range(im.n_frames):
        im.seek(k)
        frames.append(np.asarray(im.convert("RGB"), dtype=int))
    for f in frames:
        assert _not_blank(Image.fromarray(f.astype(np.uint8))) > 0.03
    # The sheet folds: the first and last frames differ in many pixels, and
    # no two consecutive frames are all alike while the fold ramps.
    changed = np.mean(np.any(frames[0] != frames[-1], axis=-1))
    assert changed > 0.03, changed
    ramp = frames[: len(frames) * 3 // 4]
    assert all(np.any(a != b) for a, b in zip(ramp, ramp[1:]))


def test_snapshot_sheet_is_not_blank(main_job):
    im = Image.open(main_job["snapshots"])
    assert im.size[0] > 400 and im.size[1] > 200
    assert _not_blank(im) > 0.03


def test_python_paraview_series_reads_back(main_job):
    names, rows = _rows(main_job["csv"])
    times, files = fold_pictures.read_pvd(main_job["pvd"] / "miura.pvd")
    np.testing.assert_allclose(times, rows[:, 0], rtol=0, atol=1e-12)
    n = sum(1 for c in names if c.startswith("vertex[") and c.endswith(".x"))
    creases = [c for c in names if c.startswith("crease[")]
    for k in [0, len(files) // 2, len(files) - 1]:
        m = meshio.read(files[k])
        assert m.points.shape == (n, 3)
        want = np.array([[rows[k, names.index(f"vertex[{i}].{c}")] for c in "xyz"]
                         for i in range(n)])
        np.testing.assert_allclose(m.points, want, rtol=0, atol=1e-15)
        lines = [j for j, b in enumerate(m.cells) if b.type == "line"]
        assert len(lines) == 1 and len(m.cells[lines[0]].data) == len(creases)
        angles = m.cell_data["fold_angle_deg"][lines[0]]
        edges = m.cell_data["fold_edge"][lines[0]]
        for a, e in zip(angles, edges):
            assert a == pytest.approx(np.degrees(rows[k, names.index(f"crease[{e}].angle")]),
                                      abs=1e-12)


def test_cli_paraview_series_reads_back(miura):
    d, fold, _ = miura
    csv, pvd = d / "cli.csv", d / "cli_pvd"
    r = subprocess.run([str(cli()), "simulate", str(fold), "--stop-time", "0.1", "--step", "0.02",
                        "-o", str(csv), "--pvd", str(pvd)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert "miura.pvd" in r.stderr
    names, rows = _rows(csv)
    times, files = fold_pictures.read_pvd(pvd / "miura.pvd")
    assert len(times) == 6
    np.testing.assert_allclose(times, rows[:, 0], rtol=0, atol=1e-12)
    n = sum(1 for c in names if c.startswith("vertex[") and c.endswith(".x"))
    strain = names.index("energy.strain")
    for k, f in enumerate(files):
        m = meshio.read(f)
        kinds = np.concatenate(m.cell_data["cell_kind"])
        # The sampled surface at 3 subdivisions per side (no contact: the
        # default): an unrefined FOLD scene's mesh vertices are the FOLD
        # vertices, the first n points, then 2 samples inside each mesh edge
        # (E = n + F - 1 on a sheet without holes) and 1 inside each facet
        # (F facets of 9 sub-triangles).
        facets = (kinds == 0).sum() // 9
        assert (kinds == 0).sum() == 9 * facets
        assert m.points.shape == (n + 2 * (n + facets - 1) + facets, 3)
        fold_vertex = np.ravel(m.point_data["fold_vertex"])  # one component a point
        np.testing.assert_array_equal(fold_vertex[:n], np.arange(n))
        assert (fold_vertex[n:] == -1).all()
        x0 = [rows[k, names.index(f"vertex[{i}].x")] for i in range(n)]
        np.testing.assert_allclose(m.points[:n, 0], x0, rtol=1e-12, atol=1e-15)
        energy = np.concatenate(m.cell_data["strain_energy"])[kinds == 0]
        assert energy.sum() == pytest.approx(rows[k, strain], rel=1e-9, abs=1e-30)
    assert rows[-1, strain] > 0


def _has_ffmpeg():
    from matplotlib import animation

    return animation.FFMpegWriter.isAvailable()


@pytest.mark.skipif(not _has_ffmpeg(), reason="no MP4 encoder (ffmpeg) on this machine")
def test_mp4_animation_where_an_encoder_exists(miura, main_job, tmp_path):
    _, _, fmu = miura
    names, rows = _rows(main_job["csv"])
    res = {n: rows[:, k] for k, n in enumerate(names)}
    sheet = fold_pictures.load_sheet(fmu, names)
    X = fold_pictures.positions(res, sheet.n_vertices)
    ang = fold_pictures.crease_angles(res, sheet)
    out = tmp_path / "m.mp4"
    n = fold_pictures.write_animation(out, sheet, res["time"], X, ang, max_frames=20)
    assert n == 20
    r = subprocess.run(["ffprobe", "-v", "error", "-count_frames", "-select_streams", "v:0",
                        "-show_entries", "stream=nb_read_frames", "-of", "csv=p=0", str(out)],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert int(r.stdout.strip()) == 20


def test_an_fmu_without_position_outputs_gets_a_clear_error(tmp_path, capsys):
    import json

    scene = json.loads((ROOT / "tests" / "fmpy" / "scenes" / "square.json").read_text())
    scene["outputs"]["positions"] = False
    src = tmp_path / "nopos.json"
    src.write_text(json.dumps(scene))
    fmu = tmp_path / "nopos.fmu"
    r = build(src, fmu)
    assert r.returncode == 0, r.stderr
    rc = simulate_fmu.main([str(fmu), "--stop-time", "0.05", "--step", "0.01",
                            "--csv", str(tmp_path / "x.csv"), "--png", str(tmp_path / "x.png"),
                            "--gif", str(tmp_path / "x.gif")])
    assert rc == 1
    assert "no vertex positions" in capsys.readouterr().err
    assert not (tmp_path / "x.gif").exists()
