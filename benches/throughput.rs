//! Throughput of the implicit stepper on Miura-ori sheets of growing size:
//! DOFs, internal steps per second of CPU time, Newton iterations and
//! factorizations per step, and where the time goes (assembly,
//! factorization, solves). Each sheet folds from flat under the default
//! rest-angle ramp (0 -> 1 over the first half) with 10 ms communication
//! steps.
//!
//! `cargo bench --bench throughput -- [--sizes 2,4,8,16] [--time 1.0]
//! [--tolerance 1e-3] [--newton modified|full] [--max-step 1e-3]
//! [--quadrature 7|12] [--bending pointwise|split]`
//!
//! CPU is the process's CPU clock, wall the wall clock (they differ on a
//! loaded machine); the phase shares are the stepping thread's CPU time over
//! the process's, "other" the rest (predictor, error estimate, outputs), so
//! they add up to 100 %. "sim/CPU" compares simulated time with CPU time (> 1:
//! faster than real time). The cost-growth exponent fits cost per step ~ n^p between
//! successive sizes.

use origami_fmu::benchmarks::{fold_by_ramp, miura_scene};
use origami_fmu::cpu_time::Stopwatch;
use origami_fmu::model::Model;
use origami_fmu::scene::NewtonMode;

mod common;

struct Options {
    sizes: Vec<usize>,
    time: f64,
    tolerance: f64,
    newton: NewtonMode,
    max_step: f64,
    quadrature: origami_fmu::element::Rule,
    bending: origami_fmu::element::Bending,
}

fn options() -> Options {
    let mut o = Options {
        sizes: vec![2, 4, 8, 16],
        time: 1.0,
        tolerance: 1e-3,
        newton: NewtonMode::Modified,
        max_step: 1e-3,
        quadrature: origami_fmu::element::Rule::default(),
        bending: origami_fmu::element::Bending::default(),
    };
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut i = 0;
    while i < args.len() {
        let val = args.get(i + 1).cloned().unwrap_or_default();
        match args[i].as_str() {
            "--sizes" => o.sizes = val.split(',').map(|s| s.parse().expect("size")).collect(),
            "--time" => o.time = val.parse().expect("time"),
            "--tolerance" => o.tolerance = val.parse().expect("tolerance"),
            "--max-step" => o.max_step = val.parse().expect("max step"),
            "--quadrature" => o.quadrature = common::quadrature_rule(&val),
            "--bending" => {
                o.bending = match val.as_str() {
                    "pointwise" => origami_fmu::element::Bending::Pointwise,
                    "split" => origami_fmu::element::Bending::Split,
                    _ => panic!("--bending pointwise|split"),
                }
            }
            "--newton" => {
                o.newton = match val.as_str() {
                    "full" => NewtonMode::Full,
                    "modified" => NewtonMode::Modified,
                    _ => panic!("--newton full|modified"),
                }
            }
            // cargo bench passes --bench; ignore what is not ours.
            _ => {
                i += 1;
                continue;
            }
        }
        i += 2;
    }
    o
}

fn main() {
    origami_fmu::solver::set_phase_timing(true);
    let o = options();
    println!(
        "Miura-ori folding, {} s simulated, tolerance {:.0e}, max step {:.0e} s, {:?} Newton, {:?} quadrature, {:?} bending",
        o.time, o.tolerance, o.max_step, o.newton, o.quadrature, o.bending
    );
    println!(
        "| cells | DOFs | steps | steps/s | Newton its/step | factorizations/step | assembly % | factorization % | solves % | other % | LLT/LDLT/LU | CPU s | wall s | sim/CPU | cost/step exponent |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    let mut last: Option<(usize, f64)> = None;
    for &n in &o.sizes {
        let mut sc = miura_scene(n);
        sc.solver.tolerance = o.tolerance;
        sc.solver.newton = o.newton;
        sc.solver.max_step = o.max_step;
        sc.solver.quadrature = o.quadrature;
        sc.solver.bending = o.bending;
        let mut m = Model::new(sc).expect("model");
        m.initialize().expect("initialize");
        let dt = 0.01;
        let steps = (o.time / dt).round() as usize;
        let clock = Stopwatch::start();
        let total = fold_by_ramp(&mut m, steps, dt, 0.5 * o.time);
        let (cpu, wall) = (clock.cpu(), clock.wall());
        let dofs = m.n_dofs();
        let per_step = cpu / total.steps as f64;
        let exponent = last
            .map(|(d0, c0)| {
                format!(
                    "{:.2}",
                    (per_step / c0).ln() / (dofs as f64 / d0 as f64).ln()
                )
            })
            .unwrap_or_else(|| "-".into());
        last = Some((dofs, per_step));
        let pct = |x: f64| 100.0 * x / cpu;
        let kinds = m
            .solver_stats()
            .map(|s| format!("{}/{}/{}", s.llt, s.ldlt, s.lu))
            .unwrap_or_default();
        println!(
            "| {n}x{n} | {dofs} | {} | {:.0} | {:.2} | {:.2} | {:.0} | {:.0} | {:.0} | {:.0} | {kinds} | {:.2} | {wall:.2} | {:.2} | {exponent} |",
            total.steps,
            total.steps as f64 / cpu,
            total.newton_iterations as f64 / total.steps as f64,
            total.factorizations as f64 / total.steps as f64,
            pct(total.assembly_time),
            pct(total.factor_time),
            pct(total.solve_time),
            pct(cpu - total.assembly_time - total.factor_time - total.solve_time),
            cpu,
            o.time / cpu,
        );
    }
}
