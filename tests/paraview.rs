//! The ParaView writer: a written frame reads back with the points, cells
//! and fields that went in; a series of a folding model lists every output
//! time, draws the sampled surface (the mesh vertices first), and its
//! per-sub-triangle strain energies add up to the model's `energy.strain`
//! output and its line angles equal the `crease[e].angle` outputs.

use origami_fmu::ids::VertexId;
use origami_fmu::mesh::builders::grid;
use origami_fmu::model::Model;
use origami_fmu::paraview::{Frame, Series, pvd_text, vtu_text};
use origami_fmu::scene::{Fix, Scene, Support};

/// The whitespace-separated values of the `DataArray` named `name` (the
/// unnamed one is the points array: pass "").
fn array(xml: &str, name: &str) -> Vec<f64> {
    let key = if name.is_empty() {
        "<Points>".to_string()
    } else {
        format!("Name=\"{name}\"")
    };
    let at = xml.find(&key).unwrap_or_else(|| panic!("no array {name}"));
    let open = at + xml[at..].find('>').unwrap() + 1;
    let open = if name.is_empty() {
        open + xml[open..].find('>').unwrap() + 1
    } else {
        open
    };
    let close = open + xml[open..].find("</DataArray>").unwrap();
    xml[open..close]
        .split_whitespace()
        .map(|w| w.parse::<f64>().unwrap())
        .collect()
}

fn attr(xml: &str, name: &str) -> String {
    let key = format!("{name}=\"");
    let at = xml.find(&key).unwrap() + key.len();
    xml[at..at + xml[at..].find('"').unwrap()].to_string()
}

#[test]
fn a_frame_reads_back() {
    let points = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 1e-300],
        [0.0, 1.0, -2.5],
    ];
    let reference = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ];
    let fr = Frame {
        points: &points,
        reference: &reference,
        fold_vertex_count: 3,
        triangles: &[[0, 1, 2], [0, 2, 3]],
        facets: &[0, 1],
        facet_energy: &[1.5e-7, 2.0],
        facet_area: &[0.5, 0.5],
        lines: &[([0, 2], 4)],
        line_angle: &[std::f64::consts::FRAC_PI_2],
    };
    let xml = vtu_text(&fr).unwrap();
    assert_eq!(attr(&xml, "NumberOfPoints"), "4");
    assert_eq!(attr(&xml, "NumberOfCells"), "3");
    let flat: Vec<f64> = points.iter().flatten().copied().collect();
    assert_eq!(array(&xml, ""), flat);
    assert_eq!(
        array(&xml, "connectivity"),
        [0., 1., 2., 0., 2., 3., 0., 2.]
    );
    assert_eq!(array(&xml, "offsets"), [3., 6., 8.]);
    assert_eq!(array(&xml, "types"), [5., 5., 3.]);
    assert_eq!(array(&xml, "cell_kind"), [0., 0., 1.]);
    assert_eq!(array(&xml, "facet"), [0., 1., -1.]);
    assert_eq!(array(&xml, "fold_edge"), [-1., -1., 4.]);
    assert_eq!(array(&xml, "strain_energy"), [1.5e-7, 2.0, 0.0]);
    assert_eq!(array(&xml, "strain_energy_density"), [3e-7, 4.0, 0.0]);
    assert_eq!(array(&xml, "fold_angle_deg"), [0.0, 0.0, 90.0]);
    assert_eq!(array(&xml, "fold_vertex"), [0., 1., 2., -1.]);
    let d = array(&xml, "displacement");
    assert_eq!(d[8], 1e-300);
    assert_eq!(d[11], -2.5);
}

#[test]
fn bad_frames_are_refused_with_a_message() {
    let points = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [f64::NAN, 1.0, 0.0]];
    let ok = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]];
    let mk = |p: &'static [[f64; 3]], tri: &'static [[usize; 3]], e: &'static [f64]| Frame {
        points: p,
        reference: &[[0.0; 3]; 3],
        fold_vertex_count: 3,
        triangles: tri,
        facets: &[0],
        facet_energy: e,
        facet_area: &[0.5],
        lines: &[],
        line_angle: &[],
    };
    let pts: &'static [[f64; 3]] = Box::leak(Box::new(points));
    let good: &'static [[f64; 3]] = Box::leak(Box::new(ok));
    let err = vtu_text(&mk(pts, &[[0, 1, 2]], &[0.0]))
        .err()
        .unwrap()
        .to_string();
    assert!(err.contains("non-finite"), "{err}");
    let err = vtu_text(&mk(good, &[[0, 1, 2]], &[]))
        .err()
        .unwrap()
        .to_string();
    assert!(err.contains("lengths"), "{err}");
    let err = vtu_text(&mk(good, &[[0, 1, 7]], &[0.0]))
        .err()
        .unwrap()
        .to_string();
    assert!(err.contains("vertex 7"), "{err}");
}

#[test]
fn pvd_lists_times_and_files() {
    let text = pvd_text(&[(0.0, "a_00000.vtu".into()), (0.25, "a&b.vtu".into())]);
    let steps: Vec<f64> = text
        .match_indices("timestep=\"")
        .map(|(i, k)| {
            let s = &text[i + k.len()..];
            s[..s.find('"').unwrap()].parse().unwrap()
        })
        .collect();
    assert_eq!(steps, [0.0, 0.25]);
    assert!(text.contains("file=\"a&amp;b.vtu\""));
    assert!(text.contains("type=\"Collection\""));
}

#[test]
fn a_folding_series_has_every_time_and_consistent_fields() {
    // Two 20 mm panels, crease along x = 20 mm folding to 90 deg, refined
    // once (so the mesh has more vertices than the FOLD file), left edge clamped.
    let mesh = grid(0.04, 0.02, 2, 1, &[(1, std::f64::consts::FRAC_PI_2)]);
    let mut scene = Scene::with_defaults("two_panels", mesh);
    scene.supports.push(Support {
        vertices: vec![VertexId(0), VertexId(3)],
        fix: Fix::Clamped,
    });
    let scene = origami_fmu::scene::refine::refine(&scene, 1).unwrap();
    let mut m = Model::new(scene).unwrap();
    m.initialize().unwrap();
    let dir = std::env::temp_dir().join(format!("origami_pvd_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let mut series = Series::new(&dir, "two", &m).unwrap();
    series.write(&m).unwrap();
    let fold = m.input_id("fold").unwrap();
    let strain = m
        .outputs()
        .iter()
        .position(|v| v.name == "energy.strain")
        .unwrap();
    let crease = m
        .outputs()
        .iter()
        .position(|v| v.name.starts_with("crease["))
        .unwrap();
    for k in 1..=12 {
        m.set_input(fold, (k as f64 / 10.0).min(1.0)).unwrap();
        m.advance(0.01).unwrap();
        series.write(&m).unwrap();
    }
    let pvd = std::fs::read_to_string(series.finish().unwrap()).unwrap();
    let entries: Vec<(f64, String)> = pvd
        .lines()
        .filter(|l| l.contains("<DataSet"))
        .map(|l| (attr(l, "timestep").parse().unwrap(), attr(l, "file")))
        .collect();
    assert_eq!(entries.len(), 13);
    let mesh = &m.scene().mesh;
    let n_vertices = mesh.n_vertices();
    assert!(n_vertices > m.scene().fold_vertex_count);
    // The sampled surface (no contact: the default 3 subdivisions per
    // side): the mesh vertices, n - 1 samples inside each edge and
    // (n - 1)(n - 2) / 2 inside each facet; n^2 sub-triangles a facet.
    let n = m.surface_subdivisions();
    assert_eq!(n, 3);
    let (n_edges, n_facets) = (mesh.edges().len(), mesh.triangles().len());
    let n_points = n_vertices + n_edges * (n - 1) + n_facets * (n - 1) * (n - 2) / 2;
    for (k, (t, file)) in entries.iter().enumerate() {
        assert!((t - 0.01 * k as f64).abs() < 1e-12, "time {t} of frame {k}");
        let xml = std::fs::read_to_string(dir.join(file)).unwrap();
        assert_eq!(attr(&xml, "NumberOfPoints"), n_points.to_string());
    }
    // The last frame against the model now.
    let xml = std::fs::read_to_string(dir.join(&entries[12].1)).unwrap();
    let energy: f64 = array(&xml, "strain_energy").iter().sum();
    let total = m.output_values()[strain];
    assert!(total > 0.0);
    assert!(
        (energy - total).abs() <= 1e-12 * total,
        "facets {energy} J, model {total} J"
    );
    let kinds = array(&xml, "cell_kind");
    let angles = array(&xml, "fold_angle_deg");
    let line_angles: Vec<f64> = kinds
        .iter()
        .zip(&angles)
        .filter(|(k, _)| **k == 1.0)
        .map(|(_, a)| *a)
        .collect();
    // The crease was split in two by the refinement, each half drawn along
    // its n samples: 2 n lines, one FOLD edge.
    assert_eq!(line_angles.len(), 2 * n);
    // Each facet's n^2 sub-triangles name it.
    let facets = array(&xml, "facet");
    for f in 0..n_facets {
        let count = facets.iter().filter(|&&g| g == f as f64).count();
        assert_eq!(count, n * n, "sub-triangles of facet {f}");
    }
    assert_eq!(facets.len(), n_facets * n * n + 2 * n);
    // The FOLD vertices first, then the refined vertices and the samples.
    let fold_vertex = array(&xml, "fold_vertex");
    let fold_count = m.scene().fold_vertex_count;
    for (p, &v) in fold_vertex.iter().enumerate() {
        let want = if p < fold_count { p as f64 } else { -1.0 };
        assert_eq!(v, want, "fold_vertex of point {p}");
    }
    let want = m.output_values()[crease].to_degrees();
    assert!(want > 10.0, "folded {want} deg");
    for a in line_angles {
        assert!((a - want).abs() < 1e-9 * want.abs(), "{a} vs {want}");
    }
    let pts = array(&xml, "");
    for v in 0..n_vertices {
        let p = m.vertex_position(VertexId(v));
        for c in 0..3 {
            assert!((pts[3 * v + c] - p[c]).abs() <= 1e-15 * (1.0 + p[c].abs()));
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
