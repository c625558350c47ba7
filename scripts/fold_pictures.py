"""Pictures and ParaView files of an origami FMU run (fmpy results).

The FMU outputs vertex[i].x/y/z for every FOLD vertex and crease[e].angle for
every FOLD crease edge; the faces come from the FMU's resources/scene.json
(the model's mesh: triangles, FOLD vertices first). When the mesh was refined
(it has vertices that are not outputs), the FOLD faces of resources/scene.fold
are drawn instead. Facets are coloured by the mean |fold angle| of the creases
around their FOLD face.

Functions: load_sheet (faces and creases of an FMU), write_animation (GIF or
MP4), write_snapshots (a grid of 3D views at several times) and write_pvd (a
ParaView .pvd series of .vtu files through meshio)."""

import json
import pathlib
import zipfile
from dataclasses import dataclass
from xml.sax.saxutils import quoteattr

import numpy as np


@dataclass
class Sheet:
    """What the pictures need of a scene, in FOLD vertex indices."""

    n_vertices: int
    reference: np.ndarray  # (n, 3) flat reference positions (m)
    faces: list  # polygons (lists of vertex indices) to draw
    edges: np.ndarray  # (m, 2) FOLD edges drawn as lines
    edge_fold: np.ndarray  # (m,) FOLD edge index of each line
    creases: list  # FOLD edge indices with a crease[e].angle output
    face_creases: list  # per face: the FOLD crease edges around its FOLD face


class _Union:
    def __init__(self, n):
        self.p = list(range(n))

    def find(self, a):
        while self.p[a] != a:
            self.p[a] = self.p[self.p[a]]
            a = self.p[a]
        return a

    def join(self, a, b):
        self.p[self.find(a)] = self.find(b)


def load_sheet(fmu, output_names):
    """The Sheet of an FMU file; `output_names` are the FMU's output names
    (to know which crease angles exist)."""
    with zipfile.ZipFile(fmu) as z:
        names = set(z.namelist())
        scene = json.loads(z.read("resources/scene.json"))
        fold = json.loads(z.read("resources/scene.fold")) if "resources/scene.fold" in names else None
    mesh = scene["mesh"]
    n = int(scene["fold_vertex_count"])
    coords = np.array(mesh["coords"], dtype=float)
    reference = np.column_stack([coords[:n], np.zeros(n)])
    # FOLD edges: their end vertices are the FOLD vertices among the mesh
    # edges that carry the tag (refinement splits an edge into pieces).
    ends = {}
    for e in mesh["edges"]:
        f = e.get("fold_edge")
        if f is not None:
            ends.setdefault(f, set()).update(v for v in e["v"] if v < n)
    fold_edges = sorted(f for f, vs in ends.items() if len(vs) == 2)
    pair = {tuple(sorted(ends[f])): f for f in fold_edges}
    outputs = set(output_names)
    creases = [f for f in fold_edges if f"crease[{f}].angle" in outputs]
    crease_set = set(creases)
    tris = mesh["triangles"]
    if all(v < n for t in tris for v in t):
        faces = [list(t) for t in tris]
    elif fold is not None and all(v < n for f in fold.get("faces_vertices", []) for v in f):
        faces = [list(f) for f in fold["faces_vertices"]]
    else:
        raise ValueError(
            f"{fmu}: the mesh has vertices that are not FMU outputs (refined) and the FMU "
            "has no FOLD faces in resources/scene.fold to draw instead")
    # Faces joined across sides that are no FOLD edge (triangulation
    # diagonals) make up one FOLD face; its creases colour all its parts.
    side_faces = {}
    for i, f in enumerate(faces):
        for a, b in zip(f, f[1:] + f[:1]):
            side_faces.setdefault(tuple(sorted((a, b))), []).append(i)
    u = _Union(len(faces))
    for side, fs in side_faces.items():
        if side not in pair and len(fs) == 2:
            u.join(fs[0], fs[1])
    group_creases = {}
    for side, fs in side_faces.items():
        f = pair.get(side)
        if f in crease_set:
            for i in fs:
                group_creases.setdefault(u.find(i), set()).add(f)
    face_creases = [sorted(group_creases.get(u.find(i), ())) for i in range(len(faces))]
    edges = np.array([sorted(ends[f]) for f in fold_edges], dtype=int).reshape(-1, 2)
    return Sheet(n, reference, faces, edges, np.array(fold_edges, dtype=int), creases,
                 face_creases)


def positions(res, n):
    """(rows, n, 3) vertex positions from an fmpy result."""
    names = res.dtype.names if hasattr(res, "dtype") else res.keys()
    if n and "vertex[0].x" not in names:
        raise ValueError("the FMU outputs no vertex positions (the scene turns them off): "
                         "no pictures or ParaView files")
    return np.stack([np.column_stack([res[f"vertex[{i}].{c}"] for c in "xyz"])
                     for i in range(n)], axis=1)


def crease_angles(res, sheet):
    """(rows, creases) fold angles in degrees, in the order of sheet.creases."""
    if not sheet.creases:
        return np.zeros((len(res), 0))
    return np.degrees(np.column_stack([res[f"crease[{f}].angle"] for f in sheet.creases]))


def face_values(sheet, angles):
    """(rows, faces): mean |fold angle| (deg) of the creases around each face."""
    col = {f: k for k, f in enumerate(sheet.creases)}
    out = np.zeros((angles.shape[0], len(sheet.faces)))
    for i, fc in enumerate(sheet.face_creases):
        if fc:
            out[:, i] = np.abs(angles[:, [col[f] for f in fc]]).mean(axis=1)
    return out


class _View:
    """One 3D axes showing the sheet; `show(k)` draws row k."""

    def __init__(self, ax, sheet, X, values, vmax, cmap):
        from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection
        import matplotlib.colors as mcolors

        self.sheet, self.X, self.values = sheet, X, values
        self.norm = mcolors.Normalize(0.0, vmax)
        self.cmap = cmap
        lo = X.reshape(-1, 3).min(axis=0)
        hi = X.reshape(-1, 3).max(axis=0)
        mid, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
        span = max(half.max(), 1e-12)
        half = np.maximum(half, 0.02 * span)  # a flat sheet still gets a z range
        ax.set_xlim(mid[0] - half[0], mid[0] + half[0])
        ax.set_ylim(mid[1] - half[1], mid[1] + half[1])
        ax.set_zlim(mid[2] - half[2], mid[2] + half[2])
        ax.set_box_aspect(tuple(half), zoom=1.05)  # equal scale on all axes
        ax.view_init(elev=28, azim=-60)
        ax.set_axis_off()
        self.polys = Poly3DCollection([X[0][f] for f in sheet.faces], linewidths=0.4)
        self.lines = Line3DCollection(X[0][sheet.edges], colors="0.15", linewidths=0.6)
        ax.add_collection3d(self.polys, autolim=False)
        ax.add_collection3d(self.lines, autolim=False)
        self.ax = ax

    def show(self, k):
        x = self.X[k]
        verts = [x[f] for f in self.sheet.faces]
        rgba = self.cmap(self.norm(self.values[k]))
        # Light shading by the facet normal so the 3D shape reads.
        light = np.array([-0.4, -0.5, 0.77])
        light /= np.linalg.norm(light)
        for i, v in enumerate(verts):
            nrm = np.cross(v[1] - v[0], v[2] - v[0])
            ln = np.linalg.norm(nrm)
            s = abs(nrm @ light) / ln if ln > 0 else 1.0
            rgba[i, :3] *= 0.55 + 0.45 * s
        self.polys.set_verts(verts)
        self.polys.set_facecolor(rgba)
        # Edges in the face colour close the hairline gaps between triangles.
        self.polys.set_edgecolor(rgba)
        self.lines.set_segments(x[self.sheet.edges])


def _color_limit(values):
    vmax = float(np.max(values)) if values.size else 0.0
    return vmax if vmax > 0 else 1.0


def _frame_rows(n_rows, max_frames):
    return np.unique(np.linspace(0, n_rows - 1, min(n_rows, max_frames)).round().astype(int))


def write_animation(path, sheet, times, X, angles, title="", max_frames=50, fps=12):
    """Animation of the fold: a GIF (Pillow) or, for a .mp4 path, an MP4
    (ffmpeg; raises RuntimeError when no encoder is available). Returns the
    number of frames written."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib import animation

    path = pathlib.Path(path)
    if path.suffix.lower() == ".mp4":
        if not animation.FFMpegWriter.isAvailable():
            raise RuntimeError("no MP4 encoder (ffmpeg) available")
        writer = animation.FFMpegWriter(fps=fps)
    else:
        writer = animation.PillowWriter(fps=fps)
    values = face_values(sheet, angles)
    rows = _frame_rows(len(times), max_frames)
    cmap = matplotlib.colormaps["viridis"]
    fig = plt.figure(figsize=(4.8, 4.2))
    ax = fig.add_axes([0.0, 0.0, 0.84, 0.92], projection="3d")
    view = _View(ax, sheet, X[rows], values[rows], _color_limit(values), cmap)
    _colorbar(fig, view, fig.add_axes([0.86, 0.15, 0.03, 0.6]))
    label = fig.text(0.02, 0.95, "", fontsize=9)

    def draw(k):
        view.show(k)
        label.set_text(f"{title}  t = {times[rows[k]]:.3f} s")

    anim = animation.FuncAnimation(fig, draw, frames=len(rows))
    anim.save(str(path), writer=writer, dpi=80)
    plt.close(fig)
    return len(rows)


def _colorbar(fig, view, cax):
    import matplotlib.cm as cm

    sm = cm.ScalarMappable(norm=view.norm, cmap=view.cmap)
    cb = fig.colorbar(sm, cax=cax)
    cb.set_label("mean |fold angle| of facet creases (deg)", fontsize=8)
    cb.ax.tick_params(labelsize=7)


def write_snapshots(path, sheet, times, X, angles, title="", n=6, cols=3, dpi=80):
    """A sheet of 3D views of the fold at `n` evenly spaced times (PNG)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    values = face_values(sheet, angles)
    rows = _frame_rows(len(times), n)
    nr = -(-len(rows) // cols)
    cmap = matplotlib.colormaps["viridis"]
    vmax = _color_limit(values)
    fig = plt.figure(figsize=(3.2 * cols + 0.8, 2.4 * nr + 0.4))
    views = []
    for j, k in enumerate(rows):
        r, c = divmod(j, cols)
        w, h = 0.9 / cols, 0.92 / nr
        ax = fig.add_axes([c * w, 0.92 - (r + 1) * h, w, h], projection="3d")
        # Every panel on the scale of the whole run, so sizes compare.
        view = _View(ax, sheet, X, values, vmax, cmap)
        view.show(k)
        ax.set_title(f"t = {times[k]:.3f} s", fontsize=9, y=0.92)
        views.append(view)
    fig.suptitle(title, fontsize=10, y=0.985)
    _colorbar(fig, views[0], fig.add_axes([0.92, 0.2, 0.015, 0.55]))
    fig.savefig(path, dpi=dpi)
    plt.close(fig)


def write_pvd(directory, stem, sheet, times, X, angles):
    """A ParaView series: DIRECTORY/STEM.pvd listing STEM_NNNNN.vtu, one per
    time, with the FOLD vertices, the drawn faces and the crease lines;
    cell data fold_angle_deg (lines), cell_kind (0 facet, 1 crease) and
    fold_edge; point data displacement and fold_vertex. Returns the .pvd path."""
    import meshio

    d = pathlib.Path(directory)
    d.mkdir(parents=True, exist_ok=True)
    by_size = {}
    for f in sheet.faces:
        by_size.setdefault(len(f), []).append(f)
    kinds = {3: "triangle", 4: "quad"}
    blocks = [(kinds.get(s, "polygon"), np.array(fs, dtype=int)) for s, fs in sorted(by_size.items())]
    col = {f: k for k, f in enumerate(sheet.creases)}
    crease_lines = [i for i, f in enumerate(sheet.edge_fold) if f in col]
    lines = sheet.edges[crease_lines]
    line_cols = [col[sheet.edge_fold[i]] for i in crease_lines]
    cells = blocks + ([("line", lines)] if len(lines) else [])
    nb = [len(b) for _, b in blocks]
    entries = []
    for k, t in enumerate(times):
        ang = [np.zeros(m) for m in nb] + ([angles[k, line_cols]] if len(lines) else [])
        kind = [np.zeros(m, dtype=np.uint8) for m in nb] + (
            [np.ones(len(lines), dtype=np.uint8)] if len(lines) else [])
        fe = [np.full(m, -1, dtype=np.int64) for m in nb] + (
            [sheet.edge_fold[crease_lines].astype(np.int64)] if len(lines) else [])
        mesh = meshio.Mesh(
            X[k], cells,
            point_data={"displacement": X[k] - sheet.reference,
                        "fold_vertex": np.arange(sheet.n_vertices, dtype=np.int64)},
            cell_data={"fold_angle_deg": ang, "cell_kind": kind, "fold_edge": fe})
        name = f"{stem}_{k:05d}.vtu"
        mesh.write(d / name, file_format="vtu")
        entries.append((float(t), name))
    pvd = d / f"{stem}.pvd"
    body = "".join(f'    <DataSet timestep="{t!r}" group="" part="0" file={quoteattr(n)}/>\n'
                   for t, n in entries)
    pvd.write_text('<?xml version="1.0"?>\n'
                   '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">\n'
                   f"  <Collection>\n{body}  </Collection>\n</VTKFile>\n")
    return pvd


def read_pvd(path):
    """(times, file paths) of a .pvd collection, in file order."""
    import xml.etree.ElementTree as ET

    path = pathlib.Path(path)
    root = ET.parse(path).getroot()
    sets = root.find("Collection").findall("DataSet")
    return ([float(s.get("timestep")) for s in sets], [path.parent / s.get("file") for s in sets])
