//! Rigid frames that hold parts of the sheet (attachments): a frame's pose,
//! the values it prescribes to the slots it holds, and the wrench that
//! generalized forces on held slots exert on a frame.
//!
//! A frame at pose (x, R) holds a vertex's position slot at
//! `R (X - X0) + x` and each of its gradient slots at `R G0` (`X`, `G0`
//! their reference values, `X0` the frame's origin in the reference). The
//! pose is an origin `x` and a rotation vector `r` (`R = exp([r x])`,
//! Rodrigues' formula).
//!
//! Wrench: a small motion of the frame, `dx` and a rotation `dtheta` about
//! its origin (`dR = [dtheta x] R`), moves a held position `p` by
//! `dx + dtheta x (p - x)` and a held gradient `g` by `dtheta x g`
//! (gradients do not translate). Generalized forces `r_s` on the held slots
//! then do the virtual work `F . dx + M . dtheta` with
//!
//! ```text
//! F = sum_pos r_s,    M = sum_pos (p_s - x) x r_s + sum_grad g_s x r_s:
//! ```
//!
//! a force on a gradient slot is a force couple. With `r` the residual of
//! the equation of motion at the held slots (`f_ext - M qdd - f_int`), `F`
//! and `M` are the force and moment the sheet exerts on the frame, about
//! its origin, in world axes. In a static state `r = -dV/dq` there (`V`
//! the sheet's potential energy), so the wrench is minus the derivative of
//! `V` with respect to the frame's pose (tested against finite differences
//! in `model::attach`).

use crate::dofs::{DofLayout, SlotKind};
use crate::ids::VertexId;
use nalgebra::{Matrix3, Vector3};

/// Below this angle (rad) the rotation formulas use their series.
const SMALL_ANGLE: f64 = 1e-4;

/// `[a x]`, the matrix of the cross product with `a`.
pub fn cross_matrix(a: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -a.z, a.y, a.z, 0.0, -a.x, -a.y, a.x, 0.0)
}

/// The rotation `exp([r x])` of the rotation vector `r` (axis times angle,
/// rad): Rodrigues' formula.
pub fn rotation(r: &Vector3<f64>) -> Matrix3<f64> {
    let t2 = r.norm_squared();
    let t = t2.sqrt();
    let (a, b) = if t < SMALL_ANGLE {
        (1.0 - t2 / 6.0, 0.5 - t2 / 24.0)
    } else {
        (t.sin() / t, (1.0 - t.cos()) / t2)
    };
    let k = cross_matrix(r);
    Matrix3::identity() + a * k + b * k * k
}

/// The left Jacobian of the rotation vector: the angular velocity (world
/// axes) of `R(r(t))` is `J(r) dr/dt`.
pub fn left_jacobian(r: &Vector3<f64>) -> Matrix3<f64> {
    let t2 = r.norm_squared();
    let t = t2.sqrt();
    let (a, b) = if t < SMALL_ANGLE {
        (0.5 - t2 / 24.0, 1.0 / 6.0 - t2 / 120.0)
    } else {
        ((1.0 - t.cos()) / t2, (t - t.sin()) / (t2 * t))
    };
    let k = cross_matrix(r);
    Matrix3::identity() + a * k + b * k * k
}

/// A frame's pose: origin (m) and rotation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// Origin, world coordinates.
    pub origin: Vector3<f64>,
    /// Rotation from the reference orientation.
    pub rotation: Matrix3<f64>,
}

impl Pose {
    /// The pose of origin `x` and rotation vector `r`.
    pub fn new(x: Vector3<f64>, r: &Vector3<f64>) -> Pose {
        Pose {
            origin: x,
            rotation: rotation(r),
        }
    }
}

/// A rigid body's placement with its velocity: the pose from its inputs
/// (origin and rotation vector), the origin's velocity and the angular
/// velocity (world axes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Motion {
    /// Where it is.
    pub pose: Pose,
    /// The rotation vector `pose.rotation` was made from (rad).
    pub rotation_vector: Vector3<f64>,
    /// Velocity of the origin (m/s).
    pub velocity: Vector3<f64>,
    /// Angular velocity (rad/s).
    pub angular: Vector3<f64>,
}

impl Motion {
    /// The number of values [`Motion::values`] gives.
    pub const VALUES: usize = 12;

    /// At origin `x` and rotation vector `r`, moving with origin velocity
    /// `v` and angular velocity `w`.
    pub fn new(x: Vector3<f64>, r: Vector3<f64>, v: Vector3<f64>, w: Vector3<f64>) -> Motion {
        Motion {
            pose: Pose::new(x, &r),
            rotation_vector: r,
            velocity: v,
            angular: w,
        }
    }

    /// At rest at origin `x`, not turned.
    pub fn at_rest(x: Vector3<f64>) -> Motion {
        Motion::new(x, Vector3::zeros(), Vector3::zeros(), Vector3::zeros())
    }

    /// Origin, rotation vector, velocity and angular velocity in a row.
    pub fn values(&self) -> [f64; Motion::VALUES] {
        let mut out = [0.0; Motion::VALUES];
        for (k, v) in [
            &self.pose.origin,
            &self.rotation_vector,
            &self.velocity,
            &self.angular,
        ]
        .into_iter()
        .enumerate()
        {
            out[3 * k..3 * k + 3].copy_from_slice(v.as_slice());
        }
        out
    }

    /// The motion of [`Motion::values`]' row (`x` holds at least
    /// [`Motion::VALUES`] numbers).
    pub fn from_values(x: &[f64]) -> Motion {
        let v = |k: usize| Vector3::new(x[3 * k], x[3 * k + 1], x[3 * k + 2]);
        Motion::new(v(0), v(1), v(2), v(3))
    }

    /// The velocity of the body's point at `p`.
    pub fn point_velocity(&self, p: &Vector3<f64>) -> Vector3<f64> {
        self.velocity + self.angular.cross(&(p - self.pose.origin))
    }
}

/// One slot a frame holds: which, whether it is a position, and its
/// reference value relative to the frame (`X - X0` or `G0`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeldSlot {
    /// Slot index.
    pub slot: usize,
    /// A position slot (else a gradient).
    pub position: bool,
    /// `X - X0` for a position, `G0` for a gradient.
    pub reference: Vector3<f64>,
}

/// The slots a frame holds and where they are in its reference pose.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HeldSlots {
    /// The frame's origin in the reference.
    pub origin: Vector3<f64>,
    /// The held slots.
    pub slots: Vec<HeldSlot>,
}

impl HeldSlots {
    /// Every slot of `vertices` (positions and gradients) at the reference
    /// slot values `q_ref`, relative to the reference origin `origin`;
    /// slots for which `taken` is true are left out (and are marked taken).
    pub fn new(
        layout: &DofLayout,
        q_ref: &[f64],
        vertices: &[VertexId],
        origin: Vector3<f64>,
        taken: &mut [bool],
    ) -> HeldSlots {
        let mut slots = Vec::new();
        for &v in vertices {
            for s in layout.vertex_slots(v) {
                if taken[s] {
                    continue;
                }
                taken[s] = true;
                let position = layout.slot_kind[s] == SlotKind::Position;
                let x = Vector3::new(q_ref[3 * s], q_ref[3 * s + 1], q_ref[3 * s + 2]);
                let reference = if position { x - origin } else { x };
                slots.push(HeldSlot {
                    slot: s,
                    position,
                    reference,
                });
            }
        }
        HeldSlots { origin, slots }
    }

    /// The value of held slot `h` at `pose`.
    pub fn value(h: &HeldSlot, pose: &Pose) -> Vector3<f64> {
        let y = pose.rotation * h.reference;
        if h.position { y + pose.origin } else { y }
    }

    /// The prescribed scalar values at `pose`, appended to `out` as
    /// (scalar index, value).
    pub fn prescribe(&self, pose: &Pose, out: &mut Vec<(usize, f64)>) {
        for h in &self.slots {
            let y = Self::value(h, pose);
            for c in 0..3 {
                out.push((3 * h.slot + c, y[c]));
            }
        }
    }

    /// Velocity and acceleration of each held slot (scalar index, velocity,
    /// acceleration) when the frame moves at `pose` with origin velocity
    /// `xd` and acceleration `xdd`, angular velocity `w` and angular
    /// acceleration `wd` (world axes).
    pub fn rates(
        &self,
        pose: &Pose,
        [xd, xdd]: [Vector3<f64>; 2],
        [w, wd]: [Vector3<f64>; 2],
        out: &mut Vec<(usize, f64, f64)>,
    ) {
        for h in &self.slots {
            // The part that turns with the frame, relative to its origin.
            let y = pose.rotation * h.reference;
            let (mut v, mut a) = (w.cross(&y), wd.cross(&y) + w.cross(&w.cross(&y)));
            if h.position {
                v += xd;
                a += xdd;
            }
            for c in 0..3 {
                out.push((3 * h.slot + c, v[c], a[c]));
            }
        }
    }
}

/// A force and a moment (N, N m), world axes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Wrench {
    /// Force.
    pub force: Vector3<f64>,
    /// Moment about the point it was taken about.
    pub moment: Vector3<f64>,
}

impl Wrench {
    /// The six components: force x, y, z, moment x, y, z.
    pub fn components(&self) -> [f64; 6] {
        let (f, m) = (&self.force, &self.moment);
        [f.x, f.y, f.z, m.x, m.y, m.z]
    }
}

/// The wrench about `about` of the generalized forces `r` (all scalars) on
/// the slots `(slot, is_position)` at the slot values `q` (see the module
/// docs): the resultant of the position slots' forces, and their moment
/// plus the gradient slots' couples.
pub fn wrench(
    slots: impl IntoIterator<Item = (usize, bool)>,
    q: &[f64],
    r: &[f64],
    about: &Vector3<f64>,
) -> Wrench {
    let at = |x: &[f64], s: usize| Vector3::new(x[3 * s], x[3 * s + 1], x[3 * s + 2]);
    let mut w = Wrench::default();
    for (s, position) in slots {
        let (qs, rs) = (at(q, s), at(r, s));
        if position {
            w.force += rs;
            w.moment += (qs - about).cross(&rs);
        } else {
            w.moment += qs.cross(&rs);
        }
    }
    w
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rodrigues' formula is a rotation about `r` by |r|, also below the
    /// series threshold; the left Jacobian maps the rate of the rotation
    /// vector to the angular velocity (finite differences of R R^T).
    #[test]
    fn rotation_and_its_jacobian() {
        for r in [
            Vector3::new(0.3, -0.7, 1.1),
            Vector3::new(2e-5, 1e-5, -3e-5),
            Vector3::zeros(),
        ] {
            let m = rotation(&r);
            let n = nalgebra::Rotation3::new(r);
            assert!((m - n.matrix()).norm() < 1e-15, "{r:?}");
            let rd = Vector3::new(-0.4, 0.9, 0.2);
            let d = 1e-6;
            let dr = (rotation(&(r + d * rd)) - rotation(&(r - d * rd))) / (2.0 * d);
            let wx = dr * m.transpose();
            let w = Vector3::new(wx[(2, 1)], wx[(0, 2)], wx[(1, 0)]);
            let want = left_jacobian(&r) * rd;
            assert!((w - want).norm() < 1e-8, "{w:?} vs {want:?}");
        }
    }

    /// The wrench does the virtual work of the forces under a small rigid
    /// motion of the slots: positions p -> p + dx + dth x (p - c),
    /// gradients g -> g + dth x g.
    #[test]
    fn wrench_is_the_virtual_work_of_a_rigid_motion() {
        let q = [0.1, 0.2, 0.3, 0.9, -0.2, 0.4, -0.3, 0.5, 0.8];
        let r = [1.0, -2.0, 0.5, 0.3, 0.7, -1.1, 2.0, 0.1, -0.6];
        let slots = [(0, true), (1, false), (2, true)];
        let c = Vector3::new(0.05, -0.1, 0.2);
        let w = wrench(slots, &q, &r, &c);
        let (dx, dth) = (Vector3::new(0.3, -0.1, 0.7), Vector3::new(-0.2, 0.5, 0.4));
        let mut work = 0.0;
        for (s, pos) in slots {
            let qs = Vector3::new(q[3 * s], q[3 * s + 1], q[3 * s + 2]);
            let rs = Vector3::new(r[3 * s], r[3 * s + 1], r[3 * s + 2]);
            let dq = if pos {
                dx + dth.cross(&(qs - c))
            } else {
                dth.cross(&qs)
            };
            work += rs.dot(&dq);
        }
        let want = w.force.dot(&dx) + w.moment.dot(&dth);
        assert!((work - want).abs() < 1e-14, "{work} vs {want}");
    }
}
