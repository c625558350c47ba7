//! Which quadrature rule's coarse-mesh dynamics is closer to the converged
//! sheet: the undamped free square of `tests/fmpy/scenes/square.json`
//! (0.1 m, two facets, one diagonal crease, fold ramped to 90 degrees over
//! 0.1 s, then free) at 0, 1, 2, 3 levels of uniform refinement (2, 8, 32,
//! 128 facets) under the 7- and 12-point rules, tolerance 1e-7. Prints the
//! largest distance of the four corners from the finest 12-point run at
//! 0.02, 0.05, 0.1 and 0.2 s, in m.
//!
//! `cargo bench --bench quadrature_fidelity`

use origami_fmu::element::Rule;
use origami_fmu::ids::VertexId;
use origami_fmu::scene::refine::refine;
mod common;

const TIMES: [f64; 4] = [0.02, 0.05, 0.1, 0.2];

/// Corner positions at [`TIMES`] of the square refined `levels` times.
fn run(levels: usize, rule: Rule) -> Vec<[[f64; 3]; 4]> {
    let (mut m, fold) = common::square_model(|scene| {
        let mut scene = refine(&scene, levels).expect("refined square");
        scene.solver.quadrature = rule;
        scene.solver.tolerance = 1e-7;
        scene
    });
    let dt = 0.01;
    let mut out = Vec::new();
    for k in 1..=20 {
        let t = k as f64 * dt;
        // Ramp timing: the value set is reached at the step's end.
        m.set_input(fold, (t / 0.1).min(1.0))
            .expect("fold in range");
        m.advance(dt).expect("advance");
        if TIMES.iter().any(|&s| (s - t).abs() < 1e-9) {
            out.push([0, 1, 2, 3].map(|v| m.vertex_position(VertexId(v))));
        }
    }
    out
}

/// Largest corner distance (m) between two runs at each of [`TIMES`].
fn corner_errors(run: &[[[f64; 3]; 4]], reference: &[[[f64; 3]; 4]]) -> Vec<f64> {
    run.iter()
        .zip(reference)
        .map(|(a, b)| {
            (0..4)
                .map(|v| {
                    (0..3)
                        .map(|i| (a[v][i] - b[v][i]).powi(2))
                        .sum::<f64>()
                        .sqrt()
                })
                .fold(0.0, f64::max)
        })
        .collect()
}

fn main() {
    let finest = 3;
    let reference = run(finest, Rule::Dunavant12);
    println!(
        "| facets | rule | {} |",
        TIMES
            .map(|t| format!("corner error at {t} s (m)"))
            .join(" | ")
    );
    println!("| --- | --- |{}", " --- |".repeat(TIMES.len()));
    for levels in 0..=finest {
        for rule in [Rule::Dunavant7, Rule::Dunavant12] {
            // The finest 12-point run is the reference itself.
            if levels == finest && rule == Rule::Dunavant12 {
                continue;
            }
            let errs: Vec<String> = corner_errors(&run(levels, rule), &reference)
                .iter()
                .map(|e| format!("{e:.2e}"))
                .collect();
            println!(
                "| {} | {:?} | {} |",
                2 * 4usize.pow(levels as u32),
                rule,
                errs.join(" | ")
            );
        }
    }
}
