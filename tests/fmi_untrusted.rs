//! Every byte from outside is untrusted (issue 38): the probes that found
//! panics, hangs and silently accepted states, as regression tests through
//! the exported functions. Outputs in every state, serialized states
//! (flipped bits, truncations, a state of another scene, forged values
//! with a valid checksum), the bounds on the work of a call, and messages
//! that name what to change.

mod common;

use common::fmi::*;
use origami_fmu::fmi::exports::*;
use origami_fmu::ids::VertexId;
use origami_fmu::mesh::builders::square_with_diagonal;
use origami_fmu::model::Model;
use origami_fmu::scene::{Scene, VertexInput};

/// The square of `tests/fmi_abi.rs`: one creased diagonal, a vertex force.
fn square() -> Scene {
    let mut s = Scene::with_defaults("square", square_with_diagonal(0.1, true, 1.5));
    s.vertex_forces.push(VertexInput {
        name: "tip".into(),
        vertex: VertexId(2),
    });
    s
}

/// The square with self-contact on (contact outputs, extra matrix pairs).
fn contact_square() -> Scene {
    let mut s = square();
    s.name = "contact_square".into();
    s.contact = Some(origami_fmu::contact::ContactSettings {
        thickness: 5e-4,
        ..Default::default()
    });
    s
}

/// Value reference of the variable called `name`.
fn vr(scene: &Scene, name: &str) -> u32 {
    let m = Model::new(scene.clone()).unwrap();
    let all: Vec<&str> = m
        .parameters()
        .iter()
        .chain(m.inputs())
        .chain(m.outputs())
        .map(|v| v.name.as_str())
        .collect();
    all.iter()
        .position(|n| *n == name)
        .unwrap_or_else(|| panic!("no variable {name}")) as u32
}

/// An initialized instance of `scene` after three steps folding.
fn running(tag: &str, scene: &Scene) -> Fmu {
    let f = Fmu::of(tag, scene);
    f.initialize();
    let fold = vr(scene, "fold");
    assert_eq!(f.set(&[fold], &[0.5]), fmi2OK);
    for k in 0..3 {
        assert_eq!(f.step(k as f64 * 0.01, 0.01), fmi2OK, "{}", f.last());
    }
    f
}

#[test]
fn contact_outputs_are_readable_before_initialization_and_after_reset() {
    let scene = contact_square();
    let f = Fmu::of("contact_outputs", &scene);
    let names = ["contact.min_gap", "contact.pairs", "contact.normal_force"];
    let vrs: Vec<u32> = names.iter().map(|n| vr(&scene, n)).collect();
    let starts: Vec<f64> = {
        let m = Model::new(scene.clone()).unwrap();
        let o = m.parameters().len() + m.inputs().len();
        vrs.iter()
            .map(|&v| m.outputs()[v as usize - o].start)
            .collect()
    };
    // Instantiated, initialization mode: the start values.
    let (s, v) = f.get(&vrs);
    assert_eq!((s, &v), (fmi2OK, &starts), "{}", f.last());
    unsafe {
        assert_eq!(fmi2EnterInitializationMode(f.c), fmi2OK);
    }
    assert_eq!(f.get(&vrs), (fmi2OK, starts.clone()));
    unsafe {
        assert_eq!(fmi2ExitInitializationMode(f.c), fmi2OK);
    }
    // Running: the search's answer (nothing touches in the flat square).
    let (s, v) = f.get(&vrs);
    assert_eq!(s, fmi2OK);
    assert!(v.iter().all(|x| x.is_finite()), "{v:?}");
    assert_eq!(f.step(0.0, 0.01), fmi2OK);
    assert_eq!(f.get(&vrs).0, fmi2OK);
    // After reset: the start values again, and the instance goes on.
    unsafe {
        assert_eq!(fmi2Reset(f.c), fmi2OK);
    }
    assert_eq!(f.get(&vrs), (fmi2OK, starts.clone()));
    assert_eq!(f.get(&f.vrs().2).0, fmi2OK, "{}", f.last());
    f.initialize();
    assert_eq!(f.step(0.0, 0.01), fmi2OK);
    assert_eq!(f.count(fmi2Fatal), 0);
}

/// A step the internal-step budget cannot cover is discarded before any
/// work (the message says how many steps it would need), not after it.
#[test]
fn a_step_far_beyond_the_internal_step_budget_is_discarded_at_once() {
    let f = running("budget", &square());
    assert_eq!(f.step(0.03, 1e300), fmi2Discard);
    let msg = f.last();
    assert!(msg.contains("at least"), "{msg}");
    assert!(msg.contains("1e300"), "short numbers: {msg}");
    let mut t = 0.0;
    unsafe {
        assert_eq!(fmi2GetRealStatus(f.c, 2, &mut t), fmi2OK);
    }
    assert_eq!(t, 0.03);
}

/// Settings outside the range where a step finishes are refused, with the
/// range in the message.
#[test]
fn solver_settings_outside_their_working_range_are_refused() {
    let scene = square();
    let f = Fmu::of("settings", &scene);
    for (name, bad) in [
        ("solver.tolerance", 1e-300),
        ("solver.tolerance", 0.9),
        ("solver.max_internal_steps", 1e9),
        ("solver.max_step", 1e-12),
        ("solver.max_step", -1.0),
        ("solver.rho_inf", 5.0),
    ] {
        assert_eq!(f.set(&[vr(&scene, name)], &[bad]), fmi2Error, "{name} = {bad}");
        let msg = f.last();
        assert!(msg.contains(name), "{msg}");
    }
    // Within the range: accepted.
    assert_eq!(f.set(&[vr(&scene, "solver.tolerance")], &[1e-8]), fmi2OK);
    assert_eq!(
        f.set(&[vr(&scene, "solver.max_internal_steps")], &[1e6]),
        fmi2OK
    );
}

/// Numbers in messages are short: 1e-200, not 200 zeros.
#[test]
fn messages_print_numbers_in_short_form() {
    let f = running("short", &square());
    assert_eq!(f.step(1e-200, 0.01), fmi2Error);
    let msg = f.last();
    assert!(msg.contains("1e-200"), "{msg}");
    assert!(!msg.contains("0.0000000"), "{msg}");
    assert!(msg.len() < 300, "{msg}");
}
