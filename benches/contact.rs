//! What contact costs. Part 1: the contact search (broad phase, pair
//! filters, distances) on n x n Miura sheets folded half-way, against
//! the facet count: near-linear growth means a flat time per facet.
//! Part 2: whole folds with and without contact (process CPU and wall time, steps,
//! rejections, Newton steps cut by the collision check, pattern growths).
//!
//! `cargo bench --bench contact -- [--repeats 5] [--search 0]`

use origami_fmu::benchmarks::{arg, best_us, fold_by_ramp, miura_scene};
use origami_fmu::contact::{ContactSettings, ContactTerm};
use origami_fmu::cpu_time::Stopwatch;
use origami_fmu::ids::EdgeId;
use origami_fmu::mesh::Mesh;
use origami_fmu::model::Model;
use std::f64::consts::PI;

/// A crease's target (rad) from the mesh, the edge and the file's target.
type Target = dyn Fn(&Mesh, usize, f64) -> f64;

fn with_contact(mut scene: origami_fmu::Scene) -> origami_fmu::Scene {
    scene.contact = Some(ContactSettings {
        thickness: scene.material.thickness,
        ..Default::default()
    });
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
        let m = &scene.material;
        let term = ContactTerm::new(
            &scene.mesh,
            &asm.layout,
            &asm.elements,
            scene.contact.as_ref().unwrap(),
            m.density * m.thickness,
            m.youngs_modulus * m.thickness,
        )
        .unwrap();
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
    let base = |m: &Mesh, e: usize, _: f64| {
        let [a, b] = m.edges()[e].v;
        let d = m.coord(b) - m.coord(a);
        if d.x.abs() > 1e-9 && d.y.abs() > 1e-9 {
            PI
        } else if d.y.abs() <= 1e-9 {
            -PI
        } else {
            0.0
        }
    };
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
    for (name, path, target) in scenes {
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
}
