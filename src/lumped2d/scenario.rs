//! The profile scenario: everything `talus profile` needs, read from TOML and checked before any work.
//!
//! Unknown keys are errors that name the key and the line. Paths are relative to the scenario file.
//!
//! # Format
//! ```toml
//! name = "bench stack, 60° faces, 7 m benches"   # optional
//! rocks = 300              # number of rocks
//! mass_kg = 1000.0         # rock mass (scales energies; sizes the rock for the arrow-height switch)
//! seed = 42                # same seed, same results, whatever the thread count (default 0)
//! envelope_spacing_m = 1.0 # stations for envelopes.csv (default 1 m)
//! collectors_x_m = [40.0, 60.0]   # vertical collectors for collectors.csv (default none)
//!
//! # The profile: a CSV file (x_m,z_m,material; relative to this file) ...
//! #   profile = { csv = "profile.csv" }
//! # ... or a benched slope (BenchGeometry; materials "face" and "floor"; top crest at x = crest_floor_m).
//! [profile.bench]
//! bench_height_m = 20.0
//! face_angle_deg = 60.0
//! bench_width_m = 7.0
//! n_benches = 5
//!
//! # One table per profile material: a Table 1 preset and/or explicit values (see `MaterialSpec`).
//! [materials.face]
//! preset = "face_all"
//! roughness_sd_deg = 2.0
//!
//! [materials.floor]
//! rn = { mean = 0.300, sd = 0.058 }
//! rt = { mean = 0.622, sd = 0.119 }
//! friction_angle_deg = 25.0
//! roughness_sd_deg = 2.0
//!
//! # Each value is a number or [min, max], drawn uniformly per rock.
//! [release]
//! x_m = [10.0, 10.5]    # m along the profile
//! height_m = 0.5        # above the profile, m (default 0)
//! vx_mps = [1.0, 2.0]   # default 0
//! vz_mps = 0.0          # default 0
//! spin_radps = 0.0      # default 0; only used with a rotational rule
//!
//! # ... or, instead of [release], rocks and mass_kg: every run of a field campaign (`talus calibrate`'s format
//! # along the profile: release_points.csv with x_m, z_m, vx_mps, vz_mps, wy_radps, block_id, and
//! # block_metadata.csv), each `repeats` times from its measured state with its block's mass.
//! # [campaign]
//! # dir = "my_campaign"   # relative to this file
//! # repeats = 20          # default 20
//!
//! # Engine options (see `Options2d`; all optional).
//! [options]
//! scale_rn_by_velocity = false
//! rn_velocity_scale_mps = 9.144 # K of Rn/(1 + (v_n/K)²)
//! rn_mass_exponent = 0.0      # Rn (m/m_ref)^-β; 0 = off
//! rn_reference_mass_kg = 1000.0
//! rotation = "off"            # "off" | "rocfall" | "crsp"
//! friction_angle = "material" # "material" | "from_rt" | "zero"
//! switch_speed_mps = 0.5
//! arrow_height_ratio = 0.1
//! stop_speed_mps = 0.1
//! max_events = 10000
//! max_time_s = 600.0
//! ```

use super::engine::RockStart2d;
use super::material::{Material2d, MaterialSpec};
use super::options::Options2d;
use super::profile::Profile;
use super::release::{Release2d, ValueRange};
use super::slope::Slope2d;
use crate::campaign::{Campaign, Ground};
use crate::error::{Error, Result};
use crate::terrain::BenchGeometry;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Where the profile comes from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", try_from = "RawProfileSource")]
pub enum ProfileSource {
    /// A profile CSV (`x_m,z_m,material`), relative to the scenario file.
    Csv(PathBuf),
    /// A benched slope; its materials are `face` and `floor`.
    Bench(BenchGeometry),
}

/// The `[profile]` table as written: [`ProfileSource`] read through it, so that giving both keys or neither is
/// told in words (serde's enum said "wanted exactly 1 element, more than 1 element").
#[derive(Deserialize)]
#[serde(deny_unknown_fields, expecting = "a table with `csv = \"profile.csv\"` or `[profile.bench]`")]
struct RawProfileSource {
    /// A profile CSV.
    csv: Option<PathBuf>,
    /// A benched slope.
    bench: Option<BenchGeometry>,
}

impl TryFrom<RawProfileSource> for ProfileSource {
    type Error = String;

    fn try_from(raw: RawProfileSource) -> std::result::Result<ProfileSource, String> {
        match (raw.csv, raw.bench) {
            (Some(csv), None) => Ok(ProfileSource::Csv(csv)),
            (None, Some(bench)) => Ok(ProfileSource::Bench(bench)),
            (Some(_), Some(_)) => Err("[profile] gives both `csv` and `[profile.bench]`, which exclude each other: \
                 keep `csv` to read the profile from that CSV file, or `[profile.bench]` to generate a benched \
                 slope, and delete the other"
                .to_string()),
            (None, None) => Err("[profile] gives neither `csv` nor `[profile.bench]`: add `csv = \"profile.csv\"` \
                 (a profile CSV) or a `[profile.bench]` table (a benched slope)"
                .to_string()),
        }
    }
}

/// The `[release]` table: each value a number or `[min, max]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReleaseSpec {
    /// Release x, m.
    pub x_m: ValueRange,
    /// Height above the profile, m (default: 0).
    #[serde(default)]
    pub height_m: ValueRange,
    /// Horizontal velocity, m/s (default: 0).
    #[serde(default)]
    pub vx_mps: ValueRange,
    /// Vertical velocity, up positive, m/s (default: 0).
    #[serde(default)]
    pub vz_mps: ValueRange,
    /// Spin, rad/s, clockwise positive in the x–z view (default: 0).
    #[serde(default)]
    pub spin_radps: ValueRange,
}

fn default_spacing() -> f64 {
    1.0
}

fn default_repeats() -> usize {
    20
}

/// The `[campaign]` table: release every run of a field campaign `repeats` times from its measured state.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CampaignRelease {
    /// The campaign folder (`talus calibrate`'s format, along the profile: `y_m` absent or 0), relative to the
    /// scenario file.
    pub dir: PathBuf,
    /// Rocks per field run (default: 20).
    #[serde(default = "default_repeats")]
    pub repeats: usize,
}

/// A profile scenario as written in TOML (see the module docs for the format).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProfileScenario {
    /// A name for the run (optional).
    #[serde(default)]
    pub name: Option<String>,
    /// The profile.
    pub profile: ProfileSource,
    /// One material per profile material name.
    pub materials: BTreeMap<String, MaterialSpec>,
    /// The release of ranges (give it or `campaign`).
    #[serde(default)]
    pub release: Option<ReleaseSpec>,
    /// The release of a field campaign's runs (give it or `release`).
    #[serde(default)]
    pub campaign: Option<CampaignRelease>,
    /// Number of rocks (with `release`).
    #[serde(default)]
    pub rocks: Option<usize>,
    /// Rock mass, kg (with `release`; a campaign's rocks have their blocks' masses).
    #[serde(default)]
    pub mass_kg: Option<f64>,
    /// Random seed (default: 0).
    #[serde(default)]
    pub seed: u64,
    /// Engine options.
    #[serde(default)]
    pub options: Options2d,
    /// Spacing of the envelope stations along x, m (default: 1).
    #[serde(default = "default_spacing")]
    pub envelope_spacing_m: f64,
    /// x of the vertical collectors, m (default: none).
    #[serde(default)]
    pub collectors_x_m: Vec<f64>,
    /// Directory that relative paths are resolved against (the scenario file's folder; not read from TOML).
    #[serde(skip)]
    pub base_dir: Option<PathBuf>,
    /// Where the scenario was read from, for messages (not read from TOML).
    #[serde(skip)]
    pub source: Option<String>,
}

/// A scenario checked and ready to run.
#[derive(Debug, Clone, PartialEq)]
pub struct ResolvedScenario {
    /// Profile and materials.
    pub slope: Slope2d,
    /// The materials by name, as resolved.
    pub materials: BTreeMap<String, Material2d>,
    /// The release of ranges, with the scenario's mass; for a campaign, the ranges its starts span and their mean
    /// mass (a description: the rocks start from `starts`).
    pub release: Release2d,
    /// A campaign's rock starts, one per rock (each run `repeats` times in a row); empty for a release of ranges.
    pub starts: Vec<RockStart2d>,
    /// Number of rocks.
    pub rocks: usize,
    /// Engine options.
    pub options: Options2d,
    /// The bench geometry, when the profile is a benched slope.
    pub bench: Option<BenchGeometry>,
    /// Where the profile came from (`bench` or the CSV path).
    pub profile_source: String,
}

impl ProfileScenario {
    /// Reads a scenario file; relative paths in it are resolved against its folder.
    ///
    /// # Errors
    /// I/O errors, and TOML errors naming the file, the line and the key.
    pub fn load(path: &Path) -> Result<ProfileScenario> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        let mut s = ProfileScenario::from_toml_str(&text, &path.display().to_string())?;
        s.base_dir = path.parent().map(Path::to_path_buf);
        Ok(s)
    }

    /// Parses a scenario from TOML text; `source` names it in errors.
    ///
    /// # Errors
    /// TOML errors (syntax, unknown keys, wrong types) located as `source:line`.
    pub fn from_toml_str(text: &str, source: &str) -> Result<ProfileScenario> {
        let mut s: ProfileScenario = toml::from_str(text).map_err(|e| {
            crate::io::toml_error(
                text,
                source,
                &e,
                "check the key names and values against the profile scenario format (README, \"Other commands\": \
                 talus profile; examples/profile_bench.toml)",
            )
        })?;
        s.source = Some(source.to_string());
        Ok(s)
    }

    /// Checks everything and builds the slope, materials and release.
    ///
    /// # Errors
    /// The first problem found, naming the field (e.g. `materials.floor.rn`, `release.x_m`).
    pub fn resolve(&self) -> Result<ResolvedScenario> {
        let (profile, bench, profile_source) = match &self.profile {
            ProfileSource::Csv(p) => {
                let path = match &self.base_dir {
                    Some(d) if p.is_relative() => d.join(p),
                    _ => p.clone(),
                };
                (Profile::from_csv_path(&path)?, None, path.display().to_string())
            }
            ProfileSource::Bench(g) => {
                g.validate("profile.bench.")?;
                (Profile::from_bench(g)?, Some(g.clone()), "bench".to_string())
            }
        };
        let mut materials = BTreeMap::new();
        for (name, spec) in &self.materials {
            materials.insert(name.clone(), spec.resolve(&format!("materials.{name}"))?);
        }
        let slope = Slope2d::with_named_materials(profile, &materials)?;
        let (release, starts) = match (&self.release, &self.campaign) {
            (Some(spec), None) => (self.ranges(spec, slope.profile())?, Vec::new()),
            (None, Some(c)) => {
                for (key, given) in [("rocks", self.rocks.is_some()), ("mass_kg", self.mass_kg.is_some())] {
                    if given {
                        return Err(Error::invalid(
                            key,
                            "is given beside [campaign]",
                            "leave it out: a campaign releases its runs `repeats` times each, with their blocks' masses",
                        ));
                    }
                }
                let dir = match &self.base_dir {
                    Some(d) if c.dir.is_relative() => d.join(&c.dir),
                    _ => c.dir.clone(),
                };
                let starts = campaign_starts(&dir, c.repeats, slope.profile())?;
                (Release2d::spanning(&starts, slope.profile()), starts)
            }
            (Some(_), Some(_)) => {
                return Err(Error::invalid("release", "is given beside [campaign]", "give one of them"));
            }
            (None, None) => {
                return Err(Error::invalid(
                    "release",
                    "is missing",
                    "give [release] ranges with rocks and mass_kg, or a [campaign] folder",
                ));
            }
        };
        self.options.validate("options.")?;
        let (x0, x1) = slope.profile().x_range_m();
        if !(self.envelope_spacing_m.is_finite() && self.envelope_spacing_m > 0.0) {
            return Err(Error::invalid(
                "envelope_spacing_m",
                format!("must be a positive number of metres, got {}", self.envelope_spacing_m),
                "e.g. envelope_spacing_m = 1.0",
            ));
        }
        super::profile::check_station_count("envelope_spacing_m", self.envelope_spacing_m, x1 - x0, "")?;
        for (i, &x) in self.collectors_x_m.iter().enumerate() {
            if !(x >= x0 && x <= x1) {
                return Err(Error::invalid(
                    format!("collectors_x_m[{i}]"),
                    format!("{x} is outside the profile's x range [{x0}, {x1}]"),
                    "place collectors on the profile",
                ));
            }
        }
        let rocks = if starts.is_empty() { self.rocks.unwrap_or(0) } else { starts.len() };
        Ok(ResolvedScenario {
            slope,
            materials,
            release,
            starts,
            rocks,
            options: self.options.clone(),
            bench,
            profile_source,
        })
    }

    /// The release of ranges, checked against `profile`, with `rocks` and `mass_kg`.
    fn ranges(&self, spec: &ReleaseSpec, profile: &Profile) -> Result<Release2d> {
        let mass_kg = self
            .mass_kg
            .ok_or_else(|| Error::invalid("mass_kg", "is missing", "give the rock mass in kg, e.g. mass_kg = 1000"))?;
        if !(mass_kg.is_finite() && mass_kg > 0.0) {
            return Err(Error::invalid(
                "mass_kg",
                format!("must be a positive number of kilograms, got {mass_kg}"),
                "give the rock mass in kg, e.g. mass_kg = 1000",
            ));
        }
        match self.rocks {
            None => return Err(Error::invalid("rocks", "is missing", "give the number of rocks, e.g. rocks = 300")),
            Some(0) => return Err(Error::invalid("rocks", "must be at least 1", "e.g. rocks = 300")),
            Some(n) if n > crate::source::MAX_ROCKS => return Err(Error::invalid(
                "rocks",
                format!("{n} is more than the limit of {} rocks a run", crate::source::MAX_ROCKS),
                "give fewer rocks (--rocks or rocks), or split the ensemble into runs with different seeds (--seed)",
            )),
            Some(_) => {}
        }
        let release = Release2d {
            x_m: spec.x_m,
            height_m: spec.height_m,
            vx_mps: spec.vx_mps,
            vz_mps: spec.vz_mps,
            spin_radps: spec.spin_radps,
            mass_kg,
        };
        release.validate(profile, "release.")?;
        Ok(release)
    }
}

/// The starts of every run of the campaign in `dir`, in file order, each `repeats` times: its measured position
/// (x, z), velocity (vx, vz) and spin (`wy_radps`), and its block's mass.
///
/// # Errors
/// The campaign's own errors; `repeats` 0; a run off the profile's plane (y ≠ 0), outside its x range or below it.
fn campaign_starts(dir: &Path, repeats: usize, profile: &Profile) -> Result<Vec<RockStart2d>> {
    if repeats == 0 {
        return Err(Error::invalid("campaign.repeats", "must be at least 1", "e.g. repeats = 20"));
    }
    let campaign = Campaign::read_on(dir, Ground::Profile)?;
    let (x0, x1) = profile.x_range_m();
    let mut starts = Vec::new();
    for r in &campaign.releases {
        let [x, y, z] = r.position_m;
        let ground = profile.z_at(x).filter(|_| (x0..=x1).contains(&x));
        let problem = match ground {
            _ if y != 0.0 => Some(format!("has y = {y}: a profile campaign lies in the profile's plane")),
            None => Some(format!("starts at x = {x}, outside the profile [{x0}, {x1}]")),
            Some(g) if z < g - 1e-6 => Some(format!("starts at z = {z}, below the profile ({g} there)")),
            _ => None,
        };
        if let Some(message) = problem {
            return Err(Error::invalid(
                format!("{}: run {}", dir.join("release_points.csv").display(), r.trajectory_id),
                message,
                "check that the campaign and the profile share a frame",
            ));
        }
        let start = RockStart2d {
            x_m: x,
            z_m: z,
            vx_mps: r.velocity_mps[0],
            vz_mps: r.velocity_mps[2],
            spin_radps: r.spin_radps[1],
            mass_kg: campaign.blocks[&r.block_id].mass_kg,
        };
        starts.extend(std::iter::repeat_n(start, repeats));
    }
    Ok(starts)
}

#[cfg(test)]
mod tests {
    use super::*;

    const EXAMPLE: &str = include_str!("../../examples/profile_bench.toml");

    #[test]
    fn example_scenario_resolves() {
        let s = ProfileScenario::from_toml_str(EXAMPLE, "profile_bench.toml").unwrap();
        let r = s.resolve().unwrap();
        assert_eq!(r.slope.profile().material_names(), &["face".to_string(), "floor".to_string()]);
        assert!(r.bench.is_some());
    }

    /// `csv` and `[profile.bench]` together, or neither, are told in words at the `[profile]` line (serde's enum
    /// said "wanted exactly 1 element, more than 1 element"); each alone still reads.
    #[test]
    fn a_profile_with_both_sources_or_none_says_which_to_keep() {
        let read = |text: &str| ProfileScenario::from_toml_str(text, "s.toml").map(|s| s.profile);
        let e = read("materials = {}\n[profile]\ncsv = \"p.csv\"\n[profile.bench]\nn_benches = 2\n").unwrap_err();
        let e = e.to_string();
        assert!(e.starts_with("s.toml:2: ") && e.contains("exclude each other"), "{e}");
        assert!(e.contains("keep `csv`") && !e.contains("element"), "{e}");
        let e = read("materials = {}\n[profile]\n").unwrap_err().to_string();
        assert!(e.contains("neither `csv` nor `[profile.bench]`"), "{e}");
        let bench = read("materials = {}\n[profile.bench]\nn_benches = 2\n").unwrap();
        assert_eq!(bench, ProfileSource::Bench(BenchGeometry { n_benches: 2, ..Default::default() }));
        let s = ProfileScenario::from_toml_str("profile = { csv = \"p.csv\" }\nmaterials = {}\n", "s.toml").unwrap();
        assert_eq!(s.profile, ProfileSource::Csv("p.csv".into()));
        let e = ProfileScenario::from_toml_str("profile = 3\nmaterials = {}\n", "s.toml").unwrap_err().to_string();
        assert!(e.contains("`csv = \"profile.csv\"` or `[profile.bench]`"), "{e}");
    }

    #[test]
    fn unknown_keys_and_bad_values_are_named() {
        let bad = EXAMPLE.replace("seed = 42", "seed = 42\nsead = 1");
        let e = ProfileScenario::from_toml_str(&bad, "s.toml").unwrap_err().to_string();
        assert!(e.contains("sead") && e.contains("s.toml:"), "{e}");
        let bad = EXAMPLE.replace("x_m = [10.0, 10.5]", "x_m = [10.0, 1000.5]");
        let e = ProfileScenario::from_toml_str(&bad, "s.toml").unwrap().resolve().unwrap_err().to_string();
        assert!(e.contains("release.x_m"), "{e}");
        for key in ["rocks = 300\n", "mass_kg = 1000.0\n"] {
            let bad = EXAMPLE.replace(key, "");
            let e = ProfileScenario::from_toml_str(&bad, "s.toml").unwrap().resolve().unwrap_err().to_string();
            assert!(e.contains(key.split(' ').next().unwrap()) && e.contains("missing"), "{e}");
        }
        let bad = EXAMPLE.replace("[materials.floor]", "[materials.flor]");
        let e = ProfileScenario::from_toml_str(&bad, "s.toml").unwrap().resolve().unwrap_err().to_string();
        assert!(e.contains("materials.floor") && e.contains("flor"), "{e}");
        let bad = EXAMPLE.replace("switch_speed_mps = 0.5", "switch_speed_mps = 0.5\nswitch_speed = 1");
        let e = ProfileScenario::from_toml_str(&bad, "s.toml").unwrap_err().to_string();
        assert!(e.contains("switch_speed"), "{e}");
    }

    /// A `[campaign]` release starts every run `repeats` times from its measured state with its block's mass;
    /// it excludes `[release]`, `rocks` and `mass_kg`, and a run off the profile is named.
    #[test]
    fn a_campaign_release_starts_each_run_as_measured() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let write = |release: &str| {
            std::fs::write(d.join("release_points.csv"), release).unwrap();
            std::fs::write(d.join("block_metadata.csv"), "block_id,mass_kg,size_x_m,size_y_m,size_z_m\nb,500,1,1,1\n")
                .unwrap();
        };
        write("trajectory_id,x_m,z_m,vx_mps,vz_mps,block_id\nr1,10.2,200,1.5,0,b\nr2,10.4,200,2.0,0,b\n");
        let i = EXAMPLE.find("[release]").unwrap();
        let j = EXAMPLE[i..].find("\n[").map_or(EXAMPLE.len(), |k| i + k + 1);
        let without = format!("{}{}", &EXAMPLE[..i], &EXAMPLE[j..]);
        let without =
            without.lines().filter(|l| !l.starts_with("rocks") && !l.starts_with("mass_kg")).collect::<Vec<_>>();
        let base = without.join("\n");
        // `top`: keys before the first table; `table`: tables after the others.
        let scenario = |top: &str, table: &str| {
            let mut s = ProfileScenario::from_toml_str(&format!("{top}\n{base}\n{table}"), "s.toml").unwrap();
            s.base_dir = Some(d.to_path_buf());
            s.resolve()
        };
        let r = scenario("", "[campaign]\ndir = \".\"\nrepeats = 3\n").unwrap();
        assert_eq!((r.rocks, r.starts.len()), (6, 6));
        let (a, b) = (r.starts[2], r.starts[3]);
        assert_eq!([a.x_m, a.z_m, a.vx_mps, a.mass_kg, b.x_m, b.vx_mps], [10.2, 200.0, 1.5, 500.0, 10.4, 2.0]);
        let e = scenario("rocks = 5", "[campaign]\ndir = \".\"\n").unwrap_err().to_string();
        assert!(e.contains("rocks") && e.contains("[campaign]"), "{e}");
        let e = scenario("", "").unwrap_err().to_string();
        assert!(e.contains("release") && e.contains("missing"), "{e}");
        let e = ProfileScenario::from_toml_str(&format!("{EXAMPLE}\n[campaign]\ndir = \".\"\n"), "s.toml")
            .unwrap()
            .resolve()
            .unwrap_err()
            .to_string();
        assert!(e.contains("release") && e.contains("beside"), "{e}");
        write("trajectory_id,x_m,y_m,z_m,vx_mps,vz_mps,block_id\nr1,10.2,3,200,0,0,b\n");
        let e = scenario("", "[campaign]\ndir = \".\"\n").unwrap_err().to_string();
        assert!(e.contains("run r1") && e.contains("y = 3"), "{e}");
    }
}
