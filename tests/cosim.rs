//! The co-simulation contract on the Model API (issue 16): inputs held over
//! a step as FMI 2.0 masters set them, input slopes, rigid motion left
//! undamped by the default damping, damping parameters that act, the cap on
//! internal steps, parameter values that never panic, and restores that
//! repeat bit for bit while the iteration matrix is kept across steps.

mod common;

use common::{crease_angle, input, two_panels};
use nalgebra::Vector3;
use origami_fmu::assembly::Assembler;
use origami_fmu::element::ElementOptions;
use origami_fmu::ids::VertexId;
use origami_fmu::mesh::builders::square_with_diagonal;
use origami_fmu::model::{Error, Model, ParameterId, physics};
use origami_fmu::scene::{InputTiming, Integrator, Scene};
use std::panic::{AssertUnwindSafe, catch_unwind};

const W: f64 = 0.02;

fn parameter(m: &Model, name: &str) -> ParameterId {
    m.parameter_id(name)
        .unwrap_or_else(|| panic!("no parameter {name}"))
}

/// Positions of every FOLD vertex, flattened.
fn positions(m: &Model) -> Vec<f64> {
    (0..m.scene().fold_vertex_count)
        .flat_map(|v| m.vertex_position(VertexId(v)))
        .collect()
}

/// The user's fold step: the shipped single crease
/// (scenes/single_crease.fold), its fold input set from 0 to 1 before the
/// first step, read 10 ms later through communication steps of 10 ms, 1 ms
/// and 0.1 ms: the angles agree within 0.5 degrees.
/// - With a servo (`actuator.time_constant` 4.63 ms, the automatic value
///   this scene had as its default until issue 51) at the default
///   tolerance: the servo spreads the step over its time constant, so no
///   step of the master excites what the tolerance cannot follow.
/// - With the ideal actuator (the default since issue 51) the 90 degree
///   rest-angle jump rings the crease's nodes at about 770 Hz; the default
///   tolerance 1e-4 follows that ringing to 0.6-1.7 degrees of the
///   converged 91.81 (91.17, 91.23, 93.48; measured 2026-12-06), tolerance
///   1e-5 to 0.2 degrees: the comparison runs at 1e-5.
#[test]
fn a_fold_step_reads_the_same_through_every_communication_step() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/single_crease.fold");
    let angle_after = |big_h: f64, tau: f64, tolerance: Option<f64>| {
        let (scene, _) = origami_fmu::scene::load(path).unwrap();
        let mut m = Model::new(scene).unwrap();
        m.set_parameter(parameter(&m, "actuator.time_constant"), tau)
            .unwrap();
        if let Some(t) = tolerance {
            m.set_parameter(parameter(&m, "solver.tolerance"), t)
                .unwrap();
        }
        m.initialize().unwrap();
        let fold = input(&m, "fold");
        m.set_input(fold, 1.0).unwrap();
        for _ in 0..(0.01 / big_h).round() as usize {
            m.advance(big_h).unwrap();
        }
        crease_angle(&m).to_degrees()
    };
    for (tau, tolerance) in [(0.004631296329969823, None), (0.0, Some(1e-5))] {
        let a = [1e-2, 1e-3, 1e-4].map(|h| angle_after(h, tau, tolerance));
        println!("time constant {tau} s: angle 10 ms after the step: {a:?} deg");
        assert!(a[0] > 1.0, "the crease moved: {} deg", a[0]);
        for x in &a[1..] {
            assert!((x - a[0]).abs() < 0.5, "time constant {tau} s: {a:?}");
        }
    }
}

/// A fold step (0 -> 0.1, a 0.15 rad rest-angle jump) set once before the
/// step from t0 = 20 ms: the response 10 ms later is the same whether the
/// master steps by 10 ms, 1 ms or 0.1 ms (it is the held input in every
/// case), within the integrator's tolerance (set to 1e-8 here): 1e-4 of the
/// angle and 2e-6 of the sheet size. Setting the same value again before
/// every step changes nothing (bit for bit). At the default tolerance 1e-6
/// the angle's global error in this ringing transient is 2 % (0.1585 rad
/// against 0.16225 converged; 1e-7: 0.16196), which is the integrator's
/// accuracy, not the input timing.
#[test]
fn a_held_step_input_gives_one_response_for_every_communication_step() {
    let run = |big_h: f64, set_every_step: bool| {
        let mut scene = two_panels(W, 1.5, Integrator::GeneralizedAlpha);
        scene.solver.tolerance = 1e-8;
        let mut m = Model::new(scene).unwrap();
        m.initialize().unwrap();
        let fold = input(&m, "fold");
        m.advance(0.02).unwrap();
        m.set_input(fold, 0.1).unwrap();
        let n = (0.01 / big_h).round() as usize;
        for _ in 0..n {
            if set_every_step {
                m.set_input(fold, 0.1).unwrap();
            }
            m.advance(big_h).unwrap();
        }
        assert!((m.time() - 0.03).abs() < 1e-12);
        (crease_angle(&m), positions(&m))
    };
    let (a0, p0) = run(1e-2, false);
    assert!(a0 > 0.1, "the crease moved: {a0}");
    for h in [1e-3, 1e-4] {
        let (a, p) = run(h, false);
        let dp = p
            .iter()
            .zip(&p0)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        println!("H = {h:e}: angle {a:.9} vs {a0:.9}, positions differ by {dp:.2e} m");
        assert!((a - a0).abs() < 1e-4 * a0, "H = {h}: angle {a} vs {a0}");
        assert!(dp < 2e-6 * 2.0 * W, "H = {h}: positions differ by {dp} m");
    }
    let once = run(1e-3, false);
    let every = run(1e-3, true);
    assert_eq!(once.0.to_bits(), every.0.to_bits());
}

/// One input signal, two ways to give it: held values with their slopes
/// (fmi2SetRealInputDerivatives) and the scene option that ramps to the
/// value set for the step's end. The runs agree to round-off.
#[test]
fn slopes_reproduce_the_ramp_option() {
    let ramp = |t: f64| (t / 0.05).min(1.0);
    let run = |timing: InputTiming| {
        let mut scene = two_panels(W, 1.5, Integrator::GeneralizedAlpha);
        scene.solver.input_timing = timing;
        let mut m = Model::new(scene).unwrap();
        m.initialize().unwrap();
        let fold = input(&m, "fold");
        let h = 5e-3;
        for k in 0..20 {
            let t = k as f64 * h;
            match timing {
                InputTiming::Hold => {
                    m.set_input(fold, ramp(t)).unwrap();
                    let slope = (ramp(t + h) - ramp(t)) / h;
                    m.set_input_derivative(fold, 1, slope).unwrap();
                }
                InputTiming::FirstOrderHold => m.set_input(fold, ramp(t + h)).unwrap(),
            }
            m.advance(h).unwrap();
        }
        (crease_angle(&m), m.input(fold).unwrap())
    };
    let (a_hold, u_hold) = run(InputTiming::Hold);
    let (a_ramp, u_ramp) = run(InputTiming::FirstOrderHold);
    assert!((u_hold - 1.0).abs() < 1e-12 && (u_ramp - 1.0).abs() < 1e-12);
    assert!(
        (a_hold - a_ramp).abs() < 1e-9,
        "held with slopes {a_hold}, ramped {a_ramp}"
    );
    // Derivatives need held inputs.
    let mut scene = two_panels(W, 1.5, Integrator::GeneralizedAlpha);
    scene.solver.input_timing = InputTiming::FirstOrderHold;
    let mut m = Model::new(scene).unwrap();
    m.initialize().unwrap();
    assert!(
        m.set_input_derivative(m.input_at(0).unwrap(), 1, 1.0)
            .is_err()
    );
    assert!(
        m.set_input_derivative(m.input_at(0).unwrap(), 2, 1.0)
            .is_err()
    );
}

/// A free square sheet with one creased diagonal.
fn free_sheet() -> Scene {
    Scene::with_defaults("free", square_with_diagonal(0.1, true, 1.5))
}

/// With the default damping (on, and not small: alpha > 1/s here) a free
/// sheet under gravity falls g t^2 / 2 within 0.1 % over 0.5 s: the damping
/// acts on deformation only.
#[test]
fn a_free_sheet_falls_freely_under_the_default_damping() {
    let mut scene = free_sheet();
    scene.gravity = Some([0.0, 0.0, -9.81]);
    let mut m = Model::new(scene).unwrap();
    let alpha = m.parameter(parameter(&m, "damping.alpha")).unwrap();
    assert!(alpha > 1.0, "automatic damping is on: alpha {alpha}");
    m.initialize().unwrap();
    for _ in 0..50 {
        m.advance(0.01).unwrap();
    }
    let want = 0.5 * 9.81 * 0.25;
    for v in 0..4 {
        let z = m.vertex_position(VertexId(v))[2];
        assert!(
            ((-z) - want).abs() < 1e-3 * want,
            "vertex {v} fell {} m, free fall {want} m",
            -z
        );
    }
}

/// Angular momentum sum_i q_i x (M v)_i of the nodal state (exact for
/// M = M_s (x) I3).
fn angular_momentum(asm: &Assembler, q: &[f64], v: &[f64]) -> Vector3<f64> {
    let mut mv = vec![0.0; v.len()];
    asm.mass_mul(v, &mut mv);
    (0..q.len() / 3)
        .map(|s| {
            let x = Vector3::new(q[3 * s], q[3 * s + 1], q[3 * s + 2]);
            let p = Vector3::new(mv[3 * s], mv[3 * s + 1], mv[3 * s + 2]);
            x.cross(&p)
        })
        .sum()
}

/// A free sheet spinning at 1 rev/s about its normal through its centre,
/// one revolution: returns the relative change of its angular momentum, the
/// momentum at the end, and how far it is from where it started (m).
fn spin_one_revolution(scene: Scene, asm: &Assembler) -> (f64, Vector3<f64>, f64) {
    let mut m = Model::new(scene).unwrap();
    m.initialize().unwrap();
    let omega = 2.0 * std::f64::consts::PI;
    m.set_rigid_velocity([0.0; 3], [0.0, 0.0, omega], [0.05, 0.05, 0.0])
        .unwrap();
    let s0 = m.save_state();
    let l0 = angular_momentum(asm, &s0.dynamics.q, &s0.dynamics.v);
    assert!((l0.z).abs() > 0.0 && l0.x.abs() < 1e-12 * l0.z.abs());
    let start = positions(&m);
    for _ in 0..100 {
        m.advance(0.01).unwrap();
    }
    let s1 = m.save_state();
    let l1 = angular_momentum(asm, &s1.dynamics.q, &s1.dynamics.v);
    let back = positions(&m)
        .iter()
        .zip(&start)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    ((l1 - l0).norm() / l0.norm(), l1, back)
}

/// The default damping leaves a free spin alone: over one revolution at 1
/// rev/s its angular momentum is the undamped run's within 1e-6 (at the
/// default tolerance, where the integrator's own drift is 1.9e-4 with or
/// without damping; the sheet comes back 1.6e-4 m off), and at tolerance
/// 1e-5 the momentum is kept within 1e-4 and the sheet is back within 1e-4 m
/// of where it started.
#[test]
fn a_free_spin_keeps_its_angular_momentum() {
    let scene = free_sheet();
    let asm = Assembler::new(&scene.mesh, physics(&scene), ElementOptions::default(), &[]).unwrap();
    let (drift, l_damped, _) = spin_one_revolution(scene.clone(), &asm);
    let mut undamped = scene.clone();
    undamped.auto_damping = false;
    let (drift_undamped, l_undamped, _) = spin_one_revolution(undamped, &asm);
    let by_damping = (l_damped - l_undamped).norm() / l_undamped.norm();
    println!(
        "angular momentum drift {drift:.2e} damped, {drift_undamped:.2e} undamped; \
         damping's share {by_damping:.2e}"
    );
    assert!(
        by_damping < 1e-6,
        "the damping changes the spin by {by_damping}"
    );
    let mut tight = scene;
    tight.solver.tolerance = 1e-5;
    let (drift, _, back) = spin_one_revolution(tight, &asm);
    println!("at tolerance 1e-5: drift {drift:.2e}, return error {back:.2e} m");
    assert!(drift < 1e-4, "angular momentum drift {drift}");
    assert!(back < 1e-3 * 0.1, "return error {back} m");
}

/// Setting a damping parameter takes effect (and switches the automatic
/// damping off): ten times the automatic alpha changes the fold.
#[test]
fn damping_parameters_act() {
    let run = |alpha_factor: Option<f64>| {
        let mut m = Model::new(two_panels(W, 1.5, Integrator::GeneralizedAlpha)).unwrap();
        let ia = parameter(&m, "damping.alpha");
        let auto = m.parameter(ia).unwrap();
        if let Some(f) = alpha_factor {
            m.set_parameter(ia, f * auto).unwrap();
        }
        m.initialize().unwrap();
        let fold = input(&m, "fold");
        m.set_input(fold, 1.0).unwrap();
        for _ in 0..10 {
            m.advance(0.01).unwrap();
        }
        (crease_angle(&m), m.parameter(ia).unwrap(), auto)
    };
    let (a_auto, alpha_auto, auto) = run(None);
    let (a_same, _, _) = run(Some(1.0));
    let (a_ten, alpha_ten, _) = run(Some(10.0));
    assert_eq!(alpha_auto, auto);
    assert_eq!(alpha_ten, 10.0 * auto);
    assert_eq!(
        a_same, a_auto,
        "the automatic value set by hand is the same damping"
    );
    assert!(
        (a_ten - a_auto).abs() > 1e-3,
        "alpha x 10 changes the fold: {a_ten} vs {a_auto}"
    );
}

/// solver.max_internal_steps bounds one advance: past it the advance fails
/// cleanly with the reason, and the state is as before.
#[test]
fn the_internal_step_cap_fails_cleanly() {
    for integrator in [Integrator::GeneralizedAlpha, Integrator::CentralDifference] {
        let mut m = Model::new(two_panels(W, 1.5, integrator)).unwrap();
        let cap = parameter(&m, "solver.max_internal_steps");
        m.set_parameter(cap, 5.0).unwrap();
        m.initialize().unwrap();
        let before = m.save_state();
        match m.advance(1e3) {
            Err(Error::StepFailed { reason, .. }) => {
                assert!(reason.contains("max_internal_steps"), "{reason}")
            }
            other => panic!("{integrator:?}: expected a failed step, got {other:?}"),
        }
        assert_eq!(m.save_state(), before);
    }
}

/// max_step below min_step, a tolerance of 50 and other bad values are
/// refused with a message by set_parameter.
#[test]
fn bad_parameters_are_refused_with_a_reason() {
    let mut m = Model::new(two_panels(W, 1.5, Integrator::GeneralizedAlpha)).unwrap();
    let e = m
        .set_parameter(parameter(&m, "solver.max_step"), 1e-10)
        .unwrap_err()
        .to_string();
    assert!(e.contains("larger than max_step"), "{e}");
    let e = m
        .set_parameter(parameter(&m, "solver.tolerance"), 50.0)
        .unwrap_err()
        .to_string();
    assert!(e.contains("[1e-12, 0.5]"), "{e}");
    let e = m
        .set_parameter(parameter(&m, "solver.max_internal_steps"), 2.5)
        .unwrap_err()
        .to_string();
    assert!(e.contains("whole number"), "{e}");
}

/// Random values (in and out of range, tiny, huge, non-finite) through
/// set_parameter, then initialize and a few advances: errors are fine, a
/// panic never.
#[test]
fn parameter_fuzz_never_panics() {
    let mut seed: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut next = move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        seed
    };
    let specials = [
        0.0,
        -1.0,
        1e-300,
        1e300,
        f64::NAN,
        f64::INFINITY,
        -f64::INFINITY,
        0.5,
        1.0,
        2.0,
        1e-9,
        1e-3,
        1e6,
        -0.999,
        0.499,
    ];
    let template = Model::new(two_panels(W, 1.5, Integrator::GeneralizedAlpha)).unwrap();
    let n_par = template.parameters().len();
    let mut ran = 0;
    for case in 0..60 {
        let result = catch_unwind(AssertUnwindSafe(|| {
            let mut m = Model::new(two_panels(W, 1.5, Integrator::GeneralizedAlpha)).unwrap();
            // Bound each advance's work so that the fuzz stays quick.
            let cap = parameter(&m, "solver.max_internal_steps");
            m.set_parameter(cap, 200.0).unwrap();
            for _ in 0..3 {
                let i = (next() % n_par as u64) as usize;
                let start = m.parameters()[i].start;
                let r = next();
                let v = if r % 3 == 0 {
                    specials[(r / 3 % specials.len() as u64) as usize]
                } else {
                    start * (((r >> 8) % 2001) as f64 / 1000.0 - 0.5) * 4.0
                };
                let _ = m.set_parameter(m.parameter_at(i).unwrap(), v);
            }
            if m.initialize().is_ok() {
                let fold = input(&m, "fold");
                m.set_input(fold, 1.0).unwrap();
                for _ in 0..3 {
                    if m.advance(1e-4).is_err() {
                        break;
                    }
                    assert!(m.output_values().iter().all(|x| x.is_finite()));
                }
                true
            } else {
                false
            }
        }));
        match result {
            Ok(initialized) => ran += initialized as usize,
            Err(_) => panic!("case {case} panicked"),
        }
    }
    assert!(ran > 10, "only {ran} cases initialized");
}

/// The iteration matrix is kept across advances; a state restored into
/// the same or a fresh instance re-forms it and continues bit for bit.
#[test]
fn restores_repeat_bit_for_bit_with_the_kept_matrix() {
    let drive = |m: &mut Model, k0: usize, n: usize| -> Vec<Vec<u64>> {
        let fold = input(m, "fold");
        (k0..k0 + n)
            .map(|k| {
                m.set_input(fold, (k as f64 * 0.002 / 0.05).min(1.0))
                    .unwrap();
                m.advance(2e-3).unwrap();
                m.output_values().iter().map(|x| x.to_bits()).collect()
            })
            .collect()
    };
    let mut a = Model::new(two_panels(W, 1.5, Integrator::GeneralizedAlpha)).unwrap();
    a.initialize().unwrap();
    drive(&mut a, 0, 15);
    let saved = a.save_state();
    assert!(
        saved.memory.jacobian.is_some(),
        "modified Newton keeps a matrix"
    );
    let first = drive(&mut a, 15, 15);
    a.restore_state(&saved).unwrap();
    assert_eq!(drive(&mut a, 15, 15), first, "same instance");
    let mut b = Model::new(two_panels(W, 1.5, Integrator::GeneralizedAlpha)).unwrap();
    b.initialize().unwrap();
    let json = serde_json::to_string(&saved).unwrap();
    b.restore_state(&serde_json::from_str(&json).unwrap())
        .unwrap();
    assert_eq!(
        drive(&mut b, 15, 15),
        first,
        "fresh instance, serialized state"
    );
}

/// A step the error control cannot make accurate enough is taken at the
/// minimum step size, whatever its error, also where the communication
/// step is a little more than a multiple of it (the last step then joins
/// the rest, stretched by up to 1e-3; a stretched step must still count as
/// at the minimum, or a large error is rejected for ever).
#[test]
fn steps_at_the_minimum_size_are_accepted_when_the_rest_is_no_multiple() {
    let mut scene = two_panels(W, 1.5, Integrator::GeneralizedAlpha);
    scene.solver.tolerance = 1e-14;
    scene.solver.min_step = 5e-5;
    let mut m = Model::new(scene).unwrap();
    m.initialize().unwrap();
    let h = 4.0005 * 5e-5;
    let mut steps = 0;
    for _ in 0..3 {
        let r = m.advance(h).unwrap();
        steps += r.steps;
    }
    // Four stretched minimum steps per advance.
    assert_eq!(steps, 12);
    assert!(positions(&m).iter().all(|x| x.is_finite()));
}
