//! The calibrated model as a scenario file: `talus calibrate` writes `calibrated.toml`, which `talus run` reads as
//! it is (re-running every field release) and which a user edits to map another slope with the calibrated
//! materials and effects.

use crate::error::{Error, Result};
use crate::scenario::{MaterialSpec, TerrainSpec, ZoneSpec};
use crate::sim::SimParams;
use crate::terrain::Material;
use std::path::Path;

/// A scenario (TOML text) of the 3DRB model: the terrain as the calibration read it (paths made absolute) with
/// the zones the loop added, every material with its calibrated values, the engine settings with the effects, and
/// one campaign source releasing each field run `repeats` times.
///
/// # Errors
/// A path that cannot be made absolute, or a value TOML cannot hold.
pub fn rigid_body_scenario(
    campaign: &Path,
    terrain: &TerrainSpec,
    materials: &[Material],
    zones: Vec<ZoneSpec>,
    sim: SimParams,
    repeats: usize,
    seed: u64,
) -> Result<String> {
    let absolute = |p: &Path| std::path::absolute(p).map_err(|e| Error::io(p, e));
    let mut terrain = terrain.clone();
    terrain.files = terrain.files.iter().map(|f| absolute(f)).collect::<Result<_>>()?;
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
    doc.insert("title".into(), toml::Value::String(format!("calibrated on {}", campaign.display())));
    doc.insert("terrain".into(), value(&terrain)?);
    doc.insert("materials".into(), toml::Value::Table(materials));
    // One campaign source (`SourceSpec`): each field run released `repeats` times from its measured state.
    let mut source = toml::Table::new();
    source.insert("name".into(), "campaign".into());
    source.insert("type".into(), "campaign".into());
    source.insert("campaign".into(), absolute(campaign)?.display().to_string().into());
    source.insert("repeats".into(), toml::Value::Integer(repeats as i64));
    doc.insert("sources".into(), toml::Value::Array(vec![toml::Value::Table(source)]));
    doc.insert("simulation".into(), simulation);
    let text = toml::to_string(&doc).map_err(|e| bug(e.to_string()))?;
    Ok(format!(
        "# The final model of `talus calibrate` as a scenario. `talus run THIS_FILE --out DIR` releases every field\n\
         # run {repeats} times (the same model as the calibration, with its own random numbers); replace [[sources]]\n\
         # (and [terrain]) to map another slope with these materials and effects.\n{text}"
    ))
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
