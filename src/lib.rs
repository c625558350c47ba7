//! # origami-fmu
//!
//! Origami folding dynamics with the iso-parametric ANCF shell model (Tao & Li
//! 2019, as corrected in the project's MATH notes): every facet is a cubic
//! triangular Kirchhoff shell with Green-Lagrange membrane strain, creases are
//! rotational springs at the crease end nodes, and the mass matrix is
//! constant. The model is packed as an FMI 2.0 co-simulation FMU.
//!
//! Layers, bottom up: [`mesh`] (crease pattern as data), [`scene`] (FOLD
//! scenes with physics keys), and [`model`] (the plain Rust API that the FMU
//! and the CLI drive), with [`fmi`] on top: the FMI 2.0 co-simulation
//! functions exported from the cdylib. `unsafe` code is denied everywhere
//! but in two files of [`fmi`] (the pointer helpers and the exports).
#![warn(missing_docs)]
#![deny(unsafe_code)]

pub mod assembly;
pub mod benchmarks;
pub mod cli;
pub mod crease;
pub mod curves;
pub mod dofs;
pub mod element;
pub mod fmi;
pub mod material;
pub mod mesh;
pub mod model;
pub mod paraview;
pub mod rigid;
pub mod rng;
pub mod scene;
pub mod solver;
