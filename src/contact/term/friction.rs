//! Self-contact's lagged dashpots and friction: per-pair data, forces, matrices, friction's stop.

use super::ContactTerm;
use super::candidates::CandidateCache;
use super::pairs::{Kind, PairKey};
use crate::assembly::{Evaluation, MatrixCoeffs};
use crate::contact::lagged::{Lagged, dashpot};
use crate::contact::potentials::{friction_matrix, slip_factor};
use crate::contact::surface::eval_map;
use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

/// A self-contact pair as its lagged data reads it: its key, and the
/// closest-point weights `w` of its four contact vertices (the relative
/// velocity at the closest points is `sum w_i v_i`).
#[derive(Clone, Copy, Debug)]
pub(super) struct Stencil {
    /// Edge-edge or not: with `ids`, the pair's key.
    edge: bool,
    pub(super) ids: [usize; 4],
    w: [f64; 4],
}

impl Stencil {
    pub(super) fn key(&self) -> PairKey {
        (self.edge, self.ids)
    }

    /// The relative velocity at the closest points at contact-vertex
    /// velocities `v`.
    fn velocity(&self, v: &[Vector3<f64>]) -> Vector3<f64> {
        (0..4).map(|k| self.w[k] * v[self.ids[k]]).sum()
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
        self.at_start.begin(x, v);
        let act = self.active(x).unwrap_or_default();
        self.touching = !act.is_empty();
        for (p, s, kappa) in act {
            let xs = self.points(x, &p);
            let (w, n) = self.closest(&p, &xs);
            let pair = Stencil {
                edge: matches!(p.kind, Kind::EdgeEdge { .. }),
                ids: p.ids(),
                w,
            };
            let c = dashpot(self.zeta, kappa, p.mass, s, self.s_hat_of(&p));
            let lambda = self.normal_force(&p, &xs, s, kappa);
            let lagged = Lagged::new(pair, c, n, lambda, &pair.velocity(v));
            self.at_start.lagged.push(lagged);
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
        if self.mu <= 0.0 || self.at_start.lagged.is_empty() {
            return 1.0;
        }
        let at = |x: &[f64], i: usize| eval_map(&self.surf.maps[i], x);
        self.at_start.friction_fraction(self.eps_v, |lg| {
            let Stencil { ids, w, .. } = lg.pair;
            let vr: Vector3<f64> = (0..4).map(|k| w[k] * at(v, ids[k])).sum();
            let dr: Vector3<f64> =
                (0..4).map(|k| w[k] * at(dq, ids[k])).sum::<Vector3<f64>>() * dv_dq;
            Some((vr, dr))
        })
    }

    /// The iteration matrix of a lagged pair's dashpot and friction (`co.c`
    /// times their velocity derivatives) over its four points, at contact
    /// vertex velocities `v` (none if neither acts).
    pub(super) fn lagged_matrix(
        &self,
        lg: &Lagged<Stencil>,
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
            let u = lg.tangential(&lg.pair.velocity(v));
            let slip = slip_factor(u.norm(), self.eps_v);
            k3 += friction_matrix(co.c * self.mu * lg.lambda, &lg.basis, u, slip);
        }
        let w = lg.pair.w;
        let mut h = SMatrix::<f64, 12, 12>::zeros();
        for a in 0..4 {
            for b in 0..4 {
                h.fixed_view_mut::<3, 3>(3 * a, 3 * b)
                    .copy_from(&(w[a] * w[b] * k3));
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
        for lg in self.at_start.lagged.iter().filter(|lg| lg.c > 0.0) {
            let ids = lg.pair.ids;
            let rate = lg.normal.dot(&lg.pair.velocity(v));
            out.contact_damping_power += lg.c * rate * rate;
            let mut g = SVector::<f64, 12>::zeros();
            for k in 0..4 {
                g.fixed_rows_mut::<3>(3 * k)
                    .copy_from(&((lg.c * rate * lg.pair.w[k]) * lg.normal));
            }
            self.scatter_force(&ids, &g, &mut out.force);
            self.scatter_force(&ids, &g, &mut out.dissipative_force.damping);
        }
        // Friction with the lagged normal forces and bases.
        for lg in self.at_start.lagged.iter().filter(|_| self.mu > 0.0) {
            let ids = lg.pair.ids;
            let vr = lg.pair.velocity(v);
            let (fr, _, _) = lg.friction(self.mu, self.eps_v, &vr);
            out.friction_power += fr.dot(&vr);
            let mut g = SVector::<f64, 12>::zeros();
            for k in 0..4 {
                g.fixed_rows_mut::<3>(3 * k).copy_from(&(lg.pair.w[k] * fr));
            }
            self.scatter_force(&ids, &g, &mut out.force);
            self.scatter_force(&ids, &g, &mut out.dissipative_force.friction);
        }
    }
}
