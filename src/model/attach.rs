//! Rigid attachments and reactions: where each attachment's frame starts,
//! the slots it holds, and the reaction outputs (the wrench the sheet
//! exerts on each attachment, support and prescribed motion), taken from
//! the residual of the equation of motion at the held DOFs at the end of
//! a step, `f_ext - M qdd - f_int` (generalized-alpha holds the equation
//! at t_{n+1}, prescribed DOFs included, with their inertia).

use super::inputs::InputMap;
use crate::assembly::Assembler;
use crate::dofs::SlotKind;
use crate::frame::{self, HeldSlots, Pose};
use crate::ids::VertexId;
use crate::scene::{Attachment, Fix, Scene, Support};
use crate::solver::stepper::Dynamics;
use nalgebra::Vector3;

/// Inputs per attachment: `x, y, z, rx, ry, rz`.
pub(super) const POSE_INPUTS: usize = 6;

/// The origin of attachment `a`'s frame in the reference: the centroid of
/// its FOLD vertices.
pub(super) fn origin(scene: &Scene, a: &Attachment) -> Vector3<f64> {
    centroid(scene, &a.vertices)
}

/// The centroid of `vertices` in the reference, counting FOLD vertices
/// only (split copies and refinement vertices left out) where there are
/// any.
pub(super) fn centroid(scene: &Scene, vertices: &[VertexId]) -> Vector3<f64> {
    let listed: Vec<_> = vertices
        .iter()
        .filter(|v| v.index() < scene.fold_vertex_count)
        .collect();
    let vs = if listed.is_empty() {
        vertices.iter().collect()
    } else {
        listed
    };
    let mut c = Vector3::zeros();
    for &&v in &vs {
        let x = scene.mesh.coord(v);
        c += Vector3::new(x.x, x.y, 0.0);
    }
    c / vs.len().max(1) as f64
}

/// Whether support `s` reports a moment besides its force: a clamped one,
/// or one of several vertices (a single pinned vertex transmits none).
pub fn support_has_moment(s: &Support) -> bool {
    s.fix == Fix::Clamped || s.vertices.len() > 1
}

/// The point a reaction's moment is taken about.
#[derive(Clone, Copy, Debug)]
pub(super) enum About {
    /// The origin of attachment k's frame (where the inputs put it).
    Frame(usize),
    /// A fixed point (a support's centroid).
    Point(Vector3<f64>),
}

/// One reaction output group: the held slots (slot, is a position) whose
/// residual it sums, and whether it reports a moment (about what).
#[derive(Clone, Debug)]
pub(super) struct Reaction {
    pub(super) slots: Vec<(usize, bool)>,
    pub(super) about: About,
    pub(super) moment: bool,
}

/// The reaction outputs of a model, in output order: each attachment's
/// wrench, then (when the scene asks for reactions) each support's and
/// each motion's.
#[derive(Clone, Debug, Default)]
pub(super) struct Reactions {
    pub(super) groups: Vec<Reaction>,
}

impl Reactions {
    /// Whether the model reports any reaction.
    pub(super) fn is_empty(&self) -> bool {
        self.groups.is_empty()
    }

    /// The output values (force, then moment where reported, per group)
    /// at positions `q` and accelerations `qdd` under the external force
    /// `f_ext`, the internal force `force` and the frames at `frames`,
    /// appended to `out`.
    pub(super) fn values(
        &self,
        asm: &Assembler,
        (q, qdd): (&[f64], &[f64]),
        (f_ext, force): (&[f64], &[f64]),
        frames: &[Pose],
        out: &mut Vec<f64>,
    ) {
        if self.is_empty() {
            return;
        }
        let mut r = vec![0.0; q.len()];
        asm.mass_mul(qdd, &mut r);
        for ((x, &fe), &fi) in r.iter_mut().zip(f_ext).zip(force) {
            *x = fe - *x - fi;
        }
        for g in &self.groups {
            let about = match g.about {
                About::Frame(k) => frames[k].origin,
                About::Point(c) => c,
            };
            let w = frame::wrench(g.slots.iter().copied(), q, &r, &about);
            let c = w.components();
            out.extend_from_slice(if g.moment { &c[..] } else { &c[..3] });
        }
    }
}

/// One attachment of the input map: its first input and held slots.
#[derive(Clone, Debug)]
pub(super) struct FrameInput {
    /// Index of its `x` input (`y, z, rx, ry, rz` follow).
    pub(super) input: usize,
    /// The slots it holds.
    pub(super) held: HeldSlots,
}

impl FrameInput {
    /// The frame's pose under the input values `u`.
    pub(super) fn pose(&self, u: &[f64]) -> Pose {
        pose(self.input, u)
    }

    /// The frame's velocity and acceleration (see [`rates`]).
    pub(super) fn rates(
        &self,
        u: &[f64],
        d1: &[f64],
        d2: &[f64],
    ) -> ([Vector3<f64>; 2], [Vector3<f64>; 2]) {
        rates(self.input, u, d1, d2)
    }
}

/// The pose of the six pose inputs from `input` (`x, y, z, rx, ry, rz`)
/// under the input values `u`.
pub(super) fn pose(input: usize, u: &[f64]) -> Pose {
    let p = &u[input..input + POSE_INPUTS];
    Pose::new(
        Vector3::new(p[0], p[1], p[2]),
        &Vector3::new(p[3], p[4], p[5]),
    )
}

/// The velocity and acceleration of the pose inputs from `input`: the
/// origin's `[xd, xdd]` and the angular `[w, wd]` (world axes), from the
/// inputs `u` and their first and second derivatives (the rotation
/// vector's rates mapped by the left Jacobian; its rate of change along the
/// path by a central difference).
pub(super) fn rates(
    input: usize,
    u: &[f64],
    d1: &[f64],
    d2: &[f64],
) -> ([Vector3<f64>; 2], [Vector3<f64>; 2]) {
    let at = |x: &[f64], k: usize| {
        let i = input + k;
        Vector3::new(
            x.get(i).copied().unwrap_or(0.0),
            x.get(i + 1).copied().unwrap_or(0.0),
            x.get(i + 2).copied().unwrap_or(0.0),
        )
    };
    let (r, rd, rdd) = (at(u, 3), at(d1, 3), at(d2, 3));
    let w = frame::left_jacobian(&r) * rd;
    let mut wd = frame::left_jacobian(&r) * rdd;
    let speed = rd.norm();
    if speed > 0.0 {
        let h = 1e-4 / speed;
        let dj =
            (frame::left_jacobian(&(r + h * rd)) - frame::left_jacobian(&(r - h * rd))) / (2.0 * h);
        wd += dj * rd;
    }
    ([at(d1, 0), at(d2, 0)], [w, wd])
}

/// The motion of the pose inputs from `input` (pose and velocity) under
/// the inputs `u` and their derivatives `d1`, `d2`.
pub(super) fn motion(input: usize, u: &[f64], d1: &[f64], d2: &[f64]) -> frame::Motion {
    let ([v, _], [w, _]) = rates(input, u, d1, d2);
    let p = &u[input..input + POSE_INPUTS];
    frame::Motion::new(
        Vector3::new(p[0], p[1], p[2]),
        Vector3::new(p[3], p[4], p[5]),
        v,
        w,
    )
}

/// The initial state of a sheet with attachments, from the inputs `u` and
/// their first and second derivatives `(d1, d2)`: every slot carried by
/// the first attachment's frame (placed by its pose, moving with its
/// velocity field), then each frame's held slots at their own velocities
/// and accelerations. Nothing changes without attachments.
pub(super) fn start_with_frames(
    asm: &Assembler,
    inputs: &InputMap,
    u: &[f64],
    (d1, d2): (&[f64], &[f64]),
    d: &mut Dynamics,
) {
    let Some(first) = inputs.frames.first() else {
        return;
    };
    let pose = first.pose(u);
    let ([xd, _], [w, _]) = first.rates(u, d1, d2);
    let o0 = first.held.origin;
    let moved = pose.origin != o0 || pose.rotation != nalgebra::Matrix3::identity();
    let layout = &asm.layout;
    for (s, kind) in layout.slot_kind.iter().enumerate() {
        if asm.free[3 * s] == crate::assembly::FIXED {
            // Held, supported or driven: the prescribed values and rates.
            continue;
        }
        let position = *kind == SlotKind::Position;
        let x = Vector3::new(d.q[3 * s], d.q[3 * s + 1], d.q[3 * s + 2]);
        let y = match (moved, position) {
            (false, _) => x,
            (true, true) => pose.rotation * (x - o0) + pose.origin,
            (true, false) => pose.rotation * x,
        };
        let v = if position {
            xd + w.cross(&(y - pose.origin))
        } else {
            w.cross(&y)
        };
        d.q[3 * s..3 * s + 3].copy_from_slice(y.as_slice());
        d.v[3 * s..3 * s + 3].copy_from_slice(v.as_slice());
    }
    let mut rates = Vec::new();
    for f in &inputs.frames {
        let (lin, ang) = f.rates(u, d1, d2);
        f.held.rates(&f.pose(u), lin, ang, &mut rates);
    }
    for (i, v, a) in rates {
        d.v[i] = v;
        d.qdd[i] = a;
        d.abar[i] = a;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Model;
    use crate::solver::statics::{self, Load, StaticSettings};

    /// Two 50 x 50 mm panels of 1 mm plastic with a valley crease between
    /// them, the edge x = 0 clamped to the attachment `mount`, under gravity.
    pub(crate) fn hanging_sheet() -> crate::Scene {
        let text = r#"{
          "frame_unit": "m",
          "vertices_coords": [[0,0],[0.05,0],[0.1,0],[0.1,0.05],[0.05,0.05],[0,0.05]],
          "edges_vertices": [[0,1],[1,2],[2,3],[3,4],[4,5],[5,0],[1,4]],
          "edges_assignment": ["B","B","B","B","B","B","V"],
          "edges_foldAngle": [null,null,null,null,null,null,90],
          "faces_vertices": [[0,1,4,5],[1,2,3,4]],
          "ancf:material": {"thickness": 1e-3, "youngs_modulus": 2e9, "density": 1200},
          "ancf:loads": {"gravity": [0, 0, -9.81]},
          "ancf:attachments": [{"name": "mount", "vertices": [0, 5]}]
        }"#;
        crate::scene::from_str(text).unwrap().0
    }

    struct Gravity(Vec<f64>);
    impl Load for Gravity {
        fn apply(
            &self,
            _: &Assembler,
            _: &[f64],
            lambda: f64,
            f: &mut [f64],
            _: Option<&mut [f64]>,
        ) {
            for (fi, x) in f.iter_mut().zip(&self.0) {
                *fi += lambda * x;
            }
        }
    }

    /// Quasi-static: the wrench the model reports (the residual at the held
    /// slots, about the frame's origin) is minus the derivative of the
    /// sheet's potential energy at equilibrium (strain + crease + gravity)
    /// with respect to the frame's pose: its origin moved along each axis,
    /// and turned about each world axis (`exp([e_k dtheta x]) R0`, the pose
    /// given back as a rotation vector), by central differences, within
    /// 1e-5 of the wrench's size, at a tilted pose.
    #[test]
    fn wrench_is_minus_the_pose_derivative_of_the_potential_energy() {
        let model = Model::new(hanging_sheet()).unwrap();
        let sys = model.sys.as_ref().unwrap();
        let asm = &sys.asm;
        let u0: Vec<f64> = model.inputs.iter().map(|v| v.start).collect();
        let base = model
            .inputs
            .iter()
            .position(|v| v.name == "mount.x")
            .unwrap();
        let d0 = sys.inputs.drive(&u0);
        let gravity = Gravity(d0.f_ext.clone());
        let settings = StaticSettings {
            tolerance: 1e-13,
            ..StaticSettings::default()
        };
        let flat = vec![std::f64::consts::PI; asm.creases.len()];
        // Equilibrium at the pose (x, r) from `q` (the free slots' guess),
        // and its potential energy.
        let solve = |x: Vector3<f64>, r: Vector3<f64>, q: &mut Vec<f64>, steps: usize| {
            let mut u = u0.clone();
            u[base..base + 3].copy_from_slice(x.as_slice());
            u[base + 3..base + 6].copy_from_slice(r.as_slice());
            for &(i, v) in &sys.inputs.drive(&u).prescribed {
                q[i] = v;
            }
            let s = StaticSettings {
                load_steps: steps,
                ..settings
            };
            statics::solve(asm, q, &d0.theta0, &gravity, s).unwrap();
            let mut ev = crate::assembly::Evaluation::default();
            let st = crate::assembly::State {
                q,
                v: &vec![0.0; q.len()],
                theta0: &d0.theta0,
                moment: &d0.moment,
                theta_prev: &flat,
            };
            asm.evaluate(&st, &mut ev, None).unwrap();
            let work: f64 = gravity.0.iter().zip(q.iter()).map(|(f, x)| f * x).sum();
            (ev.strain_energy + ev.crease_energy - work, ev, u)
        };
        // A tilted, shifted pose; the sheet placed rigidly with it first.
        let x0 = Vector3::new(0.01, 0.03, -0.02) + Vector3::new(u0[base], u0[base + 1], 0.0);
        let r0 = Vector3::new(0.3, -0.2, 0.5);
        let mut d = Dynamics {
            q: asm.layout.reference_state(&model.scene.mesh),
            v: vec![0.0; asm.n_dofs()],
            qdd: vec![0.0; asm.n_dofs()],
            abar: vec![0.0; asm.n_dofs()],
        };
        let mut u = u0.clone();
        u[base..base + 3].copy_from_slice(x0.as_slice());
        u[base + 3..base + 6].copy_from_slice(r0.as_slice());
        let zeros = vec![0.0; u.len()];
        start_with_frames(asm, &sys.inputs, &u, (&zeros, &zeros), &mut d);
        let mut q0 = d.q.clone();
        let (_, ev, u) = solve(x0, r0, &mut q0, 10);
        let dr = sys.inputs.drive(&u);
        let mut out = Vec::new();
        let zero = vec![0.0; q0.len()];
        sys.reactions.values(
            asm,
            (&q0, &zero),
            (&dr.f_ext, &ev.force),
            &dr.frames,
            &mut out,
        );
        let wrench: Vec<f64> = out[..6].to_vec();
        let size = wrench.iter().map(|x| x * x).sum::<f64>().sqrt();
        // The sheet's weight and a lever arm of a few cm.
        assert!(size > 1e-3, "{wrench:?}");
        let (eps, eps_r) = (1e-6, 1e-5);
        let r0_rot = frame::rotation(&r0);
        let mut worst: f64 = 0.0;
        for k in 0..3 {
            let e = Vector3::ith(k, 1.0);
            let energy = |x: Vector3<f64>, r: Vector3<f64>| solve(x, r, &mut q0.clone(), 1).0;
            let dx = (energy(x0 + eps * e, r0) - energy(x0 - eps * e, r0)) / (2.0 * eps);
            let turned = |s: f64| {
                let m = frame::rotation(&(s * e)) * r0_rot;
                nalgebra::Rotation3::from_matrix_unchecked(m).scaled_axis()
            };
            let dth = (energy(x0, turned(eps_r)) - energy(x0, turned(-eps_r))) / (2.0 * eps_r);
            for (what, got, want) in [("force", wrench[k], -dx), ("moment", wrench[3 + k], -dth)] {
                worst = worst.max((got - want).abs() / size);
                assert!(
                    (got - want).abs() < 1e-5 * size,
                    "{what} {k}: wrench {got:.9e}, -dV/dpose {want:.9e}"
                );
            }
        }
        eprintln!("wrench vs -dV/dpose: largest difference {worst:.1e} of the wrench");
    }
}
