//! Outer k-fold cross-validation over all runs (`talus calibrate --kfold`): every run held out once by a
//! [`calibrate`] that did not see it, the held-out errors pooled; and the study repeated over seeds.

use super::metrics::{metrics_set, Metrics, MetricsSet};
use super::model::RunSims;
use super::params::Params;
use super::report::{metrics_header, metrics_rows};
use super::runs::{assign_groups, FieldRun};
use super::{calibrate, runs, split, stats, CalibrationConfig, Model};
use crate::error::Result;
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::time::Instant;

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
    /// The final model's parameters, fitted without this fold's runs.
    #[serde(default)]
    pub parameters: Params,
    /// Held-out runs whose baseline simulations stall at the release ([`runs::runs_stalling`]).
    #[serde(default)]
    pub holdout_stalling: Vec<runs::StallingRun>,
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
    /// Held-out runs that no final simulation starts ([`runs::runs_not_started`]): the terrain or the recorded
    /// release state holds the rock, whatever the parameters.
    #[serde(default)]
    pub not_started: Vec<String>,
    /// The final held-out metrics over the other runs (`None` when every run starts), reported beside
    /// [`Self::final_set`], never instead of it: what the parameters score where the model can start the rock (ours).
    #[serde(default)]
    pub final_started: Option<MetricsSet>,
    /// Each final parameter across the folds ([`parameter_spread`]).
    #[serde(default)]
    pub parameters: Vec<ParameterSpread>,
    /// Wall time, s.
    pub total_s: f64,
}

/// One fitted parameter of the final models across the folds of a k-fold cross-validation (over repeats, every
/// fold of every repeat): how much the calibrated value moves when other runs are held out, and, over repeats,
/// with other random numbers. It is the spread of fits to overlapping subsets (a jackknife-like reading, ours),
/// not a confidence interval: a parameter the runs do not pin wanders, one they pin stays put.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParameterSpread {
    /// Parameter name, e.g. `default.cr_mean`.
    pub name: String,
    /// Per fold, in order; `None` where that fold's final model lacks it (an effect the fold did not keep).
    pub values: Vec<Option<f64>>,
    /// Mean over the folds that have it.
    pub mean: f64,
    /// Sample standard deviation over the folds that have it (0 for one).
    pub sd: f64,
    /// Smallest value.
    pub min: f64,
    /// Largest value.
    pub max: f64,
}

/// The spread of every parameter any of `fits` has, in name order.
pub fn parameter_spread<'a>(fits: impl IntoIterator<Item = &'a Params>) -> Vec<ParameterSpread> {
    let fits: Vec<&Params> = fits.into_iter().collect();
    let names: std::collections::BTreeSet<&String> = fits.iter().flat_map(|p| p.0.keys()).collect();
    names
        .into_iter()
        .map(|name| {
            let values: Vec<Option<f64>> = fits.iter().map(|p| p.get(name)).collect();
            let present: Vec<f64> = values.iter().flatten().copied().collect();
            ParameterSpread {
                name: name.clone(),
                mean: stats::mean(&present),
                sd: stats::sample_sd(&present),
                min: present.iter().copied().fold(f64::INFINITY, f64::min),
                max: present.iter().copied().fold(f64::NEG_INFINITY, f64::max),
                values,
            }
        })
        .collect()
}

/// The outer fold of every run: each release group's runs spread evenly over the `k` folds, or each release
/// cluster's of `fold_link_m` where that is set (stratified k-fold; the clusters ours).
pub fn fold_assignment(runs: &[FieldRun], cfg: &CalibrationConfig, k: usize) -> Vec<usize> {
    let all: Vec<usize> = (0..runs.len()).collect();
    let clustered = cfg.fold_link_m.map(|link_m| {
        let mut c = runs.to_vec();
        assign_groups(&mut c, link_m);
        c
    });
    split::folds(clustered.as_deref().unwrap_or(runs), &all, k, cfg.seed, 100)
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
    let fold_of = fold_assignment(runs, cfg, k);
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
            parameters: c.report.final_stage.parameters.clone(),
            holdout_stalling: c.report.runs_stalling.iter().filter(|r| r.set == "holdout").cloned().collect(),
            time_s: t.elapsed().as_secs_f64(),
        });
        base_pool.extend(c.baseline_holdout);
        final_pool.extend(c.final_holdout);
    }
    let (not_started, final_started) = started_only(runs, &final_pool);
    let parameters = parameter_spread(folds.iter().map(|f| &f.parameters));
    let cv = CrossValidation {
        model: model.kind().as_str().into(),
        k,
        folds,
        baseline: metrics_set(runs, &base_pool),
        final_set: metrics_set(runs, &final_pool),
        not_started,
        final_started,
        parameters,
        total_s: t0.elapsed().as_secs_f64(),
    };
    write_study(out, "cv_report", &cv, &cv_markdown(&cv))?;
    Ok(cv)
}

/// The runs of `pool` that no simulation starts, and the metrics of the others (`None` if there are none).
fn started_only(runs: &[FieldRun], pool: &[RunSims]) -> (Vec<String>, Option<MetricsSet>) {
    let not_started = runs::runs_not_started(runs, pool);
    if not_started.is_empty() {
        return (not_started, None);
    }
    let started: Vec<RunSims> = pool.iter().filter(|s| !not_started.contains(&runs[s.run].id)).cloned().collect();
    let set = metrics_set(runs, &started);
    (not_started, Some(set))
}

/// One held-out metric across the repeats of a k-fold cross-validation.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct MetricSpread {
    /// `all` or `block ID`, each followed by `, started` for the runs the model starts (only when some repeat
    /// has a run not started, [`CrossValidation::not_started`]).
    pub runs: String,
    /// A [`Metrics`] name, e.g. `runout_mae_m`.
    pub metric: String,
    /// Per repeat, pooled over its folds (final models).
    pub values: Vec<f64>,
    /// Their mean.
    pub mean: f64,
    /// Their sample standard deviation (0 for one repeat).
    pub sd: f64,
}

/// An outer k-fold cross-validation repeated with seeds `seed`, `seed + 1`, ...: other folds and other random
/// numbers each time, so the spread shows how much one k-fold estimate is a draw (repeated k-fold
/// cross-validation, Kim 2009, Comput. Stat. Data Anal. 53:3735).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RepeatedCrossValidation {
    /// `3drb` or `2dlm`.
    pub model: String,
    /// Folds of each repeat.
    pub k: usize,
    /// Seed of each repeat.
    pub seeds: Vec<u64>,
    /// Mean ± sd of the held-out metrics over the repeats.
    pub summary: Vec<MetricSpread>,
    /// Each final parameter across every fold of every repeat ([`parameter_spread`]).
    #[serde(default)]
    pub parameters: Vec<ParameterSpread>,
    /// Each repeat.
    pub repeats: Vec<CrossValidation>,
    /// Wall time, s.
    pub total_s: f64,
}

/// Runs [`cross_validate`] `cfg.outer_repeats` times, repeat r (from 0) with seed `cfg.seed + r` into
/// `out/repeat_{r+1}/`, and writes the spread to `out/cv_repeats.json` and `out/cv_repeats.md`.
pub fn repeated_cross_validation(
    model: &dyn Model,
    cfg: &CalibrationConfig,
    k: usize,
    out: &Path,
    log: &(dyn Fn(&str) + Sync),
) -> Result<RepeatedCrossValidation> {
    let t0 = Instant::now();
    let mut repeats = Vec::new();
    let seeds: Vec<u64> = (0..cfg.outer_repeats as u64).map(|r| cfg.seed.wrapping_add(r)).collect();
    for (r, &seed) in seeds.iter().enumerate() {
        log(&format!("repeat {}/{} of the {k}-fold cross-validation, seed {seed}", r + 1, seeds.len()));
        let cfg = CalibrationConfig { seed, ..cfg.clone() };
        repeats.push(cross_validate(model, &cfg, k, &out.join(format!("repeat_{}", r + 1)), log)?);
    }
    let mut summary = Vec::new();
    let blocks: Vec<String> = repeats[0].final_set.by_block.keys().cloned().collect();
    // Each scope's metrics per repeat: all runs, each block, and the same without the runs not started where a
    // repeat has any (a repeat without them counts its full figures there).
    let scope = |set: &MetricsSet, block: Option<&String>| block.map_or(set.overall, |b| set.by_block[b]);
    let mut scopes: Vec<(String, Vec<Metrics>)> = Vec::new();
    let with_started = repeats.iter().any(|cv| cv.final_started.is_some());
    for block in std::iter::once(None).chain(blocks.iter().map(Some)) {
        let name = block.map_or("all".to_string(), |b| format!("block {b}"));
        scopes.push((name.clone(), repeats.iter().map(|cv| scope(&cv.final_set, block)).collect()));
        if with_started {
            let started = |cv: &CrossValidation| {
                let set = cv.final_started.as_ref().filter(|s| block.is_none_or(|b| s.by_block.contains_key(b)));
                scope(set.unwrap_or(&cv.final_set), block)
            };
            scopes.push((format!("{name}, started"), repeats.iter().map(started).collect()));
        }
    }
    for (runs, per_repeat) in scopes {
        let per_repeat: Vec<[(&str, f64); 9]> = per_repeat.iter().map(spread_metrics).collect();
        for (i, (metric, _)) in per_repeat[0].iter().enumerate() {
            let values: Vec<f64> = per_repeat.iter().map(|m| m[i].1).collect();
            let (mean, sd) = (stats::mean(&values), stats::sample_sd(&values));
            summary.push(MetricSpread { runs: runs.clone(), metric: metric.to_string(), values, mean, sd });
        }
    }
    let parameters = parameter_spread(repeats.iter().flat_map(|cv| cv.folds.iter().map(|f| &f.parameters)));
    let rcv = RepeatedCrossValidation {
        model: model.kind().as_str().into(),
        k,
        seeds,
        summary,
        parameters,
        repeats,
        total_s: t0.elapsed().as_secs_f64(),
    };
    write_study(out, "cv_repeats", &rcv, &repeats_markdown(&rcv))?;
    Ok(rcv)
}

/// Writes `out/STEM.json` and `out/STEM.md`.
fn write_study(out: &Path, stem: &str, study: &impl Serialize, markdown: &str) -> Result<()> {
    crate::io::write_json_atomic(&out.join(format!("{stem}.json")), study)?;
    crate::io::write_bytes_atomic(&out.join(format!("{stem}.md")), markdown.as_bytes())
}

/// The metrics whose spread [`repeated_cross_validation`] reports.
fn spread_metrics(m: &Metrics) -> [(&'static str, f64); 9] {
    [
        ("runout_mae_m", m.runout_mae_m),
        ("runout_w1_m", m.runout_w1_m),
        ("runout_w1_if_right_m", m.runout_w1_if_right_m),
        ("coverage_90", m.coverage_90),
        ("coverage_90_if_right", m.coverage_90_if_right),
        ("runout_bias_m", m.runout_bias_m),
        ("runout_bias_if_right_m", m.runout_bias_if_right_m),
        ("endpoint_mae_m", m.endpoint_mae_m),
        ("scatter_floor_mae_m", m.scatter_floor_mae_m),
    ]
}

fn repeats_markdown(r: &RepeatedCrossValidation) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let seeds: Vec<String> = r.seeds.iter().map(|x| x.to_string()).collect();
    let _ = writeln!(
        s,
        "# Outer {}-fold cross-validation repeated {} times ({})
",
        r.k,
        r.seeds.len(),
        r.model
    );
    let _ = writeln!(
        s,
        "Seeds {} (each repeat its own folds and random numbers; its report in `repeat_N/`); held-out metrics of \
         the final models pooled over each repeat's folds; {:.0} s in all.\n",
        seeds.join(", "),
        r.total_s
    );
    let _ = writeln!(
        s,
        "| runs | metric | {} | mean ± sd |",
        seeds.iter().map(|x| format!("seed {x}")).collect::<Vec<_>>().join(" | ")
    );
    let _ = writeln!(s, "|---|---|{}---|", "---|".repeat(seeds.len()));
    for m in &r.summary {
        let values: Vec<String> = m.values.iter().map(|v| format!("{v:.2}")).collect();
        let _ = writeln!(s, "| {} | {} | {} | {:.2} ± {:.2} |", m.runs, m.metric, values.join(" | "), m.mean, m.sd);
    }
    let n = r.repeats.iter().map(|cv| cv.folds.len()).sum::<usize>();
    parameters_markdown(
        &mut s,
        &r.model,
        &r.parameters,
        &format!("all {n} folds of the {} repeats", r.seeds.len()),
        false,
    );
    s
}

/// The section on the fitted parameters across folds: each fold's value when `per_fold`, then mean ± sd and range;
/// then how to run the fold models of `model` side by side.
fn parameters_markdown(s: &mut String, model: &str, spread: &[ParameterSpread], folds: &str, per_fold: bool) {
    use std::fmt::Write as _;
    let Some(first) = spread.first() else { return };
    let _ = writeln!(
        s,
        "\n## Fitted parameters across the folds\n\nThe final model of {folds}, each fitted without its held-out \
         runs: how much a calibrated value moves with the runs it is fitted to. A spread \
         of fits to overlapping subsets, not a confidence interval; a fixed parameter has sd 0, and a blank marks a \
         fold whose final model lacks the parameter (an effect it did not keep).{}\n",
        if per_fold {
            " The folds share one seed's random numbers, so this spread leaves out what the numbers move; \
             `--kfold-repeats` adds it."
        } else {
            " The repeats each have their own random numbers, so this spread also shows what the numbers move."
        }
    );
    let k = if per_fold { first.values.len() } else { 0 };
    let heads: String = (1..=k).map(|f| format!(" fold {f} |")).collect();
    let _ = writeln!(s, "| parameter |{heads} folds | mean ± sd | min – max |");
    let _ = writeln!(s, "|---|{}---|---|---|", "---|".repeat(k));
    for p in spread {
        let cells: String = p.values.iter().take(k).map(|v| v.map_or(" |".into(), |v| format!(" {v:.4} |"))).collect();
        let n = p.values.iter().flatten().count();
        let _ = writeln!(s, "| {} |{cells} {n} | {:.4} ± {:.4} | {:.4} – {:.4} |", p.name, p.mean, p.sd, p.min, p.max);
    }
    let what = if model == "2dlm" { "envelope along the profile" } else { "hazard raster" };
    let _ = writeln!(
        s,
        "\nWhat the spread does to the results: `talus envelope {} --floor --out DIR` (from this folder) runs these \
         models with one seed and gives, for each {what}, the lowest, median and highest value over them, beside \
         the spread that seeds alone give.",
        fold_models_glob(model, per_fold)
    );
    if model != "2dlm" {
        let _ = writeln!(
            s,
            "A barrier that holds under every one of them: `talus barrier SITE.toml --models {} --floor --out DIR` \
             (SITE.toml: the terrain, sources and `[barrier_design]`, with the models' material names).",
            fold_models_glob(model, per_fold)
        );
    }
}

/// The scenario files of a cross-validation's fold models, relative to its output folder (one cross-validation's
/// when `per_fold`, else every repeat's), for `talus envelope`: `calibrated.toml` for `3drb`,
/// `calibrated_profile.toml` for `2dlm`.
pub fn fold_models_glob(model: &str, per_fold: bool) -> String {
    let file = if model == "2dlm" { "calibrated_profile.toml" } else { "calibrated.toml" };
    if per_fold {
        format!("fold_*/{file}")
    } else {
        format!("repeat_*/fold_*/{file}")
    }
}

/// `v083 (0.55), v093 (0.60)`.
fn stalling_list(runs: &[runs::StallingRun]) -> String {
    runs.iter().map(|r| format!("{} ({:.2})", r.trajectory_id, r.stalled_share)).collect::<Vec<_>>().join(", ")
}

fn cv_markdown(cv: &CrossValidation) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let _ = writeln!(s, "# Outer {}-fold cross-validation ({})\n", cv.k, cv.model);
    let _ = writeln!(s, "Every run predicted once by the fold that did not see it; {:.0} s in all.\n", cv.total_s);
    metrics_header(&mut s);
    let started_label = format!("final, without {} (not started)", cv.not_started.join(", "));
    let started = cv.final_started.as_ref().map(|set| (started_label.as_str(), set));
    for (name, set) in [("baseline", &cv.baseline), ("final", &cv.final_set)].into_iter().chain(started) {
        metrics_rows(&mut s, name, &set.overall);
        for (b, m) in &set.by_block {
            metrics_rows(&mut s, &format!("{name}, block {b}"), m);
        }
    }
    if !cv.not_started.is_empty() {
        let _ = writeln!(
            s,
            "\nNot started: every final simulation of {} ends within {} m of its release while the field rock ran; \
             the terrain or the recorded release state holds it, so the rows without it show what the parameters \
             score where the model can start the rock.",
            cv.not_started.join(", "),
            runs::NOT_STARTED_M
        );
    }
    let _ = writeln!(
        s,
        "\n| fold | effects kept | baseline MAE | final MAE | held-out runs stalling (share of simulations) | time (s) |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|");
    for f in &cv.folds {
        let _ = writeln!(
            s,
            "| {} | {} | {:.2} | {:.2} | {} | {:.0} |",
            f.fold,
            f.effects_added.join(", "),
            f.baseline_holdout.runout_mae_m,
            f.final_holdout.runout_mae_m,
            stalling_list(&f.holdout_stalling),
            f.time_s
        );
    }
    parameters_markdown(&mut s, &cv.model, &cv.parameters, &format!("each of the {} folds", cv.k), true);
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibrate::metrics::tests::{run, sims};

    #[test]
    fn runs_the_model_never_starts_are_scored_beside_the_others_not_instead() {
        let runs = vec![run(0, 1, 50.0), run(1, 1, 60.0), run(2, 2, 40.0)];
        let pool = vec![sims(0, &[48.0, 52.0]), sims(1, &[0.2, 0.4]), sims(2, &[39.0, 45.0])];
        let (ids, started) = started_only(&runs, &pool);
        assert_eq!(ids, vec!["r1".to_string()]);
        let started = started.unwrap();
        assert_eq!(started.overall.runs, 2);
        // |50 − 50| and |40 − 42| over the two runs that start, against 60 − 0.3 added over all three.
        assert!((started.overall.runout_mae_m - 1.0).abs() < 1e-12, "{:?}", started.overall);
        assert!((metrics_set(&runs, &pool).overall.runout_mae_m - (2.0 + 59.7) / 3.0).abs() < 1e-12);
        assert_eq!(started.by_block["b1"].runs, 1);
        assert_eq!(started_only(&runs, &[pool[0].clone(), pool[2].clone()]), (vec![], None));
    }

    #[test]
    fn a_parameter_spread_covers_the_folds_that_have_it_and_leaves_the_others_blank() {
        let fit = |cr: f64, k: Option<f64>| {
            let mut p = Params::default();
            p.set("default.cr_mean", cr);
            if let Some(k) = k {
                p.set("speed_restitution.k_mps", k);
            }
            p
        };
        let fits = [fit(0.2, None), fit(0.4, Some(6.0)), fit(0.3, Some(8.0))];
        let spread = parameter_spread(&fits);
        assert_eq!(spread.len(), 2);
        let cr = &spread[0];
        assert_eq!((cr.name.as_str(), cr.values.clone()), ("default.cr_mean", vec![Some(0.2), Some(0.4), Some(0.3)]));
        assert!((cr.mean - 0.3).abs() < 1e-12 && (cr.sd - 0.1).abs() < 1e-12 && (cr.min, cr.max) == (0.2, 0.4));
        let k = &spread[1];
        assert_eq!(k.values, vec![None, Some(6.0), Some(8.0)]);
        assert_eq!((k.mean, k.min, k.max), (7.0, 6.0, 8.0));
        assert!((k.sd - 2f64.sqrt()).abs() < 1e-12);
        let mut md = String::new();
        parameters_markdown(&mut md, "3drb", &spread, "each of the 3 folds", true);
        assert!(md.contains("| parameter | fold 1 | fold 2 | fold 3 | folds | mean ± sd | min – max |"), "{md}");
        assert!(
            md.contains("| speed_restitution.k_mps | | 6.0000 | 8.0000 | 2 | 7.0000 ± 1.4142 | 6.0000 – 8.0000 |"),
            "{md}"
        );
        assert!(md.contains("`talus envelope fold_*/calibrated.toml --floor --out DIR`"), "{md}");
        assert!(md.contains("`talus barrier SITE.toml --models fold_*/calibrated.toml --floor --out DIR`"), "{md}");
        let mut md = String::new();
        parameters_markdown(&mut md, "2dlm", &spread, "each of the 3 folds", false);
        assert!(md.contains("`talus envelope repeat_*/fold_*/calibrated_profile.toml --floor --out DIR`"), "{md}");
    }
}
