//! Issue 51's bench: every way a master drives the inputs, side by side in
//! one run, at default settings (ideal actuators) unless a row says
//! otherwise.
//!
//! - Ramp rows: the fold input goes 0 -> 1 over 0.5 s and holds (10 ms
//!   communication steps, 2 s), given four ways: `slopes` (value and slope
//!   at each step start, `fmi2SetRealInputDerivatives`), `held` (the value
//!   at each step start, held over the step: fmpy's `simulate_fmu`,
//!   fmusim, most masters), `first-order hold` (the same samples with
//!   `input.first_order_hold` = 1: each step ramps to the sample, which
//!   acts one step late) and `held, error filter` (held with
//!   `solver.error_filter` = 1). Scenes: the single crease
//!   (scenes/single_crease.fold; error: the fold angle's distance from its
//!   target, rad) and Miura-ori sheets of m x m panels (20 mm, 60 degree
//!   sectors) folded to their full rigid fold (error: the largest vertex
//!   distance from the exact rigid fold after the best-fit rigid motion, in
//!   panel edges). Columns: CPU from which the error stays below the limit
//!   until the end, that CPU over the slopes row's, total CPU, steps
//!   (rejected), Newton iterations, factorizations, final error.
//! - Loop rows: a controller sets the fold input every 1 ms from the first
//!   folding crease's angle, held over the step, to hold it at 45 degrees:
//!   `I` (`u += Ki h e`, Ki 10/s, e = 45 deg - |angle| in rad), `PI 0.2/20`
//!   (issue 51's first PI: `u = Kp e + Ki sum(e h)`, Kp 0.2, Ki 20/s) and
//!   `PI 0.01/10` (Kp 0.01, Ki 10/s). Columns: the loop's gain margin at
//!   its sample rate (with `--margins`: the factor on both gains at which
//!   the loop linearized about 45 degrees turns unstable, from the plant's
//!   sampled step response at tolerance 1e-8; below 1 the loop is unstable
//!   and measures nothing), simulated time over CPU (x real time), the
//!   largest difference of the loop's angle from the same loop at a
//!   tolerance 100x tighter at any step (deg), steps (rejected), Newton
//!   iterations, factorizations. Single crease 0.6 s, Miura 0.3 s.
//!
//! - Precision rows (`--only precision`, alone): the held and sloped fold
//!   ramp (1 s) and the I loop (0.3 s) on the 4x4 Miura at several
//!   tolerances, plain and filtered error estimate: the largest distance of
//!   every vertex and fold angle from the same run at tolerance 1e-8, at
//!   any step, against CPU (the reference runs take minutes).
//!
//! `cargo bench --bench input_paths -- [--sizes 4,10,16] [--loop-sizes 4]
//! [--margins] [--tau T] [--only ramps|loops|precision]` (`--tau`: a servo's
//! time constant in s for every row). CPU is this thread's CPU time.

#[path = "common/mod.rs"]
mod common;

use nalgebra::Vector3;
use origami_fmu::benchmarks::{aligned_max_distance, arg_text};
use origami_fmu::cpu_time::CpuInstant;
use origami_fmu::ids::VertexId;
use origami_fmu::model::{Model, StepReport};
use origami_fmu::scene::Scene;
use origami_fmu::scene::patterns::Miura;

/// How the master drives the fold ramp.
#[derive(Clone, Copy, PartialEq, Debug)]
enum Path {
    Slopes,
    Held,
    FirstOrderHold,
    HeldFiltered,
}

impl Path {
    fn label(self) -> &'static str {
        match self {
            Path::Slopes => "slopes",
            Path::Held => "held",
            Path::FirstOrderHold => "first-order hold",
            Path::HeldFiltered => "held, error filter",
        }
    }
}

/// A feedback law on the fold input.
#[derive(Clone, Copy, PartialEq, Debug)]
enum Loop {
    /// `u += Ki h e`.
    I { ki: f64 },
    /// `u = Kp e + Ki sum(e h)`.
    Pi { kp: f64, ki: f64 },
}

impl Loop {
    fn label(self) -> String {
        match self {
            Loop::I { ki } => format!("I {ki}"),
            Loop::Pi { kp, ki } => format!("PI {kp}/{ki}"),
        }
    }
    /// The same law with both gains times `f`.
    fn scaled(self, f: f64) -> Loop {
        match self {
            Loop::I { ki } => Loop::I { ki: f * ki },
            Loop::Pi { kp, ki } => Loop::Pi {
                kp: f * kp,
                ki: f * ki,
            },
        }
    }
}

/// The controller's state: the input it sets and its integral.
#[derive(Default)]
struct Controller {
    u: f64,
    integral: f64,
}

impl Controller {
    /// The input for the error `e` (rad) over a step `h`.
    fn next(&mut self, law: Loop, e: f64, h: f64) -> f64 {
        match law {
            Loop::I { ki } => self.u += ki * h * e,
            Loop::Pi { kp, ki } => {
                self.integral += e * h;
                self.u = kp * e + ki * self.integral;
            }
        }
        self.u
    }
}

/// The scenes of the bench.
#[derive(Clone, Copy, PartialEq, Debug)]
enum Sheet {
    Crease,
    Miura(usize),
}

impl Sheet {
    fn label(self) -> String {
        match self {
            Sheet::Crease => "single crease".into(),
            Sheet::Miura(p) => format!("Miura {p}x{p}"),
        }
    }

    fn scene(self, tau: Option<f64>) -> Scene {
        let mut scene = match self {
            Sheet::Crease => {
                let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/single_crease.fold");
                origami_fmu::scene::load(path).expect("single crease").0
            }
            Sheet::Miura(p) => common::miura_scene(p),
        };
        scene.actuator_time_constant = tau;
        scene
    }

    /// The error limit of the ramp rows.
    fn limit(self) -> f64 {
        match self {
            Sheet::Crease | Sheet::Miura(4) => 1e-4,
            Sheet::Miura(_) => 1e-3,
        }
    }
}

/// A model of `scene` with the named parameters set, initialized.
fn model(scene: Scene, parameters: &[(&str, f64)]) -> Model {
    let mut m = Model::new(scene).expect("model");
    for &(name, x) in parameters {
        let id = m.parameter_id(name).expect("parameter");
        m.set_parameter(id, x).expect("value");
    }
    m.initialize().expect("initialize");
    m
}

/// Index of the output of the first crease that folds, and its full angle.
fn folding_crease(m: &Model) -> (usize, f64) {
    m.outputs()
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
        .expect("a folding crease")
}

/// What one ramp run measured.
struct RampRow {
    below: Option<f64>,
    cpu: f64,
    work: StepReport,
    final_error: f64,
}

/// The fold ramp driven by `path` on `sheet`.
fn ramp(sheet: Sheet, path: Path, tau: Option<f64>) -> RampRow {
    let parameters: &[(&str, f64)] = match path {
        Path::Slopes | Path::Held => &[],
        Path::FirstOrderHold => &[("input.first_order_hold", 1.0)],
        Path::HeldFiltered => &[("solver.error_filter", 1.0)],
    };
    let mut m = model(sheet.scene(tau), parameters);
    let fold = m.input_id("fold").expect("fold input");
    let (crease, target) = folding_crease(&m);
    let exact = match sheet {
        Sheet::Crease => None,
        Sheet::Miura(p) => {
            let miura = Miura {
                nx: p / 2,
                ny: p / 2,
                ..Default::default()
            };
            Some((miura.folded(), miura.a))
        }
    };
    let (rise, dt, steps) = (0.5, 0.01, 200);
    let mut work = StepReport::default();
    let mut trace = Vec::with_capacity(steps);
    let clock = CpuInstant::now();
    for k in 0..steps {
        let t = k as f64 * dt;
        m.set_input(fold, (t / rise).min(1.0)).expect("input");
        if path == Path::Slopes {
            let slope = if t < rise { 1.0 / rise } else { 0.0 };
            m.set_input_derivative(fold, 1, slope).expect("slope");
        }
        work.accumulate(&m.advance(dt).expect("step"));
        let cpu = clock.elapsed().as_secs_f64();
        let error = match &exact {
            Some((x_exact, a)) => {
                let x: Vec<Vector3<f64>> = (0..x_exact.len())
                    .map(|v| Vector3::from(m.vertex_position(VertexId(v))))
                    .collect();
                aligned_max_distance(&x, x_exact) / a
            }
            None => (m.output_values()[crease] - target).abs(),
        };
        trace.push((cpu, error));
    }
    let cpu = clock.elapsed().as_secs_f64();
    let limit = sheet.limit();
    let below = match trace.iter().rposition(|&(_, e)| e >= limit) {
        None => Some(0.0),
        Some(i) if i + 1 < trace.len() => Some(trace[i].0),
        Some(_) => None,
    };
    RampRow {
        below,
        cpu,
        work,
        final_error: trace.last().map_or(f64::NAN, |t| t.1),
    }
}

/// The loop `law` at 1 kHz on `sheet` at `tolerance` (None: the default)
/// with `parameters`: (CPU, work, the crease's angle after every step).
fn run_loop(
    sheet: Sheet,
    law: Loop,
    tolerance: Option<f64>,
    parameters: &[(&str, f64)],
    tau: Option<f64>,
) -> (f64, StepReport, Vec<f64>) {
    let mut all = parameters.to_vec();
    if let Some(t) = tolerance {
        all.push(("solver.tolerance", t));
    }
    let mut m = model(sheet.scene(tau), &all);
    let fold = m.input_id("fold").expect("fold input");
    let (crease, _) = folding_crease(&m);
    let angle = m.output_ids().nth(crease).expect("crease output");
    let (h, t_end) = (1e-3, loop_duration(sheet));
    let n = (t_end / h).round() as usize;
    let set = 45f64.to_radians();
    let mut c = Controller::default();
    let mut work = StepReport::default();
    let mut trace = Vec::with_capacity(n);
    let clock = CpuInstant::now();
    for _ in 0..n {
        let e = set - m.output(angle).expect("angle").abs();
        m.set_input(fold, c.next(law, e, h)).expect("input");
        work.accumulate(&m.advance(h).expect("step"));
        trace.push(m.output(angle).expect("angle"));
    }
    (clock.elapsed().as_secs_f64(), work, trace)
}

fn loop_duration(sheet: Sheet) -> f64 {
    match sheet {
        Sheet::Crease => 0.6,
        Sheet::Miura(_) => 0.3,
    }
}

/// The loop's gain margin at 1 kHz about 45 degrees: the plant's sampled
/// response to a held step of the input (tolerance 1e-8, from the sheet
/// settled at 45 degrees), then the linear loop on that response, its gains
/// scaled until it grows. None where it grows at every factor tried.
fn gain_margin(sheet: Sheet, law: Loop, tau: Option<f64>) -> Option<f64> {
    let s = sampled_step_response(sheet, tau);
    let grows = |f: f64| linear_loop_grows(&s, law.scaled(f));
    let mut f: f64 = 0.01;
    if grows(f) {
        return None;
    }
    while f < 100.0 && !grows(f * 1.02) {
        f *= 1.02;
    }
    Some(f)
}

/// The response of the folding crease's |angle| (rad per unit of input)
/// at 1 ms samples to a held step of the fold input, about 45 degrees.
fn sampled_step_response(sheet: Sheet, tau: Option<f64>) -> Vec<f64> {
    let mut m = model(sheet.scene(tau), &[("solver.tolerance", 1e-8)]);
    let fold = m.input_id("fold").expect("fold input");
    let (crease, target) = folding_crease(&m);
    let u_star = 45f64.to_radians() / target.abs();
    // Reach u* along a 0.3 s ramp with its slope, then settle 2 s.
    for k in 0..30 {
        m.set_input(fold, u_star * k as f64 / 30.0).expect("input");
        m.set_input_derivative(fold, 1, u_star / 0.3)
            .expect("slope");
        m.advance(0.01).expect("step");
    }
    m.set_input(fold, u_star).expect("input");
    for _ in 0..200 {
        m.advance(0.01).expect("step");
    }
    let du = 1e-3;
    let a0 = m.output_values()[crease].abs();
    m.set_input(fold, u_star + du).expect("input");
    let mut s = vec![0.0];
    for _ in 0..1500 {
        m.advance(1e-3).expect("step");
        s.push((m.output_values()[crease].abs() - a0) / du);
    }
    s
}

/// Whether the loop `law`, closed on the linear plant of sampled step
/// response `s`, lets a set-point step's error grow over 1.4 s.
fn linear_loop_grows(s: &[f64], law: Loop) -> bool {
    let g: Vec<f64> = s.windows(2).map(|w| w[1] - w[0]).collect();
    let n = 1400;
    let (h, mut c) = (1e-3, Controller::default());
    let mut u = vec![0.0; n];
    let (mut early, mut late): (f64, f64) = (0.0, 0.0);
    for k in 0..n {
        let y: f64 = (1..=g.len().min(k)).map(|j| g[j - 1] * u[k - j]).sum();
        let e = 1.0 - y;
        u[k] = c.next(law, e, h);
        if k > n / 2 {
            late = late.max(e.abs());
        } else if k > n / 10 {
            early = early.max(e.abs());
        }
    }
    // A NaN (a blown-up loop) counts as growth.
    !matches!(
        late.partial_cmp(&early),
        Some(std::cmp::Ordering::Less | std::cmp::Ordering::Equal)
    )
}

fn ramp_rows(sizes: &[usize], tau: Option<f64>) {
    println!(
        "| sheet, error limit | input path | CPU s to stay below the limit | vs slopes | CPU s total | steps (rejected) | Newton its | factorizations | final error |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    let sheets = std::iter::once(Sheet::Crease).chain(sizes.iter().map(|&p| Sheet::Miura(p)));
    for sheet in sheets {
        let mut slopes = None;
        for path in [
            Path::Slopes,
            Path::Held,
            Path::FirstOrderHold,
            Path::HeldFiltered,
        ] {
            let r = ramp(sheet, path, tau);
            if path == Path::Slopes {
                slopes = r.below;
            }
            let ratio = match (r.below, slopes) {
                (Some(b), Some(s)) if s > 0.0 => format!("{:.2}", b / s),
                _ => "-".into(),
            };
            println!(
                "| {} < {:.0e} | {} | {} | {ratio} | {:.3} | {} ({}) | {} | {} | {:.1e} |",
                sheet.label(),
                sheet.limit(),
                path.label(),
                r.below.map_or("never".into(), |c| format!("{c:.3}")),
                r.cpu,
                r.work.steps,
                r.work.rejected,
                r.work.newton_iterations,
                r.work.factorizations,
                r.final_error,
            );
        }
    }
}

fn loop_rows(sizes: &[usize], margins: bool, tau: Option<f64>) {
    println!();
    println!(
        "| sheet | loop | options | gain margin | x real time | CPU s | largest difference from tolerance / 100 (deg) | steps (rejected) | Newton its | factorizations |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    let sheets = std::iter::once(Sheet::Crease).chain(sizes.iter().map(|&p| Sheet::Miura(p)));
    for sheet in sheets {
        for law in [
            Loop::I { ki: 10.0 },
            Loop::Pi { kp: 0.2, ki: 20.0 },
            Loop::Pi { kp: 0.01, ki: 10.0 },
        ] {
            let margin = if margins {
                gain_margin(sheet, law, tau).map_or("< 0.01".into(), |f| format!("{f:.2}"))
            } else {
                "-".into()
            };
            for (label, parameters) in [
                ("defaults", &[][..]),
                ("error filter", &[("solver.error_filter", 1.0)][..]),
            ] {
                let (cpu, w, trace) = run_loop(sheet, law, None, parameters, tau);
                let tight = parameters.to_vec();
                let tolerance = 1e-2 * origami_fmu::scene::SolverSettings::default().tolerance;
                let (_, _, reference) = run_loop(sheet, law, Some(tolerance), &tight, tau);
                let diff = trace
                    .iter()
                    .zip(&reference)
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0, f64::max)
                    .to_degrees();
                println!(
                    "| {} | {} | {label} | {margin} | {:.2} | {cpu:.3} | {diff:.3} | {} ({}) | {} | {} |",
                    sheet.label(),
                    law.label(),
                    loop_duration(sheet) / cpu,
                    w.steps,
                    w.rejected,
                    w.newton_iterations,
                    w.factorizations,
                );
            }
        }
    }
}

fn sizes(name: &str, default: &[usize]) -> Vec<usize> {
    arg_text(name)
        .map(|v| {
            v.split(',')
                .filter(|x| !x.is_empty())
                .map(|x| x.parse().expect("a size"))
                .collect()
        })
        .unwrap_or_else(|| default.to_vec())
}

/// What a precision row drives.
#[derive(Clone, Copy, Debug)]
enum Run {
    Ramp(Path),
    Loop(Loop),
}

/// Every output after every communication step of `run` on the 4x4 Miura
/// (the ramp for 1 s, the loop for 0.3 s), and the CPU it took.
fn outputs_over(run: Run, tolerance: f64, filter: bool) -> (f64, Vec<Vec<f64>>) {
    let sheet = Sheet::Miura(4);
    let mut parameters = vec![("solver.tolerance", tolerance)];
    if filter {
        parameters.push(("solver.error_filter", 1.0));
    }
    let mut m = model(sheet.scene(None), &parameters);
    let fold = m.input_id("fold").expect("fold input");
    let (crease, _) = folding_crease(&m);
    let (h, n) = match run {
        Run::Ramp(_) => (0.01, 100),
        Run::Loop(_) => (1e-3, 300),
    };
    let set = 45f64.to_radians();
    let mut c = Controller::default();
    let mut rows = Vec::with_capacity(n);
    let clock = CpuInstant::now();
    for k in 0..n {
        let t = k as f64 * h;
        match run {
            Run::Ramp(path) => {
                m.set_input(fold, (t / 0.5).min(1.0)).expect("input");
                if path == Path::Slopes {
                    let slope = if t < 0.5 { 2.0 } else { 0.0 };
                    m.set_input_derivative(fold, 1, slope).expect("slope");
                }
            }
            Run::Loop(law) => {
                let e = set - m.output_values()[crease].abs();
                m.set_input(fold, c.next(law, e, h)).expect("input");
            }
        }
        m.advance(h).expect("step");
        rows.push(m.output_values());
    }
    (clock.elapsed().as_secs_f64(), rows)
}

/// Work against precision on the 4x4 Miura: the largest distance over the
/// run of every vertex (m) and fold angle (deg) from the same run at
/// tolerance 1e-8, against CPU, with the plain and the filtered estimate.
fn precision_rows() {
    let m = model(Sheet::Miura(4).scene(None), &[]);
    let kinds: Vec<bool> = m
        .outputs()
        .iter()
        .map(|v| v.name.starts_with("vertex["))
        .collect();
    let angles: Vec<bool> = m
        .outputs()
        .iter()
        .map(|v| v.name.starts_with("crease["))
        .collect();
    println!();
    println!("| run | estimate | tolerance | CPU s | vertices (m) | fold angles (deg) |");
    println!("|---|---|---|---|---|---|");
    let runs = [
        (
            "fold ramp, slopes",
            Run::Ramp(Path::Slopes),
            &[1e-4, 1e-5][..],
        ),
        (
            "fold ramp, held",
            Run::Ramp(Path::Held),
            &[1e-3, 1e-4, 3e-5, 1e-5][..],
        ),
        ("I loop", Run::Loop(Loop::I { ki: 10.0 }), &[1e-4, 1e-5][..]),
    ];
    for (label, run, tolerances) in runs {
        let (_, reference) = outputs_over(run, 1e-8, false);
        for &tol in tolerances {
            for filter in [false, true] {
                let (cpu, rows) = outputs_over(run, tol, filter);
                let (mut dx, mut da): (f64, f64) = (0.0, 0.0);
                for (a, b) in rows.iter().zip(&reference) {
                    for (k, (x, y)) in a.iter().zip(b).enumerate() {
                        if kinds[k] {
                            dx = dx.max((x - y).abs());
                        } else if angles[k] {
                            da = da.max((x - y).abs().to_degrees());
                        }
                    }
                }
                println!(
                    "| {label} | {} | {tol:.0e} | {cpu:.3} | {dx:.1e} | {da:.2} |",
                    if filter { "filtered" } else { "raw" }
                );
            }
        }
    }
}

fn main() {
    let tau: Option<f64> = arg_text("--tau").map(|v| v.parse().expect("a time constant (s)"));
    let margins = std::env::args().any(|a| a == "--margins");
    let only = arg_text("--only");
    if only.as_deref() == Some("precision") {
        precision_rows();
        return;
    }
    if only.as_deref() != Some("loops") {
        ramp_rows(&sizes("--sizes", &[4, 10, 16]), tau);
    }
    if only.as_deref() != Some("ramps") {
        loop_rows(&sizes("--loop-sizes", &[4]), margins, tau);
    }
}
