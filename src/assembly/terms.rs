//! The force-term interface: every contribution to the equations of motion
//! `M a + f(q, v) = f_ext(t)` is a [`ForceTerm`] that adds its part of `f`,
//! its energy and its part of the iteration matrix `k df/dq + c df/dv`. The
//! built-in terms (shell elements, crease springs with their moments and
//! dashpots, mass damping) are the first clients; more plug in through
//! [`super::Assembler::with_terms`], declaring the slot pairs they couple
//! ([`ForceTerm::pattern`]) and using [`ForceTerm::before_step`] for
//! per-step work such as a broad phase. Terms that keep surfaces apart
//! (contact) are [`BarrierTerm`]s as well: they also limit the stepper's
//! moves, carry memory in saved states and report powers.
//!
//! External loads that depend only on time (gravity, vertex-force inputs)
//! stay in the stepper's `f_ext`: it evaluates them at the integrator's own
//! time points, which is where held and interpolated inputs are defined.

use super::errors::{EvalError, MemoryError};
use super::{
    Assembler, Evaluation, MatrixCoeffs, State, local_vector, scatter_force, scatter_matrix,
};
use crate::crease;
use crate::dofs::DofLayout;
use crate::element::MembraneResultants;
use crate::frame::Motion;
use crate::solver::LowRank;
use nalgebra::{SMatrix, SVector};

/// One contribution to the equations of motion.
pub trait ForceTerm: Send + Sync {
    /// Name for reports and errors.
    fn name(&self) -> &str;

    /// Slot pairs whose 3x3 blocks [`ForceTerm::add`] writes, beyond the
    /// facets' and creases' own (they join the pattern when the assembler is
    /// built; write them with [`Assembler::add_block`]).
    fn pattern(&self, _layout: &DofLayout) -> Vec<(usize, usize)> {
        Vec::new()
    }

    /// Called with the accepted state `(q, v)` before each time step; returns
    /// slot pairs the term may write in this step (the pattern grows by the
    /// ones it lacks; an empty list keeps it).
    fn before_step(&mut self, _asm: &Assembler, _q: &[f64], _v: &[f64]) -> Vec<(usize, usize)> {
        Vec::new()
    }

    /// Take lagged data (contact: friction's normal forces and bases) from
    /// the step start `(q, v)`; [`ForceTerm::before_step`] does this too.
    fn lag(&mut self, _asm: &Assembler, _q: &[f64], _v: &[f64]) {}

    /// Add the term's viscous force at `(q, v)` to `out` (all DOFs): the
    /// part of its force that dissipates (mass and stiffness damping,
    /// crease dashpots), whose work the model integrates over each step as
    /// `energy.dissipated` (contact's friction and dashpots it reports in
    /// [`Evaluation::dissipative_force`]).
    fn viscous_force(&self, _asm: &Assembler, _q: &[f64], _v: &[f64], _out: &mut [f64]) {}

    /// A dense low-rank part of `k df/dq + c df/dv` that the sparse
    /// pattern cannot hold (all DOFs; mass damping's rigid-body projection
    /// couples every DOF): [`Assembler::matrix_low_rank`] gathers them for
    /// the solver.
    fn low_rank(&self, _asm: &Assembler, _q: &[f64], _co: MatrixCoeffs) -> Option<LowRank> {
        None
    }

    /// Add this term's force to `out.force` (all DOFs, internal-force sign:
    /// it opposes the motion it resists) and its energy to `out`; with a
    /// matrix, add `k df/dq + c df/dv` (free DOFs, pattern order).
    fn add(
        &self,
        asm: &Assembler,
        st: &State,
        out: &mut Evaluation,
        matrix: Option<(&mut [f64], MatrixCoeffs)>,
    ) -> Result<(), EvalError>;
}

/// A force term that keeps surfaces apart (self-contact, obstacles): beyond
/// what every term does, it limits the stepper's moves to collision-free
/// ones, carries memory from step to step, and reports powers. The
/// assembler keeps these terms apart from the plain ones and evaluates
/// them after them ([`Assembler::add_barrier`]).
pub trait BarrierTerm: ForceTerm {
    /// What the term carries from step to step beyond the state `(q, v)`
    /// (contact: each pair's barrier stiffness), for saved model states; a
    /// restore hands it back through [`BarrierTerm::restore_memory`].
    fn memory(&self) -> Vec<f64> {
        Vec::new()
    }

    /// Whether `memory` (untrusted: a restored state's) is what
    /// [`BarrierTerm::memory`] could have given; a term that carries nothing
    /// takes only the empty list.
    fn check_memory(&self, memory: &[f64]) -> Result<(), MemoryError> {
        no_memory(memory)
    }

    /// Take back what [`BarrierTerm::memory`] gave (empty: as built), checked
    /// by [`BarrierTerm::check_memory`].
    fn restore_memory(&mut self, memory: &[f64]) -> Result<(), MemoryError> {
        self.check_memory(memory)
    }

    /// Largest fraction in (0, 1] of the move `q -> q + dq` (all DOFs) the
    /// term admits (contact: free of collisions); the stepper limits its
    /// Newton steps and predictors to it.
    fn max_step_fraction(&self, asm: &Assembler, q: &[f64], dq: &[f64]) -> f64;

    /// [`BarrierTerm::max_step_fraction`] of a move from the step start:
    /// `q` where the term's moving bodies were at the start, `q + dq` where
    /// they are at the end (the predictors' moves).
    fn max_motion_fraction(&self, asm: &Assembler, q: &[f64], dq: &[f64]) -> f64 {
        self.max_step_fraction(asm, q, dq)
    }

    /// Place the term's moving bodies (moving obstacles, in scene order):
    /// `start` at the step start, `end` at the step end, where the forces
    /// are evaluated.
    fn place(&mut self, _start: &[Motion], _end: &[Motion]) {}

    /// Whether any of the term's bodies moves: a guess that holds the
    /// sheet still is then checked for collisions too.
    fn moves(&self) -> bool {
        false
    }

    /// Largest fraction in (0, 1] of a Newton correction `q -> q + dq`,
    /// with the velocities moving by `dv_dq dq` alongside from `v`, up to
    /// which the term's stiffness stays as the iteration matrix has it
    /// (contact: where a sliding pair's correction would carry it through
    /// sticking to sliding the other way, the fraction at which it comes to
    /// rest); the stepper stops the correction there and forms the matrix
    /// anew.
    fn max_correction_fraction(
        &self,
        _asm: &Assembler,
        _q: &[f64],
        _v: &[f64],
        _dq: &[f64],
        _dv_dq: f64,
    ) -> f64 {
        1.0
    }

    /// Whether the term limits this step's Newton corrections (contact:
    /// pairs within the barrier at the step start); Newton then backtracks.
    fn limits_steps(&self) -> bool;

    /// Whether the term reports powers in [`Evaluation`] (contact:
    /// friction, dashpots) that the stepper integrates over each step: the
    /// stepper then evaluates every accepted state in full.
    fn reports_power(&self) -> bool {
        false
    }

    /// Whether this step's dissipative forces may be nonzero (a term that
    /// reports powers and knows at the step start that they vanish all
    /// step says no: the stepper then skips the full evaluation at the
    /// step's end and takes them as zero there).
    fn dissipates_this_step(&self) -> bool {
        self.reports_power()
    }

    /// The term as self-contact, for the contact reports (typed access,
    /// no downcast).
    fn as_contact(&self) -> Option<&crate::contact::ContactTerm> {
        None
    }

    /// The term as the rigid obstacles' contact, for their reports (typed
    /// access, no downcast).
    fn as_obstacles(&self) -> Option<&crate::contact::ObstacleTerm> {
        None
    }
}

/// A memory check for what carries nothing: only the empty list.
pub(super) fn no_memory(memory: &[f64]) -> Result<(), MemoryError> {
    if memory.is_empty() {
        Ok(())
    } else {
        Err(MemoryError::CarriesNothing {
            values: memory.len(),
        })
    }
}

/// The built-in terms in evaluation order. (Each implementation repeats the
/// trait's `add` signature; `duplicates` reports those lines as shared.)
pub(super) fn built_in() -> Vec<Box<dyn ForceTerm>> {
    vec![
        Box::new(Shell::default()),
        Box::new(CreaseSprings),
        Box::new(MassDamping),
    ]
}

/// Membrane and bending of every facet, with stiffness damping `beta K`.
#[derive(Default)]
struct Shell {
    /// Each facet's membrane resultants at the step start, for the
    /// iteration matrix's membrane geometric stiffness where the assembler
    /// lags it ([`Assembler::lag_membrane_stiffness`]; empty otherwise).
    lagged: Vec<MembraneResultants>,
}

impl Shell {
    fn take_lag(&mut self, asm: &Assembler, q: &[f64]) {
        self.lagged.clear();
        if !asm.lags_membrane_stiffness() {
            return;
        }
        let mat = &asm.physics.material;
        self.lagged.extend(
            asm.elements
                .iter()
                .enumerate()
                .map(|(f, el)| el.membrane_resultants(mat, &local_vector(&asm.layout.local[f], q))),
        );
    }
}

impl ForceTerm for Shell {
    fn name(&self) -> &str {
        "shell"
    }

    fn before_step(&mut self, asm: &Assembler, q: &[f64], _v: &[f64]) -> Vec<(usize, usize)> {
        self.take_lag(asm, q);
        Vec::new()
    }

    fn lag(&mut self, asm: &Assembler, q: &[f64], _v: &[f64]) {
        self.take_lag(asm, q);
    }

    /// Stiffness damping `beta K v` (none unless beta is set).
    fn viscous_force(&self, asm: &Assembler, q: &[f64], v: &[f64], out: &mut [f64]) {
        let p = asm.physics;
        if p.beta == 0.0 {
            return;
        }
        let mut fe = SVector::<f64, 27>::zeros();
        let mut ke = SMatrix::<f64, 27, 27>::zeros();
        for (f, el) in asm.elements.iter().enumerate() {
            let e = local_vector(&asm.layout.local[f], q);
            el.eval_lagged(&p.material, &e, &mut fe, Some(&mut ke), None);
            let ve = local_vector(&asm.layout.local[f], v);
            let mut vv = SVector::<f64, 27>::zeros();
            for (k, vk) in ve.iter().enumerate() {
                vv.fixed_rows_mut::<3>(3 * k).copy_from(vk);
            }
            let fd = p.beta * (ke * vv);
            scatter_force(&asm.face_maps[f], fd.as_slice(), out);
        }
    }

    fn add(
        &self,
        asm: &Assembler,
        st: &State,
        out: &mut Evaluation,
        mut matrix: Option<(&mut [f64], MatrixCoeffs)>,
    ) -> Result<(), EvalError> {
        let p = asm.physics;
        // Stiffness weight in the matrix, and whether element tangents are needed.
        let kw = matrix
            .as_ref()
            .map(|(_, co)| co.k + co.c * p.beta)
            .unwrap_or(0.0);
        let need_tangent = matrix.is_some() || p.beta != 0.0;
        let mut fe = SVector::<f64, 27>::zeros();
        let mut ke = SMatrix::<f64, 27, 27>::zeros();
        for (f, el) in asm.elements.iter().enumerate() {
            let bm = &asm.face_maps[f];
            let e = local_vector(&asm.layout.local[f], st.q);
            let en = el.eval_lagged(
                &p.material,
                &e,
                &mut fe,
                if need_tangent { Some(&mut ke) } else { None },
                self.lagged.get(f),
            );
            out.strain_energy += en.membrane + en.bending;
            if p.beta != 0.0 {
                let ve = local_vector(&asm.layout.local[f], st.v);
                let mut vv = SVector::<f64, 27>::zeros();
                for (k, vk) in ve.iter().enumerate() {
                    vv.fixed_rows_mut::<3>(3 * k).copy_from(vk);
                }
                fe += p.beta * (ke * vv);
            }
            scatter_force(bm, fe.as_slice(), &mut out.force);
            if let Some((vals, _)) = matrix.as_mut() {
                scatter_matrix::<27>(bm, &ke, kw, vals);
            }
        }
        Ok(())
    }
}

/// The rotational springs at both ends of every crease, their applied
/// moments (inputs) and dashpots.
struct CreaseSprings;

impl ForceTerm for CreaseSprings {
    fn name(&self) -> &str {
        "crease springs"
    }

    fn viscous_force(&self, asm: &Assembler, q: &[f64], v: &[f64], out: &mut [f64]) {
        Self::dashpots(asm, q, v, out);
    }

    fn add(
        &self,
        asm: &Assembler,
        st: &State,
        out: &mut Evaluation,
        mut matrix: Option<(&mut [f64], MatrixCoeffs)>,
    ) -> Result<(), EvalError> {
        let p = asm.physics;
        let damping = asm.has_damping();
        let mut f9 = SVector::<f64, 9>::zeros();
        let mut k9 = SMatrix::<f64, 9, 9>::zeros();
        for (i, ce) in asm.creases.iter().enumerate() {
            let [a, b, t] = ce.vectors(st.q);
            let d = crease::theta_derivatives(&a, &b, &t, matrix.is_some());
            let theta = ce.checked_angle(d.theta, &[a, b, t], st.theta_prev[i])?;
            out.theta.push(theta);
            let k = p.crease_k_per_length * ce.length;
            f9.fill(0.0);
            let want_k = matrix.is_some();
            out.crease_energy += crease::spring(
                k,
                theta,
                st.theta0[i],
                &d,
                &mut f9,
                if want_k { Some(&mut k9) } else { None },
            );
            let g = SVector::<f64, 9>::from_iterator(d.grad.iter().flat_map(|x| x.iter().copied()));
            let mom = st.moment[i];
            if mom != 0.0 {
                f9 -= mom * g;
                if want_k && let Some(h) = &d.hess {
                    for r in 0..3 {
                        for c in 0..3 {
                            let blk = h[r][c];
                            for x in 0..3 {
                                for y in 0..3 {
                                    k9[(3 * r + x, 3 * c + y)] -= mom * blk[(x, y)];
                                }
                            }
                        }
                    }
                }
            }
            let cdamp = p.crease_c_per_length * ce.length;
            let mut cmat_w = 0.0;
            if damping && cdamp != 0.0 {
                let vl = [
                    ce.combos[0].eval(st.v),
                    ce.combos[1].eval(st.v),
                    ce.combos[2].eval(st.v),
                ];
                let rate: f64 = (0..3).map(|j| d.grad[j].dot(&vl[j])).sum();
                f9 += cdamp * rate * g;
                cmat_w = matrix.as_ref().map(|(_, co)| co.c * cdamp).unwrap_or(0.0);
            }
            let bm = &asm.crease_maps[i];
            scatter_force(bm, f9.as_slice(), &mut out.force);
            if let Some((vals, co)) = matrix.as_mut() {
                let mut kk = (co.k + co.c * p.beta) * k9;
                if cmat_w != 0.0 {
                    kk += cmat_w * g * g.transpose();
                }
                scatter_matrix::<9>(bm, &kk, 1.0, vals);
            }
        }
        Ok(())
    }
}

impl CreaseSprings {
    /// The dashpots' force `c theta_dot grad theta` of every crease end,
    /// added to `out`.
    fn dashpots(asm: &Assembler, q: &[f64], v: &[f64], out: &mut [f64]) {
        let cl = asm.physics.crease_c_per_length;
        if !asm.has_damping() || cl == 0.0 {
            return;
        }
        for (i, ce) in asm.creases.iter().enumerate() {
            let [a, b, t] = ce.vectors(q);
            let d = crease::theta_derivatives(&a, &b, &t, false);
            let vl = [
                ce.combos[0].eval(v),
                ce.combos[1].eval(v),
                ce.combos[2].eval(v),
            ];
            let rate: f64 = (0..3).map(|j| d.grad[j].dot(&vl[j])).sum();
            let f9 = d.grad9() * (cl * ce.length * rate);
            scatter_force(&asm.crease_maps[i], f9.as_slice(), out);
        }
    }
}

/// Mass damping `alpha M (v - P v)`, `P v` the M-orthogonal rigid part of
/// `v` that the supports allow (rigid motion is not damped); on a sheet
/// held by frames, `alpha M (v - v_F)`, `v_F` the frames' rigid motion.
struct MassDamping;

impl MassDamping {
    /// `alpha M (v - P v)` at `(q, v)` (held by frames: `alpha M (v - v_F)`),
    /// added to `out`.
    fn force(asm: &Assembler, q: &[f64], v: &[f64], out: &mut [f64]) {
        let alpha = asm.physics.alpha;
        let n = asm.n_dofs();
        let mut mv = vec![0.0; n];
        let mut pv = vec![0.0; n];
        if !asm.rigid.held().is_empty() {
            // Held by frames: the velocity relative to their rigid motion.
            // (Its dependence on q, alpha M [w x] on the positions, is left
            // out of the matrix: alpha |w| against its c alpha M.)
            let mut rel = v.to_vec();
            if let Some([t, w, c]) = asm.rigid.frame_velocity(q, v) {
                let mut vr = vec![0.0; n];
                asm.rigid.rigid_velocity(q, t, w, c, &mut vr);
                rel.iter_mut().zip(&vr).for_each(|(x, r)| *x -= r);
            }
            asm.mass_mul(&rel, &mut mv);
        } else if asm.rigid.n_allowed() > 0 {
            let mut mq = vec![0.0; n];
            asm.mass_mul_n([v, q], [&mut mv, &mut mq]);
            if asm.rigid.rigid_momentum(q, &mv, &mq, &mut pv).is_none() {
                pv.fill(0.0);
            }
        } else {
            // A clamped sheet has no rigid motion: nothing to project.
            asm.mass_mul(v, &mut mv);
        }
        for ((f, x), r) in out.iter_mut().zip(mv).zip(pv) {
            *f += alpha * (x - r);
        }
    }
}

impl ForceTerm for MassDamping {
    fn name(&self) -> &str {
        "mass damping"
    }

    fn add(
        &self,
        asm: &Assembler,
        st: &State,
        out: &mut Evaluation,
        matrix: Option<(&mut [f64], MatrixCoeffs)>,
    ) -> Result<(), EvalError> {
        let alpha = asm.physics.alpha;
        if alpha == 0.0 {
            return Ok(());
        }
        // The sparse matrix takes c alpha M; the rigid projection's
        // -c alpha M P is dense and comes as a low-rank part.
        if let Some((vals, co)) = matrix {
            let w = co.c * alpha;
            for (v, m) in vals.iter_mut().zip(&asm.mass_values) {
                *v += w * m;
            }
        }
        Self::force(asm, st.q, st.v, &mut out.force);
        Ok(())
    }

    fn viscous_force(&self, asm: &Assembler, q: &[f64], v: &[f64], out: &mut [f64]) {
        if asm.physics.alpha != 0.0 {
            Self::force(asm, q, v, out);
        }
    }

    /// `-c alpha M P = -U (G / (c alpha))^-1 U^T` (the dependence of the
    /// rigid modes on `q` is left out: second order in the rigid part of
    /// the velocity). Without it modified, and even full, Newton contracts
    /// at a rate of about `alpha h` on the sheet's rigid motion.
    fn low_rank(&self, asm: &Assembler, q: &[f64], co: MatrixCoeffs) -> Option<LowRank> {
        let w = co.c * asm.physics.alpha;
        if w == 0.0 || asm.rigid.n_allowed() == 0 {
            return None;
        }
        let mut mq = vec![0.0; asm.n_dofs()];
        asm.mass_mul(q, &mut mq);
        let (u, g) = asm.rigid.momentum_basis(q, &mq)?;
        Some(LowRank { u, s: g / w })
    }
}
