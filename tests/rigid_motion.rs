//! Global rigid motions of a folded sheet: a 2 x 2 Miura-ori in its
//! rigid-folded state (Schenk & Guest, fold angle 60 deg) plus a random
//! perturbation, so that both the strain and the crease energy are non-zero,
//! is moved as a whole (positions rotate and translate, gradient slots
//! rotate only). The total energy and the crease angles must not change and
//! the internal force must rotate with the body: f(R q + t) = R f(q).
//!
//! Tolerances: energy within 1e-12 of a unit deformation (every crease end
//! folded 1 rad from rest, 6.6e-3 J here; the state holds 2.0e-3 J strain and
//! 2.1e-2 J crease energy), force within 1e-11 of max |f|, angles within
//! 1e-12 rad. Measured worst: rotations alone 4e-14 and 3e-13; shifts add the
//! rounding of positions far from the origin (0.6 m away: 4e-13 and 3e-12;
//! it grows with the distance, facets are 20 mm).

use nalgebra::{Matrix2, Matrix3, Matrix3x2, Rotation3, Unit, Vector3};
use origami_fmu::assembly::{Assembler, Evaluation, Physics, State};
use origami_fmu::dofs::SlotKind;
use origami_fmu::element::Rule;
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
    let asm = Assembler::new(mesh, physics, Rule::default(), &[]).unwrap();
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
            let [a, b, c] = mesh.triangles[sec.faces[0]];
            let flat = Matrix2::from_columns(&[
                mesh.coords[b] - mesh.coords[a],
                mesh.coords[c] - mesh.coords[a],
            ]);
            let bent = Matrix3x2::from_columns(&[folded[b] - folded[a], folded[c] - folded[a]]);
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

/// Evaluate with flat rest angles and the given unwrapping history.
fn evaluate(asm: &Assembler, q: &[f64], theta_prev: &[f64]) -> Evaluation {
    let n = asm.creases.len();
    let theta0 = vec![PI; n];
    let moment = vec![0.0; n];
    let v = vec![0.0; q.len()];
    let st = State {
        q,
        v: &v,
        theta0: &theta0,
        moment: &moment,
        theta_prev,
    };
    let mut ev = Evaluation::default();
    asm.evaluate(&st, &mut ev, None).unwrap();
    ev
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

#[test]
fn energy_angles_and_force_follow_rigid_motions() {
    let (asm, mut q) = folded_miura();
    let flat = vec![PI; asm.creases.len()];
    // Energy of a unit deformation: every crease end folded by 1 rad from its
    // rest angle, sum k_end / 2 (J).
    let unit: f64 = asm
        .creases
        .iter()
        .map(|c| 0.5 * asm.physics.crease_k_per_length * c.length)
        .sum();
    // The rigid fold is an isometry with planar facets: no strain energy.
    let rigid = evaluate(&asm, &q, &flat).strain_energy;
    assert!(rigid < 1e-12 * unit, "rigid fold strain energy {rigid:e} J");
    perturb(&asm, &mut q);
    // Unwrapping history: the folded state's own angles, taken from the flat state.
    let theta = evaluate(&asm, &q, &flat).theta;
    let base = evaluate(&asm, &q, &theta);
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
                let ev = evaluate(&asm, &moved(&asm, &q, &r, t), &theta);
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
