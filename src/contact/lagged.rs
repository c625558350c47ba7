//! What self-contact and the obstacles lag from the step start, and friction's force and stop on it.

use super::potentials::{ddb, reversal_fraction, slip_factor, tangent_basis};
use nalgebra::{Vector2, Vector3};

/// Dashpot and friction data of one pair, lagged from the start of the
/// step: within a step both are smooth in the iterate (a coefficient read
/// from the iterate's own gap would put `sqrt(b''(s))`, whose slope is
/// infinite where a pair enters the barrier, into Newton's residual).
/// `pair` says which pair it is and where its relative velocity is read.
#[derive(Clone, Debug)]
pub(crate) struct Lagged<P> {
    pub(crate) pair: P,
    /// Normal dashpot coefficient (N s/m).
    pub(crate) c: f64,
    /// Unit normal at the closest points, towards the pair's first side
    /// (from the second primitive to the first; an obstacle's outward
    /// normal).
    pub(crate) normal: Vector3<f64>,
    /// Orthonormal tangent basis.
    pub(crate) basis: [Vector3<f64>; 2],
    /// Normal force (N).
    pub(crate) lambda: f64,
    /// Tangential relative velocity at the step start (in `basis`).
    pub(crate) slide: Vector2<f64>,
}

/// The normal dashpot coefficient `2 zeta sqrt(k m)` of a pair of sample
/// mass `mass` at gap `s` in a barrier of width `s_hat` and stiffness
/// `kappa`: critical for `zeta = 1` at the barrier's stiffness there,
/// `k = kappa b''(s)`.
pub(crate) fn dashpot(zeta: f64, kappa: f64, mass: f64, s: f64, s_hat: f64) -> f64 {
    let k = kappa * ddb(s, s_hat).max(0.0);
    2.0 * zeta * (k * mass).sqrt()
}

impl<P> Lagged<P> {
    /// Pair `pair` at the step start: its dashpot coefficient `c`, unit
    /// `normal`, normal force `lambda` and relative velocity `vr` at the
    /// closest points.
    pub(crate) fn new(
        pair: P,
        c: f64,
        normal: Vector3<f64>,
        lambda: f64,
        vr: &Vector3<f64>,
    ) -> Self {
        let basis = tangent_basis(&normal);
        Lagged {
            pair,
            c,
            normal,
            basis,
            lambda,
            slide: Vector2::new(basis[0].dot(vr), basis[1].dot(vr)),
        }
    }

    /// The tangential part of a relative velocity `vr`, in `basis`.
    pub(crate) fn tangential(&self, vr: &Vector3<f64>) -> Vector2<f64> {
        Vector2::new(self.basis[0].dot(vr), self.basis[1].dot(vr))
    }

    /// Smoothed Coulomb friction `mu lambda f1(|u|) u/|u|` at relative
    /// velocity `vr` (`eps_v` the stick velocity), with the tangential
    /// velocity `u` and the [`slip_factor`] it was taken at.
    pub(crate) fn friction(
        &self,
        mu: f64,
        eps_v: f64,
        vr: &Vector3<f64>,
    ) -> (Vector3<f64>, Vector2<f64>, (f64, f64)) {
        let u = self.tangential(vr);
        let slip = slip_factor(u.norm(), eps_v);
        let ml = mu * self.lambda;
        let ut = self.basis[0] * u.x + self.basis[1] * u.y;
        ((ml * slip.0) * ut, u, slip)
    }
}

/// What a barrier term lags from the step start: the sample positions and
/// velocities there (a pair first met within the step takes the stiffness
/// it would have been given at them), and the pairs then in the barrier.
#[derive(Clone, Debug)]
pub(crate) struct StepStart<P> {
    pub(crate) x: Vec<Vector3<f64>>,
    pub(crate) v: Vec<Vector3<f64>>,
    pub(crate) lagged: Vec<Lagged<P>>,
}

impl<P> Default for StepStart<P> {
    fn default() -> Self {
        StepStart {
            x: Vec::new(),
            v: Vec::new(),
            lagged: Vec::new(),
        }
    }
}

impl<P> StepStart<P> {
    /// A step starting at sample positions `x` and velocities `v`, with
    /// no pair lagged yet.
    pub(crate) fn begin(&mut self, x: &[Vector3<f64>], v: &[Vector3<f64>]) {
        self.x.clear();
        self.x.extend_from_slice(x);
        self.v.clear();
        self.v.extend_from_slice(v);
        self.lagged.clear();
    }

    /// The fraction of a Newton correction at which the first sliding
    /// friction pair it would carry through sticking (to sliding the other
    /// way, beyond the stick velocity `eps_v`) comes closest to rest; 1 if
    /// none. `rates` gives a pair's relative velocity at the closest points
    /// and its change over the correction, or None where the pair has no
    /// friction. In slip the friction force is constant along the slide and
    /// Newton's linear model does not see it stop, so a correction that
    /// should stop a pair overshoots to the opposite slip, and the next one
    /// back: the iteration cycles (a line search only creeps towards the
    /// stick). At rest the pair's stick stiffness is in the next matrix.
    pub(crate) fn friction_fraction(
        &self,
        eps_v: f64,
        rates: impl Fn(&Lagged<P>) -> Option<(Vector3<f64>, Vector3<f64>)>,
    ) -> f64 {
        let mut t: f64 = 1.0;
        for lg in self.lagged.iter().filter(|lg| lg.lambda > 0.0) {
            let Some((vr, dr)) = rates(lg) else {
                continue;
            };
            let (u, du) = (lg.tangential(&vr), lg.tangential(&dr));
            if let Some(stop) = reversal_fraction(u, du, lg.slide, eps_v) {
                t = t.min(stop);
            }
        }
        t
    }
}
