//! Terrain: the surface rocks move over, its materials, and the generators of synthetic slopes.

pub mod bench;

pub use bench::BenchGeometry;
