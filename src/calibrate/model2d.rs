//! The 2DLM engine as a calibration [`Model`] on a profile campaign: releases and rest points along the profile
//! (`x_m`, `z_m`; `y_m` absent or zero), the profile from `profile.csv`, each run started at its measured position
//! and velocity (vx, vz; spin from `wy_radps`), mass from its block.

use super::config::{CalibrationConfig, ModelKind};
use super::effects::EffectKind;
use super::impacts::{read_impacts, tangential_restitutions_as_tracked, Impact};
use super::measured::{Measured, MIN_BOUNCES_MEASURED};
use super::model::{MapFrame, Model, PathSummary, PathThinner, Prepared, Reading, Sim, SimEnd};
use super::params::{apply_mobility_2d, Candidate, Params, Region};
use super::rebound::{attach_tracks, rebound_meter, ReboundMeter};
use super::runs::{FieldRun, ReleaseGroups};
use super::scenario_file;
use crate::campaign::{Campaign, TrackPoint};
use crate::error::{Error, Result};
use crate::lumped2d::{
    simulate_rock, FlightPiece, FrictionAngle, ImpactEvent, Material2d, Options2d, PathObserver, PathPiece,
    PathRecorder, Profile, RockStart2d, Rotation, SlidePiece, Slope2d, StopReason, PFEIFFER_BOWEN_MPS,
};
use crate::random::{stream, TruncNormal};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The 2DLM engine bound to a profile campaign.
#[derive(Debug, Clone)]
pub struct Model2d {
    runs: Vec<FieldRun>,
    groups: ReleaseGroups,
    profile: Profile,
    materials: Vec<String>,
    options: Options2d,
    reading: Reading,
    /// The campaign folder and the profile file, for [`Model::scenario_files`] (`None` when built from parts).
    files: Option<(PathBuf, PathBuf)>,
    /// [`Model::input_notes`].
    notes: Vec<String>,
}

impl Model2d {
    /// Reads the profile and binds the runs of `campaign` to it; a release off the profile or more than a metre
    /// below it, and a rest point outside its x range, are refused ([`Campaign::check_release_points`],
    /// [`Campaign::check_rest_points`]).
    pub fn new(
        campaign: &Campaign,
        runs: Vec<FieldRun>,
        groups: ReleaseGroups,
        profile_file: &Path,
        cfg: &CalibrationConfig,
    ) -> Result<Model2d> {
        let profile = Profile::from_csv_path(profile_file)?;
        let (x0, x1) = profile.x_range_m();
        let ground = format!("the profile, whose x range is [{x0}, {x1}]");
        let high = campaign.check_release_points(|p| profile.z_at(p[0]).map(|z| p[2] - z), &ground)?;
        let mut model = Self::from_parts(runs, groups, profile, cfg.options2d.clone())?
            .with_release_attempts(cfg.release_attempts)
            .with_rest_noise(cfg.rest_noise_m);
        campaign.check_rest_points(|p| (x0..=x1).contains(&p[0]), &ground)?;
        model.files = Some((campaign.dir.clone(), profile_file.to_path_buf()));
        model.notes.extend(campaign.unobserved_note().into_iter().chain(high));
        Ok(model.with_tracks(&campaign.tracks, cfg.track_noise_m)?.with_bounce_reads(cfg.bounce_weight != Some(0.0)))
    }

    /// A model from a profile and options. For synthetic studies and tests.
    pub fn from_parts(
        runs: Vec<FieldRun>,
        groups: ReleaseGroups,
        profile: Profile,
        options: Options2d,
    ) -> Result<Model2d> {
        let (x0, x1) = profile.x_range_m();
        for r in &runs {
            if r.release_m[1] != 0.0 || r.rest_m[1] != 0.0 {
                return Err(Error::invalid(
                    format!("run {}", r.id),
                    "has a non-zero y in a profile campaign",
                    "give y_m = 0 (or leave the column out) for runs along a profile",
                ));
            }
            if !(r.release_m[0] >= x0 && r.release_m[0] <= x1) {
                return Err(Error::invalid(
                    format!("run {}", r.id),
                    format!("release x {} is outside the profile [{x0}, {x1}]", r.release_m[0]),
                    "check the campaign and the profile share a frame",
                ));
            }
        }
        let materials = profile.material_names().to_vec();
        let reading = Reading::for_runs(&runs);
        Ok(Model2d { runs, groups, profile, materials, options, reading, files: None, notes: Vec::new() })
    }

    /// The model measuring every simulated path's rebound height, or not (by default: if a run is tracked).
    pub fn with_rebounds(mut self, on: bool) -> Model2d {
        self.reading.rebounds = on;
        self
    }

    /// The model reading the bounces of the simulated paths of runs whose tracks show bounces with a tangential
    /// restitution, for the bounce score, or not (by default: if a run's track shows one).
    pub fn with_bounce_reads(mut self, on: bool) -> Model2d {
        self.reading.bounce_reads = on && self.runs.iter().any(FieldRun::has_tangential_bounce);
        self
    }

    /// The model with the tracked paths `tracks` (by run id, `x_m` along the profile) attached: each tracked run gets
    /// its observed rebound, above the same profile as the simulated ones, and its track times; with
    /// `track_noise_m` declared, simulated paths are read as the tracks were ([`ReboundMeter`]).
    ///
    /// # Errors
    /// A track has no point over the profile.
    pub fn with_tracks(
        mut self,
        tracks: &BTreeMap<String, Vec<TrackPoint>>,
        track_noise_m: Option<f64>,
    ) -> Result<Model2d> {
        self.reading.track_noise_m = track_noise_m;
        let profile = &self.profile;
        self.reading.rebounds |= attach_tracks(
            &mut self.runs,
            tracks,
            track_noise_m,
            |q| profile.z_at(q.position_m[0]).map_or(f64::NAN, |z| q.position_m[2] - z),
            |track, noise_m| profile_impacts(profile, track, noise_m),
        )?;
        Ok(self.with_bounce_reads(true))
    }

    /// The model with [`CalibrationConfig::release_attempts`] set (1 by [`Model2d::from_parts`]).
    pub fn with_release_attempts(mut self, attempts: usize) -> Model2d {
        self.reading.release_attempts = attempts;
        self
    }

    /// The model with [`CalibrationConfig::rest_noise_m`] set (none by [`Model2d::from_parts`]).
    pub fn with_rest_noise(mut self, rest_noise_m: Option<f64>) -> Model2d {
        self.reading.rest_noise_m = rest_noise_m;
        self
    }

    fn material(params: &Params, prefix: &str, m: f64) -> Result<Material2d> {
        let g = |n: &str| {
            params.get(&format!("{prefix}.{n}")).ok_or_else(|| {
                Error::invalid(
                    format!("{prefix}.{n}"),
                    "has no value",
                    "this is a bug in the calibration: please report it",
                )
            })
        };
        let (rn, rt, f) = apply_mobility_2d(g("rn_mean")?, g("rt_mean")?, g("friction_angle_deg")?, m);
        let mat = Material2d {
            rn: TruncNormal::three_sigma(rn, g("rn_sd")?, 0.0, 1.0),
            rt: TruncNormal::three_sigma(rt, g("rt_sd")?, 0.0, 1.0),
            friction: FrictionAngle::Given(TruncNormal::fixed(f.clamp(0.0, 89.9))),
            roughness_sd_deg: g("roughness_sd_deg")?.clamp(0.0, 30.0),
        };
        Ok(mat)
    }

    /// The profile with `zones` cut in as extra materials: vertices are added at the interval ends, and segments
    /// whose middle lies inside an interval take the zone's material.
    fn zoned_profile(&self, zones: &[(String, [f64; 2])]) -> Result<Profile> {
        if zones.is_empty() {
            return Ok(self.profile.clone());
        }
        let p = &self.profile;
        let mut xs: Vec<[f64; 2]> = (0..p.n_vertices()).map(|i| p.vertex(i)).collect();
        let mut seg_mat: Vec<usize> = p.segment_materials().to_vec();
        for (_, [a, b]) in zones {
            for cut in [*a, *b] {
                let mut k = 0;
                while k + 1 < xs.len() {
                    let (u, v) = (xs[k], xs[k + 1]);
                    if v[0] > u[0] && cut > u[0] + 1e-6 && cut < v[0] - 1e-6 {
                        let z = u[1] + (v[1] - u[1]) * (cut - u[0]) / (v[0] - u[0]);
                        xs.insert(k + 1, [cut, z]);
                        seg_mat.insert(k + 1, seg_mat[k]);
                        break;
                    }
                    k += 1;
                }
            }
        }
        let mut names = p.material_names().to_vec();
        for (label, [a, b]) in zones {
            names.push(label.clone());
            let idx = names.len() - 1;
            for k in 0..seg_mat.len() {
                let mid = 0.5 * (xs[k][0] + xs[k + 1][0]);
                if mid >= *a && mid <= *b {
                    seg_mat[k] = idx;
                }
            }
        }
        Profile::new(&xs, seg_mat, names, "profile with zones")
    }
}

struct Prepared2d<'a> {
    model: &'a Model2d,
    slope: Slope2d,
    options: Options2d,
}

impl Model for Model2d {
    fn kind(&self) -> ModelKind {
        ModelKind::Lumped2d
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

    fn input_notes(&self) -> &[String] {
        &self.notes
    }

    fn release_height_m(&self, run: &FieldRun) -> f64 {
        self.profile.z_at(run.release_m[0]).map(|z| run.release_m[2] - z).unwrap_or(0.0).max(0.0)
    }

    fn dominant_material(&self, region: &Region) -> String {
        let p = &self.profile;
        let mut length = vec![0.0; self.materials.len()];
        for k in 0..p.n_segments() {
            let (a, b) = (p.vertex(k), p.vertex(k + 1));
            if region.contains(0.5 * (a[0] + b[0]), 0.0) {
                length[p.segment_materials()[k]] += b[0] - a[0];
            }
        }
        let best = (0..length.len()).max_by(|&i, &j| length[i].total_cmp(&length[j]).then(j.cmp(&i))).unwrap_or(0);
        self.materials[best].clone()
    }

    fn map_frame(&self) -> MapFrame {
        let (x0, x1) = self.profile.x_range_m();
        MapFrame { dem: None, extent_m: [x0, -0.5, x1, 0.5], cell_m: ((x1 - x0) / 100.0).max(0.5), profile: true }
    }

    fn read_impacts(&self, track: &[TrackPoint], noise_m: f64) -> Vec<Impact> {
        profile_impacts(&self.profile, track, noise_m)
    }

    /// Rt of each material from the tangential restitutions of the observed bounces on it.
    fn measured_by_tracks(&self, which: &[usize]) -> Vec<Measured> {
        let mut rt: Vec<Vec<f64>> = vec![Vec::new(); self.materials.len()];
        for i in which.iter().flat_map(|&r| &self.runs[r].impacts) {
            if let Some(e) = i.tangential_restitution {
                rt[slope_at(&self.profile, i.position_m[0]).1].push(e);
            }
        }
        (self.materials.iter().zip(&rt))
            .filter(|(_, v)| v.len() >= MIN_BOUNCES_MEASURED)
            .map(|(m, v)| Measured::of(m, "rt_mean", v))
            .collect()
    }

    fn prepare<'a>(&'a self, candidate: &Candidate) -> Result<Box<dyn Prepared + 'a>> {
        let (profile, mats, options, _) = self.realize(candidate)?;
        let slope = Slope2d::new(profile, mats)?;
        Ok(Box::new(Prepared2d { model: self, slope, options }))
    }

    fn scenario_files(
        &self,
        candidate: &Candidate,
        repeats: usize,
        seed: u64,
        dir: &Path,
    ) -> Result<Vec<(String, String)>> {
        let Some((campaign, profile_file)) = &self.files else {
            return Ok(Vec::new());
        };
        let (profile, mats, options, zoned) = self.realize(candidate)?;
        scenario_file::lumped_mass_scenario(dir, campaign, profile_file, &profile, zoned, &mats, options, repeats, seed)
    }
}

impl Model2d {
    /// The profile with the candidate's zones cut in, its materials (in the profile's order) with the candidate's
    /// values, the engine options with its effects, and whether it has zones.
    fn realize(&self, candidate: &Candidate) -> Result<(Profile, Vec<Material2d>, Options2d, bool)> {
        let p = &candidate.params;
        let m = p.mobility();
        let mut options = self.options.clone();
        let mut zones = Vec::new();
        for e in &candidate.effects {
            match e.kind {
                EffectKind::SpeedRestitution => {
                    options.scale_rn_by_velocity = true;
                    options.rn_velocity_scale_mps = p.get_or(&format!("{}.k_mps", e.label), PFEIFFER_BOWEN_MPS);
                }
                EffectKind::MassRestitution => {
                    options.rn_mass_exponent = p.get_or(&format!("{}.exponent", e.label), 0.0);
                    options.rn_reference_mass_kg = p.get_or(&format!("{}.reference_kg", e.label), 1000.0);
                }
                EffectKind::CrspRotation => options.rotation = Rotation::Crsp,
                EffectKind::Zone => match &e.region {
                    Some(Region::Interval(iv)) => zones.push((e.label.clone(), *iv)),
                    _ => {
                        return Err(Error::invalid(
                            &e.label,
                            "a 2DLM zone needs an interval along the profile",
                            "this is a bug in the calibration: please report it",
                        ))
                    }
                },
                _ => {
                    return Err(Error::invalid(
                        &e.label,
                        format!("{:?} is not available in the 2DLM engine", e.kind),
                        "use --model 3drb for this effect",
                    ));
                }
            }
        }
        let profile = self.zoned_profile(&zones)?;
        let mut mats = Vec::new();
        for name in &self.materials {
            mats.push(Self::material(p, name, m)?);
        }
        for (label, _) in &zones {
            mats.push(Self::material(p, label, m)?);
        }
        Ok((profile, mats, options, !zones.is_empty()))
    }
}

impl Prepared for Prepared2d<'_> {
    fn path(&self, run: &FieldRun, repeat: usize, seed: u64) -> Vec<TrackPoint> {
        Model2d::track(&self.slope, &self.options, run, repeat, seed)
    }

    fn simulate(&self, run: &FieldRun, repeat: usize, seed: u64) -> Sim {
        let profile = self.slope.profile();
        let meter =
            self.model.reading.rebounds.then(|| rebound_meter(self.model.reading.track_noise_m, run, repeat, seed));
        let read_bounces = self.model.reading.bounce_reads && run.has_tangential_bounce();
        let mut obs = PathObserver2d::new(profile, meter, read_bounces);
        let r = simulate_run(&self.slope, &self.options, run, repeat, seed, &mut obs);
        let mut summary = obs.summary;
        summary.rebound_height_m = obs.rebound.map_or(0.0, ReboundMeter::finish);
        let total: f64 = summary.material_fraction.iter().sum();
        if total > 0.0 {
            summary.slope_mean_deg /= total;
            summary.gentle_fraction /= total;
            for f in summary.material_fraction.iter_mut() {
                *f /= total;
            }
        }
        if summary.impacts > 0 {
            summary.impact_speed_mean_mps /= summary.impacts as f64;
            summary.impact_angle_mean_deg /= summary.impacts as f64;
        }
        summary.end_slope_deg = slope_at(profile, r.end_x_m).0;
        if let Some(rec) = &obs.recorder {
            summary.tangential_restitutions =
                tangential_restitutions_as_tracked(self.model, run, repeat, seed, &track_of(rec));
        }
        // Zones add materials after the declared ones; fold them into the fraction vector as they are.
        let path = obs.thinner.finish(r.end_x_m, 0.0);
        Sim {
            runout_m: r.runout_m,
            rest_m: [r.end_x_m, 0.0, r.end_z_m],
            end: match r.stop_reason {
                StopReason::Stopped => SimEnd::Rest,
                StopReason::LeftProfile => SimEnd::LeftTerrain,
                StopReason::MaxEvents | StopReason::MaxTime => SimEnd::Limit,
            },
            summary,
            path,
        }
    }
}

/// Simulates `run` from its measured release state, with the random stream of its `repeat` under `seed`.
fn simulate_run(
    slope: &Slope2d,
    options: &Options2d,
    run: &FieldRun,
    repeat: usize,
    seed: u64,
    obs: &mut impl PathObserver,
) -> crate::lumped2d::RockResult2d {
    let mut rng = stream(seed, super::model::stream_index(run.index, repeat));
    let start = RockStart2d {
        x_m: run.release_m[0],
        z_m: run.release_m[2],
        vx_mps: run.velocity_mps[0],
        vz_mps: run.velocity_mps[2],
        spin_radps: run.spin_radps[1],
        mass_kg: run.mass_kg,
    };
    simulate_rock(slope, &start, options, &mut rng, obs)
}

impl Model2d {
    /// The path of every run under `candidate` (the same path as its simulation with `repeat` and `seed`), as a
    /// tracked path of `observed_trajectories.csv` gives it: the centre every 0.05 s of each flight and at both ends
    /// of each slide. Synthetic campaigns written to disk use it.
    ///
    /// # Errors
    /// The candidate does not fit the model.
    pub fn tracks(&self, candidate: &Candidate, repeat: usize, seed: u64) -> Result<Vec<Vec<TrackPoint>>> {
        let (profile, mats, options, _) = self.realize(candidate)?;
        let slope = Slope2d::new(profile, mats)?;
        Ok(self.runs.iter().map(|run| Self::track(&slope, &options, run, repeat, seed)).collect())
    }

    /// The path of one run on `slope` (see [`Model2d::tracks`]).
    fn track(slope: &Slope2d, options: &Options2d, run: &FieldRun, repeat: usize, seed: u64) -> Vec<TrackPoint> {
        let mut rec = PathRecorder::default();
        simulate_run(slope, options, run, repeat, seed, &mut rec);
        track_of(&rec)
    }
}

/// The recorded path as a track: the centre every 0.05 s of each flight and at both ends of each slide.
fn track_of(rec: &PathRecorder) -> Vec<TrackPoint> {
    let mut track: Vec<TrackPoint> = Vec::new();
    for piece in &rec.pieces {
        let samples: Vec<(f64, [f64; 2])> = match piece {
            PathPiece::Flight(f) => {
                let steps = (f.duration_s / 0.05).ceil().max(1.0) as usize;
                let dt_s = |i: usize| f.duration_s * i as f64 / steps as f64;
                (0..=steps).map(|i| (f.t0_s + dt_s(i), f.position_at(dt_s(i)))).collect()
            }
            PathPiece::Slide(s) => vec![(s.t0_s, s.position_at(0.0)), (s.t0_s + s.duration_s, s.end_position())],
            PathPiece::Impact(_) => Vec::new(),
        };
        // Pieces meet end to start: keep the time strictly increasing.
        for (time_s, [x, z]) in samples {
            if track.last().is_none_or(|q| time_s > q.time_s) {
                track.push(TrackPoint { time_s, position_m: [x, 0.0, z] });
            }
        }
    }
    track
}

/// The bounces of `track` (x along `profile`, z up) over the profile ([`read_impacts`]).
fn profile_impacts(profile: &Profile, track: &[TrackPoint], noise_m: f64) -> Vec<Impact> {
    read_impacts(track, noise_m, &|x, _| profile.z_at(x))
}

/// Slope (degrees) and material index of the profile at x (the first segment there).
fn slope_at(profile: &Profile, x: f64) -> (f64, usize) {
    let n = profile.n_segments();
    let k = profile.segments_at(x).start.min(n.saturating_sub(1));
    let (a, b) = (profile.vertex(k), profile.vertex(k + 1));
    let slope = (b[1] - a[1]).abs().atan2((b[0] - a[0]).abs()).to_degrees();
    (slope, profile.segment_materials()[k])
}

struct PathObserver2d<'a> {
    profile: &'a Profile,
    summary: PathSummary,
    thinner: PathThinner,
    /// The rebound height so far, if measured.
    rebound: Option<ReboundMeter<'a>>,
    /// The path's pieces, if its bounces are read.
    recorder: Option<PathRecorder>,
}

impl<'a> PathObserver2d<'a> {
    fn new(profile: &'a Profile, rebound: Option<ReboundMeter<'a>>, record: bool) -> Self {
        let summary =
            PathSummary { material_fraction: vec![0.0; profile.material_names().len()], ..Default::default() };
        let recorder = record.then(PathRecorder::default);
        PathObserver2d { profile, summary, thinner: PathThinner::default(), rebound, recorder }
    }

    /// Adds a horizontal stretch [x0, x1] of the path.
    fn stretch(&mut self, x0: f64, x1: f64) {
        let (lo, hi) = (x0.min(x1), x0.max(x1));
        if hi <= lo {
            return;
        }
        // Walk the segments under the stretch.
        let p = self.profile;
        for k in 0..p.n_segments() {
            let (a, b) = (p.vertex(k), p.vertex(k + 1));
            let (s0, s1) = (a[0].max(lo), b[0].min(hi));
            if s1 <= s0 {
                continue;
            }
            let len = s1 - s0;
            let slope = (b[1] - a[1]).abs().atan2((b[0] - a[0]).abs()).to_degrees();
            self.summary.slope_mean_deg += slope * len;
            if slope < 30.0 {
                self.summary.gentle_fraction += len;
            }
            self.summary.material_fraction[p.segment_materials()[k]] += len;
        }
        let steps = ((hi - lo) / 1.0).ceil() as usize;
        for i in 0..=steps {
            let x = x0 + (x1 - x0) * i as f64 / steps.max(1) as f64;
            self.thinner.offer(x, 0.0, 1.0);
        }
    }
}

impl PathObserver for PathObserver2d<'_> {
    fn flight(&mut self, piece: &FlightPiece) {
        if let Some(r) = &mut self.recorder {
            r.flight(piece);
        }
        let e = piece.end_position();
        self.stretch(piece.x0_m, e[0]);
        // The flight every 0.05 s and at its end (its apex is missed by at most g·0.025²/2 ≈ 3 mm).
        if let Some(rebound) = &mut self.rebound {
            let steps = (piece.duration_s / 0.05).ceil().max(1.0) as usize;
            for i in 0..=steps {
                let t = piece.duration_s * i as f64 / steps as f64;
                let [x, z] = piece.position_at(t);
                rebound.offer(piece.t0_s + t, self.profile.z_at(x).map_or(f64::NAN, |g| z - g));
            }
        }
    }

    fn slide(&mut self, piece: &SlidePiece) {
        if let Some(r) = &mut self.recorder {
            r.slide(piece);
        }
        let e = piece.end_position();
        self.stretch(piece.x0_m, e[0]);
        if let Some(rebound) = &mut self.rebound {
            rebound.offer(piece.t0_s, 0.0);
            rebound.offer(piece.t0_s + piece.duration_s, 0.0);
        }
    }

    fn impact(&mut self, ev: &ImpactEvent) {
        if let Some(r) = &mut self.recorder {
            r.impact(ev);
        }
        let p = self.profile;
        let k = ev.segment.min(p.n_segments().saturating_sub(1));
        let (a, b) = (p.vertex(k), p.vertex(k + 1));
        let len = (b[0] - a[0]).hypot(b[1] - a[1]).max(1e-12);
        let (t, n) = ([(b[0] - a[0]) / len, (b[1] - a[1]) / len], [-(b[1] - a[1]) / len, (b[0] - a[0]) / len]);
        let v = ev.velocity_in_mps;
        let vn = (v[0] * n[0] + v[1] * n[1]).abs();
        let vt = (v[0] * t[0] + v[1] * t[1]).abs();
        let s = &mut self.summary;
        s.impacts += 1;
        s.impact_speed_mean_mps += vn;
        s.impact_speed_max_mps = s.impact_speed_max_mps.max(vn);
        s.impact_angle_mean_deg += vn.atan2(vt).to_degrees();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibrate::params::EffectSpec;
    use crate::calibrate::synthetic::{synthetic_2d, truth_2d, write_profile_campaign, Synthetic2d};
    use crate::lumped2d::ProfileScenario;

    /// A lumped mass dropped 10 m onto level ground with Rn 0.5 rebounds to Rn² · 10 = 2.5 m, and a tracked path
    /// read from `observed_trajectories.csv` gives its run the rebound of the same definition over the same profile.
    #[test]
    fn rebound_heights_of_a_drop_and_of_a_tracked_path() {
        use crate::calibrate::synthetic::{material_params_2d, synthetic_profile};
        let profile = synthetic_profile(&[(1000.0, 0.0)]).unwrap();
        let ground = profile.z_at(50.0).unwrap();
        let mut run = crate::calibrate::metrics::tests::run(0, 0, 1.0);
        run.release_m = [50.0, 0.0, ground + 10.0];
        run.rest_m = [51.0, 0.0, ground];
        let model = Model2d::from_parts(
            vec![run.clone()],
            ReleaseGroups { names: vec!["g".into()], link_m: 0.0 },
            profile,
            Options2d::default(),
        )
        .unwrap()
        .with_rebounds(true);
        let c =
            Candidate { params: material_params_2d("ground", [0.5, 0.0, 0.8, 0.0, 30.0, 0.0]), effects: Vec::new() };
        let sim = model.prepare(&c).unwrap().simulate(&run, 0, 1);
        assert!((sim.summary.rebound_height_m - 2.5).abs() < 0.01, "{}", sim.summary.rebound_height_m);

        let spec = Synthetic2d::default();
        let dir = tempfile::tempdir().unwrap();
        write_profile_campaign(&spec, dir.path(), 0.0).unwrap();
        let campaign = Campaign::read(dir.path()).unwrap();
        let first = &campaign.releases[0];
        let profile = synthetic_profile(&spec.profile).unwrap();
        // Falls 0.5 m to the ground, rises 0.9 m, comes down to 0.3 m: rebound 0.9 m.
        let mut track = String::from("trajectory_id,time_s,x_m,z_m\n");
        for (k, h) in [0.5, 0.0, 0.9, 0.3, 0.3].iter().enumerate() {
            let x = first.position_m[0] + k as f64;
            track += &format!("{},{},{x},{}\n", first.trajectory_id, 0.1 * k as f64, profile.z_at(x).unwrap() + h);
        }
        std::fs::write(dir.path().join("observed_trajectories.csv"), track).unwrap();
        let campaign = Campaign::read(dir.path()).unwrap();
        let (runs, groups) = crate::calibrate::runs::field_runs(&campaign, 2.0, crate::terrain::UpAxis::Z).unwrap();
        let cfg = CalibrationConfig::default();
        let model = Model2d::new(&campaign, runs, groups, &dir.path().join("profile.csv"), &cfg).unwrap();
        let observed: Vec<Option<f64>> = model.runs().iter().map(|r| r.rebound_height_m).collect();
        assert!((observed[0].unwrap() - 0.9).abs() < 1e-9, "{observed:?}");
        assert!(observed[1..].iter().all(Option::is_none), "{observed:?}");
    }

    /// `calibrated_profile.toml` of a model with a zone the loop added and speed-dependent restitution: the zoned
    /// profile is written beside it, and read back as `talus profile` reads it, every segment has the calibrated
    /// material, the engine the calibrated options, and the rocks start as the field runs did, `repeats` each.
    #[test]
    fn the_calibrated_profile_scenario_holds_the_zoned_model() {
        let spec = Synthetic2d::default();
        let synth = synthetic_2d(&spec, Options2d::default()).unwrap();
        // The same campaign as files, as `talus calibrate` reads them.
        let dir = tempfile::tempdir().unwrap();
        write_profile_campaign(&spec, dir.path(), 0.0).unwrap();
        let profile_file = dir.path().join("profile.csv");
        let (runs, groups) = (synth.runs().to_vec(), synth.groups().clone());
        let campaign = Campaign::read(dir.path()).unwrap();
        let model = Model2d::new(&campaign, runs, groups, &profile_file, &CalibrationConfig::default()).unwrap();
        let mut c = truth_2d(&spec);
        let effect = |kind, label: &str, region| EffectSpec { kind, label: label.into(), material: None, region };
        c.effects.push(effect(EffectKind::Zone, "zone1", Some(Region::Interval([10.0, 20.0]))));
        c.effects.push(effect(EffectKind::SpeedRestitution, "speed", None));
        c.params.set("speed.k_mps", 7.0);
        for (k, v) in [("rn_mean", 0.1), ("rn_sd", 0.0), ("rt_mean", 0.5), ("rt_sd", 0.02)] {
            c.params.set(format!("zone1.{k}"), v);
        }
        c.params.set("zone1.friction_angle_deg", 40.0);
        c.params.set("zone1.roughness_sd_deg", 1.0);
        let out = dir.path().join("out");
        std::fs::create_dir_all(&out).unwrap();
        let files = model.scenario_files(&c, 2, 9, &out).unwrap();
        let names: Vec<&str> = files.iter().map(|f| f.0.as_str()).collect();
        assert_eq!(names, [scenario_file::PROFILE_SCENARIO, scenario_file::ZONED_PROFILE]);
        for (name, text) in &files {
            std::fs::write(out.join(name), text).unwrap();
        }
        let sc = ProfileScenario::load(&out.join(scenario_file::PROFILE_SCENARIO)).unwrap();
        assert_eq!((sc.campaign.as_ref().map(|c| c.repeats), sc.seed), (Some(2), 9));
        let read = sc.resolve().unwrap();
        assert_eq!(read.rocks, 2 * model.runs().len());
        for (k, r) in model.runs().iter().enumerate() {
            let s = &read.starts[2 * k + 1];
            let [vx, _, vz] = r.velocity_mps;
            let want = [r.release_m[0], r.release_m[2], vx, vz, r.spin_radps[1], r.mass_kg];
            assert_eq!([s.x_m, s.z_m, s.vx_mps, s.vz_mps, s.spin_radps, s.mass_kg], want, "{}", r.id);
        }
        let (profile, materials, options, zoned) = model.realize(&c).unwrap();
        assert!(zoned && options.scale_rn_by_velocity && options.rn_velocity_scale_mps == 7.0);
        assert_eq!(read.options, options);
        let p = read.slope.profile();
        assert_eq!((p.x_m(), p.n_segments()), (profile.x_m(), profile.n_segments()));
        for k in 0..p.n_segments() {
            let got = &read.slope.materials()[p.segment_materials()[k]];
            assert_eq!(got, &materials[profile.segment_materials()[k]], "segment {k}");
        }
        assert!(profile.material_names().contains(&"zone1".to_string()));
    }
}
