//! `talus envelope`.

use super::progress;
use anyhow::Context;
use clap::Args;
use std::path::{Path, PathBuf};
use talus::envelope::profile::run_profile_envelope;
use talus::envelope::{model_names, run_envelope, Spread3};

/// Run several scenarios of one terrain with the same seed and combine their hazard rasters cell by cell: the
/// lowest, median and highest value over the models (GeoTIFF and PNG), and how many models' rocks reach each
/// cell. Made for the fold models of `talus calibrate --kfold` (their calibrated.toml files): read beside --floor
/// (the spread of seeds alone), the maps' spread is the calibration's uncertainty. Writes envelope.md,
/// envelope.json and each model's run in models/NAME/. Given 2DLM profile scenarios (a 2DLM calibration's
/// calibrated_profile.toml files), combines their envelopes.csv and collectors.csv station by station instead,
/// with the share each bench catches.
///
/// Example:
///   talus envelope outputs/cv/fold_*/calibrated.toml --floor --out outputs/cv_envelope
///   talus envelope outputs/cv/fold_*/calibrated.toml --site my_cutting.toml --floor --out outputs/cutting
///   talus envelope outputs/cv_2d/fold_*/calibrated_profile.toml --floor --out outputs/cv_2d_envelope
#[derive(Debug, Args)]
#[command(verbatim_doc_comment)]
pub struct EnvelopeArgs {
    /// Scenario files (TOML), two or more, all on the same terrain with the same [output] cell_size_m (or all
    /// profile scenarios on the same profile).
    #[arg(required = true, num_args = 1..)]
    scenarios: Vec<PathBuf>,
    /// Output folder (created if missing).
    #[arg(long)]
    out: PathBuf,
    /// Also run the first scenario once per model with the seeds that follow (in OUT/floor/): the spread the
    /// random draws alone give at this number of rocks, beside which the models' spread is read.
    #[arg(long)]
    floor: bool,
    /// Run the models on this site instead: its terrain, sources, rocks, collectors and output settings, with each
    /// model's materials and [simulation] engine settings (effects included). The site's material names must be
    /// the models'.
    #[arg(long)]
    site: Option<PathBuf>,
    /// Also write every raster (the models' and the combined ones) as an ESRI ASCII grid (as `[output]
    /// ascii_grids = true` in the first scenario, or in the site).
    #[arg(long)]
    ascii_grids: bool,
    #[command(flatten)]
    control: super::RunControl,
}

pub fn run(a: EnvelopeArgs) -> anyhow::Result<()> {
    a.control.check()?;
    // One file given twice would read as models that agree.
    let canonical: Vec<PathBuf> = a.scenarios.iter().map(|p| p.canonicalize().unwrap_or_else(|_| p.clone())).collect();
    if let Some((i, p)) = canonical.iter().enumerate().find(|(i, p)| canonical[..*i].contains(p)) {
        anyhow::bail!(
            "{}: given twice (as model {} and as an earlier one)\n  how to fix: give each model once; an envelope \
             of one model's seeds is --floor",
            p.display(),
            i + 1
        );
    }
    if super::is_profile(&a.scenarios[0]) {
        return run_profiles(&a);
    }
    let site = a.site.as_ref().map(|p| super::read_3d(p, "envelope --site").map(|f| (f, p))).transpose()?;
    let models = super::load_models(&a.scenarios, site.as_ref().map(|(f, p)| (f, p.as_path())), "envelope")?;
    let scenarios: Vec<_> = (models.into_iter())
        .map(|(name, mut scenario)| {
            scenario.file.output.ascii_grids |= a.ascii_grids;
            (scenario, name)
        })
        .collect();
    let pb = progress::bar(0, "rocks");
    let n = scenarios.len();
    let runs = if a.floor { 2 * n } else { n };
    let progress = |run: usize, done: usize, total: usize| {
        if done == 1 {
            pb.set_length(total as u64);
            pb.set_message(format!("run {} of {runs}", run + 1));
            pb.reset();
        }
        pb.set_position(done as u64);
    };
    let summary = run_envelope(&scenarios, &a.control.overrides(None), &a.out, a.floor, &progress)
        .with_context(|| format!("combining {n} models into {}", a.out.display()))?;
    pb.finish_and_clear();
    let rocks = summary.models[0].rocks;
    let rocks = if summary.models.iter().all(|m| m.rocks == rocks) {
        format!("{rocks} rocks each")
    } else {
        "rocks as each scenario says".to_string()
    };
    say!("{n} models, {rocks} with seed {}, in {:.1} s", summary.models[0].seed, summary.wall_time_s);
    for m in &summary.models {
        say!(
            "  {}: run-out median {:.1} m (P95 {:.1} m); largest energy P95 {:.1} kJ; largest bounce P50 {:.2} m, P95 {:.2} m",
            m.name, m.runout_m.p50, m.runout_m.p95, m.max_kinetic_kj.p95, m.max_bounce_m.p50, m.max_bounce_m.p95
        );
        for w in &m.warnings {
            eprintln!("warning: model {}: {w}", m.name);
        }
    }
    if let Some(fl) = &summary.floor {
        // The same figures over the first model's seeds, as ranges: the spread the models' rows must exceed.
        say!(
            "  seeds alone ({} runs of {}): run-out median {} m (P95 {} m); largest energy P95 {} kJ; largest bounce \
             P50 {} m, P95 {} m",
            fl.models.len(),
            summary.models[0].name,
            span(&fl.models, |m| Some(m.runout_m.p50), 1),
            span(&fl.models, |m| Some(m.runout_m.p95), 1),
            span(&fl.models, |m| Some(m.max_kinetic_kj.p95), 1),
            span(&fl.models, |m| Some(m.max_bounce_m.p50), 2),
            span(&fl.models, |m| Some(m.max_bounce_m.p95), 2)
        );
    }
    say!(
        "(max - min) / median over the models, in the median cell and at P95, over the cells at least {} rocks of \
         every model reach:",
        talus::envelope::WELL_SAMPLED_ROCKS
    );
    for (i, r) in summary.rasters.iter().enumerate() {
        let pct = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{:.0} %", 100.0 * v));
        let floor = summary.floor.as_ref().map_or(String::new(), |f| {
            format!(
                "; seeds alone {} and {}",
                pct(f.rasters[i].relative_spread_p50),
                pct(f.rasters[i].relative_spread_p95)
            )
        });
        say!(
            "  {}: {} and {} ({} cells){floor}",
            r.raster,
            pct(r.relative_spread_p50),
            pct(r.relative_spread_p95),
            r.cells
        );
    }
    if summary.rasters.iter().all(|r| r.cells == 0) {
        say!(
            "  (no cell is reached by {} rocks of every model: raise --rocks to compare the maps)",
            talus::envelope::WELL_SAMPLED_ROCKS
        );
    }
    let zones = |z: &talus::envelope::ZoneSpread| {
        let ha = |x: &Spread3| match (x.min, x.max) {
            (Some(lo), Some(hi)) => format!("{:.2}-{:.2}", lo / 1e4, hi / 1e4),
            _ => "-".to_string(),
        };
        let pct =
            |d: usize, n: usize| if n == 0 { "-".to_string() } else { format!("{:.1} %", 100.0 * d as f64 / n as f64) };
        format!(
            "high {} ha, medium {} ha, low {} ha; level differs on {} of zoned cells ({} of well-sampled ones)",
            ha(&z.high_m2),
            ha(&z.medium_m2),
            ha(&z.low_m2),
            pct(z.cells_differing, z.cells_zoned),
            pct(z.well_sampled_differing, z.well_sampled_zoned)
        )
    };
    say!("hazard zones over the models: {}", zones(&summary.zones));
    if let Some(f) = &summary.floor {
        say!("  seeds alone: {}", zones(&f.zones));
    }
    for c in &summary.collectors {
        let floor = summary.floor.as_ref().and_then(|f| f.collectors.iter().find(|x| x.name == c.name));
        let seeds = floor.map_or(String::new(), |f| {
            format!(" (seeds alone {} m, {} kJ)", range(&f.passing_height_m_p95, 2), range(&f.kinetic_kj_p95, 1))
        });
        say!(
            "collector {}: passing height P95 {} m, kinetic energy P95 {} kJ over the models{seeds}; fraction crossing {}",
            c.name,
            range(&c.passing_height_m_p95, 2),
            range(&c.kinetic_kj_p95, 1),
            range(&c.fraction_crossing, 3)
        );
    }
    say!("wrote {} files to {}; read {}", summary.outputs.len(), a.out.display(), a.out.join("envelope.md").display());
    Ok(())
}

/// Whether `path` is a 2DLM profile scenario (it has a `profile` key); anything else is read as a 3D scenario,
/// whose reader reports what is wrong with it.
/// `talus envelope` on 2DLM profile scenarios.
fn run_profiles(a: &EnvelopeArgs) -> anyhow::Result<()> {
    if a.site.is_some() {
        anyhow::bail!("--site: carries 3D models to another terrain; for profile models, edit their `profile` instead");
    }
    if a.ascii_grids {
        anyhow::bail!("--ascii-grids: profile models give tables (envelopes.csv), not rasters; leave it out");
    }
    let paths: Vec<&Path> = a.scenarios.iter().map(PathBuf::as_path).collect();
    let mut scenarios = Vec::new();
    for (path, name) in paths.iter().zip(model_names(&paths)) {
        let mut sc = super::read_profile(path, "envelope")?;
        if let Some(n) = a.control.rocks {
            if sc.campaign.is_some() {
                anyhow::bail!("--rocks: {} releases a campaign; set its [campaign] repeats instead", path.display());
            }
            sc.rocks = Some(n);
        }
        scenarios.push((sc, name));
    }
    let seed = a.control.seed.unwrap_or(scenarios[0].0.seed);
    let summary = super::with_threads(a.control.threads, || {
        run_profile_envelope(&scenarios, seed, &a.out, a.floor)
            .with_context(|| format!("combining {} profile models into {}", scenarios.len(), a.out.display()))
    })?;
    let f = talus::envelope::fmt_opt;
    say!("{} profile models with seed {seed}, in {:.1} s", summary.models.len(), summary.wall_time_s);
    for m in &summary.models {
        say!(
            "  {}: {} rocks, run-out median {} m (P95 {} m); highest bounce P95 {} m, energy P95 {} kJ along the profile",
            m.name,
            m.rocks,
            f(m.runout_p50_m, 1),
            f(m.runout_p95_m, 1),
            f(m.highest_bounce_p95_m, 2),
            f(m.highest_kinetic_p95_kj, 1)
        );
    }
    if let Some(fl) = &summary.floor {
        // The same figures over the first model's seeds, as ranges: the spread the models' rows must exceed.
        say!(
            "  seeds alone ({} runs of {}): run-out median {} m (P95 {} m); highest bounce P95 {} m, energy P95 {} kJ",
            fl.models.len(),
            summary.models[0].name,
            span(&fl.models, |m| m.runout_p50_m, 1),
            span(&fl.models, |m| m.runout_p95_m, 1),
            span(&fl.models, |m| m.highest_bounce_p95_m, 2),
            span(&fl.models, |m| m.highest_kinetic_p95_kj, 1)
        );
    }
    if let Some(b) = summary.bench_fractions.get(1) {
        let seeds = summary
            .floor
            .as_ref()
            .and_then(|fl| fl.bench_fractions.get(1))
            .map_or(String::new(), |s| format!(" (seeds alone {}-{})", f(s.min, 3), f(s.max, 3)));
        say!("first bench catches {}-{} of the rocks over the models{seeds}", f(b.min, 3), f(b.max, 3));
    }
    say!("wrote envelopes.csv, collectors.csv and envelope.md to {}", a.out.display());
    Ok(())
}

/// "min-max" of `get` over `models` (a floor's runs) with `digits` decimals.
fn span<T>(models: &[T], get: impl Fn(&T) -> Option<f64>, digits: usize) -> String {
    range(&Spread3::of(models.iter().map(get)), digits)
}

/// "min-max" of `x` with `digits` decimals, `-` when it has none.
fn range(x: &Spread3, digits: usize) -> String {
    match (x.min, x.max) {
        (Some(lo), Some(hi)) => format!("{lo:.digits$}-{hi:.digits$}"),
        _ => "-".to_string(),
    }
}
