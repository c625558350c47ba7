//! What contact costs. Part 1: the contact search (broad phase, pair
//! filters, distances) on n x n Miura sheets folded half-way, against
//! the facet count: near-linear growth means a flat time per facet.
//! Part 2: whole folds with and without contact (process CPU and wall time, steps,
//! rejections, Newton steps cut by the collision check, pattern growths).
//! Part 3: what reading every output after every step costs against
//! reading none (a master that records every output, as fmpy does), and
//! contact on against off where nothing touches, the runs interleaved.
//! Part 4: a flat stack released in one held communication step (the
//! deployable's scene, mu = 0 and 0.5): CPU s, steps, energy balance.
//! CPU is the process's CPU time (the machine is shared).
//!
//! `cargo bench --bench contact -- [--repeats 5] [--search 0] [--folds 0] [--reads 0|1|2] [--release 0]`
//! (`--reads 2` adds the Miura folded flat to part 3.)

use origami_fmu::benchmarks::{arg, best_us, fold_by_ramp, miura_scene};
use origami_fmu::contact::ContactTerm;
use origami_fmu::cpu_time::Stopwatch;
use origami_fmu::ids::EdgeId;
use origami_fmu::mesh::Mesh;
use origami_fmu::model::Model;
use std::f64::consts::PI;

/// A crease's target (rad) from the mesh, the edge and the file's target.
type Target = dyn Fn(&Mesh, usize, f64) -> f64;

fn with_contact(mut scene: origami_fmu::Scene) -> origami_fmu::Scene {
    scene.contact = Some(scene.default_contact());
    scene
}

fn main() {
    let repeats = arg("--repeats", 5);
    println!("## Contact search against facet count (Miura n x n, folded to 0.5 of its targets)");
    println!(
        "| n | facets | contact vertices | search (CPU ms, best of repeats) | per facet (us) |"
    );
    println!("|---|---|---|---|---|");
    // `--search 0` skips part 1 (its 16 x 16 fold takes minutes).
    let sizes: &[usize] = if arg("--search", 1) == 1 {
        &[2, 4, 8, 16]
    } else {
        &[]
    };
    for &n in sizes {
        // Folded without contact (nothing touches half-way); the contact
        // term is built apart and timed on that state.
        let mut model = Model::new(miura_scene(n)).unwrap();
        model.initialize().unwrap();
        fold_by_ramp(&mut model, 20, 0.01, 0.4);
        let facets = model.scene().mesh.triangles().len();
        let state = model.save_state();
        let q = state.dynamics.q.clone();
        let scene = with_contact(model.scene().clone());
        let asm = origami_fmu::assembly::Assembler::new(
            &scene.mesh,
            origami_fmu::model::physics(&scene),
            Default::default(),
            &[],
        )
        .unwrap();
        let term = ContactTerm::on(&asm, &scene.mesh, scene.contact.as_ref().unwrap()).unwrap();
        let search = 0.01;
        let us = best_us(repeats, || {
            std::hint::black_box(term.report(&q, search));
        });
        println!(
            "| {n} | {facets} | {} | {:.3} | {:.2} |",
            term.surface().n_vertices(),
            us / 1e3,
            us / facets as f64
        );
    }
    println!();
    println!("## Folds with and without contact (defaults, 10 ms communication steps)");
    println!(
        "| scene | contact | CPU (s) | wall (s) | steps | rejected | cut by CCD | pattern growths | pairs at end |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    // Crease targets: the file's own, all to +-180 deg, or the waterbomb
    // base collapsed (diagonals valley, the x midline mountain, the y
    // midline unfolded: the file's targets are a 3D waterbomb).
    let own = |_: &Mesh, _: usize, t: f64| t;
    let flat = |_: &Mesh, _: usize, t: f64| PI * t.signum();
    let base = |m: &Mesh, e: usize, _: f64| origami_fmu::benchmarks::waterbomb_base_target(m, e);
    let scenes: [(&str, &str, &Target); 4] = [
        ("diagonal to 180 deg", "diag", &flat),
        (
            "Miura 4x4 to its targets (no touch)",
            "scenes/miura_4x4.fold",
            &own,
        ),
        (
            "Miura 4x4 folded flat (+-180 deg)",
            "scenes/miura_4x4.fold",
            &flat,
        ),
        ("waterbomb base collapsed", "scenes/waterbomb.fold", &base),
    ];
    let scenes: &[(&str, &str, &Target)] = if arg("--folds", 1) == 1 { &scenes } else { &[] };
    for &(name, path, target) in scenes {
        for contact in [false, true] {
            let mut scene = if path == "diag" {
                origami_fmu::Scene::with_defaults(
                    "diag",
                    origami_fmu::mesh::builders::square_with_diagonal(0.1, true, PI),
                )
            } else {
                origami_fmu::scene::load(path).unwrap().0
            };
            for e in 0..scene.mesh.edges().len() {
                let edge = &scene.mesh.edges()[e];
                if edge.kind == origami_fmu::mesh::EdgeKind::Crease {
                    let t = target(&scene.mesh, e, edge.fold_target);
                    scene.mesh.set_fold_target(EdgeId(e), t).unwrap();
                }
            }
            if contact {
                scene = with_contact(scene);
            }
            let mut model = Model::new(scene).unwrap();
            model.initialize().unwrap();
            let clock = Stopwatch::start();
            let r = fold_by_ramp(&mut model, 80, 0.01, 0.5);
            let (cpu, wall) = (clock.cpu(), clock.wall());
            let pairs = model.contact().map(|c| c.pairs).unwrap_or(0);
            println!(
                "| {name} | {} | {cpu:.2} | {wall:.2} | {} | {} | {} | {} | {pairs} |",
                if contact { "on" } else { "off" },
                r.steps,
                r.rejected,
                r.limited_steps,
                r.pattern_growths
            );
        }
    }
    if arg("--reads", 1) >= 1 {
        reads(arg("--reads", 1) >= 2);
        never_touching(repeats);
    }
    if arg("--release", 1) == 1 {
        release();
    }
}

/// Part 3: the same fold with every output read after every step and with
/// none read, CPU s side by side (best of three of each).
fn reads(flat_fold: bool) {
    println!();
    println!("## Reading every output after every step against reading none (best of 3, CPU s)");
    println!("| scene | contact | outputs | read none | read all | ratio |");
    println!("|---|---|---|---|---|---|");
    let flat = |_: &Mesh, _: usize, t: f64| PI * t.signum();
    let own = |_: &Mesh, _: usize, t: f64| t;
    let cases: [(&str, &Target, bool); 3] = [
        ("Miura 4x4 to its targets (nothing touches)", &own, false),
        ("Miura 4x4 to its targets (nothing touches)", &own, true),
        ("Miura 4x4 folded flat", &flat, true),
    ];
    // The flat fold (about 100 CPU s a run) only with --reads 2.
    for (name, target, contact) in cases.into_iter().take(if flat_fold { 3 } else { 2 }) {
        let mut scene = origami_fmu::scene::load("scenes/miura_4x4.fold").unwrap().0;
        for e in 0..scene.mesh.edges().len() {
            let edge = &scene.mesh.edges()[e];
            if edge.kind == origami_fmu::mesh::EdgeKind::Crease {
                let t = target(&scene.mesh, e, edge.fold_target);
                scene.mesh.set_fold_target(EdgeId(e), t).unwrap();
            }
        }
        if contact {
            scene = with_contact(scene);
        }
        let time = |read: bool| {
            (0..3)
                .map(|_| {
                    let mut model = Model::new(scene.clone()).unwrap();
                    model.initialize().unwrap();
                    let clock = Stopwatch::start();
                    let mut sink = 0.0;
                    origami_fmu::benchmarks::fold_by_ramp_with(
                        &mut model,
                        80,
                        0.01,
                        0.5,
                        true,
                        |m, _| {
                            if read {
                                sink += m.output_values().iter().sum::<f64>();
                            }
                        },
                    );
                    std::hint::black_box(sink);
                    clock.cpu()
                })
                .fold(f64::INFINITY, f64::min)
        };
        let (none, all) = (time(false), time(true));
        let outputs = Model::new(scene.clone()).unwrap().outputs().len();
        println!(
            "| {name} | {} | {outputs} | {none:.3} | {all:.3} | {:.2} |",
            if contact { "on" } else { "off" },
            all / none
        );
    }
}

/// Part 3, last: contact on against off where nothing touches (the Miura
/// 4x4 to its own targets, outputs not read), the runs interleaved (off,
/// on, off, ...) so the machine's load falls on both alike; best of
/// `repeats` each, CPU s.
fn never_touching(repeats: usize) {
    let scene = origami_fmu::scene::load("scenes/miura_4x4.fold").unwrap().0;
    let scenes = [scene.clone(), with_contact(scene)];
    let mut best = [f64::INFINITY; 2];
    for _ in 0..repeats {
        for (b, scene) in best.iter_mut().zip(&scenes) {
            let mut model = Model::new(scene.clone()).unwrap();
            model.initialize().unwrap();
            let clock = Stopwatch::start();
            origami_fmu::benchmarks::fold_by_ramp_with(&mut model, 80, 0.01, 0.5, true, |_, _| {});
            *b = b.min(clock.cpu());
        }
    }
    println!();
    println!(
        "Contact never touching, interleaved (best of {repeats}, CPU s): off {:.3}, on {:.3}, ratio {:.2}",
        best[0],
        best[1],
        best[1] / best[0]
    );
}

/// Part 4: the deployable closed flat, then its input set from 1 to 0 and
/// held over one 0.1 s communication step (tolerance 1e-6, rho_inf = 1, no
/// damping: the balance closes); CPU s of that step.
fn release() {
    println!();
    println!("## A flat stack released in one held 0.1 s communication step");
    println!(
        "| friction | CPU s | steps (rejected) | Newton its | factorizations | smallest step (s) | energy balance / largest energy |"
    );
    println!("|---|---|---|---|---|---|---|");
    for mu in [0.0, 0.5] {
        let mut scene = origami_fmu::benchmarks::deployable_scene();
        scene.solver.max_internal_steps = 1_000_000;
        let mut scene = with_contact(scene);
        if let Some(c) = scene.contact.as_mut() {
            c.friction = mu;
        }
        let mut model = Model::new(scene).unwrap();
        model.initialize().unwrap();
        let fold = model.input_id("fold").unwrap();
        let out = |m: &Model, name: &str| m.output(m.output_id(name).unwrap()).unwrap();
        let energy = |m: &Model| {
            [
                "energy.kinetic",
                "energy.strain",
                "energy.crease",
                "energy.contact",
            ]
            .iter()
            .map(|n| out(m, n))
            .sum::<f64>()
        };
        let balance =
            |m: &Model| energy(m) + out(m, "energy.dissipated") - out(m, "energy.input_work");
        let (mut worst, mut largest) = (0.0f64, 0.0f64);
        for k in 0..80 {
            let t = k as f64 * 0.005;
            let (u, s) = if t < 0.3 {
                (t / 0.3, 1.0 / 0.3)
            } else {
                (1.0, 0.0)
            };
            model.set_input(fold, u).unwrap();
            model.set_input_derivative(fold, 1, s).unwrap();
            model.advance(0.005).unwrap();
            largest = largest.max(energy(&model));
            worst = worst.max(balance(&model).abs());
        }
        model.set_input(fold, 0.0).unwrap();
        model.set_input_derivative(fold, 1, 0.0).unwrap();
        let clock = Stopwatch::start();
        let r = model.advance(0.1);
        let cpu = clock.cpu();
        match r {
            Ok(r) => {
                largest = largest.max(energy(&model));
                worst = worst.max(balance(&model).abs());
                println!(
                    "| {mu} | {cpu:.2} | {} ({}) | {} | {} | {:.1e} | {:.2e} |",
                    r.steps,
                    r.rejected,
                    r.newton_iterations,
                    r.factorizations,
                    r.min_step,
                    worst / largest
                );
            }
            Err(e) => println!("| {mu} | {cpu:.2} | failed: {e} | | | | |"),
        }
    }
}
