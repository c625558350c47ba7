//! Issue 51: the actuators are ideal by default (the input is the rest
//! angle at once); a servo is an option (`actuator.time_constant` tau > 0)
//! whose response is the critically damped one,
//! `tau^2 a'' + 2 tau a' + a = u`, whatever the communication step.

use origami_fmu::Model;
use origami_fmu::scene::Scene;

fn single_crease() -> Scene {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/single_crease.fold");
    origami_fmu::scene::load(path).unwrap().0
}

/// The crease's full fold angle (rad): the fold input's value 1.
const TARGET: f64 = std::f64::consts::FRAC_PI_2;

/// The actuator's value (a fold fraction) as the sheet feels it now.
fn applied(m: &Model) -> f64 {
    m.save_state().actuators[0][0]
}

#[test]
fn the_actuator_is_ideal_by_default() {
    let mut m = Model::new(single_crease()).unwrap();
    let tau = m.parameter_id("actuator.time_constant").unwrap();
    assert_eq!(m.parameter(tau).unwrap(), 0.0);
    m.initialize().unwrap();
    let fold = m.input_id("fold").unwrap();
    m.set_input(fold, 0.5).unwrap();
    // The rest angle is the input's at once: before the step and after it.
    assert_eq!(applied(&m), 0.5);
    m.advance(1e-3).unwrap();
    assert_eq!(applied(&m), 0.5);
}

/// A step of the input from 0 to 1 at t = 0, held: the servo's value at
/// every communication point against the closed form
/// a(t) = 1 - (1 + t / tau) exp(-t / tau), within 1e-3 rad of rest angle,
/// for tau from 1e-4 to 1 s and communication steps from 1e-4 to 1e-2 s.
#[test]
fn the_servo_follows_its_step_response() {
    for tau in [1e-4, 1e-3, 1e-2, 0.1, 1.0] {
        for h in [1e-4, 1e-3, 1e-2] {
            let mut m = Model::new(single_crease()).unwrap();
            let p = m.parameter_id("actuator.time_constant").unwrap();
            m.set_parameter(p, tau).unwrap();
            m.initialize().unwrap();
            let fold = m.input_id("fold").unwrap();
            m.set_input(fold, 1.0).unwrap();
            assert_eq!(applied(&m), 0.0, "a servo starts where it was");
            // Over five time constants or 200 steps, whichever is shorter.
            let n = ((5.0 * tau / h).ceil() as usize).clamp(3, 200);
            let mut worst: f64 = 0.0;
            for k in 1..=n {
                m.advance(h).unwrap();
                let t = k as f64 * h;
                let exact = 1.0 - (1.0 + t / tau) * (-t / tau).exp();
                worst = worst.max((applied(&m) - exact).abs() * TARGET);
            }
            assert!(worst < 1e-3, "tau {tau} s, step {h} s: off by {worst} rad");
        }
    }
}
