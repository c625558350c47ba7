//! Case A (docs/validation.md, Sze, Liu & Lo 2004) under mesh refinement: prints
//! a markdown table of the tip errors at M/M_max = 0.25, 0.5, 0.75 and 1,
//! the observed orders and the Newton iterations.
//! Run with `cargo bench --bench roll_up_convergence`.

use origami_fmu::benchmarks::{ROLL_UP_L, RollUp, roll_up_exact};
// Times are CPU time (this thread's clock; the benches run on one thread).
use origami_fmu::cpu_time::CpuInstant as Instant;

const RATIOS: [f64; 4] = [0.25, 0.5, 0.75, 1.0];
/// Cells along x; each doubles the previous one.
const MESHES: [usize; 7] = [4, 8, 16, 32, 64, 128, 256];

/// Signed errors of -u and w: relative to the exact value, except w at
/// the full circle (exact 0), relative to L.
fn errors(ratio: f64, u: f64, w: f64) -> [f64; 2] {
    let (ue, we) = roll_up_exact(ratio);
    let w_scale = if ratio == 1.0 { ROLL_UP_L } else { we };
    [(u - ue) / ue, (w - we) / w_scale]
}

/// `log2(a / b)` of two magnitudes, blank when either is missing or zero.
fn order(a: Option<f64>, b: Option<f64>) -> String {
    match (a, b) {
        (Some(a), Some(b)) if a != 0.0 && b != 0.0 => format!("{:.2}", (a.abs() / b.abs()).log2()),
        _ => String::new(),
    }
}

fn main() {
    // errs[mesh][ratio] = [-u error, w error], None where the solve failed.
    let mut errs: Vec<Option<Vec<[f64; 2]>>> = Vec::new();
    let mut info = Vec::new();
    for nx in MESHES {
        let start = Instant::now();
        match RollUp::new(nx).solve(&RATIOS) {
            Ok(run) => {
                let secs = start.elapsed().as_secs_f64();
                let its: Vec<usize> = run.points.iter().map(|p| p.iterations).collect();
                errs.push(Some(
                    run.points
                        .iter()
                        .map(|p| errors(p.ratio, p.u, p.w))
                        .collect(),
                ));
                info.push((run.dofs, its, secs));
                eprintln!("{nx} x 1 cells: {secs:.2} CPU s");
            }
            Err(e) => {
                eprintln!("{nx} x 1 cells failed: {e}");
                errs.push(None);
                info.push((0, vec![0; RATIOS.len()], 0.0));
            }
        }
    }
    let s = RollUp::new(1).settings;
    println!(
        "Case A, n x 1 cells split along one diagonal direction, planar (dr/dY = e_y \
         held), one load path through M/M_max = 0.25, 0.5, 0.75, 1 (largest increment \
         1/{}, relative residual {:.0e}). Errors are signed, relative to the exact value \
         (w at M/M_max = 1: relative to L). \"order\" = log2 of the error ratio to the \
         next coarser mesh; \"self\" = log2 of the ratio of successive changes over the \
         last three meshes (the order of the mesh error without the exact value). \
         Newton iterations count from the start of the path.\n",
        s.load_steps, s.tolerance
    );
    println!(
        "| cells | DOFs | M/M_max | -u error | order | self | w error | order | self | Newton its |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    let get = |i: usize, k: usize, c: usize| errs.get(i)?.as_ref().map(|e| e[k][c]);
    for (k, ratio) in RATIOS.iter().enumerate() {
        for (i, nx) in MESHES.iter().enumerate() {
            let (dofs, its, _) = &info[i];
            let Some(e) = &errs[i] else {
                println!("| {nx} x 1 | | {ratio} | failed | | | | | | |");
                continue;
            };
            let prev = |c| i.checked_sub(1).and_then(|j| get(j, k, c));
            let step = |j: Option<usize>, c| Some(get(j?, k, c)? - get(j? + 1, k, c)?);
            let self_order = |c| order(step(i.checked_sub(2), c), step(i.checked_sub(1), c));
            println!(
                "| {nx} x 1 | {dofs} | {ratio} | {:+.2e} | {} | {} | {:+.2e} | {} | {} | {} |",
                e[k][0],
                order(prev(0), Some(e[k][0])),
                self_order(0),
                e[k][1],
                order(prev(1), Some(e[k][1])),
                self_order(1),
                its[k],
            );
        }
    }
    let times: Vec<String> = MESHES
        .iter()
        .zip(&info)
        .map(|(nx, (_, _, secs))| format!("{nx}: {secs:.2} s"))
        .collect();
    println!(
        "\nPath time per mesh (cells along x): {}.",
        times.join(", ")
    );
}
