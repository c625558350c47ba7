//! A scene pays only for the force terms it has. Part 1 times one
//! evaluation of the internal force (and of force plus iteration matrix)
//! on an 8x8 Miura-ori sheet for each combination of damping terms and
//! crease torques; part 2 times whole simulations with and without gravity
//! and vertex-force inputs, per Newton iteration. Absent terms cost
//! nothing: the bare rows are the floor, and each term adds its own price.
//!
//! `cargo bench --bench terms -- [--size 8] [--repeats 50]`

use origami_fmu::assembly::{Assembler, Evaluation, MatrixCoeffs, Physics, State};
use origami_fmu::benchmarks::{fold_by_ramp, miura_scene};
use origami_fmu::element::ElementOptions;
use origami_fmu::ids::VertexId;
use origami_fmu::model::{Model, StepReport};
use origami_fmu::scene::VertexInput;
// Times are CPU time (this thread's clock; the benches run on one thread).
use origami_fmu::cpu_time::CpuInstant as Instant;

use origami_fmu::benchmarks::{arg, best_us};

/// Deterministic pseudo-random numbers in [-1, 1].
fn noise(i: usize) -> f64 {
    let x = (i as u64)
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((x >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
}

fn main() {
    let size = arg("--size", 8);
    let repeats = arg("--repeats", 50);
    let scene = miura_scene(size);
    let mesh = &scene.mesh;
    // The scene's own physics, every damping term off.
    let bare = Physics {
        crease_c_per_length: 0.0,
        alpha: 0.0,
        beta: 0.0,
        ..origami_fmu::model::physics(&scene)
    };
    println!(
        "Part 1: one evaluation on {size}x{size} Miura-ori, best of {repeats} (CPU microseconds)"
    );
    println!("| terms | DOFs | force | force + matrix | force vs bare | force + matrix vs bare |");
    println!("|---|---|---|---|---|---|");
    let variants: [(&str, Physics, bool); 6] = [
        ("bare: shell + crease springs", bare, false),
        ("+ crease torque inputs", bare, true),
        (
            "+ mass damping (alpha)",
            Physics { alpha: 5.0, ..bare },
            false,
        ),
        (
            "+ stiffness damping (beta)",
            Physics { beta: 1e-4, ..bare },
            false,
        ),
        (
            "+ crease dashpots",
            Physics {
                crease_c_per_length: 1e-6,
                ..bare
            },
            false,
        ),
        (
            "all of the above",
            Physics {
                alpha: 5.0,
                beta: 1e-4,
                crease_c_per_length: 1e-6,
                ..bare
            },
            true,
        ),
    ];
    struct Case {
        name: &'static str,
        asm: Assembler,
        q: Vec<f64>,
        v: Vec<f64>,
        theta0: Vec<f64>,
        moment: Vec<f64>,
        theta_prev: Vec<f64>,
        best: (f64, f64),
    }
    let mut cases: Vec<Case> = variants
        .into_iter()
        .map(|(name, physics, torque)| {
            let asm =
                Assembler::new(mesh, physics, ElementOptions::default(), &[]).expect("assembler");
            let n = asm.n_dofs();
            let q_ref = asm.layout.reference_state(mesh);
            // A slightly deformed, moving state: every term has work to do.
            let q = q_ref
                .iter()
                .enumerate()
                .map(|(i, x)| x + 1e-4 * noise(i))
                .collect();
            let v = (0..n).map(|i| 1e-2 * noise(i + n)).collect();
            let ends = asm.creases.len();
            let theta0 = vec![std::f64::consts::PI; ends];
            let moment = vec![if torque { 1e-6 } else { 0.0 }; ends];
            Case {
                name,
                asm,
                q,
                v,
                theta_prev: theta0.clone(),
                theta0,
                moment,
                best: (f64::INFINITY, f64::INFINITY),
            }
        })
        .collect();
    let mut ev = Evaluation::default();
    let co = MatrixCoeffs {
        k: 1.0,
        c: 100.0,
        m: 1e4,
    };
    // Rounds interleave the cases, so a slow spell of the shared machine
    // hits them alike; each keeps its best time.
    for _ in 0..repeats {
        for c in cases.iter_mut() {
            let st = State {
                q: &c.q,
                v: &c.v,
                theta0: &c.theta0,
                moment: &c.moment,
                theta_prev: &c.theta_prev,
            };
            let mut matrix = vec![0.0; c.asm.nnz()];
            let force = best_us(1, || c.asm.evaluate(&st, &mut ev, None).expect("evaluate"));
            let full = best_us(1, || {
                c.asm
                    .evaluate(&st, &mut ev, Some((&mut matrix[..], co)))
                    .expect("evaluate")
            });
            c.best = (c.best.0.min(force), c.best.1.min(full));
        }
    }
    let base = cases[0].best;
    for c in &cases {
        let (force, full) = c.best;
        println!(
            "| {} | {} | {force:.0} | {full:.0} | {:.2} | {:.2} |",
            c.name,
            c.asm.n_dofs(),
            force / base.0,
            full / base.1
        );
    }

    println!();
    println!(
        "Part 2: {size}x{size} Miura-ori, first 0.2 s of a fold over 0.5 s (tolerance 1e-3, 10 ms steps), best of 3, CPU per Newton iteration"
    );
    println!(
        "| scene | steps (rejected) | Newton its | factorizations | CPU per iteration (ms) | vs bare |"
    );
    println!("|---|---|---|---|---|---|");
    let names = ["bare", "+ gravity", "+ 4 vertex-force inputs (zero)"];
    let mut best = [f64::INFINITY; 3];
    let mut counts = [
        StepReport::default(),
        StepReport::default(),
        StepReport::default(),
    ];
    for _ in 0..3 {
        for k in 0..3 {
            let mut sc = miura_scene(size);
            sc.solver.max_step = 1e-2;
            sc.solver.tolerance = 1e-3;
            if k == 1 {
                sc.gravity = Some([0.0, 0.0, -9.81]);
            }
            if k == 2 {
                sc.vertex_forces = (0..4)
                    .map(|i| VertexInput {
                        name: format!("force{i}"),
                        vertex: VertexId(i),
                    })
                    .collect();
            }
            let mut m = Model::new(sc).expect("model");
            m.initialize().expect("initialize");
            let start = Instant::now();
            let total = fold_by_ramp(&mut m, 20, 0.01, 0.5);
            let per_it = start.elapsed().as_secs_f64() * 1e3 / total.newton_iterations as f64;
            best[k] = best[k].min(per_it);
            counts[k] = total;
        }
    }
    for k in 0..3 {
        let t = &counts[k];
        println!(
            "| {} | {} ({}) | {} | {} | {:.2} | {:.2} |",
            names[k],
            t.steps,
            t.rejected,
            t.newton_iterations,
            t.factorizations,
            best[k],
            best[k] / best[0]
        );
    }
}
