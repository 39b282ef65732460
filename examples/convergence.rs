//! Time-step convergence of the default example: the median run-out of `examples/bench_stack.toml` at the default
//! step and at half of it (same rocks, same seed).
//!
//! ```text
//! cargo run --release --example convergence              # 4,000 rocks
//! cargo run --release --example convergence -- 10000     # more rocks
//! ```

use std::path::Path;
use talus::run::{quantile_sorted, setup, RunOverrides};
use talus::scenario::ScenarioFile;

fn main() {
    let rocks: usize = std::env::args().nth(1).and_then(|s| s.parse().ok()).unwrap_or(4000);
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/bench_stack.toml");
    let sc = ScenarioFile::read(&path).and_then(|f| f.resolve(&path)).expect("scenario");
    let base = setup(&sc, &RunOverrides { rocks: Some(rocks), ..Default::default() }).expect("setup");
    let dt = base.params.dt_s;
    println!("{rocks} rocks on the bench stack");
    println!("{:>10} {:>16} {:>16} {:>16}", "dt_s", "median runout_m", "p90 runout_m", "stopped");
    let mut medians = Vec::new();
    for step in [dt, dt / 2.0] {
        let mut s = base.clone();
        s.params.dt_s = step;
        let records = talus::parallel::collect_in_order(rocks, 0, |i| s.run_rock(i, &mut ()));
        let mut runout: Vec<f64> = records.iter().map(|r| r.runout_m).collect();
        runout.sort_by(f64::total_cmp);
        let stopped = records.iter().filter(|r| r.outcome.stop_reason == talus::sim::StopReason::Stopped).count();
        let median = quantile_sorted(&runout, 0.5);
        println!("{:>10} {:>16.3} {:>16.3} {:>16}", step, median, quantile_sorted(&runout, 0.9), stopped);
        medians.push(median);
    }
    println!(
        "halving the step moves the median run-out by {:.2} %",
        100.0 * (medians[1] - medians[0]).abs() / medians[0]
    );
}
