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
//!
//! [`synthetic`] makes campaigns with talus itself, with an effect switched on, to check that the loop finds it.

pub mod backanalysis;
pub mod config;
pub mod diagnose;
pub mod effects;
#[path = "loop.rs"]
pub mod effects_loop;
pub mod fit;
pub mod maps;
pub mod metrics;
pub mod model;
pub mod model2d;
pub mod model3d;
pub mod objective;
pub mod params;
pub mod report;
pub mod runs;
pub mod search;
pub mod split;
pub mod stats;
pub mod synthetic;
pub mod zone;

pub use config::{CalibrationConfig, ModelKind};
pub use metrics::{Metrics, MetricsSet};
pub use model::{Model, RunSims};
pub use report::Report;

use crate::campaign::Campaign;
use crate::error::{Error, Result};
use fit::Context;
use metrics::metrics_set;
use params::{Candidate, FreeParam, Params};
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::time::Instant;

/// Reads a campaign folder and binds it to the terrain (3DRB) or profile (2DLM) file.
pub fn open_model(
    campaign_dir: &Path,
    terrain_file: &Path,
    kind: ModelKind,
    cfg: &CalibrationConfig,
    source: &str,
) -> Result<Box<dyn Model>> {
    let campaign = Campaign::read(campaign_dir)?;
    let (runs, groups) = runs::field_runs(&campaign, cfg.group_link_m)?;
    let model: Box<dyn Model> = match kind {
        ModelKind::Rigid3d => Box::new(model3d::Model3d::new(&campaign, runs, groups, terrain_file, cfg, source)?),
        ModelKind::Lumped2d => Box::new(model2d::Model2d::new(runs, groups, terrain_file, cfg)?),
    };
    cfg.check_materials(kind, model.materials(), source)?;
    cfg.check_effects(kind, source)?;
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
            let s = cfg.setting(kind, m, p);
            let name = format!("{m}.{p}");
            params.set(name.clone(), s.start());
            if let Some((min, max, _)) = s.bounds() {
                free.push(FreeParam { name, min, max });
            }
        }
    }
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
    let t0 = Instant::now();
    let ctx = Context::new(model, cfg, log);
    let runs = model.runs();
    let (start, free) = base_candidate(model, cfg);
    log(&format!("population fit of {} free parameters on {} runs", free.len(), cal.len()));
    let (baseline, search, searches) = fit::fit_population(&ctx, &start, &free, cal);
    let t_fit = t0.elapsed().as_secs_f64();
    let back =
        if cfg.back_analysis.enabled { backanalysis::back_analyse(&ctx, &baseline, &free, cal) } else { Vec::new() };
    let t_back = t0.elapsed().as_secs_f64();
    let lp = effects_loop::effects_loop(&ctx, &baseline, &free, cal)?;
    let t_loop = t0.elapsed().as_secs_f64();
    log("final evaluation");
    let final_c = lp.candidate.clone();
    let base_cal = ctx.sims(&baseline, cal, cfg.repeats)?;
    let base_hold = if hold.is_empty() { Vec::new() } else { ctx.sims(&baseline, hold, cfg.repeats)? };
    let (final_cal, final_hold) = if final_c == baseline {
        (base_cal.clone(), base_hold.clone())
    } else {
        (
            ctx.sims(&final_c, cal, cfg.repeats)?,
            if hold.is_empty() { Vec::new() } else { ctx.sims(&final_c, hold, cfg.repeats)? },
        )
    };
    let mut not_started = runs::runs_not_started(runs, &base_cal);
    not_started.extend(runs::runs_not_started(runs, &base_hold));
    for id in &not_started {
        log(&format!(
            "warning: run {id}: every baseline simulation ends within {} m of its release; the field rock ran \
             farther (check its release state and the terrain there)",
            runs::NOT_STARTED_M
        ));
    }
    let (_, diag_final) = diagnose::diagnose(model, &final_cal, cfg.effects.permutations, cfg.seed);
    let diag_base = lp
        .diagnostics
        .first()
        .cloned()
        .unwrap_or_else(|| diagnose::diagnose(model, &base_cal, cfg.effects.permutations, cfg.seed).1);
    let frame = model.map_frame();
    let zc = zone::zone_check(model, &base_cal, &frame, 199, cfg.seed.wrapping_add(1));
    let ids = |v: &[usize]| v.iter().map(|&i| runs[i].id.clone()).collect::<Vec<_>>();
    let labels = |c: &Candidate| c.effects.iter().map(|e| e.label.clone()).collect::<Vec<_>>();
    let release_groups = model
        .group_names()
        .iter()
        .enumerate()
        .map(|(g, name)| report::GroupInfo {
            name: name.clone(),
            runs: runs.iter().filter(|r| r.group == g).count(),
            holdout: hold.iter().filter(|&&i| runs[i].group == g).count(),
        })
        .collect();
    let threads =
        if cfg.threads == 0 { std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1) } else { cfg.threads };
    let mut report = Report {
        model: model.kind().as_str().into(),
        calibration_ids: ids(cal),
        holdout_ids: ids(hold),
        split: split.into(),
        release_groups,
        duplicate_runs: runs::duplicate_runs(runs),
        runs_not_started: not_started,
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
        back_analysis: back,
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
    report.timing.total_s = t0.elapsed().as_secs_f64();
    report.timing.final_evaluation_s = report.timing.total_s - t_loop;
    report.timing.simulations = ctx.simulations.load(std::sync::atomic::Ordering::Relaxed);
    if let Some(dir) = out {
        report::write_report(dir, &report, model, &base_cal, &final_cal, &base_hold, &final_hold, Some(&zc))?;
    }
    Ok(Calibration { report, baseline_holdout: base_hold, final_holdout: final_hold })
}

/// One fold of an outer cross-validation.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct FoldSummary {
    /// Fold index.
    pub fold: usize,
    /// Held-out ids.
    pub holdout_ids: Vec<String>,
    /// Effects kept.
    pub effects_added: Vec<String>,
    /// Baseline held-out metrics.
    pub baseline_holdout: Metrics,
    /// Final held-out metrics.
    pub final_holdout: Metrics,
    /// Wall time, s.
    pub time_s: f64,
}

/// An outer k-fold cross-validation over all runs: every run is held out once.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct CrossValidation {
    /// `3drb` or `2dlm`.
    pub model: String,
    /// Folds.
    pub k: usize,
    /// Per fold.
    pub folds: Vec<FoldSummary>,
    /// Held-out metrics pooled over all folds (every run predicted by the fold that did not see it): baseline.
    pub baseline: MetricsSet,
    /// The same for the final models.
    #[serde(rename = "final")]
    pub final_set: MetricsSet,
    /// Wall time, s.
    pub total_s: f64,
}

/// Runs [`calibrate`] `k` times, each fold held out once, writing each fold's report to `out/fold_i/` and the
/// pooled summary to `out/cv_report.json` and `out/cv_report.md`.
pub fn cross_validate(
    model: &dyn Model,
    cfg: &CalibrationConfig,
    k: usize,
    out: &Path,
    log: &(dyn Fn(&str) + Sync),
) -> Result<CrossValidation> {
    let t0 = Instant::now();
    let runs = model.runs();
    let all: Vec<usize> = (0..runs.len()).collect();
    let fold_of = split::folds(runs, &all, k, cfg.seed, 100);
    let mut folds = Vec::new();
    let (mut base_pool, mut final_pool) = (Vec::new(), Vec::new());
    for f in 0..k {
        let t = Instant::now();
        let hold: Vec<usize> = all.iter().copied().filter(|&i| fold_of[i] == f).collect();
        let cal: Vec<usize> = all.iter().copied().filter(|&i| fold_of[i] != f).collect();
        log(&format!("fold {}/{k}: {} calibration runs, {} held out", f + 1, cal.len(), hold.len()));
        let dir = out.join(format!("fold_{}", f + 1));
        // The folds measure held-out errors; the back-analysis table comes from a single calibration.
        let mut fold_cfg = cfg.clone();
        fold_cfg.back_analysis.enabled = false;
        let cfg = &fold_cfg;
        let c = calibrate(
            model,
            cfg,
            &cal,
            &hold,
            &format!("outer {k}-fold cross-validation, fold {} (seed {})", f + 1, cfg.seed),
            Some(&dir),
            log,
        )?;
        folds.push(FoldSummary {
            fold: f + 1,
            holdout_ids: c.report.holdout_ids.clone(),
            effects_added: c.report.effects_added.iter().map(|e| e.label.clone()).collect(),
            baseline_holdout: c.report.baseline.holdout,
            final_holdout: c.report.final_stage.holdout,
            time_s: t.elapsed().as_secs_f64(),
        });
        base_pool.extend(c.baseline_holdout);
        final_pool.extend(c.final_holdout);
    }
    let cv = CrossValidation {
        model: model.kind().as_str().into(),
        k,
        folds,
        baseline: metrics_set(runs, &base_pool),
        final_set: metrics_set(runs, &final_pool),
        total_s: t0.elapsed().as_secs_f64(),
    };
    let json = serde_json::to_string_pretty(&cv)
        .map_err(|e| Error::invalid("cv_report.json", e.to_string(), "this is a bug: please report it"))?;
    crate::io::write_bytes_atomic(&out.join("cv_report.json"), json.as_bytes())?;
    crate::io::write_bytes_atomic(&out.join("cv_report.md"), cv_markdown(&cv).as_bytes())?;
    Ok(cv)
}

fn cv_markdown(cv: &CrossValidation) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let _ = writeln!(s, "# Outer {}-fold cross-validation ({})\n", cv.k, cv.model);
    let _ = writeln!(s, "Every run predicted once by the fold that did not see it; {:.0} s in all.\n", cv.total_s);
    let _ = writeln!(
        s,
        "| model, runs | n | runout_mae_m | runout_w1_m | coverage_90 | runout_bias_m | endpoint_mae_m | floor |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|");
    let row = |s: &mut String, l: &str, m: &Metrics| {
        let _ = writeln!(
            s,
            "| {l} | {} | {:.2} | {:.2} | {:.2} | {:+.2} | {:.2} | {:.2} |",
            m.runs,
            m.runout_mae_m,
            m.runout_w1_m,
            m.coverage_90,
            m.runout_bias_m,
            m.endpoint_mae_m,
            m.scatter_floor_mae_m
        );
    };
    for (name, set) in [("baseline", &cv.baseline), ("final", &cv.final_set)] {
        row(&mut s, name, &set.overall);
        for (b, m) in &set.by_block {
            row(&mut s, &format!("{name}, block {b}"), m);
        }
    }
    let _ = writeln!(s, "\n| fold | effects kept | baseline MAE | final MAE | time (s) |");
    let _ = writeln!(s, "|---|---|---|---|---|");
    for f in &cv.folds {
        let _ = writeln!(
            s,
            "| {} | {} | {:.2} | {:.2} | {:.0} |",
            f.fold,
            f.effects_added.join(", "),
            f.baseline_holdout.runout_mae_m,
            f.final_holdout.runout_mae_m,
            f.time_s
        );
    }
    s
}
