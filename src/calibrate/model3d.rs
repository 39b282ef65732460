//! The 3DRB engine as a calibration [`Model`]: the campaign's blocks as rigid boxes on the terrain surface, each run
//! started from its measured release exactly as `talus run` starts a campaign source (position, velocity and spin
//! as measured, random orientation, lifted only if a vertex is buried; [`crate::source`]).

use super::config::{CalibrationConfig, LevelBeyond, ModelKind};
use super::effects::EffectKind;
use super::impacts::{read_impacts, tangential_restitutions_as_tracked};
use super::model::{MapFrame, Model, PathSummary, PathThinner, Prepared, Reading, Sim, SimEnd};
use super::params::{apply_mobility_3d, Candidate, Params, Region};
use super::rebound::{attach_tracks, rebound_meter, ReboundMeter};
use super::runs::{FieldRun, ReleaseGroups};
use super::scenario_file;
use crate::campaign::{Campaign, TrackPoint};
use crate::error::{Error, Result};
use crate::random::{stream, TruncNormal};
use crate::raster::Grid;
use crate::rock::RockBody;
use crate::scenario::{MaterialsBy, TerrainSpec, ZoneSpec};
use crate::sim::{simulate, Impact, Observer, Sample, SimParams, StopReason};
use crate::source::measured_release;
use crate::terrain::{Material, Terrain, UpAxis};
use nalgebra::Vector3;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The 3DRB engine bound to a campaign and a terrain.
#[derive(Debug, Clone)]
pub struct Model3d {
    runs: Vec<FieldRun>,
    groups: ReleaseGroups,
    materials: Vec<String>,
    terrain: Terrain,
    bodies: BTreeMap<String, RockBody>,
    sim: SimParams,
    dem: Option<Grid>,
    median_mass_kg: f64,
    reading: Reading,
    /// The files read (`None` when built from parts).
    files: Option<Files>,
    /// [`Model::input_notes`].
    notes: Vec<String>,
}

/// What a model read from files was read from: the campaign folder and the terrain as read, for
/// [`Model::scenario_files`], and the settings' name, to read them again levelled ([`Model3d::relevelled`]).
#[derive(Debug, Clone)]
struct Files {
    campaign_dir: PathBuf,
    spec: TerrainSpec,
    source: String,
}

/// The terrain as messages name it: `the terrain, which spans x [a, b] and y [c, d]`, its horizontal extent in the
/// campaign's (the files') frame.
fn terrain_extent(terrain: &Terrain) -> String {
    let (x0, y0, x1, y1) = terrain.surface.bounds_xy();
    let [a, b] = [[x0, y0], [x1, y1]].map(|[x, y]| terrain.to_file_frame(&Vector3::new(x, y, 0.0)));
    let (k, name) = match terrain.up {
        UpAxis::Z => (1, "y"),
        UpAxis::Y => (2, "z"),
    };
    let range = |i: usize| format!("[{}, {}]", a[i].min(b[i]), a[i].max(b[i]));
    format!("the terrain, which spans x {} and {name} {}", range(0), range(k))
}

impl Model3d {
    /// Reads the terrain file and builds the blocks of `campaign` for its `runs` (in the model's frame:
    /// [`super::runs::field_runs`] with the settings' up axis). `source` names the settings file in errors. A
    /// release not over the terrain or more than a metre below it, and a rest point not over it, are refused
    /// ([`Campaign::check_release_points`], [`Campaign::check_rest_points`]).
    pub fn new(
        campaign: &Campaign,
        runs: Vec<FieldRun>,
        groups: ReleaseGroups,
        terrain_file: &Path,
        cfg: &CalibrationConfig,
        source: &str,
    ) -> Result<Model3d> {
        let map = &cfg.terrain;
        // The file is read once: its names give the materials, its mesh the terrain, its grid (a DEM's) the map frame.
        let (mesh, dem) = crate::terrain::build::read_terrain_file(terrain_file)?;
        let stem = terrain_file.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        let rename = |n: &str| map.material_names.get(n).cloned().unwrap_or_else(|| n.to_string());
        let mut names: Vec<String> = match map.materials_by {
            MaterialsBy::Single => vec!["default".into()],
            MaterialsBy::Slope => vec!["face".into(), "floor".into()],
            MaterialsBy::Group => mesh.group_names.iter().map(|n| rename(n)).collect(),
            MaterialsBy::Material => mesh.material_names.iter().map(|n| rename(n)).collect(),
            MaterialsBy::File => vec![rename(&stem)],
        };
        for z in &map.zones {
            names.push(z.material.clone());
        }
        names.sort();
        names.dedup();
        let placeholder: Vec<Material> = names
            .iter()
            .map(|n| Material {
                name: n.clone(),
                cr: TruncNormal::fixed(0.3),
                static_friction_deg: 35.0,
                dynamic_friction_deg: 30.0,
                dynamic_friction_sd_deg: 0.0,
                drag_per_s: 0.0,
            })
            .collect();
        let spec = TerrainSpec {
            files: vec![terrain_file.to_path_buf()],
            up: map.up,
            crs_epsg: None,
            materials_by: map.materials_by,
            slope_face_deg: map.slope_face_deg,
            material_names: map.material_names.clone(),
            zones: map.zones.clone(),
            clip: map.clip.clone(),
            level_beyond: map.level_beyond.as_ref().and_then(LevelBeyond::polygon).cloned(),
        };
        let crs = dem.as_ref().map(|g| g.crs.clone()).unwrap_or_default();
        let mut terrain = crate::terrain::build::assemble_terrain(
            &[(terrain_file.to_path_buf(), mesh)],
            crs,
            &spec,
            &placeholder,
            Path::new(source),
        )?;
        terrain.grid_anchor_xy = dem.as_ref().map(|g| [g.x_min_m, g.y_max_m]);
        // The campaign's points first, so that a point off the terrain is named at its file line.
        let ground = terrain_extent(&terrain);
        let high = campaign.check_release_points(
            |p| {
                let q = terrain.from_file_frame(p);
                terrain.surface.height(q.x, q.y).map(|z| q.z - z)
            },
            &ground,
        )?;
        campaign.check_rest_points(
            |p| {
                let q = terrain.from_file_frame(p);
                terrain.surface.at(q.x, q.y).is_some()
            },
            &ground,
        )?;
        let mut bodies = BTreeMap::new();
        for (id, block) in &campaign.blocks {
            bodies.insert(id.clone(), campaign.body(block)?);
        }
        // The tracks in the runs' frame, talus's z-up axes, as the engine and every horizontal reading take them.
        let up = terrain.up;
        let tracks: BTreeMap<String, Vec<TrackPoint>> = campaign
            .tracks
            .iter()
            .map(|(id, track)| {
                let model_frame =
                    track.iter().map(|q| TrackPoint { position_m: up.to_internal(q.position_m).into(), ..*q });
                (id.clone(), model_frame.collect())
            })
            .collect();
        let mut model = Self::from_parts(runs, groups, terrain, bodies, cfg.simulation.clone(), dem)?
            .with_release_attempts(cfg.release_attempts)
            .with_rest_noise(cfg.rest_noise_m);
        model.files = Some(Files { campaign_dir: campaign.dir.clone(), spec, source: source.to_string() });
        model.notes.extend(campaign.unobserved_note().into_iter().chain(high));
        Ok(model.with_tracks(&tracks, cfg.track_noise_m)?.with_bounce_reads(cfg.bounce_weight.is_some_and(|w| w > 0.0)))
    }

    /// The model reading the bounces of the simulated paths of runs whose tracks show bounces with a tangential
    /// restitution, for the bounce score, or not (the default: a 3DRB model scores its bounces only where the
    /// settings give `bounce_weight`).
    pub fn with_bounce_reads(mut self, on: bool) -> Model3d {
        self.reading.bounce_reads = on && self.runs.iter().any(FieldRun::has_tangential_bounce);
        self
    }

    /// A model from a terrain already built (its materials name the calibrated materials), rock bodies by block
    /// id, and engine settings. For synthetic studies and tests.
    pub fn from_parts(
        runs: Vec<FieldRun>,
        groups: ReleaseGroups,
        terrain: Terrain,
        bodies: BTreeMap<String, RockBody>,
        sim: SimParams,
        dem: Option<Grid>,
    ) -> Result<Model3d> {
        for r in &runs {
            if !bodies.contains_key(&r.block_id) {
                return Err(Error::invalid(
                    format!("run {}", r.id),
                    format!("block '{}' has no body", r.block_id),
                    "list the block in block_metadata.csv",
                ));
            }
            let p = to_local(&terrain, r.release_m);
            if terrain.surface.at(p.x, p.y).is_none() {
                return Err(Error::invalid(
                    format!("run {}", r.trajectory_label()),
                    format!("release point {:?} is not over the terrain", r.release_m),
                    "check that the campaign and the terrain share a frame",
                ));
            }
        }
        let materials = terrain.materials.iter().map(|m| m.name.clone()).collect();
        let mut masses: Vec<f64> = runs.iter().map(|r| r.mass_kg).collect();
        masses.sort_by(|a, b| a.total_cmp(b));
        let median_mass_kg = masses.get(masses.len() / 2).copied().unwrap_or(100.0);
        let reading = Reading::for_runs(&runs);
        let notes = terrain.notes.clone();
        Ok(Model3d { runs, groups, materials, terrain, bodies, sim, dem, median_mass_kg, reading, files: None, notes })
    }

    /// The model with the tracked paths `tracks` (by run id, in the campaign's frame) attached: each tracked run gets
    /// its observed rebound, read on the same terrain as the simulated ones, and its track times; with
    /// `track_noise_m` declared, simulated paths are read as the tracks were ([`ReboundMeter`]).
    ///
    /// # Errors
    /// A track has no point over the terrain.
    pub fn with_tracks(
        mut self,
        tracks: &BTreeMap<String, Vec<TrackPoint>>,
        track_noise_m: Option<f64>,
    ) -> Result<Model3d> {
        self.reading.track_noise_m = track_noise_m;
        let terrain = &self.terrain;
        self.reading.rebounds |= attach_tracks(
            &mut self.runs,
            tracks,
            track_noise_m,
            |q| {
                let p = to_local(terrain, q.position_m);
                terrain.surface.height(p.x, p.y).map_or(f64::NAN, |z| p.z - z)
            },
            |track, noise_m| terrain_impacts(terrain, track, noise_m),
        )?;
        Ok(self)
    }

    /// The model with [`CalibrationConfig::release_attempts`] set (1 by [`Model3d::from_parts`]).
    pub fn with_release_attempts(mut self, attempts: usize) -> Model3d {
        self.reading.release_attempts = attempts;
        self
    }

    /// The model with [`CalibrationConfig::rest_noise_m`] set (none by [`Model3d::from_parts`]).
    pub fn with_rest_noise(mut self, rest_noise_m: Option<f64>) -> Model3d {
        self.reading.rest_noise_m = rest_noise_m;
        self
    }

    /// The model read again from its files with the ground levelled past `polygon` (`[terrain] level_beyond`, x, y
    /// in the terrain file's horizontal axes), for the same runs in the same order; `None` for a model built from
    /// parts, whose ground no settings shape.
    ///
    /// # Errors
    /// The files no longer read as they did, or no vertex of the terrain lies inside `polygon`.
    pub fn relevelled(&self, cfg: &CalibrationConfig, polygon: Vec<[f64; 2]>) -> Result<Option<Model3d>> {
        let Some(files) = &self.files else { return Ok(None) };
        let campaign = Campaign::read_on(&files.campaign_dir, crate::campaign::Ground::Terrain)?;
        let mut cfg = cfg.clone();
        cfg.terrain.level_beyond = Some(LevelBeyond::Polygon(polygon));
        let terrain_file = &files.spec.files[0];
        Model3d::new(&campaign, self.runs.clone(), self.groups.clone(), terrain_file, &cfg, &files.source).map(Some)
    }

    /// The terrain (with the placeholder materials it was built with).
    pub fn terrain(&self) -> &Terrain {
        &self.terrain
    }

    fn material(params: &Params, prefix: &str, name: &str, m: f64) -> Result<Material> {
        let g = |n: &str| {
            params.get(&format!("{prefix}.{n}")).ok_or_else(|| {
                Error::invalid(
                    format!("{prefix}.{n}"),
                    "has no value",
                    "this is a bug in the calibration: please report it",
                )
            })
        };
        let (cr, sd, s, d) =
            apply_mobility_3d(g("cr_mean")?, g("cr_sd")?, g("static_friction_deg")?, g("dynamic_friction_deg")?, m);
        Ok(Material {
            name: name.to_string(),
            cr: TruncNormal::three_sigma(cr, sd, 0.0, 1.0),
            static_friction_deg: s.clamp(0.0, 89.0),
            dynamic_friction_deg: d.clamp(0.0, 89.0),
            dynamic_friction_sd_deg: params.get_or(&format!("{prefix}.dynamic_friction_sd_deg"), 0.0),
            drag_per_s: params.get_or(&format!("{prefix}.drag_per_s"), 0.0),
        })
    }
}

impl FieldRun {
    /// The run's id, for messages.
    pub fn trajectory_label(&self) -> &str {
        &self.id
    }
}

struct Prepared3d<'a> {
    model: &'a Model3d,
    terrain: Terrain,
    sim: SimParams,
}

impl Model for Model3d {
    fn kind(&self) -> ModelKind {
        ModelKind::Rigid3d
    }

    fn runs(&self) -> &[FieldRun] {
        &self.runs
    }

    fn groups(&self) -> &ReleaseGroups {
        &self.groups
    }

    fn materials(&self) -> &[String] {
        &self.materials
    }

    fn reading(&self) -> &Reading {
        &self.reading
    }

    fn release_height_m(&self, run: &FieldRun) -> f64 {
        let p = to_local(&self.terrain, run.release_m);
        self.terrain.surface.height(p.x, p.y).map(|z| p.z - z).unwrap_or(0.0)
    }

    fn dominant_material(&self, region: &Region) -> String {
        let mut count = vec![0usize; self.materials.len()];
        for t in triangles_in(&self.terrain, region) {
            let m = self.terrain.triangle_material[t as usize] as usize;
            if m < count.len() {
                count[m] += 1;
            }
        }
        let best = (0..count.len()).max_by_key(|&k| (count[k], std::cmp::Reverse(k))).unwrap_or(0);
        self.materials[best].clone()
    }

    fn input_notes(&self) -> &[String] {
        &self.notes
    }

    fn levelled_by_settings(&self) -> bool {
        self.files.is_some()
    }

    fn relevelled(&self, cfg: &CalibrationConfig, polygon: Vec<[f64; 2]>) -> Result<Option<Box<dyn Model>>> {
        Ok(Model3d::relevelled(self, cfg, polygon)?.map(|m| Box::new(m) as Box<dyn Model>))
    }

    fn map_frame(&self) -> MapFrame {
        let (x0, y0, x1, y1) = self.terrain.surface.bounds_xy();
        let o = self.terrain.origin;
        let terrain_box = [x0 + o.x, y0 + o.y, x1 + o.x, y1 + o.y];
        let b = crate::terrain::bbox_xy(self.runs.iter().flat_map(|r| [r.release_m, r.rest_m]));
        let pad = 0.15 * (b[2] - b[0]).max(b[3] - b[1]) + 10.0;
        let extent = [
            (b[0] - pad).max(terrain_box[0]),
            (b[1] - pad).max(terrain_box[1]),
            (b[2] + pad).min(terrain_box[2]),
            (b[3] + pad).min(terrain_box[3]),
        ];
        let tri = self.terrain.triangle_material.len().max(1) as f64;
        let spacing = (2.0 * (x1 - x0) * (y1 - y0) / tri).sqrt();
        let base = self.dem.as_ref().map(|g| g.cell_x_m).unwrap_or(spacing);
        let cell = base.max((extent[2] - extent[0]).max(extent[3] - extent[1]) / 50.0);
        MapFrame { dem: self.dem.clone(), extent_m: extent, cell_m: cell, profile: false }
    }

    fn read_impacts(&self, track: &[TrackPoint], noise_m: f64) -> Vec<super::impacts::Impact> {
        terrain_impacts(&self.terrain, track, noise_m)
    }

    fn prepare<'a>(&'a self, candidate: &Candidate) -> Result<Box<dyn Prepared + 'a>> {
        let (terrain, sim, _) = self.realize(candidate)?;
        Ok(Box::new(Prepared3d { model: self, terrain, sim }))
    }

    fn scenario_files(
        &self,
        candidate: &Candidate,
        repeats: usize,
        seed: u64,
        dir: &Path,
    ) -> Result<Vec<(String, String)>> {
        let Some(files) = &self.files else {
            return Ok(Vec::new());
        };
        let (terrain, sim, zones) = self.realize(candidate)?;
        let text = scenario_file::rigid_body_scenario(
            dir,
            &files.campaign_dir,
            &files.spec,
            &terrain.materials,
            zones,
            sim,
            repeats,
            seed,
        )?;
        Ok(vec![(scenario_file::RUN_SCENARIO.to_string(), text)])
    }
}

/// The triangles of `terrain` whose centre lies in `region`: near enough the ground a zone there takes (it splits the
/// triangles its edges cross, [`Terrain::paint_zone`]) to say which material it covers most.
fn triangles_in<'a>(terrain: &'a Terrain, region: &'a Region) -> impl Iterator<Item = u32> + 'a {
    (0..terrain.triangle_material.len() as u32).filter(move |&t| {
        let [a, b, c] = terrain.surface.corners(t);
        let centre = (a + b + c) / 3.0 + terrain.origin;
        region.contains(centre.x, centre.y)
    })
}

impl Model3d {
    /// The terrain with the candidate's materials (and zones), the engine settings with its effects, and the zones
    /// it adds as the scenario declares them.
    fn realize(&self, candidate: &Candidate) -> Result<(Terrain, SimParams, Vec<ZoneSpec>)> {
        let p = &candidate.params;
        let m = p.mobility();
        let mut terrain = self.terrain.clone();
        for (k, name) in self.materials.iter().enumerate() {
            terrain.materials[k] = Self::material(p, name, name, m)?;
        }
        let mut sim = self.sim.clone();
        let mut zones = Vec::new();
        let value = |label: &str, n: &str| {
            p.get(&format!("{label}.{n}")).ok_or_else(|| {
                Error::invalid(
                    format!("{label}.{n}"),
                    "has no value",
                    "this is a bug in the calibration: please report it",
                )
            })
        };
        for e in &candidate.effects {
            let fx = &mut sim.effects;
            match e.kind {
                EffectKind::SpeedRestitution => fx.speed_restitution_k_mps = Some(value(&e.label, "k_mps")?),
                EffectKind::AngleRestitution => fx.angle_restitution_exponent = Some(value(&e.label, "exponent")?),
                EffectKind::MassRestitution => {
                    fx.mass_restitution_exponent = Some(value(&e.label, "exponent")?);
                    fx.mass_reference_kg = Some(p.get_or(&format!("{}.reference_kg", e.label), self.median_mass_kg));
                }
                EffectKind::Roughness => fx.roughness_m = Some(value(&e.label, "rough_m")?),
                EffectKind::RollingResistance => fx.rolling_resistance = Some(value(&e.label, "mu_r")?),
                EffectKind::VegetationDrag => fx.vegetation_drag_kg_s = Some(value(&e.label, "c_kg_s")?),
                EffectKind::SlipFriction => fx.slip_friction_max_deg = Some(value(&e.label, "max_deg")?),
                EffectKind::ScarDrag => fx.scar_drag_coefficient = Some(value(&e.label, "coefficient")?),
                EffectKind::SoftDrag => {
                    fx.soft_drag_per_s = Some(value(&e.label, "rate_per_s")?);
                    fx.soft_materials = e.material.iter().cloned().collect();
                }
                EffectKind::Zone => {
                    let Some(region) = &e.region else {
                        return Err(Error::invalid(
                            &e.label,
                            "a zone without a region",
                            "this is a bug in the calibration: please report it",
                        ));
                    };
                    let Region::Polygon(polygon) = region else {
                        return Err(Error::invalid(
                            &e.label,
                            "a 3DRB zone needs a polygon",
                            "this is a bug in the calibration: please report it",
                        ));
                    };
                    // The scenario's zone in the files' horizontal axes, as a user gives polygons.
                    let files_polygon = polygon.iter().map(|&[x, y]| terrain.up.horizontal_of_internal(x, y));
                    zones.push(ZoneSpec { material: e.label.clone(), polygon: files_polygon.collect() });
                    terrain.materials.push(Self::material(p, &e.label, &e.label, m)?);
                    // As a scenario's [[terrain.zones]]: the zone ends exactly on its polygon.
                    let o = terrain.origin;
                    let local: Vec<[f64; 2]> = polygon.iter().map(|q| [q[0] - o.x, q[1] - o.y]).collect();
                    terrain.paint_zone(&local, (terrain.materials.len() - 1) as u16)?;
                }
                EffectKind::CrspRotation => {
                    return Err(Error::invalid(&e.label, "the CRSP rule is a 2DLM option", "use it with --model 2dlm"));
                }
            }
        }
        sim.effects.validate("effects.")?;
        for (k, mat) in terrain.materials.iter().enumerate() {
            mat.validate(&format!("materials.{}", terrain.materials[k].name))?;
        }
        terrain.friction = terrain.materials.iter().map(|m| (m.mu_static(), m.mu_dynamic())).collect();
        Ok((terrain, sim, zones))
    }

    /// The path of simulation `repeat` of every run under `seed` with `candidate`: a point every millisecond (time
    /// since release, centre of mass in the campaign's frame; [`TRACK_STEP_S`]), the same simulations as
    /// [`Prepared::simulate`]'s.
    ///
    /// # Errors
    /// The candidate cannot be realised.
    pub fn tracks(&self, candidate: &Candidate, repeat: usize, seed: u64) -> Result<Vec<Vec<TrackPoint>>> {
        let (terrain, sim, _) = self.realize(candidate)?;
        let prepared = Prepared3d { model: self, terrain, sim };
        Ok(self.runs.iter().map(|run| prepared.path(run, repeat, seed)).collect())
    }
}

/// A point of the model's frame (talus's z-up axes: the campaign's, turned for y-up files) in `terrain`'s local
/// frame.
fn to_local(terrain: &Terrain, p: [f64; 3]) -> Vector3<f64> {
    Vector3::from(p) - terrain.origin
}

/// A point of `terrain`'s local frame in the model's frame.
fn to_model(terrain: &Terrain, local: &Vector3<f64>) -> [f64; 3] {
    (local + terrain.origin).into()
}

/// The bounces of `track` (model frame) over `terrain` ([`read_impacts`], read in the local frame, each bounce's
/// position given back in the model's).
fn terrain_impacts(terrain: &Terrain, track: &[TrackPoint], noise_m: f64) -> Vec<super::impacts::Impact> {
    let local: Vec<TrackPoint> = track
        .iter()
        .map(|q| TrackPoint { time_s: q.time_s, position_m: to_local(terrain, q.position_m).into() })
        .collect();
    let mut impacts = read_impacts(&local, noise_m, &|x, y| terrain.surface.height(x, y));
    for imp in &mut impacts {
        imp.position_m = track[imp.point].position_m;
    }
    impacts
}

/// Time between the points of a recorded path, s: a tracking system's millisecond.
pub const TRACK_STEP_S: f64 = 0.001;

/// Between samples sent after every step ([`Observer::every_step`]) a gap longer than this is a free flight (contact
/// steps are the engine's `dt_s`, 2 ms by default; a flight sends a sample at least every 0.1 s), s.
const FLIGHT_STEP_S: f64 = 0.004;

/// The centre of mass `tau_s` into a free flight from `p0` at velocity `v0` (local frame, z up).
fn free_flight(p0: Vector3<f64>, v0: Vector3<f64>, tau_s: f64) -> Vector3<f64> {
    p0 + v0 * tau_s + Vector3::new(0.0, 0.0, -0.5 * crate::sim::GRAVITY_MPS2 * tau_s * tau_s)
}

/// Records a simulation's path in the campaign's frame as a tracking system would: a point every
/// [`TRACK_STEP_S`] from the first sample, whatever the engine's steps (up to 0.25 s in flight). Across a flight
/// step the point is the free flight from the step's start (exact: the engine flies analytically), across a
/// contact step of a few milliseconds it is linear between the step's ends.
struct PathRecorder3d<'a> {
    terrain: &'a Terrain,
    points: Vec<TrackPoint>,
    /// The last sample: time, s; centre and velocity (local frame).
    last: Option<(f64, Vector3<f64>, Vector3<f64>)>,
    /// Time of the first sample, s.
    start_s: f64,
}

impl<'a> PathRecorder3d<'a> {
    fn new(terrain: &'a Terrain) -> Self {
        PathRecorder3d { terrain, points: Vec::new(), last: None, start_s: 0.0 }
    }
}

impl Observer for PathRecorder3d<'_> {
    fn every_step(&self) -> bool {
        true
    }

    fn sample(&mut self, s: &Sample) {
        let Some((t0, p0, v0)) = self.last else {
            self.start_s = s.t_s;
            self.points.push(TrackPoint { time_s: s.t_s, position_m: to_model(self.terrain, &s.position_m) });
            self.last = Some((s.t_s, s.position_m, s.velocity_mps));
            return;
        };
        if s.t_s <= t0 {
            return;
        }
        loop {
            let t = self.start_s + self.points.len() as f64 * TRACK_STEP_S;
            if t > s.t_s {
                break;
            }
            let tau = t - t0;
            let p = if s.t_s - t0 > FLIGHT_STEP_S {
                free_flight(p0, v0, tau)
            } else {
                p0 + (s.position_m - p0) * (tau / (s.t_s - t0))
            };
            self.points.push(TrackPoint { time_s: t, position_m: to_model(self.terrain, &p) });
        }
        self.last = Some((s.t_s, s.position_m, s.velocity_mps));
    }
}

impl Prepared for Prepared3d<'_> {
    fn simulate(&self, run: &FieldRun, repeat: usize, seed: u64) -> Sim {
        if !(self.model.reading.bounce_reads && run.has_tangential_bounce()) {
            return self.simulate_observed(run, repeat, seed, &mut ());
        }
        let mut rec = PathRecorder3d::new(&self.terrain);
        let mut sim = self.simulate_observed(run, repeat, seed, &mut rec);
        sim.summary.tangential_restitutions =
            tangential_restitutions_as_tracked(self.model, run, repeat, seed, &rec.points);
        sim
    }

    fn path(&self, run: &FieldRun, repeat: usize, seed: u64) -> Vec<TrackPoint> {
        let mut rec = PathRecorder3d::new(&self.terrain);
        self.simulate_observed(run, repeat, seed, &mut rec);
        rec.points
    }
}

impl Prepared3d<'_> {
    /// [`Prepared::simulate`], with `extra` watching the engine too.
    fn simulate_observed(&self, run: &FieldRun, repeat: usize, seed: u64, extra: &mut impl Observer) -> Sim {
        let model = self.model;
        let terrain = &self.terrain;
        let body = &model.bodies[&run.block_id];
        let mut rng = stream(seed, super::model::stream_index(run.index, repeat));
        let p = to_local(&model.terrain, run.release_m);
        let (v, w) = (run.velocity_mps.into(), run.spin_radps.into());
        let start = measured_release(terrain, body, p, v, w, &mut rng, self.sim.terrain_edge_contacts);
        let meter =
            self.model.reading.rebounds.then(|| rebound_meter(self.model.reading.track_noise_m, run, repeat, seed));
        let mut obs = PathObserver3d::new(terrain, meter);
        let out = simulate(terrain, body, start, &self.sim, &mut rng, &mut (&mut obs, extra));
        let end = out.final_state.position_m;
        let d = end - start.position_m;
        let o = terrain.origin;
        let path = obs.thinner.finish(end.x + o.x, end.y + o.y);
        let mut summary = obs.summary;
        summary.rebound_height_m = obs.rebound.map_or(0.0, ReboundMeter::finish);
        let total = summary.material_fraction.iter().sum::<f64>();
        if total > 0.0 {
            summary.slope_mean_deg /= total;
            summary.gentle_fraction /= total;
            for f in summary.material_fraction.iter_mut() {
                *f /= total;
            }
        } else if let Some(g) = terrain.surface.at(p.x, p.y) {
            summary.slope_mean_deg = slope_deg(&g.normal);
            summary.gentle_fraction = if summary.slope_mean_deg < 30.0 { 1.0 } else { 0.0 };
        }
        if summary.impacts > 0 {
            summary.impact_speed_mean_mps /= summary.impacts as f64;
            summary.impact_angle_mean_deg /= summary.impacts as f64;
        }
        summary.end_slope_deg =
            terrain.surface.at(end.x, end.y).map(|g| slope_deg(&g.normal)).unwrap_or(summary.slope_mean_deg);
        Sim {
            runout_m: d.x.hypot(d.y),
            rest_m: to_model(terrain, &end),
            end: match out.stop_reason {
                // A calibration places no barrier; one that caught the rock would have stopped it.
                StopReason::Stopped | StopReason::Barrier => SimEnd::Rest,
                StopReason::LeftTerrain => SimEnd::LeftTerrain,
                StopReason::MaxTime => SimEnd::Limit,
            },
            summary,
            path,
        }
    }
}

fn slope_deg(n: &Vector3<f64>) -> f64 {
    n.z.abs().clamp(0.0, 1.0).acos().to_degrees()
}

/// Gathers the path summary while the engine runs.
struct PathObserver3d<'a> {
    terrain: &'a Terrain,
    last: Option<Vector3<f64>>,
    /// The last sample's time, s, and velocity, m/s (local frame).
    last_motion: Option<(f64, Vector3<f64>)>,
    summary: PathSummary,
    thinner: PathThinner,
    /// The rebound height so far, if measured.
    rebound: Option<ReboundMeter<'a>>,
}

impl<'a> PathObserver3d<'a> {
    fn new(terrain: &'a Terrain, rebound: Option<ReboundMeter<'a>>) -> Self {
        let summary = PathSummary { material_fraction: vec![0.0; terrain.materials.len()], ..Default::default() };
        PathObserver3d { terrain, last: None, last_motion: None, summary, thinner: PathThinner::default(), rebound }
    }
}

impl Observer for PathObserver3d<'_> {
    /// Every step where the rebound is measured: a flight is then read every millisecond from the step before it.
    fn every_step(&self) -> bool {
        self.rebound.is_some()
    }

    fn sample(&mut self, s: &Sample) {
        let x = s.position_m;
        let o = self.terrain.origin;
        self.thinner.offer(x.x + o.x, x.y + o.y, 1.0);
        if let Some(rebound) = &mut self.rebound {
            let height = |p: Vector3<f64>| self.terrain.surface.height(p.x, p.y).map_or(f64::NAN, |z| p.z - z);
            // Across a flight step (up to 0.25 s) the path is read every millisecond, as it is recorded
            // ([`PathRecorder3d`]): a bounce's apex lies between the step's ends.
            if let (Some(p0), Some((t0, v0))) = (self.last, self.last_motion) {
                if s.t_s - t0 > FLIGHT_STEP_S {
                    let mut t = t0 + TRACK_STEP_S;
                    while t < s.t_s {
                        rebound.offer(t, height(free_flight(p0, v0, t - t0)));
                        t += TRACK_STEP_S;
                    }
                }
            }
            rebound.offer(s.t_s, height(x));
        }
        if let Some(last) = self.last {
            let step = (x.x - last.x).hypot(x.y - last.y);
            if step > 0.0 {
                if let Some(g) = self.terrain.surface.at(x.x, x.y) {
                    let slope = slope_deg(&g.normal);
                    self.summary.slope_mean_deg += slope * step;
                    if slope < 30.0 {
                        self.summary.gentle_fraction += step;
                    }
                    let m = self.terrain.triangle_material[g.triangle as usize] as usize;
                    if let Some(f) = self.summary.material_fraction.get_mut(m) {
                        *f += step;
                    }
                }
            }
        }
        self.last = Some(x);
        self.last_motion = Some((s.t_s, s.velocity_mps));
    }

    fn impact(&mut self, i: &Impact) {
        let s = &mut self.summary;
        s.impacts += 1;
        s.impact_speed_mean_mps += i.approach_speed_mps;
        s.impact_speed_max_mps = s.impact_speed_max_mps.max(i.approach_speed_mps);
        s.impact_angle_mean_deg += i.impact_angle_deg;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibrate::{base_candidate, effects::EffectKind, params::EffectSpec, runs::field_runs};

    #[test]
    fn a_tracked_run_on_the_terrain_gets_its_observed_rebound_and_simulated_ones() {
        // The Tschamut campaign with one run tracked: 2 m above the ground at its release, on the ground 5 m
        // downhill, 1.5 m above it 10 m downhill, on the ground again: rebound 1.5 m, read on the same terrain.
        let shipped = Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/tschamut2014");
        let dir = tempfile::tempdir().unwrap();
        for f in ["release_points.csv", "observed_deposition.csv", "block_metadata.csv"] {
            std::fs::copy(shipped.join(f), dir.path().join(f)).unwrap();
        }
        let terrain_file = shipped.join("terrain_proxy.asc");
        let cfg = CalibrationConfig::default();
        let campaign = Campaign::read(dir.path()).unwrap();
        let (runs, groups) = field_runs(&campaign, cfg.group_link_m, UpAxis::Z).unwrap();
        let untracked = Model3d::new(&campaign, runs, groups, &terrain_file, &cfg, "test").unwrap();
        let first = &untracked.runs()[0];
        let [x0, y0, _] = first.release_m;
        let ground = |x: f64, y: f64| {
            let p = to_local(&untracked.terrain, [x, y, 0.0]);
            untracked.terrain.surface.height(p.x, p.y).unwrap() - p.z
        };
        let mut track = String::from("trajectory_id,time_s,x_m,y_m,z_m\n");
        for (k, (dy, h)) in [(0.0, 2.0), (-5.0, 0.0), (-10.0, 1.5), (-15.0, 0.0)].iter().enumerate() {
            let (x, y) = (x0, y0 + dy);
            track += &format!("{},{},{x},{y},{}\n", first.id, 0.5 * k as f64, ground(x, y) + h);
        }
        std::fs::write(dir.path().join("observed_trajectories.csv"), track).unwrap();
        let campaign = Campaign::read(dir.path()).unwrap();
        let (runs, groups) = field_runs(&campaign, cfg.group_link_m, UpAxis::Z).unwrap();
        let model = Model3d::new(&campaign, runs, groups, &terrain_file, &cfg, "test").unwrap();
        let run = &model.runs()[0];
        assert!((run.rebound_height_m.unwrap() - 1.5).abs() < 1e-6, "{:?}", run.rebound_height_m);
        assert!(model.runs()[1..].iter().all(|r| r.rebound_height_m.is_none()));
        // Simulated paths of a tracked campaign are measured too (an untracked one skips the work).
        let (c, _) = base_candidate(&model, &cfg);
        let rebound = |m: &Model3d| {
            (0..4).map(|k| m.prepare(&c).unwrap().simulate(run, k, 3).summary.rebound_height_m).fold(0.0, f64::max)
        };
        assert!(rebound(&model) > 0.0 && rebound(&untracked) == 0.0);
        // With the tracking noise declared (here 0) a simulated path is read at the track's four times only: it
        // never rebounds higher than read at every sample, and the simulation itself is unchanged.
        let read_cfg = CalibrationConfig { track_noise_m: Some(0.0), ..cfg.clone() };
        let (runs, groups) = field_runs(&campaign, cfg.group_link_m, UpAxis::Z).unwrap();
        let read = Model3d::new(&campaign, runs, groups, &terrain_file, &read_cfg, "test").unwrap();
        let (every, at_times) = (model.prepare(&c).unwrap(), read.prepare(&c).unwrap());
        let mut lower = 0;
        for k in 0..4 {
            let (a, b) = (every.simulate(run, k, 3), at_times.simulate(run, k, 3));
            assert!(b.summary.rebound_height_m <= a.summary.rebound_height_m + 1e-9);
            assert_eq!(a.runout_m, b.runout_m);
            lower += usize::from(b.summary.rebound_height_m < a.summary.rebound_height_m - 1e-6);
        }
        assert!(lower > 0, "four readings in 1.5 s should miss some apex");
        // A track without y_m lies at y = 0, off this terrain: an error naming the file and the run.
        let no_y = format!("trajectory_id,time_s,x_m,z_m\n{0},0,{x0},1500\n{0},1,{x0},1490\n", first.id);
        std::fs::write(dir.path().join("observed_trajectories.csv"), no_y).unwrap();
        let campaign = Campaign::read(dir.path()).unwrap();
        let (runs, groups) = field_runs(&campaign, cfg.group_link_m, UpAxis::Z).unwrap();
        let e = Model3d::new(&campaign, runs, groups, &terrain_file, &cfg, "test").unwrap_err().to_string();
        assert!(e.contains("observed_trajectories.csv, run") && e.contains("y_m"), "{e}");
    }

    /// `calibrated.toml` is the calibrated model: read back as `talus run` reads it, its terrain (with a zone the
    /// loop added) has the same materials triangle by triangle and its engine the same settings and effects; it
    /// names its files relative to its own folder.
    #[test]
    fn the_calibrated_scenario_runs_the_calibrated_model() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/tschamut2014");
        let mut cfg = CalibrationConfig::default();
        cfg.terrain.level_beyond =
            Some(LevelBeyond::Polygon(vec![[-40.0, 130.0], [185.0, 130.0], [185.0, 320.0], [-40.0, 320.0]]));
        let campaign = Campaign::read(&dir).unwrap();
        let (runs, groups) = field_runs(&campaign, cfg.group_link_m, UpAxis::Z).unwrap();
        let model = Model3d::new(&campaign, runs, groups, &dir.join("terrain_proxy.asc"), &cfg, "test").unwrap();
        let (mut c, _) = base_candidate(&model, &cfg);
        c.params.set("default.cr_mean", 0.27);
        c.params.set("default.dynamic_friction_sd_deg", 3.0);
        c.params.set("roughness.rough_m", 0.15);
        c.effects.push(EffectSpec {
            kind: EffectKind::Roughness,
            label: "roughness".into(),
            material: None,
            region: None,
        });
        for (k, v) in [("cr_mean", 0.1), ("cr_sd", 0.02), ("static_friction_deg", 40.0), ("dynamic_friction_deg", 35.0)]
        {
            c.params.set(format!("zone1.{k}"), v);
        }
        c.params.set("zone1.drag_per_s", 4.0);
        let zone = vec![[60.0, 140.0], [110.0, 140.0], [110.0, 180.0], [60.0, 180.0]];
        c.effects.push(EffectSpec {
            kind: EffectKind::Zone,
            label: "zone1".into(),
            material: None,
            region: Some(Region::Polygon(zone)),
        });
        // Written beside the campaign (under target/), so its files are named relative to it.
        let target = Path::new(env!("CARGO_MANIFEST_DIR")).join("target");
        std::fs::create_dir_all(&target).unwrap(); // absent when CARGO_TARGET_DIR points elsewhere
        let out = tempfile::tempdir_in(target).unwrap();
        let [(name, text)] = &model.scenario_files(&c, 3, 7, out.path()).unwrap()[..] else { panic!("one file") };
        assert_eq!(name, scenario_file::RUN_SCENARIO);
        assert!(
            text.contains("\"../../meshes/tschamut2014/terrain_proxy.asc\"")
                && !text.contains(env!("CARGO_MANIFEST_DIR")),
            "{text}"
        );
        let path = out.path().join("calibrated.toml");
        std::fs::write(&path, text).unwrap();
        let sc = crate::scenario::ScenarioFile::read(&path).unwrap().resolve(&path).unwrap();
        let terrain = crate::run::load_terrain(&sc).unwrap();
        let (want, sim, _) = model.realize(&c).unwrap();
        let names =
            |t: &Terrain| t.triangle_material.iter().map(|&i| t.materials[i as usize].clone()).collect::<Vec<_>>();
        assert_eq!(names(&terrain), names(&want), "{text}");
        assert!(terrain.triangle_material.iter().any(|&i| terrain.materials[i as usize].name == "zone1"), "{text}");
        assert_eq!(sc.file.simulation.params, sim, "{text}");
        assert_eq!(sim.effects.roughness_m, Some(0.15));
        assert_eq!(sc.file.simulation.seed, 7);
        assert_eq!(sc.file.sources[0].repeats, Some(3));
        // A model built from parts has no files to name: no scenario.
        let parts = Model3d::from_parts(
            Vec::new(),
            ReleaseGroups { names: Vec::new(), link_m: 0.0 },
            model.terrain.clone(),
            BTreeMap::new(),
            SimParams::default(),
            None,
        );
        assert!(parts.unwrap().scenario_files(&c, 3, 7, out.path()).unwrap().is_empty());
    }
}
