//! The files `talus calibrate` writes into its output folder. A calibration into the folder of an earlier one
//! removes the earlier one's files it did not write again (a split after a k-fold study left `fold_*` and
//! `cv_report.*`; a 3-fold study after a 5-fold one left `fold_4` and `fold_5`, which `talus envelope
//! DIR/fold_*/...` then mixed in), so that the folder holds one study, as `talus run` does with its summary's files
//! (ours). Only files of the names a calibration writes are touched, in the folder itself and in its `fold_N` and
//! `repeat_N` folders, and only when the folder (or one of those) holds an earlier calibration's report.

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
        || named("profile_", &[".svg"])
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
    /// Lists the files of an earlier calibration in `dir`: none unless `dir`, or one of its `fold_N` / `repeat_N`
    /// folders (a k-fold study stopped before its summary), holds a calibration report.
    pub fn list(dir: &Path) -> EarlierOutputs {
        let has_report = |d: &Path| REPORTS.iter().any(|r| d.join(r).is_file());
        let folders = std::fs::read_dir(dir).into_iter().flatten().flatten();
        let marked = has_report(dir)
            || folders.filter(|e| is_output_folder(&e.file_name().to_string_lossy())).any(|e| has_report(&e.path()));
        let mut earlier = EarlierOutputs::default();
        if marked {
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
        for name in [
            "report.json",
            "runs.csv",
            "residual_vs_mass_kg.svg",
            "profile_default.cr_sd.svg",
            "residual_map_final.tif",
            "cv_repeats.md",
        ] {
            assert!(is_output_file(name), "{name}");
        }
        for name in ["notes.md", "terrain.asc", "residual_vs_mass_kg.txt", "my_runout.csv"] {
            assert!(!is_output_file(name), "{name}");
        }
        assert!(is_output_folder("fold_12") && is_output_folder("repeat_1"));
        assert!(!is_output_folder("fold_") && !is_output_folder("fold_a") && !is_output_folder("data"));
    }

    /// A k-fold study stopped after its first fold left `fold_1/` and no summary: still an earlier calibration's.
    /// A file written again since the listing stays; a user's file stays.
    #[test]
    fn an_interrupted_study_is_listed_and_what_was_not_written_again_goes() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::create_dir(d.join("fold_1")).unwrap();
        for f in ["fold_1/report.json", "fold_1/runs.csv", "notes.md", "runs.csv"] {
            std::fs::write(d.join(f), "old").unwrap();
        }
        let earlier = EarlierOutputs::list(d);
        assert_eq!(earlier.files.len(), 3, "{earlier:?}");
        std::thread::sleep(std::time::Duration::from_millis(20));
        let tmp = d.join(".runs.csv.tmp");
        std::fs::write(&tmp, "new").unwrap();
        std::fs::rename(&tmp, d.join("runs.csv")).unwrap();
        assert_eq!(earlier.remove_stale().unwrap(), 2);
        assert!(!d.join("fold_1").exists() && d.join("notes.md").is_file());
        assert_eq!(std::fs::read_to_string(d.join("runs.csv")).unwrap(), "new");
        assert_eq!(EarlierOutputs::list(d).files.len(), 0, "no report left: nothing listed");
    }
}
