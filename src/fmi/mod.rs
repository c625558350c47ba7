//! The FMI 2.0 co-simulation layer. The crate denies `unsafe` code; only
//! [`ptr`] (every pointer dereference, handle and logger call) and
//! [`exports`] (the `#[unsafe(no_mangle)]` C functions that call it) are
//! allowed it.
//!
//! - [`types`]: the C types of the standard (`#[repr(C)]`).
//! - [`exports`]: every `fmi2*` function, exported with its C name; each
//!   body under `catch_unwind`, pointers checked through [`ptr`], enum
//!   arguments validated from integers.
//! - [`ptr`]: the audited pointer helpers: null, alignment, length and
//!   magic-number checks of what the host passes.
//! - [`instance`]: the state machine around a [`crate::model::Model`]
//!   and the value-reference map (parameters, inputs, outputs; contiguous).
//! - [`xml`]: the modelDescription.xml writer.
//! - [`container`]: the bytes of a serialized FMU state (versioned,
//!   checksummed, bound to the GUID).
//! - [`resources`]: the scene file in `resources/`, the GUID derived from
//!   it, and resource-location URIs.
//!
//! One shared library (`modelIdentifier` [`MODEL_IDENTIFIER`]) serves every
//! scene: the scene travels in the FMU's `resources/` folder and the GUID
//! (a hash of the scene file and the crate version) ties the XML, the scene
//! and the library together.

pub mod container;
#[allow(unsafe_code)]
pub mod exports;
pub mod instance;
#[allow(unsafe_code)]
pub mod ptr;
pub mod resources;
pub mod types;
pub mod xml;

pub use resources::{MODEL_IDENTIFIER, SCENE_FILE};

use crate::model::Model;
use crate::scene::Scene;

/// Everything an FMU of one scene is made of, apart from the binary.
#[derive(Clone, Debug)]
pub struct FmuContents {
    /// The scene (validated).
    pub scene: Scene,
    /// Bytes of `resources/`[`SCENE_FILE`].
    pub scene_file: Vec<u8>,
    /// The GUID.
    pub guid: String,
    /// modelDescription.xml.
    pub model_description: String,
    /// Number of parameters, inputs and outputs.
    pub counts: [usize; 3],
}

/// The modelDescription.xml, scene file and GUID of the FMU of `scene`.
pub fn fmu_contents(scene: &Scene) -> Result<FmuContents, resources::ResourceError> {
    let scene_file = resources::scene_bytes(scene);
    // Read back exactly what the FMU will read at instantiation.
    let scene = resources::parse_scene(&scene_file)?;
    let guid = resources::guid(&scene_file);
    let model = Model::new(scene.clone()).map_err(resources::ResourceError::Model)?;
    resources::check_variable_names(&model)?;
    let counts = [
        model.parameters().len(),
        model.inputs().len(),
        model.outputs().len(),
    ];
    let model_description = xml::model_description(&model, &guid);
    Ok(FmuContents {
        scene,
        scene_file,
        guid,
        model_description,
        counts,
    })
}
