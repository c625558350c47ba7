//! Static equilibrium by Newton's method with load stepping and a
//! backtracking line search: `f_int(q) = lambda f_ext + extra(q)` for
//! `lambda` from 0 to 1. Used for the benchmarks with known static answers.

use crate::assembly::{Assembler, Evaluation, FIXED, MatrixCoeffs, State};
use crate::solver::SparseSolver;

/// A load that depends on the configuration (e.g. an end moment acting on
/// a rotation angle): adds `-dV/dq` scaled by `lambda` to `force` and, if
/// given, the matching `d2V/dq2` to the matrix values.
pub trait Load {
    /// Add `lambda * (-dV/dq)` to `force_ext` and `lambda * d2V/dq2` to `matrix`.
    fn apply(
        &self,
        asm: &Assembler,
        q: &[f64],
        lambda: f64,
        force_ext: &mut [f64],
        matrix: Option<&mut [f64]>,
    );
}

/// Settings of the static solve.
#[derive(Clone, Copy, Debug)]
pub struct StaticSettings {
    /// Number of equal load increments.
    pub load_steps: usize,
    /// Maximum Newton iterations per increment.
    pub max_iterations: usize,
    /// Converged when the residual norm is below `tolerance` times the
    /// external force norm, or when the work of a Newton correction is
    /// below 1e-16 of the increment's first (the round-off floor).
    pub tolerance: f64,
}

impl Default for StaticSettings {
    fn default() -> Self {
        StaticSettings {
            load_steps: 10,
            max_iterations: 50,
            tolerance: 1e-9,
        }
    }
}

/// What a static solve did.
#[derive(Clone, Debug, Default)]
pub struct StaticReport {
    /// Newton iterations per load increment.
    pub iterations: Vec<usize>,
    /// Final relative residual norm per increment.
    pub residuals: Vec<f64>,
}

/// Solve for equilibrium starting from `q` (updated in place). Fixed DOFs
/// keep their values in `q`. `theta0` are the crease rest angles; the
/// theta history starts flat (pi).
pub fn solve(
    asm: &Assembler,
    q: &mut [f64],
    theta0: &[f64],
    load: &dyn Load,
    settings: StaticSettings,
) -> Result<StaticReport, String> {
    let n = asm.n_dofs();
    let mut solver = SparseSolver::new(asm.n_free, asm.col_ptr.clone(), asm.row_idx.clone())?;
    let zeros = vec![0.0; n];
    let moment = vec![0.0; asm.creases.len()];
    let mut theta_prev = vec![std::f64::consts::PI; asm.creases.len()];
    let mut ev = Evaluation::default();
    let mut mat = vec![0.0; asm.nnz()];
    let mut fext = vec![0.0; n];
    let mut rhs = vec![0.0; asm.n_free];
    let mut report = StaticReport::default();
    let co = MatrixCoeffs {
        k: 1.0,
        m: 0.0,
        c: 0.0,
    };
    let residual = |q: &[f64],
                    lambda: f64,
                    theta_prev: &[f64],
                    ev: &mut Evaluation,
                    fext: &mut Vec<f64>,
                    mat: Option<&mut [f64]>|
     -> Result<f64, String> {
        let st = State {
            q,
            v: &zeros,
            theta0,
            moment: &moment,
            theta_prev,
        };
        match mat {
            Some(m) => {
                asm.evaluate(&st, ev, Some((&mut *m, co)))?;
                fext.iter_mut().for_each(|x| *x = 0.0);
                load.apply(asm, q, lambda, fext, Some(m));
            }
            None => {
                asm.evaluate(&st, ev, None)?;
                fext.iter_mut().for_each(|x| *x = 0.0);
                load.apply(asm, q, lambda, fext, None);
            }
        }
        let mut r2 = 0.0;
        for i in 0..n {
            if asm.free[i] != FIXED {
                let r = ev.force[i] - fext[i];
                r2 += r * r;
            }
        }
        Ok(r2.sqrt())
    };
    for step in 1..=settings.load_steps {
        let lambda = step as f64 / settings.load_steps as f64;
        // Reference force norm: the external load at this lambda.
        let mut converged = false;
        let mut it = 0;
        let mut rnorm = 0.0;
        let mut first_work = 0.0;
        while it < settings.max_iterations {
            it += 1;
            rnorm = residual(q, lambda, &theta_prev, &mut ev, &mut fext, Some(&mut mat))?;
            let fref = fext.iter().map(|x| x * x).sum::<f64>().sqrt().max(1e-300);
            if rnorm <= settings.tolerance * fref {
                converged = true;
                break;
            }
            for i in 0..n {
                let fi = asm.free[i];
                if fi != FIXED {
                    rhs[fi] = fext[i] - ev.force[i];
                }
            }
            solver.factor(&mat)?;
            let b = rhs.clone();
            solver.solve_in_place(&mut rhs)?;
            // Energy criterion (Bathe): the work of the correction against the
            // residual, relative to the first one of this increment. It stays
            // meaningful where the force residual hits its round-off floor
            // (thin sheets: membrane stiffness >> load).
            let work = rhs.iter().zip(&b).map(|(x, y)| x * y).sum::<f64>().abs();
            if it == 1 {
                first_work = work;
            } else if work <= 1e-16 * first_work {
                converged = true;
                break;
            }
            // Line search on the energy slope along the step (Crisfield):
            // s(alpha) = dq . R(q + alpha dq) should vanish; accept the full
            // step when |s(1)| <= 0.8 |s(0)|, else take secant steps.
            let q0: Vec<f64> = q.to_vec();
            let slope = |q: &mut [f64],
                         alpha: f64,
                         ev: &mut Evaluation,
                         fext: &mut Vec<f64>|
             -> Option<f64> {
                for i in 0..n {
                    let fi = asm.free[i];
                    if fi != FIXED {
                        q[i] = q0[i] + alpha * rhs[fi];
                    }
                }
                residual(q, lambda, &theta_prev, ev, fext, None).ok()?;
                let mut s = 0.0;
                for i in 0..n {
                    let fi = asm.free[i];
                    if fi != FIXED {
                        s -= rhs[fi] * (ev.force[i] - fext[i]);
                    }
                }
                s.is_finite().then_some(s)
            };
            // s(0) = dq . (f_ext - f_int) at q0, with the sign convention of `slope`.
            let s0: f64 = (0..n)
                .filter(|&i| asm.free[i] != FIXED)
                .map(|i| rhs[asm.free[i]] * (fext[i] - ev.force[i]))
                .sum();
            let (mut a_lo, mut s_lo, mut alpha) = (0.0, s0, 1.0);
            for _ in 0..8 {
                match slope(q, alpha, &mut ev, &mut fext) {
                    Some(s) if s.abs() <= 0.8 * s0.abs() => break,
                    Some(s) => {
                        // secant between (a_lo, s_lo) and (alpha, s)
                        let next = if (s_lo - s).abs() > 0.0 {
                            alpha - s * (alpha - a_lo) / (s - s_lo)
                        } else {
                            0.5 * alpha
                        };
                        a_lo = alpha;
                        s_lo = s;
                        alpha = next.clamp(0.05, 4.0);
                    }
                    None => alpha *= 0.25,
                }
            }
            if slope(q, alpha, &mut ev, &mut fext).is_none() {
                return Err(format!(
                    "static solve reached an invalid configuration at load factor {lambda:.3}"
                ));
            }
        }
        if !converged {
            return Err(format!(
                "static Newton did not converge at load factor {lambda:.3} (relative residual {:.3e} after {it} iterations)",
                rnorm / fext.iter().map(|x| x * x).sum::<f64>().sqrt().max(1e-300)
            ));
        }
        theta_prev.clone_from(&ev.theta);
        let fref = fext.iter().map(|x| x * x).sum::<f64>().sqrt().max(1e-300);
        report.iterations.push(it);
        report.residuals.push(rnorm / fref);
    }
    Ok(report)
}
