//! # origami-fmu
//!
//! Origami folding dynamics with the iso-parametric ANCF shell model (Tao & Li
//! 2019, with the paper's sign and scaling errors corrected; docs/model.md):
//! every facet is a cubic triangular Kirchhoff shell with Green-Lagrange
//! membrane strain, creases are rotational springs at the crease end nodes,
//! and the mass matrix is constant. The model is packed as an FMI 2.0 co-simulation FMU.
//!
//! Layers, bottom up: [`mesh`] (crease pattern as data) and [`material`]
//! (the sheet), the shell [`element`], the [`crease`] springs and the
//! [`assembly`], [`scene`] (FOLD scenes with physics keys), and [`model`]
//! (the plain Rust API that the FMU and the CLI drive; it runs the
//! [`solver`]s), with [`fmi`] on top: the FMI 2.0 co-simulation functions
//! exported from the cdylib. `unsafe` code is denied everywhere but in two
//! files of [`fmi`] (the pointer helpers and the exports) and the one
//! clock call of [`cpu_time`] (one for unix, one for Windows).
//!
//! The names a user of the Rust API needs most are re-exported here:
//! [`Scene`] (read one with [`scene::load`] or [`scene::from_str`], or build
//! one around a [`Mesh`]), [`Material`], [`Model`] with its [`Error`],
//! [`Phase`], [`StepReport`], [`ModelState`] and [`VariableSpec`], and
//! [`SceneError`]. A square sheet with one creased diagonal, folded a little
//! for 10 ms:
//!
//! ```
//! use origami_fmu::mesh::builders::square_with_diagonal;
//! use origami_fmu::{Material, Model, Phase, Scene};
//!
//! // 10 cm square, the diagonal a crease with a target of 1.5 rad.
//! let scene = Scene::with_defaults("square", square_with_diagonal(0.1, true, 1.5));
//! assert_eq!(scene.material, Material::default());
//! let mut model = Model::new(scene)?;
//! model.initialize()?;
//! assert_eq!(model.phase(), Phase::Running);
//! // The default actuator `fold` drives the rest angle: 0.1 of the target.
//! let fold = model.input_id("fold").expect("the scene has a fold input");
//! model.set_input(fold, 0.1)?;
//! let report = model.advance(0.01)?;
//! assert!(report.steps >= 1);
//! assert!((model.time() - 0.01).abs() < 1e-12);
//! assert!(model.output_values().iter().all(|x| x.is_finite()));
//! # Ok::<(), origami_fmu::Error>(())
//! ```
#![warn(missing_docs)]
#![deny(unsafe_code)]

// The public API: what a user of the Rust library needs (the README's
// "Rust API" lists it).
pub mod ids;
pub mod material;
pub mod mesh;
pub mod model;
pub mod motion;
pub mod paraview;
pub mod scene;

// Internals, public only for the crate's own benches, CLI binary and tests
// (hidden from the documentation; no stability promised).
#[doc(hidden)]
pub mod assembly;
#[doc(hidden)]
pub mod benchmarks;
#[doc(hidden)]
pub mod cli;
#[doc(hidden)]
pub mod contact;
#[doc(hidden)]
pub mod cpu_time;
#[doc(hidden)]
pub mod crease;
#[doc(hidden)]
pub mod curves;
#[doc(hidden)]
pub mod dofs;
#[doc(hidden)]
pub mod element;
#[doc(hidden)]
pub mod fmi;
#[doc(hidden)]
pub mod frame;
#[doc(hidden)]
pub mod pictures;
#[doc(hidden)]
pub mod rigid;
#[doc(hidden)]
pub mod rng;
#[doc(hidden)]
pub mod sampled;
#[doc(hidden)]
pub mod solver;
#[doc(hidden)]
pub mod text;

pub use material::Material;
pub use mesh::Mesh;
pub use model::{
    Error, InputId, Model, ModelState, OutputId, ParameterId, Phase, StepReport, VariableSpec,
};
pub use scene::{Scene, SceneError};

/// The README's Rust example, compiled and run as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
