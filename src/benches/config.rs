//! The settings of a bench design study, read from TOML and checked before any work. The defaults are the seed
//! paper's Section 5 study (seed-paper.md, "The design study").
//!
//! Unknown keys are errors that name the key and the line. Every key is optional; a table given in the file
//! replaces that table's defaults key by key (except `[lumped2d.face]`-style material tables, which replace the
//! whole material: start them from `preset = "..."` to change one value).
//!
//! # Format (all defaults shown)
//! ```toml
//! bench_height_m = 20.0                 # vertical height of every face, m
//! n_benches = 5                         # catch benches in the stack (one more face drops to the toe floor)
//! face_angles_deg = [45.0, 60.0, 75.0]
//! bench_widths_m = [4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0]
//! masses_kg = [100.0, 1000.0, 10000.0]  # 3DRB rock i: masses_kg[(i / shapes) % masses]; 2DLM: runs per mass
//! seed = 1                              # repeat r uses seed + r
//! repeats = 1                           # runs of every configuration with seeds seed, seed + 1, ...
//! threads = 0                           # 0 = all cores; results do not depend on it
//! retention_target = 0.9                # design target for first-bench capture (physics.md §7)
//!
//! [geometry]                            # the bench stack around the study's benches (BenchGeometry)
//! crest_floor_m = 10.0                  # flat floor behind the top crest, m
//! toe_floor_m = 60.0                    # run-out floor after the last toe, m
//! lateral_width_m = 200.0               # y extent of the 3DRB terrain, m (rocks start in the middle)
//! max_edge_m = 2.5                      # largest triangle edge of the 3DRB terrain, m
//!
//! [release]                             # the same for both models
//! setback_m = 0.0                       # centre of mass this far behind the top crest, m
//! clearance_m = 0.1                     # lowest point of the rock above the crest floor, m
//! speed_mps = [1.0, 2.0]                # horizontal speed towards the slope, drawn uniformly, m/s
//!
//! [lumped2d]                            # 2DLM (runs = 0 skips the model)
//! runs = 300                            # per configuration and mass
//! face = { preset = "face_all", roughness_sd_deg = 2.0 }    # Table 1 (talus::lumped2d::MaterialSpec)
//! floor = { preset = "floor_all", roughness_sd_deg = 2.0 }
//! [lumped2d.options]                    # talus::lumped2d::Options2d, e.g. scale_rn_by_velocity = true
//!
//! [rigid3d]                             # 3DRB (runs = 0 skips the model)
//! runs = 90                             # per configuration, over all shapes and masses
//! shapes = ["cube", "flat_box", "smartie"]   # rock i has shape shapes[i % number of shapes]
//! density_kg_m3 = 2650.0
//! face = { preset = "face_all" }        # Table 2 (talus::scenario::MaterialSpec)
//! floor = { preset = "floor_all" }
//! [rigid3d.simulation]                  # talus::sim::SimParams, e.g. dt_s = 0.001
//!
//! [records]                             # historic events (optional)
//! file = "records.csv"                  # bench_height_m,bench_width_m,face_angle_deg,runout_m; relative to this file
//! bench_height_tolerance_m = 5.0        # records used: |bench height − bench_height_m| <= this
//! face_angle_tolerance_deg = 7.5        # per-angle curves: |face angle − angle| <= this
//! ```

use crate::error::{Error, Result};
use crate::lumped2d::{Material2d, MaterialSpec as MaterialSpec2d, Options2d};
use crate::rock::{ShapeKind, DEFAULT_DENSITY_KG_M3};
use crate::scenario::MaterialSpec as MaterialSpec3d;
use crate::sim::SimParams;
use crate::terrain::bench::MAX_LENGTH_M;
use crate::terrain::{BenchGeometry, Material};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The bench stack around the study's benches: everything in [`BenchGeometry`] that the study does not vary.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GeometrySpec {
    /// Flat floor behind the top crest, m (default: 10).
    pub crest_floor_m: f64,
    /// Flat run-out floor after the last toe, m (default: 60).
    pub toe_floor_m: f64,
    /// Lateral (y) width of the 3DRB terrain, m (default: 200, ours: wide enough that few rocks leave by the
    /// sides of a 120 m stack; wheel-shaped smarties roll far sideways; the count is reported).
    pub lateral_width_m: f64,
    /// Largest triangle edge of the 3DRB terrain, m (default: 2.5, as `talus mesh bench`).
    pub max_edge_m: f64,
}

impl Default for GeometrySpec {
    fn default() -> Self {
        GeometrySpec { crest_floor_m: 10.0, toe_floor_m: 60.0, lateral_width_m: 200.0, max_edge_m: 2.5 }
    }
}

/// How every rock starts, the same for both models (ours; see the module docs of [`super::release`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ReleaseSpec {
    /// Horizontal distance of the centre of mass behind the top crest, m (default: 0: right above the crest edge).
    pub setback_m: f64,
    /// Height of the rock's lowest point above the crest floor, m (default: 0.1). For the point mass of 2DLM it
    /// is the height of the point.
    pub clearance_m: f64,
    /// Horizontal speed towards the slope, `[min, max]` drawn uniformly per rock, m/s (default: [1, 2], the
    /// seed paper's pushed rocks).
    pub speed_mps: [f64; 2],
}

impl Default for ReleaseSpec {
    fn default() -> Self {
        ReleaseSpec { setback_m: 0.0, clearance_m: 0.1, speed_mps: [1.0, 2.0] }
    }
}

/// The 2DLM model of the study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Lumped2dSpec {
    /// Rocks per configuration, repeat **and mass** (default: 300, the paper's; 0 skips the model): with 3 masses
    /// a configuration gets 900 point masses, and the 21 configurations of the paper 63 runs of 300, as issue 3
    /// reads the paper. Rock i has mass `masses_kg[i % M]`.
    pub runs: usize,
    /// Face material (default: Table 1 "face_all" with slope roughness 2°, the paper's).
    pub face: MaterialSpec2d,
    /// Floor material (default: Table 1 "floor_all" with slope roughness 2°; the paper gives the roughness for the
    /// faces, applying it to the floors too is ours).
    pub floor: MaterialSpec2d,
    /// Engine options (default: RocFall's defaults, see [`Options2d`]).
    pub options: Options2d,
}

impl Default for Lumped2dSpec {
    fn default() -> Self {
        let spec = |preset: &str| MaterialSpec2d {
            preset: Some(preset.to_string()),
            roughness_sd_deg: Some(2.0),
            ..Default::default()
        };
        Lumped2dSpec { runs: 300, face: spec("face_all"), floor: spec("floor_all"), options: Options2d::default() }
    }
}

/// The 3DRB model of the study.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Rigid3dSpec {
    /// Rocks per configuration and repeat, over all shapes and masses (default: 90, the paper's: 10 per shape
    /// and mass; 0 skips the model).
    pub runs: usize,
    /// Shapes: `cube`, `flat_box`, `smartie` (default: all three, the paper's).
    pub shapes: Vec<String>,
    /// Rock density, kg/m³ (default: 2650).
    pub density_kg_m3: f64,
    /// Face material (default: Table 2 "face_all"; faces are smooth, as in the paper).
    pub face: MaterialSpec3d,
    /// Floor material (default: Table 2 "floor_all").
    pub floor: MaterialSpec3d,
    /// Engine settings (default: [`SimParams::default`]).
    pub simulation: SimParams,
}

impl Default for Rigid3dSpec {
    fn default() -> Self {
        let spec = |preset: &str| MaterialSpec3d { preset: Some(preset.to_string()), ..Default::default() };
        Rigid3dSpec {
            runs: 90,
            shapes: vec!["cube".into(), "flat_box".into(), "smartie".into()],
            density_kg_m3: DEFAULT_DENSITY_KG_M3,
            face: spec("face_all"),
            floor: spec("floor_all"),
            simulation: SimParams::default(),
        }
    }
}

/// Historic rock-fall records to compare with (optional).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RecordsSpec {
    /// The records CSV (`bench_height_m,bench_width_m,face_angle_deg,runout_m`), relative to the config file
    /// (default: none).
    pub file: Option<PathBuf>,
    /// Records whose bench height differs from the study's by more than this are not used, m (default: 5).
    pub bench_height_tolerance_m: f64,
    /// A per-angle curve uses the records whose face angle is within this of the angle, degrees (default: 7.5,
    /// half the paper's 15° spacing).
    pub face_angle_tolerance_deg: f64,
}

impl Default for RecordsSpec {
    fn default() -> Self {
        RecordsSpec { file: None, bench_height_tolerance_m: 5.0, face_angle_tolerance_deg: 7.5 }
    }
}

/// A bench design study as written in TOML (see the module docs for the format). [`Default`] is the seed paper's
/// Section 5 study.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StudyConfig {
    /// Vertical height of every face, m (default: 20).
    pub bench_height_m: f64,
    /// Catch benches in the stack (default: 5).
    pub n_benches: usize,
    /// Face angles from horizontal, degrees (default: 45, 60, 75).
    pub face_angles_deg: Vec<f64>,
    /// Catch-bench widths, m (default: 4 to 10 in 1 m steps).
    pub bench_widths_m: Vec<f64>,
    /// Rock masses, kg, shared out evenly over the rocks (default: 100, 1,000, 10,000).
    pub masses_kg: Vec<f64>,
    /// Seed of all random draws; repeat r uses `seed + r` (default: 1).
    pub seed: u64,
    /// Runs of every configuration with different seeds (default: 1).
    pub repeats: usize,
    /// Threads, 0 = all cores (default: 0). Results do not depend on it.
    pub threads: usize,
    /// Design target for the fraction captured on the first bench (default: 0.9, physics.md §7).
    pub retention_target: f64,
    /// The stack around the benches.
    pub geometry: GeometrySpec,
    /// The release, shared by both models.
    pub release: ReleaseSpec,
    /// The 2DLM model.
    pub lumped2d: Lumped2dSpec,
    /// The 3DRB model.
    pub rigid3d: Rigid3dSpec,
    /// Historic records.
    pub records: RecordsSpec,
    /// Folder that relative paths are resolved against (the config file's; not read from TOML).
    #[serde(skip)]
    pub base_dir: Option<PathBuf>,
}

impl Default for StudyConfig {
    fn default() -> Self {
        StudyConfig {
            bench_height_m: 20.0,
            n_benches: 5,
            face_angles_deg: vec![45.0, 60.0, 75.0],
            bench_widths_m: (4..=10).map(f64::from).collect(),
            masses_kg: vec![100.0, 1000.0, 10000.0],
            seed: 1,
            repeats: 1,
            threads: 0,
            retention_target: 0.9,
            geometry: GeometrySpec::default(),
            release: ReleaseSpec::default(),
            lumped2d: Lumped2dSpec::default(),
            rigid3d: Rigid3dSpec::default(),
            records: RecordsSpec::default(),
            base_dir: None,
        }
    }
}

/// Materials and rock shapes of a checked study.
#[derive(Debug, Clone)]
pub struct ResolvedMaterials {
    /// 2DLM face.
    pub face_2d: Material2d,
    /// 2DLM floor.
    pub floor_2d: Material2d,
    /// 3DRB face (named `face`).
    pub face_3d: Material,
    /// 3DRB floor (named `floor`).
    pub floor_3d: Material,
    /// 3DRB shapes.
    pub shapes: Vec<ShapeKind>,
}

impl StudyConfig {
    /// Reads a study file; relative paths in it are resolved against its folder.
    ///
    /// # Errors
    /// I/O errors, and TOML errors naming the file, the line and the key.
    pub fn load(path: &Path) -> Result<StudyConfig> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        let mut c = StudyConfig::from_toml_str(&text, &path.display().to_string())?;
        c.base_dir = path.parent().map(Path::to_path_buf);
        Ok(c)
    }

    /// Parses a study from TOML text; `source` names it in errors.
    ///
    /// # Errors
    /// TOML errors (syntax, unknown keys, wrong types) located as `source:line`.
    pub fn from_toml_str(text: &str, source: &str) -> Result<StudyConfig> {
        toml::from_str(text).map_err(|e| {
            crate::io::toml_error(
                text,
                source,
                &e,
                "check the key names and values against the study format (README, \"The bench design study\"; \
                 examples/benches_quick.toml)",
            )
        })
    }

    /// The Modified Ritchie Criterion bench width for this bench height, BW = 0.2 × BH + 4.5 m (Ryan & Pryor
    /// 2000, physics.md §7).
    pub fn modified_ritchie_width_m(&self) -> f64 {
        modified_ritchie_width_m(self.bench_height_m)
    }

    /// Rocks per configuration and repeat of `model`: 2DLM `runs` per mass, 3DRB `runs`.
    pub fn rocks_per_configuration(&self, model: super::Model) -> usize {
        match model {
            super::Model::Lumped2d => self.lumped2d.runs * self.masses_kg.len(),
            super::Model::Rigid3d => self.rigid3d.runs,
        }
    }

    /// The records file resolved against the config file's folder, if any.
    pub fn records_path(&self) -> Option<PathBuf> {
        self.records.file.as_ref().map(|p| match &self.base_dir {
            Some(d) if p.is_relative() => d.join(p),
            _ => p.clone(),
        })
    }

    /// The bench stack of one configuration.
    pub fn geometry(&self, face_angle_deg: f64, bench_width_m: f64) -> BenchGeometry {
        BenchGeometry {
            bench_height_m: self.bench_height_m,
            face_angle_deg,
            bench_width_m,
            n_benches: self.n_benches,
            crest_floor_m: self.geometry.crest_floor_m,
            toe_floor_m: self.geometry.toe_floor_m,
            lateral_width_m: self.geometry.lateral_width_m,
            max_edge_m: self.geometry.max_edge_m,
        }
    }

    /// Checks every value; errors name the key as written in the study file.
    ///
    /// # Errors
    /// The first problem found.
    pub fn validate(&self) -> Result<ResolvedMaterials> {
        let positive = |name: &str, v: f64, hint: &str| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(Error::invalid(name, format!("must be a positive number, got {v}"), hint))
            }
        };
        let non_negative = |name: &str, v: f64, hint: &str| {
            if v.is_finite() && v >= 0.0 {
                Ok(())
            } else {
                Err(Error::invalid(name, format!("must be 0 or more, got {v}"), hint))
            }
        };
        // The two keys the geometry has under other names are checked here against its limits, so an error names
        // the key (or flag) the user gave.
        if !(self.bench_height_m > 0.0 && self.bench_height_m <= MAX_LENGTH_M) {
            return Err(Error::invalid(
                "bench_height_m",
                format!("must be a positive number of metres up to {MAX_LENGTH_M}, got {}", self.bench_height_m),
                "e.g. bench_height_m = 20",
            ));
        }
        crate::parallel::check_threads("threads", self.threads)?;
        if self.n_benches == 0 {
            return Err(Error::invalid("n_benches", "must be at least 1", "give 1 or more benches, e.g. 5"));
        }
        check_list("face_angles_deg", &self.face_angles_deg, |a| a > 1.0 && a < 89.9, "between 1 and 89.9 degrees")?;
        check_list(
            "bench_widths_m",
            &self.bench_widths_m,
            |w| (0.0..=MAX_LENGTH_M).contains(&w),
            "0 to 10,000 metres",
        )?;
        check_list("masses_kg", &self.masses_kg, |m| m > 0.0, "positive masses in kg")?;
        if self.repeats == 0 {
            return Err(Error::invalid("repeats", "must be at least 1", "give 1 or more repeats (5 pools five seeds)"));
        }
        // Every rock of the study is kept (rocks.csv): at most MAX_ROCKS a model, as a run's.
        let configurations = self.face_angles_deg.len() * self.bench_widths_m.len();
        for (model, field) in [(super::Model::Lumped2d, "lumped2d.runs"), (super::Model::Rigid3d, "rigid3d.runs")] {
            let rocks = self.rocks_per_configuration(model).checked_mul(configurations * self.repeats);
            if rocks.is_none_or(|n| n > crate::source::MAX_ROCKS) {
                return Err(Error::invalid(
                    field,
                    format!(
                        "runs × {configurations} configurations × {} repeats is more than the limit of {} rocks a \
                         study",
                        self.repeats,
                        crate::source::MAX_ROCKS
                    ),
                    "give fewer runs (--runs-2dlm, --runs-3drb) or repeats",
                ));
            }
        }
        if !(self.retention_target > 0.0 && self.retention_target <= 1.0) {
            return Err(Error::invalid(
                "retention_target",
                format!("must be a fraction in (0, 1], got {}", self.retention_target),
                "e.g. retention_target = 0.9 for 90 %",
            ));
        }
        let g = &self.geometry;
        non_negative("geometry.crest_floor_m", g.crest_floor_m, "e.g. 10")?;
        non_negative("geometry.toe_floor_m", g.toe_floor_m, "e.g. 60")?;
        positive("geometry.lateral_width_m", g.lateral_width_m, "e.g. 200")?;
        positive("geometry.max_edge_m", g.max_edge_m, "e.g. 2.5")?;
        for &a in &self.face_angles_deg {
            for &w in &self.bench_widths_m {
                self.geometry(a, w).validate("geometry.")?;
            }
        }
        let r = &self.release;
        non_negative("release.setback_m", r.setback_m, "e.g. 0")?;
        if r.setback_m > g.crest_floor_m {
            return Err(Error::invalid(
                "release.setback_m",
                format!("{} m is behind the crest floor ({} m wide)", r.setback_m, g.crest_floor_m),
                "release on the crest floor: setback_m <= geometry.crest_floor_m",
            ));
        }
        non_negative("release.clearance_m", r.clearance_m, "e.g. 0.1")?;
        let [lo, hi] = r.speed_mps;
        if !(lo.is_finite() && hi.is_finite() && lo >= 0.0 && lo <= hi) {
            return Err(Error::invalid(
                "release.speed_mps",
                format!("[{lo}, {hi}] is not an ordered pair of speeds >= 0"),
                "e.g. speed_mps = [1.0, 2.0]",
            ));
        }
        if self.lumped2d.runs == 0 && self.rigid3d.runs == 0 {
            return Err(Error::invalid(
                "lumped2d.runs, rigid3d.runs",
                "both are 0: nothing to simulate",
                "give at least one model some runs, e.g. lumped2d.runs = 300",
            ));
        }
        let face_2d = self.lumped2d.face.resolve("lumped2d.face")?;
        let floor_2d = self.lumped2d.floor.resolve("lumped2d.floor")?;
        self.lumped2d.options.validate("lumped2d.options.")?;
        let face_3d = self.rigid3d.face.build("face", "rigid3d.face")?;
        let floor_3d = self.rigid3d.floor.build("floor", "rigid3d.floor")?;
        self.rigid3d.simulation.validate("rigid3d.simulation.")?;
        positive("rigid3d.density_kg_m3", self.rigid3d.density_kg_m3, "e.g. 2650")?;
        if self.rigid3d.shapes.is_empty() {
            return Err(Error::invalid(
                "rigid3d.shapes",
                "is empty",
                "e.g. shapes = [\"cube\", \"flat_box\", \"smartie\"]",
            ));
        }
        let mut shapes = Vec::new();
        for (i, s) in self.rigid3d.shapes.iter().enumerate() {
            shapes.push(ShapeKind::builtin(s).ok_or_else(|| {
                Error::invalid(
                    format!("rigid3d.shapes[{i}]"),
                    format!("unknown shape '{s}'"),
                    "use cube, flat_box or smartie",
                )
            })?);
        }
        positive("records.bench_height_tolerance_m", self.records.bench_height_tolerance_m, "e.g. 5")?;
        positive("records.face_angle_tolerance_deg", self.records.face_angle_tolerance_deg, "e.g. 7.5")?;
        Ok(ResolvedMaterials { face_2d, floor_2d, face_3d, floor_3d, shapes })
    }
}

/// The Modified Ritchie Criterion: catch-bench width BW = 0.2 × BH + 4.5 m for a bench height BH in m (Ryan &
/// Pryor 2000, physics.md §7).
pub fn modified_ritchie_width_m(bench_height_m: f64) -> f64 {
    0.2 * bench_height_m + 4.5
}

fn check_list(name: &str, values: &[f64], ok: impl Fn(f64) -> bool, what: &str) -> Result<()> {
    if values.is_empty() {
        return Err(Error::invalid(name, "is empty", format!("give at least one value ({what})")));
    }
    for (i, &v) in values.iter().enumerate() {
        if !(v.is_finite() && ok(v)) {
            return Err(Error::invalid(format!("{name}[{i}]"), format!("{v} is not {what}"), format!("give {what}")));
        }
        if values[..i].contains(&v) {
            return Err(Error::invalid(format!("{name}[{i}]"), format!("{v} is repeated"), "give each value once"));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_the_paper_study_and_validate() {
        let c = StudyConfig::default();
        c.validate().unwrap();
        assert_eq!(c.bench_widths_m, vec![4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0]);
        assert_eq!(c.modified_ritchie_width_m(), 8.5);
        let empty = StudyConfig::from_toml_str("", "s.toml").unwrap();
        assert_eq!(serde_json::to_string(&empty).unwrap(), serde_json::to_string(&c).unwrap());
    }

    #[test]
    fn example_study_resolves() {
        let text = include_str!("../../examples/benches_quick.toml");
        let c = StudyConfig::from_toml_str(text, "benches_quick.toml").unwrap();
        c.validate().unwrap();
        assert_eq!(c.repeats, 3);
    }

    #[test]
    fn bad_keys_and_values_are_named() {
        let e = StudyConfig::from_toml_str("seed = 1\nbench_hieght_m = 30\n", "s.toml").unwrap_err().to_string();
        assert!(e.contains("bench_hieght_m") && e.contains("s.toml:2"), "{e}");
        let e = StudyConfig::from_toml_str("[rigid3d]\nrun = 5\n", "s.toml").unwrap_err().to_string();
        assert!(e.contains("run") && e.contains("s.toml:2"), "{e}");
        let c = StudyConfig::from_toml_str("face_angles_deg = [45.0, 95.0]", "s.toml").unwrap();
        assert!(c.validate().unwrap_err().to_string().contains("face_angles_deg[1]"));
        let c = StudyConfig::from_toml_str("[rigid3d]\nshapes = [\"cube\", \"sphere\"]", "s.toml").unwrap();
        assert!(c.validate().unwrap_err().to_string().contains("rigid3d.shapes[1]"));
        let c = StudyConfig::from_toml_str("[lumped2d.face]\npreset = \"face_al\"", "s.toml").unwrap();
        assert!(c.validate().unwrap_err().to_string().contains("lumped2d.face.preset"));
    }
}
