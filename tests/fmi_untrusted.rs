//! Every byte from outside is untrusted (issue 38): the probes that found
//! panics, hangs and silently accepted states, as regression tests through
//! the exported functions. Outputs in every state, serialized states
//! (flipped bits, truncations, a state of another scene, forged values
//! with a valid checksum), the bounds on the work of a call, and messages
//! that name what to change.

mod common;

use common::fmi::*;
use origami_fmu::fmi::container;
use origami_fmu::fmi::exports::*;
use origami_fmu::model::Model;
use origami_fmu::scene::Scene;
use serde_json::{Value, json};

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

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
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

#[test]
fn every_flipped_bit_of_a_serialized_state_is_refused_and_changes_nothing() {
    let f = running("bitflip", &square());
    let s = f.save();
    let bytes = f.serialize(s);
    let before = f.outputs();
    let mut refused = 0;
    for bit in 0..8 * bytes.len() {
        let mut b = bytes.clone();
        b[bit / 8] ^= 1 << (bit % 8);
        let (st, state) = f.deserialize(&b);
        assert_eq!(st, fmi2Error, "bit {bit} was accepted");
        assert!(state.is_null());
        refused += 1;
    }
    assert_eq!(refused, 8 * bytes.len());
    assert!(f.last().contains("fmi2DeSerializeFMUstate"), "{}", f.last());
    assert_eq!(bits(&f.outputs()), bits(&before));
    // The unchanged bytes still restore.
    let (st, state) = f.deserialize(&bytes);
    assert_eq!(st, fmi2OK, "{}", f.last());
    assert_eq!(f.restore(state), fmi2OK);
    assert_eq!(f.step(0.03, 0.01), fmi2OK);
    f.free_state(state);
    f.free_state(s);
}

#[test]
fn truncated_and_extended_states_are_refused() {
    let f = running("truncate", &square());
    let s = f.save();
    let bytes = f.serialize(s);
    for n in 0..bytes.len() {
        let (st, state) = f.deserialize(&bytes[..n]);
        assert_eq!(st, fmi2Error, "{n} of {} bytes accepted", bytes.len());
        assert!(state.is_null());
    }
    let mut longer = bytes.clone();
    longer.push(b' ');
    assert_eq!(f.deserialize(&longer).0, fmi2Error);
    assert!(f.last().contains("bytes"), "{}", f.last());
    f.free_state(s);
}

#[test]
fn a_state_of_another_scene_is_refused_with_both_guids() {
    let a = running("foreign_a", &square());
    let b = running("foreign_b", &contact_square());
    let s = a.save();
    let bytes = a.serialize(s);
    let (st, state) = b.deserialize(&bytes);
    assert_eq!(st, fmi2Error);
    assert!(state.is_null());
    let msg = b.last();
    assert!(msg.contains("belongs to the FMU with GUID"), "{msg}");
    // In memory too: a state of one FMU is refused by an instance of another.
    let before = b.outputs();
    assert_eq!(b.restore(s), fmi2Error);
    assert!(
        b.last().contains("belongs to the FMU with GUID"),
        "{}",
        b.last()
    );
    assert_eq!(bits(&b.outputs()), bits(&before));
    a.free_state(s);
}

/// `bytes` (a serialized state) with `edit` applied to its payload and
/// sealed again with a valid checksum: what a forger would hand in.
fn forged(bytes: &[u8], edit: impl FnOnce(&mut Value)) -> Vec<u8> {
    let guid = container::guid(bytes).expect("a container").to_string();
    let payload = container::open(&guid, bytes).expect("a valid state");
    let mut v: Value = serde_json::from_slice(payload).unwrap();
    edit(&mut v);
    container::seal(&guid, &serde_json::to_vec(&v).unwrap())
}

/// Set the JSON value at `pointer` (it must exist).
fn put(v: &mut Value, pointer: &str, x: Value) {
    *v.pointer_mut(pointer)
        .unwrap_or_else(|| panic!("no {pointer} in the state")) = x;
}

#[test]
fn forged_values_with_a_valid_checksum_are_refused_and_change_nothing() {
    let scene = contact_square();
    let f = running("forge", &scene);
    let s = f.save();
    let bytes = f.serialize(s);
    assert_eq!(f.deserialize(&bytes).0, fmi2OK, "the untouched state");
    let p = |name: &str| format!("/model/parameters/{}", vr(&scene, name));
    let n_out = f.counts.2;
    // A state whose outputs are read from it stores none: the forger hands
    // in the list of outputs read now, edited.
    let stored = f.outputs();
    type Edit = Box<dyn Fn(&mut Value)>;
    let cases: Vec<(&str, Edit, &str)> = vec![
        (
            "max_step 1e-12, max_internal_steps 1e18 (a hang)",
            Box::new({
                let (a, b) = (p("solver.max_step"), p("solver.max_internal_steps"));
                move |v| {
                    put(v, &a, json!(1e-12));
                    put(v, &b, json!(1e18));
                }
            }),
            "solver.max",
        ),
        (
            "max_step -1 (a spin)",
            Box::new({
                let a = p("solver.max_step");
                move |v| put(v, &a, json!(-1.0))
            }),
            "solver.max_step",
        ),
        (
            "rho_inf 5",
            Box::new({
                let a = p("solver.rho_inf");
                move |v| put(v, &a, json!(5.0))
            }),
            "solver.rho_inf",
        ),
        (
            "tolerance 50",
            Box::new({
                let a = p("solver.tolerance");
                move |v| put(v, &a, json!(50.0))
            }),
            "solver.tolerance",
        ),
        (
            "a stored output of 1e308",
            Box::new({
                let stored = stored.clone();
                move |v| {
                    store_outputs(v, &stored);
                    put(v, "/model/outputs/0", json!(1e308))
                }
            }),
            "outputs",
        ),
        (
            "an output list one short",
            Box::new({
                let stored = stored.clone();
                move |v| {
                    store_outputs(v, &stored);
                    let o = v.pointer_mut("/model/outputs").unwrap();
                    o.as_array_mut().unwrap().truncate(n_out - 1);
                }
            }),
            "outputs",
        ),
        (
            "extra_pairs out of range",
            Box::new(|v| put(v, "/model/extra_pairs", json!([[0, 1_000_000]]))),
            "extra_pairs",
        ),
        (
            "a contact pair stiffness of -1",
            Box::new(|v| forge_term_memory(v, true, json!([0.0, 0.0, 1.0, 2.0, 3.0, -1.0]))),
            "term_memory",
        ),
        (
            "a contact pair on vertex 1e9",
            Box::new(|v| forge_term_memory(v, true, json!([1.0, 0.0, 1.0, 2.0, 1e9, 1.0]))),
            "term_memory",
        ),
        (
            "a crease stop point 1e6",
            Box::new(|v| forge_term_memory(v, true, json!([2.0, 1e6, 0.0, 0.0, 0.0, 1.0]))),
            "term_memory",
        ),
        (
            "a crease stop entry with a vertex after its point",
            Box::new(|v| forge_term_memory(v, true, json!([2.0, 0.0, 3.0, 0.0, 0.0, 1.0]))),
            "term_memory",
        ),
        (
            "a crease stop stiffness of 0",
            Box::new(|v| forge_term_memory(v, true, json!([2.0, 0.0, 0.0, 0.0, 0.0, 0.0]))),
            "term_memory",
        ),
        (
            "a contact pair list of five values",
            Box::new(|v| forge_term_memory(v, true, json!([0.0, 0.0, 1.0, 2.0, 3.0]))),
            "term_memory",
        ),
        (
            "a candidate cache origin of one entry",
            Box::new(|v| forge_term_memory(v, true, json!([3.0, 0.0, 0.0, 0.0, 0.0, 0.0]))),
            "term_memory",
        ),
        (
            "a candidate cache origin entry out of order",
            Box::new(|v| forge_origin(v, 1, json!(0.0))),
            "term_memory",
        ),
        (
            "a candidate cache origin value of 1e300",
            Box::new(|v| forge_origin(v, 2, json!(1e300))),
            "term_memory",
        ),
        (
            "memory for a term that carries none",
            Box::new(|v| forge_term_memory(v, false, json!([1.0]))),
            "term_memory",
        ),
        (
            "Jacobian arrays of the wrong length",
            Box::new(|v| {
                let j = v.pointer_mut("/model/memory/jacobian").unwrap();
                assert!(!j.is_null(), "the state holds an iteration matrix");
                j["q"].as_array_mut().unwrap().pop();
            }),
            "jacobian",
        ),
        (
            "a Jacobian step of -1",
            Box::new(|v| put(v, "/model/memory/jacobian/h", json!(-1.0))),
            "jacobian",
        ),
        (
            "positions one short",
            Box::new(|v| {
                v.pointer_mut("/model/dynamics/q")
                    .unwrap()
                    .as_array_mut()
                    .unwrap()
                    .pop();
            }),
            "dynamics",
        ),
        (
            "a velocity of 1e300",
            Box::new(|v| put(v, "/model/dynamics/v/0", json!(1e300))),
            "dynamics",
        ),
        (
            "crease angles one long",
            Box::new(|v| {
                v.pointer_mut("/model/crease_theta")
                    .unwrap()
                    .as_array_mut()
                    .unwrap()
                    .push(json!(3.0));
            }),
            "crease_theta",
        ),
        (
            "time 1e308",
            Box::new(|v| put(v, "/model/time", json!(1e308))),
            "time",
        ),
        (
            "next step size -1",
            Box::new(|v| put(v, "/model/memory/h_next", json!(-1.0))),
            "h_next",
        ),
        (
            "an input of 1e308",
            Box::new(|v| put(v, "/model/inputs_now/0", json!(1e308))),
            "fold",
        ),
        (
            "an actuator's response of 1e308",
            Box::new(|v| put(v, "/model/actuators/0/0", json!(1e308))),
            "actuators",
        ),
        (
            "a slope of 1e308",
            Box::new(|v| put(v, "/model/input_slopes/0", json!(1e308))),
            "fold",
        ),
        (
            "a second derivative of 1e308",
            Box::new(|v| put(v, "/model/input_second_derivatives/0", json!(1e308))),
            "input_second_derivatives",
        ),
        (
            "the model's phase before initialization with the FMU stepping",
            Box::new(|v| put(v, "/model/phase", json!("Setup"))),
            "phase",
        ),
        (
            "a stop time before the start time",
            Box::new(|v| {
                put(v, "/start_time", json!(1.0));
                put(v, "/stop_time", json!(0.5));
            }),
            "stop",
        ),
        (
            "a predictor streak at the largest u32",
            Box::new(|v| {
                put(
                    v,
                    "/model/memory/newton/extrapolation_streak",
                    json!(u32::MAX),
                )
            }),
            "extrapolation_streak",
        ),
        (
            "friction forces one short",
            Box::new(|v| {
                let fr = v.pointer_mut("/model/dissipative_force/friction").unwrap();
                let a = fr.as_array_mut().unwrap();
                assert!(!a.is_empty(), "contact keeps its friction forces");
                a.pop();
            }),
            "dissipative_force",
        ),
        (
            "friction work of 1e300",
            Box::new(|v| put(v, "/model/work/friction", json!(1e300))),
            "work",
        ),
        (
            "a parameter list one short",
            Box::new(|v| {
                v.pointer_mut("/model/parameters")
                    .unwrap()
                    .as_array_mut()
                    .unwrap()
                    .pop();
            }),
            "parameters",
        ),
        (
            "the payload's GUID of another FMU",
            Box::new(|v| put(v, "/guid", json!("{00000000-0000-0000-0000-000000000000}"))),
            "GUID",
        ),
        (
            "not a state at all",
            Box::new(|v| *v = json!({"guid": 1})),
            "fmi2DeSerializeFMUstate",
        ),
    ];
    let before = f.outputs();
    for (what, edit, expect) in &cases {
        let b = forged(&bytes, edit);
        let (st, state) = f.deserialize(&b);
        assert_eq!(st, fmi2Error, "{what}: accepted");
        assert!(state.is_null(), "{what}");
        let msg = f.last();
        assert!(
            msg.contains(expect),
            "{what}: the message should name {expect:?}: {msg}"
        );
        assert_eq!(bits(&f.outputs()), bits(&before), "{what}: changed");
    }
    assert_eq!(f.count(fmi2Fatal), 0);
    // The instance goes on as if nothing happened.
    assert_eq!(f.step(0.03, 0.01), fmi2OK);
    f.free_state(s);
}

/// Store `values` as the state's outputs where it holds none (they were
/// to be read from the state).
fn store_outputs(v: &mut Value, values: &[f64]) {
    let o = v.pointer_mut("/model/outputs").expect("an outputs field");
    if o.is_null() {
        *o = json!(values);
    }
}

/// Replace the saved memory of the contact term (`contact`, the last
/// term) or of the first term by `x`.
fn forge_term_memory(v: &mut Value, contact: bool, x: Value) {
    let t = v
        .pointer_mut("/model/term_memory")
        .unwrap()
        .as_array_mut()
        .unwrap();
    assert!(t.len() > 1, "one memory per force term");
    let k = if contact { t.len() - 1 } else { 0 };
    t[k] = x;
}

/// Set value `at` of the last entry of contact's memory list, the last of
/// the candidate cache's origin (kind 3), to `x`.
fn forge_origin(v: &mut Value, at: usize, x: Value) {
    let mem = v.pointer_mut("/model/term_memory").unwrap();
    let contact = mem.as_array_mut().unwrap().last_mut().unwrap();
    let list = contact.as_array_mut().unwrap();
    let k = list.len() - 6;
    assert_eq!(list[k], json!(3.0), "the state lists the cache's origin");
    list[k + at] = x;
}

/// The Rust API validates what it restores too: a state with forged
/// values is refused and the model is left as it was.
#[test]
fn model_restore_refuses_forged_states_and_changes_nothing() {
    let mut m = Model::new(contact_square()).unwrap();
    m.initialize().unwrap();
    m.set_input(m.input_at(0).unwrap(), 0.5).unwrap();
    m.advance(0.01).unwrap();
    let good = m.save_state();
    let n = good.dynamics.q.len();
    let mut cases: Vec<(&str, origami_fmu::ModelState)> = Vec::new();
    let mut s = good.clone();
    s.extra_pairs.push((0, 10 * n));
    cases.push(("extra_pairs", s));
    let mut s = good.clone();
    if let Some(j) = s.memory.jacobian.as_mut() {
        j.theta0.push(0.0);
    }
    cases.push(("jacobian", s));
    let mut s = good.clone();
    s.dynamics.abar.truncate(1);
    cases.push(("dynamics", s));
    let mut s = good.clone();
    s.parameters[0] = -1.0;
    cases.push(("material.youngs_modulus", s));
    let mut s = good.clone();
    s.time = f64::NAN;
    cases.push(("time", s));
    let mut s = good.clone();
    s.term_memory
        .last_mut()
        .unwrap()
        .extend([0.0, 0.0, 1.0, 2.0, 3.0, f64::NAN]);
    cases.push(("term_memory", s));
    let mut s = good.clone();
    s.term_memory.pop();
    cases.push(("term_memory", s));
    let mut s = good.clone();
    s.viscous_force = vec![0.0; n + 1];
    cases.push(("viscous_force", s));
    let before = m.output_values();
    for (expect, s) in cases {
        let e = m.restore_state(&s).unwrap_err().to_string();
        assert!(e.contains(expect), "{expect}: {e}");
        assert_eq!(m.save_state(), good, "{expect}: the state changed");
        assert_eq!(bits(&m.output_values()), bits(&before));
    }
    m.advance(0.01).unwrap();
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
        assert_eq!(
            f.set(&[vr(&scene, name)], &[bad]),
            fmi2Error,
            "{name} = {bad}"
        );
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

/// Values that cannot give finite forces are refused when set, by name;
/// an initialization or a step whose forces are not finite names the
/// force term and the variables that set it, with their values.
#[test]
fn non_finite_forces_name_the_variables_to_change() {
    let scene = square();
    let f = Fmu::of("names", &scene);
    for (name, value) in [
        ("material.density", 1e-300),
        ("crease.length_scale", 1e-300),
        ("tip.x", 1e308),
    ] {
        assert_eq!(f.set(&[vr(&scene, name)], &[value]), fmi2Error);
        let msg = f.last();
        let limit = msg.contains("at least 1e-30") || msg.contains("at most 1e30");
        assert!(msg.contains(name) && limit, "{msg}");
    }
    // Within the limits one by one, beyond them together: the step says
    // which term and which values.
    for (name, value) in [
        ("material.youngs_modulus", 1e30),
        ("material.thickness", 1e30),
        ("fold", 1e29),
    ] {
        assert_eq!(f.set(&[vr(&scene, name)], &[value]), fmi2OK, "{name}");
    }
    f.initialize();
    assert_eq!(f.step(0.0, 0.01), fmi2Discard);
    let msg = f.last();
    assert!(msg.contains("(those of the shell)"), "{msg}");
    assert!(
        msg.contains("check material.youngs_modulus = 1e30"),
        "{msg}"
    );
    // An initialization that fails (a scene built in code, not checked by
    // the scene reader) says the same.
    let mut s = square();
    s.material.density = 1e-300;
    s.material.thickness = 1e-300;
    let mut m = Model::new(s).unwrap();
    let e = m.initialize().unwrap_err().to_string();
    assert!(
        e.contains("not finite") && e.contains("material.density = 1e-300"),
        "{e}"
    );
}
