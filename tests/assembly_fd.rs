//! The assembled global tangent against finite differences of the assembled
//! residual, and the residual against the total energy, at large random
//! deformations of a creased sheet (folds beyond 90 degrees included); and
//! energy, angles and force of a folded sheet under global rigid motions.

use nalgebra::{Matrix2, Matrix3, Matrix3x2, Rotation3, Unit, Vector3};
use origami_fmu::assembly::{Assembler, Evaluation, MatrixCoeffs, Physics, State};
use origami_fmu::dofs::SlotKind;
use origami_fmu::element::ElementOptions;
use origami_fmu::mesh::builders::grid;
use origami_fmu::scene::Material;
use origami_fmu::scene::build::from_fold;
use origami_fmu::scene::patterns::Miura;
use std::f64::consts::{PI, TAU};

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
    let asm = Assembler::new(&mesh, physics, ElementOptions::default(), &[]).unwrap();
    let mut q = asm.layout.reference_state(&mesh);
    // Fold rigidly-ish: rotate the right third about the crease line x = 0.02 by ~120 deg,
    // then add random perturbations.
    let mut rng = Rng(0x9e3779b97f4a7c15);
    for x in q.iter_mut() {
        *x += 0.05 * rng.next() * 0.01;
    }
    (asm, q)
}

/// Evaluate with rest angles 2.0, 2.1, 2.2, ... rad.
fn eval(
    asm: &Assembler,
    q: &[f64],
    theta_prev: &[f64],
    out: &mut Evaluation,
    m: Option<&mut Vec<f64>>,
) {
    let theta0: Vec<f64> = (0..asm.creases.len())
        .map(|i| 2.0 + 0.1 * i as f64)
        .collect();
    eval_with(asm, q, &theta0, theta_prev, out, m);
}

/// Evaluate forces, energies, angles and (if `m` is given) the tangent.
fn eval_with(
    asm: &Assembler,
    q: &[f64],
    theta0: &[f64],
    theta_prev: &[f64],
    out: &mut Evaluation,
    m: Option<&mut Vec<f64>>,
) {
    let n = asm.creases.len();
    let moment = vec![0.0; n];
    let v = vec![0.0; q.len()];
    let st = State {
        q,
        v: &v,
        theta0,
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
    // The case A strip (docs/validation.md) on 4 cells.
    let mesh = origami_fmu::mesh::builders::strip(12.0, 1.0, 4, 1);
    let physics = origami_fmu::benchmarks::roll_up_physics();
    let asm = Assembler::new(&mesh, physics, ElementOptions::default(), &[]).unwrap();
    let q = asm.layout.reference_state(&mesh);
    check(&asm, &q);
}

fn check(asm: &Assembler, q: &[f64]) {
    let q = q.to_vec();
    let theta_prev = vec![std::f64::consts::PI; asm.creases.len()];
    let mut base = Evaluation::default();
    let mut k = vec![0.0; asm.nnz()];
    eval(asm, &q, &theta_prev, &mut base, Some(&mut k));
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
        eval(asm, &qp, &base.theta, &mut ep, None);
        eval(asm, &qm, &base.theta, &mut em, None);
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

/// The assembler of a 2 x 2 Miura-ori (paper, creases with L* = 10 mm, no
/// supports) and its rigid-folded state.
fn folded_miura() -> (Assembler, Vec<f64>) {
    let miura = Miura {
        nx: 2,
        ny: 2,
        ..Miura::default()
    };
    let (scene, _) = from_fold(&miura.generate().unwrap(), None).unwrap();
    let mesh = &scene.mesh;
    let folded = miura.folded();
    assert_eq!(mesh.n_vertices(), folded.len(), "no refinement vertices");
    let physics = Physics {
        material: scene.material,
        crease_k_per_length: scene.material.bending_stiffness() / 0.01,
        crease_c_per_length: 0.0,
        alpha: 0.0,
        beta: 0.0,
    };
    let asm = Assembler::new(mesh, physics, ElementOptions::default(), &[]).unwrap();
    let layout = &asm.layout;
    let mut q = vec![0.0; asm.n_dofs()];
    for (v, x) in folded.iter().enumerate() {
        let s = layout.position_slot[v];
        q[3 * s..3 * s + 3].copy_from_slice(x.as_slice());
    }
    // Each sector's gradient G maps the flat facet onto the folded one
    // (facets stay planar and unstretched); its slots q_k solve
    // G = sum_k q_k c_k^T, i.e. [q0 q1] = G C^-1 with the c_k as rows of C.
    for sectors in &layout.sectors {
        for sec in sectors {
            let [a, b, c] = mesh.triangle(sec.faces[0]);
            let flat = Matrix2::from_columns(&[
                mesh.coord(b) - mesh.coord(a),
                mesh.coord(c) - mesh.coord(a),
            ]);
            let bent = Matrix3x2::from_columns(&[
                folded[b.index()] - folded[a.index()],
                folded[c.index()] - folded[a.index()],
            ]);
            let g = bent * flat.try_inverse().unwrap();
            let (s0, c0) = sec.terms[0];
            let (s1, c1) = sec.terms[1];
            let cm = Matrix2::from_rows(&[c0.transpose(), c1.transpose()]);
            let slots = g * cm.try_inverse().unwrap();
            for (k, s) in [s0, s1].into_iter().enumerate() {
                q[3 * s..3 * s + 3].copy_from_slice(slots.column(k).as_slice());
            }
        }
    }
    (asm, q)
}

/// Perturb every slot randomly, so that the facets stretch and bend.
fn perturb(asm: &Assembler, q: &mut [f64]) {
    // Up to 0.02 mm on positions (facets are 20 mm), 1e-3 on gradients.
    let layout = &asm.layout;
    let mut rng = Rng(0x2545f4914f6cdd1d);
    for s in 0..layout.n_slots() {
        let amp = match layout.slot_kind[s] {
            SlotKind::Position => 2e-5,
            SlotKind::Gradient => 1e-3,
        };
        for x in &mut q[3 * s..3 * s + 3] {
            *x += amp * rng.next();
        }
    }
}

/// `R q + t` on every slot, `t` on positions only.
fn moved(asm: &Assembler, q: &[f64], r: &Matrix3<f64>, t: &Vector3<f64>) -> Vec<f64> {
    let mut out = q.to_vec();
    for s in 0..asm.layout.n_slots() {
        let mut x = r * Vector3::from_column_slice(&q[3 * s..3 * s + 3]);
        if asm.layout.slot_kind[s] == SlotKind::Position {
            x += t;
        }
        out[3 * s..3 * s + 3].copy_from_slice(x.as_slice());
    }
    out
}

/// Global rigid motions of a folded sheet: a 2 x 2 Miura-ori in its
/// rigid-folded state (Schenk & Guest, fold angle 60 deg) plus a random
/// perturbation, so that both the strain and the crease energy are non-zero,
/// is moved as a whole (positions rotate and translate, gradient slots
/// rotate only). The total energy and the crease angles must not change and
/// the internal force must rotate with the body: f(R q + t) = R f(q).
///
/// Tolerances: energy within 1e-12 of a unit deformation (every crease end
/// folded 1 rad from rest, 6.6e-3 J here; the state holds 2.0e-3 J strain and
/// 2.1e-2 J crease energy), force within 1e-11 of max |f|, angles within
/// 1e-12 rad. Measured worst: rotations alone 4e-14 and 3e-13; shifts add the
/// rounding of positions far from the origin (0.6 m away: 4e-13 and 3e-12;
/// it grows with the distance, facets are 20 mm).
#[test]
fn energy_angles_and_force_follow_rigid_motions() {
    let (asm, mut q) = folded_miura();
    let flat = vec![PI; asm.creases.len()];
    // Flat rest angles: the folded state holds crease energy.
    let evaluate = |q: &[f64], theta_prev: &[f64]| {
        let mut ev = Evaluation::default();
        eval_with(&asm, q, &flat, theta_prev, &mut ev, None);
        ev
    };
    // Energy of a unit deformation: every crease end folded by 1 rad from its
    // rest angle, sum k_end / 2 (J).
    let unit: f64 = asm
        .creases
        .iter()
        .map(|c| 0.5 * asm.physics.crease_k_per_length * c.length)
        .sum();
    // The rigid fold is an isometry with planar facets: no strain energy.
    let rigid = evaluate(&q, &flat).strain_energy;
    assert!(rigid < 1e-12 * unit, "rigid fold strain energy {rigid:e} J");
    perturb(&asm, &mut q);
    // Unwrapping history: the folded state's own angles, taken from the flat state.
    let theta = evaluate(&q, &flat).theta;
    let base = evaluate(&q, &theta);
    let fmax = base.force.iter().fold(0.0f64, |m, f| m.max(f.abs()));
    eprintln!(
        "rigid fold strain {rigid:.1e} J; perturbed: strain {:.3e} J, crease {:.3e} J, unit {unit:.3e} J, max |f| {fmax:.3e}",
        base.strain_energy, base.crease_energy
    );
    assert!(base.strain_energy > 1e-3 * unit && base.crease_energy > unit);
    assert!(base.theta.iter().zip(&theta).all(|(a, b)| a == b));

    let axes = [
        Vector3::x(),
        Vector3::y(),
        Vector3::z(),
        Vector3::new(1.0, 2.0, 3.0),
        Vector3::new(-0.3, 0.9, 0.2),
    ];
    let angles = [
        0.7,
        PI / 2.0,
        PI - 1e-7,
        PI,
        PI + 1e-7,
        4.0,
        TAU - 1e-9,
        TAU,
    ];
    let shifts = [
        Vector3::zeros(),
        Vector3::new(0.03, -0.02, 0.05),
        Vector3::new(0.3, -0.2, 0.5),
    ];
    let (mut worst_e, mut worst_f, mut worst_theta) = (0.0f64, 0.0f64, 0.0f64);
    for axis in axes {
        for angle in angles {
            for t in &shifts {
                let r = *Rotation3::from_axis_angle(&Unit::new_normalize(axis), angle).matrix();
                let ev = evaluate(&moved(&asm, &q, &r, t), &theta);
                let de =
                    (ev.strain_energy + ev.crease_energy - base.strain_energy - base.crease_energy)
                        .abs();
                let rf = moved(&asm, &base.force, &r, &Vector3::zeros());
                let df = ev
                    .force
                    .iter()
                    .zip(&rf)
                    .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
                let dtheta = ev
                    .theta
                    .iter()
                    .zip(&theta)
                    .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
                worst_e = worst_e.max(de / unit);
                worst_f = worst_f.max(df / fmax);
                worst_theta = worst_theta.max(dtheta);
                let what = format!("axis {axis:?}, angle {angle}, shift {t:?}");
                assert!(de < 1e-12 * unit, "{what}: energy changed by {de:e} J");
                assert!(
                    df < 1e-11 * fmax,
                    "{what}: force off by {df:e} (max |f| {fmax:e})"
                );
                assert!(
                    dtheta < 1e-12,
                    "{what}: crease angle changed by {dtheta:e} rad"
                );
            }
        }
    }
    eprintln!(
        "worst: energy {worst_e:.2e} of unit, force {worst_f:.2e} of max |f|, angle {worst_theta:.2e} rad"
    );
}

/// `c df/dv` of mass damping (it spares the rigid motion: `alpha M (v - P v)`)
/// is the sparse `c alpha M` plus the dense low-rank `-c alpha M P`; together
/// they match central differences of the force in the velocity, for a free
/// sheet (six modes) and a sheet whose supports leave only rotations about
/// one vertex (three).
#[test]
fn mass_damping_matrix_with_its_low_rank_part_matches_finite_differences() {
    let (mut asm, mut q) = folded_miura();
    perturb(&asm, &mut q);
    asm.physics.alpha = 40.0;
    check_damping(&asm, &q, 6);
    // Pin vertex 0's position slot: translations are no longer rigid motions.
    let s = asm.layout.position_slot[0];
    let supported = [3 * s, 3 * s + 1, 3 * s + 2];
    let length = 0.04;
    asm.rigid.set_supports(&supported, &q, length);
    check_damping(&asm, &q, 3);
}

fn check_damping(asm: &Assembler, q: &[f64], rank: usize) {
    let n = q.len();
    let mut rng = Rng(777);
    let v: Vec<f64> = (0..n).map(|_| rng.next()).collect();
    let w: Vec<f64> = (0..n).map(|_| rng.next()).collect();
    let nc = asm.creases.len();
    let theta0 = vec![PI; nc];
    let moment = vec![0.0; nc];
    let theta_prev = {
        let mut t = Vec::new();
        asm.crease_angles(q, &vec![PI; nc], &mut t).unwrap();
        t
    };
    let co = MatrixCoeffs {
        k: 0.0,
        m: 0.0,
        c: 1.0,
    };
    let force = |v: &[f64], m: Option<&mut Vec<f64>>| {
        let st = State {
            q,
            v,
            theta0: &theta0,
            moment: &moment,
            theta_prev: &theta_prev,
        };
        let mut out = Evaluation::default();
        asm.evaluate(&st, &mut out, m.map(|m| (m.as_mut_slice(), co)))
            .unwrap();
        out.force
    };
    let mut c = vec![0.0; asm.nnz()];
    force(&v, Some(&mut c));
    let lr = asm.matrix_low_rank(q, co).expect("a low-rank part");
    assert_eq!(lr.rank(), rank);
    // The matrix times w (free DOFs): sparse part, then -U S^-1 U^T w.
    let nf = asm.n_free;
    let wf: Vec<f64> = (0..nf)
        .map(|f| w[asm.free.iter().position(|&x| x == f).unwrap()])
        .collect();
    let mut cw = vec![0.0; nf];
    for (j, wj) in wf.iter().enumerate() {
        for p in asm.col_ptr[j]..asm.col_ptr[j + 1] {
            cw[asm.row_idx[p]] += c[p] * wj;
        }
    }
    let u = nalgebra::DMatrix::from_column_slice(nf, rank, &lr.u);
    let y =
        lr.s.clone()
            .lu()
            .solve(&(u.transpose() * nalgebra::DVector::from_column_slice(&wf)))
            .unwrap();
    let low = &u * y;
    for i in 0..nf {
        cw[i] -= low[i];
    }
    // Central differences in v along w (fixed DOFs of w count too: the
    // force's dependence on them is not in the free-DOF matrix, so keep
    // them at zero).
    let wv: Vec<f64> = (0..n)
        .map(|i| if asm.free[i] == usize::MAX { 0.0 } else { w[i] })
        .collect();
    let eps = 1e-3;
    let vp: Vec<f64> = v.iter().zip(&wv).map(|(a, b)| a + eps * b).collect();
    let vm: Vec<f64> = v.iter().zip(&wv).map(|(a, b)| a - eps * b).collect();
    let (fp, fm) = (force(&vp, None), force(&vm, None));
    let scale = cw.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    let mut worst: f64 = 0.0;
    let mut low_size: f64 = 0.0;
    for i in 0..n {
        let f = asm.free[i];
        if f == usize::MAX {
            continue;
        }
        let fd = (fp[i] - fm[i]) / (2.0 * eps);
        worst = worst.max((fd - cw[f]).abs() / scale);
        low_size = low_size.max(low[f].abs() / scale);
    }
    assert!(worst < 1e-8, "damping matrix error {worst}");
    // The low-rank part is no round-off correction.
    assert!(low_size > 1e-2, "low-rank part only {low_size}");
}

/// Where the assembler lags the membrane's geometric stiffness, the
/// matrix differs from the exact tangent (that of an assembler that does
/// not lag) and the force is the same bit for bit.
#[test]
fn the_lagged_membrane_stiffness_changes_the_matrix_not_the_force() {
    let (mut asm, q) = folded_miura();
    let mut start = q.clone();
    perturb(&asm, &mut start);
    let nc = asm.creases.len();
    let theta0 = vec![PI; nc];
    let moment = vec![0.0; nc];
    let mut theta_prev = Vec::new();
    asm.crease_angles(&q, &vec![PI; nc], &mut theta_prev)
        .unwrap();
    let v = vec![0.0; q.len()];
    let matrix = |asm: &Assembler| {
        let st = State {
            q: &q,
            v: &v,
            theta0: &theta0,
            moment: &moment,
            theta_prev: &theta_prev,
        };
        let co = MatrixCoeffs {
            k: 1.0,
            m: 0.0,
            c: 0.0,
        };
        let mut out = Evaluation::default();
        let mut vals = vec![0.0; asm.nnz()];
        asm.evaluate(&st, &mut out, Some((&mut vals[..], co)))
            .unwrap();
        (vals, out.force)
    };
    let (tangent, force) = matrix(&asm);
    asm.lag_membrane_stiffness(true);
    asm.lag(&start, &v);
    let (lagged, f_lagged) = matrix(&asm);
    assert_eq!(f_lagged, force);
    let diff: f64 = lagged
        .iter()
        .zip(&tangent)
        .map(|(a, b)| (a - b).powi(2))
        .sum::<f64>()
        .sqrt();
    let size: f64 = tangent.iter().map(|a| a * a).sum::<f64>().sqrt();
    assert!(
        diff > 1e-8 * size,
        "the lagged matrix differs: {diff:.3e} of {size:.3e}"
    );
}
