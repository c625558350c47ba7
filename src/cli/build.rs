//! `origami-fmu build SCENE -o X.fmu`: pack a scene as an FMI 2.0
//! co-simulation FMU.
//!
//! The FMU holds `modelDescription.xml` (generated from the scene), one
//! binary per platform, `binaries/<platform>/origami_fmu.<so|dll|dylib>`
//! (copies of this crate's cdylib; see [`super::platforms`] for where they
//! are found and how they are built), and the scene in `resources/`.

use super::platforms::{BuildTree, Platform};
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
    /// Platforms to pack, comma-separated: linux64, win64, darwin64. A named platform's binary
    /// is built through cargo when missing; a cross-built one (win64 on Linux) is brought up
    /// to date when its toolchain is installed [default: this host's platform plus every
    /// cross-built binary found, e.g. target/x86_64-win7-windows-gnu/release/origami_fmu.dll].
    #[arg(long, value_delimiter = ',', value_name = "LIST")]
    pub platforms: Vec<Platform>,
    /// A shared library to pack (repeatable), in the platform folder its format names: ELF
    /// linux64, PE32+ win64, Mach-O darwin64 [default: this crate's, as cargo builds it next
    /// to this executable].
    #[arg(long, value_name = "FILE")]
    pub library: Vec<PathBuf>,
    /// Start value of the parameter ramp.time: the FMU folds by itself, every rest-angle
    /// actuator going from 0 to 1 over SECONDS, in tools that drive no input [default: 0,
    /// off: the master drives the inputs].
    #[arg(long, value_name = "SECONDS")]
    pub ramp: Option<f64>,
    /// How a FOLD scene is read (--frame, --size, --unit, --f-edges).
    #[command(flatten)]
    pub read: SceneOptions,
}

/// One platform's binary, read.
struct Binary {
    platform: Platform,
    source: PathBuf,
    bytes: Vec<u8>,
}

/// Read `path` as the binary of `platform`, refusing a file of another format.
fn read_binary(platform: Platform, path: PathBuf) -> Result<Binary, CliError> {
    let bytes = std::fs::read(&path).map_err(super::error::io("read the FMU library", &path))?;
    match Platform::of_binary(&bytes) {
        Some(p) if p == platform => Ok(Binary {
            platform,
            source: path,
            bytes,
        }),
        found => Err(CliError::WrongBinary {
            path,
            platform,
            found,
        }),
    }
}

/// The binaries to pack, one per platform, in [`Platform::ALL`]'s order;
/// notes for the report.
fn binaries(args: &BuildArgs, notes: &mut Vec<String>) -> Result<Vec<Binary>, CliError> {
    let mut out: Vec<Binary> = Vec::new();
    for path in &args.library {
        let bytes = std::fs::read(path).map_err(super::error::io("read the FMU library", path))?;
        let platform =
            Platform::of_binary(&bytes).ok_or_else(|| CliError::NotABinary(path.clone()))?;
        if !args.platforms.is_empty() && !args.platforms.contains(&platform) {
            return Err(CliError::LibraryNotListed {
                path: path.clone(),
                platform,
            });
        }
        if out.iter().any(|b| b.platform == platform) {
            return Err(CliError::TwoLibraries(platform));
        }
        out.push(Binary {
            platform,
            source: path.clone(),
            bytes,
        });
    }
    if args.platforms.is_empty() && !args.library.is_empty() {
        return Ok(sorted(out));
    }
    let tree = BuildTree::of_executable()?;
    if args.platforms.is_empty() {
        let host = Platform::host().ok_or(CliError::NoHostPlatform)?;
        let path = tree
            .find(host)
            .ok_or_else(|| CliError::LibraryMissing(tree.exe_dir.join(host.cargo_file())))?;
        let host_time = modified(&path);
        out.push(read_binary(host, path)?);
        for p in Platform::ALL.into_iter().filter(|&p| p != host) {
            if let Some(path) = tree.find(p) {
                if modified(&path) < host_time {
                    notes.push(format!(
                        "{p}: {} is older than the {host} library; `--platforms {host},{p}` \
                         rebuilds it",
                        path.display()
                    ));
                }
                out.push(read_binary(p, path)?);
            }
        }
        return Ok(sorted(out));
    }
    for &p in &args.platforms {
        if !out.iter().any(|b| b.platform == p) {
            let path = named_binary(&tree, p)?;
            out.push(read_binary(p, path)?);
        }
    }
    Ok(sorted(out))
}

fn sorted(mut binaries: Vec<Binary>) -> Vec<Binary> {
    binaries.sort_by_key(|b| b.platform);
    binaries
}

fn modified(path: &Path) -> Option<std::time::SystemTime> {
    std::fs::metadata(path).and_then(|m| m.modified()).ok()
}

/// The binary of a platform named in `--platforms`: the host's as found
/// (built when missing); a cross-built one built through cargo (up to date
/// in seconds when nothing changed) when its toolchain is installed, else
/// as found; else the error that says what to install.
fn named_binary(tree: &BuildTree, platform: Platform) -> Result<PathBuf, CliError> {
    let found = tree.find(platform);
    if Some(platform) == Platform::host()
        && let Some(path) = found
    {
        return Ok(path);
    }
    let mut cargo = match tree.build_command(platform) {
        Ok(c) => c,
        Err(why) => return found.ok_or(CliError::PlatformUnavailable { platform, why }),
    };
    super::err(&format!("{platform}: building the binary: {cargo:?}\n"));
    let status = cargo.status().map_err(|e| CliError::PlatformBuild {
        platform,
        why: e.to_string(),
    })?;
    if !status.success() {
        return Err(CliError::PlatformBuild {
            platform,
            why: format!("cargo {status}; its messages are above"),
        });
    }
    tree.find(platform).ok_or_else(|| CliError::PlatformBuild {
        platform,
        why: format!(
            "cargo succeeded but left none of {:?}",
            tree.candidates(platform)
        ),
    })
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
    let mut notes = Vec::new();
    let binaries = binaries(args, &mut notes)?;
    let paths: Vec<String> = binaries.iter().map(|b| b.platform.fmu_path()).collect();
    let resource = format!("resources/{SCENE_FILE}");
    // A FOLD source travels along as resources/scene.fold, for the user and
    // other FOLD tools; the FMU itself loads the validated scene JSON.
    let fold_source = if args.scene.extension().is_some_and(|e| e == "json") {
        None
    } else {
        Some(std::fs::read(&args.scene).map_err(super::error::io("read", &args.scene))?)
    };
    let mut files: Vec<(&str, &[u8], u32)> = vec![(
        "modelDescription.xml",
        contents.model_description.as_bytes(),
        0o644,
    )];
    for (b, path) in binaries.iter().zip(&paths) {
        files.push((path, &b.bytes, 0o755));
    }
    files.push((&resource, &contents.scene_file, 0o644));
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
    for (b, path) in binaries.iter().zip(&paths) {
        let _ = writeln!(
            o,
            "  {path} ({} bytes, from {})",
            b.bytes.len(),
            b.source.display()
        );
    }
    for n in &notes {
        let _ = writeln!(o, "  note: {n}");
    }
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
