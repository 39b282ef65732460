//! The files `talus calibrate` writes into its output folder. A calibration into the folder of an earlier one
//! removes the earlier one's files it did not write again (a split after a k-fold study left `fold_*` and
//! `cv_report.*`; a 3-fold study after a 5-fold one left `fold_4` and `fold_5`, which `talus envelope
//! DIR/fold_*/...` then mixed in), so that the folder holds one study, as `talus run` does with its summary's files
//! (ours). Only files of the names a calibration writes are touched, in the folder itself and in its `fold_N` and
//! `repeat_N` folders, and only when the folder holds an earlier calibration's report.

use crate::error::{Error, Result};
use std::path::{Path, PathBuf};
use std::time::SystemTime;

/// The reports one of which marks a folder as an earlier calibration's (a split, a k-fold study, a repeated one).
const REPORTS: [&str; 3] = ["report.json", "cv_report.json", "cv_repeats.json"];

/// Whether `name` is a file a calibration writes: reports, run tables, charts, maps and the calibrated model.
fn is_output_file(name: &str) -> bool {
    const FILES: [&str; 10] = [
        "report.md",
        "runs.csv",
        "impacts.csv",
        "cv_report.md",
        "cv_repeats.md",
        "calibrated.toml",
        "calibrated_profile.toml",
        "calibrated_profile.csv",
        "deposition_excess.tif",
        "deposition_excess.png",
    ];
    let named =
        |prefix: &str, extensions: &[&str]| name.starts_with(prefix) && extensions.iter().any(|e| name.ends_with(e));
    REPORTS.contains(&name)
        || FILES.contains(&name)
        || named("residual_vs_", &[".svg"])
        || named("bounce_ranks_vs_", &[".svg"])
        || named("runout_", &[".svg"])
        || named("residual_map", &[".svg", ".tif", ".png"])
}

/// Whether `name` is a folder of a cross-validation: `fold_N` or `repeat_N`.
fn is_output_folder(name: &str) -> bool {
    ["fold_", "repeat_"]
        .iter()
        .filter_map(|p| name.strip_prefix(p))
        .any(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()))
}

/// An earlier calibration's files in a folder, each with its modification time when listed.
#[derive(Debug, Default)]
pub struct EarlierOutputs {
    files: Vec<(PathBuf, SystemTime)>,
    folders: Vec<PathBuf>,
}

impl EarlierOutputs {
    /// Lists the files of an earlier calibration in `dir` (none when `dir` holds no calibration report).
    pub fn list(dir: &Path) -> EarlierOutputs {
        let mut earlier = EarlierOutputs::default();
        if REPORTS.iter().any(|r| dir.join(r).is_file()) {
            earlier.collect(dir);
        }
        earlier
    }

    fn collect(&mut self, dir: &Path) {
        let Ok(entries) = std::fs::read_dir(dir) else { return };
        for entry in entries.flatten() {
            // Not followed: a link is neither a file nor a folder here.
            let Ok(meta) = entry.metadata() else { continue };
            let name = entry.file_name().to_string_lossy().into_owned();
            if meta.is_dir() && is_output_folder(&name) {
                self.folders.push(entry.path());
                self.collect(&entry.path());
            } else if meta.is_file() && is_output_file(&name) {
                if let Ok(t) = meta.modified() {
                    self.files.push((entry.path(), t));
                }
            }
        }
    }

    /// Removes the listed files that were not written again since (their modification time unchanged), then the
    /// listed folders left empty. Returns the number of files removed.
    ///
    /// # Errors
    /// A stale file cannot be removed.
    pub fn remove_stale(&self) -> Result<usize> {
        let mut removed = 0;
        for (path, listed) in &self.files {
            let unchanged = std::fs::metadata(path).and_then(|m| m.modified()).is_ok_and(|t| t == *listed);
            if unchanged {
                std::fs::remove_file(path).map_err(|e| Error::io(path, e))?;
                removed += 1;
            }
        }
        // Deepest first, so that a repeat's folder empties after its folds'; a folder still holding files stays.
        for folder in self.folders.iter().rev() {
            let _ = std::fs::remove_dir(folder);
        }
        Ok(removed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_a_calibrations_own_names_count() {
        for name in ["report.json", "runs.csv", "residual_vs_mass_kg.svg", "residual_map_final.tif", "cv_repeats.md"] {
            assert!(is_output_file(name), "{name}");
        }
        for name in ["notes.md", "terrain.asc", "residual_vs_mass_kg.txt", "my_runout.csv"] {
            assert!(!is_output_file(name), "{name}");
        }
        assert!(is_output_folder("fold_12") && is_output_folder("repeat_1"));
        assert!(!is_output_folder("fold_") && !is_output_folder("fold_a") && !is_output_folder("data"));
    }
}
