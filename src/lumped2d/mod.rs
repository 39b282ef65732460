//! The 2D lumped-mass engine (2DLM) with RocFall semantics, and the library side of `talus profile`.
//!
//! A rock is a point mass on a slope profile (a polyline in the x–z plane). It flies on exact parabolas, bounces
//! with normal and tangential restitution (Rn, Rt) drawn per impact, feels the slope roughness as a random
//! perturbation of the segment angle, and slides in closed form with a friction angle. Mass only scales energies
//! (and sizes the rock for the arrow-height switch and the optional rotational rules). See physics.md §3 and §8.
//!
//! - [`Profile`]: the polyline (CSV, bench geometry, or a section through a 3D surface, [`section_from_mesh`]).
//! - [`Material2d`]: Rn, Rt, friction, roughness, with the seed paper's Table 1 presets.
//! - [`Options2d`]: optional physics and thresholds.
//! - [`simulate_rock`]: one rock; a [`PathObserver`] sees its analytic path pieces.
//! - [`simulate_rocks`], [`simulate_bench`]: ensembles without files.
//! - [`ProfileScenario`] and [`run_profile`]: a TOML scenario in, CSV and JSON out (the format is documented in
//!   [`scenario`]).
//!
//! # Units
//! SI throughout: m, s, m/s, kg, J; angles in degrees where the name says `_deg`.
//!
//! # Examples
//! ```
//! use talus::lumped2d::{run_profile, ProfileScenario};
//! let toml = r#"
//!     rocks = 20
//!     mass_kg = 1000.0
//!     seed = 1
//!     [profile.bench]
//!     face_angle_deg = 60.0
//!     [materials.face]
//!     preset = "face_all"
//!     [materials.floor]
//!     preset = "floor_all"
//!     [release]
//!     x_m = [10.0, 10.5]
//!     height_m = 0.5
//!     vx_mps = [1.0, 2.0]
//! "#;
//! let scenario = ProfileScenario::from_toml_str(toml, "inline").unwrap();
//! let out = tempfile::tempdir().unwrap();
//! let summary = run_profile(&scenario, out.path()).unwrap();
//! assert_eq!(summary.rocks, 20);
//! assert!(out.path().join("envelopes.csv").exists());
//! ```

mod engine;
mod gauges;
mod material;
mod options;
mod path;
mod profile;
mod release;
mod run;
pub mod scenario;
mod section;
mod slope;

pub use engine::{pfeiffer_bowen_rn, simulate_rock, RockResult2d, RockStart2d, StopReason, G_MPS2, PFEIFFER_BOWEN_MPS};
pub use gauges::{Crossing, GaugeEnsemble, GaugeLayout, GaugeRecorder, GaugeStats, LogHistogram};
pub use material::{tan_friction_from_rt, DistSpec, FrictionAngle, FrictionMode, Material2d, MaterialSpec};
pub use options::{FrictionSource, Options2d, Rotation};
pub use path::{FlightPiece, ImpactEvent, PathObserver, PathPiece, PathRecorder, SlidePiece};
pub use profile::{Profile, MAX_STATIONS};
pub use release::{Release2d, ValueRange};
pub use run::{
    run_profile, simulate_bench, simulate_ensemble_rock, simulate_rocks, BenchCapture, BenchCaptureSummary, BenchRun,
    Percentiles, ProfileInfo, ProfileSummary, StopCounts,
};
pub use scenario::{CampaignRelease, ProfileScenario, ProfileSource, ReleaseSpec, ResolvedScenario};
pub use section::{section_from_mesh, SectionMaterials};
pub use slope::Slope2d;
