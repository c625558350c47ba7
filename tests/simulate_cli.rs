//! `origami-fmu simulate` as a user runs it: the default input is the
//! model's built-in ramp whatever the stop time, pictures come out of the
//! CLI alone, and a failed step says where the run stopped.

use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_origami-fmu"))
}

fn scratch(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("origami_fmu_sim_{tag}_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Rows of a CSV written by `simulate` (header skipped).
fn rows(path: &Path) -> Vec<Vec<f64>> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect()
}

fn simulate(scene: &Path, extra: &[&str]) -> (std::process::Output, String) {
    let r = bin()
        .arg("simulate")
        .arg(scene)
        .args(extra)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&r.stderr).into_owned();
    (r, err)
}

/// The stop time no longer squeezes the input: a 0.05 s run is the first
/// 0.05 s of the 0.15 s run, bit for bit.
#[test]
fn the_input_signal_does_not_depend_on_the_stop_time() {
    let dir = scratch("stop");
    let scene = root().join("scenes/single_crease.fold");
    let (short, long) = (dir.join("short.csv"), dir.join("long.csv"));
    for (t, csv) in [("0.05", &short), ("0.15", &long)] {
        let (r, err) = simulate(&scene, &["--stop-time", t, "-o", csv.to_str().unwrap()]);
        assert!(r.status.success(), "{err}");
        assert!(err.contains("ramps from 0 to 1 over 0.5 s"), "{err}");
    }
    let (a, b) = (rows(&short), rows(&long));
    assert_eq!(a.len(), 6);
    assert_eq!(b.len(), 16);
    assert_eq!(a[..], b[..a.len()]);
    // A ramp of 0.1 s folds further by 0.05 s than the default 0.5 s.
    let fast = dir.join("fast.csv");
    let (r, err) = simulate(
        &scene,
        &[
            "--stop-time",
            "0.05",
            "--ramp",
            "0.1",
            "-o",
            fast.to_str().unwrap(),
        ],
    );
    assert!(r.status.success(), "{err}");
    let angle = |rows: &[Vec<f64>]| rows.last().unwrap()[1..].to_vec();
    let c = rows(&fast);
    assert_ne!(angle(&c), angle(&a));
    let _ = std::fs::remove_dir_all(&dir);
}

/// --gif, --snapshots and --plot write real images without Python; a run
/// without -o writes no CSV and still says what it did.
#[test]
fn pictures_from_the_cli_alone() {
    let dir = scratch("pictures");
    let (gif, png, plot) = (dir.join("f.gif"), dir.join("s.png"), dir.join("p.png"));
    let (r, err) = simulate(
        &root().join("scenes/single_crease.fold"),
        &[
            "--stop-time",
            "0.3",
            "--ramp",
            "0.2",
            "--ramp-shape",
            "smooth",
            "--gif",
            gif.to_str().unwrap(),
            "--snapshots",
            png.to_str().unwrap(),
            "--plot",
            plot.to_str().unwrap(),
        ],
    );
    assert!(r.status.success(), "{err}");
    assert!(err.contains("(smooth)"), "{err}");
    assert!(err.contains("animation: 31 frames"), "{err}");
    assert!(err.contains("snapshots: 6 views"), "{err}");
    let gif = std::fs::read(&gif).unwrap();
    assert_eq!(&gif[..6], b"GIF89a");
    assert!(gif.len() > 10_000, "{} bytes", gif.len());
    for p in [&png, &plot] {
        let bytes = std::fs::read(p).unwrap();
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
        assert!(
            bytes.len() > 10_000,
            "{}: {} bytes",
            p.display(),
            bytes.len()
        );
    }
    // No progress bar off a terminal: stderr holds only the report lines.
    assert!(!err.contains("elapsed"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A step the solver cannot finish ends the run with an error that says
/// where it stopped; the outputs up to there are written.
#[test]
fn a_failed_step_is_reported_with_where_the_run_stopped() {
    let dir = scratch("fail");
    let mut fold: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(root().join("scenes/single_crease.fold")).unwrap(),
    )
    .unwrap();
    fold["ancf:solver"] = serde_json::json!({"max_internal_steps": 1, "max_step": 1e-4});
    let scene = dir.join("tight.fold");
    std::fs::write(&scene, fold.to_string()).unwrap();
    let csv = dir.join("out.csv");
    let (r, err) = simulate(&scene, &["--stop-time", "0.1", "-o", csv.to_str().unwrap()]);
    assert!(!r.status.success());
    assert!(err.contains("the run stopped at t = 0 of 0.1 s"), "{err}");
    assert!(err.contains("solver.max_internal_steps"), "{err}");
    assert_eq!(rows(&csv).len(), 1);
    let _ = std::fs::remove_dir_all(&dir);
}
