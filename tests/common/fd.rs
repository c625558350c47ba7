//! Finite-difference checks of force terms: the force against the energy's
//! gradient, the iteration matrix against the force's derivative.

use origami_fmu::assembly::{Assembler, Evaluation, MatrixCoeffs, State};
use std::f64::consts::PI;

/// Forces (and the matrix `co` if given) of `asm` at `(q, v)`.
pub fn eval_at(
    asm: &Assembler,
    q: &[f64],
    v: &[f64],
    m: Option<(&mut [f64], MatrixCoeffs)>,
) -> Evaluation {
    let pi = vec![PI; asm.creases.len()];
    let no_moment = vec![0.0; asm.creases.len()];
    let st = State {
        q,
        v,
        theta0: &pi,
        moment: &no_moment,
        theta_prev: &pi,
    };
    let mut ev = Evaluation::default();
    asm.evaluate(&st, &mut ev, m).unwrap();
    ev
}

/// Largest difference between the matrix `vals` (free DOFs) and central
/// differences of the force along every DOF of `x` (`q` or `v`, by
/// `along_v`), relative to the largest matrix entry.
pub fn matrix_fd_error(
    asm: &Assembler,
    q: &[f64],
    v: &[f64],
    vals: &[f64],
    along_v: bool,
    h: f64,
) -> f64 {
    let n = q.len();
    let maxk = vals.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    assert!(maxk > 0.0);
    let mut worst: f64 = 0.0;
    for j in 0..n {
        let col = asm.free[j];
        if col == usize::MAX {
            continue;
        }
        let mut xp = if along_v { v.to_vec() } else { q.to_vec() };
        let mut xm = xp.clone();
        xp[j] += h;
        xm[j] -= h;
        let (ep, em) = if along_v {
            (eval_at(asm, q, &xp, None), eval_at(asm, q, &xm, None))
        } else {
            (eval_at(asm, &xp, v, None), eval_at(asm, &xm, v, None))
        };
        let mut dense = vec![0.0; asm.nnz().max(n)];
        for p in asm.col_ptr[col]..asm.col_ptr[col + 1] {
            dense[asm.row_idx[p]] = vals[p];
        }
        for i in 0..n {
            let fi = asm.free[i];
            if fi == usize::MAX {
                continue;
            }
            let fd = (ep.force[i] - em.force[i]) / (2.0 * h);
            worst = worst.max((fd - dense[fi]).abs() / maxk);
        }
    }
    worst
}

/// The force of `asm` at rest at `q` (contact in touch) is the gradient of
/// its energy, and its matrix (exact Hessians) the derivative of its force.
pub fn force_and_tangent_match_finite_differences(asm: &Assembler, q: &[f64]) {
    force_and_tangent_match_finite_differences_with_step(asm, q, 1e-8);
}

/// [`force_and_tangent_match_finite_differences`] with central differences
/// of step `h`: pairs at gaps of a few `1e-7` m need a step well below
/// them (the truncation error grows as `(h / gap)^2`).
pub fn force_and_tangent_match_finite_differences_with_step(asm: &Assembler, q: &[f64], h: f64) {
    let zeros = vec![0.0; q.len()];
    let e0 = eval_at(asm, q, &zeros, None);
    assert!(e0.term_energy > 0.0, "contact acts");
    let mut worst: f64 = 0.0;
    let mut fmax: f64 = 0.0;
    let total = |ev: &Evaluation| ev.strain_energy + ev.crease_energy + ev.term_energy;
    for i in 0..q.len() {
        let mut qp = q.to_vec();
        let mut qm = q.to_vec();
        qp[i] += h;
        qm[i] -= h;
        let fd = (total(&eval_at(asm, &qp, &zeros, None))
            - total(&eval_at(asm, &qm, &zeros, None)))
            / (2.0 * h);
        worst = worst.max((fd - e0.force[i]).abs());
        fmax = fmax.max(e0.force[i].abs());
    }
    assert!(fmax > 0.0);
    assert!(
        worst <= 1e-5 * fmax,
        "force vs energy: {worst:.3e} of {fmax:.3e}"
    );
    // Tangent vs force (exact Hessian; the pattern holds the pair's blocks).
    let mut k = vec![0.0; asm.nnz()];
    let co = MatrixCoeffs {
        k: 1.0,
        m: 0.0,
        c: 0.0,
    };
    eval_at(asm, q, &zeros, Some((&mut k, co)));
    let err = matrix_fd_error(asm, q, &zeros, &k, false, h);
    assert!(err <= 1e-5, "tangent vs force: {err:.3e}");
}
