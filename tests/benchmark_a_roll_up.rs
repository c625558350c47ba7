//! BENCHMARKS.md case A (Sze, Liu & Lo 2004, case 3.2): a cantilever strip
//! rolled up by an end moment. L = 12, b = 1, h = 0.1, E = 1.2e6, nu = 0
//! (EI = 100), clamped at x = 0; M_max = 2 pi EI / L rolls it into a full
//! circle. Exact tip: -u = L (1 - sin t / t), w = L (1 - cos t) / t, t = M L / EI.
//! Mesh: 16 x 1 cells split along one diagonal direction (a three-direction
//! mesh, 32 triangles), 12-point rule; tolerance 1 % of each exact value (w at
//! the full circle is 0: compared against 1 % of L).
//!
//! Known limits, measured here: on "union-jack" meshes (alternating
//! diagonals) the BCIZ-type element does not converge (the small-moment tip
//! rotation gets 10 % too large at 16 cells, see
//! `union_jack_mesh_does_not_converge`); at M/M_max >= 0.75 the 16-cell mesh
//! is off by more than 1 % and the load-stepped Newton fails near the full
//! circle.

use nalgebra::Matrix3;
use origami_fmu::assembly::{Assembler, Physics};
use origami_fmu::element::Rule;
use origami_fmu::mesh::builders::grid_with;
use origami_fmu::scene::Material;
use origami_fmu::solver::statics::{self, Load, StaticSettings};
use std::f64::consts::PI;

const L: f64 = 12.0;
const EI: f64 = 100.0;

/// A moment about -y... rolling the strip towards +z: potential -M psi with
/// psi = atan2(t_z, t_x) of the x-gradient t at each free-end vertex.
struct EndMoment {
    /// (x-gradient slot, share of the total moment)
    slots: Vec<(usize, f64)>,
    /// Total moment at lambda = 1.
    moment: f64,
}

impl Load for EndMoment {
    fn apply(
        &self,
        asm: &Assembler,
        q: &[f64],
        lambda: f64,
        f: &mut [f64],
        matrix: Option<&mut [f64]>,
    ) {
        let mut matrix = matrix;
        for &(s, share) in &self.slots {
            let m = lambda * self.moment * share;
            let (x, z) = (q[3 * s], q[3 * s + 2]);
            let r2 = x * x + z * z;
            f[3 * s] += m * (-z / r2);
            f[3 * s + 2] += m * (x / r2);
            if let Some(vals) = matrix.as_deref_mut() {
                let r4 = r2 * r2;
                let mut h = Matrix3::zeros();
                h[(0, 0)] = 2.0 * x * z / r4;
                h[(2, 2)] = -2.0 * x * z / r4;
                h[(0, 2)] = (z * z - x * x) / r4;
                h[(2, 0)] = h[(0, 2)];
                asm.add_block(s, s, &(-m * h), vals);
            }
        }
    }
}

fn solve(ratio: f64, nx: usize, alternate: bool) -> (f64, f64) {
    let mesh = grid_with(L, 1.0, nx, 1, &[], alternate);
    let physics = Physics {
        material: Material {
            youngs_modulus: 1.2e6,
            poisson_ratio: 0.0,
            thickness: 0.1,
            density: 1.0,
        },
        crease_k_per_length: 0.0,
        crease_c_per_length: 0.0,
        alpha: 0.0,
        beta: 0.0,
    };
    let layout = origami_fmu::dofs::DofLayout::new(&mesh);
    let left: Vec<usize> = (0..mesh.n_vertices())
        .filter(|&v| mesh.coords[v].x == 0.0)
        .collect();
    let right: Vec<usize> = (0..mesh.n_vertices())
        .filter(|&v| mesh.coords[v].x == L)
        .collect();
    let fixed: Vec<usize> = left.iter().flat_map(|&v| layout.vertex_slots(v)).collect();
    let asm = Assembler::new(&mesh, physics, Rule::default(), &fixed).unwrap();
    let mut q = asm.layout.reference_state(&mesh);
    let slots = right
        .iter()
        .map(|&v| {
            let sec = &asm.layout.sectors[v][0];
            let (s, c) = sec
                .terms
                .iter()
                .find(|(_, c)| (c.x - 1.0).abs() < 1e-12)
                .copied()
                .unwrap();
            assert!(c.y.abs() < 1e-12);
            (s, 1.0 / right.len() as f64)
        })
        .collect();
    let m_max = 2.0 * PI * EI / L;
    let load = EndMoment {
        slots,
        moment: ratio * m_max,
    };
    let steps = (40.0 * ratio).ceil() as usize;
    let settings = StaticSettings {
        load_steps: steps,
        max_iterations: 60,
        tolerance: 1e-7,
    };
    statics::solve(&asm, &mut q, &[], &load, settings).unwrap();
    let tip: Vec<[f64; 3]> = right
        .iter()
        .map(|&v| {
            let s = asm.layout.position_slot[v];
            [q[3 * s], q[3 * s + 1], q[3 * s + 2]]
        })
        .collect();
    let x = tip.iter().map(|p| p[0]).sum::<f64>() / tip.len() as f64;
    let z = tip.iter().map(|p| p[2]).sum::<f64>() / tip.len() as f64;
    (L - x, z)
}

fn exact(ratio: f64) -> (f64, f64) {
    let t = ratio * 2.0 * PI;
    (L * (1.0 - t.sin() / t), L * (1.0 - t.cos()) / t)
}

#[test]
fn strip_rolls_up_within_one_percent() {
    check_roll_up(&[0.25, 0.5]);
}

#[test]
#[ignore = "known failure (issue 2): 16 cells are off by 11 % in w at 0.75 and Newton fails near the full circle"]
fn strip_rolls_into_full_circle() {
    check_roll_up(&[0.75, 1.0]);
}

fn check_roll_up(ratios: &[f64]) {
    for &ratio in ratios {
        let (u, w) = solve(ratio, 16, false);
        let (ue, we) = exact(ratio);
        eprintln!("M/Mmax {ratio}: -u {u:.4} (exact {ue:.4}), w {w:.4} (exact {we:.4})");
        assert!(
            (u - ue).abs() <= 0.01 * ue.abs().max(0.01 * L),
            "-u {u} vs {ue}"
        );
        assert!(
            (w - we).abs() <= 0.01 * if we.abs() > 1e-9 { we.abs() } else { L },
            "w {w} vs {we}"
        );
    }
}

/// Small moment (linear regime, theta = 0.0126): tip deflection w = M L^2 / (2 EI)
/// within 0.1 % on three-direction meshes of 4, 8 and 16 cells.
#[test]
fn small_moment_linear_rotation() {
    for nx in [4, 8, 16] {
        let ratio = 0.002;
        let (_, w) = solve(ratio, nx, false);
        let (_, we) = exact(ratio);
        assert!((w - we).abs() < 1e-3 * we, "nx {nx}: w {w} vs {we}");
    }
}

/// Records the known non-convergence on union-jack meshes (alternating
/// diagonals): the error grows under refinement instead of shrinking.
#[test]
fn union_jack_mesh_does_not_converge() {
    let ratio = 0.002;
    let (_, we) = exact(ratio);
    let err = |nx| (solve(ratio, nx, true).1 - we).abs() / we;
    let (e4, e16) = (err(4), err(16));
    assert!(e4 < 2e-3, "coarse union-jack error {e4}");
    assert!(
        e16 > 0.05,
        "if this fails the element now converges on union-jack meshes: update the docs ({e16})"
    );
}

#[test]
#[ignore]
fn convergence_table() {
    for nx in [16, 32, 64] {
        for ratio in [0.25, 0.5, 0.75, 1.0] {
            let (u, w) = solve(ratio, nx, false);
            let (ue, we) = exact(ratio);
            eprintln!(
                "nx {nx} M/Mmax {ratio}: err -u {:.3e} w {:.3e} (relative to L)",
                (u - ue).abs() / L,
                (w - we).abs() / L
            );
        }
    }
}
