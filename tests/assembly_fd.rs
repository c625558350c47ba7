//! The assembled global tangent against finite differences of the assembled
//! residual, and the residual against the total energy, at large random
//! deformations of a creased sheet (folds beyond 90 degrees included).

use origami_fmu::assembly::{Assembler, Evaluation, MatrixCoeffs, Physics, State};
use origami_fmu::element::Rule;
use origami_fmu::mesh::builders::grid;
use origami_fmu::scene::Material;

/// Small deterministic PRNG (xorshift) so the test needs no crate.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
}

fn setup() -> (Assembler, Vec<f64>) {
    let mesh = grid(0.03, 0.02, 3, 2, &[(1, 1.5), (2, -2.0)]);
    let physics = Physics {
        material: Material {
            youngs_modulus: 1.0e6,
            poisson_ratio: 0.3,
            thickness: 1e-3,
            density: 1000.0,
        },
        crease_k_per_length: 0.05,
        crease_c_per_length: 0.0,
        alpha: 0.0,
        beta: 0.0,
    };
    let asm = Assembler::new(&mesh, physics, Rule::default(), &[]).unwrap();
    let mut q = asm.layout.reference_state(&mesh);
    // Fold rigidly-ish: rotate the right third about the crease line x = 0.02 by ~120 deg,
    // then add random perturbations.
    let mut rng = Rng(0x9e3779b97f4a7c15);
    for x in q.iter_mut() {
        *x += 0.05 * rng.next() * 0.01;
    }
    (asm, q)
}

fn eval(
    asm: &Assembler,
    q: &[f64],
    theta_prev: &[f64],
    out: &mut Evaluation,
    m: Option<&mut Vec<f64>>,
) {
    let n = asm.creases.len();
    let theta0: Vec<f64> = (0..n).map(|i| 2.0 + 0.1 * i as f64).collect();
    let moment = vec![0.0; n];
    let v = vec![0.0; q.len()];
    let st = State {
        q,
        v: &v,
        theta0: &theta0,
        moment: &moment,
        theta_prev,
    };
    asm.evaluate(
        &st,
        out,
        m.map(|m| {
            (
                m.as_mut_slice(),
                MatrixCoeffs {
                    k: 1.0,
                    m: 0.0,
                    c: 0.0,
                },
            )
        }),
    )
    .unwrap();
}

#[test]
fn global_tangent_matches_finite_differences() {
    let (asm, mut q) = setup();
    // Large random deformation.
    let mut rng = Rng(12345);
    for (i, x) in q.iter_mut().enumerate() {
        *x += 0.2 * rng.next() * if i % 3 == 2 { 1.0 } else { 0.3 };
    }
    check(&asm, &q);
}

/// At the flat, stress-free reference (where normals and curvatures are
/// exactly planar) the tangent must match too.
#[test]
fn global_tangent_at_flat_reference() {
    let mesh = origami_fmu::mesh::builders::strip(12.0, 1.0, 4, 1);
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
    let asm = Assembler::new(&mesh, physics, Rule::default(), &[]).unwrap();
    let q = asm.layout.reference_state(&mesh);
    check(&asm, &q);
}

fn check(asm: &Assembler, q: &[f64]) {
    let asm = asm;
    let q = q.to_vec();
    let theta_prev = vec![std::f64::consts::PI; asm.creases.len()];
    let mut base = Evaluation::default();
    let mut k = vec![0.0; asm.nnz()];
    eval(&asm, &q, &theta_prev, &mut base, Some(&mut k));
    let n = q.len();
    let h = 1e-6;
    let mut maxk: f64 = 0.0;
    for v in &k {
        maxk = maxk.max(v.abs());
    }
    let mut worst: f64 = 0.0;
    for j in 0..n {
        let mut qp = q.clone();
        let mut qm = q.clone();
        qp[j] += h;
        qm[j] -= h;
        let (mut ep, mut em) = (Evaluation::default(), Evaluation::default());
        eval(&asm, &qp, &base.theta, &mut ep, None);
        eval(&asm, &qm, &base.theta, &mut em, None);
        // column j of K
        let col = asm.free[j];
        let mut dense = vec![0.0; n];
        for p in asm.col_ptr[col]..asm.col_ptr[col + 1] {
            dense[asm.row_idx[p]] = k[p];
        }
        for i in 0..n {
            let fd = (ep.force[i] - em.force[i]) / (2.0 * h);
            worst = worst.max((fd - dense[asm.free[i]]).abs() / maxk);
        }
        // residual vs energy
        let de =
            (ep.strain_energy + ep.crease_energy - em.strain_energy - em.crease_energy) / (2.0 * h);
        // at a stress-free state the force is ~0: measure against the force a
        // unit-scale (1e-6) displacement produces instead
        let scale = base
            .force
            .iter()
            .fold(0.0f64, |a, b| a.max(b.abs()))
            .max(maxk * 1e-6);
        assert!(
            (de - base.force[j]).abs() <= 1e-6 * scale,
            "dof {j}: dU {de} vs f {}",
            base.force[j]
        );
    }
    assert!(worst < 1e-6, "relative tangent error {worst}");
}
