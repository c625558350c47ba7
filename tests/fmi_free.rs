//! Freeing (issue 38): `fmi2FreeFMUstate` frees a state in every state of
//! its instance, a dead one (after a panic) included, and
//! `fmi2FreeInstance` frees every state the instance created that the host
//! did not free. A test binary of its own without the test harness (it
//! counts the states alive in the process, and `scripts/c_host_test.sh`
//! runs it under valgrind, where the harness's threads would be noise).

mod common;

use common::fmi::*;
use origami_fmu::fmi::exports::*;
use origami_fmu::fmi::instance::live_states;
use origami_fmu::fmi::types::fmi2FMUstate;
use origami_fmu::mesh::builders::square_with_diagonal;
use origami_fmu::scene::Scene;
use std::ptr::null_mut;

fn main() {
    states_are_freed_in_every_phase_and_with_their_instance_after_a_panic();
    println!("fmi_free: states freed in every phase and with a dead instance");
}

fn states_are_freed_in_every_phase_and_with_their_instance_after_a_panic() {
    let base = live_states();
    let mut scene = Scene::with_defaults("square", square_with_diagonal(0.1, true, 1.5));
    // At most two internal steps of 1 ms: a 10 ms step is discarded.
    scene.solver.max_internal_steps = 2;
    scene.solver.max_step = 1e-3;
    let f = Fmu::of("free", &scene);
    // One state made and freed in each phase the instance passes.
    let cycle = |f: &Fmu| {
        let s = f.save();
        assert_eq!(live_states(), base + 1);
        f.free_state(s);
        assert_eq!(live_states(), base);
    };
    cycle(&f); // instantiated
    unsafe {
        assert_eq!(fmi2EnterInitializationMode(f.c), fmi2OK);
        cycle(&f); // initialization mode
        assert_eq!(fmi2ExitInitializationMode(f.c), fmi2OK);
        cycle(&f); // step complete
        assert_eq!(f.step(0.0, 0.01), fmi2Discard);
        cycle(&f); // step failed
        assert_eq!(fmi2Terminate(f.c), fmi2OK);
        cycle(&f); // terminated
        assert_eq!(fmi2Reset(f.c), fmi2OK);
    }
    f.initialize();
    // Three states: two saved, one deserialized; another instance's state
    // is not freed through this one.
    let a = f.save();
    let _b = f.save();
    let (st, _c) = f.deserialize(&f.serialize(a));
    assert_eq!(st, fmi2OK);
    assert_eq!(live_states(), base + 3);
    let g = Fmu::of("free_other", &scene);
    let mut foreign = g.save();
    unsafe {
        assert_eq!(fmi2FreeFMUstate(f.c, &mut foreign), fmi2Error);
    }
    assert!(f.last().contains("another instance"), "{}", f.last());
    assert!(!foreign.is_null());
    g.free_state(foreign);
    // A panic kills the instance: every call but the freeing ones is fatal.
    // (This test process silences the panic's text; the FMU itself installs
    // no hook.)
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    // SAFETY: a live instance.
    let killed = unsafe { guard(f.c, "test", |_| panic!("on purpose: the test kills it")) };
    std::panic::set_hook(hook);
    assert_eq!(killed, fmi2Fatal);
    unsafe {
        assert_eq!(fmi2DoStep(f.c, 0.0, 0.001, 0), fmi2Fatal);
        let mut none: fmi2FMUstate = null_mut();
        assert_eq!(fmi2GetFMUstate(f.c, &mut none), fmi2Fatal);
    }
    f.free_state(a);
    assert_eq!(live_states(), base + 2);
    // The other two are freed with the instance.
    drop(f);
    assert_eq!(live_states(), base);
    drop(g);
    assert_eq!(live_states(), base);
}
