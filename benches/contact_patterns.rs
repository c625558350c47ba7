//! Real crease patterns folded with self-contact, as a user runs them: each
//! driven to its full fold over 1 s (the `fold` input ramped 0 -> 1 with
//! its slope, 10 ms communication steps, as a master with input
//! derivatives drives it), then held to 1.5 s, at default settings, with
//! contact on and off. Per run: CPU s of the fold (the checks apart),
//! internal steps, Newton iterations, the smallest `contact.min_gap` over
//! the outputs, whether it finished (else where it failed), the longest
//! single communication step in CPU s, the outputs at which the checker
//! (neighbours included, creases past flat) found a crossing of the sampled
//! surface contact computes with (its own subdivisions, 3 by default; the
//! guarantee: none) and of the curved facets sampled at 16 per side
//! (information: they may cross between contact's samples, where the chord
//! error says so), the largest `contact.chord_error` over the outputs, and
//! for the patterns folded flat the distance of the end state from the
//! flat-folding map (share of the folded size, in the state's best-fit
//! plane). Under the table, the first output at which the sampled surface
//! crossed, with its facets, the first at which the curved facets did,
//! with their chord errors, and the first at which `contact.min_gap` fell
//! below 0 (the guarantee: never).
//!
//! (A flat stack released in one held communication step, and what
//! reading every output costs, are parts 3 and 4 of `benches/contact.rs`.)
//!
//! `cargo bench --bench contact_patterns -- [--patterns miura,yoshimura,kresling,waterbomb,smallbird,bird,wbtess]
//! [--fold PATH ...] [--scene PATH ...] [--contact on|off|both] [--no-check] [--cpu-limit S]
//! [--frame N] [--ramp S] [--hold S] [--back S] [--held] [--subdivisions N] [--rule-off NAME]` (the suite runs unless `--fold` or `--scene` alone are given)
//! (`--patterns pyramid` adds Origami Simulator's BoxPleatPyramid to its own
//! targets, not flat and not in the default list; `--cpu-limit S` stops a
//! run once its fold and its checks together have taken S CPU s, reported
//! as not finished.)
//! (`--fold PATH` adds a FOLD file of your own, its creases driven to +-180
//! degrees by their sign; `--scene PATH` a scene as it is, its own targets
//! or folding sequence (`ancf:sequence`, keyframes), the flat-fold error
//! against the flat-folding map of its final fold angles where they are all
//! 0 or +-180 degrees; `--frame N` reads those files' frame N. `--ramp S` and `--hold S` set the drive: the `fold`
//! input from 0 to 1 over S s, then held for S s (defaults 1 and 0.5);
//! `--back S` then returns it to 0 over S s and holds it the same time
//! again (issue 52's deployment: the last column is the largest |fold
//! angle| at the end; the flat-fold error is taken where the fold's hold
//! ends); `--held` gives the input's values alone, no slopes, as a master
//! without input derivatives holds its samples. `--subdivisions N` samples
//! contact's surface at N per facet side instead of the default 3.
//! `--rule-off NAME` switches one of the stepper's speed rules off (the
//! names of `IntegrationParameters::rules`), for a side-by-side run.
//! `--help` prints this.)

mod common;
use common::cpu_seconds;
use nalgebra::Vector3;
use origami_fmu::benchmarks::{flat_fold_error, flat_folded_positions, fold_flat_by_sign};
use origami_fmu::contact::ContactSettings;
use origami_fmu::contact::check::IntersectionReport;
use origami_fmu::ids::{EdgeId, VertexId};
use origami_fmu::mesh::EdgeKind;
use origami_fmu::model::Model;
use origami_fmu::scene::Scene;
use std::f64::consts::PI;

/// One run's results.
struct Row {
    cpu: f64,
    steps: usize,
    newton: usize,
    min_gap: Option<f64>,
    failed: Option<String>,
    longest: (f64, f64),
    /// Outputs at which the sampled surface crossed, and the first of them
    /// (time, what the checker found).
    crossings: usize,
    first_crossing: Option<(f64, IntersectionReport)>,
    /// The first output with `contact.min_gap` below 0: time, gap.
    first_negative_gap: Option<(f64, f64)>,
    /// Outputs at which the curved facets crossed (16 samples per side),
    /// and the first of them described.
    curved_crossings: usize,
    first_curved: Option<String>,
    chord_error: Option<f64>,
    outputs: usize,
    flat_error: Option<f64>,
    /// Largest |fold angle| at the end of a drive that returns to 0 (deg).
    deployed: Option<f64>,
}

/// The waterbomb base collapsed: diagonals valley, the x midline mountain,
/// the y midline unfolded (the shipped scene's targets are a 3D waterbomb).
fn waterbomb_base(scene: &mut Scene) {
    for e in 0..scene.mesh.edges().len() {
        let edge = &scene.mesh.edges()[e];
        if edge.kind != EdgeKind::Crease {
            continue;
        }
        let t = origami_fmu::benchmarks::waterbomb_base_target(&scene.mesh, e);
        scene.mesh.set_fold_target(EdgeId(e), t).unwrap();
    }
}

/// The scene's mesh with each crease's target where the drive ends: its
/// sequence's last target (0 for a crease no stage names) or its own.
fn final_targets(scene: &Scene) -> origami_fmu::mesh::Mesh {
    let mut mesh = scene.mesh.clone();
    if let Some(sq) = &scene.sequence {
        let entries = sq.entries();
        for e in 0..mesh.edges().len() {
            let edge = &mesh.edges()[e];
            if edge.kind != EdgeKind::Crease {
                continue;
            }
            let t = edge
                .fold_edge
                .and_then(|fe| entries.get(&fe))
                .and_then(|list| list.last())
                .map_or(0.0, |&(_, t)| t);
            mesh.set_fold_target(EdgeId(e), t).unwrap();
        }
    }
    mesh
}

/// Whether every crease of `mesh` ends flat or at +-180 degrees.
fn ends_flat(mesh: &origami_fmu::mesh::Mesh) -> bool {
    mesh.edges().iter().all(|e| {
        e.kind != EdgeKind::Crease
            || e.fold_target == 0.0
            || (e.fold_target.abs() - PI).abs() < 1e-9
    })
}

/// The curved facets' crossing `rep` now: time, each facet pair, whether
/// they share a vertex, and their chord errors (m) against the thickness.
fn describe_curved(model: &Model, rep: &IntersectionReport) -> String {
    let triangles = model.scene().mesh.triangles();
    let (each, thickness) = model.facet_chord_errors().unwrap_or_default();
    let of = |f: usize| each.get(f).copied().unwrap_or(0.0);
    let pairs: Vec<String> = rep
        .intersecting
        .iter()
        .map(|&(f, g)| {
            let shared = triangles[f].iter().any(|v| triangles[g].contains(v));
            format!(
                "({f}, {g}{}, chord errors {:.2e}, {:.2e})",
                if shared { ", sharing a vertex" } else { "" },
                of(f),
                of(g)
            )
        })
        .collect();
    format!(
        "t = {:.2} s: facets {}, creases past flat {:?} (thickness {thickness:.2e} m)",
        model.time(),
        pairs.join(" "),
        rep.past_flat
    )
}

/// How the `fold` input is driven: 0 -> 1 over `ramp` s, then held `hold`
/// s; with `back` > 0 then back to 0 over `back` s and held `hold` s more.
/// With its slopes (a master with input derivatives), or `held` (the
/// values alone, as a master without them holds its samples).
#[derive(Clone, Copy)]
struct Drive {
    ramp: f64,
    hold: f64,
    back: f64,
    held: bool,
}

impl Drive {
    /// The input and its slope over the step from `t`.
    fn at(&self, t: f64) -> (f64, f64) {
        let (u, slope) = if t < self.ramp {
            (t / self.ramp, 1.0 / self.ramp)
        } else if self.back <= 0.0 || t < self.ramp + self.hold {
            (1.0, 0.0)
        } else if t < self.ramp + self.hold + self.back {
            (
                1.0 - (t - self.ramp - self.hold) / self.back,
                -1.0 / self.back,
            )
        } else {
            (0.0, 0.0)
        };
        (u, if self.held { 0.0 } else { slope })
    }

    /// The whole drive's length (s).
    fn length(&self) -> f64 {
        let out = if self.back > 0.0 {
            self.back + self.hold
        } else {
            0.0
        };
        self.ramp + self.hold + out
    }
}

/// `scene` driven by `drive`, with self-contact where `contact` is given.
fn run(
    scene: Scene,
    contact: Option<ContactSettings>,
    check: bool,
    flat: bool,
    cpu_limit: f64,
    drive: Drive,
) -> Row {
    let mut scene = scene;
    if let Some(c) = contact {
        scene.contact = Some(c);
    }
    let map = flat.then(|| flat_folded_positions(&final_targets(&scene)));
    let mut model = Model::new(scene).unwrap();
    model.initialize().unwrap();
    let fold = model.input_id("fold").unwrap();
    let dt = 0.01;
    let mut row = Row {
        cpu: 0.0,
        steps: 0,
        newton: 0,
        min_gap: None,
        failed: None,
        longest: (0.0, 0.0),
        crossings: 0,
        first_crossing: None,
        first_negative_gap: None,
        curved_crossings: 0,
        first_curved: None,
        chord_error: None,
        outputs: 0,
        flat_error: None,
        deployed: None,
    };
    // The checks' CPU: with the fold's, against the limit.
    let mut checking = 0.0;
    let n = (drive.length() / dt).round() as usize;
    let folded_at = ((drive.ramp + drive.hold) / dt).round() as usize;
    for k in 0..n {
        let t = k as f64 * dt;
        let (u, slope) = drive.at(t);
        model.set_input(fold, u).unwrap();
        model.set_input_derivative(fold, 1, slope).unwrap();
        let c0 = cpu_seconds();
        let r = model.advance(dt);
        let c = cpu_seconds() - c0;
        row.cpu += c;
        if c > row.longest.0 {
            row.longest = (c, t);
        }
        match r {
            Ok(r) => {
                row.steps += r.steps;
                row.newton += r.newton_iterations;
            }
            Err(e) => {
                row.failed = Some(format!("at {t:.2} s: {e}"));
                break;
            }
        }
        row.outputs += 1;
        if row.cpu + checking > cpu_limit && k + 1 < n {
            row.failed = Some(format!(
                "stopped at {:.2} s: over the {cpu_limit} CPU s limit",
                t + dt
            ));
            break;
        }
        if let Some(c) = model.contact() {
            row.min_gap = Some(row.min_gap.map_or(c.min_gap, |g| g.min(c.min_gap)));
            if c.min_gap < 0.0 {
                row.first_negative_gap
                    .get_or_insert((model.time(), c.min_gap));
            }
        }
        if let Some((e, _)) = model.chord_error() {
            row.chord_error = Some(row.chord_error.map_or(e, |w| w.max(e)));
        }
        let c0 = cpu_seconds();
        if check {
            let sampled = model.check_sampled_surface(0.0).unwrap();
            if !sampled.is_clear() {
                row.crossings += 1;
                row.first_crossing.get_or_insert((model.time(), sampled));
            }
            let curved = model.check_intersections(16, 0.0).unwrap();
            if !curved.is_clear() {
                row.curved_crossings += 1;
                if row.first_curved.is_none() {
                    row.first_curved = Some(describe_curved(&model, &curved));
                }
            }
        }
        checking += cpu_seconds() - c0;
        if let (Some(map), true) = (&map, k + 1 == folded_at) {
            let x: Vec<Vector3<f64>> = (0..model.scene().mesh.n_vertices())
                .map(|v| Vector3::from(model.vertex_position(VertexId(v))))
                .collect();
            row.flat_error = Some(flat_fold_error(map, &x));
        }
    }
    if drive.back > 0.0 && row.failed.is_none() {
        let largest = model
            .outputs()
            .iter()
            .zip(model.output_values())
            .filter(|(v, _)| v.name.starts_with("crease[") && v.name.ends_with(".angle"))
            .fold(0.0, |m: f64, (_, a)| m.max(a.abs()));
        row.deployed = Some(largest.to_degrees());
    }
    row
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.iter().any(|a| a == "--help" || a == "-h") {
        println!(
            "{}",
            include_str!("contact_patterns.rs")
                .lines()
                .take_while(|l| l.starts_with("//!"))
                .map(|l| l.trim_start_matches("//!").trim_start())
                .collect::<Vec<_>>()
                .join("\n")
        );
        return;
    }
    let list = |flag: &str| -> Vec<String> {
        args.iter()
            .enumerate()
            .filter(|(_, a)| *a == flag)
            .filter_map(|(i, _)| args.get(i + 1).cloned())
            .collect()
    };
    let number = |flag: &str, default: f64| -> f64 {
        origami_fmu::benchmarks::arg_text(flag).map_or(default, |v| v.parse().unwrap())
    };
    let drive = Drive {
        ramp: number("--ramp", 1.0),
        hold: number("--hold", 0.5),
        back: number("--back", 0.0),
        held: args.iter().any(|a| a == "--held"),
    };
    let value = origami_fmu::benchmarks::arg_text;
    let folds = list("--fold");
    let own = list("--scene");
    // The suite unless files alone are asked for.
    let suite = if folds.is_empty() && own.is_empty() {
        "miura,yoshimura,kresling,waterbomb,smallbird,bird,wbtess".to_string()
    } else {
        String::new()
    };
    let patterns: Vec<String> = value("--patterns")
        .unwrap_or(suite)
        .split(',')
        .filter(|p| !p.is_empty())
        .map(String::from)
        .collect();
    let which = value("--contact").unwrap_or_else(|| "both".into());
    let modes: Vec<bool> = match which.as_str() {
        "on" => vec![true],
        "off" => vec![false],
        _ => vec![false, true],
    };
    let check = !args.iter().any(|a| a == "--no-check");
    let subdivisions: Option<usize> = value("--subdivisions").map(|v| v.parse().unwrap());
    let cpu_limit: f64 = value("--cpu-limit").map_or(f64::INFINITY, |v| v.parse().unwrap());
    let root = env!("CARGO_MANIFEST_DIR");
    let mut scenes: Vec<(String, Scene, bool)> = Vec::new();
    for p in &patterns {
        let load = |f: &str| origami_fmu::scene::load(format!("{root}/{f}")).unwrap().0;
        let (name, scene, flat) = match p.as_str() {
            "miura" => {
                let mut s = load("scenes/miura_4x4.fold");
                fold_flat_by_sign(&mut s);
                ("Miura 4x4 folded flat", s, true)
            }
            "yoshimura" => {
                let mut s = load("scenes/yoshimura.fold");
                fold_flat_by_sign(&mut s);
                ("Yoshimura folded flat", s, true)
            }
            "kresling" => {
                let mut s = load("scenes/kresling.fold");
                fold_flat_by_sign(&mut s);
                ("Kresling folded flat", s, true)
            }
            "waterbomb" => {
                let mut s = load("scenes/waterbomb.fold");
                waterbomb_base(&mut s);
                ("waterbomb base", s, true)
            }
            "smallbird" => {
                let mut s = load("tests/data/flat-folder/244_komatsuoripa_Smallbird_Base.fold");
                fold_flat_by_sign(&mut s);
                ("small bird base (flat-folder)", s, true)
            }
            "bird" => {
                let mut s = load("tests/data/flat-folder/089_traditionaloripa_9_Birdbase.fold");
                fold_flat_by_sign(&mut s);
                ("9 bird bases (flat-folder)", s, true)
            }
            "wbtess" => {
                // Its own targets: the collapsed tessellation, +-180 deg.
                let s = load("scenes/waterbomb_tessellation.fold");
                ("waterbomb tessellation 4x4", s, true)
            }
            "pyramid" => {
                // Its own targets (not flat): it ends at them, uncrossed.
                let s = load("tests/data/origami-simulator/BoxPleatPyramid.fold");
                ("BoxPleatPyramid (Origami Simulator)", s, false)
            }
            other => panic!("unknown pattern {other}"),
        };
        scenes.push((name.to_string(), scene, flat));
    }
    // `--frame N`: the files' frame N (a file whose first frame is folded).
    let options = origami_fmu::scene::LoadOptions {
        frame: value("--frame")
            .map(|n| origami_fmu::scene::FrameSelector::Index(n.parse().unwrap())),
        ..Default::default()
    };
    let read = |f: &str| {
        origami_fmu::scene::load_with(f, &options)
            .unwrap_or_else(|e| panic!("{f} does not load: {e}"))
            .0
    };
    for f in &folds {
        let mut s = read(f);
        fold_flat_by_sign(&mut s);
        scenes.push((f.rsplit('/').next().unwrap_or(f).to_string(), s, true));
    }
    for f in &own {
        let s = read(f);
        let flat = ends_flat(&final_targets(&s));
        scenes.push((f.rsplit('/').next().unwrap_or(f).to_string(), s, flat));
    }
    let rule_off = value("--rule-off").map(|n| {
        origami_fmu::solver::IntegrationParameters::rule(&n)
            .unwrap_or_else(|| panic!("no rule {n}"))
    });
    if let Some(r) = rule_off {
        for (_, s, _) in &mut scenes {
            s.solver.integration = (r.off)(s.solver.integration);
        }
    }
    println!(
        "## Patterns folded over {} s and held {} s more{}, {} ({}, 10 ms steps; CPU of the folds, the checks apart)",
        drive.ramp,
        drive.hold,
        if drive.back > 0.0 {
            format!(
                ", back to flat over {} s and held {} s",
                drive.back, drive.hold
            )
        } else {
            String::new()
        },
        if drive.held {
            "held samples (no slopes)"
        } else {
            "with slopes"
        },
        match subdivisions {
            Some(n) => format!("default settings but contact's {n} subdivisions"),
            None => "default settings".to_string(),
        } + &rule_off.map_or(String::new(), |r| format!(", the rule {} off", r.name))
    );
    println!(
        "| pattern | facets | contact | CPU s | steps | Newton its | smallest gap (m) | finished | longest step (CPU s, at t) | outputs crossing: sampled surface | curved facets (16/side) | largest chord error (m) | flat-fold error | largest angle at the end (deg) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    let mut notes = Vec::new();
    for (name, scene, flat) in &scenes {
        for &contact in &modes {
            let facets = scene.mesh.triangles().len();
            // Contact at its defaults, at `--subdivisions` where given.
            let settings = contact.then(|| {
                let mut c = scene.default_contact();
                if let Some(n) = subdivisions {
                    c.subdivisions = n;
                }
                c
            });
            let r = run(scene.clone(), settings, check, *flat, cpu_limit, drive);
            let outputs = |n: usize| {
                if check {
                    format!("{n} of {}", r.outputs)
                } else {
                    "-".into()
                }
            };
            if let Some(text) = &r.first_curved {
                notes.push(format!(
                    "- {name}, contact {}: the curved facets (16/side) first crossed at {text}",
                    if contact { "on" } else { "off" },
                ));
            }
            if let Some((t, gap)) = r.first_negative_gap {
                notes.push(format!(
                    "- {name}, contact on: contact.min_gap first below 0 at t = {t:.2} s ({gap:.2e} m)"
                ));
            }
            if let Some((t, rep)) = &r.first_crossing {
                notes.push(format!(
                    "- {name}, contact {}: the sampled surface first crossed at t = {t:.2} s: \
                     facets {:?}, creases past flat {:?}",
                    if contact { "on" } else { "off" },
                    rep.intersecting,
                    rep.past_flat,
                ));
            }
            println!(
                "| {name} | {facets} | {} | {:.2} | {} | {} | {} | {} | {:.2} (at {:.2} s) | {} | {} | {} | {} | {} |",
                if contact { "on" } else { "off" },
                r.cpu,
                r.steps,
                r.newton,
                r.min_gap.map_or("-".into(), |g| format!("{g:.2e}")),
                r.failed.as_deref().unwrap_or("yes"),
                r.longest.0,
                r.longest.1,
                outputs(r.crossings),
                outputs(r.curved_crossings),
                r.chord_error.map_or("-".into(), |e| format!("{e:.2e}")),
                r.flat_error
                    .map_or("-".into(), |e| format!("{:.2} %", 100.0 * e)),
                r.deployed.map_or("-".into(), |a| format!("{a:.2}")),
            );
        }
    }
    for n in notes {
        println!("{n}");
    }
}
