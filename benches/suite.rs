//! The broad suite of scenes every stepper rule is measured on (issue 37):
//! a rule is kept only where the suite as a whole gains from it.
//!
//! Scenes (each at default settings unless it says otherwise):
//! - `miura4`, `miura4-held`, `miura16`: Miura-ori sheets of 4x4 and 16x16
//!   panels (20 mm, 60 degree sectors) folded to their full rigid fold
//!   (ramp 0 -> 1 over 0.5 s, then held; 10 ms communication steps; 2 s),
//!   the input given with its slope or held over each step (sample and
//!   hold, as most masters do); quality: final distance to the exact rigid
//!   fold in panel edges.
//! - `throughput8`: 8x8 Miura cells at tolerance 1e-3 and 1 ms steps at
//!   most, 1 s (the throughput bench's real-time row).
//! - `pyramid`: Origami Simulator's BoxPleatPyramid, its first 0.1 s.
//! - `extreme`: four cases of the extreme suite (two 20 mm panels): a rest
//!   angle jump within 1 us then held (tolerance 1e-4), a fold 0 -> 179 ->
//!   -179 -> 0 degrees, a sheet of thickness ratio 1e-5 folded to 90
//!   degrees, a free sheet spinning at 100 rad/s (tolerance 1e-6);
//!   quality: the largest angle or return error of the four.
//! - `contact`: the waterbomb base collapsed flat with self-contact on
//!   (friction 0.3); quality: the smallest gap (m, negative = crossing).
//! - `cosim`: the 4x4 Miura folded through 1e-4 s communication steps (1 s).
//! - `crease-step`: a single crease whose fold input jumps to 1 before the
//!   first of 10 ms steps (held), 0.5 s; quality: the angle at 10 ms (deg).
//!
//! Every row also gives the largest vertex distance from the default
//! rules' end state (in the sheet's size), so a rule's effect on the
//! answer shows beside its cost.
//!
//! `cargo bench --bench suite -- [--scenes a,b,...] [--rules default,name,...] [--tau T] [--repeat N]`
//! (`--rules all`: the defaults, then each rule off in turn; the names are
//! those of `IntegrationParameters::rules`; `--tau`: the actuators' time
//! constant in s, 0 for ideal actuators; `--repeat`: run every
//! configuration N times, interleaved, and keep each scene's least CPU).
//! CPU is this thread's CPU time.

#[path = "../tests/common/mod.rs"]
mod test_common;

use nalgebra::Vector3;
use origami_fmu::benchmarks::{aligned_max_distance, fold_by_ramp_with};
use origami_fmu::ids::VertexId;
use origami_fmu::model::{Model, StepReport};
use origami_fmu::scene::Scene;
use origami_fmu::scene::patterns::Miura;
use origami_fmu::solver::{IntegrationParameters, Rule};
use std::f64::consts::PI;

/// CPU time of this thread so far, s.
fn cpu_seconds() -> f64 {
    origami_fmu::cpu_time::now(origami_fmu::cpu_time::Clock::Thread).as_secs_f64()
}

/// What one scene's run did.
#[derive(Default)]
struct Row {
    cpu: f64,
    work: StepReport,
    /// The scene's own measure of the answer (see the module doc).
    quality: f64,
    /// Vertex positions at the end (for the distance from the defaults).
    end: Vec<Vector3<f64>>,
    /// The sheet's size (m).
    size: f64,
}

fn positions(m: &Model) -> Vec<Vector3<f64>> {
    (0..m.scene().mesh.n_vertices())
        .map(|v| Vector3::from(m.vertex_position(VertexId(v))))
        .collect()
}

fn finish(m: &Model, cpu: f64, work: StepReport, quality: f64) -> Row {
    Row {
        cpu,
        work,
        quality,
        end: positions(m),
        size: m.scene().mesh.size(),
    }
}

/// The Miura sheet of `panels` x `panels` folded with or without slopes.
fn miura(panels: usize, slopes: bool, tweak: &dyn Fn(&mut Scene)) -> Row {
    let miura = Miura {
        nx: panels / 2,
        ny: panels / 2,
        ..Default::default()
    };
    let exact = miura.folded();
    let mut scene = origami_fmu::scene::from_fold(&miura.generate().unwrap(), None)
        .unwrap()
        .0;
    tweak(&mut scene);
    let mut m = Model::new(scene).unwrap();
    m.initialize().unwrap();
    let c0 = cpu_seconds();
    let work = fold_by_ramp_with(&mut m, 200, 0.01, 0.5, slopes, |_, _| {});
    let cpu = cpu_seconds() - c0;
    let err = aligned_max_distance(&positions(&m), &exact) / miura.a;
    finish(&m, cpu, work, err)
}

fn throughput8(tweak: &dyn Fn(&mut Scene)) -> Row {
    let mut scene = origami_fmu::benchmarks::miura_scene(8);
    scene.solver.tolerance = 1e-3;
    scene.solver.max_step = 1e-3;
    tweak(&mut scene);
    let mut m = Model::new(scene).unwrap();
    m.initialize().unwrap();
    let c0 = cpu_seconds();
    let work = fold_by_ramp_with(&mut m, 100, 0.01, 0.5, true, |_, _| {});
    let cpu = cpu_seconds() - c0;
    let exact = Miura {
        nx: 8,
        ny: 8,
        ..Default::default()
    };
    let err = aligned_max_distance(&positions(&m), &exact.folded()) / exact.a;
    finish(&m, cpu, work, err)
}

fn pyramid(tweak: &dyn Fn(&mut Scene)) -> Row {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/origami-simulator/BoxPleatPyramid.fold"
    );
    let (mut scene, _) = origami_fmu::scene::load(path).unwrap();
    tweak(&mut scene);
    let mut m = Model::new(scene).unwrap();
    m.initialize().unwrap();
    let c0 = cpu_seconds();
    let work = fold_by_ramp_with(&mut m, 10, 0.01, 0.5, true, |_, _| {});
    let cpu = cpu_seconds() - c0;
    finish(&m, cpu, work, f64::NAN)
}

/// Drive `fold` piecewise linearly through `points` (value and slope set
/// before each step of at most `dt`).
fn drive(m: &mut Model, work: &mut StepReport, points: &[(f64, f64)], dt: f64) {
    let fold = test_common::input(m, "fold");
    let (mut t0, mut u0) = (m.time(), m.input(fold).unwrap());
    for &(t1, u1) in points {
        while m.time() < t1 - 1e-12 * t1 {
            let h = dt.min(t1 - m.time());
            let u = u0 + (u1 - u0) * ((m.time() - t0) / (t1 - t0)).min(1.0);
            m.set_input(fold, u).unwrap();
            m.set_input_derivative(fold, 1, (u1 - u0) / (t1 - t0))
                .unwrap();
            work.accumulate(&m.advance(h).unwrap());
        }
        (t0, u0) = (t1, u1);
    }
}

fn extreme(tweak: &dyn Fn(&mut Scene)) -> Row {
    use test_common::{crease_angle, hinge_omega, two_panels};
    let w = 0.02;
    let ga = origami_fmu::scene::Integrator::GeneralizedAlpha;
    let mut work = StepReport::default();
    let mut worst = 0.0f64;
    let mut cpu = 0.0;
    // Rest angle jump within 1 us, then held for 20 hinge periods.
    {
        let mut scene = two_panels(w, PI / 2.0, ga);
        scene.solver.tolerance = 1e-4;
        tweak(&mut scene);
        let t = 2.0 * PI / hinge_omega(&scene, w);
        let mut m = Model::new(scene).unwrap();
        m.initialize().unwrap();
        let c0 = cpu_seconds();
        drive(&mut m, &mut work, &[(1e-6, 1.0)], 1e-6);
        drive(&mut m, &mut work, &[(20.0 * t, 1.0)], 1e-3);
        cpu += cpu_seconds() - c0;
        worst = worst.max((crease_angle(&m) - PI / 2.0).abs());
    }
    // Through flat to +-179 degrees.
    {
        let full = 179f64.to_radians();
        let mut scene = two_panels(w, full, ga);
        tweak(&mut scene);
        let t = 2.0 * PI / hinge_omega(&scene, w);
        scene.solver.max_step = t / 20.0;
        let mut m = Model::new(scene).unwrap();
        m.initialize().unwrap();
        let c0 = cpu_seconds();
        for (k, u) in [1.0, -1.0, 0.0].into_iter().enumerate() {
            let t0 = 12.0 * t * k as f64;
            drive(
                &mut m,
                &mut work,
                &[(t0 + 2.0 * t, u), (t0 + 12.0 * t, u)],
                t / 10.0,
            );
            worst = worst.max((crease_angle(&m) - u * full).abs());
        }
        cpu += cpu_seconds() - c0;
    }
    // Thickness ratio 1e-5 folded to 90 degrees.
    {
        let mut scene = two_panels(w, PI / 2.0, ga);
        scene.material.thickness = 1e-5 * w;
        tweak(&mut scene);
        let t = 2.0 * PI / hinge_omega(&scene, w);
        scene.solver.max_step = t / 20.0;
        let mut m = Model::new(scene).unwrap();
        m.initialize().unwrap();
        let c0 = cpu_seconds();
        drive(
            &mut m,
            &mut work,
            &[(2.0 * t, 1.0), (12.0 * t, 1.0)],
            t / 10.0,
        );
        cpu += cpu_seconds() - c0;
        worst = worst.max((crease_angle(&m) - PI / 2.0).abs());
    }
    // A free sheet spinning at 100 rad/s about its normal, one revolution.
    {
        let (a, rate) = (0.04, 100.0);
        let mesh = origami_fmu::mesh::builders::grid(a, a, 2, 2, &[(1, 0.0)]);
        let mut scene = Scene::with_defaults("spin", mesh);
        scene.auto_damping = false;
        scene.solver.tolerance = 1e-6;
        tweak(&mut scene);
        let centre = Vector3::new(a / 2.0, a / 2.0, 0.0);
        let mut m = Model::new(scene).unwrap();
        m.initialize().unwrap();
        test_common::set_velocity(&mut m, |x, _| {
            test_common::rigid_rotation(rate * Vector3::z(), centre, x)
        });
        let start = positions(&m);
        let c0 = cpu_seconds();
        for _ in 0..100 {
            work.accumulate(&m.advance(2.0 * PI / rate / 100.0).unwrap());
        }
        cpu += cpu_seconds() - c0;
        let back = positions(&m)
            .iter()
            .zip(&start)
            .map(|(x, y)| (x - y).norm() / (a / 2f64.sqrt()))
            .fold(0.0, f64::max);
        worst = worst.max(back);
        finish(&m, cpu, work, worst)
    }
}

fn contact(tweak: &dyn Fn(&mut Scene)) -> Row {
    use origami_fmu::ids::EdgeId;
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/waterbomb.fold");
    let (mut scene, _) = origami_fmu::scene::load(path).unwrap();
    for e in 0..scene.mesh.edges().len() {
        if scene.mesh.edges()[e].kind == origami_fmu::mesh::EdgeKind::Crease {
            let t = origami_fmu::benchmarks::waterbomb_base_target(&scene.mesh, e);
            scene.mesh.set_fold_target(EdgeId(e), t).unwrap();
        }
    }
    scene.contact = Some(origami_fmu::contact::ContactSettings {
        friction: 0.3,
        ..scene.default_contact()
    });
    tweak(&mut scene);
    let mut m = Model::new(scene).unwrap();
    m.initialize().unwrap();
    let c0 = cpu_seconds();
    let work = fold_by_ramp_with(&mut m, 80, 0.01, 0.5, true, |_, _| {});
    let cpu = cpu_seconds() - c0;
    let gap = m.contact().unwrap().min_gap;
    finish(&m, cpu, work, gap)
}

fn cosim(tweak: &dyn Fn(&mut Scene)) -> Row {
    let mut scene = origami_fmu::benchmarks::miura_scene(2);
    tweak(&mut scene);
    let mut m = Model::new(scene).unwrap();
    m.initialize().unwrap();
    let c0 = cpu_seconds();
    let work = fold_by_ramp_with(&mut m, 10_000, 1e-4, 0.6, true, |_, _| {});
    let cpu = cpu_seconds() - c0;
    finish(&m, cpu, work, f64::NAN)
}

fn crease_step(tweak: &dyn Fn(&mut Scene)) -> Row {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/single_crease.fold");
    let (mut scene, _) = origami_fmu::scene::load(path).unwrap();
    tweak(&mut scene);
    let mut m = Model::new(scene).unwrap();
    m.initialize().unwrap();
    let fold = test_common::input(&m, "fold");
    let angle = m
        .outputs()
        .iter()
        .position(|v| v.name.starts_with("crease["))
        .unwrap();
    let mut work = StepReport::default();
    let mut at_10ms = f64::NAN;
    let c0 = cpu_seconds();
    for k in 0..50 {
        m.set_input(fold, 1.0).unwrap();
        work.accumulate(&m.advance(0.01).unwrap());
        if k == 0 {
            at_10ms = m.output_values()[angle].to_degrees();
        }
    }
    let cpu = cpu_seconds() - c0;
    finish(&m, cpu, work, at_10ms)
}

type SceneFn = fn(&dyn Fn(&mut Scene)) -> Row;

fn scenes() -> Vec<(&'static str, SceneFn)> {
    vec![
        ("miura4", |t| miura(4, true, t)),
        ("miura4-held", |t| miura(4, false, t)),
        ("miura16", |t| miura(16, true, t)),
        ("throughput8", throughput8),
        ("pyramid", pyramid),
        ("extreme", extreme),
        ("contact", contact),
        ("cosim", cosim),
        ("crease-step", crease_step),
    ]
}

/// One configuration's rows (None: the scene failed).
type Rows = Vec<Option<Row>>;

fn run_config(
    chosen: &[(&'static str, SceneFn)],
    params: IntegrationParameters,
    tau: Option<f64>,
) -> Rows {
    chosen
        .iter()
        .map(|(_, f)| {
            let tweak = move |s: &mut Scene| {
                s.solver.integration = params;
                if tau.is_some() {
                    s.actuator_time_constant = tau;
                }
            };
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| f(&tweak))).ok()
        })
        .collect()
}

fn print_rows(chosen: &[(&'static str, SceneFn)], rows: &Rows, base: Option<&Rows>) {
    println!(
        "| scene | CPU s | steps (rejected) | Newton its | factorizations | quality | off the defaults' end |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- |");
    for (i, ((name, _), r)) in chosen.iter().zip(rows).enumerate() {
        let Some(r) = r else {
            println!("| {name} | failed | | | | | |");
            continue;
        };
        let off = match base.and_then(|b| b[i].as_ref()) {
            Some(b) => format!(
                "{:.1e}",
                r.end
                    .iter()
                    .zip(&b.end)
                    .map(|(x, y)| (x - y).norm())
                    .fold(0.0, f64::max)
                    / r.size
            ),
            None => "-".into(),
        };
        println!(
            "| {name} | {:.2} | {} ({}) | {} | {} | {:.3e} | {off} |",
            r.cpu,
            r.work.steps,
            r.work.rejected,
            r.work.newton_iterations,
            r.work.factorizations,
            r.quality
        );
    }
}

/// The geometric mean over the scenes of `f(rule off) / f(defaults)`
/// (None where a scene failed with the rule off).
fn mean_ratio(base: &Rows, rows: &Rows, f: impl Fn(&Row) -> f64) -> Option<f64> {
    let mut log = 0.0;
    let mut n = 0;
    for (b, r) in base.iter().zip(rows) {
        let (Some(b), r) = (b, r) else { continue };
        let r = r.as_ref()?;
        log += (f(r).max(1e-9) / f(b).max(1e-9)).ln();
        n += 1;
    }
    Some((log / n.max(1) as f64).exp())
}

fn main() {
    let value = origami_fmu::benchmarks::arg_text;
    let wanted: Option<Vec<String>> =
        value("--scenes").map(|v| v.split(',').map(String::from).collect());
    let chosen: Vec<_> = scenes()
        .into_iter()
        .filter(|(n, _)| wanted.as_ref().is_none_or(|w| w.iter().any(|x| x == n)))
        .collect();
    let rules: Vec<&Rule> = match value("--rules").as_deref() {
        None | Some("default") => vec![],
        Some("all") => IntegrationParameters::rules().iter().collect(),
        Some(list) => list
            .split(',')
            .filter(|n| *n != "default")
            .map(|n| IntegrationParameters::rule(n).unwrap_or_else(|| panic!("no rule {n}")))
            .collect(),
    };
    let defaults = IntegrationParameters::default();
    // Each configuration `--repeat` times, interleaved, keeping each
    // scene's least CPU (the least disturbed run on a shared machine; the
    // counts are the same every time).
    let repeat: usize = value("--repeat").map_or(1, |v| v.parse().expect("a count"));
    // The actuators' time constant (default: the scenes' own, automatic).
    let tau: Option<f64> = value("--tau").map(|v| v.parse().expect("a time constant (s)"));
    let configs: Vec<IntegrationParameters> = std::iter::once(defaults)
        .chain(rules.iter().map(|r| (r.off)(defaults)))
        .collect();
    let mut results: Vec<Rows> = Vec::new();
    for k in 0..repeat {
        for (c, &params) in configs.iter().enumerate() {
            let rows = run_config(&chosen, params, tau);
            if k == 0 {
                results.push(rows);
                continue;
            }
            for (best, row) in results[c].iter_mut().zip(rows) {
                if let (Some(b), Some(r)) = (best.as_mut(), row) {
                    b.cpu = b.cpu.min(r.cpu);
                }
            }
        }
    }
    let mut results = results.into_iter();
    let base = results.next().expect("the defaults ran");
    println!("## defaults");
    print_rows(&chosen, &base, None);
    let total = |rows: &Rows| rows.iter().flatten().map(|r| r.cpu).sum::<f64>();
    println!("\nsuite CPU {:.2} s", total(&base));
    let mut summary = Vec::new();
    for (rule, rows) in rules.into_iter().zip(results) {
        println!("\n## {} off ({})", rule.name, rule.what);
        print_rows(&chosen, &rows, Some(&base));
        summary.push((rule, rows));
    }
    if summary.is_empty() {
        return;
    }
    println!(
        "\n| rule | what it does | suite CPU off / on | mean CPU ratio off / on | mean steps ratio | mean Newton its ratio | mean factorizations ratio | scenes failed off |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- |");
    for (rule, rows) in &summary {
        let show = |x: Option<f64>| x.map_or("-".into(), |x| format!("{x:.3}"));
        let failed: Vec<&str> = chosen
            .iter()
            .zip(rows)
            .filter(|(_, r)| r.is_none())
            .map(|((n, _), _)| *n)
            .collect();
        println!(
            "| {} | {} | {:.3} | {} | {} | {} | {} | {} |",
            rule.name,
            rule.what,
            total(rows) / total(&base),
            show(mean_ratio(&base, rows, |r| r.cpu)),
            show(mean_ratio(
                &base,
                rows,
                |r| (r.work.steps + r.work.rejected) as f64
            )),
            show(mean_ratio(&base, rows, |r| r.work.newton_iterations as f64)),
            show(mean_ratio(&base, rows, |r| r.work.factorizations as f64)),
            if failed.is_empty() {
                "-".into()
            } else {
                failed.join(", ")
            }
        );
    }
}
