//! The effects loop: diagnose the residuals of the current model on the calibration runs, propose the effects
//! whose signature shows, test each by nested cross-validation inside the calibration runs, keep the best one if it
//! clearly helps, refit, and repeat until nothing more helps.
//!
//! **Nested cross-validation** (ours, designed to cost a handful of model evaluations per effect): the
//! calibration runs are split into `inner_folds` folds (stratified by release group). Each arm of the comparison
//! has a small set of settings, every setting simulated for all calibration runs (`screen_repeats` times each,
//! default `repeats`) with common random numbers:
//! - the *baseline arm*: the current model re-centred by a global mobility factor m ∈ {1/1.44, 1/1.2, 1, 1.2,
//!   1.44} ([`super::params::apply_mobility_3d`]);
//! - an *effect arm*: the effect's parameter on its grid × the same mobility factors (so the effect is not
//!   credited for a mere re-centring), or × Cr factors {0.5, 0.7, 1, 1.4, 2} for a restitution effect, which
//!   changes what Cr means, or × the mobility factors on the dynamic friction alone for a resistance in contact
//!   (rolling resistance, soft-ground and vegetation drag) and for roughness ([`super::effects::Recentring`]); for
//!   a zone, the candidate zones are derived from the training folds only and the zone material's mobility is
//!   stepped over {0.2, 0.4, 0.7, 1.5} (in 3DRB also, at mobility 1, its soft-ground drag over {3, 10, 30} s⁻¹). A
//!   restitution effect is switched on *centred*: every material's Cr is divided by the effect's factor at the
//!   current model's typical impact (median impact speed, median impact angle; the mass effect is neutral at the
//!   median mass), so that the effect changes how restitution varies, not its typical level (ours).
//!
//! The effect and zone arms *race* their settings (`race_repeats`, default 4; ours, after Maron & Moore 1997): every
//! setting is first simulated `race_repeats` times per run, each inner fold keeps its three best on its training
//! runs, and only those go on to `screen_repeats` (the first look's simulations are their first repeats); a zone arm
//! of 24 candidate regions × 10 settings then simulates about a quarter of what it did.
//!
//! In each fold, each arm picks the setting with the best objective on the other folds' runs, and the fold's own
//! runs are predicted with it. That gives every calibration run an out-of-fold error under each arm: a cheap
//! screening. The error is the run's CRPS (continuous ranked probability score, [`super::metrics::crps`]): a proper
//! score in metres that reduces to |median − observed| for a sharp prediction and also credits a prediction whose
//! spread matches the field scatter, which the run-out MAE alone cannot see (ours). An effect whose screening cuts
//! the mean CRPS by at least `min_improvement` is then confirmed by a
//! *refitting* cross-validation: in each fold, both arms start from the setting that fold chose and refit their
//! free parameters (the base parameters, plus the effect's own, a zone's material included) with the optimiser on the
//! fold's training runs (`cv_refit_evaluations` evaluations), and predict the fold's runs. The decision uses the
//! refitted errors.
//!
//! **"Clearly improves"** (ours): the out-of-fold mean CRPS falls by at least `min_improvement` (5 %), a
//! one-sided paired sign-flip permutation test on the per-run CRPS differences gives p ≤ `alpha` (0.05), and the
//! exact sign-flip test on the inner folds' summed differences does too (`fold_test`; with 5 folds: every fold
//! better), since a fold's runs share that fold's refitted parameters and are not independent of each other. The
//! per-run test's `alpha` is divided by the number of effects the round signalled (`bonferroni`): the round keeps
//! the best of several, and each at `alpha` would let a campaign without any effect through far more often. Among
//! the effects that pass, the one with the fewest added parameters whose out-of-fold CRPS is within one standard
//! error of the best one's is kept (the one-standard-error rule, `choose`; `one_se_rule = false`: the largest
//! cut), then refitted with the optimiser (together with the base parameters), and the loop starts again.

use super::config::{CalibrationConfig, ModelKind, ParamSetting};
use super::diagnose::{diagnose, merged, spread_check, Diagnostic, DEPOSITION_EXCESS};
use super::effects::{
    definition, effects_for, proposed_by_default, recentring, EffectDef, EffectKind, Recentring, CR_SCALE_GRID,
    MOBILITY_GRID, ZONE_DRAG_GRID, ZONE_MOBILITY_GRID, ZONE_SOFT_MOBILITY,
};
use super::fit::{fit, fit_population, unit_of, Context};
use super::impacts::{self, BOUNCE_RESIDUAL};
use super::model::{not_at_rest, Model, RunSims, Sim};
use super::objective::{run_score, score, score_of};
use super::params::{
    apply_mobility_2d, apply_mobility_3d, fold_mobility, friction_over, mobility_scaled, normalize, Candidate,
    EffectSpec, FreeParam, Region, MOBILITY,
};
use super::runs::FieldRun;
use super::split::folds;
use super::stats::{exact_sign_flip_p, mean, paired_excess, paired_sign_flip_p};
use super::zone::zone_check;
use crate::random::stream;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::sync::atomic::Ordering;

/// An effect the loop tried.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EffectTrial {
    /// Round (1-based).
    pub round: usize,
    /// Effect name.
    pub name: String,
    /// Label in the parameters.
    pub label: String,
    /// The covariates (or the zone check) that proposed it.
    pub proposed_by: Vec<Diagnostic>,
    /// Grid screening: out-of-fold mean CRPS of the baseline arm, m.
    pub grid_cv_crps_before_m: f64,
    /// Grid screening: out-of-fold mean CRPS of the effect arm, m.
    pub grid_cv_crps_after_m: f64,
    /// Out-of-fold mean CRPS of the baseline arm (refitted in each fold when the screening was promising), m.
    pub cv_crps_before_m: f64,
    /// Out-of-fold mean CRPS of the effect arm (refitted likewise), m.
    pub cv_crps_after_m: f64,
    /// Out-of-fold run-out MAE of the baseline arm, m.
    pub cv_runout_mae_before_m: f64,
    /// Out-of-fold run-out MAE of the effect arm, m.
    pub cv_runout_mae_after_m: f64,
    /// 1 − CRPS after / CRPS before.
    pub relative_improvement: f64,
    /// One-sided paired permutation p-value.
    pub p_value: f64,
    /// The largest `p_value` that passed in this trial's round: `alpha`, divided by the effects the round signalled
    /// under `bonferroni` (0 in reports before 2026-12-01, when it was `alpha`).
    #[serde(default)]
    pub p_threshold: f64,
    /// Per inner fold, the mean cut of the CRPS over the fold's runs (before − after, m; positive where the effect
    /// predicts better). A fold's runs share its refitted parameters, so a cut carried by one fold's refit shows here.
    #[serde(default)]
    pub fold_cuts_m: Vec<f64>,
    /// The exact one-sided sign-flip p-value over the folds' summed cuts (at least 2^−folds), which `fold_test`
    /// asks to reach `alpha` too.
    #[serde(default)]
    pub fold_p_value: f64,
    /// Kept.
    pub kept: bool,
    /// The effect's parameters at the best setting on all calibration runs (before the refit).
    pub parameters: BTreeMap<String, f64>,
    /// The zone, if any.
    pub region: Option<Region>,
}

impl EffectTrial {
    /// The inner folds whose runs the effect predicts better.
    pub fn folds_better(&self) -> usize {
        self.fold_cuts_m.iter().filter(|&&c| c > 0.0).count()
    }
}

/// An effect kept by the loop.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AddedEffect {
    /// Effect name.
    pub name: String,
    /// Label in the parameters.
    pub label: String,
    /// Its parameters after the refit.
    pub parameters: BTreeMap<String, f64>,
    /// Why: the trial that kept it, with the formula and source.
    pub evidence: serde_json::Value,
    /// The zone, if any.
    pub region: Option<Region>,
}

/// The loop's outcome.
#[derive(Debug, Clone)]
pub struct LoopResult {
    /// The final model.
    pub candidate: Candidate,
    /// Effects kept, in order.
    pub added: Vec<AddedEffect>,
    /// Every trial.
    pub trials: Vec<EffectTrial>,
    /// Each round's starting model as diagnosed (round 1: the baseline).
    pub rounds: Vec<Diagnosed>,
}

/// A round's starting model as the loop diagnosed it: its simulations of the calibration runs at the reported
/// repeats and seed, which the final evaluation reuses rather than simulating the same model again.
#[derive(Debug, Clone)]
pub struct Diagnosed {
    /// The model.
    pub candidate: Candidate,
    /// Its simulations of the calibration runs (`repeats` each, the run's own seed).
    pub sims: Vec<RunSims>,
    /// Its bounces read on the tracked calibration runs, when these hold enough observed bounces to diagnose.
    pub bounces: Option<Vec<(usize, Vec<impacts::Impact>)>>,
    /// The run-out (and bounce) diagnostics.
    pub diagnostics: Vec<Diagnostic>,
    /// The zone check (draws seeded by `seed` + round), when a zone is a candidate.
    pub zone_check: Option<super::zone::ZoneCheck>,
}

#[derive(Clone)]
struct Proposal {
    def: &'static EffectDef,
    label: String,
    material: Option<String>,
    evidence: Vec<Diagnostic>,
    strength: f64,
}

/// Runs the loop from `baseline` (fitted) on calibration runs `cal`, refitting `base_free` with kept effects.
pub fn effects_loop(
    ctx: &Context,
    baseline: &Candidate,
    base_free: &[FreeParam],
    cal: &[usize],
) -> crate::Result<LoopResult> {
    let cfg = ctx.cfg;
    let model = ctx.model;
    let kind = model.kind();
    let mut current = baseline.clone();
    let mut out = LoopResult { candidate: current.clone(), added: Vec::new(), trials: Vec::new(), rounds: Vec::new() };
    let allowed = allowed_effects(cfg, kind);
    let frame = model.map_frame();
    let mut free = base_free.to_vec();
    for round in 1..=cfg.effects.max_rounds {
        (ctx.log)(&format!("effects loop, round {round}: diagnosing"));
        let diag_sims = ctx.sims(&current, cal, cfg.repeats)?;
        let (_, mut diags) = diagnose(model, &diag_sims, cfg.effects.permutations, cfg.seed);
        // On tracked runs, the bounces: does the model's restitution miss the tracks' with speed or incidence?
        let observed_bounces: usize = cal.iter().map(|&i| model.runs()[i].impacts.len()).sum();
        let mut bounce_sims = None;
        if observed_bounces >= impacts::MIN_BOUNCES_DIAGNOSED {
            let noise = model.track_noise_m();
            let simulated =
                impacts::simulated_impacts(model, &current, cal, cfg.repeats, cfg.seed, noise, cfg.threads)?;
            let ranks = impacts::bounce_ranks(model.runs(), &simulated);
            bounce_sims = Some(simulated);
            let bounce = impacts::bounce_diagnostics(&ranks, cfg.effects.permutations, cfg.seed);
            for d in &bounce {
                (ctx.log)(&format!(
                    "effects loop, round {round}: observed bounces ranked among simulated ones against {}: rho {:.2}, \
                     p = {:.3} ({} bounces)",
                    d.covariate, d.spearman_rho, d.p_value, d.n
                ));
            }
            diags = merged(diags, bounce);
        }
        let zone_allowed = allowed.iter().any(|d| d.kind == EffectKind::Zone);
        let zc = zone_allowed.then(|| zone_check(model, &diag_sims, &frame, 199, cfg.seed.wrapping_add(round as u64)));
        out.rounds.push(Diagnosed {
            candidate: current.clone(),
            sims: diag_sims.clone(),
            bounces: bounce_sims,
            diagnostics: diags.clone(),
            zone_check: zc.clone(),
        });
        if let Some(z) = &zc {
            (ctx.log)(&format!(
                "effects loop, round {round}: zone check p = {:.3} (largest deposition excess {:.3}, p {:.3}; \
                 overrun share {:.3}, p {:.3})",
                z.p_value, z.statistic, z.deposition_p_value, z.overrun_share, z.overrun_p_value
            ));
        }
        let spread = spread_check(model.runs(), &diag_sims);
        (ctx.log)(&format!(
            "effects loop, round {round}: spread check: {:.2} of the runs outside their simulated range \
             (exchangeable: 2/(repeats + 1)), p = {:.3}",
            spread.spearman_rho, spread.p_value
        ));
        let (batch, waiting) = propose(
            ctx,
            &allowed,
            &current,
            &diags,
            &spread,
            zc.as_ref().map(|z| (z.p_value, z.statistic, !z.regions.is_empty())),
        );
        if batch.is_empty() {
            (ctx.log)("effects loop: no effect's signature shows in the residuals");
            break;
        }
        let fold_of = folds(model.runs(), cal, cfg.inner_folds, cfg.seed, round as u64);
        let centre = Centre {
            impact_speed_mps: super::stats::median(
                &diag_sims.iter().map(|s| s.median_of(|x| x.summary.impact_speed_mean_mps)).collect::<Vec<_>>(),
            ),
            impact_angle_deg: super::stats::median(
                &diag_sims.iter().map(|s| s.median_of(|x| x.summary.impact_angle_mean_deg)).collect::<Vec<_>>(),
            ),
        };
        // The baseline arm: the current model re-centred by the mobility factor.
        let mut base_arm = Arm::default();
        for &m in &MOBILITY_GRID {
            let mut c = current.clone();
            c.params.set(MOBILITY, m);
            base_arm.screen(ctx, cal, c, cfg.screen_repeats())?;
        }
        base_arm.fold_settings = vec![(0..base_arm.settings.len()).collect(); cfg.inner_folds];
        // With the arms fitted again, so is the baseline: an effect is credited only with what the baseline fitted
        // again cannot match.
        if cfg.fit_arms(model.kind()) {
            base_arm.add_fitted(ctx, &current, &free, cal, &fold_of, "the baseline fitted again")?;
        }
        let (e0_grid, base_chosen) = cross_validate(ctx, cal, &fold_of, &base_arm.settings, &base_arm.fold_settings);
        let mut e0_refit: Option<Vec<CvError>> = None;
        let mut passed: Vec<Passed> = Vec::new();
        let signalled = batch.len() + waiting.len();
        let run_alpha = per_run_alpha(&cfg.effects, signalled);
        if run_alpha < cfg.effects.alpha {
            (ctx.log)(&format!(
                "effects loop, round {round}: {signalled} effects signalled; each must reach p <= {run_alpha:.4} over the runs (alpha {} / {signalled}, [effects] bonferroni)",
                cfg.effects.alpha
            ));
        }
        // With `restart_arms`, the current model with its materials back at the settings' start, shared by the arms.
        let restart_from = cfg.effects.restart_arms.then(|| with_start_materials(ctx, &current));
        // Each proposal's arm; `in_batches` decides which are tried.
        let mut try_one = |prop: Proposal| -> crate::Result<bool> {
            (ctx.log)(&format!("effects loop, round {round}: trying {}", prop.label));
            let mut effect_free = free.clone();
            if prop.def.kind == EffectKind::Zone {
                effect_free.extend(zone_free(ctx, &prop.label));
            } else if let Some(param) = prop.def.param {
                let (min, max) = prop.def.bounds;
                effect_free.push(FreeParam { name: format!("{}.{param}", prop.label), min, max });
            }
            let arm = if prop.def.kind == EffectKind::Zone {
                zone_arm(ctx, &base_arm, &prop.label, &diag_sims, cal, &fold_of)?
            } else {
                let values: Vec<Option<f64>> = if prop.def.grid.is_empty() {
                    vec![None]
                } else {
                    prop.def.grid.iter().map(|v| Some(*v)).collect()
                };
                let how = recentring(prop.def.kind);
                let axis: &[f64] = if how == Recentring::CrScale { &CR_SCALE_GRID } else { &MOBILITY_GRID };
                let effect = |from: &Candidate, v| {
                    with_effect(model, from, prop.def, &prop.label, prop.material.clone(), v, &centre)
                };
                let mut cands = Vec::new();
                for &v in &values {
                    for &m in axis {
                        let mut c = effect(&current, v);
                        match how {
                            Recentring::CrScale => scale_cr(&mut c, m),
                            Recentring::DynamicFriction => scale_dynamic_friction(&mut c, m),
                            Recentring::Mobility => c.params.set(MOBILITY, m),
                        }
                        cands.push(c);
                    }
                }
                if let Some(from) = &restart_from {
                    cands.extend(values.iter().map(|&v| effect(from, v)));
                }
                let first_looks = cands.len() * cal.len() * cfg.first_look_repeats();
                (ctx.log)(&format!(
                    "  {}: {} settings, {first_looks} simulations for their first looks{}",
                    prop.label,
                    cands.len(),
                    ctx.time_for(first_looks)
                ));
                let mut arm = Arm::default();
                for c in cands {
                    arm.screen(ctx, cal, c, cfg.first_look_repeats())?;
                }
                arm.fold_settings = vec![(0..arm.settings.len()).collect(); cfg.inner_folds];
                arm.full = (0..arm.settings.len()).collect();
                arm.race(ctx, cal, &fold_of, &prop.label, |c, r| ctx.sims_repeats(&screened(ctx, c), cal, r))?;
                if cfg.fit_arms(model.kind()) && prop.def.param.is_some() {
                    let from = effect(&current, values[values.len() / 2]);
                    arm.add_fitted(ctx, &from, &effect_free, cal, &fold_of, &format!("{} fitted", prop.label))?;
                }
                arm
            };
            let (e1_grid, chosen) = cross_validate(ctx, cal, &fold_of, &arm.settings, &arm.fold_settings);
            let mean_score = |e: &[CvError]| mean(&e.iter().map(|x| x.crps_m).collect::<Vec<_>>());
            let mae = |e: &[CvError]| mean(&e.iter().map(|x| x.abs_m).collect::<Vec<_>>());
            let grid_before = mean_score(&e0_grid);
            let grid_after = mean_score(&e1_grid);
            // The setting that is best on all calibration runs starts the final refit.
            let full = arm
                .full
                .iter()
                .map(|&s| (score(cfg, model.runs(), &arm.settings[s]), s))
                .min_by(|a, b| a.0.total_cmp(&b.0))
                .map(|(_, s)| arm.cands[s].clone())
                .unwrap_or_else(|| current.clone());
            // Promising on the grid: confirm with the refitting cross-validation.
            let screening_cut = if grid_before > 0.0 { 1.0 - grid_after / grid_before } else { 0.0 };
            let (before, after) = if screening_cut >= cfg.effects.min_improvement && full.effect(&prop.label).is_some()
            {
                if e0_refit.is_none() {
                    (ctx.log)(&format!("  refitting the baseline in each fold{}", refit_cv_time(ctx, cal.len())));
                    let starts: Vec<Candidate> = base_chosen.iter().map(|&c| folded(ctx, &base_arm.cands[c])).collect();
                    let sims: Vec<&[RunSims]> = base_chosen.iter().map(|&c| base_arm.settings[c].as_slice()).collect();
                    let what = format!("round {round} baseline");
                    e0_refit = Some(refit_cv(ctx, &starts, &sims, &free, cal, &fold_of, &what)?);
                }
                (ctx.log)(&format!("  refitting {} in each fold{}", prop.label, refit_cv_time(ctx, cal.len())));
                let starts: Vec<Candidate> = chosen.iter().map(|&c| folded(ctx, &arm.cands[c])).collect();
                let sims: Vec<&[RunSims]> = chosen.iter().map(|&c| arm.settings[c].as_slice()).collect();
                (
                    e0_refit.clone().unwrap_or_default(),
                    refit_cv(ctx, &starts, &sims, &effect_free, cal, &fold_of, &prop.label)?,
                )
            } else {
                (e0_grid.clone(), e1_grid.clone())
            };
            let (mb, ma) = (mean_score(&before), mean_score(&after));
            let diffs: Vec<f64> = before.iter().zip(&after).map(|(a, b)| a.crps_m - b.crps_m).collect();
            let mut rng = stream(cfg.seed, u64::MAX - 4000 - round as u64);
            let p = paired_sign_flip_p(&diffs, cfg.effects.permutations, &mut rng);
            // Each inner fold that holds runs: the sum of its runs' differences, and their number.
            let fold_totals: Vec<(f64, usize)> = (0..cfg.inner_folds)
                .map(|f| {
                    let d: Vec<f64> = diffs.iter().zip(&fold_of).filter(|(_, &k)| k == f).map(|(d, _)| *d).collect();
                    (d.iter().sum(), d.len())
                })
                .filter(|&(_, n)| n > 0)
                .collect();
            let fold_sums: Vec<f64> = fold_totals.iter().map(|&(sum, _)| sum).collect();
            let fold_cuts_m: Vec<f64> = fold_totals.iter().map(|&(sum, n)| sum / n as f64).collect();
            let fold_p = exact_sign_flip_p(&fold_sums);
            let improvement = if mb > 0.0 { 1.0 - ma / mb } else { 0.0 };
            let effect_params: BTreeMap<String, f64> = full
                .params
                .0
                .iter()
                .filter(|(k, _)| k.starts_with(&format!("{}.", prop.label)) || k.as_str() == MOBILITY)
                .map(|(k, v)| (k.clone(), *v))
                .collect();
            let region = full.effect(&prop.label).and_then(|e| e.region.clone());
            let trial = EffectTrial {
                round,
                name: prop.def.name.to_string(),
                label: prop.label.clone(),
                proposed_by: prop.evidence.clone(),
                grid_cv_crps_before_m: grid_before,
                grid_cv_crps_after_m: grid_after,
                cv_crps_before_m: mb,
                cv_crps_after_m: ma,
                cv_runout_mae_before_m: mae(&before),
                cv_runout_mae_after_m: mae(&after),
                relative_improvement: improvement,
                p_value: p,
                p_threshold: run_alpha,
                fold_cuts_m,
                fold_p_value: fold_p,
                kept: false,
                parameters: effect_params,
                region,
            };
            (ctx.log)(&format!(
                "  {}: CV CRPS {mb:.2} -> {ma:.2} m ({:+.1} %), p = {p:.3}; CV run-out MAE {:.2} -> {:.2} m (grid screening CRPS {grid_before:.2} -> {grid_after:.2} m); better in {} of {} folds (cuts {} m, fold p = {fold_p:.3})",
                prop.label,
                -100.0 * improvement,
                mae(&before),
                mae(&after),
                trial.folds_better(),
                trial.fold_cuts_m.len(),
                trial.fold_cuts_m.iter().map(|c| format!("{c:+.2}")).collect::<Vec<_>>().join(" ")
            ));
            // With k folds no pattern but the observed one reaches p = 2^-k: there, every fold better.
            let fold_alpha = cfg.effects.alpha.max(0.5f64.powi(fold_sums.len() as i32));
            let passes = improvement >= cfg.effects.min_improvement
                && p <= run_alpha
                && (!cfg.effects.fold_test || fold_p <= fold_alpha)
                && full.effect(&prop.label).is_some();
            out.trials.push(trial.clone());
            if passes {
                passed.push(Passed {
                    cv_crps_m: after.iter().map(|e| e.crps_m).collect(),
                    added_parameters: effect_free.len() - free.len(),
                    trial,
                    full,
                    free: effect_free,
                });
            }
            Ok(passes)
        };
        in_batches(batch, waiting, cfg.effects.max_proposals, &mut try_one, &|n, left| {
            (ctx.log)(&format!(
                "effects loop, round {round}: none of these passes; trying the next {n} signalled ({left} more after them)"
            ))
        })?;
        let arms: Vec<(&[f64], usize)> = passed.iter().map(|p| (p.cv_crps_m.as_slice(), p.added_parameters)).collect();
        let Some(pick) = choose(&arms, cfg.effects.one_se_rule) else {
            (ctx.log)("effects loop: no effect clearly improves the cross-validated error");
            break;
        };
        let rivals: Vec<serde_json::Value> = passed
            .iter()
            .enumerate()
            .filter(|(k, _)| *k != pick.kept)
            .map(|(k, p)| {
                serde_json::json!({
                    "label": p.trial.label,
                    "relative_improvement": p.trial.relative_improvement,
                    "added_parameters": p.added_parameters,
                    "within_one_se_of_best": pick.within_one_se[k],
                })
            })
            .collect();
        let Passed { trial, full: chosen, free: refit_free, added_parameters, .. } = passed.swap_remove(pick.kept);
        if !rivals.is_empty() {
            (ctx.log)(&format!(
                "effects loop, round {round}: {} effects pass; {} kept ({added_parameters} added parameter{}{})",
                rivals.len() + 1,
                trial.label,
                if added_parameters == 1 { "" } else { "s" },
                if pick.simpler_than_best {
                    ", the simplest within one standard error of the best"
                } else {
                    ", the best"
                }
            ));
        }
        if let Some(t) = out.trials.iter_mut().rev().find(|t| t.label == trial.label && t.round == round) {
            t.kept = true;
        }
        // Refit on all calibration runs: base parameters plus the effect's own.
        let spec = chosen.effect(&trial.label).cloned().expect("chosen candidate carries its effect");
        let start = folded(ctx, &chosen);
        let def = definition(kind, spec.kind).expect("effect defined for the model");
        (ctx.log)(&format!("effects loop, round {round}: keeping {}, refitting", spec.label));
        let (refit, _) = fit(
            ctx,
            &start,
            &refit_free,
            cal,
            cfg.refit_evaluations(kind),
            &format!("refit with {}", spec.label),
            cfg.seed,
        );
        current = refit;
        free = refit_free;
        let parameters: BTreeMap<String, f64> = current
            .params
            .0
            .iter()
            .filter(|(k, _)| k.starts_with(&format!("{}.", spec.label)))
            .map(|(k, v)| (k.clone(), *v))
            .collect();
        let evidence = serde_json::json!({
            "round": round,
            "formula": def.formula,
            "proposed_by": trial.proposed_by,
            "grid_cv_crps_before_m": trial.grid_cv_crps_before_m,
            "grid_cv_crps_after_m": trial.grid_cv_crps_after_m,
            "cv_crps_before_m": trial.cv_crps_before_m,
            "cv_crps_after_m": trial.cv_crps_after_m,
            "cv_runout_mae_before_m": trial.cv_runout_mae_before_m,
            "cv_runout_mae_after_m": trial.cv_runout_mae_after_m,
            "relative_improvement": trial.relative_improvement,
            "p_value": trial.p_value,
            "p_threshold": trial.p_threshold,
            "fold_cuts_m": trial.fold_cuts_m,
            "fold_p_value": trial.fold_p_value,
            "inner_folds": cfg.inner_folds,
            "criterion": format!(
                "relative improvement >= {} and one-sided paired permutation p <= {} over the runs{}{}",
                cfg.effects.min_improvement,
                trial.p_threshold,
                if cfg.effects.bonferroni { " (alpha over the effects the round signalled)" } else { "" },
                if cfg.effects.fold_test { format!(" and <= {} over the inner folds", cfg.effects.alpha) } else { String::new() }
            ),
            "added_parameters": added_parameters,
            "selection": if cfg.effects.one_se_rule { SELECTION_ONE_SE } else { SELECTION_BEST },
            "rivals": rivals,
        });
        out.added.push(AddedEffect {
            name: def.name.to_string(),
            label: spec.label.clone(),
            parameters,
            evidence,
            region: spec.region.clone(),
        });
    }
    out.candidate = current;
    Ok(out)
}

const SELECTION_ONE_SE: &str = "of the effects that pass, the one with the fewest added parameters whose out-of-fold \
    mean CRPS is within one standard error (of the per-run differences) of the best one's";
const SELECTION_BEST: &str = "of the effects that pass, the one with the largest cut";

/// Tries `first`, then `waiting` `max` at a time, strongest first, until a batch holds an effect that passes:
/// `try_one` tries one and says whether it passed; `next(n, left)` is told of each further batch. So every signalled
/// effect is tried before a round ends with nothing kept, and a weaker one only when the stronger ones fail (ours).
fn in_batches<P>(
    first: Vec<P>,
    mut waiting: Vec<P>,
    max: usize,
    try_one: &mut dyn FnMut(P) -> crate::Result<bool>,
    next: &dyn Fn(usize, usize),
) -> crate::Result<()> {
    let mut batch = first;
    loop {
        let mut any = false;
        for p in batch {
            any |= try_one(p)?;
        }
        if any || waiting.is_empty() {
            return Ok(());
        }
        let n = max.clamp(1, waiting.len());
        batch = waiting.drain(..n).collect();
        next(n, waiting.len());
    }
}

/// The largest per-run p-value that keeps an effect in a round that signalled `signalled` effects: `alpha`, divided
/// by their number under `bonferroni`.
fn per_run_alpha(effects: &super::config::EffectsConfig, signalled: usize) -> f64 {
    if effects.bonferroni {
        effects.alpha / signalled.max(1) as f64
    } else {
        effects.alpha
    }
}

/// An effect that passed the cross-validation this round.
struct Passed {
    /// Each calibration run's out-of-fold CRPS under the effect's arm, m.
    cv_crps_m: Vec<f64>,
    /// Parameters the effect adds to the fit (a zone's material; its polygon, chosen from the data, not counted).
    added_parameters: usize,
    trial: EffectTrial,
    full: Candidate,
    free: Vec<FreeParam>,
}

/// The choice among the effects that pass.
struct Pick {
    kept: usize,
    /// For each passing effect: is its out-of-fold CRPS within one standard error of the best one's.
    within_one_se: Vec<bool>,
    /// The kept effect is not the one with the largest cut.
    simpler_than_best: bool,
}

/// Which passing effect to keep. Without `one_se_rule`, the largest cut. With it, the one-standard-error rule
/// (Breiman et al. 1984, *Classification and Regression Trees*, §3.4.3; Hastie, Tibshirani & Friedman 2009, §7.10):
/// among the effects whose mean out-of-fold CRPS exceeds the best one's by at most the standard error of the
/// per-run paired differences, the one with the fewest added parameters (ties: the larger cut). When two effects
/// fit the calibration runs alike, the data do not choose between them, and the simpler one is kept; the others
/// are reported as rivals. `arms`: each passing effect's per-run out-of-fold CRPS (the same runs in the same order)
/// and its added parameters.
fn choose(arms: &[(&[f64], usize)], one_se_rule: bool) -> Option<Pick> {
    let means: Vec<f64> = arms.iter().map(|a| mean(a.0)).collect();
    let best = (0..arms.len()).min_by(|&a, &b| means[a].total_cmp(&means[b]))?;
    let within_one_se: Vec<bool> = arms
        .iter()
        .map(|a| {
            let (excess, se) = paired_excess(a.0, arms[best].0);
            excess <= se
        })
        .collect();
    let kept = if one_se_rule {
        (0..arms.len())
            .filter(|&k| within_one_se[k])
            .min_by(|&a, &b| arms[a].1.cmp(&arms[b].1).then(means[a].total_cmp(&means[b])))
            .unwrap_or(best)
    } else {
        best
    };
    Some(Pick { kept, within_one_se, simpler_than_best: kept != best })
}

/// Multiplies every material's (and zone's) mean restitution (Cr in 3DRB, Rn in 2DLM) by `f`, capped at 1.
fn scale_cr(c: &mut Candidate, f: f64) {
    map_params(c, &[".cr_mean", ".rn_mean"], |v| (v * f).min(1.0));
}

/// Divides tan of every material's (and zone's) dynamic friction angle by `f` (3DRB; f > 1 is more slippery, as
/// with the mobility factor).
fn scale_dynamic_friction(c: &mut Candidate, f: f64) {
    map_params(c, &[".dynamic_friction_deg"], |v| friction_over(v, f));
}

/// Replaces every parameter whose name ends with one of `suffixes` by `f` of its value.
fn map_params(c: &mut Candidate, suffixes: &[&str], f: impl Fn(f64) -> f64) {
    for (_, v) in c.params.0.iter_mut().filter(|(k, _)| suffixes.iter().any(|s| k.ends_with(s))) {
        *v = f(*v);
    }
}

/// A candidate with its mobility factor folded into the materials, every material parameter the settings fix (or a
/// campaign's tracks measured, [`super::measured`]) back at its fixed value: a re-centring arm moves them all, a
/// refit starting from the result must not.
fn folded(ctx: &Context, c: &Candidate) -> Candidate {
    let (model, kind) = (ctx.model, ctx.model.kind());
    let mut out = c.clone();
    out.params = fold_mobility(kind, &c.params, model.materials());
    for m in model.materials() {
        for p in kind.material_parameters() {
            if let Some(ParamSetting::Fixed(v)) = ctx.cfg.used_setting(kind, m, p) {
                out.params.set(format!("{m}.{p}"), v);
            }
        }
    }
    normalize(&mut out.params);
    out
}

/// The candidate a re-centring arm simulates for `c`: where the settings fix a parameter the re-centring moves (the
/// mobility factor's, [`mobility_scaled`]), `c` [`folded`], so that the arm moves the free parameters only, as the
/// refit from its choice will; elsewhere `c` itself (the same model, without the rounding of a fold).
fn screened(ctx: &Context, c: &Candidate) -> Candidate {
    let kind = ctx.model.kind();
    let fixes_one = ctx.model.materials().iter().any(|m| {
        mobility_scaled(kind).iter().any(|p| matches!(ctx.cfg.used_setting(kind, m, p), Some(ParamSetting::Fixed(_))))
    });
    if fixes_one {
        folded(ctx, c)
    } else {
        c.clone()
    }
}

/// [`refit_cv`]'s simulations on `n` calibration runs (each fold's evaluations on its training runs, then its
/// runs predicted), and how long they take at the pace so far.
fn refit_cv_time(ctx: &Context, n: usize) -> String {
    let cfg = ctx.cfg;
    let k = cfg.inner_folds.max(1);
    let fits = (k - 1) * n * cfg.cv_refit_evaluations(ctx.model.kind()) * cfg.search_repeats;
    ctx.time_for(fits + n * cfg.repeats)
}

/// Refitting cross-validation: in each fold, `free` is refitted from `starts[f]` on the other folds' runs
/// (`cv_refit_evaluations` objective evaluations), then the fold's runs are predicted. Returns per-run errors in
/// the order of `cal`.
///
/// With `[effects] refit_check`, a refit is kept only if it also beats its start on fresh repeats of the training
/// runs (ours, as the population fit chooses between its searches): the search chooses on `search_repeats` repeats
/// a run, and the best of a few dozen candidates on those repeats is partly the one that drew well on them (the
/// winner's curse; on Tschamut, stop 61, the baseline's refits ended worse out of fold than their starts, 14.01 →
/// 15.08 m, and inflated every effect's cut). The fresh repeats are the screening's beyond the search's
/// (`search_repeats..screen_repeats`): `start_sims[f]` holds the start's (its setting's simulations of all
/// calibration runs, order of `cal`), so only the refit's are simulated. With `screen_repeats ≤ search_repeats`
/// there are none and every refit is kept.
fn refit_cv(
    ctx: &Context,
    starts: &[Candidate],
    start_sims: &[&[RunSims]],
    free: &[FreeParam],
    cal: &[usize],
    fold_of: &[usize],
    what: &str,
) -> crate::Result<Vec<CvError>> {
    let runs = ctx.model.runs();
    let mut errors = vec![CvError { crps_m: f64::NAN, abs_m: f64::NAN }; cal.len()];
    for (f, start) in starts.iter().enumerate() {
        let train_pos: Vec<usize> = (0..cal.len()).filter(|&j| fold_of[j] != f).collect();
        let train: Vec<usize> = train_pos.iter().map(|&j| cal[j]).collect();
        let test_pos: Vec<usize> = (0..cal.len()).filter(|&j| fold_of[j] == f).collect();
        if test_pos.is_empty() {
            continue;
        }
        // Only parameters the fold's start uses (a fold without a zone of its own has none to fit).
        let mats = ctx.model.materials();
        let used: Vec<FreeParam> = free
            .iter()
            .filter(|p| {
                p.name
                    .split_once('.')
                    .is_none_or(|(prefix, _)| mats.iter().any(|m| m == prefix) || start.effect(prefix).is_some())
            })
            .cloned()
            .collect();
        let c = if used.is_empty() {
            start.clone()
        } else {
            let what = format!("{what}, fold {}", f + 1);
            let evaluations = ctx.cfg.cv_refit_evaluations(ctx.model.kind());
            let (c, search) = fit(ctx, start, &used, &train, evaluations, &what, ctx.cfg.seed);
            let moved = search.x != unit_of(start, &used);
            if !moved || !ctx.cfg.effects.refit_check || beats_its_start(ctx, &c, start_sims[f], &train_pos, &what)? {
                c
            } else {
                start.clone()
            }
        };
        let test: Vec<usize> = test_pos.iter().map(|&j| cal[j]).collect();
        // The fold's runs are predicted with the reported repeats: a steadier median for the paired test.
        let sims = ctx.sims(&c, &test, ctx.cfg.repeats)?;
        for (j, s) in test_pos.iter().zip(&sims) {
            errors[*j] = CvError::of(ctx.cfg, &runs[s.run], s);
        }
    }
    Ok(errors)
}

/// Whether refit `c` scores lower than its start on the fresh repeats of the training runs (see [`refit_cv`]):
/// `start_sims` are the start's simulations of the calibration runs, `train` the training runs' places among them;
/// true when there are none.
fn beats_its_start(
    ctx: &Context,
    c: &Candidate,
    start_sims: &[RunSims],
    train: &[usize],
    what: &str,
) -> crate::Result<bool> {
    let fresh = ctx.cfg.search_repeats..ctx.cfg.screen_repeats();
    if fresh.is_empty() {
        return Ok(true);
    }
    let runs = ctx.model.runs();
    let started: Vec<RunSims> = train
        .iter()
        .map(|&j| RunSims { run: start_sims[j].run, sims: start_sims[j].repeats_in(fresh.clone()).to_vec() })
        .collect();
    let which: Vec<usize> = started.iter().map(|s| s.run).collect();
    let refit = score(ctx.cfg, runs, &ctx.sims_repeats(c, &which, fresh)?);
    let before = score(ctx.cfg, runs, &started);
    let kept = refit < before;
    (ctx.log)(&format!(
        "{what}: {refit:.2} m on fresh repeats of its training runs against its start's {before:.2} m: {}",
        if kept { "the refit predicts" } else { "the start predicts" }
    ));
    Ok(kept)
}

/// `current` with every material parameter at the settings' start point (its effects and zones as they are).
fn with_start_materials(ctx: &Context, current: &Candidate) -> Candidate {
    let (start, _) = super::base_candidate(ctx.model, ctx.cfg);
    let mut c = current.clone();
    for m in ctx.model.materials() {
        let prefix = format!("{m}.");
        for (k, v) in start.params.0.iter().filter(|(k, _)| k.starts_with(&prefix)) {
            c.params.set(k.clone(), *v);
        }
    }
    c
}

/// The effects the loop may propose: those listed in `candidates`, or, when none are, those proposed by default.
fn allowed_effects(cfg: &CalibrationConfig, kind: ModelKind) -> Vec<&'static EffectDef> {
    let listed = &cfg.effects.candidates;
    effects_for(kind)
        .iter()
        .filter(|d| if listed.is_empty() { proposed_by_default(d.kind) } else { listed.iter().any(|c| c == d.name) })
        .collect()
}

/// The effects whose signature shows, strongest first: the first batch (see [`strongest`]) and the rest.
fn propose(
    ctx: &Context,
    allowed: &[&'static EffectDef],
    current: &Candidate,
    diags: &[Diagnostic],
    spread: &Diagnostic,
    zone: Option<(f64, f64, bool)>,
) -> (Vec<Proposal>, Vec<Proposal>) {
    let cfg = ctx.cfg;
    let alpha = cfg.effects.propose_alpha;
    // Run-out residuals, on a tracked campaign scored with its rebounds the rebound residuals, and the bounces read
    // from tracks: all carry an effect's signature.
    let rebounds = cfg.rebound_weight.is_some_and(|w| w > 0.0);
    let runout: Vec<&Diagnostic> = diags
        .iter()
        .filter(|d| d.residual == "runout" || (rebounds && d.residual == "rebound") || d.residual == BOUNCE_RESIDUAL)
        .collect();
    let mut props = Vec::new();
    for def in allowed {
        match def.kind {
            EffectKind::Zone => {
                if let Some((p, stat, has_region)) = zone {
                    if p <= alpha && has_region {
                        let n_zones = current.effects.iter().filter(|e| e.kind == EffectKind::Zone).count();
                        let ev = Diagnostic {
                            covariate: DEPOSITION_EXCESS.into(),
                            residual: "rest_points".into(),
                            spearman_rho: stat,
                            p_value: p,
                            n: 0,
                        };
                        props.push(Proposal {
                            def,
                            label: format!("zone{}", n_zones + 1),
                            material: None,
                            evidence: vec![ev],
                            strength: p,
                        });
                    }
                }
            }
            EffectKind::SoftDrag => {
                if current.effect_of(EffectKind::SoftDrag).is_some() {
                    continue;
                }
                for d in runout.iter().filter(|d| d.covariate.starts_with("path_fraction_") && d.p_value <= alpha) {
                    let m = d.covariate.trim_start_matches("path_fraction_").to_string();
                    if props.iter().any(|p: &Proposal| p.material.as_ref() == Some(&m)) {
                        continue; // both residuals point at the material: one proposal
                    }
                    props.push(Proposal {
                        def,
                        label: format!("soft_drag_{m}"),
                        material: Some(m),
                        evidence: vec![(*d).clone()],
                        strength: d.p_value,
                    });
                }
            }
            _ => {
                if current.effect_of(def.kind).is_some() {
                    continue;
                }
                let hits = signature_hits(def, &runout, spread, alpha);
                if let Some(strength) = hits.iter().map(|d| d.p_value).reduce(f64::min) {
                    props.push(Proposal { def, label: def.name.to_string(), material: None, evidence: hits, strength });
                }
            }
        }
    }
    let (first, waiting) = strongest(props, cfg.effects.max_proposals);
    if !waiting.is_empty() {
        let names: Vec<String> = waiting.iter().map(|p| format!("{} (p = {:.3})", p.label, p.strength)).collect();
        (ctx.log)(&format!(
            "effects loop: also signalled, tried only if none of the first {} passes ([effects] max_proposals): {}",
            first.len(),
            names.join(", ")
        ));
    }
    (first, waiting)
}

/// `props` strongest first (smallest p, then largest |rho|): the first `max`, and any effect the bounces point at
/// (they measure restitution directly, where the run-out residuals see it through the whole path; ours); then the
/// rest, waiting for a later batch.
fn strongest(mut props: Vec<Proposal>, max: usize) -> (Vec<Proposal>, Vec<Proposal>) {
    props.sort_by(|a, b| {
        a.strength.total_cmp(&b.strength).then_with(|| {
            let ra = a.evidence.iter().map(|d| d.spearman_rho.abs()).fold(0.0, f64::max);
            let rb = b.evidence.iter().map(|d| d.spearman_rho.abs()).fold(0.0, f64::max);
            rb.total_cmp(&ra)
        })
    });
    let direct = |p: &Proposal| p.evidence.iter().any(|d| d.residual == BOUNCE_RESIDUAL);
    let mut k = 0;
    props.into_iter().partition(|p| {
        k += 1;
        k <= max || direct(p)
    })
}

/// The diagnostics (run-out correlations, and the spread check) in `def`'s signature at p ≤ `alpha`.
fn signature_hits(def: &EffectDef, runout: &[&Diagnostic], spread: &Diagnostic, alpha: f64) -> Vec<Diagnostic> {
    runout
        .iter()
        .copied()
        .chain(std::iter::once(spread))
        .filter(|d| def.signature.contains(&d.covariate.as_str()) && d.p_value <= alpha)
        .cloned()
        .collect()
}

/// Out-of-fold errors: in each fold, the setting (among `fold_settings[f]`) with the best objective on the other
/// folds' runs predicts the fold's runs. Returns the per-run errors (order of `cal`) and the chosen setting per
/// fold.
fn cross_validate(
    ctx: &Context,
    cal: &[usize],
    fold_of: &[usize],
    settings: &[Vec<RunSims>],
    fold_settings: &[Vec<usize>],
) -> (Vec<CvError>, Vec<usize>) {
    let runs = ctx.model.runs();
    let k = fold_settings.len();
    let mut errors = vec![CvError { crps_m: f64::NAN, abs_m: f64::NAN }; cal.len()];
    let mut chosen = vec![0; k];
    for f in 0..k {
        let train: Vec<usize> = (0..cal.len()).filter(|&j| fold_of[j] != f).collect();
        let scored: Vec<(usize, f64)> =
            fold_settings[f].iter().map(|&s| (s, score_on(ctx.cfg, runs, &settings[s], &train))).collect();
        let best = scored.iter().min_by(|a, b| a.1.total_cmp(&b.1)).map(|x| x.0).unwrap_or(0);
        chosen[f] = best;
        for j in (0..cal.len()).filter(|&j| fold_of[j] == f) {
            let s = &settings[best][j];
            errors[j] = CvError::of(ctx.cfg, &runs[s.run], s);
        }
    }
    (errors, chosen)
}

/// The objective of a setting's simulations `setting` (one per calibration run) on the calibration runs numbered
/// `which` (indices into `setting`).
fn score_on(cfg: &CalibrationConfig, runs: &[FieldRun], setting: &[RunSims], which: &[usize]) -> f64 {
    score_of(cfg, runs, &which.iter().map(|&j| &setting[j]).collect::<Vec<_>>())
}

/// One run's out-of-fold errors.
#[derive(Debug, Clone, Copy, PartialEq)]
struct CvError {
    /// CRPS of the simulated run-outs, plus the weighted CRPS of the rebound heights of a tracked run
    /// ([`run_score`]), m.
    crps_m: f64,
    /// |median simulated − observed run-out|, m.
    abs_m: f64,
}

impl CvError {
    /// The errors of `run`'s simulations `s`.
    fn of(cfg: &CalibrationConfig, run: &FieldRun, s: &RunSims) -> CvError {
        CvError { crps_m: run_score(cfg, run, s), abs_m: (s.median_runout() - run.runout_m).abs() }
    }
}

/// The typical impact of the current model, where restitution effects are centred.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Centre {
    /// Median impact (normal approach) speed, m/s.
    pub impact_speed_mps: f64,
    /// Median impact angle, degrees.
    pub impact_angle_deg: f64,
}

/// `current` with effect `def` at `value` (its parameter), labelled `label`, centred at `centre` (see the module
/// docs).
pub fn with_effect(
    model: &dyn Model,
    current: &Candidate,
    def: &EffectDef,
    label: &str,
    material: Option<String>,
    value: Option<f64>,
    centre: &Centre,
) -> Candidate {
    let mut c = current.clone();
    if let (Some(param), Some(v)) = (def.param, value) {
        c.params.set(format!("{label}.{param}"), v);
    }
    // The effect's factor at the typical impact; the restitution (Cr, or Rn in 2DLM) is divided by it.
    let factor = match (model.kind(), def.kind, value) {
        (_, EffectKind::SpeedRestitution, Some(k)) if centre.impact_speed_mps.is_finite() => {
            1.0 / (1.0 + (centre.impact_speed_mps / k).powi(2))
        }
        (ModelKind::Rigid3d, EffectKind::AngleRestitution, Some(a)) if centre.impact_angle_deg.is_finite() => {
            (centre.impact_angle_deg.max(5.0) / 30.0).powf(-a)
        }
        _ => 1.0,
    };
    if factor > 0.0 && factor != 1.0 {
        scale_cr(&mut c, 1.0 / factor);
    }
    if def.kind == EffectKind::MassRestitution {
        let mut masses: Vec<f64> = model.runs().iter().map(|r| r.mass_kg).collect();
        masses.sort_by(|a, b| a.total_cmp(b));
        c.params.set(format!("{label}.reference_kg"), masses[masses.len() / 2]);
    }
    c.effects.push(EffectSpec { kind: def.kind, label: label.to_string(), material, region: None });
    c
}

/// `current` with a zone over `region` whose material is the region's dominant material with mobility `z` (and, in
/// 3DRB, soft-ground drag at `drag_per_s`).
pub fn with_zone(
    model: &dyn Model,
    current: &Candidate,
    label: &str,
    region: &Region,
    z: f64,
    drag_per_s: f64,
) -> Candidate {
    let mut c = current.clone();
    let dom = model.dominant_material(region);
    let g = |n: &str| current.params.get_or(&format!("{dom}.{n}"), 0.0);
    match model.kind() {
        ModelKind::Rigid3d => {
            let (cr, sd, s, d) =
                apply_mobility_3d(g("cr_mean"), g("cr_sd"), g("static_friction_deg"), g("dynamic_friction_deg"), z);
            for (n, v) in [
                ("cr_mean", cr),
                ("cr_sd", sd),
                ("static_friction_deg", s),
                ("dynamic_friction_deg", d),
                ("dynamic_friction_sd_deg", g("dynamic_friction_sd_deg")),
                ("drag_per_s", drag_per_s),
            ] {
                c.params.set(format!("{label}.{n}"), v);
            }
        }
        ModelKind::Lumped2d => {
            let (rn, rt, f) = apply_mobility_2d(g("rn_mean"), g("rt_mean"), g("friction_angle_deg"), z);
            for (n, v) in [
                ("rn_mean", rn),
                ("rn_sd", g("rn_sd")),
                ("rt_mean", rt),
                ("rt_sd", g("rt_sd")),
                ("friction_angle_deg", f),
                ("roughness_sd_deg", g("roughness_sd_deg")),
            ] {
                c.params.set(format!("{label}.{n}"), v);
            }
        }
    }
    c.effects.push(EffectSpec {
        kind: EffectKind::Zone,
        label: label.to_string(),
        material: None,
        region: Some(region.clone()),
    });
    c
}

/// The free parameters of a zone's material in a refit.
fn zone_free(ctx: &Context, label: &str) -> Vec<FreeParam> {
    let kind = ctx.model.kind();
    let names: &[&str] = match kind {
        ModelKind::Rigid3d => &["cr_mean", "static_friction_deg", "dynamic_friction_deg", "drag_per_s"],
        ModelKind::Lumped2d => &["rn_mean", "rt_mean", "friction_angle_deg"],
    };
    names
        .iter()
        .map(|n| {
            let (min, max) = match (*n, kind.default_parameter(n).bounds()) {
                // Ours: at 60/s a block in contact loses 99.8 % of its speed in a tenth of a second.
                ("drag_per_s", _) => (0.0, 60.0),
                (_, Some((a, b, _))) => (a, b),
                (_, None) => kind.parameter_range(n),
            };
            FreeParam { name: format!("{label}.{n}"), min, max }
        })
        .collect()
}

/// Settings each inner fold (and the choice on all calibration runs) carries from the race's first look to the full
/// screening (ours; docs/calibration.md, "The screening's race").
const RACE_KEEP: usize = 3;

/// The settings of one arm of the comparison: simulations of all calibration runs per setting, the candidate of
/// each, which settings each fold may choose, and which ones count for the choice on all calibration runs.
#[derive(Default)]
struct Arm {
    settings: Vec<Vec<RunSims>>,
    cands: Vec<Candidate>,
    fold_settings: Vec<Vec<usize>>,
    full: Vec<usize>,
}

impl Arm {
    /// Adds candidate `c` with `repeats` simulations of each calibration run in `cal`: `screen_repeats` for a
    /// setting simulated in full, [`CalibrationConfig::first_look_repeats`] for one that races ([`Arm::race`]);
    /// returns its setting's index.
    fn screen(&mut self, ctx: &Context, cal: &[usize], c: Candidate, repeats: usize) -> crate::Result<usize> {
        self.settings.push(ctx.sims(&screened(ctx, &c), cal, repeats)?);
        self.cands.push(c);
        Ok(self.settings.len() - 1)
    }

    /// The race (ours, after the racing algorithms of model selection, Maron & Moore 1997): of the settings at their
    /// first look, each inner fold keeps the [`RACE_KEEP`] with the best objective on its training runs, and the
    /// choice on all calibration runs likewise; those are simulated on to `screen_repeats` (`more(candidate,
    /// repeats)` simulates the repeats numbered `repeats`: the first look's simulations are their first repeats, with
    /// the same random numbers), and the others are dropped from every fold's choice. A setting no fold keeps after
    /// a few repeats is rarely the one it would choose after all of them, and the choice is then scored out of fold
    /// at the full repeats. Settings simulated in full from the start take part as they are.
    fn race(
        &mut self,
        ctx: &Context,
        cal: &[usize],
        fold_of: &[usize],
        label: &str,
        more: impl Fn(&Candidate, std::ops::Range<usize>) -> crate::Result<Vec<RunSims>>,
    ) -> crate::Result<()> {
        let (first, full) = (ctx.cfg.first_look_repeats(), ctx.cfg.screen_repeats());
        let short = |settings: &[Vec<RunSims>], s: usize| settings[s].first().is_some_and(|r| r.sims.len() < full);
        let glanced = (0..self.settings.len()).filter(|&s| short(&self.settings, s)).count();
        if glanced == 0 {
            return Ok(());
        }
        let runs = ctx.model.runs();
        let best = |pool: &[usize], which: &[usize]| -> Vec<usize> {
            let mut scored: Vec<(f64, usize)> = pool
                .iter()
                .filter(|&&s| short(&self.settings, s))
                .map(|&s| (score_on(ctx.cfg, runs, &self.settings[s], which), s))
                .collect();
            scored.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            scored.into_iter().take(RACE_KEEP).map(|(_, s)| s).collect()
        };
        let mut kept = std::collections::BTreeSet::new();
        for (f, pool) in self.fold_settings.iter().enumerate() {
            kept.extend(best(pool, &(0..cal.len()).filter(|&j| fold_of[j] != f).collect::<Vec<_>>()));
        }
        kept.extend(best(&self.full, &(0..cal.len()).collect::<Vec<_>>()));
        (ctx.log)(&format!(
            "  {label}: {glanced} settings at a first look of {first} repeats, {} of them on to {full}",
            kept.len()
        ));
        for &s in &kept {
            let rest = more(&self.cands[s], first..full)?;
            for (mine, r) in self.settings[s].iter_mut().zip(rest) {
                mine.sims.extend(r.sims);
            }
        }
        let settings = &self.settings;
        for pool in self.fold_settings.iter_mut().chain(std::iter::once(&mut self.full)) {
            pool.retain(|&s| !short(settings, s));
        }
        Ok(())
    }

    /// Adds `free` fitted from `from` as the baseline was ([`fit_population`]): on each inner fold's training runs,
    /// a setting only that fold may choose, and on all calibration runs, one for the choice on all of them. No fit
    /// sees the runs it is scored on in the cross-validation.
    fn add_fitted(
        &mut self,
        ctx: &Context,
        from: &Candidate,
        free: &[FreeParam],
        cal: &[usize],
        fold_of: &[usize],
        what: &str,
    ) -> crate::Result<()> {
        let k = self.fold_settings.len();
        // The fits run quietly (a few hundred progress lines an arm otherwise); their simulations still count.
        let quiet = |_: &str| {};
        let inner = Context::new(ctx.model, ctx.cfg, &quiet);
        let mut objectives = Vec::new();
        for f in 0..=k {
            let train: Vec<usize> = (0..cal.len()).filter(|&j| f == k || fold_of[j] != f).map(|j| cal[j]).collect();
            let (c, search, _) = fit_population(&inner, from, free, &train, what);
            objectives.push(search.f);
            let s = self.screen(ctx, cal, c, ctx.cfg.screen_repeats())?;
            if f < k {
                self.fold_settings[f].push(s);
            } else {
                self.full.push(s);
            }
        }
        ctx.simulations.fetch_add(inner.simulations.load(Ordering::Relaxed), Ordering::Relaxed);
        let folds = objectives[..k].iter().map(|v| format!("{v:.2}")).collect::<Vec<_>>().join(", ");
        (ctx.log)(&format!(
            "  {what}: objective {folds} m on each fold's training runs, {:.2} m on all calibration runs",
            objectives[k]
        ));
        Ok(())
    }
}

/// The zone arm: candidate zones per fold from the training runs' deposition excess and overrun band, and from all
/// calibration runs for the refit's start; each stepped over the zone mobility grid. Simulations whose path under
/// the baseline setting stays away from the zone are taken from it ([`sims_reusing`]).
fn zone_arm(
    ctx: &Context,
    base_arm: &Arm,
    label: &str,
    diag_sims: &[RunSims],
    cal: &[usize],
    fold_of: &[usize],
) -> crate::Result<Arm> {
    let cfg = ctx.cfg;
    let model = ctx.model;
    let frame = model.map_frame();
    let k = cfg.inner_folds;
    let mid = MOBILITY_GRID.len() / 2;
    let (reference, base) = (&base_arm.settings[mid], &base_arm.cands[mid]);
    let mut arm = Arm { fold_settings: vec![Vec::new(); k], ..Default::default() };
    // The zone settings' simulations that did not come to rest, and all of them.
    let mut unrested = (0usize, 0usize);
    // Each candidate zone over its own mobility grid (and, in 3DRB, its drag grid), from the baseline setting
    // (m = 1); the refitting cross-validation then refits the rest of the terrain with it.
    let drags: &[f64] = if model.kind() == ModelKind::Rigid3d { &ZONE_DRAG_GRID } else { &[] };
    let settings: Vec<(f64, f64)> = ZONE_MOBILITY_GRID
        .iter()
        .map(|&z| (z, 0.0))
        .chain([1.0, ZONE_SOFT_MOBILITY].into_iter().flat_map(|z| drags.iter().map(move |&c| (z, c))))
        .collect();
    // Each fold's candidate regions from its training runs (the last: from all calibration runs), as indices into
    // the distinct regions: folds often find the same zone, whose settings are then simulated once.
    let mut distinct: Vec<Region> = Vec::new();
    let mut fold_regions: Vec<Vec<usize>> = Vec::new();
    for f in 0..=k {
        let train: Vec<RunSims> =
            (0..cal.len()).filter(|&j| f == k || fold_of[j] != f).map(|j| diag_sims[j].clone()).collect();
        let mut ids = Vec::new();
        for region in zone_check(model, &train, &frame, 0, cfg.seed).regions {
            ids.push(distinct.iter().position(|d| *d == region).unwrap_or_else(|| {
                distinct.push(region);
                distinct.len() - 1
            }));
        }
        fold_regions.push(ids);
    }
    // A region's settings simulate again only the reference's simulations whose path comes near it.
    let looks = 0..cfg.first_look_repeats();
    let near_sims: usize = distinct
        .iter()
        .map(|region| {
            let near = nears(ctx, region);
            reference.iter().map(|rs| rs.repeats_in(looks.clone()).iter().filter(|s| near(s)).count()).sum::<usize>()
        })
        .sum();
    let first_looks = settings.len() * near_sims;
    (ctx.log)(&format!(
        "  {label}: {} candidate regions from the folds, {} settings each: {first_looks} simulations for their first \
         looks (of {}: the others keep clear of their region){}",
        distinct.len(),
        settings.len(),
        distinct.len() * settings.len() * cal.len() * looks.len(),
        ctx.time_for(first_looks)
    ));
    let simulated_before = ctx.simulations.load(std::sync::atomic::Ordering::Relaxed);
    // Where each distinct region's settings start in the arm, once simulated.
    let mut first_setting: Vec<Option<usize>> = vec![None; distinct.len()];
    for (f, regions) in fold_regions.iter().enumerate() {
        if regions.is_empty() {
            if f < k {
                // No zone from this fold's training runs: the arm predicts with the baseline setting.
                arm.settings.push(reference.clone());
                arm.cands.push(base.clone());
                arm.fold_settings[f].push(arm.settings.len() - 1);
            }
            continue;
        }
        for &i in regions {
            let region = &distinct[i];
            let first = match first_setting[i] {
                Some(first) => first,
                None => {
                    let first = arm.settings.len();
                    first_setting[i] = Some(first);
                    let [x0, y0, x1, y1] = region.bbox();
                    let place = match region {
                        Region::Polygon(_) => format!("x {x0:.0} to {x1:.0} m, y {y0:.0} to {y1:.0} m"),
                        Region::Interval(_) => format!("{x0:.0} to {x1:.0} m along the profile"),
                    };
                    (ctx.log)(&format!(
                        "  {label}: candidate region {} of {} ({place}), {} settings",
                        i + 1,
                        distinct.len(),
                        settings.len()
                    ));
                    for &(z, drag) in &settings {
                        let c = with_zone(model, base, label, region, z, drag);
                        let sims = sims_reusing(ctx, &c, cal, reference, region, 0..cfg.first_look_repeats())?;
                        let (n, all) = not_at_rest(&sims);
                        unrested = (unrested.0 + n, unrested.1 + all);
                        arm.settings.push(sims);
                        arm.cands.push(c);
                    }
                    first
                }
            };
            let chosen = if f < k { &mut arm.fold_settings[f] } else { &mut arm.full };
            chosen.extend(first..first + settings.len());
        }
    }
    debug_assert_eq!(ctx.simulations.load(std::sync::atomic::Ordering::Relaxed) - simulated_before, first_looks);
    let region_of =
        |c: &Candidate| c.effect(label).and_then(|e| e.region.clone()).expect("a zone setting has its region");
    arm.race(ctx, cal, fold_of, label, |c, r| sims_reusing(ctx, c, cal, reference, &region_of(c), r))?;
    if let (zone, zone_all @ 1..) = unrested {
        let (base, base_all) = not_at_rest(reference);
        (ctx.log)(&format!(
            "  {label}: {zone} of {zone_all} simulations left the terrain or ran to the time limit (the baseline: {base} \
             of {base_all})"
        ));
        if zone as f64 / zone_all as f64 > 2.0 * base as f64 / base_all as f64 + 0.01 {
            (ctx.log)(
                "  on a zone with soft-ground drag a rock creeps on, to the time limit, where the slope is steeper than \
                 its dynamic friction; if that is what lengthens this arm, a lower [simulation] max_time_s shortens it \
                 (docs/calibration-results.md, \"Why a 3DRB zone arm can take an hour\")",
            );
        }
    }
    Ok(arm)
}

/// Whether a simulation's path comes near `region`: into its bounding box widened by two map cells plus 3 m (a
/// rock's reach, the path's thinning and the flights between its points, whose impacts the path may miss; until
/// 2026-11-30 zones took whole triangles, which also reach about a cell beyond the region).
fn nears(ctx: &Context, region: &Region) -> impl Fn(&Sim) -> bool {
    let [x0, y0, x1, y1] = region.bbox();
    let margin = 2.0 * ctx.model.map_frame().cell_m + 3.0;
    move |s: &Sim| {
        s.path.iter().any(|p| {
            (p[0] as f64) >= x0 - margin
                && (p[0] as f64) <= x1 + margin
                && (p[1] as f64) >= y0 - margin
                && (p[1] as f64) <= y1 + margin
        })
    }
}

/// Simulates `cal` under `c` (the repeats numbered `repeats`), reusing `reference` (the same candidate without the
/// zone) for every simulation whose path keeps clear of the region ([`nears`]). A reused simulation is the one `c`
/// would run (same parameters off the zone, never touching it) as long as the rock draws nothing after its
/// per-material draws at release, as in the default 3DRB model and in 2DLM; with roughness, a dynamic-friction
/// spread or Cr drawn per impact, the zone's own material draw moves the later draws of `c`'s stream, and the reused
/// simulation is the same model on other random numbers.
fn sims_reusing(
    ctx: &Context,
    c: &Candidate,
    cal: &[usize],
    reference: &[RunSims],
    region: &Region,
    repeats: std::ops::Range<usize>,
) -> crate::Result<Vec<RunSims>> {
    let near = nears(ctx, region);
    let mut out: Vec<RunSims> =
        reference.iter().map(|rs| RunSims { run: rs.run, sims: rs.repeats_in(repeats.clone()).to_vec() }).collect();
    let needed: Vec<(usize, usize)> = out
        .iter()
        .enumerate()
        .flat_map(|(j, rs)| rs.sims.iter().enumerate().filter(|(_, s)| near(s)).map(move |(r, _)| (j, r)))
        .collect();
    let prepared = ctx.model.prepare(c)?;
    let runs = ctx.model.runs();
    ctx.simulations.fetch_add(needed.len(), std::sync::atomic::Ordering::Relaxed);
    let fresh = crate::parallel::collect_in_order(needed.len(), ctx.cfg.threads, |k| {
        let (j, r) = needed[k];
        super::model::as_measured(ctx.model, prepared.as_ref(), &runs[cal[j]], repeats.start + r, ctx.cfg.seed)
    });
    for ((j, r), s) in needed.into_iter().zip(fresh) {
        out[j].sims[r] = s;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibrate::model2d::Model2d;
    use crate::calibrate::synthetic::{case_2d, synthetic_2d, truth_2d, Synthetic2d};

    /// The zone arm takes from the baseline the simulations that keep clear of a region: on the default 3DRB model
    /// they are the ones the zone's own setting would run, bit for bit (the zone is split into the terrain on the
    /// terrain's own bins, so the steps of a rock that never meets it do not change).
    #[test]
    fn a_zone_setting_takes_from_the_baseline_exactly_the_simulations_it_would_run() {
        use crate::calibrate::synthetic::{case_3d, synthetic_3d, truth_3d, Synthetic3d};
        let spec = Synthetic3d { runs_per_group: 2, ..case_3d("zone", 1).unwrap() };
        let model = synthetic_3d(&spec, crate::sim::SimParams::default()).unwrap();
        let zoned = truth_3d(&spec);
        let mut plain = zoned.clone();
        plain.effects.clear();
        let cfg = CalibrationConfig { threads: 2, ..Default::default() };
        let ctx = Context::new(&model, &cfg, &|_: &str| {});
        let cal: Vec<usize> = (0..model.runs().len()).collect();
        let region = zoned.effects[0].region.clone().unwrap();
        let reference = ctx.sims(&plain, &cal, 3).unwrap();
        let near = nears(&ctx, &region);
        let all = reference.iter().flat_map(|r| &r.sims);
        let (n_near, n) = (all.clone().filter(|s| near(s)).count(), all.count());
        assert!(n_near > 0 && n_near < n, "{n_near} of {n} simulations come near the zone");
        let reused = sims_reusing(&ctx, &zoned, &cal, &reference, &region, 0..3).unwrap();
        let fresh = ctx.sims(&zoned, &cal, 3).unwrap();
        // Where they end and how they got there (a reused path summary has no share on the zone's material), to
        // the bit: Debug writes the shortest decimal that reads back as the same f64.
        let ends = |rs: &[RunSims]| -> Vec<String> {
            let sims = rs.iter().flat_map(|r| &r.sims);
            sims.map(|s| format!("{:?} {:?} {:?} {:?}", s.runout_m, s.rest_m, s.end, s.path)).collect()
        };
        let (a, b) = (ends(&reused), ends(&fresh));
        let differ: Vec<usize> = (0..a.len()).filter(|&i| a[i] != b[i]).collect();
        let first = |v: &[String]| differ.first().map(|&i| v[i].chars().take(100).collect::<String>());
        assert!(differ.is_empty(), "{} of {} differ: {:?} against {:?}", differ.len(), a.len(), first(&a), first(&b));
    }

    /// Bonferroni: a round that signalled four effects asks p <= 0.0125 of each; one that signalled none (no trial
    /// follows) or one asks `alpha`, and so does every round with the correction off.
    #[test]
    fn the_per_run_alpha_is_shared_among_the_effects_a_round_signalled() {
        let on = super::super::config::EffectsConfig::default();
        assert_eq!(per_run_alpha(&on, 4), 0.0125);
        assert_eq!(per_run_alpha(&on, 1), 0.05);
        assert_eq!(per_run_alpha(&on, 0), 0.05);
        let off = super::super::config::EffectsConfig { bonferroni: false, ..on };
        assert_eq!(per_run_alpha(&off, 4), 0.05);
    }

    /// The 2DLM `control_a` campaign (data seed 1) several tests run on: its spec, its model, all its runs as
    /// calibration runs, and their three folds.
    fn control_a_2d() -> (Synthetic2d, Model2d, Vec<usize>, Vec<usize>) {
        let spec = case_2d("control_a", 1).unwrap();
        let model = synthetic_2d(&spec, crate::lumped2d::Options2d::default()).unwrap();
        let cal: Vec<usize> = (0..model.runs().len()).collect();
        let fold_of = folds(model.runs(), &cal, 3, 1, 1);
        (spec, model, cal, fold_of)
    }

    #[test]
    fn the_one_se_rule_keeps_the_simplest_effect_that_fits_as_well_as_the_best() {
        // Per-run out-of-fold CRPS of three passing effects on 40 runs: a zone (4 parameters) best by 0.05 m on
        // average with per-run differences of sd 0.5 m (standard error 0.08 m), a speed effect (1 parameter) and
        // a second one-parameter effect 0.5 m worse than the zone everywhere.
        let zone: Vec<f64> = (0..40).map(|i| 3.0 + 0.1 * (i % 7) as f64).collect();
        let speed: Vec<f64> =
            zone.iter().enumerate().map(|(i, z)| z + 0.05 + if i % 2 == 0 { 0.5 } else { -0.5 }).collect();
        let worse: Vec<f64> = zone.iter().map(|z| z + 0.5).collect();
        let arms = [(zone.as_slice(), 4), (speed.as_slice(), 1), (worse.as_slice(), 1)];
        let pick = choose(&arms, true).unwrap();
        assert_eq!(pick.kept, 1);
        assert!(pick.simpler_than_best);
        assert_eq!(pick.within_one_se, vec![true, true, false]);
        // Without the rule, or when the simple effect is clearly worse, the largest cut is kept.
        assert_eq!(choose(&arms, false).unwrap().kept, 0);
        let pick = choose(&[(zone.as_slice(), 4), (worse.as_slice(), 1)], true).unwrap();
        assert_eq!((pick.kept, pick.simpler_than_best), (0, false));
        // Equal complexity: the better one.
        assert_eq!(choose(&[(worse.as_slice(), 1), (speed.as_slice(), 1)], true).unwrap().kept, 1);
        assert!(choose(&[], true).is_none());
    }

    #[test]
    fn slippage_friction_and_scarring_drag_are_tried_only_when_listed() {
        let names = |cfg: &CalibrationConfig| {
            allowed_effects(cfg, ModelKind::Rigid3d).iter().map(|d| d.name).collect::<Vec<_>>()
        };
        let mut cfg = CalibrationConfig::default();
        let by_default = names(&cfg);
        assert_eq!(by_default.len(), effects_for(ModelKind::Rigid3d).len() - 2);
        assert!(!by_default.contains(&"slip_friction") && !by_default.contains(&"scar_drag"));
        assert!(by_default.contains(&"rolling_resistance"));
        cfg.effects.candidates = vec!["scar_drag".into(), "slip_friction".into(), "zone".into()];
        assert_eq!(names(&cfg), ["zone", "slip_friction", "scar_drag"]);
    }

    #[test]
    fn the_strongest_proposals_are_tried_and_any_the_bounces_point_at() {
        let prop = |kind: EffectKind, residual: &str, p_value: f64| {
            let def = definition(ModelKind::Rigid3d, kind).unwrap();
            let ev = Diagnostic { covariate: "x".into(), residual: residual.into(), spearman_rho: 0.3, p_value, n: 40 };
            Proposal { def, label: def.name.into(), material: None, evidence: vec![ev], strength: p_value }
        };
        let props = vec![
            prop(EffectKind::SpeedRestitution, BOUNCE_RESIDUAL, 0.016),
            prop(EffectKind::MassRestitution, "runout", 0.02),
            prop(EffectKind::Roughness, "runout", 0.001),
            prop(EffectKind::AngleRestitution, "runout", 0.003),
        ];
        let names = |ps: Vec<Proposal>| ps.iter().map(|p| p.def.name).collect::<Vec<_>>();
        let (first, waiting) = strongest(props.clone(), 2);
        assert_eq!(names(first), ["roughness", "angle_restitution", "speed_restitution"]);
        assert_eq!(names(waiting), ["mass_restitution"]);
        assert_eq!(names(strongest(props.clone(), 3).0), ["roughness", "angle_restitution", "speed_restitution"]);
        let (first, waiting) = strongest(props, 4);
        assert_eq!((first.len(), waiting.len()), (4, 0));
    }

    #[test]
    fn a_further_batch_is_tried_only_when_none_of_the_last_passes() {
        let run = |first: Vec<u8>, waiting: Vec<u8>, passing: &[u8]| {
            let (mut tried, batches) = (Vec::new(), std::cell::RefCell::new(Vec::new()));
            let mut try_one = |p: u8| {
                tried.push(p);
                Ok(passing.contains(&p))
            };
            in_batches(first, waiting, 2, &mut try_one, &|n, left| batches.borrow_mut().push((n, left))).unwrap();
            (tried, batches.into_inner())
        };
        // The first batch passes: the rest wait.
        assert_eq!(run(vec![1, 2], vec![3, 4, 5], &[2]), (vec![1, 2], vec![]));
        // Only the fourth passes: the second batch is tried, not the third.
        assert_eq!(run(vec![1, 2], vec![3, 4, 5], &[4, 5]), (vec![1, 2, 3, 4], vec![(2, 1)]));
        // Nothing passes: all are tried.
        assert_eq!(run(vec![1, 2], vec![3, 4, 5], &[]), (vec![1, 2, 3, 4, 5], vec![(2, 1), (1, 0)]));
        // Nothing in the first batch (every proposal waits): the next is tried all the same.
        assert_eq!(run(vec![], vec![3], &[3]), (vec![3], vec![(1, 0)]));
    }

    #[test]
    fn the_spread_check_proposes_roughness_alone() {
        let d = |covariate: &str, p_value: f64| Diagnostic {
            covariate: covariate.into(),
            residual: "runout".into(),
            spearman_rho: 0.3,
            p_value,
            n: 40,
        };
        let too_narrow = d(crate::calibrate::diagnose::OUTSIDE_RANGE, 0.001);
        let hits = |kind: EffectKind, spread: &Diagnostic| {
            signature_hits(definition(ModelKind::Rigid3d, kind).unwrap(), &[&d("mass_kg", 0.5)], spread, 0.05)
        };
        assert_eq!(hits(EffectKind::Roughness, &too_narrow), vec![too_narrow.clone()]);
        for kind in [EffectKind::SpeedRestitution, EffectKind::MassRestitution, EffectKind::VegetationDrag] {
            assert!(hits(kind, &too_narrow).is_empty(), "{kind:?}");
        }
        // Within what chance gives: nothing.
        assert!(hits(EffectKind::Roughness, &d(crate::calibrate::diagnose::OUTSIDE_RANGE, 0.3)).is_empty());
    }

    #[test]
    fn a_resistance_effect_or_roughness_recentres_only_the_dynamic_friction() {
        let mut c = Candidate::default();
        for (k, v) in [("a.cr_mean", 0.3), ("a.static_friction_deg", 40.0), ("a.dynamic_friction_deg", 20.0)] {
            c.params.set(k, v);
        }
        for kind in [EffectKind::VegetationDrag, EffectKind::RollingResistance, EffectKind::Roughness] {
            assert_eq!(recentring(kind), Recentring::DynamicFriction, "{kind:?}");
        }
        scale_dynamic_friction(&mut c, 1.2);
        let d = c.params.get("a.dynamic_friction_deg").unwrap();
        assert!((d.to_radians().tan() - 20f64.to_radians().tan() / 1.2).abs() < 1e-12, "{d}");
        assert_eq!((c.params.get("a.cr_mean"), c.params.get("a.static_friction_deg")), (Some(0.3), Some(40.0)));
    }

    #[test]
    fn folding_a_recentred_candidate_keeps_the_fixed_parameters_fixed() {
        // A 2DLM campaign with Rt fixed at 0.8: the mobility factor 1.44 moves Rn, Rt and friction; folded into the
        // materials, Rn and friction keep the move and Rt is back at 0.8.
        let (_, model, _, _) = control_a_2d();
        let mut cfg = CalibrationConfig::default();
        cfg.materials.entry("ground".into()).or_default().insert("rt_mean".into(), ParamSetting::Fixed(0.8));
        let quiet = |_: &str| {};
        let ctx = Context::new(&model, &cfg, &quiet);
        let (mut c, _) = crate::calibrate::base_candidate(&model, &cfg);
        let get = |c: &Candidate, k: &str| c.params.get(&format!("ground.{k}")).unwrap();
        let (rn, f) = (get(&c, "rn_mean"), get(&c, "friction_angle_deg"));
        c.params.set(MOBILITY, 1.44);
        let out = folded(&ctx, &c);
        assert_eq!(out.params.get(MOBILITY), None);
        assert_eq!(get(&out, "rt_mean"), 0.8);
        assert!((get(&out, "rn_mean") - (rn * 1.44).min(1.0)).abs() < 1e-12);
        assert!((get(&out, "friction_angle_deg") - friction_over(f, 1.44)).abs() < 1e-12);
        // A re-centring arm simulates the folded candidate: Rt stays fixed there too.
        assert_eq!(screened(&ctx, &c), out);
        // With nothing the factor moves fixed (the standard deviations are, by default), the candidate itself.
        let free = CalibrationConfig::default();
        let ctx = Context::new(&model, &free, &quiet);
        assert_eq!(screened(&ctx, &c), c);
    }

    #[test]
    fn the_race_carries_each_folds_best_first_looks_on_to_the_full_repeats() {
        let (_, model, cal, fold_of) = control_a_2d();
        let quiet = |_: &str| {};
        let arm_of = |cfg: &CalibrationConfig| {
            let ctx = Context::new(&model, cfg, &quiet);
            let (base, _) = crate::calibrate::base_candidate(&model, cfg);
            let mut arm = Arm::default();
            for m in [0.5, 0.7, 0.85, 1.0, 1.2, 1.44, 2.0] {
                let mut c = base.clone();
                c.params.set(MOBILITY, m);
                arm.screen(&ctx, &cal, c, cfg.first_look_repeats()).unwrap();
            }
            arm.fold_settings = vec![(0..arm.settings.len()).collect(); 3];
            arm.full = (0..arm.settings.len()).collect();
            let first: Vec<Vec<RunSims>> = arm.settings.clone();
            arm.race(&ctx, &cal, &fold_of, "test", |c, r| ctx.sims_repeats(&screened(&ctx, c), &cal, r)).unwrap();
            (arm, first, ctx.simulations.load(Ordering::Relaxed))
        };
        let cfg = CalibrationConfig::default();
        assert_eq!((cfg.first_look_repeats(), cfg.screen_repeats()), (4, 20));
        let (arm, first, simulated) = arm_of(&cfg);
        let ctx = Context::new(&model, &cfg, &quiet);
        let runs = model.runs();
        let mut carried = std::collections::BTreeSet::new();
        for f in 0..=3 {
            let (pool, train): (&[usize], Vec<usize>) = if f < 3 {
                (&arm.fold_settings[f], (0..cal.len()).filter(|&j| fold_of[j] != f).collect())
            } else {
                (&arm.full, (0..cal.len()).collect())
            };
            // The fold's three best first looks go on, and only settings simulated in full stay to be chosen.
            let mut ranked: Vec<(f64, usize)> =
                (0..first.len()).map(|s| (score_on(&cfg, runs, &first[s], &train), s)).collect();
            ranked.sort_by(|a, b| a.0.total_cmp(&b.0));
            for &(_, s) in &ranked[..RACE_KEEP] {
                assert!(pool.contains(&s), "fold {f}: setting {s} of {ranked:?} not carried on");
            }
            assert!(pool.iter().all(|&s| arm.settings[s].iter().all(|r| r.sims.len() == 20)), "fold {f}");
            carried.extend(pool.iter().copied());
        }
        assert!(carried.len() < arm.settings.len(), "the race dropped nothing: {carried:?}");
        // Carried on with the same random numbers: the 20 repeats are those a full screening simulates.
        for &s in &carried {
            let full = ctx.sims(&screened(&ctx, &arm.cands[s]), &cal, 20).unwrap();
            for (a, b) in arm.settings[s].iter().zip(&full) {
                let runouts = |r: &RunSims| r.sims.iter().map(|x| x.runout_m).collect::<Vec<_>>();
                assert_eq!(runouts(a), runouts(b), "setting {s}, run {}", a.run);
            }
        }
        let n = cal.len();
        assert_eq!(simulated, 7 * n * 4 + carried.len() * n * 16);
        // Off: every setting at the full repeats and every one in every fold's choice.
        let mut off = CalibrationConfig::default();
        off.effects.race_repeats = 0;
        let (arm, _, simulated) = arm_of(&off);
        assert_eq!((arm.fold_settings[0].len(), arm.full.len(), simulated), (7, 7, 7 * n * 20));
    }

    #[test]
    fn a_refit_is_kept_only_if_it_beats_its_start_on_fresh_repeats() {
        let (spec, model, cal, fold_of) = control_a_2d();
        let train: Vec<usize> = (0..cal.len()).filter(|&j| fold_of[j] != 0).collect();
        let quiet = |_: &str| {};
        let cfg = CalibrationConfig::default();
        let ctx = Context::new(&model, &cfg, &quiet);
        let truth = truth_2d(&spec);
        let mut off = truth.clone();
        scale_cr(&mut off, 0.5);
        let screening = |c: &Candidate| ctx.sims(c, &cal, cfg.screen_repeats()).unwrap();
        let (truth_sims, off_sims) = (screening(&truth), screening(&off));
        let before = ctx.simulations.load(Ordering::Relaxed);
        // The true model beats a start with half its restitution, not the other way round, and a refit that ties its
        // start on the fresh repeats (here the start itself) is not kept.
        assert!(beats_its_start(&ctx, &truth, &off_sims, &train, "test").unwrap());
        assert!(!beats_its_start(&ctx, &off, &truth_sims, &train, "test").unwrap());
        assert!(!beats_its_start(&ctx, &truth, &truth_sims, &train, "test").unwrap());
        // Only the refit's fresh repeats of the training runs are simulated: the start's are the screening's.
        assert_eq!(ctx.simulations.load(Ordering::Relaxed) - before, 3 * train.len() * (20 - 4));
        // Without fresh repeats every refit is kept, and nothing is simulated.
        let mut same = CalibrationConfig::default();
        same.effects.screen_repeats = Some(same.search_repeats);
        let ctx = Context::new(&model, &same, &quiet);
        assert!(beats_its_start(&ctx, &off, &truth_sims, &train, "test").unwrap());
        assert_eq!(ctx.simulations.load(Ordering::Relaxed), 0);
    }

    #[test]
    fn with_the_refit_check_each_fold_whose_search_moved_is_predicted_as_its_decision_says() {
        use std::sync::Mutex;
        let (spec, model, cal, fold_of) = control_a_2d();
        let run = |check: bool| {
            let mut cfg = CalibrationConfig::default();
            (cfg.effects.refit_check, cfg.effects.cv_refit_evaluations) = (check, Some(12));
            let lines = Mutex::new(Vec::new());
            let log = |l: &str| lines.lock().unwrap().push(l.to_string());
            let ctx = Context::new(&model, &cfg, &log);
            // Fold 1 starts from the settings' start point, far off; folds 2 and 3 near the true model.
            let (far, free) = crate::calibrate::base_candidate(&model, &cfg);
            let mut near = truth_2d(&spec);
            scale_cr(&mut near, 0.9);
            let starts = vec![far, near.clone(), near];
            let sims: Vec<Vec<RunSims>> =
                starts.iter().map(|c| ctx.sims(c, &cal, cfg.screen_repeats()).unwrap()).collect();
            let sims: Vec<&[RunSims]> = sims.iter().map(|s| s.as_slice()).collect();
            let errors = refit_cv(&ctx, &starts, &sims, &free, &cal, &fold_of, "test").unwrap();
            // Each run as its fold's start predicts it.
            let by_start: Vec<CvError> = cal
                .iter()
                .map(|&j| {
                    let s = &ctx.sims(&starts[fold_of[j]], &[j], cfg.repeats).unwrap()[0];
                    CvError::of(&cfg, &model.runs()[s.run], s)
                })
                .collect();
            let decisions: Vec<String> =
                lines.into_inner().unwrap().into_iter().filter(|l| l.contains("on fresh repeats")).collect();
            (errors, by_start, decisions)
        };
        let (_, _, none) = run(false);
        assert!(none.is_empty(), "{none:?}");
        let (errors, by_start, decisions) = run(true);
        // Every fold whose search moved says what predicts it, and that is what does.
        assert!(!decisions.is_empty());
        for d in &decisions {
            let f: usize =
                d.split("fold ").nth(1).and_then(|x| x.split(':').next()).unwrap().parse::<usize>().unwrap() - 1;
            let same = (0..cal.len()).filter(|&j| fold_of[j] == f).all(|j| errors[j] == by_start[j]);
            assert_eq!(same, d.ends_with("the start predicts"), "{d}");
        }
    }

    #[test]
    fn a_restarted_arm_takes_the_materials_from_the_start_point_and_keeps_the_effects() {
        let (_, model, _, _) = control_a_2d();
        let cfg = CalibrationConfig::default();
        let quiet = |_: &str| {};
        let ctx = Context::new(&model, &cfg, &quiet);
        let (start, _) = crate::calibrate::base_candidate(&model, &cfg);
        let mut fitted = start.clone();
        fitted.params.set("ground.rn_mean", 0.02);
        fitted.params.set("ground.friction_angle_deg", 60.0);
        fitted.params.set("speed_restitution.k_mps", 9.0);
        fitted.effects.push(crate::calibrate::params::EffectSpec {
            kind: EffectKind::SpeedRestitution,
            label: "speed_restitution".into(),
            material: None,
            region: None,
        });
        let out = with_start_materials(&ctx, &fitted);
        assert_eq!(out.params.get("ground.rn_mean"), start.params.get("ground.rn_mean"));
        assert_eq!(out.params.get("ground.friction_angle_deg"), start.params.get("ground.friction_angle_deg"));
        assert_eq!((out.params.get("speed_restitution.k_mps"), out.effects.len()), (Some(9.0), 1));
    }
}
