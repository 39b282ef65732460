//! `talus profile`.

use clap::Args;
use std::path::PathBuf;
use talus::lumped2d::run_profile;

/// Run a 2D lumped-mass (2DLM) profile scenario: end points, envelopes of bounce height, speed and kinetic energy
/// along the profile, and what passes the vertical collectors.
///
/// Every key of the scenario is shown, with its unit and default, in the commented examples/profile_bench.toml
/// (README.md, "Other commands"). Writes endpoints.csv, envelopes.csv, collectors.csv, profile.csv and summary.json.
///
/// Example:
///   talus profile examples/profile_bench.toml --out outputs/profile_bench --rocks 1000 --seed 7
#[derive(Debug, Args)]
pub struct ProfileArgs {
    /// Profile scenario file (TOML).
    scenario: PathBuf,
    /// Output folder (created if missing).
    #[arg(long)]
    out: PathBuf,
    #[command(flatten)]
    control: super::RunControl,
}

pub fn run(a: ProfileArgs) -> anyhow::Result<()> {
    a.control.check()?;
    let mut scenario = super::read_profile(&a.scenario, "profile")?;
    if let Some(n) = a.control.rocks {
        if scenario.campaign.is_some() {
            anyhow::bail!("--rocks: {} releases a campaign; set its [campaign] repeats instead", a.scenario.display());
        }
        scenario.rocks = Some(n);
    }
    if let Some(s) = a.control.seed {
        scenario.seed = s;
    }
    let summary = super::with_threads(a.control.threads, || {
        run_profile(&scenario, &a.out).map_err(|e| super::running(&a.scenario, e))
    })?;
    for w in &summary.warnings {
        eprintln!("warning: {w}");
    }
    let s = summary.stop_reasons;
    say!(
        "{} rocks in {:.2} s ({:.0} rocks/s): {} stopped, {} left the profile, {} hit the event cap, {} the time cap",
        summary.rocks,
        summary.wall_time_s,
        summary.rocks_per_second,
        s.stopped,
        s.left_profile,
        s.max_events,
        s.max_time
    );
    let m = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.1}"));
    say!(
        "run-out median {} m (P95 {} m, max {} m)",
        m(summary.runout_m.p50),
        m(summary.runout_m.p95),
        m(summary.runout_m.max)
    );
    if let Some(c) = &summary.bench_capture {
        let per: Vec<String> = (1..c.fraction_per_bench.len())
            .map(|k| format!("bench {k} {:.0} %", 100.0 * c.fraction_per_bench[k]))
            .chain(std::iter::once(format!("past the last {:.0} %", 100.0 * c.fraction_per_bench[0])))
            .collect();
        say!("captured: {}", per.join(", "));
    }
    say!("wrote {} files to {}", summary.outputs.len(), a.out.display());
    Ok(())
}
