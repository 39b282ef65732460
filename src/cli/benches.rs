//! `talus benches`.

use super::progress;
use anyhow::Context;
use clap::Args;
use indicatif::ProgressBar;
use std::cell::RefCell;
use std::path::PathBuf;
use talus::benches::{run_benches, spread_statement, Model, StudyConfig};

/// Re-run the seed paper's bench design study (Section 5) with 2DLM and 3DRB side by side.
///
/// For every face angle and catch-bench width, rocks leave the crest of a stack of benches in both models; the
/// study counts the rocks captured on each bench and compares first-bench capture with the Modified Ritchie
/// Criterion (BW = 0.2 x BH + 4.5 m), the 90 % retention target and, with --records, a mine's historic events.
/// Without --config it runs the paper's study: 20 m benches, 5 benches, faces 45/60/75 degrees, widths 4-10 m,
/// 300 2DLM runs per configuration and mass, 90 3DRB runs per configuration. Flags override the config file (every key:
/// docs/benches.md; commented example: examples/benches_quick.toml). Writes capture.csv, rocks.csv, figure7_*.svg,
/// per_bench/figure6_*.svg, summary.json and report.md (and spread.csv with --repeats, records_capture.csv with
/// --records).
///
/// Examples (the paper's study; a quick one with the spread between 3 seeds):
///
///   talus benches --out outputs/benches
///
///   talus benches --out outputs/benches_quick --face-angles-deg 60,75 --bench-widths-m 4,7,10 --repeats 3
#[derive(Debug, Args)]
pub struct BenchesArgs {
    /// Study settings (TOML); every key is optional.
    #[arg(long)]
    config: Option<PathBuf>,
    /// Output folder (created if missing).
    #[arg(long)]
    out: PathBuf,
    /// 2DLM rocks per configuration and mass (0 skips 2DLM).
    #[arg(long = "runs-2dlm")]
    runs_2dlm: Option<usize>,
    /// 3DRB rocks per configuration, over all shapes and masses (0 skips 3DRB).
    #[arg(long = "runs-3drb")]
    runs_3drb: Option<usize>,
    /// Seed of all random draws (repeat r uses seed + r).
    #[arg(long)]
    seed: Option<u64>,
    /// Height of every bench face, m.
    #[arg(long)]
    bench_height_m: Option<f64>,
    /// Number of catch benches in the stack.
    #[arg(long)]
    benches: Option<usize>,
    /// Face angles, degrees, comma-separated.
    #[arg(long, value_delimiter = ',')]
    face_angles_deg: Option<Vec<f64>>,
    /// Catch-bench widths, m, comma-separated.
    #[arg(long, value_delimiter = ',')]
    bench_widths_m: Option<Vec<f64>>,
    /// Run every configuration with K seeds and report each model's spread.
    #[arg(long)]
    repeats: Option<usize>,
    /// Historic records CSV (bench_height_m,bench_width_m,face_angle_deg,runout_m).
    #[arg(long)]
    records: Option<PathBuf>,
    /// Threads, 1 to 1024 (default: all cores). Results do not depend on it.
    #[arg(long)]
    threads: Option<usize>,
}

pub fn run(a: BenchesArgs) -> anyhow::Result<()> {
    super::check_threads_flag(a.threads)?;
    let mut c = match &a.config {
        Some(p) => StudyConfig::load(p)?,
        None => StudyConfig::default(),
    };
    if let Some(v) = a.runs_2dlm {
        c.lumped2d.runs = v;
    }
    if let Some(v) = a.runs_3drb {
        c.rigid3d.runs = v;
    }
    if let Some(v) = a.seed {
        c.seed = v;
    }
    if let Some(v) = a.bench_height_m {
        c.bench_height_m = v;
    }
    if let Some(v) = a.benches {
        c.n_benches = v;
    }
    if let Some(v) = a.face_angles_deg {
        c.face_angles_deg = v;
    }
    if let Some(v) = a.bench_widths_m {
        c.bench_widths_m = v;
    }
    if let Some(v) = a.repeats {
        c.repeats = v;
    }
    if let Some(p) = a.records {
        // Relative to the working directory, not to the config file.
        c.records.file = Some(std::path::absolute(&p).with_context(|| format!("--records {}", p.display()))?);
    }
    if let Some(v) = a.threads {
        c.threads = v;
    }
    super::check_out_folder("--out", &a.out)?;
    let bar: RefCell<Option<(Model, ProgressBar)>> = RefCell::new(None);
    let progress = |model: Model, done: usize, total: usize| {
        let mut b = bar.borrow_mut();
        if b.as_ref().is_none_or(|(m, _)| *m != model) {
            if let Some((_, pb)) = b.take() {
                pb.finish_and_clear();
            }
            *b = Some((model, progress::bar(total, &format!("{} rocks", model.label()))));
        }
        if let Some((_, pb)) = b.as_ref() {
            pb.set_position(done as u64);
        }
    };
    let what =
        a.config.as_ref().map_or("the bench study".to_string(), |p| format!("the bench study of {}", p.display()));
    let summary = run_benches(&c, &a.out, &progress).with_context(|| format!("running {what}"))?;
    if let Some((_, pb)) = bar.borrow_mut().take() {
        pb.finish_and_clear();
    }
    for (t, m) in summary.timings.iter().zip(&summary.models) {
        say!(
            "{}: {} rocks in {:.2} s ({:.0} rocks/s); {} counted, {} left before passing bench 1, {} stayed at the crest",
            t.model.label(),
            t.rocks,
            t.wall_time_s,
            t.rocks_per_second,
            m.counted,
            m.left,
            m.crest
        );
    }
    say!(
        "first-bench capture at the Modified Ritchie width {:.1} m (Wilson 95 % interval; between two simulated widths it spans both):",
        summary.modified_ritchie_width_m
    );
    for h in &summary.first_bench_at_modified_ritchie {
        let v = match (h.captured_fraction, h.ci_low, h.ci_high) {
            (Some(v), Some(lo), Some(hi)) => {
                format!("{:.1} % ({:.1}-{:.1} %)", 100.0 * v, 100.0 * lo, 100.0 * hi)
            }
            _ => "outside the simulated widths".to_string(),
        };
        say!("  {:>5}° {:<8} {v}", h.face_angle_deg, h.model);
    }
    for s in &summary.spread {
        say!("{}", spread_statement(s));
    }
    say!("wrote {} files to {} (see report.md)", summary.outputs.len(), a.out.display());
    Ok(())
}
