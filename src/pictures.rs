//! Pictures of a run, from the CLI alone (no Python): an animated GIF of
//! the folding sheet, a PNG sheet of 3D snapshots at evenly spaced times,
//! and a PNG plot of every fold angle and the energies against time.
//!
//! The sheet is drawn in 3D with one fixed view (elevation 28 deg, azimuth
//! -60 deg, orthographic) on one scale for the whole run (equal axes) as
//! the sampled surface that self-contact keeps apart ([`crate::sampled`]:
//! each facet's sub-triangles), back to front (painter's order), each
//! sub-triangle coloured by the mean |fold angle| of the creases around its
//! facet's face (facets joined across smooth edges, such as triangulation
//! diagonals, are one face) and lightly shaded by its own normal; creases
//! and the sheet's outline are drawn as lines along the facets' sampled
//! sides.
//! Drawing and encoding are plotters' (bitmap backend: PNG through `image`,
//! GIF through `gif`), text in the DejaVu Sans subset shipped in
//! `assets/fonts` (no system fonts needed).

use crate::mesh::EdgeKind;
use crate::model::Model;
use crate::sampled::SampledSheet;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::colors::colormaps::ViridisRGB;
use std::path::{Path, PathBuf};

/// The font of every label (a subset of DejaVu Sans, `assets/fonts`).
const FONT: &[u8] = include_bytes!("../assets/fonts/DejaVuSans-subset.ttf");
/// The family name the font is registered under.
const FAMILY: &str = "sans-serif";

/// Register [`FONT`] with plotters once.
fn register_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        // The font is ours and valid; a failure would only lose the labels.
        let _ = plotters::style::register_font(FAMILY, FontStyle::Normal, FONT);
    });
}

/// The sheet of a model as the pictures draw it.
#[derive(Clone, Debug)]
pub struct Sheet {
    /// The sampled surface: sub-triangles with their facet, and the points
    /// along each mesh edge.
    surface: SampledSheet,
    /// Line segments drawn over the sub-triangles (points), along the
    /// sampled sides of the creases and the outline.
    segments: Vec<[usize; 2]>,
    /// The sub-triangles of its line's facets that touch each segment (a
    /// segment is drawn right after them).
    segment_tris: Vec<Vec<usize>>,
    /// For each crease or outline line (mesh edge), its `crease[e].angle`
    /// output where it is a crease.
    line_output: Vec<Option<usize>>,
    /// The face (group of facets joined across smooth edges) of each facet.
    face: Vec<usize>,
    /// For each face, the lines (crease lines) around it.
    face_lines: Vec<Vec<usize>>,
    /// `crease[e].angle` outputs (index, FOLD edge), for the plot.
    angle_outputs: Vec<usize>,
    /// `energy.*` outputs (index, name), for the plot.
    energy_outputs: Vec<(usize, String)>,
}

/// The sheet at one time.
#[derive(Clone, Debug)]
pub struct Frame {
    /// Simulated time, s.
    pub time: f64,
    /// Position of every point of the sampled surface (the mesh vertices
    /// first), m.
    pub points: Vec<[f64; 3]>,
    /// Colour value of every face: mean |fold angle| of its creases, deg.
    pub face_values: Vec<f64>,
    /// Where a folding sequence is ("stage 2/5 (petals), 40 %"); None
    /// without one.
    pub stage: Option<String>,
}

/// Union-find root of `a`.
fn root(parent: &mut [usize], mut a: usize) -> usize {
    while parent[a] != a {
        parent[a] = parent[parent[a]];
        a = parent[a];
    }
    a
}

impl Sheet {
    /// The sheet of `model`'s mesh.
    pub fn new(model: &Model) -> Sheet {
        let mesh = &model.scene().mesh;
        let index: std::collections::HashMap<&str, usize> = model
            .outputs()
            .iter()
            .enumerate()
            .map(|(i, v)| (v.name.as_str(), i))
            .collect();
        let surface = SampledSheet::new(model);
        let nt = mesh.triangles().len();
        let mut parent: Vec<usize> = (0..nt).collect();
        let mut line_edges = Vec::new();
        let mut line_output = Vec::new();
        let mut line_faces = Vec::new();
        for (e, edge) in mesh.edges().iter().enumerate() {
            let facets = mesh.faces_of(crate::ids::EdgeId(e));
            match edge.kind {
                EdgeKind::Smooth => {
                    if let [a, b] = facets {
                        let (ra, rb) = (root(&mut parent, a.index()), root(&mut parent, b.index()));
                        parent[ra] = rb;
                    }
                }
                EdgeKind::Crease | EdgeKind::Boundary => {
                    let output = match (edge.kind, edge.fold_edge) {
                        (EdgeKind::Crease, Some(f)) => {
                            index.get(format!("crease[{f}].angle").as_str()).copied()
                        }
                        _ => None,
                    };
                    line_edges.push(e);
                    line_output.push(output);
                    line_faces.push(facets.iter().map(|f| f.index()).collect::<Vec<_>>());
                }
            }
        }
        // Each line's segments along its sampled side, with the
        // sub-triangles of the line's facets that touch the segment (drawn
        // before it: their outlines would cover its ends).
        let mut point_tris = vec![Vec::new(); surface.n_points()];
        for (k, (t, _)) in surface.triangles.iter().enumerate() {
            for &p in t {
                point_tris[p].push(k);
            }
        }
        let mut segments = Vec::new();
        let mut segment_tris = Vec::new();
        for (&e, facets) in line_edges.iter().zip(&line_faces) {
            for pair in surface.edges[e].windows(2) {
                let (a, b) = (pair[0], pair[1]);
                let mut touching = [&point_tris[a][..], &point_tris[b][..]].concat();
                touching.retain(|&k| facets.contains(&surface.triangles[k].1));
                touching.sort_unstable();
                touching.dedup();
                segments.push([a, b]);
                segment_tris.push(touching);
            }
        }
        let face: Vec<usize> = (0..nt).map(|t| root(&mut parent, t)).collect();
        let mut face_lines = vec![Vec::new(); nt];
        for (l, facets) in line_faces.iter().enumerate() {
            if line_output[l].is_some() {
                for &t in facets {
                    if !face_lines[face[t]].contains(&l) {
                        face_lines[face[t]].push(l);
                    }
                }
            }
        }
        let outputs = model.outputs();
        let angle_outputs = (0..outputs.len())
            .filter(|&i| {
                outputs[i].name.starts_with("crease[") && outputs[i].name.ends_with(".angle")
            })
            .collect();
        let energy_outputs = (0..outputs.len())
            .filter(|&i| outputs[i].name.starts_with("energy."))
            .map(|i| (i, outputs[i].name.clone()))
            .collect();
        Sheet {
            surface,
            segments,
            segment_tris,
            line_output,
            face,
            face_lines,
            angle_outputs,
            energy_outputs,
        }
    }

    /// The sheet of `model` now, with its output values `values`.
    pub fn frame(&self, model: &Model, values: &[f64]) -> Frame {
        let points = self.surface.points(model);
        let face_values = self
            .face_lines
            .iter()
            .map(|ls| {
                if ls.is_empty() {
                    return 0.0;
                }
                let sum: f64 = ls
                    .iter()
                    .map(|&l| self.line_output[l].map_or(0.0, |o| values[o].abs()))
                    .sum();
                (sum / ls.len() as f64).to_degrees()
            })
            .collect();
        let stage = model
            .scene()
            .sequence
            .as_ref()
            .zip(model.sequence_position())
            .map(|(sq, p)| sq.describe(p));
        Frame {
            time: model.time(),
            points,
            face_values,
            stage,
        }
    }
}

/// Which of `rows` output rows (0..rows) a picture of at most `max`
/// frames shows: evenly spaced, first and last included.
pub fn frame_rows(rows: usize, max: usize) -> Vec<usize> {
    if rows == 0 || max == 0 {
        return vec![];
    }
    if max == 1 || rows == 1 {
        return vec![rows - 1];
    }
    let n = max.min(rows);
    let mut out: Vec<usize> = (0..n)
        .map(|k| ((k as f64) * (rows - 1) as f64 / (n - 1) as f64).round() as usize)
        .collect();
    out.dedup();
    out
}

/// The view: orthographic, elevation 28 deg, azimuth -60 deg (z up).
struct View {
    right: [f64; 3],
    up: [f64; 3],
    toward: [f64; 3],
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

impl View {
    fn new() -> View {
        let (el, az) = (28f64.to_radians(), (-60f64).to_radians());
        let toward = [el.cos() * az.cos(), el.cos() * az.sin(), el.sin()];
        let right = [-az.sin(), az.cos(), 0.0];
        let up = cross(toward, right);
        View { right, up, toward }
    }

    /// Screen coordinates (right, up) and depth (larger: nearer).
    fn project(&self, p: [f64; 3]) -> (f64, f64, f64) {
        (dot(p, self.right), dot(p, self.up), dot(p, self.toward))
    }
}

/// Maps model coordinates into one panel, on a scale fitted to every frame.
struct Fit {
    view: View,
    center: (f64, f64),
    scale: f64,
    panel: (i32, i32),
}

impl Fit {
    /// Fit `frames` into a panel of `w` x `h` pixels with a margin.
    fn new(frames: &[&Frame], w: u32, h: u32) -> Fit {
        let view = View::new();
        let (mut lo, mut hi) = ((f64::MAX, f64::MAX), (f64::MIN, f64::MIN));
        for f in frames {
            for &p in &f.points {
                let (x, y, _) = view.project(p);
                lo = (lo.0.min(x), lo.1.min(y));
                hi = (hi.0.max(x), hi.1.max(y));
            }
        }
        let span = ((hi.0 - lo.0) / w as f64).max((hi.1 - lo.1) / h as f64);
        let scale = if span > 0.0 && span.is_finite() {
            0.9 / span
        } else {
            1.0
        };
        Fit {
            view,
            center: (0.5 * (lo.0 + hi.0), 0.5 * (lo.1 + hi.1)),
            scale,
            panel: (w as i32, h as i32),
        }
    }

    fn pixel(&self, p: [f64; 3]) -> (i32, i32) {
        let (x, y, _) = self.view.project(p);
        (
            self.panel.0 / 2 + ((x - self.center.0) * self.scale).round() as i32,
            self.panel.1 / 2 - ((y - self.center.1) * self.scale).round() as i32,
        )
    }
}

type Area<'a> = DrawingArea<BitMapBackend<'a>, Shift>;

/// The bitmap backend's error (plotters does not re-export its type).
pub type BackendError = <BitMapBackend<'static> as DrawingBackend>::ErrorType;

/// A drawing operation's error.
pub type DrawingError = DrawingAreaErrorKind<BackendError>;

/// Why a picture was not written.
#[derive(Debug)]
pub enum PictureError {
    /// Nothing to draw (`purpose`: "animate" or "draw").
    NoFrames(&'static str),
    /// A plot over time needs two output times at least.
    TooFewTimes,
    /// The file could not be created.
    Create {
        /// The file.
        path: PathBuf,
        /// The backend's error.
        source: BackendError,
    },
    /// Drawing into the picture failed.
    Drawing(DrawingError),
    /// The finished picture could not be written.
    Write {
        /// The file.
        path: PathBuf,
        /// The backend's error.
        source: DrawingError,
    },
}

impl std::fmt::Display for PictureError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            PictureError::NoFrames(purpose) => write!(f, "no frames to {purpose}"),
            PictureError::TooFewTimes => write!(f, "a plot needs at least two output times"),
            PictureError::Create { path, source } => {
                write!(f, "cannot write {}: {source}", path.display())
            }
            PictureError::Drawing(e) => write!(f, "drawing failed: {e}"),
            PictureError::Write { path, source } => {
                write!(f, "cannot write {}: {source}", path.display())
            }
        }
    }
}

impl std::error::Error for PictureError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            PictureError::Create { source, .. } => Some(source),
            PictureError::Drawing(e) | PictureError::Write { source: e, .. } => Some(e),
            PictureError::NoFrames(_) | PictureError::TooFewTimes => None,
        }
    }
}

/// The error of writing the finished picture to `path`.
fn write_err(path: &Path) -> impl FnOnce(DrawingError) -> PictureError {
    let path = path.to_path_buf();
    move |source| PictureError::Write { path, source }
}

/// Draw `frame` of `sheet` into `area` (pixel coordinates of the area).
fn draw_sheet(
    area: &Area,
    sheet: &Sheet,
    frame: &Frame,
    fit: &Fit,
    vmax: f64,
) -> Result<(), PictureError> {
    let light = {
        let l = [-0.4, -0.5, 0.77];
        let n = dot(l, l).sqrt();
        [l[0] / n, l[1] / n, l[2] / n]
    };
    // Sub-triangles and line segments in one painter's list: (depth, item);
    // a segment comes right after the nearest of its own sub-triangles, so
    // it shows on them and hides behind the surface in front of it.
    enum Item {
        Tri(usize),
        Segment(usize),
    }
    let depth = |p: [f64; 3]| fit.view.project(p).2;
    let x = &frame.points;
    let tris = &sheet.surface.triangles;
    let mut items: Vec<(f64, u8, Item)> = Vec::with_capacity(tris.len() + sheet.segments.len());
    let tri_depth: Vec<f64> = tris
        .iter()
        .map(|(tri, _)| tri.iter().map(|&v| depth(x[v])).sum::<f64>() / 3.0)
        .collect();
    for (k, &d) in tri_depth.iter().enumerate() {
        items.push((d, 0, Item::Tri(k)));
    }
    for (l, seg) in sheet.segments.iter().enumerate() {
        let d = sheet.segment_tris[l]
            .iter()
            .map(|&k| tri_depth[k])
            .fold(0.5 * (depth(x[seg[0]]) + depth(x[seg[1]])), f64::max);
        items.push((d, 1, Item::Segment(l)));
    }
    items.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    for (_, _, item) in &items {
        match *item {
            Item::Tri(k) => {
                let (tri, facet) = tris[k];
                let n = cross(sub(x[tri[1]], x[tri[0]]), sub(x[tri[2]], x[tri[0]]));
                let len = dot(n, n).sqrt();
                let shade = if len > 0.0 {
                    0.55 + 0.45 * (dot(n, light) / len).abs()
                } else {
                    1.0
                };
                let v = frame.face_values[sheet.face[facet]];
                let c = ViridisRGB::get_color_normalized(v, 0.0, vmax);
                let s = |k: u8| (k as f64 * shade).round() as u8;
                let color = RGBColor(s(c.0), s(c.1), s(c.2));
                let pts: Vec<(i32, i32)> = tri.iter().map(|&v| fit.pixel(x[v])).collect();
                area.draw(&Polygon::new(pts.clone(), color.filled()))
                    .map_err(PictureError::Drawing)?;
                // An outline in the sub-triangle's colour closes the
                // hairline gaps.
                let mut closed = pts;
                closed.push(closed[0]);
                area.draw(&PathElement::new(closed, color.stroke_width(1)))
                    .map_err(PictureError::Drawing)?;
            }
            Item::Segment(l) => {
                let [a, b] = sheet.segments[l];
                area.draw(&PathElement::new(
                    vec![fit.pixel(x[a]), fit.pixel(x[b])],
                    RGBColor(38, 38, 38).stroke_width(1),
                ))
                .map_err(PictureError::Drawing)?;
            }
        }
    }
    Ok(())
}

/// The largest colour value of `frames` (1 deg when nothing folds).
fn color_limit(frames: &[&Frame]) -> f64 {
    let m = frames
        .iter()
        .flat_map(|f| f.face_values.iter().copied())
        .fold(0.0, f64::max);
    if m > 0.0 { m } else { 1.0 }
}

/// A vertical colour bar for 0..`vmax` deg at (x, y), `h` pixels tall.
fn color_bar(area: &Area, (x, y): (i32, i32), h: i32, vmax: f64) -> Result<(), PictureError> {
    for k in 0..h {
        let v = vmax * (h - 1 - k) as f64 / (h - 1).max(1) as f64;
        let c = ViridisRGB::get_color_normalized(v, 0.0, vmax);
        area.draw(&Rectangle::new(
            [(x, y + k), (x + 12, y + k + 1)],
            RGBColor(c.0, c.1, c.2).filled(),
        ))
        .map_err(PictureError::Drawing)?;
    }
    let font = (FAMILY, 11).into_font();
    for (v, yy) in [(vmax, y), (0.5 * vmax, y + h / 2), (0.0, y + h)] {
        area.draw(&Text::new(
            format!("{v:.0}"),
            (x + 16, yy - 6),
            font.clone(),
        ))
        .map_err(PictureError::Drawing)?;
    }
    area.draw(&Text::new("deg", (x, y + h + 8), (FAMILY, 11).into_font()))
        .map_err(PictureError::Drawing)?;
    Ok(())
}

/// Write an animated GIF of `frames` (12 frames per second, then the last
/// frame held a second).
pub fn write_gif(
    path: &Path,
    sheet: &Sheet,
    frames: &[&Frame],
    title: &str,
) -> Result<(), PictureError> {
    register_font();
    if frames.is_empty() {
        return Err(PictureError::NoFrames("animate"));
    }
    let (w, h) = (480u32, 400u32);
    // A second line of text above the sheet for a sequence's stage.
    let top = if frames.iter().any(|f| f.stage.is_some()) {
        48
    } else {
        30
    };
    let fit = Fit::new(frames, w - 70, h - 10 - top as u32);
    let vmax = color_limit(frames);
    let backend = BitMapBackend::gif(path, (w, h), 83).map_err(|source| PictureError::Create {
        path: path.to_path_buf(),
        source,
    })?;
    let root = backend.into_drawing_area();
    let last = frames.len() - 1;
    for (k, f) in frames.iter().enumerate() {
        // The last frame repeats so that the folded state stays in view.
        let repeat = if k == last { 12 } else { 1 };
        for _ in 0..repeat {
            root.fill(&WHITE).map_err(PictureError::Drawing)?;
            let panel = root.margin(top, 10, 0, 70);
            draw_sheet(&panel, sheet, f, &fit, vmax)?;
            root.draw(&Text::new(
                format!("{title}   t = {:.3} s", f.time),
                (8, 8),
                (FAMILY, 14).into_font(),
            ))
            .map_err(PictureError::Drawing)?;
            if let Some(stage) = &f.stage {
                root.draw(&Text::new(stage.clone(), (8, 27), (FAMILY, 13).into_font()))
                    .map_err(PictureError::Drawing)?;
            }
            color_bar(&root, (w as i32 - 50, 80), 200, vmax)?;
            root.present().map_err(PictureError::Drawing)?;
        }
    }
    Ok(())
}

/// Write a PNG sheet of 3D views, one per frame, 3 to a row, on one scale.
pub fn write_snapshots(
    path: &Path,
    sheet: &Sheet,
    frames: &[&Frame],
    title: &str,
) -> Result<(), PictureError> {
    register_font();
    if frames.is_empty() {
        return Err(PictureError::NoFrames("draw"));
    }
    let cols = frames.len().min(3);
    let rows = frames.len().div_ceil(cols);
    let (pw, ph) = (320u32, 250u32);
    let (w, h) = (pw * cols as u32 + 70, ph * rows as u32 + 36);
    // A second label line in each panel for a sequence's stage.
    let top = if frames.iter().any(|f| f.stage.is_some()) {
        46
    } else {
        30
    };
    let fit = Fit::new(frames, pw - 10, ph - 4 - top as u32);
    let vmax = color_limit(frames);
    let root = BitMapBackend::new(path, (w, h)).into_drawing_area();
    root.fill(&WHITE).map_err(PictureError::Drawing)?;
    root.draw(&Text::new(
        title.to_string(),
        (10, 8),
        (FAMILY, 16).into_font(),
    ))
    .map_err(PictureError::Drawing)?;
    let grid = root.margin(36, 0, 0, 70);
    let panels = grid.split_evenly((rows, cols));
    for (f, panel) in frames.iter().zip(&panels) {
        panel
            .draw(&Text::new(
                format!("t = {:.3} s", f.time),
                (pw as i32 / 2 - 40, 2),
                (FAMILY, 13).into_font(),
            ))
            .map_err(PictureError::Drawing)?;
        if let Some(stage) = &f.stage {
            panel
                .draw(&Text::new(
                    stage.clone(),
                    (10, 18),
                    (FAMILY, 12).into_font(),
                ))
                .map_err(PictureError::Drawing)?;
        }
        let inner = panel.margin(top, 4, 5, 5);
        draw_sheet(&inner, sheet, f, &fit, vmax)?;
    }
    color_bar(&root, (w as i32 - 50, 60), (h as i32 - 130).max(60), vmax)?;
    root.present().map_err(write_err(path))?;
    Ok(())
}

/// The plotted series of a run: time, and per row the fold angles (deg)
/// and energies (J) of a [`Sheet`]'s outputs.
#[derive(Clone, Debug, Default)]
pub struct Series {
    time: Vec<f64>,
    angles: Vec<Vec<f64>>,
    energies: Vec<Vec<f64>>,
}

impl Series {
    /// Add the row of output `values` at time `t`.
    pub fn push(&mut self, sheet: &Sheet, t: f64, values: &[f64]) {
        self.time.push(t);
        self.angles.push(
            sheet
                .angle_outputs
                .iter()
                .map(|&i| values[i].to_degrees())
                .collect(),
        );
        self.energies.push(
            sheet
                .energy_outputs
                .iter()
                .map(|&(i, _)| values[i])
                .collect(),
        );
    }
}

/// Range of `values` with a margin (a flat series gets a unit range).
fn range(values: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(v), b.max(v)));
    if lo > hi {
        return 0.0..1.0;
    }
    let pad = if hi > lo {
        0.05 * (hi - lo)
    } else {
        lo.abs().max(1.0) * 0.05
    };
    (lo - pad)..(hi + pad)
}

/// Write a PNG plot: every fold angle (top) and the energies (bottom)
/// against time.
pub fn write_plot(
    path: &Path,
    sheet: &Sheet,
    series: &Series,
    title: &str,
) -> Result<(), PictureError> {
    register_font();
    let t = &series.time;
    if t.len() < 2 {
        return Err(PictureError::TooFewTimes);
    }
    let root = BitMapBackend::new(path, (880, 760)).into_drawing_area();
    root.fill(&WHITE).map_err(PictureError::Drawing)?;
    let (top, bottom) = root.split_vertically(380);
    let tr = t[0]..t[t.len() - 1];
    let mut chart = ChartBuilder::on(&top)
        .caption(format!("{title}: fold angles of all creases"), (FAMILY, 16))
        .margin(10)
        .x_label_area_size(30)
        .y_label_area_size(60)
        .build_cartesian_2d(tr.clone(), range(series.angles.iter().flatten().copied()))
        .map_err(PictureError::Drawing)?;
    chart
        .configure_mesh()
        .y_desc("fold angle (deg)")
        .label_style((FAMILY, 12))
        .axis_desc_style((FAMILY, 13))
        .draw()
        .map_err(PictureError::Drawing)?;
    let n = sheet.angle_outputs.len();
    for k in 0..n {
        let c = ViridisRGB::get_color_normalized(k as f64, 0.0, n.max(2) as f64 - 1.0);
        chart
            .draw_series(LineSeries::new(
                t.iter().zip(&series.angles).map(|(&x, a)| (x, a[k])),
                RGBColor(c.0, c.1, c.2).stroke_width(1),
            ))
            .map_err(PictureError::Drawing)?;
    }
    let mut chart = ChartBuilder::on(&bottom)
        .caption("energies", (FAMILY, 16))
        .margin(10)
        .x_label_area_size(36)
        .y_label_area_size(60)
        .build_cartesian_2d(tr, range(series.energies.iter().flatten().copied()))
        .map_err(PictureError::Drawing)?;
    chart
        .configure_mesh()
        .x_desc("time (s)")
        .y_desc("energy (J)")
        .y_label_formatter(&|v| format!("{v:.1e}"))
        .label_style((FAMILY, 12))
        .axis_desc_style((FAMILY, 13))
        .draw()
        .map_err(PictureError::Drawing)?;
    let palette = [
        RGBColor(31, 119, 180),
        RGBColor(255, 127, 14),
        RGBColor(44, 160, 44),
        RGBColor(214, 39, 40),
        RGBColor(148, 103, 189),
        RGBColor(140, 86, 75),
    ];
    for (k, (_, name)) in sheet.energy_outputs.iter().enumerate() {
        let color = palette[k % palette.len()];
        chart
            .draw_series(LineSeries::new(
                t.iter().zip(&series.energies).map(|(&x, e)| (x, e[k])),
                color.stroke_width(2),
            ))
            .map_err(PictureError::Drawing)?
            .label(name.clone())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
            });
    }
    if !sheet.energy_outputs.is_empty() {
        chart
            .configure_series_labels()
            .label_font((FAMILY, 12))
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .map_err(PictureError::Drawing)?;
    }
    root.present().map_err(write_err(path))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_rows_are_even_and_include_both_ends() {
        assert_eq!(frame_rows(101, 6), vec![0, 20, 40, 60, 80, 100]);
        assert_eq!(frame_rows(3, 6), vec![0, 1, 2]);
        assert_eq!(frame_rows(5, 1), vec![4]);
        assert!(frame_rows(0, 6).is_empty());
    }
}
