//! The calibrated model as a scenario file: in 3DRB `talus calibrate` writes `calibrated.toml`, which `talus run`
//! reads as it is (re-running every field release) and which a user edits to map another slope with the
//! calibrated materials and effects; in 2DLM `calibrated_profile.toml` for `talus profile` (with
//! `calibrated_profile.csv` when the loop added a zone).

use crate::error::{Error, Result};
use crate::lumped2d::{
    CampaignRelease, DistSpec, FrictionAngle, FrictionMode, Material2d, Options2d, Profile, ProfileSource,
};
use crate::random::TruncNormal;
use crate::scenario::{MaterialSpec, TerrainSpec, ZoneSpec};
use crate::sim::SimParams;
use crate::terrain::Material;
use std::path::{Component, Path, PathBuf};

/// A scenario (TOML text) of the 3DRB model, to be written into the folder `dir`: the terrain as the calibration
/// read it with the zones the loop added, every material with its calibrated values, the engine settings with the
/// effects, and one campaign source releasing each field run `repeats` times. Files are named relative to `dir`
/// (see [`relative_path`]), so the file keeps working when the project folder holding both is moved or copied.
///
/// # Errors
/// A file or `dir` that cannot be found, or a value TOML cannot hold.
#[allow(clippy::too_many_arguments)]
pub fn rigid_body_scenario(
    dir: &Path,
    campaign: &Path,
    terrain: &TerrainSpec,
    materials: &[Material],
    zones: Vec<ZoneSpec>,
    sim: SimParams,
    repeats: usize,
    seed: u64,
) -> Result<String> {
    let mut terrain = terrain.clone();
    terrain.files = terrain.files.iter().map(|f| relative_path(f, dir)).collect::<Result<_>>()?;
    terrain.zones.extend(zones);
    let materials: toml::Table = materials
        .iter()
        .map(|m| {
            let spec = MaterialSpec {
                preset: None,
                cr_mean: Some(m.cr.mean),
                cr_sd: Some(m.cr.sd),
                cr_min: Some(m.cr.min),
                cr_max: Some(m.cr.max),
                static_friction_deg: Some(m.static_friction_deg),
                dynamic_friction_deg: Some(m.dynamic_friction_deg),
                dynamic_friction_sd_deg: Some(m.dynamic_friction_sd_deg),
                drag_per_s: Some(m.drag_per_s),
            };
            Ok((m.name.clone(), value(&spec)?))
        })
        .collect::<Result<_>>()?;
    let mut simulation = value(&sim)?;
    if let toml::Value::Table(t) = &mut simulation {
        t.insert("seed".into(), toml::Value::Integer(seed as i64));
    }
    let mut doc = toml::Table::new();
    doc.insert("title".into(), toml::Value::String(format!("calibrated on {}", folder_name(campaign))));
    doc.insert("terrain".into(), value(&terrain)?);
    doc.insert("materials".into(), toml::Value::Table(materials));
    // One campaign source (`SourceSpec`): each field run released `repeats` times from its measured state.
    let mut source = toml::Table::new();
    source.insert("name".into(), "campaign".into());
    source.insert("type".into(), "campaign".into());
    source.insert("campaign".into(), relative_path(campaign, dir)?.display().to_string().into());
    source.insert("repeats".into(), toml::Value::Integer(repeats as i64));
    doc.insert("sources".into(), toml::Value::Array(vec![toml::Value::Table(source)]));
    doc.insert("simulation".into(), simulation);
    let text = toml::to_string(&doc).map_err(|e| bug(e.to_string()))?;
    Ok(format!(
        "# The final model of `talus calibrate` as a scenario. `talus run THIS_FILE --out DIR` releases every field\n\
         # run {repeats} times (the same model as the calibration, with its own random numbers); replace [[sources]]\n\
         # (and [terrain]) to map another slope with these materials and effects. Paths are relative to this file.\n{text}"
    ))
}

/// The 3DRB scenario file name.
pub const RUN_SCENARIO: &str = "calibrated.toml";
/// The 2DLM scenario file name.
pub const PROFILE_SCENARIO: &str = "calibrated_profile.toml";
/// The profile with the loop's zones, written beside [`PROFILE_SCENARIO`] when there are zones.
pub const ZONED_PROFILE: &str = "calibrated_profile.csv";

/// The 2DLM model as files for `talus profile`, to be written into the folder `dir`: the scenario
/// ([`PROFILE_SCENARIO`]: every material of `profile` with its calibrated values in profile order, the engine
/// options with the effects, and the `campaign` as its release, each run `repeats` times from its measured state)
/// and, when `zoned` (the loop cut zones into the profile read from `profile_file`), that profile as
/// [`ZONED_PROFILE`].
///
/// # Errors
/// `campaign`, `profile_file` or `dir` cannot be found, or a value TOML cannot hold.
#[allow(clippy::too_many_arguments)]
pub fn lumped_mass_scenario(
    dir: &Path,
    campaign: &Path,
    profile_file: &Path,
    profile: &Profile,
    zoned: bool,
    materials: &[Material2d],
    options: Options2d,
    repeats: usize,
    seed: u64,
) -> Result<Vec<(String, String)>> {
    let dist = |d: &TruncNormal| DistSpec { mean: d.mean, sd: d.sd, min: Some(d.min), max: Some(d.max) };
    let materials: toml::Table = profile
        .material_names()
        .iter()
        .zip(materials)
        .map(|(name, m)| {
            let (friction, friction_angle_deg) = match &m.friction {
                FrictionAngle::Given(d) => (FrictionMode::Given, Some(dist(d))),
                FrictionAngle::FromRt => (FrictionMode::FromRt, None),
                FrictionAngle::Zero => (FrictionMode::Zero, None),
            };
            let spec = crate::lumped2d::MaterialSpec {
                preset: None,
                rn: Some(dist(&m.rn)),
                rt: Some(dist(&m.rt)),
                friction_angle_deg,
                friction: Some(friction),
                roughness_sd_deg: Some(m.roughness_sd_deg),
            };
            Ok((name.clone(), value(&spec)?))
        })
        .collect::<Result<_>>()?;
    let release = CampaignRelease { dir: relative_path(campaign, dir)?, repeats };
    let (csv, zoned_text) = if zoned {
        let mut text = Vec::new();
        profile.write_csv_to(&mut text).map_err(|e| Error::io(dir.join(ZONED_PROFILE), e))?;
        (PathBuf::from(ZONED_PROFILE), Some(String::from_utf8_lossy(&text).into_owned()))
    } else {
        (relative_path(profile_file, dir)?, None)
    };
    let mut doc = toml::Table::new();
    doc.insert("name".into(), format!("calibrated on {}", folder_name(campaign)).into());
    doc.insert("seed".into(), toml::Value::Integer(seed as i64));
    doc.insert("profile".into(), value(&ProfileSource::Csv(csv))?);
    doc.insert("materials".into(), toml::Value::Table(materials));
    doc.insert("campaign".into(), value(&release)?);
    doc.insert("options".into(), value(&options)?);
    let text = toml::to_string(&doc).map_err(|e| bug(e.to_string()))?;
    let scenario = format!(
        "# The final 2DLM model of `talus calibrate` as a profile scenario. `talus profile THIS_FILE --out DIR`\n\
         # releases every field run {repeats} times from its measured state (the same model as the calibration, with\n\
         # its own random numbers); replace `profile` and [campaign] (by [release] ranges with rocks and mass_kg)\n\
         # to run another slope with these materials and options. Paths are relative to this file.\n{text}"
    );
    let mut files = vec![(PROFILE_SCENARIO.to_string(), scenario)];
    files.extend(zoned_text.map(|t| (ZONED_PROFILE.to_string(), t)));
    Ok(files)
}

fn folder_name(p: &Path) -> String {
    p.file_name().unwrap_or(p.as_os_str()).to_string_lossy().into_owned()
}

/// `file` as a path relative to the folder `dir`, both as the file system resolves them (symbolic links and `..`
/// followed): `../../meshes/site/terrain.asc` for `meshes/site/terrain.asc` seen from `outputs/run`. Absolute when
/// the two share nothing but the root (a file on another disk, or an output folder under /tmp), where a chain of
/// `..` up to the root would break as soon as either moved.
///
/// # Errors
/// `file` or `dir` does not exist.
pub fn relative_path(file: &Path, dir: &Path) -> Result<PathBuf> {
    let file = std::fs::canonicalize(file).map_err(|e| Error::io(file, e))?;
    let dir = std::fs::canonicalize(dir).map_err(|e| Error::io(dir, e))?;
    let (f, d): (Vec<Component>, Vec<Component>) = (file.components().collect(), dir.components().collect());
    let shared = f.iter().zip(&d).take_while(|(a, b)| a == b).count();
    let rooted = |c: &Component| matches!(c, Component::Prefix(_) | Component::RootDir);
    if f[..shared].iter().all(rooted) {
        return Ok(file);
    }
    let up = std::iter::repeat_n(Component::ParentDir, d.len() - shared);
    Ok(up.chain(f[shared..].iter().copied()).collect())
}

/// `v` as TOML without its empty lists and tables (the defaults a reader fills in).
fn value<T: serde::Serialize>(v: &T) -> Result<toml::Value> {
    fn prune(v: &mut toml::Value) -> bool {
        match v {
            toml::Value::Table(t) => {
                t.retain(|_, x| !prune(x));
                t.is_empty()
            }
            toml::Value::Array(a) => a.is_empty(),
            _ => false,
        }
    }
    let mut v = toml::Value::try_from(v).map_err(|e| bug(e.to_string()))?;
    prune(&mut v);
    Ok(v)
}

fn bug(message: String) -> Error {
    Error::invalid("calibrated.toml", message, "this is a bug in the calibration: please report it")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn files_are_named_relative_to_the_output_folder_unless_only_the_root_is_shared() {
        let root = tempfile::tempdir().unwrap();
        let site = root.path().join("meshes/site");
        let out = root.path().join("outputs/run");
        std::fs::create_dir_all(&site).unwrap();
        std::fs::create_dir_all(&out).unwrap();
        std::fs::write(site.join("terrain.asc"), "").unwrap();
        let rel = relative_path(&site.join("terrain.asc"), &out).unwrap();
        assert_eq!(rel, Path::new("../../meshes/site/terrain.asc"));
        assert!(out.join(&rel).is_file());
        // Through `..` in what is given, and from inside the file's own folder.
        assert_eq!(relative_path(&out.join("../../meshes/site"), &site).unwrap(), Path::new(""));
        assert_eq!(relative_path(&site, &root.path().join("meshes")).unwrap(), Path::new("site"));
        // Sharing only the root: absolute.
        let abs = relative_path(&site.join("terrain.asc"), Path::new("/")).unwrap();
        assert!(abs.is_absolute() && abs.ends_with("meshes/site/terrain.asc"), "{}", abs.display());
        let e = relative_path(&site.join("missing.asc"), &out).unwrap_err().to_string();
        assert!(e.contains("missing.asc"), "{e}");
    }
}
