//! `origami-fmu build`: the FMU it writes holds exactly the three files,
//! with the checked-in modelDescription.xml and the scene bytes; a bad
//! scene is refused with a message and a non-zero exit.

use std::io::Read;
use std::path::Path;
use std::process::Command;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn build_writes_the_fmu() {
    let out = std::env::temp_dir().join(format!("origami_fmu_cli_{}.fmu", std::process::id()));
    let scene = root().join("tests/fmpy/scenes/square.json");
    let r = Command::new(env!("CARGO_BIN_EXE_origami-fmu"))
        .arg("build")
        .arg(&scene)
        .arg("-o")
        .arg(&out)
        .args(["--platforms", "linux64"])
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let stdout = String::from_utf8_lossy(&r.stdout);
    assert!(stdout.contains("built") && stdout.contains("binaries/linux64/origami_fmu.so"));

    let mut zip = zip::ZipArchive::new(std::fs::File::open(&out).unwrap()).unwrap();
    let mut names: Vec<String> = (0..zip.len())
        .map(|i| zip.by_index(i).unwrap().name().unwrap().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        [
            "binaries/linux64/origami_fmu.so",
            "modelDescription.xml",
            "resources/scene.json"
        ]
    );
    let mut read = |name: &str| {
        let mut v = Vec::new();
        zip.by_name(name).unwrap().read_to_end(&mut v).unwrap();
        v
    };
    assert_eq!(
        read("modelDescription.xml"),
        std::fs::read(root().join("modelDescription/square.xml")).unwrap()
    );
    assert_eq!(read("resources/scene.json"), std::fs::read(&scene).unwrap());
    assert!(read("binaries/linux64/origami_fmu.so").starts_with(b"\x7fELF"));
    std::fs::remove_file(&out).unwrap();
}

#[test]
fn build_refuses_a_bad_scene() {
    let dir = std::env::temp_dir().join(format!("origami_fmu_cli_bad_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("bad.json");
    let good = std::fs::read_to_string(root().join("tests/fmpy/scenes/square.json")).unwrap();
    std::fs::write(
        &scene,
        good.replacen("\"density\": 800.0", "\"density\": -1.0", 1),
    )
    .unwrap();
    let out = dir.join("bad.fmu");
    let r = Command::new(env!("CARGO_BIN_EXE_origami-fmu"))
        .arg("build")
        .arg(&scene)
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    assert!(!r.status.success());
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.contains("material.density") && err.contains("positive"),
        "{err}"
    );
    assert!(!out.exists());
}

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_origami-fmu"))
}

/// A scratch directory for one test.
fn scratch(tag: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("origami_fmu_cli_{tag}_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The FOLD specification's flat-folded diagonal on top, its crease
/// pattern in file_frames[0].
fn two_frame_file(dir: &Path) -> std::path::PathBuf {
    let read = |n: &str| -> serde_json::Value {
        serde_json::from_str(
            &std::fs::read_to_string(root().join("tests/data/fold-spec").join(n)).unwrap(),
        )
        .unwrap()
    };
    let mut top = read("diagonal-folded.fold");
    top["file_frames"] = serde_json::json!([read("diagonal-cp.fold")]);
    let path = dir.join("two_frames.fold");
    std::fs::write(&path, top.to_string()).unwrap();
    path
}

#[test]
fn every_scene_command_takes_frame_size_unit_and_f_edges() {
    let dir = scratch("frame");
    let file = two_frame_file(&dir);
    // Without --frame: refused, naming the frame that is a crease pattern.
    for cmd in ["check", "build", "simulate"] {
        let mut c = bin();
        c.arg(cmd).arg(&file);
        if cmd != "check" {
            c.arg("-o").arg(dir.join("x.out"));
        }
        let r = c.output().unwrap();
        assert!(!r.status.success(), "{cmd}");
        let err = String::from_utf8_lossy(&r.stderr);
        assert!(
            err.contains("--frame 1") && err.contains("folded state"),
            "{cmd}: {err}"
        );
    }
    // With it: check, build and simulate read frame 1; --size scales it.
    let r = bin()
        .args(["check", "--frame", "1", "--size", "0.2"])
        .arg(&file)
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let text = String::from_utf8_lossy(&r.stdout);
    assert!(
        text.contains("size:      0.2 m x 0.2 m: --size 0.2"),
        "{text}"
    );
    let fmu = dir.join("d.fmu");
    let r = bin()
        .args(["build", "--frame", "1", "--unit", "cm"])
        .arg(&file)
        .arg("-o")
        .arg(&fmu)
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let text = String::from_utf8_lossy(&r.stdout);
    assert!(text.contains("size: 0.01 m x 0.01 m: --unit cm"), "{text}");
    assert!(fmu.exists());
    let csv = dir.join("d.csv");
    let r = bin()
        .args([
            "simulate",
            "--frame",
            "1",
            "--stop-time",
            "0.02",
            "--f-edges",
            "smooth",
        ])
        .arg(&file)
        .arg("-o")
        .arg(&csv)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(r.status.success(), "{err}");
    assert!(
        err.contains("s of CPU (") && err.contains("s wall)"),
        "{err}"
    );
    assert!(err.contains("size: 0.1 m x 0.1 m"), "{err}");
    // --size and --unit exclude each other; options on a scene JSON are refused.
    let r = bin()
        .args(["check", "--size", "0.1", "--unit", "mm"])
        .arg(&file)
        .output()
        .unwrap();
    assert!(!r.status.success());
    let r = bin()
        .args(["check", "--size", "0.1"])
        .arg(root().join("tests/fmpy/scenes/square.json"))
        .output()
        .unwrap();
    assert!(!r.status.success());
    assert!(String::from_utf8_lossy(&r.stderr).contains("apply to FOLD files"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// `origami-fmu build OPTIONS FILE -o FMU` (it must succeed), and the scene
/// the FMU carries in its resources.
fn built_scene(options: &[&str], file: &Path, fmu: &Path) -> origami_fmu::scene::Scene {
    let r = bin()
        .arg("build")
        .args(options)
        .arg(file)
        .arg("-o")
        .arg(fmu)
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let mut zip = zip::ZipArchive::new(std::fs::File::open(fmu).unwrap()).unwrap();
    let mut json = String::new();
    zip.by_name("resources/scene.json")
        .unwrap()
        .read_to_string(&mut json)
        .unwrap();
    serde_json::from_str(&json).unwrap()
}

/// `--contact` turns self-contact on in check, build and simulate, and
/// `--friction` sets its coefficient; check lists contact and its outputs.
#[test]
fn every_scene_command_takes_contact_and_friction() {
    let dir = scratch("contact");
    let file = root().join("scenes/single_crease.fold");
    let check = |extra: &[&str]| {
        let r = bin().arg("check").args(extra).arg(&file).output().unwrap();
        (
            r.status.success(),
            String::from_utf8_lossy(&r.stdout).into_owned(),
            String::from_utf8_lossy(&r.stderr).into_owned(),
        )
    };
    let (ok, text, _) = check(&[]);
    assert!(
        ok && text.contains("contact:   off (--contact turns it on)"),
        "{text}"
    );
    let (ok, text, err) = check(&["--contact", "--friction", "0.45"]);
    assert!(ok, "{err}");
    assert!(
        text.contains("contact:   on") && text.contains("friction 0.45"),
        "{text}"
    );
    assert!(
        text.contains("contact: contact.min_gap, contact.pairs, contact.normal_force"),
        "{text}"
    );
    // Friction without contact, or a bad coefficient: refused with the reason.
    let (ok, _, err) = check(&["--friction", "0.45"]);
    assert!(!ok && err.contains("add --contact"), "{err}");
    let (ok, _, err) = check(&["--contact", "--friction=-1"]);
    assert!(!ok && err.contains("--friction -1"), "{err}");
    // build: the scene in the FMU has contact with that friction.
    let scene = built_scene(
        &["--contact", "--friction", "0.45"],
        &file,
        &dir.join("c.fmu"),
    );
    assert_eq!(scene.contact.map(|c| c.friction), Some(0.45));
    // simulate: the CSV has the contact outputs.
    let csv = dir.join("c.csv");
    let r = bin()
        .args(["simulate", "--contact", "--stop-time", "0.02"])
        .arg(&file)
        .arg("-o")
        .arg(&csv)
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let head = std::fs::read_to_string(&csv).unwrap();
    assert!(head.lines().next().unwrap().contains("contact.min_gap"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--contact` on a FOLD file whose `ancf:contact` is written but not
/// enabled takes the file's settings (as docs/scenes.md says), not the
/// defaults; `--friction` still overrides the file's.
#[test]
fn contact_option_takes_the_files_settings() {
    let dir = scratch("contact-settings");
    let text = std::fs::read_to_string(root().join("scenes/single_crease.fold")).unwrap();
    let mut fold: serde_json::Value = serde_json::from_str(&text).unwrap();
    fold["ancf:contact"] =
        serde_json::json!({"thickness": 2e-5, "friction": 0.1, "subdivisions": 4});
    let file = dir.join("off.fold");
    std::fs::write(&file, fold.to_string()).unwrap();
    let check = |extra: &[&str]| {
        let r = bin().arg("check").args(extra).arg(&file).output().unwrap();
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
        String::from_utf8_lossy(&r.stdout).into_owned()
    };
    let text = check(&[]);
    assert!(
        text.contains("contact:   off (--contact turns it on)"),
        "{text}"
    );
    let text = check(&["--contact"]);
    assert!(
        text.contains("contact:   on, thickness 2e-5 m")
            && text.contains("friction 0.1,")
            && text.contains("4 subdivisions"),
        "{text}"
    );
    let text = check(&["--contact", "--friction", "0.45"]);
    assert!(
        text.contains("thickness 2e-5 m") && text.contains("friction 0.45"),
        "{text}"
    );
    // `--subdivisions` overrides the file's sampling and keeps the rest.
    let text = check(&["--contact", "--subdivisions", "1"]);
    assert!(
        text.contains("thickness 2e-5 m")
            && text.contains("friction 0.1,")
            && text.contains("1 subdivisions"),
        "{text}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--subdivisions N` sets contact's samples per facet side in check, build
/// and simulate; without contact, or outside 1..=8, it is refused with the
/// reason.
#[test]
fn subdivisions_set_contacts_sampling() {
    let dir = scratch("subdivisions");
    let file = root().join("scenes/single_crease.fold");
    let run = |extra: &[&str]| {
        let r = bin().args(extra).arg(&file).output().unwrap();
        (
            r.status.success(),
            String::from_utf8_lossy(&r.stdout).into_owned(),
            String::from_utf8_lossy(&r.stderr).into_owned(),
        )
    };
    let (ok, text, err) = run(&["check", "--contact", "--subdivisions", "1"]);
    assert!(
        ok && text.contains("1 subdivisions per facet side"),
        "{err}{text}"
    );
    let (ok, _, err) = run(&["check", "--subdivisions", "2"]);
    assert!(
        !ok && err.contains("--subdivisions") && err.contains("add --contact"),
        "{err}"
    );
    for bad in ["0", "9", "two"] {
        let (ok, _, err) = run(&["check", "--contact", "--subdivisions", bad]);
        assert!(!ok && err.contains("--subdivisions"), "{bad}: {err}");
    }
    let scene = built_scene(
        &["--contact", "--subdivisions", "2"],
        &file,
        &dir.join("s.fmu"),
    );
    assert_eq!(scene.contact.map(|c| c.subdivisions), Some(2));
    let csv = dir.join("s.csv");
    let r = bin()
        .args([
            "simulate",
            "--contact",
            "--subdivisions",
            "1",
            "--stop-time",
            "0.02",
        ])
        .arg(&file)
        .arg("-o")
        .arg(&csv)
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn help_says_what_is_true() {
    let r = bin().args(["build", "--help"]).output().unwrap();
    let text = String::from_utf8_lossy(&r.stdout);
    assert!(
        text.contains("a FOLD file") && !text.contains("for now: JSON"),
        "{text}"
    );
    for cmd in ["check", "build", "simulate"] {
        let r = bin().args([cmd, "--help"]).output().unwrap();
        let text = String::from_utf8_lossy(&r.stdout);
        for opt in ["--frame", "--size", "--unit", "--f-edges"] {
            assert!(text.contains(opt), "{cmd} --help lacks {opt}:\n{text}");
        }
    }
}

#[test]
fn a_closed_pipe_ends_output_quietly() {
    use std::process::Stdio;
    // More output than a pipe holds, and a reader that leaves after one line.
    for args in [
        &["pattern", "miura", "--nx", "40", "--ny", "40"][..],
        &["check", "tests/data/fold-spec/cube-cp.fold"][..],
    ] {
        let mut child = bin()
            .args(args)
            .current_dir(root())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let mut out = child.stdout.take().unwrap();
        let mut first = [0u8; 1];
        let _ = out.read(&mut first);
        drop(out);
        let r = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&r.stderr);
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        assert!(r.status.success(), "{args:?}: {:?} {err}", r.status);
    }
}

/// A run that would write more rows than the CLI allows is refused before
/// anything is built (a step of 1e-300 s ran for ever).
#[test]
fn simulate_refuses_more_steps_than_it_can_write() {
    let dir = scratch("steps");
    let out = dir.join("x.csv");
    let r = bin()
        .args([
            "simulate",
            "scenes/single_crease.fold",
            "--step",
            "1e-300",
            "-o",
        ])
        .arg(&out)
        .current_dir(root())
        .output()
        .unwrap();
    assert!(!r.status.success());
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.contains("communication steps; at most 10000000"),
        "{err}"
    );
    assert!(!err.contains("000000000000"), "short numbers: {err}");
    assert!(!out.exists());
}

/// `check` names each obstacle's wrench outputs and, for a moving one, its
/// pose inputs (the input list has them too).
#[test]
fn check_lists_obstacles_and_a_moving_ones_pose_inputs() {
    let dir = scratch("obstacles");
    let mut fold: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(root().join("scenes/miura_on_ground.fold")).unwrap(),
    )
    .unwrap();
    let check = |path: &Path| {
        let r = bin().arg("check").arg(path).output().unwrap();
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
        String::from_utf8_lossy(&r.stdout).into_owned()
    };
    let text = check(&root().join("scenes/miura_on_ground.fold"));
    assert!(
        text.contains("obstacles (1): wrench outputs ground.force/moment\n"),
        "{text}"
    );
    fold["ancf:obstacles"][0]["moving"] = serde_json::json!(true);
    let path = dir.join("moving.fold");
    std::fs::write(&path, fold.to_string()).unwrap();
    let text = check(&path);
    assert!(
        text.contains(
            "obstacles (1): wrench outputs ground.force/moment (moving: pose inputs \
             ground.x/y/z, ground.rx/ry/rz)"
        ) && text.contains("inputs (7): fold, ground.x, ground.y, ground.z, ground.rx"),
        "{text}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The binary names of the FMU at `path`, sorted.
fn fmu_binaries(path: &Path) -> Vec<String> {
    let mut zip = zip::ZipArchive::new(std::fs::File::open(path).unwrap()).unwrap();
    let mut names: Vec<String> = (0..zip.len())
        .map(|i| zip.by_index(i).unwrap().name().unwrap().into_owned())
        .filter(|n| n.starts_with("binaries/"))
        .collect();
    names.sort();
    names
}

/// The cdylib cargo built with the executable (target/release/ or, under
/// `cargo test`, its deps/).
fn host_library() -> std::path::PathBuf {
    let dir = Path::new(env!("CARGO_BIN_EXE_origami-fmu"))
        .parent()
        .unwrap();
    [
        dir.join("liborigami_fmu.so"),
        dir.join("deps/liborigami_fmu.so"),
    ]
    .into_iter()
    .find(|p| p.is_file())
    .expect("the cdylib is built with the executable")
}

/// Without --platforms, build packs this host's library plus the win64 DLL
/// when one was cross-built (where cargo leaves it).
#[test]
fn build_packs_the_host_and_what_was_cross_built() {
    let dir = scratch("default_platforms");
    let fmu = dir.join("sq.fmu");
    let r = bin()
        .arg("build")
        .arg(root().join("tests/fmpy/scenes/square.json"))
        .arg("-o")
        .arg(&fmu)
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let target = Path::new(env!("CARGO_BIN_EXE_origami-fmu"))
        .parent()
        .unwrap()
        .parent()
        .unwrap();
    let cross_built = ["x86_64-win7-windows-gnu", "x86_64-pc-windows-gnu"]
        .iter()
        .any(|t| target.join(t).join("release/origami_fmu.dll").is_file());
    let mut expected = vec!["binaries/linux64/origami_fmu.so"];
    if cross_built {
        expected.push("binaries/win64/origami_fmu.dll");
    }
    assert_eq!(fmu_binaries(&fmu), expected);
}

/// --library files go in the folder their format names; a platform that
/// cannot be had, an unknown platform or a file that is no library is
/// refused with what is wrong, and no FMU is written.
#[test]
fn build_places_libraries_by_platform() {
    let dir = scratch("platforms");
    let scene = root().join("tests/fmpy/scenes/square.json");
    let fmu = dir.join("p.fmu");
    let so = host_library();
    // A PE32+ image (as far as its headers go) stands for a win64 DLL.
    let mut pe = vec![0u8; 0x200];
    pe[..2].copy_from_slice(b"MZ");
    pe[0x3c] = 0x80;
    pe[0x80..0x84].copy_from_slice(b"PE\0\0");
    pe[0x80 + 24..0x80 + 26].copy_from_slice(&[0x0b, 0x02]);
    let dll = dir.join("some.dll");
    std::fs::write(&dll, &pe).unwrap();
    let build = |extra: &[&std::ffi::OsStr]| {
        let _ = std::fs::remove_file(&fmu);
        bin()
            .arg("build")
            .arg(&scene)
            .arg("-o")
            .arg(&fmu)
            .args(extra)
            .output()
            .unwrap()
    };
    let os = |s: &'static str| std::ffi::OsStr::new(s);
    let r = build(&[
        os("--library"),
        dll.as_os_str(),
        os("--library"),
        so.as_os_str(),
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert_eq!(
        fmu_binaries(&fmu),
        [
            "binaries/linux64/origami_fmu.so",
            "binaries/win64/origami_fmu.dll"
        ]
    );
    let out = String::from_utf8_lossy(&r.stdout);
    assert!(
        out.contains(&format!(
            "binaries/win64/origami_fmu.dll (512 bytes, from {})",
            dll.display()
        )),
        "{out}"
    );
    let r = build(&[
        os("--library"),
        dll.as_os_str(),
        os("--platforms"),
        os("win64"),
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert_eq!(fmu_binaries(&fmu), ["binaries/win64/origami_fmu.dll"]);

    let refused = |extra: &[&std::ffi::OsStr], wanted: &[&str]| {
        let r = build(extra);
        let err = String::from_utf8_lossy(&r.stderr);
        assert!(!r.status.success(), "{extra:?}");
        for w in wanted {
            assert!(err.contains(w), "{extra:?}: {err}");
        }
        assert!(!fmu.exists(), "{extra:?}");
    };
    refused(
        &[os("--platforms"), os("darwin64")],
        &["--platforms darwin64", "on a Mac", "README", "--library"],
    );
    refused(
        &[os("--platforms"), os("linux64,win32")],
        &["win32", "linux64, win64, darwin64"],
    );
    refused(
        &[os("--library"), scene.as_os_str()],
        &["square.json is not a 64-bit shared library"],
    );
    refused(
        &[
            os("--library"),
            so.as_os_str(),
            os("--platforms"),
            os("win64"),
        ],
        &["is a linux64 library but --platforms does not list linux64"],
    );
    refused(
        &[
            os("--library"),
            dll.as_os_str(),
            os("--library"),
            dll.as_os_str(),
        ],
        &["two --library files are win64 libraries"],
    );
}
