//! Command-line interface. Each subcommand lives in its own file and
//! returns `Result<(), CliError>`; errors print to stderr with a non-zero exit.
//! Output goes through [`out`] and [`err`], which stop quietly when the
//! reader has gone (`origami-fmu build ... | head`) instead of panicking.

pub mod build;
pub mod check;
mod error;
pub mod pattern;
pub mod platforms;
pub mod simulate;

pub use error::{CliError, InputCsvError};

use crate::scene::{self, FlatEdges, LoadOptions, Loaded};
use clap::{Parser, Subcommand, ValueEnum};
use std::path::Path;
use std::process::ExitCode;

/// origami-fmu: origami folding dynamics (iso-ANCF shells) as FMI 2.0 co-simulation FMUs.
#[derive(Parser, Debug)]
#[command(name = "origami-fmu", version, about)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Write a generated crease pattern (Miura-ori, Kresling, ...) as a FOLD file.
    Pattern(pattern::PatternArgs),
    /// Validate a FOLD scene and print its mesh, variables and warnings.
    Check(check::CheckArgs),
    /// Build an FMI 2.0 co-simulation FMU of a scene.
    Build(build::BuildArgs),
    /// Simulate a scene with the built-in model and write outputs to CSV.
    Simulate(simulate::SimulateArgs),
}

/// Write to standard output. A closed pipe ends the output quietly (the
/// reader has what it wanted); other errors are reported once on stderr.
pub fn out(text: &str) {
    write_to(&mut std::io::stdout().lock(), text, "standard output");
}

/// Write to standard error, like [`out`].
pub fn err(text: &str) {
    write_to(&mut std::io::stderr().lock(), text, "");
}

fn write_to(w: &mut dyn std::io::Write, text: &str, what: &str) {
    use std::sync::atomic::{AtomicBool, Ordering};
    static GONE: AtomicBool = AtomicBool::new(false);
    if GONE.load(Ordering::Relaxed) {
        return;
    }
    if let Err(e) = w.write_all(text.as_bytes()).and_then(|()| w.flush()) {
        GONE.store(true, Ordering::Relaxed);
        if e.kind() != std::io::ErrorKind::BrokenPipe && !what.is_empty() {
            err(&format!("warning: cannot write to {what}: {e}\n"));
        }
    }
}

/// What F edges are, on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum FEdges {
    /// A flat fold line: a crease with target 0 (the FOLD specification).
    Crease,
    /// A triangulation line: a smooth edge (as Origami Simulator writes them).
    Smooth,
}

/// How a FOLD scene is read: the options of every command that reads one.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct SceneOptions {
    /// Frame of a multi-frame FOLD file: an index (0 = top level, k = file_frames[k-1]) or a
    /// frame_title [default: the top level if it has vertices, else frame 1].
    #[arg(long, value_name = "N|TITLE")]
    pub frame: Option<String>,
    /// Scale the sheet so that the longest side of its bounding box is LENGTH metres, whatever
    /// the file's unit [default for files without a physical frame_unit: 0.1].
    #[arg(long, value_name = "LENGTH", conflicts_with = "unit")]
    pub size: Option<f64>,
    /// Read the coordinates in UNIT (m, cm, mm, um, nm, in, pt) instead of the file's frame_unit.
    #[arg(long, value_name = "UNIT")]
    pub unit: Option<String>,
    /// What FOLD F edges are [default: crease; smooth for Origami Simulator exports].
    #[arg(long, value_name = "KIND")]
    pub f_edges: Option<FEdges>,
    /// Turn self-contact on (the layers keep the sheet's thickness apart), with the scene's
    /// `ancf:contact` settings where it has them, else the defaults (docs/scenes.md).
    #[arg(long)]
    pub contact: bool,
    /// Coulomb friction coefficient of the self-contact (>= 0; also the FMU parameter
    /// `contact.friction`) [default: the scene's, else 0.3]. Needs contact on.
    #[arg(long, value_name = "MU")]
    pub friction: Option<f64>,
    /// Samples per facet side of the surface self-contact keeps apart (1..=8) [default: the
    /// scene's, else 3]. 1 samples the corners alone: a stack of flat panels several times
    /// cheaper, curved facets then passing between samples (docs/contact.md). Needs contact on.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u8).range(1..=8))]
    pub subdivisions: Option<u8>,
    /// Read the frames after the crease pattern as keyframes of a folding sequence, one stage
    /// each: auto (when every one carries fold angles or folded coordinates, and the file has
    /// no ancf:sequence), on (an error when they do not), off.
    #[arg(long, value_name = "WHEN", value_enum, default_value_t = KeyframesArg::Auto)]
    pub keyframes: KeyframesArg,
}

/// `--keyframes`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum)]
pub enum KeyframesArg {
    /// When every frame after the crease pattern carries fold angles.
    #[default]
    Auto,
    /// Always (an error when a frame does not carry fold angles).
    On,
    /// Never: the crease pattern alone.
    Off,
}

impl SceneOptions {
    /// Whether an option that only applies to FOLD files is given.
    fn any(&self) -> bool {
        self.frame.is_some()
            || self.size.is_some()
            || self.unit.is_some()
            || self.f_edges.is_some()
            || self.keyframes != KeyframesArg::Auto
    }

    /// Apply `--contact`, `--friction` and `--subdivisions` to a loaded scene.
    pub fn apply(&self, scene: &mut scene::Scene) -> Result<(), CliError> {
        if self.contact && scene.contact.is_none() {
            scene.contact = Some(scene.default_contact());
        }
        if let Some(mu) = self.friction {
            if !(mu.is_finite() && mu >= 0.0) {
                return Err(CliError::Friction(mu));
            }
            match scene.contact.as_mut() {
                Some(c) => c.friction = mu,
                None => return Err(CliError::NeedsContact("--friction", "friction")),
            }
        }
        if let Some(n) = self.subdivisions {
            match scene.contact.as_mut() {
                Some(c) => c.subdivisions = n.into(),
                None => return Err(CliError::NeedsContact("--subdivisions", "sampling")),
            }
        }
        Ok(())
    }

    /// The library's load options.
    pub fn load_options(&self) -> LoadOptions {
        LoadOptions {
            frame: self
                .frame
                .as_deref()
                .map(|f| f.parse().expect("infallible")),
            name: None,
            size: self.size,
            unit: self.unit.clone(),
            f_edges: self.f_edges.map(|f| match f {
                FEdges::Crease => FlatEdges::Crease,
                FEdges::Smooth => FlatEdges::Smooth,
            }),
            contact: self.contact,
            keyframes: match self.keyframes {
                KeyframesArg::Auto => scene::Keyframes::Auto,
                KeyframesArg::On => scene::Keyframes::On,
                KeyframesArg::Off => scene::Keyframes::Off,
            },
        }
    }
}

/// Load a scene file given on the command line: the one place that knows
/// which scene formats the CLI reads. FOLD files (any extension but
/// `.json`) go through the FOLD reader with `options`; `.json` files hold a
/// serialized [`crate::scene::Scene`] (already in metres, so the options do
/// not apply). Warnings are printed; the notes are returned.
pub fn load_scene(path: &Path, options: &SceneOptions) -> Result<Loaded, CliError> {
    if path.extension().is_some_and(|e| e == "json") {
        if options.any() {
            return Err(CliError::FoldOptionsOnJson(path.to_path_buf()));
        }
        let mut scene = crate::fmi::resources::load_scene_file(path)?;
        options.apply(&mut scene)?;
        return Ok(Loaded {
            scene,
            warnings: vec![],
            notes: vec![],
        });
    }
    let mut loaded = read_fold(path, options)?;
    options.apply(&mut loaded.scene)?;
    for w in &loaded.warnings {
        err(&format!("warning: {w}\n"));
    }
    Ok(loaded)
}

/// Read the FOLD scene at `path` with `options` (no `--contact`,
/// `--friction`, `--subdivisions`, no warnings printed).
fn read_fold(path: &Path, options: &SceneOptions) -> Result<Loaded, CliError> {
    scene::load_report(path, &options.load_options()).map_err(|source| CliError::Scene {
        path: path.to_path_buf(),
        source,
    })
}

/// Run the CLI with the process arguments.
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    let result: Result<(), CliError> = match cli.command {
        Command::Pattern(args) => pattern::run(args),
        Command::Check(args) => check::run(args),
        Command::Build(args) => build::run(&args),
        Command::Simulate(args) => simulate::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(msg) => {
            err(&format!("error: {msg}\n"));
            ExitCode::FAILURE
        }
    }
}
