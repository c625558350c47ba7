//! Self-contact's lagged dashpots and friction: per-pair data, forces, matrices, friction's stop.

use super::ContactTerm;
use super::candidates::CandidateCache;
use super::pairs::{Kind, PairKey};
use crate::assembly::{Evaluation, MatrixCoeffs};
use crate::contact::potentials::{
    ddb, friction_matrix, reversal_fraction, slip_factor, tangent_basis,
};
use nalgebra::{Matrix3, SMatrix, SVector, Vector2, Vector3};

/// Dashpot and friction data of one pair, lagged from the start of the
/// step: within a step both are smooth in the iterate (a coefficient read
/// from the iterate's own gap would put `sqrt(b''(s))`, whose slope is
/// infinite where a pair enters the barrier, into Newton's residual).
#[derive(Clone, Debug)]
pub(super) struct Lagged {
    /// Edge-edge or not: with `ids`, the pair's key.
    edge: bool,
    pub(super) ids: [usize; 4],
    /// Normal dashpot coefficient (N s/m).
    c: f64,
    /// Relative velocity at the closest points: `sum w_i v_i`.
    w: [f64; 4],
    /// Unit normal at the closest points (second side to first).
    normal: Vector3<f64>,
    /// Orthonormal tangent basis.
    basis: [Vector3<f64>; 2],
    /// Normal force (N).
    lambda: f64,
    /// Tangential relative velocity at the step start (in `basis`).
    slide: Vector2<f64>,
}

impl Lagged {
    pub(super) fn key(&self) -> PairKey {
        (self.edge, self.ids)
    }
}

impl ContactTerm {
    /// Pair stiffnesses, dashpot coefficients, friction's normal forces and
    /// bases from contact-vertex positions `x` and velocities `v`.
    /// `old` is the candidate cache the step start replaced, if it did.
    pub(super) fn lag_at(
        &mut self,
        x: &[Vector3<f64>],
        v: &[Vector3<f64>],
        old: Option<&CandidateCache>,
    ) {
        self.set_stiffnesses(x, v, old);
        self.x_start.clear();
        self.x_start.extend_from_slice(x);
        self.v_start.clear();
        self.v_start.extend_from_slice(v);
        self.lagged.clear();
        let act = self.active(x).unwrap_or_default();
        self.touching = !act.is_empty();
        for (p, s, kappa) in act {
            let xs = self.points(x, &p);
            let (w, n) = self.closest(&p, &xs);
            // Critical for zeta = 1 at the pair's barrier stiffness.
            let k = kappa * ddb(s, self.s_hat_of(&p)).max(0.0);
            let basis = tangent_basis(&n);
            let ids = p.ids();
            let vr: Vector3<f64> = (0..4).map(|k| w[k] * v[ids[k]]).sum();
            self.lagged.push(Lagged {
                edge: matches!(p.kind, Kind::EdgeEdge { .. }),
                ids,
                c: 2.0 * self.zeta * (k * p.mass).sqrt(),
                w,
                normal: n,
                basis,
                lambda: self.normal_force(&p, &xs, s, kappa),
                slide: Vector2::new(basis[0].dot(&vr), basis[1].dot(&vr)),
            });
        }
    }

    /// The fraction of a Newton correction at which the first sliding
    /// friction pair it would carry through sticking (to sliding the other
    /// way, beyond the stick velocity) comes closest to rest; 1 if none.
    /// In slip the friction force is constant along the slide and Newton's
    /// linear model does not see it stop, so a correction that should stop
    /// a pair overshoots to the opposite slip, and the next one back: the
    /// iteration cycles (a line search only creeps towards the stick). At
    /// rest the pair's stick stiffness is in the next matrix.
    pub fn friction_fraction(&self, v: &[f64], dq: &[f64], dv_dq: f64) -> f64 {
        if self.mu <= 0.0 || self.lagged.is_empty() {
            return 1.0;
        }
        let mut t: f64 = 1.0;
        let at = |x: &[f64], i: usize| -> Vector3<f64> {
            crate::contact::surface::eval_map(&self.surf.maps[i], x)
        };
        for lg in self.lagged.iter().filter(|lg| lg.lambda > 0.0) {
            let vr: Vector3<f64> = (0..4).map(|k| lg.w[k] * at(v, lg.ids[k])).sum();
            let dr: Vector3<f64> = (0..4)
                .map(|k| lg.w[k] * at(dq, lg.ids[k]))
                .sum::<Vector3<f64>>()
                * dv_dq;
            let u = Vector2::new(lg.basis[0].dot(&vr), lg.basis[1].dot(&vr));
            let du = Vector2::new(lg.basis[0].dot(&dr), lg.basis[1].dot(&dr));
            if let Some(stop) = reversal_fraction(u, du, lg.slide, self.eps_v)
                && stop < t
            {
                t = stop;
            }
        }
        t
    }

    /// The iteration matrix of a lagged pair's dashpot and friction (`co.c`
    /// times their velocity derivatives) over its four points, at contact
    /// vertex velocities `v` (none if neither acts).
    pub(super) fn lagged_matrix(
        &self,
        lg: &Lagged,
        v: &[Vector3<f64>],
        co: &MatrixCoeffs,
    ) -> Option<SMatrix<f64, 12, 12>> {
        if lg.c <= 0.0 && self.mu <= 0.0 {
            return None;
        }
        let mut k3 = Matrix3::zeros();
        if lg.c > 0.0 {
            k3 += (co.c * lg.c) * lg.normal * lg.normal.transpose();
        }
        if self.mu > 0.0 {
            // d f / d v_rel = mu lambda T [phi I + (phi'/y) u u^T] T^T.
            let vr: Vector3<f64> = (0..4).map(|k| lg.w[k] * v[lg.ids[k]]).sum();
            let u = Vector2::new(lg.basis[0].dot(&vr), lg.basis[1].dot(&vr));
            let slip = slip_factor(u.norm(), self.eps_v);
            k3 += friction_matrix(co.c * self.mu * lg.lambda, &lg.basis, u, slip);
        }
        let mut h = SMatrix::<f64, 12, 12>::zeros();
        for a in 0..4 {
            for b in 0..4 {
                h.fixed_view_mut::<3, 3>(3 * a, 3 * b)
                    .copy_from(&(lg.w[a] * lg.w[b] * k3));
            }
        }
        Some(h)
    }

    /// Add the lagged pairs' dashpot and friction forces at contact-vertex
    /// velocities `v` to `out` (forces, their dissipative parts, powers).
    pub(super) fn add_lagged_forces(&self, v: &[Vector3<f64>], out: &mut Evaluation) {
        // Dashpots on the gap rates along the lagged normals, with the
        // lagged coefficients and closest-point weights (the pair's own
        // distance gradient would turn tangential once a sample slides off
        // its triangle within the step, and damp the slide).
        for lg in self.lagged.iter().filter(|lg| lg.c > 0.0) {
            let vr: Vector3<f64> = (0..4).map(|k| lg.w[k] * v[lg.ids[k]]).sum();
            let rate = lg.normal.dot(&vr);
            out.contact_damping_power += lg.c * rate * rate;
            let mut g = SVector::<f64, 12>::zeros();
            for k in 0..4 {
                g.fixed_rows_mut::<3>(3 * k)
                    .copy_from(&((lg.c * rate * lg.w[k]) * lg.normal));
            }
            self.scatter_force(&lg.ids, &g, &mut out.force);
            self.scatter_force(&lg.ids, &g, &mut out.dissipative_force.damping);
        }
        // Friction with the lagged normal forces and bases.
        for lg in self.lagged.iter().filter(|_| self.mu > 0.0) {
            let vr: Vector3<f64> = (0..4).map(|k| lg.w[k] * v[lg.ids[k]]).sum();
            let u = Vector2::new(lg.basis[0].dot(&vr), lg.basis[1].dot(&vr));
            let y = u.norm();
            let (phi, _) = slip_factor(y, self.eps_v);
            let ml = self.mu * lg.lambda;
            let ut = lg.basis[0] * u.x + lg.basis[1] * u.y;
            let fr = ml * phi * ut;
            out.friction_power += fr.dot(&vr);
            let mut g = SVector::<f64, 12>::zeros();
            for k in 0..4 {
                g.fixed_rows_mut::<3>(3 * k).copy_from(&(lg.w[k] * fr));
            }
            self.scatter_force(&lg.ids, &g, &mut out.force);
            self.scatter_force(&lg.ids, &g, &mut out.dissipative_force.friction);
        }
    }
}
