//! Cost per simulated second against the master's communication step: the
//! 4x4 Miura-ori folding under the rest-angle ramp (0 -> 1 over 0.6 s, 1 s
//! simulated), default settings, communication steps 1e-2, 1e-3 and 1e-4 s.
//! "slopes": the master gives each step the ramp's value and slope
//! (fmi2SetRealInputDerivatives), the continuous ramp; "hold": only the
//! value at the step start (sample and hold, a staircase).
//!
//! `cargo bench --bench cosim -- [--size 4] [--time 1.0] [--slopes-only]
//! [--steps 1e-2,1e-3,1e-4] [--read-outputs]`
//!
//! CPU seconds are the process's CPU time (the machine is shared: compare
//! the ratios within one run).

mod common;
use common::cpu_seconds;
use origami_fmu::benchmarks::{fold_by_ramp_with, miura_scene};
use origami_fmu::model::Model;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let arg = |name: &str, default: f64| {
        args.iter()
            .position(|a| a == name)
            .and_then(|i| args.get(i + 1))
            .map(|v| v.parse().expect("a number"))
            .unwrap_or(default)
    };
    let n = arg("--size", 4.0) as usize;
    // Communication steps (the first is the base of the ratios).
    let dts: Vec<f64> = args
        .iter()
        .position(|a| a == "--steps")
        .and_then(|i| args.get(i + 1))
        .map(|v| v.split(',').map(|x| x.parse().expect("a step")).collect())
        .unwrap_or_else(|| vec![1e-2, 1e-3, 1e-4]);
    let time = arg("--time", 1.0);
    println!(
        "| sheet | inputs | communication step (s) | CPU s per simulated s | vs 1e-2 | internal steps | rejected | Newton its | factorizations |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    // --read-outputs: read every output after each step (simulate_fmu).
    let read = args.iter().any(|a| a == "--read-outputs");
    let modes: &[bool] = if args.iter().any(|a| a == "--slopes-only") {
        &[true]
    } else {
        &[true, false]
    };
    for &with_slopes in modes {
        let mut base = None;
        for &dt in &dts {
            let mut m = Model::new(miura_scene(n)).expect("Miura model");
            m.initialize().expect("initialize");
            let steps = (time / dt).round() as usize;
            let c0 = cpu_seconds();
            let r = fold_by_ramp_with(&mut m, steps, dt, 0.6 * time, with_slopes, |m, _| {
                if read {
                    std::hint::black_box(m.output_values());
                }
            });
            let cpu = (cpu_seconds() - c0) / time;
            let b = *base.get_or_insert(cpu);
            println!(
                "| {n}x{n} | {} | {dt:.0e} | {cpu:.3} | {:.2} | {} | {} | {} | {} |",
                if with_slopes { "slopes" } else { "hold" },
                cpu / b,
                r.steps,
                r.rejected,
                r.newton_iterations,
                r.factorizations
            );
        }
    }
}
