//! Rigid obstacles' shapes (data of a scene's `ancf:obstacles`) and their
//! geometry in closed form: the signed distance of a point, its gradient
//! (the unit outward normal at the closest point) and its Hessian.
//!
//! Every shape is convex, so its signed distance is a convex function of
//! the point: its Hessian is positive semi-definite with the normal in its
//! null space, and along any straight motion the distance never falls
//! below its tangent (what the collision check of
//! [`super::obstacles::ObstacleTerm`] relies on).

use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};

/// One shape, in world coordinates (m).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "shape", rename_all = "snake_case")]
pub enum Shape {
    /// The half-space behind the plane through `point` with unit outward
    /// `normal`.
    HalfSpace {
        /// A point of the plane.
        point: [f64; 3],
        /// Unit outward normal.
        normal: [f64; 3],
    },
    /// A ball.
    Sphere {
        /// Centre.
        center: [f64; 3],
        /// Radius.
        radius: f64,
    },
    /// A box with `half_extents` along its axes, turned by the rotation
    /// vector `rotation` (axis times angle, rad) about its centre.
    Box {
        /// Centre.
        center: [f64; 3],
        /// Half the side along each of its axes.
        half_extents: [f64; 3],
        /// Rotation vector of its axes from the world's.
        rotation: [f64; 3],
    },
    /// The points within `radius` of the segment between `ends`.
    Capsule {
        /// The segment's end points.
        ends: [[f64; 3]; 2],
        /// Radius.
        radius: f64,
    },
}

/// Why a shape's numbers make no shape: the field at fault and what is
/// wrong with it.
#[derive(Clone, Debug, PartialEq)]
pub struct ShapeError {
    /// The field (`radius`, `normal`, `half_extents[1]`, ...).
    pub field: String,
    /// What is wrong.
    pub reason: String,
}

impl std::fmt::Display for ShapeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.field, self.reason)
    }
}

impl std::error::Error for ShapeError {}

/// A point's signed distance to a shape (negative inside), its gradient
/// (unit) and its Hessian.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Closest {
    /// Signed distance (m).
    pub distance: f64,
    /// Unit outward normal at the closest point: the distance's gradient.
    pub normal: Vector3<f64>,
    /// The distance's Hessian (1/m): positive semi-definite, `normal` in
    /// its null space.
    pub hessian: Matrix3<f64>,
}

fn v3(a: &[f64; 3]) -> Vector3<f64> {
    Vector3::new(a[0], a[1], a[2])
}

/// Distance to the point `c` less `radius`.
fn ball(x: &Vector3<f64>, c: &Vector3<f64>, radius: f64) -> Closest {
    let r = x - c;
    let rho = r.norm();
    if rho == 0.0 {
        return Closest {
            distance: -radius,
            normal: Vector3::z(),
            hessian: Matrix3::zeros(),
        };
    }
    let n = r / rho;
    Closest {
        distance: rho - radius,
        normal: n,
        hessian: (Matrix3::identity() - n * n.transpose()) / rho,
    }
}

impl Shape {
    /// Whether the shape's numbers make a shape: finite, radii and half
    /// extents positive, a normal that is not zero (the message names the
    /// field at fault).
    pub fn check(&self) -> Result<(), ShapeError> {
        let fault = |field: &str, reason: String| ShapeError {
            field: field.into(),
            reason,
        };
        let finite = |name: &str, a: &[f64]| {
            if a.iter().all(|x| x.is_finite()) {
                Ok(())
            } else {
                Err(fault(name, "not finite numbers".into()))
            }
        };
        let positive = |name: &str, x: f64| {
            if x.is_finite() && x > 0.0 {
                Ok(())
            } else {
                Err(fault(name, format!("{x} is not a positive length")))
            }
        };
        match self {
            Shape::HalfSpace { point, normal } => {
                finite("point", point)?;
                finite("normal", normal)?;
                if v3(normal).norm() == 0.0 {
                    return Err(fault("normal", "the zero vector has no direction".into()));
                }
            }
            Shape::Sphere { center, radius } => {
                finite("center", center)?;
                positive("radius", *radius)?;
            }
            Shape::Box {
                center,
                half_extents,
                rotation,
            } => {
                finite("center", center)?;
                finite("rotation", rotation)?;
                for (k, &h) in half_extents.iter().enumerate() {
                    positive(&format!("half_extents[{k}]"), h)?;
                }
            }
            Shape::Capsule { ends, radius } => {
                finite("ends[0]", &ends[0])?;
                finite("ends[1]", &ends[1])?;
                positive("radius", *radius)?;
            }
        }
        Ok(())
    }

    /// The point the wrench on the shape is taken about: the plane's
    /// point, the centre (a capsule's: its segment's midpoint).
    pub fn origin(&self) -> Vector3<f64> {
        match self {
            Shape::HalfSpace { point, .. } => v3(point),
            Shape::Sphere { center, .. } | Shape::Box { center, .. } => v3(center),
            Shape::Capsule { ends, .. } => 0.5 * (v3(&ends[0]) + v3(&ends[1])),
        }
    }

    /// The signed distance of `x` to the shape with its gradient and
    /// Hessian (where the gradient is not defined, on a sphere's centre or
    /// a capsule's axis, some unit vector and a zero Hessian).
    pub fn closest(&self, x: &Vector3<f64>) -> Closest {
        match self {
            Shape::HalfSpace { point, normal } => {
                let n = v3(normal).normalize();
                Closest {
                    distance: n.dot(&(x - v3(point))),
                    normal: n,
                    hessian: Matrix3::zeros(),
                }
            }
            Shape::Sphere { center, radius } => ball(x, &v3(center), *radius),
            Shape::Box {
                center,
                half_extents,
                rotation,
            } => {
                let rot = crate::frame::rotation(&v3(rotation));
                let y = rot.transpose() * (x - v3(center));
                let h = v3(half_extents);
                let c = Vector3::from_fn(|i, _| y[i].clamp(-h[i], h[i]));
                let r = y - c;
                let rho = r.norm();
                if rho == 0.0 {
                    // Inside (or on the surface): the nearest face.
                    let (k, q) = (0..3)
                        .map(|i| (i, y[i].abs() - h[i]))
                        .fold((0, f64::NEG_INFINITY), |a, b| if b.1 > a.1 { b } else { a });
                    let s = if y[k] < 0.0 { -1.0 } else { 1.0 };
                    return Closest {
                        distance: q,
                        normal: rot * Vector3::ith(k, s),
                        hessian: Matrix3::zeros(),
                    };
                }
                let n = r / rho;
                // The clamp passes the components beyond the faces.
                let d = Matrix3::from_diagonal(&Vector3::from_fn(|i, _| {
                    if y[i].abs() > h[i] { 1.0 } else { 0.0 }
                }));
                let hl = (d - n * n.transpose()) / rho;
                Closest {
                    distance: rho,
                    normal: rot * n,
                    hessian: rot * hl * rot.transpose(),
                }
            }
            Shape::Capsule { ends, radius } => {
                let (a, b) = (v3(&ends[0]), v3(&ends[1]));
                let e = b - a;
                let l2 = e.norm_squared();
                let t = if l2 > 0.0 { (x - a).dot(&e) / l2 } else { 0.0 };
                if t <= 0.0 {
                    return ball(x, &a, *radius);
                }
                if t >= 1.0 {
                    return ball(x, &b, *radius);
                }
                let r = (x - a) - t * e;
                let rho = r.norm();
                if rho == 0.0 {
                    let u = e.normalize();
                    return Closest {
                        distance: -radius,
                        normal: super::potentials::tangent_basis(&u)[0],
                        hessian: Matrix3::zeros(),
                    };
                }
                let n = r / rho;
                let u = e / l2.sqrt();
                Closest {
                    distance: rho - radius,
                    normal: n,
                    hessian: (Matrix3::identity() - u * u.transpose() - n * n.transpose()) / rho,
                }
            }
        }
    }
}

/// A rigid obstacle of a scene (`ancf:obstacles`): its name (the prefix of
/// its outputs and inputs), its shape, the friction coefficient against the
/// sheet, and whether pose inputs move it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Obstacle {
    /// Variable name prefix of its wrench outputs.
    pub name: String,
    /// Shape and placement.
    #[serde(flatten)]
    pub shape: Shape,
    /// Coulomb friction coefficient between the sheet and the obstacle.
    pub friction: f64,
    /// Moved by pose inputs (`NAME.x/y/z`, `NAME.rx/ry/rz`: the origin
    /// [`Shape::origin`] and a rotation vector about it), else fixed.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub moving: bool,
}
