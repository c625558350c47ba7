//! `origami-fmu build SCENE -o X.fmu`: pack a scene as an FMI 2.0
//! co-simulation FMU.
//!
//! The FMU holds `modelDescription.xml` (generated from the scene),
//! `binaries/linux64/origami_fmu.so` (a copy of this crate's cdylib, found
//! next to the running executable unless `--library` names it) and the
//! scene in `resources/`.

use super::{CliError, SceneOptions, out};
use crate::fmi::{self, MODEL_IDENTIFIER, SCENE_FILE};
use std::fmt::Write as _;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Arguments of `origami-fmu build`.
#[derive(clap::Args, Debug)]
pub struct BuildArgs {
    /// The scene: a FOLD file (.fold, optionally with ancf: physics keys; docs/scenes.md) or a
    /// scene JSON (.json, as an FMU's resources/scene.json holds it).
    pub scene: PathBuf,
    /// Where to write the FMU.
    #[arg(short, long)]
    pub output: PathBuf,
    /// The shared library to pack (default: liborigami_fmu.so next to this
    /// executable, as cargo builds it).
    #[arg(long)]
    pub library: Option<PathBuf>,
    /// Start value of the parameter ramp.time: the FMU folds by itself, every rest-angle
    /// actuator going from 0 to 1 over SECONDS, in tools that drive no input [default: 0,
    /// off: the master drives the inputs].
    #[arg(long, value_name = "SECONDS")]
    pub ramp: Option<f64>,
    /// How a FOLD scene is read (--frame, --size, --unit, --f-edges).
    #[command(flatten)]
    pub read: SceneOptions,
}

/// The platform folder of the binary inside the FMU.
const PLATFORM: &str = "linux64";

/// The cdylib next to the running executable: `target/<profile>/` after
/// `cargo build`, or `target/<profile>/deps/` where `cargo test` leaves it;
/// the newer of the two when both exist.
fn default_library() -> Result<PathBuf, CliError> {
    let exe = std::env::current_exe().map_err(CliError::Executable)?;
    let dir = exe.parent().ok_or(CliError::NoExecutableFolder)?;
    let name = format!("lib{MODEL_IDENTIFIER}.so");
    let modified = |p: &Path| std::fs::metadata(p).and_then(|m| m.modified()).ok();
    // max_by_key keeps the last of equals: prefer target/<profile>/ on a tie.
    [dir.join("deps").join(&name), dir.join(&name)]
        .into_iter()
        .filter_map(|p| modified(&p).map(|t| (t, p)))
        .max_by_key(|(t, _)| *t)
        .map(|(_, p)| p)
        .ok_or_else(|| CliError::LibraryMissing(dir.join(&name)))
}

/// Run `origami-fmu build`.
pub fn run(args: &BuildArgs) -> Result<(), CliError> {
    let loaded = super::load_scene(&args.scene, &args.read)?;
    let mut scene = loaded.scene;
    if let Some(t) = args.ramp {
        crate::scene::limits::check("ramp.time", t).map_err(|source| CliError::Limit {
            option: "--ramp",
            source,
        })?;
        scene.ramp.time = t;
    }
    let contents = fmi::fmu_contents(&scene)?;
    let library = match &args.library {
        Some(l) => l.clone(),
        None => default_library()?,
    };
    let so = std::fs::read(&library).map_err(super::error::io("read the FMU library", &library))?;
    let binary = format!("binaries/{PLATFORM}/{MODEL_IDENTIFIER}.so");
    let resource = format!("resources/{SCENE_FILE}");
    // A FOLD source travels along as resources/scene.fold, for the user and
    // other FOLD tools; the FMU itself loads the validated scene JSON.
    let fold_source = if args.scene.extension().is_some_and(|e| e == "json") {
        None
    } else {
        Some(std::fs::read(&args.scene).map_err(super::error::io("read", &args.scene))?)
    };
    let mut files: Vec<(&str, &[u8], u32)> = vec![
        (
            "modelDescription.xml",
            contents.model_description.as_bytes(),
            0o644,
        ),
        (&binary, &so, 0o755),
        (&resource, &contents.scene_file, 0o644),
    ];
    if let Some(f) = &fold_source {
        files.push(("resources/scene.fold", f, 0o644));
    }
    write_zip(&args.output, &files)?;
    let mut o = String::new();
    let _ = writeln!(
        o,
        "built {}: scene {:?}, FMI 2.0 co-simulation, modelIdentifier {MODEL_IDENTIFIER}, guid {}",
        args.output.display(),
        contents.scene.name,
        contents.guid
    );
    for n in &loaded.notes {
        let _ = writeln!(o, "  {n}");
    }
    let [np, ni, no] = contents.counts;
    let _ = writeln!(o, "  variables: {np} parameters, {ni} inputs, {no} outputs");
    let _ = writeln!(
        o,
        "  modelDescription.xml ({} bytes)",
        contents.model_description.len()
    );
    let _ = writeln!(
        o,
        "  {binary} ({} bytes, from {})",
        so.len(),
        library.display()
    );
    let _ = writeln!(o, "  {resource} ({} bytes)", contents.scene_file.len());
    o.push_str(&drive_note(&contents.scene));
    out(&o);
    Ok(())
}

/// What a user must drive for the sheet to move, in `build`'s report.
fn drive_note(scene: &crate::scene::Scene) -> String {
    use crate::scene::ActuatorMode;
    let mut o = String::new();
    let rest: Vec<&str> = scene
        .actuators
        .iter()
        .filter(|a| a.mode == ActuatorMode::RestAngle)
        .map(|a| a.name.as_str())
        .collect();
    let torque: Vec<&str> = scene
        .actuators
        .iter()
        .filter(|a| a.mode == ActuatorMode::Torque)
        .map(|a| a.name.as_str())
        .collect();
    if !rest.is_empty() {
        if scene.ramp.is_on() {
            let _ = writeln!(
                o,
                "  folds by itself: {} go from 0 to 1 over {} s (parameter ramp.time; 0 hands them to the master)",
                rest.join(", "),
                scene.ramp.time
            );
        } else {
            let _ = writeln!(
                o,
                "  drive the input {} from 0 (flat) to 1 (the pattern's fold angles): it starts at 0, so \
                 until a master drives it the sheet stays flat; or set the parameter ramp.time \
                 (e.g. 0.5 s) to fold without a signal",
                rest.join(", ")
            );
        }
    }
    if !torque.is_empty() {
        let _ = writeln!(
            o,
            "  crease moment inputs (N, per unit crease length): {}",
            torque.join(", ")
        );
    }
    o
}

fn write_zip(path: &Path, files: &[(&str, &[u8], u32)]) -> Result<(), CliError> {
    use zip::write::SimpleFileOptions;
    let zip_err = |source| CliError::Zip {
        path: path.to_path_buf(),
        source,
    };
    let file = std::fs::File::create(path).map_err(super::error::io("write", path))?;
    let mut zip = zip::ZipWriter::new(file);
    for (name, bytes, mode) in files {
        let options = SimpleFileOptions::default()
            .compression_method(zip::CompressionMethod::Deflated)
            .last_modified_time(zip::DateTime::default())
            .unix_permissions(*mode);
        zip.start_file(*name, options).map_err(zip_err)?;
        zip.write_all(bytes)
            .map_err(super::error::io("write", path))?;
    }
    zip.finish().map_err(zip_err)?;
    Ok(())
}
