//! Reactions: the wrench the sheet exerts on a rigid attachment's frame
//! (`ancf:attachments`), against statics and rigid-body dynamics: a clamped
//! sheet at rest carries its weight and its moment; a frame accelerated at
//! a constant a pushes the sheet with m (a - g); a frame turning at a
//! constant rate pulls it with the centripetal m omega^2 r_cm. And the
//! reactions of supports and prescribed motions (the `reactions` output
//! group) balance the weight of the sheet they hold.
//! (The finite-difference test against the potential energy is the unit
//! test `model::attach::tests`.)

mod common;

use nalgebra::Vector3;
use origami_fmu::Model;

/// Two 50 x 50 mm panels of 1 mm plastic (2 GPa, 1200 kg/m^3) with a valley
/// crease between them, the edge x = 0 (vertices 0, 5) clamped to the
/// attachment `mount`; `extra` adds keys.
fn sheet(extra: &str) -> origami_fmu::Scene {
    common::two_plastic_panels(&format!(
        r#""ancf:attachments": [{{"name": "mount", "vertices": [0, 5]}}]{extra}"#
    ))
}

/// The frame's (force, moment) outputs now.
fn wrench(m: &Model) -> (Vector3<f64>, Vector3<f64>) {
    (vector(m, "mount.force"), vector(m, "mount.moment"))
}

use common::output_vector as vector;

/// The input `mount.NAME`.
fn input(m: &Model, name: &str) -> origami_fmu::InputId {
    let name = format!("mount.{name}");
    m.input_id(&name)
        .unwrap_or_else(|| panic!("no input {name}"))
}

/// Set the pose inputs `x` (origin) and `r` (rotation vector) with their
/// first and second derivatives, as a master does before each step.
fn set_pose(m: &mut Model, [x, xd, xdd]: [Vector3<f64>; 3], [r, rd, rdd]: [Vector3<f64>; 3]) {
    for (k, c) in ["x", "y", "z"].iter().enumerate() {
        for (prefix, [v, d1, d2]) in [("", [x, xd, xdd]), ("r", [r, rd, rdd])] {
            let i = input(m, &format!("{prefix}{c}"));
            m.set_input(i, v[k]).unwrap();
            m.set_input_derivative(i, 1, d1[k]).unwrap();
            m.set_input_derivative(i, 2, d2[k]).unwrap();
        }
    }
}

fn origin(m: &Model) -> Vector3<f64> {
    let at = |c: &str| m.input(input(m, c)).unwrap();
    Vector3::new(at("x"), at("y"), at("z"))
}

/// A sheet clamped along one edge to a resting frame settles under gravity:
/// the frame then carries the weight m g, and the moment m (c - x) x g of
/// the deflected sheet's centre of mass c about the frame's origin x,
/// within 1e-3 relative (automatic damping, 1 s).
#[test]
fn a_clamped_sheet_at_rest_hangs_its_weight_and_moment_on_the_frame() {
    let g = Vector3::new(0.0, 0.0, -9.81);
    let mut m = Model::new(sheet(r#", "ancf:loads": {"gravity": [0, 0, -9.81]}"#)).unwrap();
    m.initialize().unwrap();
    for _ in 0..100 {
        m.advance(0.01).unwrap();
    }
    let (mass, c) = m.mass_properties();
    let c = Vector3::from(c);
    let (f, mo) = wrench(&m);
    let weight = mass * g;
    let lever = mass * (c - origin(&m)).cross(&g);
    eprintln!(
        "at rest: force error {:.1e}, moment error {:.1e} (relative)",
        (f - weight).norm() / weight.norm(),
        (mo - lever).norm() / lever.norm()
    );
    assert!(
        (f - weight).norm() < 1e-3 * weight.norm(),
        "{f:?} vs {weight:?}"
    );
    assert!(
        (mo - lever).norm() < 1e-3 * lever.norm(),
        "{mo:?} vs {lever:?}"
    );
    // The sheet sags: the centre of mass is below the clamped edge.
    assert!(c.z < -1e-5, "{c:?}");
}

/// The frame accelerated at a constant a (its origin given with its first
/// and second derivatives every step, as a master would): once the
/// transients have decayed the frame pushes the sheet with m (a - g), that
/// is the sheet exerts m (g - a) on it, within 1e-3.
#[test]
fn a_frame_accelerated_at_a_constant_rate_pushes_the_sheet_with_m_a_minus_g() {
    let g = Vector3::new(0.0, 0.0, -9.81);
    let a = Vector3::new(1.0, -2.0, 3.0);
    let mut m = Model::new(sheet(r#", "ancf:loads": {"gravity": [0, 0, -9.81]}"#)).unwrap();
    let x0 = origin(&m);
    let h = 0.01;
    let zero = Vector3::zeros();
    set_pose(&mut m, [x0, zero, a], [zero; 3]);
    m.initialize().unwrap();
    for k in 1..=100 {
        m.advance(h).unwrap();
        let t = k as f64 * h;
        set_pose(&mut m, [x0 + 0.5 * a * t * t, a * t, a], [zero; 3]);
    }
    let (mass, _) = m.mass_properties();
    let (f, _) = wrench(&m);
    let want = mass * (g - a);
    eprintln!(
        "accelerated: force error {:.1e} (relative)",
        (f - want).norm() / want.norm()
    );
    assert!((f - want).norm() < 1e-3 * want.norm(), "{f:?} vs {want:?}");
}

/// The frame turning about the vertical through its origin at a constant
/// rate omega = 10 rad/s (rz = omega t, its rate given as the input's
/// derivative; the sheet starts turning with its frame): the frame holds
/// the sheet on its circle with the centripetal force, so the sheet pulls
/// the frame outwards with m omega^2 r_cm (r_cm the centre of mass's
/// distance from the axis), within 1e-3 at every communication point of
/// the second half second. The wrench is as accurate as the integrated
/// motion: Newton's iteration error makes the sheet vibrate about the
/// steady turn. Here internal steps of 2 ms, all equal (the 10 ms
/// communication step is a multiple), and tolerance 1e-5: largest error
/// 1.3e-4. At the default settings 17 % (docs/fmu.md, "Reactions").
#[test]
fn a_frame_turning_at_a_constant_rate_feels_the_centripetal_force() {
    let omega = 10.0;
    let solver = r#", "ancf:solver": {"max_step": 2e-3, "tolerance": 1e-5}"#;
    let mut m = Model::new(sheet(solver)).unwrap();
    let x0 = origin(&m);
    let zero = Vector3::zeros();
    let w = Vector3::new(0.0, 0.0, omega);
    let mut total = origami_fmu::StepReport::default();
    set_pose(&mut m, [x0, zero, zero], [zero, w, zero]);
    m.initialize().unwrap();
    let h = 0.01;
    let mut worst: f64 = 0.0;
    for k in 1..=100 {
        total.accumulate(&m.advance(h).unwrap());
        let t = k as f64 * h;
        set_pose(&mut m, [x0, zero, zero], [w * t, w, zero]);
        if t >= 0.5 {
            let (mass, c) = m.mass_properties();
            let arm = Vector3::from(c) - x0;
            let arm = Vector3::new(arm.x, arm.y, 0.0);
            let (f, _) = wrench(&m);
            let want = mass * omega * omega * arm;
            worst = worst.max((f - want).norm() / want.norm());
        }
    }
    eprintln!(
        "largest relative error over 0.5..1 s: {worst:.2e} ({} steps, {} Newton iterations)",
        total.steps, total.newton_iterations
    );
    assert!(worst < 1e-3, "{worst}");
}

/// A sheet held at rest by a clamped support along one edge (vertices 0
/// and 5) and a prescribed motion at a far corner (vertex 2, held where it
/// starts), settled under gravity: the support's force and the motion's add
/// up to the weight m g, and their moments about the support's centroid s
/// to m (c - s) x g, within 1e-6 of the weight (and of its moment).
#[test]
fn support_and_motion_reactions_balance_the_weight() {
    let mut m = Model::new(common::two_plastic_panels(
        r#""ancf:loads": {"gravity": [0, 0, -9.81]},
      "ancf:supports": [{"vertices": [0, 5], "fix": "clamped"}],
      "ancf:motions": [{"name": "tip", "vertex": 2}],
      "ancf:outputs": ["reactions"]"#,
    ))
    .unwrap();
    m.initialize().unwrap();
    for _ in 0..100 {
        m.advance(0.01).unwrap();
    }
    let g = Vector3::new(0.0, 0.0, -9.81);
    let (mass, c) = m.mass_properties();
    let s = Vector3::new(0.0, 0.025, 0.0);
    let tip = Vector3::new(0.1, 0.0, 0.0);
    let (fs, ms, ft) = (
        vector(&m, "support[0].force"),
        vector(&m, "support[0].moment"),
        vector(&m, "tip.force"),
    );
    let weight = mass * g;
    let moment = mass * (Vector3::from(c) - s).cross(&g);
    let total = ms + (tip - s).cross(&ft);
    eprintln!(
        "support and motion: force error {:.1e}, moment error {:.1e} (relative)",
        (fs + ft - weight).norm() / weight.norm(),
        (total - moment).norm() / moment.norm()
    );
    // Both carry a share.
    assert!(fs.z < -0.1 * weight.norm() && ft.z < -0.1 * weight.norm());
    assert!((fs + ft - weight).norm() < 1e-6 * weight.norm());
    assert!(
        (total - moment).norm() < 1e-6 * moment.norm(),
        "{total:?} vs {moment:?}"
    );
}
