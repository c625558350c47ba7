//! Issue 39's bench: the cost of every way a master drives the inputs, side
//! by side in one run, at default settings.
//!
//! - Miura-ori sheets of m x m panels (20 mm, 60 degree sectors) folded to
//!   their full rigid fold: the fold input ramps 0 -> 1 over 0.5 s and holds
//!   (10 ms communication steps, 2 s), given three ways:
//!   `slopes` (value and slope at each step start, `fmi2SetRealInputDerivatives`),
//!   `held` (the value at each step start, held over the step: fmpy's
//!   `simulate_fmu`, fmusim, most masters), and `controller` (a feedback law
//!   that sets a new value every step: the ramp plus 0.5 times the error of
//!   a crease's fold fraction, held).
//!   Columns: CPU from which the largest vertex distance to the exact rigid
//!   fold (after the best-fit rigid motion, in panel edges) stays below the
//!   size's limit (1e-4 at 4x4, 1e-3 beyond) until the end, total CPU,
//!   steps (rejected), Newton iterations, factorizations, final error.
//! - The single crease (scenes/single_crease.fold): its fold input stepped
//!   0 -> 1 at t = 0, `held` (set before the first step) or `slopes` (the
//!   step as a ramp over the first communication step), 10 ms steps, 0.5 s;
//!   the angle 10 ms after the step.
//!
//! `cargo bench --bench input_paths -- [--sizes 4,10,16] [--tau T]`
//! (`--tau`: the actuators' time constant in s, 0 for ideal actuators;
//! default: automatic). CPU is this thread's CPU time.

use nalgebra::Vector3;
use origami_fmu::benchmarks::aligned_max_distance;
use origami_fmu::cpu_time::CpuInstant;
use origami_fmu::ids::VertexId;
use origami_fmu::model::{Model, StepReport};
use origami_fmu::scene::Scene;
use origami_fmu::scene::patterns::Miura;

/// How the master drives the fold input.
#[derive(Clone, Copy, PartialEq, Debug)]
enum Path {
    Slopes,
    Held,
    Controller,
}

/// One Miura fold: (CPU to stay below `limit`, total CPU, work, final error).
fn miura(
    panels: usize,
    path: Path,
    limit: f64,
    tau: Option<f64>,
) -> (Option<f64>, f64, StepReport, f64) {
    let miura = Miura {
        nx: panels / 2,
        ny: panels / 2,
        ..Default::default()
    };
    let exact = miura.folded();
    let mut scene: Scene = origami_fmu::scene::from_fold(&miura.generate().unwrap(), None)
        .unwrap()
        .0;
    if tau.is_some() {
        scene.actuator_time_constant = tau;
    }
    let mut m = Model::new(scene).unwrap();
    m.initialize().unwrap();
    let fold = m.input_id("fold").expect("fold input");
    // The first crease output and its full fold angle (the controller's measurement).
    let (crease, full) = m
        .outputs()
        .iter()
        .enumerate()
        .find_map(|(k, v)| {
            let e: usize = v
                .name
                .strip_prefix("crease[")?
                .strip_suffix("].angle")?
                .parse()
                .ok()?;
            let t = m
                .scene()
                .mesh
                .edges()
                .iter()
                .find(|x| x.fold_edge.map(|f| f.index()) == Some(e))?;
            (t.fold_target != 0.0).then_some((k, t.fold_target))
        })
        .expect("a folding crease");
    let (ramp, dt, steps) = (0.5, 0.01, 200);
    let mut total = StepReport::default();
    let mut trace = Vec::with_capacity(steps);
    let clock = CpuInstant::now();
    for k in 0..steps {
        let t = k as f64 * dt;
        let r = (t / ramp).min(1.0);
        let u = match path {
            Path::Slopes | Path::Held => r,
            Path::Controller => {
                let measured = m.output_values()[crease] / full;
                (r + 0.5 * (r - measured)).clamp(0.0, 1.2)
            }
        };
        m.set_input(fold, u).unwrap();
        if path == Path::Slopes {
            m.set_input_derivative(fold, 1, if t < ramp { 1.0 / ramp } else { 0.0 })
                .unwrap();
        }
        total.accumulate(&m.advance(dt).unwrap());
        let cpu = clock.elapsed().as_secs_f64();
        let x: Vec<Vector3<f64>> = (0..exact.len())
            .map(|v| Vector3::from(m.vertex_position(VertexId(v))))
            .collect();
        trace.push((cpu, aligned_max_distance(&x, &exact) / miura.a));
    }
    let cpu = clock.elapsed().as_secs_f64();
    let below = match trace.iter().rposition(|&(_, e)| e >= limit) {
        None => Some(0.0),
        Some(i) if i + 1 < trace.len() => Some(trace[i].0),
        Some(_) => None,
    };
    (below, cpu, total, trace.last().map_or(f64::NAN, |t| t.1))
}

/// The single crease's step response: (CPU, work, angle in degrees 10 ms after the step).
fn crease_step(path: Path, tau: Option<f64>) -> (f64, StepReport, f64) {
    let path_file = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/single_crease.fold");
    let (mut scene, _) = origami_fmu::scene::load(path_file).unwrap();
    if tau.is_some() {
        scene.actuator_time_constant = tau;
    }
    let mut m = Model::new(scene).unwrap();
    m.initialize().unwrap();
    let fold = m.input_id("fold").expect("fold input");
    let angle = m
        .outputs()
        .iter()
        .position(|v| v.name.starts_with("crease["))
        .unwrap();
    let dt = 0.01;
    let mut total = StepReport::default();
    let mut at_10ms = f64::NAN;
    let clock = CpuInstant::now();
    for k in 0..50 {
        match (path, k) {
            (Path::Slopes, 0) => {
                m.set_input(fold, 0.0).unwrap();
                m.set_input_derivative(fold, 1, 1.0 / dt).unwrap();
            }
            _ => m.set_input(fold, 1.0).unwrap(),
        }
        total.accumulate(&m.advance(dt).unwrap());
        if k == 0 {
            at_10ms = m.output_values()[angle].to_degrees();
        }
    }
    (clock.elapsed().as_secs_f64(), total, at_10ms)
}

fn main() {
    let value = origami_fmu::benchmarks::arg_text;
    let sizes: Vec<usize> = value("--sizes")
        .map(|v| v.split(',').map(|x| x.parse().expect("a size")).collect())
        .unwrap_or_else(|| vec![4, 10, 16]);
    let tau: Option<f64> = value("--tau").map(|v| v.parse().expect("a time constant (s)"));
    println!(
        "| sheet | input path | CPU s to stay below the limit | CPU s total | steps (rejected) | Newton its | factorizations | final error (panel edges) |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- |");
    for &p in &sizes {
        let limit = if p <= 4 { 1e-4 } else { 1e-3 };
        for path in [Path::Slopes, Path::Held, Path::Controller] {
            let (below, cpu, w, err) = miura(p, path, limit, tau);
            println!(
                "| {p}x{p} < {limit:.0e} | {path:?} | {} | {cpu:.2} | {} ({}) | {} | {} | {err:.1e} |",
                below.map_or("never".into(), |c| format!("{c:.3}")),
                w.steps,
                w.rejected,
                w.newton_iterations,
                w.factorizations,
            );
        }
    }
    println!();
    println!(
        "| single crease step | input path | CPU s | steps (rejected) | Newton its | factorizations | angle 10 ms after the step (deg) |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- |");
    for path in [Path::Slopes, Path::Held] {
        let (cpu, w, a) = crease_step(path, tau);
        println!(
            "| 0 -> 1 at t = 0 | {path:?} | {cpu:.3} | {} ({}) | {} | {} | {a:.2} |",
            w.steps, w.rejected, w.newton_iterations, w.factorizations
        );
    }
}
