//! # talus
//!
//! An open-source rockfall hazard mapper. It loads a real terrain surface (OBJ, STL, GeoTIFF or ESRI ASCII DEM),
//! releases rocks from source zones, and runs them as 3D rigid bodies (3DRB: one coefficient of restitution plus
//! static and dynamic friction) or as 2D lumped masses on profiles (2DLM, RocFall semantics). Results are binned
//! into georeferenced hazard rasters while simulating.
//!
//! Physics choices cite `physics.md` (the project's physics notes, not in this repository; each cited section is
//! summarised with its published sources in `docs/physics-notes.md`) or a paper, or are marked as ours.
#![warn(missing_docs)]

pub mod barrier;
pub mod benches;
pub mod calibrate;
pub mod campaign;
pub mod collector;
pub mod ensemble;
pub mod envelope;
pub mod error;
pub mod hazard;
pub mod io;
pub mod lumped2d;
pub mod parallel;
pub mod random;
pub mod raster;
pub mod render;
pub mod report;
pub mod rock;
pub mod run;
pub mod scenario;
pub mod sim;
pub mod source;
pub mod terrain;
pub mod zones;

pub use error::{Error, Result};
