//! `talus barrier`.

use super::progress;
use anyhow::Context;
use clap::Args;
use std::path::PathBuf;
use talus::barrier::classes::thousands;
use talus::barrier::report::floor_sentence;
use talus::barrier::{propose_models, Status};

/// Propose rockfall barrier positions: candidate lines (contours, bench crests and toes, offsets of a toe or asset
/// line) are sized from one run (length to intercept the target share of rocks, fence height, energy class, cost)
/// and ranked; the scenario is run again with the best one in place to show what still passes. Settings:
/// [barrier_design] in the scenario (see docs/barrier.md). With --models (the fold models of `talus calibrate
/// --kfold`), each model runs the same rocks on the scenario's site and the barrier must hold in every one: its
/// length meets the target share in each, its height and class are those of the model that asks most.
///
/// Example:
///   talus barrier examples/bench_stack.toml --out outputs/bench_barrier
///   talus barrier examples/tyrol.toml --out outputs/tyrol_barrier --target-share 0.95
///   talus barrier my_site.toml --models outputs/cv/fold_*/calibrated.toml --out outputs/site_barrier
#[derive(Debug, Args)]
#[command(verbatim_doc_comment)]
pub struct BarrierArgs {
    /// Scenario file (TOML).
    scenario: PathBuf,
    /// Output folder (created if missing): index.html, proposals.*, candidates.*, without_barrier/, with_barrier/.
    #[arg(long)]
    out: PathBuf,
    #[command(flatten)]
    control: super::RunControl,
    /// Share of the rocks reaching the protected zone a barrier must intercept (overrides barrier_design.target_share).
    #[arg(long)]
    target_share: Option<f64>,
    /// Number of proposals written (overrides barrier_design.best).
    #[arg(long)]
    best: Option<usize>,
    /// Do not run again with the best proposal in place.
    #[arg(long)]
    no_rerun: bool,
    /// Also write every raster as an ESRI ASCII grid.
    #[arg(long)]
    ascii_grids: bool,
    /// Calibrated models (scenario files) to design against: each runs on the scenario's terrain, sources, rocks
    /// and [barrier_design] with its own materials and [simulation] engine settings (as `talus envelope --site`).
    /// The scenario's material names must be the models'.
    #[arg(long, num_args = 1..)]
    models: Vec<PathBuf>,
    /// With --models: also size against the first model run once per model with the seeds that follow (in
    /// OUT/floor/): the design Monte Carlo noise alone asks for, beside which the models' design is read.
    #[arg(long, requires = "models")]
    floor: bool,
    /// With --models: pool the models' rocks into one ensemble (the target share and P95s of all their rocks)
    /// instead of requiring the barrier to hold under each model (barrier_design.across_models = "pooled").
    #[arg(long, requires = "models")]
    pooled: bool,
}

pub fn run(a: BarrierArgs) -> anyhow::Result<()> {
    a.control.check()?;
    let mut file = super::read_3d(&a.scenario, "barrier")?;
    if let Some(t) = a.target_share {
        file.barrier_design.target_share = t;
    }
    if let Some(b) = a.best {
        file.barrier_design.best = b;
    }
    file.barrier_design.rerun &= !a.no_rerun;
    if a.pooled {
        file.barrier_design.across_models = talus::barrier::AcrossModels::Pooled;
    }
    file.output.ascii_grids |= a.ascii_grids;
    let sc = (file.clone())
        .resolve(&a.scenario)
        .map_err(|e| anyhow::anyhow!("{e}\n  (command-line values are checked as barrier_design.* keys)"))?;
    // The models take the site as written (its paths relative to the scenario file), not as resolved.
    let mut models = super::load_models(&a.models, Some((&file, &a.scenario)), "barrier --models")?;
    if models.is_empty() {
        models.push(("scenario".to_string(), sc.clone()));
    }
    let overrides = a.control.overrides(None);
    let pb = progress::bar(0, "rocks");
    let stage = |s: &str| {
        if pb.is_hidden() {
            eprintln!("talus barrier: {s}");
        } else {
            pb.println(format!("talus barrier: {s}"));
        }
    };
    let progress = |done: usize, total: usize| {
        if done == 1 {
            pb.reset();
            pb.set_length(total as u64);
        }
        pb.set_position(done as u64);
    };
    let study = propose_models(&models, &overrides, &a.out, a.floor, &stage, &progress)
        .with_context(|| format!("talus barrier {}", a.scenario.display()))?;
    pb.finish_and_clear();
    let ranked = study.ranked();
    let sized = study.assessments.iter().filter(|x| x.status == Status::Sized).count();
    say!("{} candidate lines, {} sized; best proposals:", study.candidates.len(), sized);
    if sized == 0 {
        say!(
            "  (no candidate has barrier_design.min_rocks = {} rocks reaching its protected zone: raise --rocks, \
             lower min_rocks, or check the asset line / candidates lie where rocks run)",
            sc.file.barrier_design.min_rocks
        );
    }
    say!(
        "{:>3}  {:<34} {:>8} {:>9} {:>10} {:>10}  {:<16} {:>8} {:>8}",
        "#",
        "position",
        "length",
        "height",
        "E P95",
        "E max",
        "class",
        "share",
        "cost"
    );
    for x in ranked.iter().take(sc.file.barrier_design.best) {
        say!(
            "{:>3}  {:<34} {:>6.1} m {:>7.1} m {:>7} kJ {:>7} kJ  {:<16} {:>7.1}% {:>8}",
            x.rank.unwrap_or(0),
            x.name,
            x.length_m,
            x.fence_height_m,
            thousands(x.energy_p95_kj),
            thousands(x.energy_max_kj),
            x.class_label,
            100.0 * x.share,
            x.cost.map_or("-".to_string(), |c| format!("{c:.0}"))
        );
    }
    if let (Some(best), true) = (ranked.first(), models.len() > 1) {
        match sc.file.barrier_design.across_models {
            talus::barrier::AcrossModels::Worst => say!(
                "#1 over {} models: height set by {}, class by {}; worst share {:.1} %",
                models.len(),
                best.height_from,
                best.energy_from,
                100.0 * best.share
            ),
            talus::barrier::AcrossModels::Pooled => say!(
                "#1 over {} models pooled: {} of the {} rocks of all runs that reach the zone intercepted ({:.1} %)",
                models.len(),
                best.intercepted,
                best.rocks_reaching,
                100.0 * best.share
            ),
        }
    }
    if let Some(text) = floor_sentence(&study) {
        say!("{text} ({})", a.out.join("floor").display());
    }
    for m in &study.models {
        let (Some(r), Some(b)) = (&m.residual, &study.barrier) else { continue };
        let of = if models.len() > 1 { format!(" under {}", m.name) } else { String::new() };
        say!(
            "with {} ({} m, {} kJ){of}: rocks reaching the protected zone {} ({:.1} %) -> {} ({:.1} %); caught {}, through {}, over {}, around {}",
            b.name.as_deref().unwrap_or("the barrier"),
            b.height_m,
            thousands(b.capacity_kj),
            r.reaching_without,
            100.0 * r.probability_without(),
            r.reaching_with,
            100.0 * r.probability_with(),
            r.caught,
            r.through,
            r.over,
            r.around
        );
    }
    say!("wrote {}", a.out.join("index.html").display());
    Ok(())
}
