//! Synthetic-effect study of `talus calibrate` (issue 5): campaigns made with talus itself with an effect switched
//! on (speed-dependent restitution, restitution scaling with block mass, a drag that holds light blocks back, a
//! soft zone), plus controls without one, calibrated with the effect undeclared. Writes
//! `outputs/calibration_study/summary.json` (and one line per case on stdout; a case run again replaces its row, the
//! others keep theirs), and a full report per case.
//!
//! Run: cargo run --release --example calibration_study [-- CASE ...]   (cases: speed speed_mixed size size_drag
//! zone rough scar speed_tracked speed_mixed_tracked size_tracked speed_2 speed_3 speed_tracked_2 speed_tracked_3
//! control_a_N control_b_N control_c_N control_d_N control_e_N control_a_tracked_N control_d_tracked_N 2d_speed
//! 2d_speed_tracked 2d_control_a_tracked_N 2d_size 2d_zone 2d_control_a_N 2d_control_b_N, N = 1..3, a trailing *
//! matches a prefix; default: all; STUDY_SEEDS=N runs the controls on seeds 1..=N; STUDY_CONFIG=FILE reads the
//! settings from FILE, and the synthetic models read their bounces and rest points and simulate as those settings
//! say)
use std::time::Instant;
use talus::calibrate::synthetic::{case_2d, case_3d, synthetic_2d, synthetic_3d, zone_overlap, Hidden, Synthetic3d};
use talus::calibrate::{self, params::Region, split, CalibrationConfig, Model};
use talus::lumped2d::Options2d;

/// Builds a case's synthetic model (campaign and terrain) on demand.
type MakeModel = Box<dyn Fn() -> Box<dyn Model>>;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let want = |c: &str| {
        args.is_empty() || args.iter().any(|a| a == c || (a.ends_with('*') && c.starts_with(a.trim_end_matches('*'))))
    };
    let out = std::path::PathBuf::from("outputs/calibration_study");
    std::fs::create_dir_all(&out).unwrap();
    // Cases not run this time keep their rows from an earlier summary.
    let summary = out.join("summary.json");
    let mut rows: Vec<serde_json::Value> =
        std::fs::read_to_string(&summary).ok().and_then(|t| serde_json::from_str(&t).ok()).unwrap_or_default();
    let cfg = match std::env::var("STUDY_CONFIG") {
        Ok(p) => CalibrationConfig::read(std::path::Path::new(&p)).unwrap(),
        Err(_) => CalibrationConfig::default(),
    };
    // The synthetic models read their simulated bounces as a model read from files with these settings would.
    let bounces = cfg.bounce_weight != Some(0.0);
    let bounces_3d = cfg.bounce_weight.is_some_and(|w| w > 0.0);
    // And read their simulated rest points with the survey error the settings declare (`rest_noise_m`).
    let rest_noise = cfg.rest_noise_m;
    // And simulate with its engine settings (`[simulation]`; the figures of docs/calibration-results.md's table before
    // 2026-11-27 were measured with `impact_substeps = 1`, the default then).
    let engine = cfg.simulation.clone();
    let model_3d = move |spec: &Synthetic3d| {
        synthetic_3d(spec, engine.clone()).unwrap().with_bounce_reads(bounces_3d).with_rest_noise(rest_noise)
    };
    let mut cases: Vec<(String, MakeModel, Hidden)> = Vec::new();
    // The control cases' seeds: 1..=3, or 1..=STUDY_SEEDS.
    let n_seeds = std::env::var("STUDY_SEEDS").ok().and_then(|v| v.parse::<u64>().ok()).unwrap_or(3);
    let seeds: Vec<u64> = (1..=n_seeds).collect();
    // The effect cases on data seed 1 (`NAME`), and the speed case with and without tracks on seeds 2 and 3 as well
    // (`NAME_2`, `NAME_3`).
    let effect_cases = [
        "speed",
        "speed_mixed",
        "size",
        "size_drag",
        "zone",
        "rough",
        "speed_tracked",
        "speed_mixed_tracked",
        "size_tracked",
        // Its effect, `scar_drag`, is tried only when listed: STUDY_CONFIG must list it among `candidates`.
        "scar",
    ]
    .into_iter()
    .map(|n| (n.to_string(), n, 1))
    .chain(["speed", "speed_tracked"].into_iter().flat_map(|n| [2, 3].map(|s| (format!("{n}_{s}"), n, s))));
    for (label, name, seed) in effect_cases {
        let spec = case_3d(name, seed).unwrap();
        let (hidden, make) = (spec.hidden.clone(), model_3d.clone());
        cases.push((label, Box::new(move || Box::new(make(&spec))), hidden));
    }
    for base in
        ["control_a", "control_b", "control_c", "control_d", "control_e", "control_a_tracked", "control_d_tracked"]
    {
        for &s in &seeds {
            let (spec, make) = (case_3d(base, s).unwrap(), model_3d.clone());
            cases.push((format!("{base}_{s}"), Box::new(move || Box::new(make(&spec))), Hidden::None));
        }
    }
    for base in ["speed", "size", "zone", "control_a", "control_b", "speed_tracked", "control_a_tracked"] {
        let seeds: &[u64] = if base.starts_with("control") { &seeds } else { &[1] };
        for &s in seeds {
            let spec = case_2d(base, s).unwrap();
            let hidden = spec.hidden.clone();
            let name = if hidden == Hidden::None { format!("2d_{base}_{s}") } else { format!("2d_{base}") };
            let make = move || {
                synthetic_2d(&spec, Options2d::default())
                    .unwrap()
                    .with_bounce_reads(bounces)
                    .with_rest_noise(rest_noise)
            };
            cases.push((name, Box::new(move || Box::new(make())), hidden));
        }
    }
    for (name, make, hidden) in cases {
        if !want(&name) {
            continue;
        }
        let t = Instant::now();
        let model = make();
        let (cal, hold) = split::seeded_split(model.runs(), cfg.holdout_fraction, cfg.seed);
        let log = |m: &str| eprintln!("[{name} {:6.1} s] {m}", t.elapsed().as_secs_f64());
        let c = calibrate::calibrate(model.as_ref(), &cfg, &cal, &hold, "seeded split", Some(&out.join(&name)), &log)
            .unwrap();
        let r = &c.report;
        let added: Vec<String> = r.effects_added.iter().map(|e| e.name.clone()).collect();
        let first = r.effects_added.first();
        let named = match (hidden.kind(), first) {
            (None, None) => true,
            (Some(k), Some(e)) => {
                r.effects_tried.iter().any(|t| t.kept && t.label == e.label)
                    && calibrate::effects::by_name(model.kind(), &e.name).map(|d| d.kind == k).unwrap_or(false)
            }
            _ => false,
        };
        let overlap = match (hidden.polygon(), first.and_then(|e| e.region.as_ref())) {
            (Some(truth), Some(Region::Polygon(p))) => Some(zone_overlap(p, truth)),
            _ => None,
        };
        let (b, f) = (r.baseline.holdout.runout_mae_m, r.final_stage.holdout.runout_mae_m);
        let row = serde_json::json!({
            "case": name, "hidden": format!("{hidden:?}"), "effects_added": added, "named_right": named,
            "holdout_runout_mae_before_m": b, "holdout_runout_mae_after_m": f, "cut": 1.0 - f / b,
            "zone_overlap": overlap, "time_s": t.elapsed().as_secs_f64(), "simulations": r.timing.simulations,
            "holdout_rebound_mae_before_m": r.baseline.holdout.rebound_mae_m,
            "holdout_rebound_mae_after_m": r.final_stage.holdout.rebound_mae_m,
            "baseline_parameters": r.baseline.parameters, "final_parameters": r.final_stage.parameters,
        });
        println!("{row}");
        rows.retain(|r| r["case"] != name.as_str());
        rows.push(row);
        std::fs::write(&summary, serde_json::to_string_pretty(&rows).unwrap()).unwrap();
    }
}
