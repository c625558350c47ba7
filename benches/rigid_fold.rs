//! Issue 12's measure: Miura-ori sheets of m x m panels (20 mm, 60 degree
//! sectors) driven at default settings to their full rigid fold (Schenk &
//! Guest theta = 60 degrees: the fold input ramps 0 -> 1 over 0.5 s, then
//! holds, 10 ms communication steps with the ramp's slope, as the peer
//! comparison's `fmu_drive.py` does), and the CPU time from which the
//! largest vertex distance to the exact rigid state (after the best-fit
//! rigid motion, in panel edges) stays below 1e-3 and 1e-4 until the end.
//!
//! Then Origami Simulator's BoxPleatPyramid (tests/data/origami-simulator,
//! 5202 facets) at the same settings, its fold input ramped 0 -> 1 over
//! 0.5 s: CPU for the first `--pyramid` seconds (0 skips it), the CPU per
//! simulated second that makes, and (from 0.2 s on) a row per tenth of a
//! second: where along the fold the CPU goes.
//!
//! `cargo bench --bench rigid_fold -- [--panels 4,8,10,16] [--stop 2.0] [--pyramid 0.01]
//! [--tolerance T] [--max-step H] [--rho-inf R] [--quadrature 7|12] [--contact]` (the last
//! five, for the Miura sheets and the pyramid alike, to compare with the
//! defaults; `--contact` turns self-contact on with its default settings)
//!
//! Also: the exponent p of total CPU ~ DOFs^p from the first sheet, steps,
//! Newton iterations, factorizations and where the CPU went (assembly,
//! factorization, solves, the rest). CPU is the process's CPU
//! time (the machine is shared: compare within one run).

use nalgebra::Vector3;
use origami_fmu::ids::VertexId;
mod common;
use common::cpu_seconds;
use origami_fmu::benchmarks::{aligned_max_distance, fold_by_ramp_with};
use origami_fmu::model::{Model, StepReport};
use origami_fmu::scene::Scene;
use origami_fmu::scene::patterns::Miura;

fn main() {
    origami_fmu::solver::set_phase_timing(true);
    let args: Vec<String> = std::env::args().skip(1).collect();
    let value = origami_fmu::benchmarks::arg_text;
    let panels: Vec<usize> = value("--panels")
        .map(|v| v.split(',').map(|x| x.parse().expect("panels")).collect())
        .unwrap_or_else(|| vec![4, 8, 10, 16]);
    let stop: f64 = value("--stop").map_or(2.0, |v| v.parse().expect("stop time"));
    let pyramid: f64 = value("--pyramid").map_or(0.01, |v| v.parse().expect("pyramid time"));
    // Settings other than the defaults, to compare (the table is for defaults).
    let tolerance: Option<f64> = value("--tolerance").map(|v| v.parse().expect("tolerance"));
    let max_step: Option<f64> = value("--max-step").map(|v| v.parse().expect("max step"));
    let rho_inf: Option<f64> = value("--rho-inf").map(|v| v.parse().expect("rho_inf"));
    let quadrature = value("--quadrature").map(|v| common::quadrature_rule(&v));
    let contact = args.iter().any(|a| a == "--contact");
    let settings = |scene: &mut Scene| {
        if contact {
            // As `"ancf:contact": {"enabled": true}` gives it: the sheet's thickness.
            scene.contact = Some(scene.default_contact());
        }
        if let Some(t) = tolerance {
            scene.solver.tolerance = t;
        }
        if let Some(h) = max_step {
            scene.solver.max_step = h;
        }
        if let Some(rule) = quadrature {
            scene.solver.quadrature = rule;
        }
        if let Some(r) = rho_inf {
            scene.solver.rho_inf = r;
        }
    };
    let (ramp, dt) = (0.5, 0.01);
    println!(
        "Miura full fold at default settings: ramp 0 -> 1 over {ramp} s, {dt} s communication steps, {stop} s simulated"
    );
    println!(
        "| panels | DOFs | CPU s to stay below 1e-3 | below 1e-4 | final error | CPU s total | growth exponent | steps (rejected) | Newton its | factorizations | assembly % | factorization % | solves % | other % |"
    );
    println!(
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"
    );
    // (DOFs, CPU s) of the first sheet: total CPU grows as DOFs^p from it.
    let mut first: Option<(f64, f64)> = None;
    for &p in &panels {
        assert!(
            p % 2 == 0,
            "--panels takes even numbers (the generator's unit cell is 2 x 2 panels)"
        );
        let miura = Miura {
            nx: p / 2,
            ny: p / 2,
            ..Default::default()
        };
        let exact: Vec<Vector3<f64>> = miura.folded();
        let fold = miura.generate().expect("Miura pattern");
        let mut scene = origami_fmu::scene::from_fold(&fold, None)
            .expect("Miura scene")
            .0;
        settings(&mut scene);
        let mut m = Model::new(scene).expect("model");
        m.initialize().expect("initialize");
        let steps = (stop / dt).round() as usize;
        // (CPU s at the end of the step, error in panel edges, internal steps so far).
        let mut trace = Vec::with_capacity(steps);
        let c0 = cpu_seconds();
        let total = fold_by_ramp_with(&mut m, steps, dt, ramp, true, |m, total| {
            let cpu = cpu_seconds() - c0;
            let x: Vec<Vector3<f64>> = (0..exact.len())
                .map(|v| Vector3::from(m.vertex_position(VertexId(v))))
                .collect();
            trace.push((cpu, aligned_max_distance(&x, &exact) / miura.a, total.steps));
        });
        let cpu = cpu_seconds() - c0;
        // (CPU s, simulated s, internal steps) at the end of the step after
        // the last one at or above `limit`.
        let stays_below = |limit: f64| match trace.iter().rposition(|&(_, e, _)| e >= limit) {
            None => Some((0.0, 0.0, 0)),
            Some(i) if i + 1 < trace.len() => Some((trace[i].0, (i + 1) as f64 * dt, trace[i].2)),
            Some(_) => None,
        };
        let show = |x: Option<(f64, f64, usize)>| {
            x.map_or("never".to_string(), |(c, t, n)| {
                format!("{c:.2} (at {t:.2} s, {n} steps)")
            })
        };
        let pct = |x: f64| 100.0 * x / cpu;
        let other = cpu - total.assembly_time - total.factor_time - total.solve_time;
        let dofs = m.n_dofs() as f64;
        let growth = match first {
            Some((d0, c0)) => format!("{:.2}", (cpu / c0).ln() / (dofs / d0).ln()),
            None => {
                first = Some((dofs, cpu));
                "-".into()
            }
        };
        println!(
            "| {p}x{p} | {} | {} | {} | {:.1e} | {cpu:.2} | {growth} | {} ({}) | {} | {} | {:.0} | {:.0} | {:.0} | {:.0} |",
            m.n_dofs(),
            show(stays_below(1e-3)),
            show(stays_below(1e-4)),
            trace.last().map_or(f64::NAN, |t| t.1),
            total.steps,
            total.rejected,
            total.newton_iterations,
            total.factorizations,
            pct(total.assembly_time),
            pct(total.factor_time),
            pct(total.solve_time),
            pct(other),
        );
    }
    if pyramid > 0.0 {
        pyramid_row(pyramid, dt, ramp, settings);
    }
}

/// The BoxPleatPyramid row: CPU for the first `time` seconds of its fold,
/// with the bench's `settings` applied to its scene.
fn pyramid_row(time: f64, dt: f64, ramp: f64, settings: impl Fn(&mut Scene)) {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/origami-simulator/BoxPleatPyramid.fold"
    );
    let (mut scene, _) = origami_fmu::scene::load(path).expect("BoxPleatPyramid loads");
    settings(&mut scene);
    let facets = scene.mesh.triangles().len();
    let mut m = Model::new(scene).expect("model");
    m.initialize().expect("initialize");
    let steps = (time / dt).round().max(1.0) as usize;
    // Where the CPU goes over the fold: a row per tenth of a second.
    let per = ((0.1 / dt).round() as usize).max(1);
    let mut rows: Vec<(f64, f64, StepReport)> = Vec::new();
    let mut k = 0;
    let c0 = cpu_seconds();
    let total = fold_by_ramp_with(&mut m, steps, dt, ramp, true, |_, total| {
        k += 1;
        if k % per == 0 || k == steps {
            let c = cpu_seconds() - c0;
            // Progress on stderr (a pyramid second takes minutes).
            eprintln!(
                "pyramid at {:.2} s: {c:.1} CPU s, {} steps, {} factorizations",
                k as f64 * dt,
                total.steps,
                total.factorizations
            );
            rows.push((k as f64 * dt, c, total.clone()));
        }
    });
    let cpu = cpu_seconds() - c0;
    let sim = steps as f64 * dt;
    if rows.len() > 1 {
        println!();
        println!(
            "| BoxPleatPyramid, until t s | CPU s in the interval | steps (rejected) | Newton its | factorizations |"
        );
        println!("| --- | --- | --- | --- | --- |");
        let mut last = (0.0, StepReport::default());
        for (t, c, r) in &rows {
            println!(
                "| {t:.2} | {:.1} | {} ({}) | {} | {} |",
                c - last.0,
                r.steps - last.1.steps,
                r.rejected - last.1.rejected,
                r.newton_iterations - last.1.newton_iterations,
                r.factorizations - last.1.factorizations,
            );
            last = (*c, r.clone());
        }
    }
    println!();
    println!(
        "| pattern | facets | DOFs | simulated s | CPU s | CPU s per simulated s | steps (rejected) | Newton its | factorizations (LLT/LDLT) | assembly % | factorization % | solves % |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    let kinds = m
        .solver_stats()
        .map_or("-".to_string(), |s| format!("{}/{}", s.llt, s.ldlt));
    let pct = |x: f64| 100.0 * x / cpu;
    println!(
        "| BoxPleatPyramid | {facets} | {} | {sim} | {cpu:.1} | {:.0} | {} ({}) | {} | {} ({kinds}) | {:.0} | {:.0} | {:.0} |",
        m.n_dofs(),
        cpu / sim,
        total.steps,
        total.rejected,
        total.newton_iterations,
        total.factorizations,
        pct(total.assembly_time),
        pct(total.factor_time),
        pct(total.solve_time),
    );
}
