//! Moving rigid obstacles (`"moving": true` in `ancf:obstacles`): pose
//! inputs `NAME.x/y/z`, `NAME.rx/ry/rz` with their derivatives move an
//! obstacle; the sheet feels its motion through the barrier, the dashpots
//! and friction on the velocity relative to the obstacle's surface, and the
//! obstacles' work enters the energy balance.
//! A ground lifted with constant acceleration pushes the sheet with
//! m (a - g); a conveyor ground drags the sheet to its speed at mu g, with
//! the classic split of the belt's work (half dissipated); a turntable
//! turns the sheet with it; a ball swept through a floating sheet pushes
//! it aside without any output inside the clearance; a state saved on a
//! moving ground continues bit for bit.

mod common;

use common::output_vector as vector;
use nalgebra::Vector3;
use origami_fmu::Model;

/// The 0.1 m plastic square centred on the origin
/// ([`common::plastic_square`]).
fn square(g: [f64; 3], obstacles: &str, extra: &str) -> origami_fmu::Scene {
    common::plastic_square(
        [-0.05, -0.05],
        g,
        &format!(r#""ancf:obstacles": {obstacles}{extra}"#),
    )
}

/// The ground 0.52 mm below the sheet (the sheet lands within the
/// barrier), moving, with friction `mu`.
fn moving_ground(mu: f64) -> String {
    format!(
        r#"[{{"name": "ground", "shape": "half_space", "point": [0, 0, -0.00052], "normal": [0, 0, 1], "friction": {mu}, "moving": true}}]"#
    )
}

fn out(m: &Model, name: &str) -> f64 {
    m.output(m.output_id(name).unwrap()).unwrap()
}

/// Set pose input `name` (e.g. "ground.z") to `value` with first and
/// second derivatives `d1`, `d2`.
fn set(m: &mut Model, name: &str, [value, d1, d2]: [f64; 3]) {
    let i = m.input_id(name).unwrap();
    m.set_input(i, value).unwrap();
    m.set_input_derivative(i, 1, d1).unwrap();
    m.set_input_derivative(i, 2, d2).unwrap();
}

/// The mean of the four corners' positions (what a master sees of the
/// square).
fn corners(m: &Model) -> Vector3<f64> {
    (0..4)
        .map(|i| vector(m, &format!("vertex[{i}]")))
        .sum::<Vector3<f64>>()
        / 4.0
}

/// A moving obstacle has its six pose inputs, starting at its origin (the
/// plane's point) and zero rotation, described as an obstacle's; a fixed
/// one has none.
#[test]
fn a_moving_obstacle_has_pose_inputs_starting_at_its_origin() {
    let two = r#"[{"name": "ground", "shape": "half_space", "point": [0.01, 0.02, -0.00052], "normal": [0, 0, 1], "moving": true},
                  {"name": "wall", "shape": "half_space", "point": [1, 0, 0], "normal": [-1, 0, 0]}]"#;
    let m = Model::new(square([0.0, 0.0, -9.81], two, "")).unwrap();
    // After the crease actuator `fold`.
    let poses = &m.inputs()[1..];
    let names: Vec<&str> = poses.iter().map(|v| v.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "ground.x",
            "ground.y",
            "ground.z",
            "ground.rx",
            "ground.ry",
            "ground.rz"
        ]
    );
    let starts: Vec<f64> = poses.iter().map(|v| v.start).collect();
    assert_eq!(starts, [0.01, 0.02, -0.00052, 0.0, 0.0, 0.0]);
    assert!(
        poses[0].description.contains("obstacle ground"),
        "{}",
        poses[0].description
    );
}

/// The sheet resting on the ground, the ground then lifted with a constant
/// acceleration a = 2 m/s^2 (its height given with its first and second
/// derivatives at every communication point): once the landing's
/// transient has decayed, the ground pushes the sheet with m (a - g) (g
/// the gravity vector), so the force the sheet exerts on the ground is
/// `ground.force.z = -m (9.81 + 2)`, within 1e-3, and the sheet rises with
/// the ground (its corners keep their height above it within the barrier
/// width).
#[test]
fn a_ground_lifted_with_constant_acceleration_pushes_with_m_a_minus_g() {
    let mut m = Model::new(square([0.0, 0.0, -9.81], &moving_ground(0.0), "")).unwrap();
    m.initialize().unwrap();
    for _ in 0..20 {
        m.advance(0.01).unwrap();
    }
    let (mass, _) = m.mass_properties();
    let z0 = -0.00052;
    let a = 2.0;
    let t0 = m.time();
    let mut worst_gap = f64::INFINITY;
    let mut steps = 0;
    for k in 0..30 {
        let t = m.time() - t0;
        set(&mut m, "ground.z", [z0 + 0.5 * a * t * t, a * t, a]);
        steps += m.advance(0.01).unwrap().steps;
        let (gap, _, _) = m.obstacle_gap().unwrap();
        worst_gap = worst_gap.min(gap);
        assert!(gap > 0.0, "output {k}: gap {gap:e}");
    }
    let t = m.time() - t0;
    let ground = z0 + 0.5 * a * t * t;
    let f = vector(&m, "ground.force");
    let want = -mass * (9.81 + a);
    let lift = corners(&m).z - ground;
    eprintln!(
        "steps {steps}; ground force {f:?}, want z {want:.6e} ({:.1e} relative); corners \
         {lift:.3e} m above the ground; smallest gap {worst_gap:.2e} m",
        (f.z - want).abs() / want.abs()
    );
    assert!((f.z - want).abs() < 1e-3 * want.abs(), "{f:?} vs {want}");
    assert!(f.xy().norm() < 1e-3 * want.abs(), "{f:?}");
    assert!(lift > 5e-4 && lift < 5e-4 + 5e-5, "{lift}");
}

/// A conveyor: the ground, friction mu = 0.3, set moving along x at
/// V = 5 cm/s under the sheet at rest (its position given with its rate).
/// Friction accelerates the sheet at mu g until it moves with the belt
/// (after V / (mu g) = 17 ms): its acceleration from 4 to 16 ms is mu g
/// within 1 %, and from 50 ms on its speed is V within 1 %. Of the belt's work on the sheet
/// (`energy.input_work`, m V^2 by then) half is dissipated by friction
/// and half is the sheet's kinetic energy, each within 3 %.
#[test]
fn a_conveyor_drags_the_sheet_to_its_speed_at_mu_g() {
    let (mu, speed, g) = (0.3, 0.05, 9.81);
    let extra = r#", "ancf:solver": {"rho_inf": 1.0, "tolerance": 1e-6}, "ancf:damping": {"alpha": 0, "beta": 0}"#;
    let mut m = Model::new(square([0.0, 0.0, -g], &moving_ground(mu), extra)).unwrap();
    m.initialize().unwrap();
    for _ in 0..20 {
        m.advance(0.01).unwrap();
    }
    let (mass, _) = m.mass_properties();
    let (w0, d0) = (out(&m, "energy.input_work"), out(&m, "energy.dissipated"));
    let t0 = m.time();
    let h = 0.002;
    let mut x_prev = corners(&m).x;
    let mut speeds = Vec::new();
    for _ in 0..50 {
        let t = m.time() - t0;
        set(&mut m, "ground.x", [speed * t, speed, 0.0]);
        m.advance(h).unwrap();
        let x = corners(&m).x;
        speeds.push((x - x_prev) / h);
        x_prev = x;
    }
    // The acceleration from the mean speeds over steps 3 and 8 (4-6 and
    // 14-16 ms: after the belt's start, before the sheet catches up).
    let early = (speeds[7] - speeds[2]) / (5.0 * h);
    let want_early = mu * g;
    let late = speeds[25..]
        .iter()
        .fold(0.0f64, |a, &s| a.max((s - speed).abs()));
    let work = out(&m, "energy.input_work") - w0;
    let dissipated = out(&m, "energy.dissipated") - d0;
    let kinetic = out(&m, "energy.kinetic");
    let mv2 = mass * speed * speed;
    eprintln!(
        "acceleration {early:.5} m/s^2 (mu g {want_early:.5}); largest deviation from V after 50 ms \
         {late:.2e} m/s; work {:.4} m V^2, dissipated {:.4}, kinetic {:.4}",
        work / mv2,
        dissipated / mv2,
        kinetic / mv2
    );
    assert!((early - want_early).abs() < 0.01 * want_early, "{early}");
    assert!(late < 0.01 * speed, "{late}");
    assert!((work - mv2).abs() < 0.03 * mv2, "work {work} vs {mv2}");
    assert!(
        (dissipated - 0.5 * mv2).abs() < 0.03 * mv2,
        "dissipated {dissipated}"
    );
    assert!(
        (kinetic - 0.5 * mv2).abs() < 0.03 * mv2,
        "kinetic {kinetic}"
    );
}

/// A turntable: the ground (mu = 0.5) turned about the vertical through
/// the sheet's centre at 2 rad/s (its rotation vector's z with its rate)
/// turns the sheet with it: after 0.4 s every corner moves at omega x r
/// within 2 % of omega r.
#[test]
fn a_turntable_turns_the_sheet_with_it() {
    let (omega, dt) = (2.0, 0.005);
    let ground = r#"[{"name": "ground", "shape": "half_space", "point": [0, 0, -0.00052], "normal": [0, 0, 1], "friction": 0.5, "moving": true}]"#;
    let mut m = Model::new(square([0.0, 0.0, -9.81], ground, "")).unwrap();
    m.initialize().unwrap();
    for _ in 0..20 {
        m.advance(0.01).unwrap();
    }
    let t0 = m.time();
    let corners_now = |m: &Model| -> Vec<Vector3<f64>> {
        (0..4).map(|i| vector(m, &format!("vertex[{i}]"))).collect()
    };
    let mut before = corners_now(&m);
    let mut worst: f64 = 0.0;
    for k in 0..80 {
        let t = m.time() - t0;
        set(&mut m, "ground.rz", [omega * t, omega, 0.0]);
        m.advance(dt).unwrap();
        let now = corners_now(&m);
        if k >= 70 {
            for (a, b) in before.iter().zip(&now) {
                let mid = 0.5 * (a + b);
                let v = (b - a) / dt;
                let want = Vector3::new(0.0, 0.0, omega).cross(&Vector3::new(mid.x, mid.y, 0.0));
                worst = worst.max((v - want).norm() / want.norm());
            }
        }
        before = now;
    }
    eprintln!("corners' velocity off omega x r by {worst:.2e} of omega r");
    assert!(worst < 0.02, "{worst}");
}

/// A rod (a capsule of radius 1 cm across the whole sheet, its axis 5 mm
/// below it, so that it cuts 5 mm into where the sheet is) swept at
/// 0.5 m/s along x under a floating sheet (no gravity) pushes it ahead and
/// up: no output has a contact sample within the sheet's half thickness of
/// it, and the sheet leaves moving along x and up. The rod's work (through
/// the barrier and the dashpots: `energy.input_work`) is the sheet's
/// kinetic, strain and barrier energy plus what the dashpots dissipated,
/// within 1 % (rho_inf = 1, no damping, tolerance 1e-6).
#[test]
fn a_rod_swept_through_a_floating_sheet_pushes_it_aside() {
    let rod = r#"[{"name": "rod", "shape": "capsule", "ends": [[-0.1, -0.1, -0.005], [-0.1, 0.1, -0.005]], "radius": 0.01, "moving": true}]"#;
    let extra = r#", "ancf:solver": {"rho_inf": 1.0, "tolerance": 1e-6}, "ancf:damping": {"alpha": 0, "beta": 0}"#;
    let mut m = Model::new(square([0.0, 0.0, 0.0], rod, extra)).unwrap();
    m.initialize().unwrap();
    let speed = 0.5;
    let mut steps = 0;
    let mut pushed: f64 = 0.0;
    for k in 0..30 {
        let t = m.time();
        set(&mut m, "rod.x", [-0.1 + speed * t, speed, 0.0]);
        steps += m.advance(0.01).unwrap().steps;
        let (gap, _, _) = m.obstacle_gap().unwrap();
        assert!(
            gap > 0.0,
            "output {k}: a sample within h/2 of the rod (gap {gap:e})"
        );
        pushed = pushed.max(vector(&m, "rod.force").norm());
    }
    let c = corners(&m);
    let work = out(&m, "energy.input_work");
    let held = common::energy_and_dissipated(&m);
    eprintln!(
        "steps {steps}; corners' mean {c:?}; largest rod force at an output {pushed:.3e} N; \
         rod's work {work:.4e} J, the sheet's energies and dissipation {held:.4e} J"
    );
    assert!(c.x > 0.02 && c.z > 0.0, "the sheet was not pushed: {c:?}");
    assert!(
        work > 0.0 && (held - work).abs() < 0.01 * work,
        "{held} vs {work}"
    );
}

/// A state saved while the sheet rides a ground moving and turning (pairs
/// in the barrier, the obstacle's motion in the term memory, a kept
/// iteration matrix) continues bit for bit in the same model and in a
/// fresh one.
#[test]
fn a_state_on_a_moving_ground_restores_bit_for_bit() {
    let scene = square([0.0, 0.0, -9.81], &moving_ground(0.3), "");
    let mut a = Model::new(scene.clone()).unwrap();
    a.initialize().unwrap();
    let drive = |m: &mut Model| {
        let t = m.time();
        set(m, "ground.x", [0.02 * t, 0.02, 0.0]);
        set(m, "ground.rz", [0.5 * t, 0.5, 0.0]);
        set(m, "ground.z", [-0.00052 + 0.001 * t, 0.001, 0.0]);
    };
    for _ in 0..5 {
        drive(&mut a);
        a.advance(0.01).unwrap();
    }
    let saved = a.save_state();
    let memory = saved.term_memory.last().cloned().unwrap_or_default();
    assert!(memory.len() > 12, "obstacle memory {memory:?}");
    common::assert_restores_bit_for_bit(scene, &mut a, &saved, (8, drive));
}

/// A plain master holds its inputs: the ground's height set 2 mm up at a
/// communication point (no derivatives) would put it into the resting
/// sheet, and the advance fails naming the obstacle and what to do, the
/// state as before; raised in small held steps (10 um per 10 ms, within
/// the barrier's reach) the ground lifts the sheet.
#[test]
fn a_held_pose_input_that_jumps_into_the_sheet_is_refused_naming_the_obstacle() {
    let mut m = Model::new(square([0.0, 0.0, -9.81], &moving_ground(0.0), "")).unwrap();
    m.initialize().unwrap();
    m.advance(0.1).unwrap();
    let before = m.save_state();
    let z = m.input_id("ground.z").unwrap();
    m.set_input(z, -0.00052 + 0.002).unwrap();
    let e = m.advance(0.01).unwrap_err().to_string();
    assert!(
        e.contains("obstacle ground") && e.contains("derivatives"),
        "{e}"
    );
    assert_eq!(m.time(), before.time);
    assert_eq!(m.save_state().dynamics, before.dynamics);
    for k in 1..=20 {
        m.set_input(z, -0.00052 + 1e-5 * k as f64).unwrap();
        m.advance(0.01).unwrap();
        let (gap, _, _) = m.obstacle_gap().unwrap();
        assert!(gap > 0.0, "{k}: {gap}");
    }
    let lift = corners(&m).z - (-0.00052 + 2e-4);
    assert!((lift - 5e-4).abs() < 5e-5, "{lift}");
}

/// A forged state is refused with the fault named, the model unchanged: a
/// moving obstacle's motion that is not finite, an obstacle memory too
/// short for the motions, and a kept iteration matrix's obstacle motions
/// of the wrong length.
#[test]
fn forged_moving_obstacle_states_are_refused() {
    let mut m = Model::new(square([0.0, 0.0, -9.81], &moving_ground(0.3), "")).unwrap();
    m.initialize().unwrap();
    let t = 0.0;
    set(&mut m, "ground.x", [t, 0.02, 0.0]);
    m.advance(0.01).unwrap();
    let good = m.save_state();
    let k = good.term_memory.len() - 1;
    let mut nan = good.clone();
    nan.term_memory[k][3] = f64::NAN;
    let e = m.restore_state(&nan).unwrap_err().to_string();
    assert!(e.contains("moving obstacle value 3"), "{e}");
    let mut short = good.clone();
    short.term_memory[k].truncate(5);
    let e = m.restore_state(&short).unwrap_err().to_string();
    assert!(e.contains("motions take the first 12"), "{e}");
    let mut jac = good.clone();
    let j = jac
        .memory
        .jacobian
        .as_mut()
        .expect("a kept iteration matrix");
    assert_eq!(j.obstacles.len(), 24, "start and end motions");
    j.obstacles.push(1.0);
    let e = m.restore_state(&jac).unwrap_err().to_string();
    assert!(e.contains("memory.jacobian.obstacles"), "{e}");
    assert_eq!(m.save_state(), good);
}
