//! Assembled patch tests of the shell element on arbitrary meshes (issue:
//! an element that converges on any triangulation). A field the element
//! must represent exactly, imposed on every slot, is a discrete equilibrium
//! of the linearized problem at the flat reference: the tangent's product with
//! it vanishes at every DOF of every interior vertex (loads act only at the
//! boundary), and its energy `u^T K u / 2` is the exact one.
//!
//! - bending: `w = (k11 x^2 + 2 k12 xy + k22 y^2) / 2` (constant curvature and
//!   twist), energy `area (h^3/24) kappa^T C kappa`;
//! - membrane: a constant in-plane strain `u = A x`, energy `area (h/2) eps^T C eps`.
//!
//! Meshes on the unit square: same diagonal, union-jack, random diagonals,
//! random diagonals with perturbed vertices, and a two-ring fan of 7
//! irregular sectors around a centre vertex. BCIZ functions pass on the
//! three-direction mesh only (checked, so the test is known to discriminate).
//! Both bending energies of Specht's functions (pointwise and split) pass.
//! Round-off: interior residuals below 1e-10 of the largest (measured up to
//! 1.4e-11, on the fan), energies within 1e-11.

use nalgebra::{Matrix3, Matrix3x2, Vector2, Vector3};
use origami_fmu::assembly::Assembler;
use origami_fmu::benchmarks::{MeshFamily, plate_physics, reference_stiffness};
use origami_fmu::element::{Bending, ElementOptions, Interpolation};
use origami_fmu::ids::{FacetId, VertexId, vertex_ids};
use origami_fmu::mesh::Mesh;

/// A two-ring fan: centre, an inner ring of 7 vertices at irregular angles
/// and radii, an outer ring on the boundary of the unit square.
fn fan() -> Mesh {
    let n = 7;
    let angles = [0.0, 0.8, 1.9, 2.6, 3.5, 4.4, 5.3];
    let radii = [0.21, 0.3, 0.18, 0.27, 0.24, 0.33, 0.2];
    let c = Vector2::new(0.5, 0.5);
    let mut coords = vec![Vector2::new(0.52, 0.47)];
    for k in 0..n {
        coords.push(c + radii[k] * Vector2::new(f64::cos(angles[k]), f64::sin(angles[k])));
    }
    for &a in &angles {
        // Project the direction onto the square's boundary.
        let d = Vector2::new(f64::cos(a + 0.1), f64::sin(a + 0.1));
        let t = 0.5 / d.x.abs().max(d.y.abs());
        coords.push(c + t * d);
    }
    let mut tris = Vec::new();
    for k in 0..n {
        let (i, j) = (1 + k, 1 + (k + 1) % n);
        let (o, p) = (1 + n + k, 1 + n + (k + 1) % n);
        tris.push(vertex_ids([0, i, j]));
        tris.push(vertex_ids([i, o, p]));
        tris.push(vertex_ids([i, p, j]));
    }
    Mesh::new(coords, tris, vec![]).expect("valid fan")
}

/// The test meshes: (name, mesh).
fn meshes() -> Vec<(&'static str, Mesh)> {
    let mut out: Vec<(&'static str, Mesh)> = MeshFamily::ALL
        .iter()
        .map(|f| (f.name(), f.grid(1.0, 1.0, 5, 4)))
        .collect();
    out.push(("fan", fan()));
    out
}

/// Largest |K u| over the DOFs of interior vertices, relative to the
/// largest |K u| anywhere, and the energy `u^T K u / 2`.
fn residual_and_energy(
    mesh: &Mesh,
    element: impl Into<ElementOptions>,
    u: &[f64],
    h: f64,
) -> (f64, f64) {
    let element = element.into();
    let asm = Assembler::new(mesh, plate_physics(2.5, 0.3, h), element, &[]).unwrap();
    let vals = reference_stiffness(&asm, mesh).unwrap();
    // No slot is fixed: free index == DOF index.
    let mut ku = vec![0.0; u.len()];
    for (col, x) in u.iter().enumerate() {
        for p in asm.col_ptr[col]..asm.col_ptr[col + 1] {
            ku[asm.row_idx[p]] += vals[p] * x;
        }
    }
    let energy = 0.5 * u.iter().zip(&ku).map(|(a, b)| a * b).sum::<f64>();
    let interior = |v: VertexId| {
        let x = mesh.coord(v);
        let e = 1e-12;
        x.x > e && x.y > e && x.x < 1.0 - e && x.y < 1.0 - e
    };
    let mut worst_interior: f64 = 0.0;
    let mut worst: f64 = 0.0;
    for (i, r) in ku.iter().enumerate() {
        worst = worst.max(r.abs());
        if interior(asm.layout.slot_vertex[i / 3]) {
            worst_interior = worst_interior.max(r.abs());
        }
    }
    (worst_interior / worst, energy)
}

/// Specht's functions with both bending energies.
fn specht_elements() -> [ElementOptions; 2] {
    [Bending::Pointwise, Bending::Split].map(|bending| ElementOptions {
        bending,
        ..ElementOptions::from(Interpolation::Specht)
    })
}

fn plane_c(nu: f64) -> Matrix3<f64> {
    let c = 2.5 / (1.0 - nu * nu);
    Matrix3::new(
        c,
        c * nu,
        0.0,
        c * nu,
        c,
        0.0,
        0.0,
        0.0,
        c * (1.0 - nu) / 2.0,
    )
}

fn area(mesh: &Mesh) -> f64 {
    (0..mesh.triangles().len())
        .map(|t| mesh.area(FacetId(t)))
        .sum()
}

#[test]
fn constant_curvature_and_twist_on_any_mesh() {
    let h = 0.1;
    let c = plane_c(0.3);
    for (name, mesh) in meshes() {
        let mut worst_bciz: f64 = 0.0;
        for k in [
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.7, -0.4, 0.25],
        ] {
            let [k11, k22, k12] = k;
            let layout = origami_fmu::dofs::DofLayout::new(&mesh);
            let u = layout.state_of_field(&mesh, |x| {
                let w = 0.5 * (k11 * x.x * x.x + 2.0 * k12 * x.x * x.y + k22 * x.y * x.y);
                let g = Vector2::new(k11 * x.x + k12 * x.y, k12 * x.x + k22 * x.y);
                (
                    Vector3::new(0.0, 0.0, w),
                    Matrix3x2::new(0.0, 0.0, 0.0, 0.0, g.x, g.y),
                )
            });
            let kv = Vector3::new(k11, k22, 2.0 * k12);
            let exact = area(&mesh) * h * h * h / 24.0 * kv.dot(&(c * kv));
            for element in specht_elements() {
                let (res, energy) = residual_and_energy(&mesh, element, &u, h);
                assert!(
                    res < 1e-10,
                    "Specht {:?}, {name}, k {k:?}: interior residual {res:e}",
                    element.bending
                );
                assert!(
                    (energy - exact).abs() < 1e-11 * exact,
                    "Specht {:?}, {name}, k {k:?}: energy {energy} vs {exact}",
                    element.bending
                );
            }
            let (res_bciz, _) = residual_and_energy(&mesh, Interpolation::Bciz, &u, h);
            worst_bciz = worst_bciz.max(res_bciz);
        }
        eprintln!("{name}: BCIZ interior residual up to {worst_bciz:.1e}");
        if name == "same diagonal" {
            assert!(worst_bciz < 1e-11, "BCIZ, {name}: {worst_bciz:e}");
        } else {
            assert!(
                worst_bciz > 1e-3,
                "BCIZ should fail on {name}: {worst_bciz:e}"
            );
        }
    }
}

#[test]
fn constant_membrane_strain_on_any_mesh() {
    let h = 0.1;
    let c = plane_c(0.3);
    for (name, mesh) in meshes() {
        for a in [
            [1e-3, 0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0, 1e-3],
            [0.0, 2e-3, 1e-3, 0.0],
        ] {
            // Displacement gradient [[a0, a1], [a2, a3]]; linear strain.
            let layout = origami_fmu::dofs::DofLayout::new(&mesh);
            let u = layout.state_of_field(&mesh, |x| {
                (
                    Vector3::new(a[0] * x.x + a[1] * x.y, a[2] * x.x + a[3] * x.y, 0.0),
                    Matrix3x2::new(a[0], a[1], a[2], a[3], 0.0, 0.0),
                )
            });
            let eps = Vector3::new(a[0], a[3], a[1] + a[2]);
            let exact = area(&mesh) * h / 2.0 * eps.dot(&(c * eps));
            let bciz = ElementOptions::from(Interpolation::Bciz);
            for element in specht_elements().into_iter().chain([bciz]) {
                let (res, energy) = residual_and_energy(&mesh, element, &u, h);
                assert!(
                    res < 1e-10,
                    "{element:?}, {name}, a {a:?}: interior residual {res:e}"
                );
                assert!(
                    (energy - exact).abs() < 1e-11 * exact,
                    "{element:?}, {name}: energy {energy} vs {exact}"
                );
            }
        }
    }
}
