//! The error of every CLI command: what the user sees after `error: `.

use crate::fmi::resources::ResourceError;
use crate::paraview::SeriesError;
use crate::pictures::PictureError;
use crate::scene::SceneError;
use crate::scene::limits::LimitError;
use std::path::PathBuf;

/// Why a command failed. The [`std::fmt::Display`] text is the message
/// printed on standard error.
#[derive(Debug)]
pub enum CliError {
    /// A file could not be read or written.
    Io {
        /// What was being done ("read", "write", "read the FMU library").
        action: &'static str,
        /// Where.
        path: PathBuf,
        /// The system's error.
        source: std::io::Error,
    },
    /// The FMU archive could not be written.
    Zip {
        /// The archive.
        path: PathBuf,
        /// The zip writer's error.
        source: zip::result::ZipError,
    },
    /// A FOLD scene could not be read.
    Scene {
        /// The file.
        path: PathBuf,
        /// The reader's error.
        source: SceneError,
    },
    /// A generated crease pattern is refused by its generator.
    Pattern(SceneError),
    /// A generated crease pattern does not load as a scene (a bug).
    PatternDoesNotLoad(SceneError),
    /// A scene JSON (or the FMU's scene resource) is refused.
    Resource(ResourceError),
    /// The scene makes no model, or the model refused a call.
    Model(crate::model::Error),
    /// The scene of `path` makes no model.
    ModelOf {
        /// The scene file, as shown.
        path: String,
        /// The model's error.
        source: crate::model::Error,
    },
    /// An option's value is out of its limits.
    Limit {
        /// The option (`--ramp`).
        option: &'static str,
        /// Why.
        source: LimitError,
    },
    /// `--friction` is negative or not finite.
    Friction(f64),
    /// A contact option (given, and what it sets) without contact.
    NeedsContact(&'static str, &'static str),
    /// FOLD-only options given for a scene JSON.
    FoldOptionsOnJson(PathBuf),
    /// `--step` or `--stop-time` is not a positive number.
    StepOrStopTime,
    /// `--stop-time / --step` gives too many communication steps.
    TooManySteps {
        /// The steps asked for.
        steps: f64,
        /// The most allowed.
        max: usize,
    },
    /// `--ramp` is negative or not finite.
    RampTime,
    /// `--fold-out` (to this file) for a scene that is not a FOLD file.
    FoldOutNeedsFold(PathBuf),
    /// The `--input` table is unusable.
    InputCsv(InputCsvError),
    /// The run stopped before its stop time (what was written stays).
    RunStopped {
        /// Why the step failed.
        source: crate::model::Error,
        /// Time reached.
        reached: f64,
        /// The stop time.
        stop: f64,
    },
    /// A picture could not be written.
    Picture(PictureError),
    /// The ParaView series could not be written.
    Series(SeriesError),
    /// The path of this executable is unknown.
    Executable(std::io::Error),
    /// The executable's path has no parent folder.
    NoExecutableFolder,
    /// The FMU library is not next to the executable.
    LibraryMissing(PathBuf),
    /// This host has no FMI 2.0 platform, so there is no default library.
    NoHostPlatform,
    /// A `--library` file is no 64-bit shared library of an FMI platform.
    NotABinary(PathBuf),
    /// A library's file format is not its platform's.
    WrongBinary {
        /// The file.
        path: PathBuf,
        /// The platform it was to be packed for.
        platform: crate::cli::platforms::Platform,
        /// The platform its format names, if any.
        found: Option<crate::cli::platforms::Platform>,
    },
    /// A `--library` is for a platform that `--platforms` does not list.
    LibraryNotListed {
        /// The file.
        path: PathBuf,
        /// Its platform.
        platform: crate::cli::platforms::Platform,
    },
    /// Two `--library` files for one platform.
    TwoLibraries(crate::cli::platforms::Platform),
    /// A platform named in `--platforms` has no binary and this machine cannot build one.
    PlatformUnavailable {
        /// The platform.
        platform: crate::cli::platforms::Platform,
        /// Why, and what to install or do.
        why: String,
    },
    /// The cargo build of a platform's binary failed.
    PlatformBuild {
        /// The platform.
        platform: crate::cli::platforms::Platform,
        /// How it failed.
        why: String,
    },
}

/// What is wrong with an `--input` CSV (lines are 1-based, the header
/// being line 1; columns are 1-based).
#[derive(Clone, Debug, PartialEq)]
pub enum InputCsvError {
    /// No header.
    Empty,
    /// No `time` column.
    NoTimeColumn,
    /// A column names no input of the scene.
    UnknownColumn(String),
    /// A line lacks a column.
    MissingColumn {
        /// The line.
        line: usize,
        /// The column.
        column: usize,
    },
    /// A value is not a number.
    NotANumber {
        /// The line.
        line: usize,
        /// The column.
        column: usize,
    },
    /// A value is not finite.
    NonFinite {
        /// The line.
        line: usize,
    },
    /// The time does not increase.
    TimeNotIncreasing {
        /// The line.
        line: usize,
    },
    /// A header and no rows.
    NoRows,
}

impl std::fmt::Display for InputCsvError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            InputCsvError::Empty => write!(f, "input CSV is empty"),
            InputCsvError::NoTimeColumn => write!(f, "input CSV has no `time` column"),
            InputCsvError::UnknownColumn(h) => {
                write!(f, "input CSV column `{h}` is not an input of the scene")
            }
            InputCsvError::MissingColumn { line, column } => {
                write!(f, "input CSV line {line}: missing column {column}")
            }
            InputCsvError::NotANumber { line, column } => {
                write!(f, "input CSV line {line}: column {column} is not a number")
            }
            InputCsvError::NonFinite { line } => {
                write!(f, "input CSV line {line}: non-finite value")
            }
            InputCsvError::TimeNotIncreasing { line } => {
                write!(f, "input CSV line {line}: time must increase")
            }
            InputCsvError::NoRows => write!(f, "input CSV has no rows"),
        }
    }
}

impl std::error::Error for InputCsvError {}

impl std::fmt::Display for CliError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CliError::Io {
                action,
                path,
                source,
            } => write!(f, "cannot {action} {}: {source}", path.display()),
            CliError::Zip { path, source } => {
                write!(f, "cannot write {}: {source}", path.display())
            }
            // The reader's I/O message names the file already.
            CliError::Scene {
                source: e @ SceneError::Io { .. },
                ..
            } => write!(f, "{e}"),
            CliError::Scene { path, source } => write!(f, "{}: {source}", path.display()),
            CliError::Pattern(e) => write!(f, "{e}"),
            CliError::PatternDoesNotLoad(e) => write!(
                f,
                "internal error: the generated pattern does not load: {e}"
            ),
            CliError::Resource(e) => write!(f, "{e}"),
            CliError::Model(e) => write!(f, "{e}"),
            CliError::ModelOf { path, source } => write!(f, "{path}: {source}"),
            CliError::Limit { option, source } => write!(f, "{option}: {source}"),
            CliError::Friction(mu) => write!(f, "--friction {mu}: must be a finite number >= 0"),
            CliError::NeedsContact(option, what) => write!(
                f,
                "{option} sets the self-contact's {what}, and contact is off: add \
                 --contact (or \"ancf:contact\": {{\"enabled\": true}} in the scene)"
            ),
            CliError::FoldOptionsOnJson(path) => write!(
                f,
                "{}: --frame, --size, --unit and --f-edges apply to FOLD files; this is a scene \
                 JSON (as written into an FMU's resources), whose geometry is fixed",
                path.display()
            ),
            CliError::StepOrStopTime => {
                write!(f, "--step and --stop-time must be positive numbers")
            }
            CliError::TooManySteps { steps, max } => write!(
                f,
                "--stop-time / --step gives {} communication steps; at most {max} \
                 (one CSV row each): take a longer --step",
                crate::text::num(*steps)
            ),
            CliError::RampTime => {
                write!(f, "--ramp must be zero or a positive number of seconds")
            }
            CliError::FoldOutNeedsFold(out) => write!(
                f,
                "--fold-out {} writes the motion over the scene's FOLD crease pattern; this                  scene is a scene JSON: simulate the FOLD file instead",
                out.display()
            ),
            CliError::InputCsv(e) => write!(f, "{e}"),
            CliError::RunStopped {
                source,
                reached,
                stop,
            } => write!(
                f,
                "{source}; the run stopped at t = {reached} of {stop} s (outputs up to there are written)"
            ),
            CliError::Picture(e) => write!(f, "{e}"),
            CliError::Series(e) => write!(f, "{e}"),
            CliError::Executable(e) => write!(f, "cannot locate this executable: {e}"),
            CliError::NoExecutableFolder => write!(f, "the executable has no parent folder"),
            CliError::LibraryMissing(path) => write!(
                f,
                "the FMU library {} is missing; build it with `cargo build --release` (it is built \
                 with the executable), or name it with --library",
                path.display()
            ),
            CliError::NoHostPlatform => write!(
                f,
                "this machine is none of FMI 2.0's platforms linux64, win64, darwin64, so there is \
                 no default library: name the libraries with --library"
            ),
            CliError::NotABinary(path) => write!(
                f,
                "--library {} is not a 64-bit shared library of linux64 (ELF), win64 (PE32+) or \
                 darwin64 (Mach-O)",
                path.display()
            ),
            CliError::WrongBinary {
                path,
                platform,
                found,
            } => write!(
                f,
                "{} is not a {platform} library (its format is {}), so it cannot be packed as \
                 {}",
                path.display(),
                found.map_or("none of linux64, win64, darwin64".into(), |p| p.to_string()),
                platform.fmu_path()
            ),
            CliError::LibraryNotListed { path, platform } => write!(
                f,
                "--library {} is a {platform} library but --platforms does not list {platform}",
                path.display()
            ),
            CliError::TwoLibraries(p) => write!(f, "two --library files are {p} libraries"),
            CliError::PlatformUnavailable { platform, why } => {
                write!(f, "--platforms {platform}: {why}")
            }
            CliError::PlatformBuild { platform, why } => {
                write!(f, "the build of the {platform} library failed: {why}")
            }
        }
    }
}

impl std::error::Error for CliError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            CliError::Io { source, .. } | CliError::Executable(source) => Some(source),
            CliError::Zip { source, .. } => Some(source),
            CliError::Scene { source, .. }
            | CliError::Pattern(source)
            | CliError::PatternDoesNotLoad(source) => Some(source),
            CliError::Resource(e) => Some(e),
            CliError::Model(source)
            | CliError::ModelOf { source, .. }
            | CliError::RunStopped { source, .. } => Some(source),
            CliError::Limit { source, .. } => Some(source),
            CliError::InputCsv(e) => Some(e),
            CliError::Picture(e) => Some(e),
            CliError::Series(e) => Some(e),
            _ => None,
        }
    }
}

impl From<ResourceError> for CliError {
    fn from(e: ResourceError) -> Self {
        CliError::Resource(e)
    }
}

impl From<crate::model::Error> for CliError {
    fn from(e: crate::model::Error) -> Self {
        CliError::Model(e)
    }
}

impl From<InputCsvError> for CliError {
    fn from(e: InputCsvError) -> Self {
        CliError::InputCsv(e)
    }
}

impl From<PictureError> for CliError {
    fn from(e: PictureError) -> Self {
        CliError::Picture(e)
    }
}

impl From<SeriesError> for CliError {
    fn from(e: SeriesError) -> Self {
        CliError::Series(e)
    }
}

/// The I/O error of `action` on `path`, for `map_err`.
pub(crate) fn io(
    action: &'static str,
    path: &std::path::Path,
) -> impl FnOnce(std::io::Error) -> CliError {
    let path = path.to_path_buf();
    move |source| CliError::Io {
        action,
        path,
        source,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::error::Error as _;

    /// A FOLD scene's error names the file, unless the reader's I/O message
    /// names it already; the reader's error stays the source.
    #[test]
    fn scene_errors_name_the_file_once() {
        let path = PathBuf::from("a/b.fold");
        let io = CliError::Scene {
            path: path.clone(),
            source: SceneError::Io {
                path: "a/b.fold".into(),
                message: "No such file or directory".into(),
            },
        };
        assert_eq!(
            io.to_string(),
            "cannot read a/b.fold: No such file or directory"
        );
        let invalid = CliError::Scene {
            path,
            source: SceneError::invalid("edges_vertices[3]", "vertex 9 out of range"),
        };
        assert_eq!(
            invalid.to_string(),
            "a/b.fold: edges_vertices[3]: vertex 9 out of range"
        );
        let source = invalid.source().expect("the reader's error");
        assert_eq!(
            source
                .downcast_ref::<SceneError>()
                .and_then(SceneError::key),
            Some("edges_vertices[3]")
        );
    }

    #[test]
    fn input_csv_messages() {
        let e: CliError = InputCsvError::NotANumber { line: 3, column: 2 }.into();
        assert_eq!(e.to_string(), "input CSV line 3: column 2 is not a number");
        assert!(e.source().is_some());
    }
}
