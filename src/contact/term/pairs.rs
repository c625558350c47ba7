//! One pair of primitives: what it joins, its key, distance, closest points, energy and force.

use super::ContactTerm;
use crate::contact::distance::{self, V3};
use crate::contact::distance_derivatives::{
    edge_edge_mollifier_derivatives, edge_edge_points, edge_edge_sq_derivatives,
    point_triangle_points, point_triangle_sq_derivatives,
};
use crate::contact::potentials::{barrier, db, ddb};
use crate::contact::scalar::{Dual2, Real};
use nalgebra::Vector3;

/// Which primitives a pair joins (contact vertex indices).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Kind {
    /// Point `p` against triangle `t`.
    PointTriangle { p: usize, t: [usize; 3] },
    /// Edge `a` against edge `b`, with the mollifier threshold from rest.
    EdgeEdge {
        a: [usize; 2],
        b: [usize; 2],
        eps_x: f64,
    },
}

#[derive(Clone, Copy, Debug)]
pub(super) struct Pair {
    pub(super) kind: Kind,
    /// Sample mass for the dashpot (kg).
    pub(super) mass: f64,
    /// Distance the pair keeps (m): the contact thickness, or less between
    /// neighbouring facets (see [`ContactTerm::candidates`]).
    pub(super) xi: f64,
}

impl Pair {
    /// Whether the pair's primitives at `xs` are farther than `d` apart by
    /// an axis-aligned bound (false says nothing).
    pub(super) fn apart(&self, xs: &[Vector3<f64>; 4], d: f64) -> bool {
        let k = match self.kind {
            Kind::PointTriangle { .. } => 1,
            Kind::EdgeEdge { .. } => 2,
        };
        distance::axis_apart(xs, k, d)
    }

    pub(super) fn ids(&self) -> [usize; 4] {
        match self.kind {
            Kind::PointTriangle { p, t } => [p, t[0], t[1], t[2]],
            Kind::EdgeEdge { a, b, .. } => [a[0], a[1], b[0], b[1]],
        }
    }
}

/// A pair's identity: edge-edge or not, and its four contact vertices.
pub(super) type PairKey = (bool, [usize; 4]);

pub(super) fn key(p: &Pair) -> PairKey {
    (matches!(p.kind, Kind::EdgeEdge { .. }), p.ids())
}

/// The index of a pair with `p`'s key in `pairs` (in the canonical order).
pub(super) fn find_key(pairs: &[Pair], p: &Pair) -> Option<usize> {
    let k = key(p);
    pairs.binary_search_by(|q| key(q).cmp(&k)).ok()
}

/// Points in the scalar type, each coordinate variable `3k + c`.
pub(super) fn lift<T: Real>(x: &[Vector3<f64>; 4]) -> [V3<T>; 4] {
    V3::stencil(x)
}

pub(super) fn distance_sq<T: Real>(kind: &Kind, x: &[V3<T>; 4]) -> T {
    match kind {
        Kind::PointTriangle { .. } => {
            distance::point_triangle_distance_sq(&x[0], &x[1], &x[2], &x[3])
        }
        Kind::EdgeEdge { .. } => distance::edge_edge_distance_sq(&x[0], &x[1], &x[2], &x[3]),
    }
}

pub(super) fn mollifier<T: Real>(kind: &Kind, x: &[V3<T>; 4]) -> T {
    match kind {
        Kind::PointTriangle { .. } => T::cst(1.0),
        Kind::EdgeEdge { eps_x, .. } => {
            distance::edge_edge_mollifier(&x[0], &x[1], &x[2], &x[3], *eps_x)
        }
    }
}

impl ContactTerm {
    pub(super) fn edge_pair(&self, a: [usize; 2], b: [usize; 2], mass: f64) -> Pair {
        let r = &self.surf.rest;
        let eps_x = distance::mollifier_threshold(&r[a[0]], &r[a[1]], &r[b[0]], &r[b[1]]);
        Pair {
            kind: Kind::EdgeEdge { a, b, eps_x },
            mass,
            xi: self.xi,
        }
    }

    pub(super) fn rest_distance(&self, p: &Pair) -> f64 {
        let r = &self.surf.rest;
        let ids = p.ids();
        let x = [r[ids[0]], r[ids[1]], r[ids[2]], r[ids[3]]];
        distance_sq::<f64>(&p.kind, &lift(&x)).sqrt()
    }

    /// A pair's barrier width (m): the same share of its thickness for all.
    pub(super) fn s_hat_of(&self, p: &Pair) -> f64 {
        self.s_hat * p.xi / self.xi
    }

    pub(super) fn points(&self, x: &[Vector3<f64>], p: &Pair) -> [Vector3<f64>; 4] {
        let ids = p.ids();
        [x[ids[0]], x[ids[1]], x[ids[2]], x[ids[3]]]
    }

    /// Normal force of a pair at gap `s` (N): `-kappa m(x) b'(s)`.
    pub(super) fn normal_force(&self, p: &Pair, xs: &[Vector3<f64>; 4], s: f64, kappa: f64) -> f64 {
        kappa * mollifier::<f64>(&p.kind, &lift(xs)) * -db(s, self.s_hat_of(p))
    }

    /// Closest-point weights (relative velocity `sum w_i v_i`) and the unit
    /// normal of a pair.
    pub(super) fn closest(&self, p: &Pair, x: &[Vector3<f64>; 4]) -> ([f64; 4], Vector3<f64>) {
        let w = match p.kind {
            Kind::PointTriangle { .. } => {
                let b = distance::point_triangle_closest(&x[0], &x[1], &x[2], &x[3]);
                [1.0, -b[0], -b[1], -b[2]]
            }
            Kind::EdgeEdge { .. } => {
                let (s, t) = distance::edge_edge_closest(&x[0], &x[1], &x[2], &x[3]);
                [1.0 - s, s, -(1.0 - t), -t]
            }
        };
        let r: Vector3<f64> = (0..4).map(|k| w[k] * x[k]).sum();
        let n = if r.norm() > 0.0 {
            r.normalize()
        } else {
            Vector3::z()
        };
        (w, n)
    }

    /// Pair energy `kappa m(x) b(s(x))` with its gradient and Hessian in the
    /// 12 stencil coordinates, from the closed-form derivatives of the
    /// squared distance `D` (and of the edge-edge mollifier `m`).
    /// Also the stencil points the energy depends on.
    pub(super) fn energy_derivatives(
        &self,
        p: &Pair,
        x: &[Vector3<f64>; 4],
        k: f64,
    ) -> (Dual2<12>, &'static [usize]) {
        let [a, b, c, d] = x;
        match p.kind {
            Kind::PointTriangle { .. } => {
                let ty = distance::point_triangle_type(a, b, c, d);
                let f = self.barrier_of_sq(p, point_triangle_sq_derivatives(ty, x), k);
                (f, point_triangle_points(ty))
            }
            Kind::EdgeEdge { eps_x, .. } => {
                let ty = distance::edge_edge_type(a, b, c, d);
                let f = self.barrier_of_sq(p, edge_edge_sq_derivatives(ty, x), k);
                match edge_edge_mollifier_derivatives(x, eps_x) {
                    Some(m) => (f * m, &[0, 1, 2, 3]),
                    None => (f, edge_edge_points(ty)),
                }
            }
        }
    }

    /// `k b(sqrt(D) - xi)` of the squared distance `D` by one chain rule
    /// in `D` (its derivatives in closed form), `k` the pair's stiffness.
    fn barrier_of_sq<T: Real>(&self, p: &Pair, d2: T, k: f64) -> T {
        let dv = d2.val();
        let r = dv.sqrt();
        let s = r - p.xi;
        let s_hat = self.s_hat_of(p);
        let (b1, b2) = (db(s, s_hat), ddb(s, s_hat));
        // ds/dD and d2s/dD2.
        let (sd, sdd) = (0.5 / r, -0.25 / (r * dv));
        d2.map(
            k * barrier(s, s_hat),
            k * b1 * sd,
            k * (b2 * sd * sd + b1 * sdd),
        )
    }
}
