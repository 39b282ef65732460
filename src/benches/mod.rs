//! The bench design study of the seed paper (Section 5), re-run with both models: `talus benches`.
//!
//! A mine sizes its catch benches with 2D lumped-mass runs and checks them against the Modified Ritchie Criterion
//! BW = 0.2 × BH + 4.5 m (physics.md §7). The study runs a stack of benches of one height for every face angle and
//! bench width, with 2DLM ([`crate::lumped2d`]) and 3DRB ([`crate::sim`]) side by side from the same release, counts
//! the rocks captured on each bench, and compares first-bench capture with the criterion, the 90 % retention
//! target and, optionally, a mine's historic records.
//!
//! - [`StudyConfig`]: the settings (TOML; defaults = the paper's study), see [`config`] for the format.
//! - [`run_study`]: simulate; [`write_outputs`]: tables, figures, summary and report; [`run_benches`]: both.
//! - [`release`]: the shared release (ours) and which rock each run is.
//! - [`records`]: historic records and the observed capture curve.
//!
//! # Units
//! SI: m, m/s, kg; angles in degrees; capture as fractions in files and per cent in figures and the report.

pub mod config;
mod figures;
mod outputs;
pub mod records;
pub mod release;
mod runner;
mod stats;

pub use config::{modified_ritchie_width_m, StudyConfig};
pub use outputs::{
    spread_statement, write_outputs, HeadlinePoint, ModelCounts, ModelSpread, RecordsSummary, StudySummary,
    CAPTURE_COLUMNS,
};
pub use records::{read_records, HistoricRecord, ObservedPoint};
pub use runner::{run_study, Cell, Configuration, Model, ModelTiming, Progress, RockClass, RockRow, StudyResult};
pub use stats::{interpolate, wilson_interval, Spread, Z_95};

use crate::error::Result;
use std::path::Path;

/// Checks the settings, reads the records (if any), runs the study and writes every output into `out_dir`.
///
/// # Errors
/// Invalid settings or records (before any simulation), and I/O errors.
pub fn run_benches(config: &StudyConfig, out_dir: &Path, progress: Progress) -> Result<StudySummary> {
    config.validate()?;
    let records = match config.records_path() {
        Some(p) => Some(read_records(&p)?),
        None => None,
    };
    let result = run_study(config, progress)?;
    write_outputs(&result, records.as_deref(), out_dir)
}
