//! `talus calibrate`: fit a model to measured field runs, measure it on runs it never saw, and look for what it
//! lacks.
//!
//! 1. **Split**: calibration runs choose everything; held-out runs ([`split`]) only measure.
//! 2. **Population fit** ([`fit`]): Nelder–Mead ([`search`]) over each material's free parameters, minimising the
//!    distance between observed and simulated run-out distributions per release group ([`objective`]), with common
//!    random numbers ([`model`]).
//! 3. **Back-analysis** ([`backanalysis`]): each run's own value of each parameter, as mean ± sd per material.
//! 4. **Effects loop** ([`effects_loop`]): residual diagnosis ([`diagnose`], [`zone`], [`maps`]), effects proposed by
//!    their signature ([`effects`]), kept only when nested cross-validation shows a clear improvement.
//! 5. **Report** ([`report`]): the five metrics ([`metrics`]) of the baseline and the final model on both sets,
//!    with the scatter floor, parameters, diagnostics, plots and maps.
//! 6. **Cross-validation** ([`crossval`]): every run held out once (`--kfold`), repeated over seeds.
//!
//! [`synthetic`] makes campaigns with talus itself, with an effect switched on, to check that the loop finds it.

pub mod backanalysis;
pub mod config;
pub mod crossval;
pub mod diagnose;
pub mod effects;
#[path = "loop.rs"]
pub mod effects_loop;
pub mod fit;
pub mod impacts;
pub mod maps;
pub mod measured;
pub mod metrics;
pub mod model;
pub mod model2d;
pub mod model3d;
pub mod objective;
pub mod outputs;
pub mod params;
pub mod rebound;
pub mod report;
pub mod runs;
pub mod scenario_file;
pub mod search;
pub mod split;
pub mod stats;
pub mod synthetic;
pub mod zone;

pub use config::{CalibrationConfig, ModelKind};
pub use crossval::{cross_validate, repeated_cross_validation, CrossValidation, RepeatedCrossValidation};
pub use metrics::{Metrics, MetricsSet};
pub use model::{Model, RunSims};
pub use report::Report;

use crate::campaign::{Campaign, Ground};
use crate::error::{Error, Result};
use fit::Context;
use metrics::metrics_set;
use params::{Candidate, FreeParam, Params};
use std::path::Path;
use std::time::Instant;

/// Refuses a terrain surface given to 2DLM and a profile CSV given to 3DRB, by the file's extension, before the
/// campaign is read (whose columns would otherwise be blamed).
fn check_ground_file(file: &Path, kind: ModelKind) -> Result<()> {
    let is_csv = file.extension().is_some_and(|e| e.eq_ignore_ascii_case("csv"));
    let (what, fix) = match kind {
        ModelKind::Lumped2d if crate::terrain::build::is_terrain_file(file) => (
            "is a terrain surface: `--model 2dlm` runs on a profile CSV (x_m, z_m, material)",
            "give `--model 3drb` for this terrain, or cut a profile from it with `talus section`",
        ),
        ModelKind::Rigid3d if is_csv => (
            "is a CSV: `--model 3drb` runs on a terrain surface (OBJ, STL, GeoTIFF or ESRI ASCII DEM)",
            "give `--model 2dlm` for a profile CSV",
        ),
        _ => return Ok(()),
    };
    Err(Error::format(format!("{} (--terrain)", file.display()), what, fix))
}

/// Reads a campaign folder and binds it to the terrain (3DRB) or profile (2DLM) file.
pub fn open_model(
    campaign_dir: &Path,
    terrain_file: &Path,
    kind: ModelKind,
    cfg: &CalibrationConfig,
    source: &str,
) -> Result<Box<dyn Model>> {
    check_ground_file(terrain_file, kind)?;
    let ground = match kind {
        ModelKind::Rigid3d => Ground::Terrain,
        ModelKind::Lumped2d => Ground::Profile,
    };
    let campaign = Campaign::read_on(campaign_dir, ground)?;
    let up = match kind {
        ModelKind::Rigid3d => cfg.terrain.up,
        ModelKind::Lumped2d => crate::terrain::UpAxis::Z,
    };
    let (runs, groups) = runs::field_runs(&campaign, cfg.group_link_m, up)?;
    let model: Box<dyn Model> = match kind {
        ModelKind::Rigid3d => Box::new(model3d::Model3d::new(&campaign, runs, groups, terrain_file, cfg, source)?),
        ModelKind::Lumped2d => Box::new(model2d::Model2d::new(&campaign, runs, groups, terrain_file, cfg)?),
    };
    cfg.check_materials(kind, model.materials(), source)?;
    cfg.check_effects(kind, source)?;
    cfg.check_model_tables(kind, source)?;
    Ok(model)
}

/// The starting candidate (every material parameter at its start or fixed value, and the declared effects with
/// theirs) and the free parameters.
pub fn base_candidate(model: &dyn Model, cfg: &CalibrationConfig) -> (Candidate, Vec<FreeParam>) {
    let kind = model.kind();
    let mut params = Params::default();
    let mut free = Vec::new();
    let mut effects = Vec::new();
    for (name, s) in &cfg.effects.declared {
        let Some(def) = effects::by_name(kind, name) else { continue };
        let Some(param) = def.param else { continue };
        let key = format!("{name}.{param}");
        params.set(key.clone(), s.start());
        if let Some((min, max, _)) = s.bounds() {
            free.push(FreeParam { name: key, min, max });
        }
        effects.push(params::EffectSpec { kind: def.kind, label: name.clone(), material: None, region: None });
    }
    for m in model.materials() {
        for p in kind.material_parameters() {
            let Some(s) = cfg.used_setting(kind, m, p) else { continue };
            let name = format!("{m}.{p}");
            params.set(name.clone(), s.start());
            if let Some((min, max, _)) = s.bounds() {
                free.push(FreeParam { name, min, max });
            }
        }
    }
    params::normalize(&mut params);
    (Candidate { params, effects }, free)
}

/// A calibration's results, with the simulations behind the reported metrics.
#[derive(Debug, Clone)]
pub struct Calibration {
    /// The report.
    pub report: Report,
    /// Baseline simulations of the held-out runs (reported repeats).
    pub baseline_holdout: Vec<RunSims>,
    /// Final-model simulations of the held-out runs.
    pub final_holdout: Vec<RunSims>,
}

/// Calibrates `model` on runs `cal`, measures on `hold`, and (if `out` is given) writes the report there. `split`
/// says how the split was made; `log` receives progress lines.
pub fn calibrate(
    model: &dyn Model,
    cfg: &CalibrationConfig,
    cal: &[usize],
    hold: &[usize],
    split: &str,
    out: Option<&Path>,
    log: &(dyn Fn(&str) + Sync),
) -> Result<Calibration> {
    if cal.len() < 3 {
        return Err(Error::invalid(
            "calibration runs",
            format!("only {} runs to calibrate on", cal.len()),
            "hold out fewer runs",
        ));
    }
    // A library caller may not have come through `open_model`: an effect name it cannot use is an error here too.
    cfg.check_effects(model.kind(), "calibration settings")?;
    // `level_beyond = "field"`: the ground levelled past this calibration's own field box.
    let relevelled = match cfg.terrain.level_beyond {
        Some(config::LevelBeyond::Field) => {
            let polygon = report::field_box_m(model.runs(), cal, cfg.terrain.up);
            let m = model.relevelled(cfg, polygon.clone())?;
            log(&match m {
                Some(_) => report::levelled_note(&polygon),
                None => "note: level_beyond = \"field\" is for a 3DRB model read from files: unused".into(),
            });
            m.map(|m| (m, polygon))
        }
        _ => None,
    };
    let levelled_beyond_m = relevelled.as_ref().map(|(_, polygon)| polygon.clone());
    let model: &dyn Model = relevelled.as_ref().map_or(model, |(m, _)| m.as_ref());
    // Held-out release points take no part in the release groups the calibration sees.
    let (grouped, groups) = runs::calibration_groups(model.runs(), cal, model.groups().link_m);
    let regrouped = model::WithRuns::new(model, grouped, groups);
    let model: &dyn Model = &regrouped;
    let t0 = Instant::now();
    let mut cfg = cfg.clone();
    if cfg.rebound_weight.is_none() {
        cfg.rebound_weight = objective::default_rebound_weight(model.runs(), cal);
    }
    let spreads = objective::default_bounce_weight(model.runs(), cal);
    if !model.reads_bounces() {
        match (cfg.bounce_weight, spreads) {
            (Some(w), _) if w > 0.0 => log("note: bounce_weight is set but this model does not read its simulated bounces (no run's track shows a bounce with a tangential restitution, or a model built without them): it is unused"),
            (None, Some(w)) if model.kind() == ModelKind::Rigid3d => log(&format!("3DRB: the tracked bounces are not in the score by default; bounce_weight = {w:.1} (the ratio of the observed spreads) puts them there")),
            _ => {}
        }
        cfg.bounce_weight = Some(0.0);
    } else if cfg.bounce_weight.is_none() {
        cfg.bounce_weight = spreads;
    }
    let measured = measured::from_tracks(&mut cfg, model, cal);
    for m in &measured {
        log(&format!(
            "{}.{}: {:.3} from the tracks (median of {} bounces on it, quartiles {:.3}-{:.3}){}",
            m.material,
            m.parameter,
            m.value,
            m.bounces,
            m.quartiles[0],
            m.quartiles[1],
            if m.fixed { ", fixed there" } else { ", not fixed" }
        ));
    }
    let tracked = cal.iter().filter(|&&i| model.runs()[i].rebound_height_m.is_some()).count();
    let scatters: Vec<f64> = cal.iter().filter_map(|&i| model.runs()[i].track_scatter_m).collect();
    let track_scatter = (!scatters.is_empty()).then(|| stats::median(&scatters));
    let impact_summary = impacts::observed_summary(model, cal);
    if tracked > 0 {
        log(&format!(
            "{tracked} calibration runs were tracked: each one's rebound-height CRPS counts {:.1} m of run-out",
            cfg.rebound_weight.unwrap_or(0.0)
        ));
        if let Some(w) = cfg.bounce_weight.filter(|&w| w > 0.0) {
            log(&format!(
                "the mean tangential-restitution CRPS of a tracked run's bounces counts {w:.1} m of run-out (bounce_weight)"
            ));
        }
        if let Some(sd) = model.track_noise_m() {
            log(&format!("simulated paths are read at the tracks' times with {sd} m of tracking noise"));
        }
        if let Some(scatter) = track_scatter {
            let hint = if model.track_noise_m().is_none() && scatter >= rebound::TRACK_SCATTER_HINT_M {
                format!(
                    " (tracking noise raises observed rebounds: if it is that, declare track_noise_m = {scatter:.2} \
                     for a fair rebound score, and compare the fit with this one: docs/calibration.md, \"Tracked paths\")"
                )
            } else {
                String::new()
            };
            log(&format!(
                "the tracked heights scatter by {scatter:.3} m around a smooth path (median over runs){hint}"
            ));
        }
        if let Some(s) = &impact_summary {
            let en = match (s.normal_restitution_median, s.normal_restitution_iqr) {
                (Some(m), Some([a, b])) => {
                    format!(": normal restitution of the centre of mass {m:.2} (quartiles {a:.2}-{b:.2})")
                }
                _ => " (too few for a median restitution: flights too short for the tracks' sampling and noise)".into(),
            };
            let file = if s.n > 0 { " (impacts.csv)" } else { "" };
            log(&format!("{} bounces read from the tracks of {} calibration runs{en}{file}", s.n, s.paths));
        }
    } else if cfg.track_noise_m.is_some() {
        log("note: track_noise_m is set but no calibration run is tracked (observed_trajectories.csv): it is unused");
    }
    let cfg = &cfg;
    let ctx = Context::new(model, cfg, log);
    let runs = model.runs();
    let (start, free) = base_candidate(model, cfg);
    log(&format!("population fit of {} free parameters on {} runs", free.len(), cal.len()));
    let (baseline, search, searches) = fit::fit_population(&ctx, &start, &free, cal, "population fit");
    let t_fit = t0.elapsed().as_secs_f64();
    let back = if cfg.back_analysis.enabled {
        backanalysis::back_analyse(&ctx, &baseline, &free, cal)
    } else {
        Default::default()
    };
    let t_back = t0.elapsed().as_secs_f64();
    let lp = effects_loop::effects_loop(&ctx, &baseline, &free, cal)?;
    let t_loop = t0.elapsed().as_secs_f64();
    log("final evaluation");
    let final_c = lp.candidate.clone();
    // A model the loop diagnosed was simulated on the calibration runs as here: reuse those simulations.
    let diagnosed = |c: &Candidate| lp.rounds.iter().find(|r| r.candidate == *c);
    let cal_sims = |c: &Candidate| match diagnosed(c) {
        Some(r) => Ok(r.sims.clone()),
        None => ctx.sims(c, cal, cfg.repeats),
    };
    let base_cal = cal_sims(&baseline)?;
    let base_hold = if hold.is_empty() { Vec::new() } else { ctx.sims(&baseline, hold, cfg.repeats)? };
    let (final_cal, final_hold) = if final_c == baseline {
        (base_cal.clone(), base_hold.clone())
    } else {
        (cal_sims(&final_c)?, if hold.is_empty() { Vec::new() } else { ctx.sims(&final_c, hold, cfg.repeats)? })
    };
    let mut stalling = runs::runs_stalling(runs, &base_cal, "calibration");
    stalling.extend(runs::runs_stalling(runs, &base_hold, "holdout"));
    let mut not_started = runs::runs_not_started(runs, &base_cal);
    not_started.extend(runs::runs_not_started(runs, &base_hold));
    for id in &not_started {
        log(&format!(
            "warning: run {id}: every baseline simulation ends within {} m of its release; the field rock ran \
             farther (check its release state and the terrain there)",
            runs::NOT_STARTED_M
        ));
    }
    let mut bounces = Vec::new();
    let observed_hold = impacts::observed_summary(model, hold);
    for (set, which, observed) in [("calibration", cal, impact_summary), ("holdout", hold, observed_hold)] {
        if let Some(observed) = observed {
            let noise = model.track_noise_m();
            let read = |c: &Candidate| match diagnosed(c).and_then(|r| r.bounces.clone()) {
                Some(b) if set == "calibration" => Ok(b),
                _ => impacts::simulated_impacts(model, c, which, cfg.repeats, cfg.seed, noise, cfg.threads),
            };
            let baseline_b = read(&baseline)?;
            let final_b = if final_c == baseline { baseline_b.clone() } else { read(&final_c)? };
            let (mut baseline_ranks, mut final_ranks) = (Vec::new(), Vec::new());
            if set == "calibration" {
                baseline_ranks = impacts::bounce_ranks(runs, &baseline_b);
                final_ranks = impacts::bounce_ranks(runs, &final_b);
            }
            bounces.push(impacts::BounceComparison {
                set: set.into(),
                observed,
                baseline: impacts::simulated_summary(&baseline_b, cfg.repeats),
                final_model: impacts::simulated_summary(&final_b, cfg.repeats),
                baseline_ranks,
                final_ranks,
            });
        }
    }
    // The loop diagnosed the baseline (round 1) and a final model its last round kept nothing to; else here.
    let cal_bounces = bounces.iter().find(|b| b.set == "calibration");
    let diagnostics = |c: &Candidate, sims: &[RunSims], ranks: Option<&Vec<impacts::BounceRanks>>| match diagnosed(c) {
        Some(r) => r.diagnostics.clone(),
        None => diagnose::merged(
            diagnose::diagnose(model, sims, cfg.effects.permutations, cfg.seed).1,
            ranks.map_or_else(Vec::new, |r| impacts::bounce_diagnostics(r, cfg.effects.permutations, cfg.seed)),
        ),
    };
    let diag_base = diagnostics(&baseline, &base_cal, cal_bounces.map(|b| &b.baseline_ranks));
    let diag_final = diagnostics(&final_c, &final_cal, cal_bounces.map(|b| &b.final_ranks));
    let frame = model.map_frame();
    // The loop's first round checked the baseline with the same draws when a zone was a candidate.
    let zc = match diagnosed(&baseline).and_then(|r| r.zone_check.clone()) {
        Some(z) => z,
        None => zone::zone_check(model, &base_cal, &frame, 199, cfg.seed.wrapping_add(1)),
    };
    let ids = |v: &[usize]| v.iter().map(|&i| runs[i].id.clone()).collect::<Vec<_>>();
    let labels = |c: &Candidate| c.effects.iter().map(|e| e.label.clone()).collect::<Vec<_>>();
    let release_groups = model
        .groups()
        .names
        .iter()
        .enumerate()
        .map(|(g, name)| report::GroupInfo {
            name: name.clone(),
            runs: runs.iter().filter(|r| r.group == g).count(),
            holdout: hold.iter().filter(|&&i| runs[i].group == g).count(),
        })
        .collect();
    let threads = crate::parallel::threads_used(cfg.threads);
    let mut report = Report {
        model: model.kind().as_str().into(),
        calibration_ids: ids(cal),
        holdout_ids: ids(hold),
        split: split.into(),
        release_groups,
        duplicate_runs: runs::duplicate_runs(runs),
        warnings: model.input_notes().to_vec(),
        levelled_beyond_m,
        runs_not_started: not_started,
        runs_stalling: stalling,
        baseline: report::Stage::new(
            baseline.params.clone(),
            labels(&baseline),
            metrics_set(runs, &base_cal),
            metrics_set(runs, &base_hold),
        ),
        final_stage: report::Stage::new(
            final_c.params.clone(),
            labels(&final_c),
            metrics_set(runs, &final_cal),
            metrics_set(runs, &final_hold),
        ),
        effects_added: lp.added.clone(),
        effects_tried: lp.trials.clone(),
        diagnostics: diag_base,
        diagnostics_final: diag_final,
        zone_check: Some((&zc).into()),
        track_scatter_m: track_scatter,
        bounces,
        measured_from_tracks: measured,
        back_analysis: back.rows,
        spread_profiles: back.spreads,
        population_fit: serde_json::json!({
            "objective": cfg.objective,
            "objective_m": search.f,
            "evaluations": search.evaluations,
            "free_parameters": free,
            "history_m": search.history,
            "searches": searches,
        }),
        timing: report::Timing {
            population_fit_s: t_fit,
            back_analysis_s: t_back - t_fit,
            effects_loop_s: t_loop - t_back,
            final_evaluation_s: 0.0,
            total_s: 0.0,
            simulations: 0,
            threads,
        },
        settings: cfg.resolved(model.kind()),
    };
    // Levelling past the field's points is suggested where the settings could level and do not.
    let field_box = (model.levelled_by_settings() && cfg.terrain.level_beyond.is_none())
        .then(|| report::field_box_m(model.runs(), cal, cfg.terrain.up));
    if let Some(w) =
        report::unrested_warning(&report.baseline.calibration, &report.final_stage.calibration, field_box.as_deref())
    {
        log(&format!("warning: {w}"));
        report.warnings.push(w);
    }
    let spread = diagnose::spread_check(runs, &final_cal);
    if let Some(w) = report::narrow_warning(&spread, cfg.repeats, cfg.rest_noise_m.is_some(), model.kind()) {
        log(&format!("warning: {w}"));
        report.warnings.push(w);
    }
    report.timing.total_s = t0.elapsed().as_secs_f64();
    report.timing.final_evaluation_s = report.timing.total_s - t_loop;
    report.timing.simulations = ctx.simulations.load(std::sync::atomic::Ordering::Relaxed);
    if let Some(dir) = out {
        crate::io::create_folder(dir)?;
        let scenario = model.scenario_files(&final_c, cfg.repeats, cfg.seed, dir)?;
        report::write_report(
            dir,
            &report,
            model,
            &base_cal,
            &final_cal,
            &base_hold,
            &final_hold,
            Some(&zc),
            &scenario,
        )?;
    }
    Ok(Calibration { report, baseline_holdout: base_hold, final_holdout: final_hold })
}
