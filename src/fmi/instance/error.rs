//! Why an instance could not be created, or a saved state was refused:
//! the text the FMU logs to the master.

use crate::fmi::container::StateBytesError;
use crate::fmi::resources::ResourceError;
use crate::model::Error as ModelError;
use crate::scene::limits::LimitError;
use crate::text::num;
use std::path::PathBuf;

/// Why `fmi2Instantiate`, `fmi2SetFMUstate`, `fmi2DeSerializeFMUstate` or
/// `fmi2SerializeFMUstate` failed.
#[derive(Debug)]
pub enum InstanceError {
    /// The host asked for model exchange.
    ModelExchange,
    /// `fmuType` is no `fmi2Type`.
    BadFmuType(i32),
    /// `fmuGUID` is NULL.
    NullGuid,
    /// `fmuResourceLocation` is NULL.
    NullResourceLocation,
    /// The resource location is unusable.
    ResourceLocation(ResourceError),
    /// The scene file could not be read.
    ReadScene {
        /// The file.
        path: PathBuf,
        /// The system's error.
        source: std::io::Error,
    },
    /// The scene file is invalid.
    InvalidScene {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        source: ResourceError,
    },
    /// The host's GUID is not the scene's.
    GuidMismatch {
        /// The GUID the host passed.
        host: String,
        /// The scene file.
        path: PathBuf,
        /// The GUID of the scene and library.
        expected: String,
    },
    /// The scene makes no model.
    Model(ModelError),
    /// A variable name is illegal or used twice.
    VariableNames(ResourceError),
    /// A saved state's container is refused (another FMU's).
    StateBytes(StateBytesError),
    /// A saved time is not a usable number.
    SavedTime {
        /// "start_time" or "stop_time".
        what: &'static str,
        /// Why.
        source: LimitError,
    },
    /// The saved stop time is before the start time.
    StopBeforeStart {
        /// Saved stop time.
        stop: f64,
        /// Saved start time.
        start: f64,
    },
    /// The saved instance phase and model phase do not go together.
    PhaseMismatch {
        /// The instance phase's name.
        phase: &'static str,
        /// The model's phase.
        model_phase: crate::model::Phase,
    },
    /// The saved model state does not fit this model.
    State(ModelError),
    /// The state could not be serialized.
    Serialize(serde_json::Error),
}

impl std::fmt::Display for InstanceError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            InstanceError::ModelExchange => write!(
                f,
                "fmuType is fmi2ModelExchange; this FMU supports co-simulation only"
            ),
            InstanceError::BadFmuType(t) => write!(f, "fmuType {t} is not a valid fmi2Type"),
            InstanceError::NullGuid => write!(f, "fmuGUID is NULL"),
            InstanceError::NullResourceLocation => write!(f, "fmuResourceLocation is NULL"),
            InstanceError::ResourceLocation(e) => write!(f, "{e}"),
            InstanceError::ReadScene { path, source } => {
                write!(f, "cannot read the scene {}: {source}", path.display())
            }
            InstanceError::InvalidScene { path, source } => {
                write!(f, "invalid scene {}: {source}", path.display())
            }
            InstanceError::GuidMismatch {
                host,
                path,
                expected,
            } => write!(
                f,
                "GUID mismatch: the host passed {host} but the scene in {} and library version {} give {expected}; \
                 the modelDescription.xml does not belong to this scene or library",
                path.display(),
                crate::fmi::resources::VERSION
            ),
            InstanceError::Model(e) => write!(f, "invalid scene: {e}"),
            InstanceError::VariableNames(e) => write!(f, "invalid scene: {e}"),
            InstanceError::StateBytes(e) => write!(f, "{e}"),
            InstanceError::SavedTime { what, source } => write!(f, "{what} = {source}"),
            InstanceError::StopBeforeStart { stop, start } => write!(
                f,
                "stop_time {} is before start_time {}",
                num(*stop),
                num(*start)
            ),
            InstanceError::PhaseMismatch { phase, model_phase } => write!(
                f,
                "phase '{phase}' with a model phase {model_phase:?}: they do not go together"
            ),
            InstanceError::State(e) => write!(f, "{e}"),
            InstanceError::Serialize(e) => write!(f, "cannot write the state: {e}"),
        }
    }
}

impl std::error::Error for InstanceError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            InstanceError::ResourceLocation(e) | InstanceError::VariableNames(e) => Some(e),
            InstanceError::ReadScene { source, .. } => Some(source),
            InstanceError::InvalidScene { source, .. } => Some(source),
            InstanceError::Model(e) | InstanceError::State(e) => Some(e),
            InstanceError::StateBytes(e) => Some(e),
            InstanceError::SavedTime { source, .. } => Some(source),
            InstanceError::Serialize(e) => Some(e),
            _ => None,
        }
    }
}
