//! Hazard rasters: where rocks pass, how fast, how high, and where they stop.

pub mod accumulate;
pub mod density;
pub mod grid;
pub mod histogram;

pub use accumulate::{CellTrack, CellVisit, HazardAccumulator};
pub use density::EndpointDensity;
pub use grid::RasterFrame;
pub use histogram::LogBins;
