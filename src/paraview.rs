//! ParaView time series of a model run: one VTK XML UnstructuredGrid file
//! (`.vtu`, ASCII) per output time and a `.pvd` collection that lists them
//! with their times, so ParaView opens the whole run as one animated dataset.
//!
//! Each `.vtu` holds the sampled surface that self-contact keeps apart
//! ([`crate::sampled`]; without contact, the curved facets sampled at the
//! default subdivisions): its points at their current positions (the mesh
//! vertices first, FOLD vertices before those added by refinement, then
//! the other samples), each facet's sub-triangles as VTK triangles, and
//! every crease edge of the mesh as VTK lines along its sampled side. Cell
//! data: `cell_kind` (0 facet, 1 crease line), `facet` (the mesh triangle
//! of a sub-triangle, -1 on lines), `fold_edge` (the FOLD edge of a crease
//! line, -1 on facets), `strain_energy` (J: the facet's, shared evenly by
//! its sub-triangles, which have equal reference areas) and
//! `strain_energy_density` (J/m^2 of reference area) on facets and
//! `fold_angle_deg` (valley positive; the `crease[e].angle` outputs, 0 when
//! the scene outputs no fold angles) on crease lines, 0 on the other kind.
//! Point data: `fold_vertex` (FOLD index, -1 for refined vertices and the
//! other samples) and `displacement` from the flat reference state (m).
//!
//! The format is small enough to write directly; the writer is tested by
//! reading files back (tests/paraview.rs and the fmpy suite with meshio).

use crate::ids::FacetId;
use crate::mesh::EdgeKind;
use crate::model::Model;
use crate::sampled::SampledSheet;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// VTK cell type of a triangle.
const VTK_TRIANGLE: u8 = 5;
/// VTK cell type of a line.
const VTK_LINE: u8 = 3;

#[doc(hidden)]
/// One frame of the series: the mesh at one time and its fields.
pub struct Frame<'a> {
    /// Current vertex positions (m).
    pub points: &'a [[f64; 3]],
    /// Reference (flat) vertex positions (m), for `displacement`.
    pub reference: &'a [[f64; 3]],
    /// FOLD vertex count: points `0..n` are FOLD vertices.
    pub fold_vertex_count: usize,
    /// Triangles (vertex indices).
    pub triangles: &'a [[usize; 3]],
    /// The facet (mesh triangle) of each triangle.
    pub facets: &'a [usize],
    /// Strain energy of each triangle (J).
    pub facet_energy: &'a [f64],
    /// Reference area of each triangle (m^2).
    pub facet_area: &'a [f64],
    /// Crease lines: end vertices and FOLD edge index.
    pub lines: &'a [([usize; 2], usize)],
    /// Fold angle of each line (rad, valley positive).
    pub line_angle: &'a [f64],
}

/// Append a `<DataArray>` of `values` (`ncomp` components) to `s`.
fn data_array<T: std::fmt::Display>(
    s: &mut String,
    ty: &str,
    name: &str,
    ncomp: usize,
    values: impl Iterator<Item = T>,
) {
    let name_attr = if name.is_empty() {
        String::new()
    } else {
        format!(" Name=\"{name}\"")
    };
    let _ = writeln!(
        s,
        "        <DataArray type=\"{ty}\"{name_attr} NumberOfComponents=\"{ncomp}\" format=\"ascii\">"
    );
    s.push_str("         ");
    for v in values {
        let _ = write!(s, " {v}");
    }
    s.push_str("\n        </DataArray>\n");
}

/// Shortest round-trip text of a float in exponent form (`1.5e-3`): plain
/// `{}` would spell 1e-300 with 300 digits.
#[derive(Clone, Copy)]
struct Exp(f64);
impl std::fmt::Display for Exp {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:e}", self.0)
    }
}

#[doc(hidden)]
/// The text of one `.vtu` file. Fails when the frame's arrays disagree in
/// length or hold a non-finite value (VTK's ASCII reader cannot read NaN).
pub fn vtu_text(fr: &Frame) -> Result<String, FrameError> {
    check_frame(fr)?;
    let (np, nt, nl) = (fr.points.len(), fr.triangles.len(), fr.lines.len());
    let mut s = String::with_capacity(64 * (np + nt + nl) + 1024);
    s.push_str("<?xml version=\"1.0\"?>\n");
    s.push_str(
        "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n",
    );
    s.push_str("  <UnstructuredGrid>\n");
    let _ = writeln!(
        s,
        "    <Piece NumberOfPoints=\"{np}\" NumberOfCells=\"{}\">",
        nt + nl
    );
    point_data(&mut s, fr);
    cell_data(&mut s, fr);
    points_and_cells(&mut s, fr);
    s.push_str("    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n");
    Ok(s)
}

/// Why a [`Frame`] cannot be written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameError {
    /// The arrays' lengths do not match the mesh.
    Lengths,
    /// A position, energy or angle is not finite.
    NonFinite,
    /// A cell names a vertex beyond the points.
    VertexOutOfRange {
        /// The vertex.
        vertex: usize,
        /// Points of the frame.
        points: usize,
    },
}

impl std::fmt::Display for FrameError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            FrameError::Lengths => write!(f, "ParaView frame: array lengths do not match the mesh"),
            FrameError::NonFinite => {
                write!(f, "ParaView frame: non-finite position, energy or angle")
            }
            FrameError::VertexOutOfRange { vertex, points } => write!(
                f,
                "ParaView frame: vertex {vertex} out of range ({points} points)"
            ),
        }
    }
}

impl std::error::Error for FrameError {}

/// The frame's arrays agree in length, hold finite values and index its points.
fn check_frame(fr: &Frame) -> Result<(), FrameError> {
    let np = fr.points.len();
    let nt = fr.triangles.len();
    let nl = fr.lines.len();
    if fr.reference.len() != np
        || fr.facet_energy.len() != nt
        || fr.facets.len() != nt
        || fr.facet_area.len() != nt
        || fr.line_angle.len() != nl
        || fr.fold_vertex_count > np
    {
        return Err(FrameError::Lengths);
    }
    let finite = fr.points.iter().flatten().all(|x| x.is_finite())
        && fr.facet_energy.iter().all(|x| x.is_finite())
        && fr.line_angle.iter().all(|x| x.is_finite());
    if !finite {
        return Err(FrameError::NonFinite);
    }
    if let Some(v) = fr
        .triangles
        .iter()
        .flatten()
        .chain(fr.lines.iter().flat_map(|(l, _)| l))
        .find(|&&v| v >= np)
    {
        return Err(FrameError::VertexOutOfRange {
            vertex: *v,
            points: np,
        });
    }
    Ok(())
}

/// The points' data: FOLD vertex index, displacement.
fn point_data(s: &mut String, fr: &Frame) {
    let np = fr.points.len();
    s.push_str("      <PointData>\n");
    data_array(
        s,
        "Int64",
        "fold_vertex",
        1,
        (0..np).map(|v| {
            if v < fr.fold_vertex_count {
                v as i64
            } else {
                -1
            }
        }),
    );
    data_array(
        s,
        "Float64",
        "displacement",
        3,
        fr.points
            .iter()
            .zip(fr.reference)
            .flat_map(|(p, r)| (0..3).map(move |c| Exp(p[c] - r[c]))),
    );
    s.push_str("      </PointData>\n");
}

/// The cells' data: kind, FOLD edge, strain energy and its density, fold angle.
fn cell_data(s: &mut String, fr: &Frame) {
    let (nt, nl) = (fr.triangles.len(), fr.lines.len());
    s.push_str("      <CellData>\n");
    let kinds = || std::iter::repeat_n(0u8, nt).chain(std::iter::repeat_n(1u8, nl));
    data_array(s, "UInt8", "cell_kind", 1, kinds());
    data_array(
        s,
        "Int64",
        "facet",
        1,
        fr.facets
            .iter()
            .map(|&f| f as i64)
            .chain(std::iter::repeat_n(-1i64, nl)),
    );
    data_array(
        s,
        "Int64",
        "fold_edge",
        1,
        std::iter::repeat_n(-1i64, nt).chain(fr.lines.iter().map(|&(_, e)| e as i64)),
    );
    data_array(
        s,
        "Float64",
        "strain_energy",
        1,
        fr.facet_energy
            .iter()
            .map(|&x| Exp(x))
            .chain(std::iter::repeat_n(Exp(0.0), nl)),
    );
    data_array(
        s,
        "Float64",
        "strain_energy_density",
        1,
        fr.facet_energy
            .iter()
            .zip(fr.facet_area)
            .map(|(&e, &a)| Exp(if a > 0.0 { e / a } else { 0.0 }))
            .chain(std::iter::repeat_n(Exp(0.0), nl)),
    );
    data_array(
        s,
        "Float64",
        "fold_angle_deg",
        1,
        std::iter::repeat_n(Exp(0.0), nt).chain(fr.line_angle.iter().map(|a| Exp(a.to_degrees()))),
    );
    s.push_str("      </CellData>\n");
}

/// The points and the cells: triangles, then crease lines.
fn points_and_cells(s: &mut String, fr: &Frame) {
    let (nt, nl) = (fr.triangles.len(), fr.lines.len());
    s.push_str("      <Points>\n");
    data_array(
        s,
        "Float64",
        "",
        3,
        fr.points.iter().flatten().map(|&x| Exp(x)),
    );
    s.push_str("      </Points>\n      <Cells>\n");
    data_array(
        s,
        "Int64",
        "connectivity",
        1,
        fr.triangles
            .iter()
            .flatten()
            .chain(fr.lines.iter().flat_map(|(l, _)| l)),
    );
    data_array(
        s,
        "Int64",
        "offsets",
        1,
        (1..=nt)
            .map(|k| 3 * k)
            .chain((1..=nl).map(|k| 3 * nt + 2 * k)),
    );
    data_array(
        s,
        "UInt8",
        "types",
        1,
        std::iter::repeat_n(VTK_TRIANGLE, nt).chain(std::iter::repeat_n(VTK_LINE, nl)),
    );
    s.push_str("      </Cells>\n");
}

/// Escape the characters XML does not allow in an attribute value.
fn xml_attr(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('"', "&quot;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

#[doc(hidden)]
/// The text of a `.pvd` collection: one `DataSet` per (time, file name
/// relative to the `.pvd`).
pub fn pvd_text(entries: &[(f64, String)]) -> String {
    let mut s = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n",
    );
    for (t, file) in entries {
        let _ = writeln!(
            s,
            "    <DataSet timestep=\"{}\" group=\"\" part=\"0\" file=\"{}\"/>",
            Exp(*t),
            xml_attr(file)
        );
    }
    s.push_str("  </Collection>\n</VTKFile>\n");
    s
}

/// A series being written: `DIR/STEM.pvd` and `DIR/STEM_00000.vtu`, ... .
pub struct Series {
    dir: PathBuf,
    stem: String,
    entries: Vec<(f64, String)>,
    /// The sampled surface drawn.
    surface: SampledSheet,
    reference: Vec<[f64; 3]>,
    /// Reference area of each sub-triangle.
    areas: Vec<f64>,
    /// The sub-triangles (points) and their facets.
    triangles: Vec<[usize; 3]>,
    facets: Vec<usize>,
    /// Crease lines along the sampled sides, with their FOLD edge.
    lines: Vec<([usize; 2], usize)>,
    /// For each line, the index of its `crease[e].angle` output (None when
    /// the scene does not output fold angles).
    line_output: Vec<Option<usize>>,
}

/// Why a [`Series`] could not be written.
#[derive(Debug)]
pub enum SeriesError {
    /// A directory could not be created or a file not be written.
    Io {
        /// What was being done ("create" or "write").
        action: &'static str,
        /// Where.
        path: PathBuf,
        /// The system's error.
        source: std::io::Error,
    },
    /// The frame's arrays do not fit the mesh.
    Frame(FrameError),
}

impl std::fmt::Display for SeriesError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SeriesError::Io {
                action,
                path,
                source,
            } => write!(f, "cannot {action} {}: {source}", path.display()),
            SeriesError::Frame(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for SeriesError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            SeriesError::Io { source, .. } => Some(source),
            SeriesError::Frame(e) => Some(e),
        }
    }
}

/// The I/O error of `action` on `path`.
fn io_error(action: &'static str, path: &Path) -> impl FnOnce(std::io::Error) -> SeriesError {
    let path = path.to_path_buf();
    move |source| SeriesError::Io {
        action,
        path,
        source,
    }
}

impl Series {
    /// Start a series of `model`'s mesh in `dir` (created if missing).
    pub fn new(dir: &Path, stem: &str, model: &Model) -> Result<Series, SeriesError> {
        std::fs::create_dir_all(dir).map_err(io_error("create", dir))?;
        let mesh = &model.scene().mesh;
        let surface = SampledSheet::new(model);
        // Sub-triangles of a facet's lattice have equal reference areas.
        let share = 1.0 / (surface.subdivisions() * surface.subdivisions()) as f64;
        let areas = surface
            .triangles
            .iter()
            .map(|&(_, f)| share * mesh.area(FacetId(f)))
            .collect();
        let (triangles, facets) = surface.triangles.iter().copied().unzip();
        let outputs: std::collections::HashMap<&str, usize> = model
            .outputs()
            .iter()
            .enumerate()
            .map(|(i, v)| (v.name.as_str(), i))
            .collect();
        let mut lines = Vec::new();
        let mut line_output = Vec::new();
        for (e, edge) in mesh.edges().iter().enumerate() {
            if let (EdgeKind::Crease, Some(f)) = (edge.kind, edge.fold_edge) {
                let output = outputs.get(format!("crease[{f}].angle").as_str()).copied();
                for pair in surface.edges[e].windows(2) {
                    lines.push(([pair[0], pair[1]], f.index()));
                    line_output.push(output);
                }
            }
        }
        Ok(Series {
            dir: dir.to_path_buf(),
            stem: stem.to_string(),
            entries: Vec::new(),
            reference: surface.reference(),
            surface,
            areas,
            triangles,
            facets,
            lines,
            line_output,
        })
    }

    /// Write the model's current state as the next frame at its time.
    pub fn write(&mut self, model: &Model) -> Result<(), SeriesError> {
        let points = self.surface.points(model);
        let facet_energy = model.facet_strain_energies();
        let share = 1.0 / (self.surface.subdivisions() * self.surface.subdivisions()) as f64;
        let energy: Vec<f64> = self
            .facets
            .iter()
            .map(|&f| share * facet_energy[f])
            .collect();
        let values = model.output_values();
        let angles: Vec<f64> = self
            .line_output
            .iter()
            .map(|o| o.map(|i| values[i]).unwrap_or(0.0))
            .collect();
        let text = vtu_text(&Frame {
            points: &points,
            reference: &self.reference,
            fold_vertex_count: model.scene().fold_vertex_count,
            triangles: &self.triangles,
            facets: &self.facets,
            facet_energy: &energy,
            facet_area: &self.areas,
            lines: &self.lines,
            line_angle: &angles,
        })
        .map_err(SeriesError::Frame)?;
        let name = format!("{}_{:05}.vtu", self.stem, self.entries.len());
        let path = self.dir.join(&name);
        std::fs::write(&path, text).map_err(io_error("write", &path))?;
        self.entries.push((model.time(), name));
        Ok(())
    }

    /// Write the `.pvd` collection of the frames so far; returns its path.
    pub fn finish(&self) -> Result<PathBuf, SeriesError> {
        let path = self.dir.join(format!("{}.pvd", self.stem));
        std::fs::write(&path, pvd_text(&self.entries)).map_err(io_error("write", &path))?;
        Ok(path)
    }
}
