//! The Tschamut campaign simulated under parameters you give, per block and over all runs: observed and simulated
//! mean run-out, bias, run-out MAE, W1 and coverage (20 repeats per run, all 80 runs; bias, W1 and coverage each
//! beside what the runs would show were the model right, `talus::calibrate::metrics`), the mean width of a run's
//! simulated 5-95 % range and the observed run-outs' sd within a release group. For looking at what a parameter or
//! an effect does to each block without a calibration. The last column is the share of simulations that run farther than every observed
//! run of their release group (the zone check's overrun share; about 1/(n+1) for a group of n runs if the model
//! were right); `stalled` is the share of simulations that end within 1 m of their release.
//!
//! The column `edge` gives the share of runs ending below y = 135 m, observed / simulated: within 5 m of the lower
//! edge of the proxy's LPS data (y = 130 m) or past it. With `--terrain-of SETTINGS` the proxy is modified as the
//! `[terrain]` section of those calibration settings says: clipped to that data
//! (`examples/tschamut_combined_clip.toml`: a simulated rock that crosses the edge ends there) or continued level
//! past it (`examples/tschamut_combined_level.toml`); their `release_attempts`, `materials_by` and `[simulation]` (`cr_draw`, say) are used too (every
//! material gets the parameters given; with `--floor CR,DYNAMIC_DEG` the material `floor` of `materials_by = "slope"`
//! gets its own Cr and dynamic angle, its static angle the same step above it). `--roughness-m R` switches
//! on size-relative ground roughness (`Effects::roughness_m`); `--effects "KEY = VALUE, ..."` any other effect, with
//! the keys of `[simulation.effects]` (`"speed_restitution_k_mps = 6, rolling_resistance = 0.1"`, say). `--campaign DIR` reads the runs and blocks from
//! another campaign folder on the same terrain (a copy with a changed `block_metadata.csv` `shape`, say); `--runs`
//! (first) adds a table of every run: observed, simulated median and 5-95 % range, rest point.
//!
//! Run: cargo run --release --example explore_tschamut -- [--runs] [--terrain-of SETTINGS] [--roughness-m R]
//!        [--effects "KEY = VALUE, ..."] [--campaign DIR] [--floor CR,DYNAMIC_DEG] CR CR_SD
//!        STATIC_DEG DYNAMIC_DEG [VEGETATION_DRAG_KG_S [DYNAMIC_FRICTION_SD_DEG]]
//! e.g. `-- 0.30 0.06 35.4 20.3` (a W1 k-fold fold's baseline), `-- 0.30 0.06 35.4 14.0 10` (with vegetation drag)
//! and `-- 0.175 0.127 42.3 18.5 5.65 3` (and a dynamic friction spread of 3° between rocks)
use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::path::Path;
use talus::calibrate::config::CalibrationConfig;
use talus::calibrate::metrics::metrics;
use talus::calibrate::model::evaluate;
use talus::calibrate::params::Candidate;
use talus::calibrate::stats::mean;
use talus::calibrate::synthetic::material_params_3d;
use talus::calibrate::zone::overrun_share;
use talus::calibrate::{open_model, ModelKind};
use talus::sim::params::Effects;

/// The shipped campaign, whose terrain every run uses (`--campaign` changes only the runs and blocks).
const TSCHAMUT_DIR: &str = "meshes/tschamut2014";
/// Simulations per run.
const REPEATS: usize = 20;
/// The lower edge of the proxy's LPS data (its 45 m padding removed), m.
const DATA_EDGE_Y_M: f64 = 130.0;

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let (mut terrain_of, mut roughness_m, mut campaign) = (None, None, TSCHAMUT_DIR.to_string());
    let mut effects = Effects::default();
    let mut floor: Option<[f64; 2]> = None;
    let per_run = args.first().is_some_and(|a| a == "--runs");
    if per_run {
        args.remove(0);
    }
    while args.len() > 1 && args[0].starts_with("--") {
        match args.drain(..2).collect::<Vec<_>>().as_slice() {
            [flag, v] if flag == "--terrain-of" => terrain_of = Some(v.clone()),
            [flag, v] if flag == "--roughness-m" => roughness_m = Some(v.parse::<f64>().expect("a number")),
            [flag, v] if flag == "--campaign" => campaign = v.clone(),
            [flag, v] if flag == "--effects" => {
                effects = toml::from_str(&v.replace(',', "\n")).unwrap_or_else(|e| {
                    panic!("--effects takes `name = value, ...` of the [simulation.effects] keys: {e}")
                })
            }
            [flag, v] if flag == "--floor" => {
                let f: Vec<f64> = v.split(',').map(|x| x.parse().expect("--floor CR,DYNAMIC_DEG")).collect();
                floor = Some(f.try_into().expect("--floor takes two numbers: CR,DYNAMIC_DEG"));
            }
            [flag, _] => panic!("unknown option {flag}"),
            _ => unreachable!(),
        }
    }
    let args: Vec<f64> = args.iter().map(|a| a.parse().expect("numbers")).collect();
    if !(4..=6).contains(&args.len()) {
        eprintln!(
            "usage: explore_tschamut [--runs] [--terrain-of SETTINGS] [--roughness-m R] [--effects \"KEY = VALUE, ...\"] [--campaign DIR] [--floor CR,DYN] CR CR_SD \
             STATIC_DEG DYNAMIC_DEG \
             [VEGETATION_DRAG_KG_S [DYNAMIC_FRICTION_SD_DEG]]"
        );
        std::process::exit(2);
    }
    let dir = Path::new(&campaign);
    let mut cfg = CalibrationConfig::default();
    if let Some(file) = terrain_of {
        let settings = CalibrationConfig::read(Path::new(&file)).unwrap();
        cfg.terrain = settings.terrain;
        cfg.release_attempts = settings.release_attempts;
        cfg.simulation = settings.simulation;
    }
    cfg.simulation.effects = effects;
    cfg.simulation.effects.vegetation_drag_kg_s = args.get(4).copied().filter(|&c| c > 0.0);
    cfg.simulation.effects.roughness_m = roughness_m;
    let model = open_model(
        dir,
        &Path::new(TSCHAMUT_DIR).join("terrain_proxy.asc"),
        ModelKind::Rigid3d,
        &cfg,
        "explore_tschamut",
    )
    .unwrap();
    let mut c = Candidate::default();
    for name in model.materials() {
        let [cr, static_deg, dynamic_deg] = match floor {
            Some([cr, d]) if name == "floor" => [cr, d + args[2] - args[3], d],
            _ => [args[0], args[2], args[3]],
        };
        c.params.0.extend(material_params_3d(name, [cr, args[1], static_deg, dynamic_deg]).0);
        c.params.set(format!("{name}.dynamic_friction_sd_deg"), args.get(5).copied().unwrap_or(0.0));
    }
    let all: Vec<usize> = (0..model.runs().len()).collect();
    let t0 = std::time::Instant::now();
    let sims = evaluate(model.as_ref(), &c, &all, REPEATS, 1, 0).unwrap();
    let secs = t0.elapsed().as_secs_f64();
    // Every simulated rest point to the bit, hashed: an engine change that claims identical results must keep it.
    let mut digest = Sha256::new();
    for x in sims.iter().flat_map(|r| &r.sims) {
        x.rest_m.iter().for_each(|v| digest.update(v.to_le_bytes()));
    }
    let n = sims.iter().map(|r| r.sims.len()).sum::<usize>();
    println!(
        "{n} simulations in {secs:.1} s: {:.0} simulations/s; rest points' sha256 {:.16x}",
        n as f64 / secs,
        digest.finalize()
    );
    println!(
        "block  runs  observed m  simulated m  bias m  if right  MAE m  floor m  W1 m  W1 if right m  coverage  if right  90% width m  obs sd in group m  overrun  edge obs/sim  stalled"
    );
    for block in ["1", "2", "4", "all"] {
        let s: Vec<_> =
            sims.iter().filter(|s| block == "all" || model.runs()[s.run].block_id == block).cloned().collect();
        let m = metrics(model.runs(), &s);
        // The mean width of each run's simulated 5-95 % interval, and the observed run-outs' sd within each
        // release group (pooled): the two should match for coverage near 0.9.
        let width = mean(&s.iter().map(|r| r.runout_quantile(0.95) - r.runout_quantile(0.05)).collect::<Vec<_>>());
        let mut groups: BTreeMap<usize, Vec<f64>> = BTreeMap::new();
        for r in &s {
            groups.entry(model.runs()[r.run].group).or_default().push(model.runs()[r.run].runout_m);
        }
        let within: Vec<f64> = groups
            .values()
            .flat_map(|g| {
                let m = mean(g);
                g.iter().map(move |x| x - m)
            })
            .collect();
        let near_edge = |y: f64| y < DATA_EDGE_Y_M + 5.0;
        let edge_obs = s.iter().filter(|r| near_edge(model.runs()[r.run].rest_m[1])).count() as f64 / s.len() as f64;
        let sims_all: Vec<_> = s.iter().flat_map(|r| &r.sims).collect();
        let edge_sim = sims_all.iter().filter(|x| near_edge(x.rest_m[1])).count() as f64 / sims_all.len() as f64;
        let stalled = sims_all.iter().filter(|x| x.runout_m < 1.0).count() as f64 / sims_all.len() as f64;
        let n_groups = groups.len() as f64;
        let sd = (within.iter().map(|d| d * d).sum::<f64>() / (within.len() as f64 - n_groups).max(1.0)).sqrt();
        println!(
            "{block:>5}  {:>4}  {:>10.1}  {:>11.1}  {:>+6.1}  {:>8.1}  {:>5.1}  {:>7.1}  {:>4.1}  {:>13.1}  {:>8.2}  {:>8.2}  {width:>11.1}  {sd:>17.1}  {:>7.3}  {edge_obs:.2}/{edge_sim:.2}  {stalled:>7.3}",
            m.runs,
            m.observed_mean_m,
            m.simulated_mean_m,
            m.runout_bias_m,
            m.runout_bias_if_right_m,
            m.runout_mae_m,
            m.scatter_floor_mae_m,
            m.runout_w1_m,
            m.runout_w1_if_right_m,
            m.coverage_90,
            m.coverage_90_if_right,
            overrun_share(model.runs(), &s, 0..REPEATS)
        );
    }
    if per_run {
        println!("run   block  group  observed m  median m  5% m  95% m  in 5-95%  rest x m  rest y m");
        for r in &sims {
            let run = &model.runs()[r.run];
            let (lo, hi) = (r.runout_quantile(0.05), r.runout_quantile(0.95));
            println!(
                "{:<5} {:>5}  {:>5}  {:>10.1}  {:>8.1}  {lo:>4.1}  {hi:>5.1}  {:>8}  {:>8.1}  {:>8.1}",
                run.id,
                run.block_id,
                run.group,
                run.runout_m,
                r.median_runout(),
                if (lo..=hi).contains(&run.runout_m) { "yes" } else { "no" },
                run.rest_m[0],
                run.rest_m[1]
            );
        }
    }
}
