//! `talus barrier`: where to put a rockfall barrier, how long, how high and of which energy class, and what still
//! passes with it in place.
//!
//! 1. Candidate lines from the terrain ([`candidates`]): contour lines across the run-out zone, bench crests and
//!    toes of a pit, offsets of a toe or asset line.
//! 2. One run of the scenario with every candidate as a collector line (written to `DIR/without_barrier/`, a full
//!    `talus run` folder whose `collectors.csv` holds every candidate's stretches).
//! 3. Each candidate sized and ranked ([`design`]): length to intercept the target share of the rocks that would
//!    reach the protected zone, design height, design energy and class, cost.
//! 4. The best proposal put in the scenario as a barrier and the scenario run again with the same rocks
//!    (`DIR/with_barrier/`), and the residual compared with the run without it ([`residual`]).
//! 5. Tables, GeoJSON, maps and `DIR/index.html` ([`report`]).
//!
//! With several models of one site ([`propose_models`], `talus barrier --models`), steps 2 and 4 run once per model
//! (`DIR/models/NAME/without_barrier/`, `.../with_barrier/`) and step 3 sizes against all of them.

pub mod candidates;
pub mod classes;
pub mod contour;
pub mod design;
pub mod grid;
pub mod report;
pub mod residual;
pub mod settings;

pub use candidates::{Candidate, CandidateKind};
pub use design::{Assessment, Status};
pub use residual::Residual;
pub use settings::{AcrossModels, ClassEnergy, DesignSpec};

use crate::collector::{Collector, ProtectedZone};
use crate::error::{Error, Result};
use crate::run::{load_terrain, run_scenario_with, RunExtras, RunOutput, RunOverrides};
use crate::scenario::{BarrierSpec, Scenario};
use crate::terrain::frame::local_to_horizontal;
use crate::terrain::{horizontal_to_local, point_in_polygon, Terrain};
use std::path::Path;

/// One model's runs in a study.
#[derive(Debug, Clone)]
pub struct ModelStudy {
    /// The model's name (`scenario` for a study of one scenario).
    pub name: String,
    /// The run without the barrier (candidates as collectors).
    pub without: RunOutput,
    /// The run with the best proposal in place, if it was run.
    pub with: Option<RunOutput>,
    /// The residual, if re-run.
    pub residual: Option<Residual>,
}

/// Everything `talus barrier` found.
#[derive(Debug, Clone)]
pub struct BarrierStudy {
    /// The candidate lines.
    pub candidates: Vec<Candidate>,
    /// Their assessments, in candidate order (see `rank`).
    pub assessments: Vec<Assessment>,
    /// Each model's runs, in the order given (one for a study of one scenario).
    pub models: Vec<ModelStudy>,
    /// The barrier put in the scenario for the re-run (horizontal frame of the terrain files).
    pub barrier: Option<BarrierSpec>,
    /// Files written into the study folder (not counting the run folders).
    pub outputs: Vec<String>,
    /// With several models and `floor`: the same study against the first model run with as many seeds
    /// (`DIR/floor/`), what Monte Carlo noise alone asks for.
    pub floor: Option<Box<BarrierStudy>>,
}

impl BarrierStudy {
    /// The assessments ranked, best first.
    pub fn ranked(&self) -> Vec<&Assessment> {
        let mut r: Vec<&Assessment> = self.assessments.iter().filter(|a| a.rank.is_some()).collect();
        r.sort_by_key(|a| a.rank);
        r
    }
}

/// Where a model's run of `kind` (`without_barrier`, `with_barrier`) goes: `DIR/kind` for one model,
/// `DIR/models/NAME/kind` for several.
pub fn run_folder(n_models: usize, name: &str, kind: &str) -> String {
    if n_models == 1 {
        kind.to_string()
    } else {
        format!("models/{name}/{kind}")
    }
}

/// The protected zone of the settings, in the local frame.
pub fn protected_zone(spec: &DesignSpec, terrain: &Terrain) -> Option<ProtectedZone> {
    let local = |pts: &[[f64; 2]]| pts.iter().map(|p| horizontal_to_local(terrain.up, &terrain.origin, *p)).collect();
    if !spec.asset_line.is_empty() {
        Some(ProtectedZone::Line(local(&spec.asset_line)))
    } else if !spec.asset_polygon.is_empty() {
        Some(ProtectedZone::Polygon(local(&spec.asset_polygon)))
    } else {
        None
    }
}

/// Refuses a protected zone with no part over the terrain: no point of the asset line (sampled about every
/// metre) or of the polygon's edge over it, and no terrain vertex inside the polygon.
///
/// # Errors
/// The zone lies off the terrain (coordinates in another frame, most likely), named by `field`.
fn check_zone_on_terrain(zone: &ProtectedZone, terrain: &Terrain, field: &str) -> Result<()> {
    let (key, pts, closed) = match zone {
        ProtectedZone::Line(p) => ("asset_line", p, false),
        ProtectedZone::Polygon(p) => ("asset_polygon", p, true),
    };
    let mut ring = pts.clone();
    if closed {
        ring.push(pts[0]);
    }
    let on_edge = terrain.surface.any_point_over(&ring, 1.0);
    let encloses = closed && terrain.surface.vertices().iter().any(|v| point_in_polygon(v.x, v.y, pts));
    if on_edge || encloses {
        return Ok(());
    }
    Err(Error::invalid(
        format!("{field}.{key}"),
        "no part of it lies over the terrain",
        "give it in the terrain's coordinates (the CRS of the DEM, or the mesh's x and y)",
    ))
}

/// The model `model` once per seed `seed`, `seed + 1`, ... (`n` of them, named `seed_S`): sized together, the
/// design that Monte Carlo noise alone asks for against `n` models, beside which a design against `n` calibrated
/// models is read (`talus barrier --floor`; ours, as `talus envelope --floor`).
fn seed_floor(model: &Scenario, seed: u64, n: usize) -> Vec<(String, Scenario)> {
    (crate::envelope::floor_seeds(seed, n).into_iter())
        .map(|(name, seed)| {
            let mut sc = model.clone();
            sc.file.simulation.seed = seed;
            (name, sc)
        })
        .collect()
}

/// Runs the whole study of one scenario into `out_dir`. `stage` is told what is being done; `progress` gets rocks
/// done / total.
pub fn propose(
    sc: &Scenario,
    overrides: &RunOverrides,
    out_dir: &Path,
    stage: &dyn Fn(&str),
    progress: &dyn Fn(usize, usize),
) -> Result<BarrierStudy> {
    propose_models(&[("scenario".to_string(), sc.clone())], overrides, out_dir, false, stage, progress)
}

/// Runs the whole study into `out_dir` with several models of one site: named scenarios that differ only in their
/// materials and engine settings (see [`crate::envelope::on_site`]); the first one's terrain, sources and
/// `[barrier_design]` are used. Each model runs the same rocks without and with the proposal; the sizing takes
/// them all ([`design::assess`]). With `floor` (and more than one model), the same study of the first model with
/// as many seeds (the first the models' seed) goes to `out_dir/floor/`. With several models, every one is checked
/// ([`crate::run::check_run`]) before anything runs or is written, so that a bad one leaves no run behind.
pub fn propose_models(
    models: &[(String, Scenario)],
    overrides: &RunOverrides,
    out_dir: &Path,
    floor: bool,
    stage: &dyn Fn(&str),
    progress: &dyn Fn(usize, usize),
) -> Result<BarrierStudy> {
    if models.len() > 1 {
        stage("checking the models");
        for (_, msc) in models {
            crate::run::check_run(msc, overrides)?;
        }
    }
    let sc = &models[0].1;
    let spec = &sc.file.barrier_design;
    let terrain = load_terrain(sc)?;
    for note in &terrain.notes {
        stage(&format!("warning: {note}"));
    }
    let zone = protected_zone(spec, &terrain);
    if let Some(z) = &zone {
        check_zone_on_terrain(z, &terrain, &format!("{}: barrier_design", sc.path.display()))?;
    }
    stage("finding candidate lines");
    let candidates = candidates::candidates(&terrain, spec, sc.file.output.cell_size_m);
    if candidates.is_empty() {
        return Err(Error::invalid(
            format!("{}: barrier_design", sc.path.display()),
            "no candidate line was found on the terrain",
            "give a toe_line or asset_line with offsets_m, a smaller contour_interval_m, or a larger max_slope_deg",
        ));
    }
    let cand_cols: Vec<Collector> =
        candidates.iter().map(|c| Collector::new(c.name.clone(), c.line_m.clone(), spec.segment_m)).collect();
    let offset = crate::collector::scenario_collectors(&sc.file.collectors, &terrain)?.len();
    let n = models.len();
    let of_model = |name: &str| if n == 1 { String::new() } else { format!(" (model {name})") };

    let mut runs = Vec::new();
    let mut tallies = Vec::new();
    for (name, msc) in models {
        stage(&format!(
            "running without a barrier{}, {} candidate lines as collectors",
            of_model(name),
            cand_cols.len()
        ));
        let mut tally = design::Tally::new(&cand_cols, offset, zone.is_some());
        let extras = RunExtras { collectors: cand_cols.clone(), zone: zone.clone() };
        let dir = out_dir.join(run_folder(n, name, "without_barrier"));
        let without = run_scenario_with(msc, overrides, &dir, progress, &extras, &mut |_, r| tally.add(r, &cand_cols))?;
        // What the run noticed beyond the terrain's notes printed above (the sources', rocks leaving over gaps).
        for w in without.summary.warnings.iter().filter(|w| !terrain.notes.contains(w)) {
            stage(&format!("warning{}: {w}", of_model(name)));
        }
        runs.push(ModelStudy { name: name.clone(), without, with: None, residual: None });
        tallies.push(tally);
    }
    let model_runs: Vec<design::ModelRun> = runs
        .iter()
        .zip(&tallies)
        .map(|(r, tally)| design::ModelRun {
            name: &r.name,
            collectors: &r.without.collectors.collectors,
            stats: &r.without.collector_stats,
            tally,
        })
        .collect();
    let assessments = design::assess(&candidates, &model_runs, spec);

    let best = assessments.iter().filter(|a| a.rank.is_some()).min_by_key(|a| a.rank).cloned();
    let mut barrier = None;
    if let (Some(best), true) = (&best, spec.rerun) {
        let b = BarrierSpec {
            name: Some(format!("proposed: {}", best.name)),
            line: best.line_m.iter().map(|p| local_to_horizontal(terrain.up, &terrain.origin, *p)).collect(),
            height_m: best.fence_height_m,
            capacity_kj: best.class_kj.unwrap_or(best.energy_max_kj.max(1.0)),
        };
        let cand = cand_cols[best.candidate].clone();
        for ((name, msc), (run, tally)) in models.iter().zip(runs.iter_mut().zip(&tallies)) {
            stage(&format!("running again with the proposed barrier on {}{}", best.name, of_model(name)));
            let mut sc2 = msc.clone();
            sc2.file.barriers.push(b.clone());
            let barrier_index = sc2.file.barriers.len() - 1;
            let extras2 = RunExtras { collectors: vec![cand.clone()], zone: zone.clone() };
            let mut res = Residual::new(tally.reaching(best.candidate), zone.is_some(), best.from_m, best.to_m);
            let dir = out_dir.join(run_folder(n, name, "with_barrier"));
            let out = run_scenario_with(&sc2, overrides, &dir, progress, &extras2, &mut |_, r| {
                res.add(r, offset as u32, barrier_index as u32)
            })?;
            run.with = Some(out);
            run.residual = Some(res);
        }
        barrier = Some(b);
    }
    let floor = if floor && n > 1 {
        let seed = overrides.seed.unwrap_or(sc.file.simulation.seed);
        stage(&format!("the floor: model {} with seeds {seed} to {}", models[0].0, seed.wrapping_add(n as u64 - 1)));
        let o = RunOverrides { seed: None, ..overrides.clone() };
        let seeds = seed_floor(sc, seed, n);
        Some(Box::new(propose_models(&seeds, &o, &out_dir.join("floor"), false, stage, progress)?))
    } else {
        None
    };
    let mut study = BarrierStudy { candidates, assessments, models: runs, barrier, outputs: Vec::new(), floor };
    stage("writing tables, maps and index.html");
    study.outputs = report::write_study(out_dir, sc, &terrain, &study)?;
    Ok(study)
}
