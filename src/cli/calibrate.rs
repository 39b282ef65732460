//! `talus calibrate`.

use clap::Args;
use std::path::PathBuf;
use std::time::Instant;
use talus::calibrate::metrics::Metrics;
use talus::calibrate::{self, split, CalibrationConfig, ModelKind};

/// Calibrate a model on a field campaign, measure it on held-out runs, and add the effects it lacks.
///
/// Writes DIR/report.json, DIR/report.md, charts and residual maps, and the final model as a scenario: in 3DRB
/// DIR/calibrated.toml for `talus run`, in 2DLM DIR/calibrated_profile.toml for `talus profile`. With --kfold, runs an outer k-fold
/// cross-validation over all runs instead (DIR/fold_i/ and DIR/cv_report.json); with --kfold-repeats R > 1, R of
/// them with seeds seed, seed+1, ... (DIR/repeat_r/ and DIR/cv_repeats.json).
///
/// Example:
///   talus calibrate meshes/tschamut2014 --terrain meshes/tschamut2014/terrain_proxy.asc --model 3drb
///       --config examples/tschamut_calibrate.toml --out outputs/tschamut_calibration
#[derive(Debug, Args)]
pub struct CalibrateArgs {
    /// Campaign folder (release_points.csv, observed_deposition.csv, block_metadata.csv; optional
    /// observed_trajectories.csv, tracked paths whose rebound heights are then fitted too).
    campaign: PathBuf,
    /// Terrain file (3drb: OBJ, STL, GeoTIFF or ESRI ASCII DEM) or profile CSV (2dlm).
    #[arg(long)]
    terrain: PathBuf,
    /// Engine: 3drb or 2dlm.
    #[arg(long, default_value = "3drb")]
    model: String,
    /// File of held-out trajectory_ids, one per line (default: a seeded split, see holdout_fraction).
    #[arg(long)]
    holdout: Option<PathBuf>,
    /// Calibrate on every run and hold none out: the final parameters (and calibrated.toml) once a --kfold study
    /// has measured the held-out error of the same settings.
    #[arg(long, conflicts_with_all = ["holdout", "kfold"])]
    all_runs: bool,
    /// Settings file (TOML): free parameters and bounds, material map, repeats, seed, folds, effects.
    #[arg(long)]
    config: Option<PathBuf>,
    /// Output folder (created if missing).
    #[arg(long)]
    out: PathBuf,
    /// Seed (overrides the settings).
    #[arg(long)]
    seed: Option<u64>,
    /// Simulations per run for the reported metrics and, unless `[effects] screen_repeats` is set, the effects
    /// loop's screening (overrides the settings; default 20).
    #[arg(long)]
    repeats: Option<usize>,
    /// Threads, 1 to 1024 (default: all cores). Results do not depend on it.
    #[arg(long)]
    threads: Option<usize>,
    /// Outer k-fold cross-validation over all runs (K folds; `--kfold` alone uses outer_folds from the settings).
    #[arg(long, num_args = 0..=1)]
    kfold: Option<Option<usize>>,
    /// Repeat the k-fold study R times with seeds seed, seed+1, ... and report mean ± sd (overrides outer_repeats).
    #[arg(long, requires = "kfold")]
    kfold_repeats: Option<usize>,
}

/// Removes what an earlier calibration into the same folder wrote and this one did not, and says so.
fn remove_earlier(earlier: &calibrate::outputs::EarlierOutputs) -> anyhow::Result<()> {
    let n = earlier.remove_stale()?;
    if n > 0 {
        eprintln!("removed {n} files of an earlier calibration in the output folder that this one did not write again");
    }
    Ok(())
}

pub fn run(a: CalibrateArgs) -> anyhow::Result<()> {
    super::check_threads_flag(a.threads)?;
    let kind = ModelKind::parse(&a.model)?;
    let (mut cfg, source) = match &a.config {
        Some(p) => (CalibrationConfig::read(p)?, p.display().to_string()),
        // A default value in the way of a flag's is named as a default, changed in a settings file.
        None => (CalibrationConfig::default(), "the default settings (change them with --config FILE)".to_string()),
    };
    if let Some(s) = a.seed {
        cfg.seed = s;
    }
    if let Some(r) = a.repeats {
        cfg.repeats = r;
    }
    if let Some(r) = a.kfold_repeats {
        cfg.outer_repeats = r;
    }
    if let Some(t) = a.threads {
        cfg.threads = t;
    }
    // A value given by a flag is named by the flag, not as a key of the settings file.
    let flags: Vec<(&str, &str)> = [
        ("repeats", a.repeats.is_some(), "--repeats"),
        ("outer_repeats", a.kfold_repeats.is_some(), "--kfold-repeats"),
        ("threads", a.threads.is_some(), "--threads"),
    ]
    .into_iter()
    .filter(|&(_, given, _)| given)
    .map(|(key, _, flag)| (key, flag))
    .collect();
    cfg.validate_with_flags(&source, &flags)?;
    super::check_out_folder("--out", &a.out)?;
    let model = calibrate::open_model(&a.campaign, &a.terrain, kind, &cfg, &source)?;
    let runs = model.runs();
    // Every input is checked before the output folder is made.
    let kfold = a.kfold.map(|k| k.unwrap_or(cfg.outer_folds));
    if let Some(k) = kfold {
        if a.holdout.is_some() {
            anyhow::bail!("--kfold and --holdout exclude each other: the k-fold study holds out every run once");
        }
        if k < 2 || k > runs.len() {
            anyhow::bail!("--kfold: must be between 2 and the number of runs ({})", runs.len());
        }
    }
    let held_out = a.holdout.as_ref().map(|p| split::read_holdout(p, runs).map(|h| (p, h))).transpose()?;
    let earlier = calibrate::outputs::EarlierOutputs::list(&a.out);
    talus::io::create_folder(&a.out)?;
    let t0 = Instant::now();
    let log = move |msg: &str| eprintln!("[{:6.1} s] {msg}", t0.elapsed().as_secs_f64());
    for note in model.input_notes() {
        eprintln!("warning: {note}");
    }
    for [a, b] in calibrate::runs::duplicate_runs(runs) {
        eprintln!("warning: runs {a} and {b} are the same record (release state and rest point); both are used, kept in one fold");
    }
    if let Some(k) = kfold {
        if cfg.outer_repeats > 1 {
            let r = calibrate::repeated_cross_validation(model.as_ref(), &cfg, k, &a.out, &log)?;
            say!(
                "outer {k}-fold cross-validation repeated with seeds {:?} in {:.0} s; held-out, mean ± sd:",
                r.seeds,
                r.total_s
            );
            for m in r.summary.iter().filter(|m| m.runs == "all") {
                say!("  {} {:.2} ± {:.2}", m.metric, m.mean, m.sd);
            }
            print_parameter_spread(&r.parameters);
            remove_earlier(&earlier)?;
            print_fold_maps(&r.model, &a.out, false);
            say!("wrote {}", a.out.join("cv_repeats.md").display());
            return Ok(());
        }
        let cv = calibrate::cross_validate(model.as_ref(), &cfg, k, &a.out, &log)?;
        let (b, f) = (&cv.baseline.overall, &cv.final_set.overall);
        say!("outer {k}-fold cross-validation over {} runs in {:.0} s", b.runs, cv.total_s);
        print_errors("held-out", b, f);
        print_parameter_spread(&cv.parameters);
        remove_earlier(&earlier)?;
        print_fold_maps(&cv.model, &a.out, true);
        say!("wrote {}", a.out.join("cv_report.md").display());
        return Ok(());
    }
    let (cal, hold, note) = match held_out {
        None if a.all_runs => (
            (0..runs.len()).collect(),
            Vec::new(),
            "no held-out runs (--all-runs): every run calibrates; the held-out error is a --kfold study's".to_string(),
        ),
        Some((p, hold)) => {
            let cal: Vec<usize> = (0..runs.len()).filter(|i| !hold.contains(i)).collect();
            (cal, hold, format!("held-out runs from {}", p.display()))
        }
        None => {
            let (cal, hold) = split::seeded_split(runs, cfg.holdout_fraction, cfg.seed);
            (
                cal,
                hold,
                format!(
                    "seeded split: about {:.0} % of each release group held out, seed {}",
                    100.0 * cfg.holdout_fraction,
                    cfg.seed
                ),
            )
        }
    };
    if a.holdout.is_none() && !a.all_runs {
        let ids: Vec<&str> = hold.iter().map(|&i| runs[i].id.as_str()).collect();
        eprintln!("{note}: {}", ids.join(" "));
    }
    let c = calibrate::calibrate(model.as_ref(), &cfg, &cal, &hold, &note, Some(&a.out), &log)?;
    remove_earlier(&earlier)?;
    let r = &c.report;
    say!(
        "{} calibration runs, {} held out; {} simulations in {:.0} s",
        cal.len(),
        hold.len(),
        r.timing.simulations,
        r.timing.total_s
    );
    say!(
        "effects added: {}",
        if r.effects_added.is_empty() {
            "none".to_string()
        } else {
            let with_rivals = |e: &calibrate::effects_loop::AddedEffect| {
                let rivals: Vec<&str> =
                    e.evidence["rivals"].as_array().into_iter().flatten().filter_map(|v| v["label"].as_str()).collect();
                if rivals.is_empty() {
                    e.label.clone()
                } else {
                    format!("{} (also passed: {})", e.label, rivals.join(", "))
                }
            };
            r.effects_added.iter().map(with_rivals).collect::<Vec<_>>().join(", ")
        }
    );
    let open = r.open_parameters();
    if !open.is_empty() {
        say!("left open by the calibration runs (every value of its grid as good as the best): {}", open.join(", "));
    }
    let (set, b, f) = if hold.is_empty() {
        ("calibration (no held-out runs: fitted on these numbers)", &r.baseline.calibration, &r.final_stage.calibration)
    } else {
        ("held-out", &r.baseline.holdout, &r.final_stage.holdout)
    };
    print_errors(set, b, f);
    if let (Some(mb), Some(mf), Some(cb), Some(cf)) =
        (b.rebound_mae_m, f.rebound_mae_m, b.rebound_crps_m, f.rebound_crps_m)
    {
        say!("{set} rebound_mae_m {mb:.3} -> {mf:.3} m, rebound_crps_m {cb:.3} -> {cf:.3} m (tracked runs)");
    }
    say!("wrote {}", a.out.join("report.md").display());
    let (file, command) = match kind {
        ModelKind::Rigid3d => (calibrate::scenario_file::RUN_SCENARIO, "run"),
        ModelKind::Lumped2d => (calibrate::scenario_file::PROFILE_SCENARIO, "profile"),
    };
    say!("the final model: talus {command} {} --out MAP", a.out.join(file).display());
    Ok(())
}

/// The fitted parameters that move across the folds, as mean ± sd (fixed ones are left out).
fn print_parameter_spread(spread: &[calibrate::crossval::ParameterSpread]) {
    // Moving: not the same value in every fold (a fixed parameter's mean can carry a rounding sd of 1e-17).
    let moving: Vec<String> =
        spread.iter().filter(|p| p.max > p.min).map(|p| format!("{} {:.3} ± {:.3}", p.name, p.mean, p.sd)).collect();
    if !moving.is_empty() {
        say!("fitted across the folds, mean ± sd: {}", moving.join(", "));
    }
}

/// How to run a cross-validation's fold models side by side (in `out`; one cross-validation's when `per_fold`, else
/// every repeat's).
fn print_fold_maps(model: &str, out: &std::path::Path, per_fold: bool) {
    let models = out.join(calibrate::crossval::fold_models_glob(model, per_fold));
    say!("the fold models side by side: talus envelope {} --floor --out DIR", models.display());
    if model != "2dlm" {
        say!(
            "a barrier that holds under each: talus barrier SITE.toml --models {} --floor --out DIR",
            models.display()
        );
    }
}

/// One line of `set`'s run-out errors, baseline `b` against final `f`.
fn print_errors(set: &str, b: &Metrics, f: &Metrics) {
    say!(
        "{set} runout_mae_m {:.2} -> {:.2} m (floor {:.2}), runout_bias_m {:+.2} -> {:+.2} m (if right ±{:.2}), runout_w1_m {:.2} -> {:.2} m (if right {:.2}), coverage_90 {:.2} -> {:.2} (if right {:.2})",
        b.runout_mae_m, f.runout_mae_m, f.scatter_floor_mae_m, b.runout_bias_m, f.runout_bias_m, f.runout_bias_if_right_m, b.runout_w1_m, f.runout_w1_m, f.runout_w1_if_right_m, b.coverage_90, f.coverage_90, f.coverage_90_if_right
    );
    if talus::calibrate::report::below_floor(f) {
        say!("  ({set}: {})", talus::calibrate::report::BELOW_FLOOR);
    }
}
