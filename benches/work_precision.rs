//! Work-precision report: error against CPU time (the process's CPU clock)
//! for each integrator on a
//! ladder of step sizes (generalized-alpha with fixed steps, with error
//! control over a ladder of tolerances, and central differences at its
//! stability limit), on three cases:
//!
//! - `crease`: two paper panels, one clamped, folded by a smooth rest-angle
//!   ramp (0 -> 1 rad over 50 ms, held to 100 ms); error: largest vertex
//!   position difference from a reference run (generalized-alpha, full
//!   Newton, 3.9 us steps) over the run, relative to the sheet size.
//! - `cantilever`: a clamped strip (docs/validation.md case B) set vibrating by a
//!   tip force applied at t = 0; error: its first frequency (mean period
//!   between upward crossings of the tip deflection through the middle of
//!   its range) against 1.875104^2 sqrt(EI/(rho A L^4)). The error has a
//!   floor from the mesh (12 x 1 cells).
//! - `miura`: a 2 x 2 Miura-ori sheet folding under the rest-angle ramp
//!   (0 -> 1 over 0.2 s, held to 0.3 s); error as for `crease`, reference
//!   with 15.6 us steps.
//!
//! `cargo bench --bench work_precision -- [--csv FILE] [--quick]` prints a
//! table and writes the CSV (default out/work_precision.csv);
//! scripts/work_precision.sh also plots it. The observed order is the
//! slope of log error against log step between successive fixed-step runs.

use origami_fmu::benchmarks;
use origami_fmu::cpu_time::Stopwatch;
use origami_fmu::ids::VertexId;
use origami_fmu::mesh::builders::grid;
use origami_fmu::model::{InputId, Model, StepReport};
use origami_fmu::scene::{Fix, Integrator, NewtonMode, Scene, Support, VertexInput};
use std::fmt::Write as _;

/// One integrator setting.
#[derive(Clone, Copy, Debug)]
enum Method {
    /// Generalized-alpha with this fixed step (s).
    GaFixed(f64),
    /// Generalized-alpha with error control at this tolerance.
    GaAdaptive(f64),
    /// Central differences at 0.8 times its stability limit.
    Central,
}

impl Method {
    fn integrator(&self) -> &'static str {
        match self {
            Method::GaFixed(_) => "generalized-alpha fixed step",
            Method::GaAdaptive(_) => "generalized-alpha adaptive",
            Method::Central => "central differences",
        }
    }

    /// Apply to a scene's solver settings.
    fn configure(&self, sc: &mut Scene) {
        let s = &mut sc.solver;
        match *self {
            Method::GaFixed(h) => {
                s.integrator = Integrator::GeneralizedAlpha;
                s.max_step = h;
                s.min_step = h;
                // With fixed steps the tolerance only sets Newton's (1e-3 of it).
                s.tolerance = 1e-6;
            }
            Method::GaAdaptive(tol) => {
                s.integrator = Integrator::GeneralizedAlpha;
                s.tolerance = tol;
                s.max_step = 1e-2;
            }
            Method::Central => s.integrator = Integrator::CentralDifference,
        }
    }
}

/// A case: builds its scene and drives it, sampling outputs.
struct Case {
    name: &'static str,
    scene: fn() -> Scene,
    /// Input values at time t (index, value).
    inputs: fn(&Model, f64) -> Vec<(InputId, f64)>,
    stop: f64,
    sample: f64,
}

/// Outputs sampled every `case.sample` seconds, with the work done.
struct Run {
    samples: Vec<Vec<f64>>,
    cpu: f64,
    report: StepReport,
}

fn run(case: &Case, method: Method) -> Result<Run, String> {
    let mut sc = (case.scene)();
    method.configure(&mut sc);
    let mut m = Model::new(sc).map_err(|e| e.to_string())?;
    m.initialize().map_err(|e| e.to_string())?;
    let n = (case.stop / case.sample).round() as usize;
    let mut samples = Vec::with_capacity(n);
    let mut report = StepReport::default();
    let clock = Stopwatch::start();
    for k in 1..=n {
        let t = k as f64 * case.sample;
        // Each input's value at the step start and its slope over the step:
        // the case's piecewise linear signal (never a staircase).
        let (t0, h) = (t - case.sample, case.sample);
        for ((i, v0), (_, v1)) in (case.inputs)(&m, t0).into_iter().zip((case.inputs)(&m, t)) {
            m.set_input(i, v0).map_err(|e| e.to_string())?;
            m.set_input_derivative(i, 1, (v1 - v0) / h)
                .map_err(|e| e.to_string())?;
        }
        report.accumulate(&m.advance(case.sample).map_err(|e| e.to_string())?);
        samples.push(m.output_values());
    }
    Ok(Run {
        samples,
        cpu: clock.cpu(),
        report,
    })
}

/// Smooth ramp 0 -> 1 over `t1` (zero slope at both ends).
fn smooth_ramp(t: f64, t1: f64) -> f64 {
    let x = (t / t1).clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

fn crease_scene() -> Scene {
    let mesh = grid(0.04, 0.02, 2, 1, &[(1, 1.0)]);
    let mut sc = Scene::with_defaults("crease", mesh);
    sc.supports.push(Support {
        vertices: vec![VertexId(0), VertexId(3)],
        fix: Fix::Clamped,
    });
    sc.solver.newton = NewtonMode::Full;
    sc
}

fn fold_input(m: &Model, t: f64, t1: f64) -> Vec<(InputId, f64)> {
    let fold = m.input_id("fold").unwrap();
    vec![(fold, smooth_ramp(t, t1))]
}

/// Case B strip: L = 20 mm, b = 2 mm, paper defaults (E = 3 GPa,
/// h = 0.1 mm, rho = 800), nu = 0 so EI = E b h^3 / 12 exactly.
const STRIP_L: f64 = 0.02;
const STRIP_B: f64 = 0.002;

fn strip_frequency() -> f64 {
    let (e, h, rho): (f64, f64, f64) = (3.0e9, 1e-4, 800.0);
    let ei = e * STRIP_B * h.powi(3) / 12.0;
    let rho_a = rho * STRIP_B * h;
    1.875104f64.powi(2) * (ei / (rho_a * STRIP_L.powi(4))).sqrt() / (2.0 * std::f64::consts::PI)
}

fn is_tip(sc: &Scene, v: usize) -> bool {
    let c = sc.mesh.coords()[v];
    (c.x - STRIP_L).abs() < 1e-12 && c.y.abs() < 1e-12
}

fn cantilever_scene() -> Scene {
    let mesh = grid(STRIP_L, STRIP_B, 12, 1, &[]);
    let mut sc = Scene::with_defaults("cantilever", mesh);
    sc.material.poisson_ratio = 0.0;
    sc.auto_damping = false;
    sc.actuators.clear();
    let left: Vec<VertexId> = sc
        .mesh
        .vertex_ids()
        .filter(|&v| sc.mesh.coord(v).x.abs() < 1e-12)
        .collect();
    let tips: Vec<VertexId> = sc
        .mesh
        .vertex_ids()
        .filter(|&v| (sc.mesh.coord(v).x - STRIP_L).abs() < 1e-12)
        .collect();
    sc.supports.push(Support {
        vertices: left,
        fix: Fix::Clamped,
    });
    // Both tip corners: a force at one corner would twist the strip too.
    for (k, &v) in tips.iter().enumerate() {
        sc.vertex_forces.push(VertexInput {
            name: format!("tip{k}"),
            vertex: v,
        });
    }
    sc.solver.rho_inf = 1.0;
    sc.solver.newton = NewtonMode::Full;
    sc
}

fn cantilever_inputs(m: &Model, _t: f64) -> Vec<(InputId, f64)> {
    // A constant 0.5 uN downwards at each tip corner from t = 0: the strip
    // oscillates about its static deflection, almost purely in mode 1.
    m.inputs()
        .iter()
        .enumerate()
        .filter(|(_, v)| v.name.starts_with("tip") && v.name.ends_with(".z"))
        .filter_map(|(i, _)| Some((m.input_at(i)?, -0.5e-6)))
        .collect()
}

fn miura_scene() -> Scene {
    let mut sc = benchmarks::miura_scene(2);
    sc.solver.newton = NewtonMode::Full;
    sc
}

/// Largest vertex position difference over all samples, relative to `size`.
fn trajectory_error(run: &Run, reference: &Run, n_pos: usize, size: f64) -> f64 {
    let mut worst: f64 = 0.0;
    for (a, b) in run.samples.iter().zip(&reference.samples) {
        for (x, y) in a[..n_pos].iter().zip(&b[..n_pos]) {
            worst = worst.max((x - y).abs());
        }
    }
    worst / size
}

/// Relative error of the first frequency from the upward crossings of the
/// tip deflection through the middle of its range.
fn frequency_error(run: &Run, tip_z: usize, sample: f64) -> f64 {
    let z: Vec<f64> = run.samples.iter().map(|s| s[tip_z]).collect();
    let (lo, hi) = z
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    let z: Vec<f64> = z.iter().map(|x| x - 0.5 * (lo + hi)).collect();
    let mut crossings = Vec::new();
    for k in 1..z.len() {
        if z[k - 1] < 0.0 && z[k] >= 0.0 {
            let f = z[k - 1] / (z[k - 1] - z[k]);
            crossings.push((k as f64 + f) * sample);
        }
    }
    if crossings.len() < 3 {
        return f64::NAN;
    }
    let periods = (crossings.len() - 1) as f64;
    let period = (crossings[crossings.len() - 1] - crossings[0]) / periods;
    ((1.0 / period) - strip_frequency()) / strip_frequency()
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let quick = args.iter().any(|a| a == "--quick");
    let csv_path = args
        .iter()
        .position(|a| a == "--csv")
        .and_then(|i| args.get(i + 1).cloned())
        .unwrap_or_else(|| "out/work_precision.csv".into());
    let cases = [
        Case {
            name: "crease",
            scene: crease_scene,
            inputs: |m, t| fold_input(m, t, 0.05),
            stop: 0.1,
            sample: 1e-2,
        },
        Case {
            name: "cantilever",
            scene: cantilever_scene,
            inputs: cantilever_inputs,
            stop: 0.1,
            sample: 4e-4,
        },
        Case {
            name: "miura",
            scene: miura_scene,
            inputs: |m, t| fold_input(m, t, 0.2),
            stop: 0.3,
            sample: 1e-2,
        },
    ];
    let mut csv = String::from(
        "case,integrator,step_s,tolerance,error,cpu_s,steps,rejected,newton_iterations,factorizations\n",
    );
    println!(
        "| case | integrator | step (s) | tolerance | error | CPU (s) | steps | Newton its | order |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for case in &cases {
        let ladder: Vec<f64> = match case.name {
            "cantilever" => vec![4e-4, 2e-4, 1e-4, 5e-5],
            "miura" => vec![1e-3, 5e-4, 2.5e-4, 1.25e-4],
            _ => vec![2e-3, 1e-3, 5e-4, 2.5e-4, 1.25e-4, 6.25e-5],
        };
        let ladder = if quick { ladder[..2].to_vec() } else { ladder };
        let mut methods: Vec<Method> = ladder.iter().map(|&h| Method::GaFixed(h)).collect();
        methods.extend([1e-2, 1e-3, 1e-4, 1e-5].map(Method::GaAdaptive));
        methods.push(Method::Central);
        let reference = match case.name {
            "cantilever" => None,
            "miura" => Some(run(
                case,
                Method::GaFixed(if quick { 1e-4 } else { 1.5625e-5 }),
            )),
            _ => Some(run(
                case,
                Method::GaFixed(if quick { 1e-5 } else { 3.90625e-6 }),
            )),
        };
        let reference = match reference {
            Some(Ok(r)) => Some(r),
            Some(Err(e)) => panic!("{}: reference run failed: {e}", case.name),
            None => None,
        };
        let sc = (case.scene)();
        let n_pos = 3 * sc.mesh.n_vertices();
        let size = sc.mesh.size();
        let mut last_fixed: Option<(f64, f64)> = None;
        for method in methods {
            let (step, tol) = match method {
                Method::GaFixed(h) => (format!("{h:e}"), String::new()),
                Method::GaAdaptive(t) => (String::new(), format!("{t:e}")),
                Method::Central => (String::new(), String::new()),
            };
            let r = match run(case, method) {
                Ok(r) => r,
                Err(e) => {
                    println!(
                        "| {} | {} | {step} | {tol} | failed: {e} | | | | |",
                        case.name,
                        method.integrator()
                    );
                    continue;
                }
            };
            let error = match &reference {
                Some(rf) => trajectory_error(&r, rf, n_pos, size),
                None => {
                    let tip = (0..sc.mesh.n_vertices()).find(|&v| is_tip(&sc, v)).unwrap();
                    frequency_error(&r, 3 * tip + 2, case.sample)
                }
            };
            let step = match method {
                Method::Central => format!("{:.3e}", r.report.min_step),
                _ => step,
            };
            let order = match method {
                Method::GaFixed(h) => {
                    let o = last_fixed
                        .map(|(h0, e0)| format!("{:.2}", (e0 / error).ln() / (h0 / h).ln()))
                        .unwrap_or_default();
                    last_fixed = Some((h, error));
                    o
                }
                _ => String::new(),
            };
            println!(
                "| {} | {} | {step} | {tol} | {error:.3e} | {:.3} | {} | {} | {order} |",
                case.name,
                method.integrator(),
                r.cpu,
                r.report.steps,
                r.report.newton_iterations
            );
            let _ = writeln!(
                csv,
                "{},{},{step},{tol},{error:e},{},{},{},{},{}",
                case.name,
                method.integrator(),
                r.cpu,
                r.report.steps,
                r.report.rejected,
                r.report.newton_iterations,
                r.report.factorizations
            );
        }
    }
    if let Some(dir) = std::path::Path::new(&csv_path).parent() {
        let _ = std::fs::create_dir_all(dir);
    }
    std::fs::write(&csv_path, csv).expect("write CSV");
    println!("wrote {csv_path}");
}
