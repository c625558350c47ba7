//! End-to-end model checks: a single crease driven through its rest angle
//! folds to the target and settles there (docs/validation.md case C: driving the
//! rest angle quasi-statically must end at phi_0 with zero crease moment).

use origami_fmu::element::Rule;
use origami_fmu::ids::VertexId;
use origami_fmu::mesh::builders::grid;
use origami_fmu::model::Model;
use origami_fmu::scene::{Fix, Scene, Support};

fn two_panels(target: f64) -> Scene {
    // Two 20 mm x 20 mm panels; crease along x = 20 mm; left edge clamped.
    let mesh = grid(0.04, 0.02, 2, 1, &[(1, target)]);
    let mut scene = Scene::with_defaults("two_panels", mesh);
    scene.supports.push(Support {
        vertices: vec![VertexId(0), VertexId(3)],
        fix: Fix::Clamped,
    });
    scene
}

fn angle(model: &Model) -> f64 {
    let names: Vec<&str> = model.outputs().iter().map(|v| v.name.as_str()).collect();
    let i = names
        .iter()
        .position(|n| n.starts_with("crease["))
        .expect("crease output");
    model.output_values()[i]
}

#[test]
fn rest_angle_ramp_folds_to_target() {
    for target in [1.2f64, -2.0, 3.0] {
        let mut m = Model::new(two_panels(target)).unwrap();
        m.initialize().unwrap();
        let fold = m.input_id("fold").unwrap();
        // ramp over 0.2 s, hold 0.8 s
        let steps = 100;
        for k in 1..=steps {
            let t = k as f64 * 0.01;
            m.set_input(fold, (t / 0.2).min(1.0)).unwrap();
            m.advance(0.01).unwrap();
            assert!(m.output_values().iter().all(|x| x.is_finite()));
        }
        let phi = angle(&m);
        assert!(
            (phi - target).abs() < 5e-3 * target.abs(),
            "target {target}: final angle {phi}"
        );
        let [_, _, crease_e] = m.energies();
        assert!(crease_e < 1e-9, "crease energy left {crease_e}");
    }
}

/// The scene's quadrature reaches the element: with `"quadrature":
/// "7-point"` the fold takes a different path (the mid-fold angle differs),
/// and both rules end at the same stress-free fold (within 1e-3 of the
/// target and of each other, crease energy below 1e-9 J).
#[test]
fn both_quadrature_rules_fold_to_the_target() {
    let target = 1.2f64;
    let run = |rule: Rule| {
        let mut scene = two_panels(target);
        scene.solver.quadrature = rule;
        let mut m = Model::new(scene).unwrap();
        m.initialize().unwrap();
        let fold = m.input_id("fold").unwrap();
        let mut mid = 0.0;
        for k in 1..=100 {
            let t = k as f64 * 0.01;
            m.set_input(fold, (t / 0.2).min(1.0)).unwrap();
            m.advance(0.01).unwrap();
            if k == 10 {
                mid = angle(&m);
            }
        }
        let [_, _, crease_e] = m.energies();
        (mid, angle(&m), crease_e)
    };
    let (mid12, end12, e12) = run(Rule::Dunavant12);
    let (mid7, end7, e7) = run(Rule::Dunavant7);
    assert!(mid12 != mid7, "the rule must reach the element");
    for (end, e) in [(end12, e12), (end7, e7)] {
        assert!((end - target).abs() < 1e-3 * target, "final angle {end}");
        assert!(e < 1e-9, "crease energy left {e}");
    }
    assert!((end12 - end7).abs() < 1e-3 * target, "{end12} vs {end7}");
}

/// Undamped, unforced, rho_inf = 1: the total energy of a small crease
/// oscillation stays constant (trapezoidal rule), and rho_inf = 0.5 makes it
/// decay: the peak energy of every 10 ms window (about two periods of
/// the fast panel modes) is below the previous window's. Sampled every 1 ms,
/// the physical energy itself may rise by ~1e-5 relative between samples:
/// generalized-alpha dissipates a quadratic form that includes algorithmic
/// terms, not exactly the physical energy.
#[test]
fn energy_conservation_and_decay() {
    for (rho, conserve) in [(1.0, true), (0.5, false)] {
        let mut scene = two_panels(1e-4);
        scene.auto_damping = false;
        scene.solver.rho_inf = rho;
        scene.solver.max_step = 2e-4;
        scene.solver.tolerance = 1e-4;
        // Energy conservation is a property of the exactly solved scheme:
        // full Newton converges quadratically far below its tolerance, while
        // modified Newton stops near it (a 1e-7 m random walk per step).
        scene.solver.newton = origami_fmu::scene::NewtonMode::Full;
        let mut m = Model::new(scene).unwrap();
        let fold = m.input_id("fold").unwrap();
        m.set_input(fold, 1.0).unwrap(); // released from flat with a 1e-4 rad rest angle (linear regime)
        m.initialize().unwrap();
        let total = |m: &Model| m.energies().iter().sum::<f64>();
        let e0 = total(&m);
        assert!(e0 > 0.0);
        let mut prev = e0;
        let mut worst: f64 = 0.0;
        let (mut window_max, mut last_window, mut step) = (0.0f64, f64::INFINITY, 0);
        for _ in 0..200 {
            m.advance(1e-3).unwrap();
            let e = total(&m);
            if std::env::var("DBG").is_ok() {
                eprintln!("t {:.4} E {:?} tot {e:.6e}", m.time(), m.energies());
            }
            worst = worst.max((e - e0).abs() / e0);
            window_max = window_max.max(e);
            step += 1;
            if step % 10 == 0 {
                if !conserve {
                    assert!(
                        window_max < last_window,
                        "window peak grew: {last_window} -> {window_max}"
                    );
                }
                last_window = window_max;
                window_max = 0.0;
            }
            prev = e;
        }
        if conserve {
            assert!(worst < 1e-5, "relative energy drift {worst}");
        } else {
            assert!(prev < 0.9 * e0, "energy did not decay: {prev} vs {e0}");
        }
        eprintln!(
            "rho_inf {rho}: worst drift {worst:.3e}, final/initial {:.4}",
            prev / e0
        );
    }
}

/// docs/validation.md case C: a moment T on the crease of two panels, one
/// clamped, folds it statically to phi = T / k (k the whole crease
/// stiffness); within 0.5 % after the damped motion settles.
#[test]
fn static_moment_on_a_crease() {
    use origami_fmu::scene::{ActuatorMode, CreaseStiffness};
    let mut scene = two_panels(1.0);
    let k_per_length = 2.0e-4; // N m / (rad m)
    scene.crease = CreaseStiffness::PerLength(k_per_length);
    scene.actuators[0].mode = ActuatorMode::Torque;
    let mut m = Model::new(scene).unwrap();
    m.initialize().unwrap();
    let moment_per_length = 0.6 * k_per_length; // phi = 0.6 rad
    m.set_input(m.input_at(0).unwrap(), moment_per_length)
        .unwrap();
    for _ in 0..200 {
        m.advance(0.01).unwrap();
    }
    let phi = angle(&m);
    assert!((phi - 0.6).abs() < 0.005 * 0.6, "phi {phi} vs 0.6");
    let [ke, _, _] = m.energies();
    assert!(ke < 1e-12, "not settled: kinetic energy {ke}");
}

/// `energy.input_work` and `energy.dissipated` let a master check the
/// balance: two panels folded by their actuator (ramped to 1.5 rad over
/// 0.1 s, held) under the automatic mass damping and a crease dashpot, with
/// the trapezoidal rule (rho_inf = 1): kinetic + strain + crease energy +
/// dissipated work - input work stays within 1 % of the largest energy,
/// and the damping dissipates a good part of it.
#[test]
fn the_energy_outputs_close_the_balance_under_damping() {
    let mut scene = two_panels(1.5);
    scene.solver.rho_inf = 1.0;
    scene.solver.tolerance = 1e-6;
    scene.damping.crease = 1e-6;
    let mut m = Model::new(scene).unwrap();
    m.initialize().unwrap();
    let out = |m: &Model, name: &str| m.output(m.output_id(name).unwrap()).unwrap();
    let fold = m.input_id("fold").unwrap();
    let (mut worst, mut largest) = (0.0f64, 0.0f64);
    for k in 0..40 {
        let t = k as f64 * 5e-3;
        m.set_input(fold, (t / 0.1).min(1.0)).unwrap();
        m.set_input_derivative(fold, 1, if t < 0.1 { 10.0 } else { 0.0 })
            .unwrap();
        m.advance(5e-3).unwrap();
        let e: f64 = ["energy.kinetic", "energy.strain", "energy.crease"]
            .iter()
            .map(|n| out(&m, n))
            .sum();
        largest = largest.max(e);
        let balance = e + out(&m, "energy.dissipated") - out(&m, "energy.input_work");
        worst = worst.max(balance.abs());
    }
    let dissipated = out(&m, "energy.dissipated");
    eprintln!(
        "balance within {:.3e} of the largest energy {largest:.3e} J; dissipated {dissipated:.3e} J, input {:.3e} J",
        worst / largest,
        out(&m, "energy.input_work")
    );
    assert!(
        worst <= 0.01 * largest,
        "balance off by {:.3e}",
        worst / largest
    );
    assert!(
        dissipated > 0.05 * largest,
        "damping dissipated {dissipated:.3e} J"
    );
}
