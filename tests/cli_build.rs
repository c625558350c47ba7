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
