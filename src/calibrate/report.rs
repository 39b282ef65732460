//! The calibration report: `report.json` (machine-readable, the keys of issue 5 and more), `report.md` (for a
//! person), SVG charts and the residual maps (GeoTIFF and PNG).

use super::backanalysis::{BackAnalysisRow, Profile, SpreadProfile};
use super::config::{CalibrationConfig, ModelKind};
use super::diagnose::{covariates, residuals, Diagnostic};
use super::effects_loop::{AddedEffect, EffectTrial};
use super::impacts::{BounceRanks, BOUNCE_NEIGHBOURS, BOUNCE_RESIDUAL};
use super::maps::residual_map;
use super::metrics::{Metrics, MetricsSet};
use super::model::{Model, RunSims};
use super::params::{Params, Region};
use super::runs::FieldRun;
use super::zone::ZoneCheck;
use crate::error::{Error, Result};
use crate::render::colormap::CATEGORICAL;
use crate::render::{
    histogram_chart, render_map, write_svg, Chart, Colormap, MapLayer, OverlayLine, Overlays, Series, SeriesStyle,
};
use crate::terrain::UpAxis;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

/// A model and its errors.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Stage {
    /// Parameter values.
    pub parameters: Params,
    /// Effects switched on (labels).
    pub effects: Vec<String>,
    /// Metrics on the calibration runs.
    pub calibration: Metrics,
    /// Metrics on the held-out runs.
    pub holdout: Metrics,
    /// Per block, calibration runs.
    pub calibration_by_block: BTreeMap<String, Metrics>,
    /// Per block, held-out runs.
    pub holdout_by_block: BTreeMap<String, Metrics>,
}

impl Stage {
    /// A stage from metric sets.
    pub fn new(parameters: Params, effects: Vec<String>, cal: MetricsSet, hold: MetricsSet) -> Stage {
        Stage {
            parameters,
            effects,
            calibration: cal.overall,
            holdout: hold.overall,
            calibration_by_block: cal.by_block,
            holdout_by_block: hold.by_block,
        }
    }
}

/// A release group.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GroupInfo {
    /// Name (`block:k`).
    pub name: String,
    /// Runs in it.
    pub runs: usize,
    /// Of which held out.
    pub holdout: usize,
}

/// Wall times and simulation counts.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Timing {
    /// Population fit, s.
    pub population_fit_s: f64,
    /// Per-run back-analysis, s.
    pub back_analysis_s: f64,
    /// Effects loop, s.
    pub effects_loop_s: f64,
    /// Final evaluation with the reported repeats, maps and report, s.
    pub final_evaluation_s: f64,
    /// Everything, s.
    pub total_s: f64,
    /// Rock simulations run.
    pub simulations: usize,
    /// Threads used.
    pub threads: usize,
}

/// Everything `report.json` holds.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Report {
    /// `3drb` or `2dlm`.
    pub model: String,
    /// Runs used to choose anything.
    pub calibration_ids: Vec<String>,
    /// Runs never used to choose anything.
    pub holdout_ids: Vec<String>,
    /// How the split was made.
    pub split: String,
    /// Release groups.
    pub release_groups: Vec<GroupInfo>,
    /// Pairs of runs that are the same record ([`super::runs::duplicate_runs`]).
    #[serde(default)]
    pub duplicate_runs: Vec<[String; 2]>,
    /// What reading the inputs noticed ([`super::Model::input_notes`]), as `talus run` warns.
    #[serde(default)]
    pub warnings: Vec<String>,
    /// The polygon past which this calibration levelled the ground, where the settings say `[terrain] level_beyond
    /// = "field"` ([`field_box_m`] of its own runs); `None` otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub levelled_beyond_m: Option<Vec<[f64; 2]>>,
    /// Runs whose baseline simulations all end at their release while the field rock ran
    /// ([`super::runs::runs_not_started`]).
    #[serde(default)]
    pub runs_not_started: Vec<String>,
    /// Runs whose baseline simulations stall in [`super::runs::STALLING_SHARE`] or more of the repeats
    /// ([`super::runs::runs_stalling`]).
    #[serde(default)]
    pub runs_stalling: Vec<super::runs::StallingRun>,
    /// The calibrated model without added effects.
    pub baseline: Stage,
    /// The model after the effects loop.
    #[serde(rename = "final")]
    pub final_stage: Stage,
    /// Effects kept.
    pub effects_added: Vec<AddedEffect>,
    /// Effects tried.
    pub effects_tried: Vec<EffectTrial>,
    /// Residual diagnosis of the baseline on the calibration runs.
    pub diagnostics: Vec<Diagnostic>,
    /// Residual diagnosis of the final model on the calibration runs.
    pub diagnostics_final: Vec<Diagnostic>,
    /// The zone check of the baseline.
    pub zone_check: Option<ZoneSummary>,
    /// How far the tracked heights of the calibration runs scatter around a smooth path, m (the median over the
    /// tracked runs of [`super::rebound::track_scatter_m`], an estimate of the tracking noise); `None` without tracks.
    #[serde(default)]
    pub track_scatter_m: Option<f64>,
    /// The bounces read from the tracks ([`super::impacts`]; each one in `impacts.csv`) and from the simulated
    /// paths read the same way, per set; empty without tracks.
    #[serde(default)]
    pub bounces: Vec<super::impacts::BounceComparison>,
    /// Material parameters the calibration runs' tracks measure ([`super::measured`]), fixed there unless the
    /// settings give them; empty without tracks.
    #[serde(default)]
    pub measured_from_tracks: Vec<super::measured::Measured>,
    /// Per-run back-analysis (mean ± sd per material).
    pub back_analysis: Vec<BackAnalysisRow>,
    /// The profile of each free spread between rocks (no per-run value; [`super::backanalysis`]).
    #[serde(default)]
    pub spread_profiles: Vec<SpreadProfile>,
    /// Objective evaluations of the population fit and its final value.
    pub population_fit: serde_json::Value,
    /// Time.
    pub timing: Timing,
    /// The settings used.
    pub settings: CalibrationConfig,
}

impl Report {
    /// Each back-analysed parameter and spread that has a profile: (`material.parameter`, population fit, profile).
    pub fn profiles(&self) -> impl Iterator<Item = (String, f64, &Profile)> {
        let rows = self.back_analysis.iter().map(|r| (&r.material, &r.parameter, r.population, &r.profile));
        let spreads = self.spread_profiles.iter().map(|s| (&s.material, &s.parameter, s.population, &s.profile));
        rows.chain(spreads).filter_map(|(m, p, fit, pr)| Some((format!("{m}.{p}"), fit, pr.as_ref()?)))
    }

    /// The back-analysed parameters and spreads whose every grid value is as good as the best (`material.parameter`):
    /// the calibration runs leave them open.
    pub fn open_parameters(&self) -> Vec<String> {
        self.profiles().filter(|(_, _, p)| p.is_open()).map(|(name, _, _)| name).collect()
    }
}

/// The zone check of the baseline on the calibration runs ([`super::zone`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ZoneSummary {
    /// Largest |deposition excess| (kernel-weighted rest points).
    pub deposition_excess: f64,
    /// Its Monte Carlo p-value.
    pub deposition_p_value: f64,
    /// Share of simulations running farther than every observed run of their release group.
    pub overrun_share: f64,
    /// Its Monte Carlo p-value.
    pub overrun_p_value: f64,
    /// The check's p-value (the smaller, doubled).
    pub p_value: f64,
}

impl From<&ZoneCheck> for ZoneSummary {
    fn from(z: &ZoneCheck) -> Self {
        ZoneSummary {
            deposition_excess: z.statistic,
            deposition_p_value: z.deposition_p_value,
            overrun_share: z.overrun_share,
            overrun_p_value: z.overrun_p_value,
            p_value: z.p_value,
        }
    }
}

/// Writes `report.json`, `report.md`, the charts and maps into `dir`, and the final model's `scenario` files
/// ([`Model::scenario_files`]).
#[allow(clippy::too_many_arguments)]
pub fn write_report(
    dir: &Path,
    report: &Report,
    model: &dyn Model,
    base_cal: &[RunSims],
    final_cal: &[RunSims],
    base_hold: &[RunSims],
    final_hold: &[RunSims],
    zone: Option<&ZoneCheck>,
    scenario: &[(String, String)],
) -> Result<()> {
    crate::io::create_folder(dir)?;
    crate::io::write_json_atomic(&dir.join("report.json"), report)?;
    let runs = model.runs();
    write_runs_csv(&dir.join("runs.csv"), model, base_cal, final_cal, base_hold, final_hold)?;
    if runs.iter().any(|r| !r.impacts.is_empty()) {
        write_impacts_csv(&dir.join("impacts.csv"), runs, base_cal, base_hold)?;
    }
    let mut figures: Vec<(String, String)> = Vec::new();
    // Covariates with a chart of run-out residual against them.
    let mut seen: Vec<String> = Vec::new();
    // Run-out distributions before and after.
    for (name, title, base, fin) in [
        ("runout_calibration.svg", "calibration runs", base_cal, final_cal),
        ("runout_holdout.svg", "held-out runs", base_hold, final_hold),
    ] {
        if base.is_empty() {
            continue;
        }
        let obs: Vec<f64> = base.iter().map(|s| runs[s.run].runout_m).collect();
        let b: Vec<f64> = base.iter().flat_map(|s| s.runouts()).collect();
        let f: Vec<f64> = fin.iter().flat_map(|s| s.runouts()).collect();
        let chart = histogram_chart(
            &format!("Run-out, {title}: observed and simulated"),
            "run-out (m)",
            &[("observed", &obs), ("baseline", &b), ("final", &f)],
            24,
        );
        write_svg(&dir.join(name), &chart)?;
        figures.push((name.into(), format!("Observed and simulated run-out distributions, {title}, before (baseline) and after (final) the effects loop.")));
    }
    // Median run-out per block (held-out runs).
    if !base_hold.is_empty() {
        let blocks: Vec<String> = {
            let mut b: Vec<String> = base_hold.iter().map(|s| runs[s.run].block_id.clone()).collect();
            b.sort();
            b.dedup();
            b
        };
        let med = |sims: &[RunSims], b: &str, observed: bool| {
            let v: Vec<f64> = sims
                .iter()
                .filter(|s| runs[s.run].block_id == b)
                .flat_map(|s| if observed { vec![runs[s.run].runout_m] } else { s.runouts() })
                .collect();
            super::stats::median(&v)
        };
        let o: Vec<f64> = blocks.iter().map(|b| med(base_hold, b, true)).collect();
        let bs: Vec<f64> = blocks.iter().map(|b| med(base_hold, b, false)).collect();
        let fs: Vec<f64> = blocks.iter().map(|b| med(final_hold, b, false)).collect();
        let cats: Vec<&str> = blocks.iter().map(|s| s.as_str()).collect();
        let mut chart = crate::render::bar_chart(
            "Median run-out per block, held-out runs",
            &cats,
            &[("observed", &o), ("baseline", &bs), ("final", &fs)],
        );
        chart.y_label = "median run-out (m)".into();
        chart.x_label = "block".into();
        write_svg(&dir.join("runout_by_block.svg"), &chart)?;
        figures.push((
            "runout_by_block.svg".into(),
            "Median observed and simulated run-out of each block on the held-out runs.".into(),
        ));
    }
    // Residual against every covariate; the four strongest shown in report.md, the others linked from its table.
    if !base_cal.is_empty() {
        let cov = covariates(model, base_cal);
        let (r0, _) = residuals(model, base_cal);
        let (r1, _) = residuals(model, final_cal);
        for d in report.diagnostics.iter().filter(|d| d.residual == "runout") {
            if seen.contains(&d.covariate) {
                continue;
            }
            let Some(x) = cov.get(&d.covariate) else { continue };
            seen.push(d.covariate.clone());
            let chart = baseline_and_final(
                format!("Run-out residual vs {} (rho = {:.2}, p = {:.3})", d.covariate, d.spearman_rho, d.p_value),
                &d.covariate,
                "observed - median simulated run-out (m)",
                [
                    x.iter().copied().zip(r0.iter().copied()).collect(),
                    x.iter().copied().zip(r1.iter().copied()).collect(),
                ],
                0.0,
            );
            let name = residual_chart(&d.covariate);
            write_svg(&dir.join(&name), &chart)?;
            if seen.len() <= 4 {
                figures.push((
                    name,
                    format!(
                        "Calibration runs' run-out residuals against {}, baseline and final (a covariate of the \
                         simulated paths is the baseline's for both).",
                        d.covariate
                    ),
                ));
            }
        }
    }
    // The observed bounces' ranks among each model's (tracked campaigns).
    for b in report.bounces.iter().filter(|b| b.set == "calibration") {
        for (base, fin) in b.baseline_ranks.iter().zip(&b.final_ranks) {
            if base.points.is_empty() && fin.points.is_empty() {
                continue;
            }
            let points = |r: &BounceRanks| r.points.iter().map(|p| (p[0], p[1])).collect();
            let chart = Chart {
                y_range: Some((0.0, 1.0)),
                ..baseline_and_final(
                    format!("Observed bounces ranked among the model's, against {}", base.covariate),
                    base.covariate,
                    "share of the model's bounces that came back slower",
                    [points(base), points(fin)],
                    0.5,
                )
            };
            let name = format!("bounce_ranks_vs_{}.svg", base.covariate);
            write_svg(&dir.join(&name), &chart)?;
            figures.push((
                name,
                format!(
                    "Each observed bounce of the calibration runs ranked by normal restitution among the model's {} \
                     simulated bounces of its run nearest in {} (docs/calibration.md, \"Bounces as evidence\"): \
                     without a trend where the model is right.",
                    BOUNCE_NEIGHBOURS, base.covariate
                ),
            ));
        }
    }
    // How sharply the runs pin each back-analysed parameter and spread.
    for (name, fit, p) in report.profiles() {
        let mut series = Series::new(
            "mean score less the lowest",
            p.values.iter().copied().zip(p.excess_m.iter().copied()).collect(),
            SeriesStyle::LineMarkers,
            CATEGORICAL[0],
        );
        let d = p.band_critical_se;
        series.error_bars =
            Some(p.excess_m.iter().zip(&p.excess_se_m).map(|(e, se)| (e - d * se, e + d * se)).collect());
        let mut series = vec![series];
        if let (Some(e), Some(se), true) = (p.population_excess_m, p.population_excess_se_m, fit.is_finite()) {
            let mut point = Series::new("population fit", vec![(fit, e)], SeriesStyle::Markers, CATEGORICAL[1]);
            let fit_d = p.population_critical_se;
            point.error_bars = Some(vec![(e - fit_d * se, e + fit_d * se)]);
            series.push(point);
        }
        let chart = Chart {
            title: format!("How sharply the calibration runs pin {name}"),
            x_label: name.clone(),
            y_label: format!("mean score less the lowest (m), ± {d:.2} paired SE"),
            series,
            hlines: vec![(0.0, String::new())],
            vlines: [(fit, "population fit".into())].into_iter().filter(|(x, _)| x.is_finite()).collect(),
            ..Default::default()
        };
        let file = profile_chart(&name);
        write_svg(&dir.join(&file), &chart)?;
        let others =
            if p.others_refit_evaluations > 0 { "fitted again at each value" } else { "at the population fit" };
        figures.push((
            file,
            format!(
                "The calibration runs' mean score (run-out CRPS plus what a track adds) along the grid of {name}, the \
                 others {others}, less the lowest, with {d:.2} paired standard errors (the fit's bar {:.2}: comparisons \
                 with the best, docs/calibration.md, \"Bands that hold the truth\"): a value whose bar reaches 0 is as \
                 good as the best ({}).",
                p.population_critical_se,
                p.describe()
            ),
        ));
    }
    // Residual maps.
    let frame = model.map_frame();
    let zones: Vec<&Region> = report.effects_added.iter().filter_map(|e| e.region.as_ref()).collect();
    for (stem, sims, what) in [("residual_map", base_cal, "baseline"), ("residual_map_final", final_cal, "final model")]
    {
        if sims.is_empty() {
            continue;
        }
        let grid = residual_map(model, sims, &frame);
        if frame.profile {
            let pts: Vec<(f64, f64)> =
                (0..grid.ncols).filter_map(|c| grid.get(c, 0).map(|v| (grid.cell_centre(c, 0).0, v as f64))).collect();
            let chart = Chart {
                title: format!("Run-out residual along the profile ({what})"),
                x_label: "x (m)".into(),
                y_label: "mean residual of runs passing (m)".into(),
                series: vec![Series::new("residual", pts, SeriesStyle::LineMarkers, CATEGORICAL[0])],
                hlines: vec![(0.0, String::new())],
                vlines: zones
                    .iter()
                    .flat_map(|r| match r {
                        Region::Interval([a, b]) => vec![(*a, "zone".to_string()), (*b, String::new())],
                        _ => vec![],
                    })
                    .collect(),
                ..Default::default()
            };
            write_svg(&dir.join(format!("{stem}.svg")), &chart)?;
            figures.push((
                format!("{stem}.svg"),
                format!("Mean run-out residual of the calibration runs passing each point of the profile ({what})."),
            ));
            continue;
        }
        crate::io::geotiff::write_grid(&dir.join(format!("{stem}.tif")), &grid)?;
        let mut layer = MapLayer::new(&grid, format!("Run-out residual, {what} (observed - simulated)"), "m");
        layer.colormap = Colormap::Diverging;
        layer.range = robust_range(&grid);
        let overlays = Overlays {
            points: sims.iter().map(|s| (runs[s.run].rest_m[0], runs[s.run].rest_m[1])).collect(),
            point_label: Some("observed rest points".into()),
            lines: zones
                .iter()
                .filter_map(|r| match r {
                    Region::Polygon(p) => {
                        let mut xy: Vec<(f64, f64)> = p.iter().map(|q| (q[0], q[1])).collect();
                        xy.push(xy[0]);
                        Some(OverlayLine { xy, colour: [20, 20, 20], width_px: 2.0, label: Some("zone".into()) })
                    }
                    _ => None,
                })
                .collect(),
            ..Default::default()
        };
        render_map(&dir.join(format!("{stem}.png")), &layer, frame.dem.as_ref(), &overlays)?;
        figures.push((format!("{stem}.png"), format!("Residual map ({what}): mean run-out residual of the calibration runs whose simulated paths cross each cell before their observed run-out (GeoTIFF: {stem}.tif).")));
    }
    if let Some(z) = zone {
        if !frame.profile {
            crate::io::geotiff::write_grid(&dir.join("deposition_excess.tif"), &z.excess)?;
            let mut layer =
                MapLayer::new(&z.excess, "Deposition excess (observed - simulated rest density)", "rests per cell");
            layer.colormap = Colormap::Diverging;
            layer.range = robust_range(&z.excess);
            render_map(&dir.join("deposition_excess.png"), &layer, frame.dem.as_ref(), &Overlays::default())?;
            figures.push((
                "deposition_excess.png".into(),
                format!("Deposition excess of the baseline (zone check p = {:.3}).", z.p_value),
            ));
        }
    }
    for (name, text) in scenario {
        crate::io::write_bytes_atomic(&dir.join(name), text.as_bytes())?;
    }
    let md = markdown(report, &figures, &seen, scenario.first().map(|f| f.0.as_str()));
    crate::io::write_bytes_atomic(&dir.join("report.md"), md.as_bytes())
}

/// A chart of the baseline's and the final model's points (markers), with a horizontal line where the model is right.
fn baseline_and_final(title: String, x_label: &str, y_label: &str, points: [Vec<(f64, f64)>; 2], right: f64) -> Chart {
    let [base, fin] = points;
    Chart {
        title,
        x_label: x_label.into(),
        y_label: y_label.into(),
        series: vec![
            Series::new("baseline", base, SeriesStyle::Markers, CATEGORICAL[1]),
            Series::new("final", fin, SeriesStyle::Markers, CATEGORICAL[2]),
        ],
        hlines: vec![(right, String::new())],
        ..Default::default()
    }
}

/// The file of the chart of the profile of `name` (`material.parameter`; a character other than a letter, digit,
/// `.`, `_` or `-` in a material's name becomes `_`).
fn profile_chart(name: &str) -> String {
    let safe: String =
        name.chars().map(|c| if c.is_ascii_alphanumeric() || "._-".contains(c) { c } else { '_' }).collect();
    format!("profile_{safe}.svg")
}

/// The file of the chart of run-out residual against `covariate`.
fn residual_chart(covariate: &str) -> String {
    format!("residual_vs_{covariate}.svg")
}

/// `runs.csv`: one row per run with its set, group, observed run-out, the baseline's and the final model's median
/// and 5–95 % run-out, residuals, and the covariates of the diagnosis (from the baseline).
fn write_runs_csv(
    path: &Path,
    model: &dyn Model,
    base_cal: &[RunSims],
    final_cal: &[RunSims],
    base_hold: &[RunSims],
    final_hold: &[RunSims],
) -> Result<()> {
    use std::io::Write as _;
    let runs = model.runs();
    let base: Vec<&RunSims> = base_cal.iter().chain(base_hold).collect();
    let fin: Vec<&RunSims> = final_cal.iter().chain(final_hold).collect();
    let all_base: Vec<RunSims> = base.iter().map(|s| (*s).clone()).collect();
    let cov = covariates(model, &all_base);
    crate::io::write_atomic(path, |w| {
        let io = |e| Error::io(path, e);
        write!(w, "trajectory_id,set,block_id,group,observed_runout_m,baseline_median_m,baseline_p05_m,baseline_p95_m,final_median_m,final_p05_m,final_p95_m,final_residual_m,baseline_stalled_share").map_err(io)?;
        for n in &cov.names {
            write!(w, ",{n}").map_err(io)?;
        }
        writeln!(w).map_err(io)?;
        for (k, (b, f)) in base.iter().zip(&fin).enumerate() {
            let r = &runs[b.run];
            let set = if k < base_cal.len() { "calibration" } else { "holdout" };
            write!(
                w,
                "{},{set},{},{},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{:.2}",
                r.id,
                r.block_id,
                model.groups().names[r.group],
                r.runout_m,
                b.median_runout(),
                b.runout_quantile(0.05),
                b.runout_quantile(0.95),
                f.median_runout(),
                f.runout_quantile(0.05),
                f.runout_quantile(0.95),
                r.runout_m - f.median_runout(),
                super::runs::stalled_share(b)
            )
            .map_err(io)?;
            for c in &cov.values {
                write!(w, ",{:.4}", c[k]).map_err(io)?;
            }
            writeln!(w).map_err(io)?;
        }
        Ok(())
    })
}

/// `impacts.csv`: one row per bounce read from a track ([`super::impacts`]), with its run and set.
fn write_impacts_csv(path: &Path, runs: &[FieldRun], cal: &[RunSims], hold: &[RunSims]) -> Result<()> {
    use std::io::Write as _;
    crate::io::write_atomic(path, |w| {
        let io = |e| Error::io(path, e);
        writeln!(w, "trajectory_id,set,time_s,x_m,y_m,z_m,normal_speed_in_mps,tangential_speed_in_mps,incidence_deg,normal_restitution,tangential_restitution").map_err(io)?;
        for (set, sims) in [("calibration", cal), ("holdout", hold)] {
            for s in sims {
                let r = &runs[s.run];
                for i in &r.impacts {
                    let [x, y, z] = i.position_m;
                    let et = i.tangential_restitution.map_or(String::new(), |v| format!("{v:.4}"));
                    writeln!(
                        w,
                        "{},{set},{:.3},{x:.3},{y:.3},{z:.3},{:.3},{:.3},{:.2},{:.4},{et}",
                        r.id,
                        i.time_s,
                        i.normal_speed_in_mps,
                        i.tangential_speed_in_mps,
                        i.incidence_deg,
                        i.normal_restitution
                    )
                    .map_err(io)?;
                }
            }
        }
        Ok(())
    })
}

/// A colour range symmetric about 0 at the 95th percentile of |value| (ours: one extreme cell would otherwise wash
/// out the map).
fn robust_range(g: &crate::raster::Grid) -> Option<(f32, f32)> {
    let abs: Vec<f64> = g.values.iter().filter(|v| v.is_finite()).map(|v| v.abs() as f64).collect();
    let q = super::stats::quantile_sorted(&super::stats::sorted(&abs), 0.95) as f32;
    (q.is_finite() && q > 0.0).then_some((-q, q))
}

fn fmt(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.2}")
    } else {
        "–".into()
    }
}

/// [`fmt`] with the sign always shown (a bias).
fn signed(v: f64) -> String {
    if v.is_finite() {
        format!("{v:+.2}")
    } else {
        fmt(v)
    }
}

/// Whether held-out metrics meet issue 5's aims: bias within ±3 m, W1 under 5 m, coverage in [0.8, 0.97], MAE
/// within 20 % of the floor.
pub fn aims(m: &Metrics) -> [bool; 4] {
    let [bias, w1, coverage] = distribution_aims(m.runout_bias_m, m.runout_w1_m, m.coverage_90);
    [bias, w1, coverage, m.runout_mae_m <= 1.2 * m.scatter_floor_mae_m]
}

/// True when a model's `runout_mae_m` is below the scatter floor: the floor then is no lower bound, because the runs of
/// a release group are not repeats of one release (they differ in release height, speed or point within
/// `group_link_m`), and MAE/floor is not to be read as an aim.
pub fn below_floor(m: &Metrics) -> bool {
    m.runs > 0 && m.runout_mae_m < m.scatter_floor_mae_m
}

/// What [`below_floor`] means, for the report and the command line.
pub const BELOW_FLOOR: &str = "the model's run-out MAE is below the scatter floor: the runs of a release group are \
     not repeats of one release (they differ in release height, speed or point within group_link_m), so the floor is \
     no lower bound here and MAE/floor is no aim to read";

/// Whether a right model would meet the aims of bias, W1 and coverage on these runs, on average (the yardsticks of
/// [`Metrics`]: the RMS bias, the mean W1 and coverage were the field runs draws of the model), in the order of
/// [`aims`].
pub fn aims_if_right(m: &Metrics) -> [bool; 3] {
    distribution_aims(m.runout_bias_if_right_m, m.runout_w1_if_right_m, m.coverage_90_if_right)
}

/// Issue 5's aims for a bias, a W1 and a coverage: within ±3 m, under 5 m, in [0.8, 0.97].
fn distribution_aims(bias_m: f64, w1_m: f64, coverage: f64) -> [bool; 3] {
    [bias_m.abs() <= 3.0, w1_m < 5.0, (0.8..=0.97).contains(&coverage)]
}

/// The header of a table of [`metrics_rows`], with its legend above it.
pub(super) fn metrics_header(s: &mut String) {
    let _ = writeln!(s, "Run-out MAE, W1, bias and end-point MAE in metres; floor: the run-out MAE of the observed runs' own group median (over the group's calibration and held-out runs); W1, coverage and bias if right: what these runs would show were their field run-outs draws of the model itself (the mean; for the bias the root mean square: a small sample shows a W1 and a bias even against the true model, and a 5–95 % interval of R simulations holds about 0.9 (R − 1)/(R + 1) of further draws; docs/calibration.md); ✗: misses the aim of issue 5 (bias within ±3 m, W1 < 5 m, coverage 0.8–0.97, MAE within 20 % of the floor); ✗†: a right model would miss it too on these runs, on average, so the miss alone does not tell a wrong model from a right one.\n");
    let _ = writeln!(s, "| model, runs | n | runout_mae_m | runout_w1_m | W1 if right | coverage_90 | coverage if right | runout_bias_m | bias if right | endpoint_mae_m | floor | MAE/floor |");
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|---|---|");
}

/// One row of the metrics table under [`metrics_header`], each aim the row misses marked (nothing for no runs).
pub(super) fn metrics_rows(s: &mut String, label: &str, m: &Metrics) {
    if m.runs == 0 {
        return;
    }
    let (a, r) = (aims(m), aims_if_right(m));
    let mark = |k: usize| match (a[k], r.get(k).copied().unwrap_or(true)) {
        (true, _) => "",
        (false, true) => " ✗",
        (false, false) => " ✗†",
    };
    let _ = writeln!(
        s,
        "| {label} | {} | {}{} | {}{} | {} | {}{} | {} | {}{} | {} | {} | {} | {} |",
        m.runs,
        fmt(m.runout_mae_m),
        mark(3),
        fmt(m.runout_w1_m),
        mark(1),
        fmt(m.runout_w1_if_right_m),
        fmt(m.coverage_90),
        mark(2),
        fmt(m.coverage_90_if_right),
        signed(m.runout_bias_m),
        mark(0),
        fmt(m.runout_bias_if_right_m),
        fmt(m.endpoint_mae_m),
        fmt(m.scatter_floor_mae_m),
        fmt(m.mae_over_floor())
    );
}

/// The markdown report: `figures` (file, caption) shown, the covariates `charted` linked to their residual chart,
/// and a note on the `scenario` file written, if any.
pub fn markdown(r: &Report, figures: &[(String, String)], charted: &[String], scenario: Option<&str>) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# Calibration report ({})\n", r.model);
    let _ = writeln!(
        s,
        "{} calibration runs, {} held-out runs ({}). {} release groups. {} simulations in {:.0} s on {} threads.\n",
        r.calibration_ids.len(),
        r.holdout_ids.len(),
        r.split,
        r.release_groups.len(),
        r.timing.simulations,
        r.timing.total_s,
        r.timing.threads
    );
    let stages = [&r.baseline.calibration, &r.baseline.holdout, &r.final_stage.calibration, &r.final_stage.holdout];
    if stages.iter().any(|m| below_floor(m)) {
        let _ = writeln!(s, "**The floor:** {BELOW_FLOOR}.\n");
    }
    for w in &r.warnings {
        let _ = writeln!(s, "**Warning:** {w}\n");
    }
    if let Some(p) = &r.levelled_beyond_m {
        let _ = writeln!(s, "**Ground:** {}.\n", levelled_note(p));
    }
    if r.settings.terrain.up == UpAxis::Y && r.model == "3drb" {
        let _ = writeln!(
            s,
            "**Axes:** the terrain's files are y-up; positions in this report (rest points, maps, zones) are in \
             talus's z-up axes, (x, −z, y) of the files'; the written scenario gives its polygons in the files' x \
             and z.\n"
        );
    }
    for [a, b] in &r.duplicate_runs {
        let _ = writeln!(
            s,
            "**Duplicate record:** runs {a} and {b} have the same release state and rest point; both are used (the \
             run weighs twice), always on the same side of a split or fold.\n"
        );
    }
    let attempts = r.settings.release_attempts;
    let released =
        if attempts > 1 { format!(" after {attempts} releases (`release_attempts`)") } else { String::new() };
    for id in &r.runs_not_started {
        let _ = writeln!(
            s,
            "**Run not started:** every baseline simulation of {id} ends within {} m of its release{released} while \
             the field rock ran farther; its error comes from the release state or the terrain at the release, not \
             from the parameters.\n",
            super::runs::NOT_STARTED_M
        );
    }
    if !r.runs_stalling.is_empty() {
        let _ = writeln!(
            s,
            "**Runs that stall at the release:** {} (the share of baseline simulations ending within {} m of the \
             release{released}; each field rock ran farther). The others of their simulations run the slope, so \
             the median run-out of such a run, and the run-out MAE and coverage with it, flip as the share crosses \
             one half.\n",
            r.runs_stalling
                .iter()
                .map(|x| format!("{} ({}, {:.2})", x.trajectory_id, x.set, x.stalled_share))
                .collect::<Vec<_>>()
                .join(", "),
            super::runs::NOT_STARTED_M
        );
    }
    let _ = writeln!(s, "## Errors\n");
    metrics_header(&mut s);
    for (name, st) in [("baseline", &r.baseline), ("final", &r.final_stage)] {
        metrics_rows(&mut s, &format!("{name}, held-out"), &st.holdout);
        for (b, m) in &st.holdout_by_block {
            metrics_rows(&mut s, &format!("{name}, held-out, block {b}"), m);
        }
        metrics_rows(&mut s, &format!("{name}, calibration"), &st.calibration);
        for (b, m) in &st.calibration_by_block {
            metrics_rows(&mut s, &format!("{name}, calibration, block {b}"), m);
        }
    }
    if r.baseline.calibration.rebound_mae_m.is_some() {
        let _ = writeln!(s, "\n### Rebound heights of the tracked runs\n");
        let _ = writeln!(s, "The rebound height is the largest rise of the centre of mass above the ground over the lowest it had been (docs/calibration.md); each tracked run's rebound CRPS counts {} m of run-out in the score (`rebound_weight`).\n", fmt(r.settings.rebound_weight.unwrap_or(0.0)));
        if let Some(scatter) = r.track_scatter_m {
            let declared =
                r.settings.track_noise_m.map_or("none declared".to_string(), |sd| format!("declared {} m", fmt(sd)));
            let _ = writeln!(s, "The tracked heights scatter by {} m around a smooth path (median over the calibration runs, an estimate of the tracking noise; `track_noise_m`: {declared}).\n", fmt(scatter));
        }
        if !r.bounces.is_empty() {
            let _ = writeln!(s, "Bounces read from the tracks, and from each model's simulated paths read the same way (as rebound heights are: at the tracks' times with the declared tracking noise, or as recorded; `impacts.csv` lists the observed ones; docs/calibration.md, \"Impacts read from tracks\"). Only bounces with a readable flight on each side count, and a rigid body's centre does not come back at Cr: compare the rows, not a row with Cr.");
            let weight = r.settings.bounce_weight.unwrap_or(0.0);
            let scored = if weight > 0.0 {
                format!("In the score the mean tangential-restitution CRPS of a tracked run's observed bounces against its simulated ones counts {} m of run-out (`bounce_weight`; docs/calibration.md, \"Bounces in the score\").\n", fmt(weight))
            } else {
                "The bounces are not in the score (`bounce_weight` 0: the default in 3DRB; in 2DLM fewer than 20 bounces with a tangential restitution, or set so).\n".to_string()
            };
            let _ = writeln!(s, "{scored}");
            let _ = writeln!(s, "| paths | bounces per path | normal restitution, median (quartiles) | tangential, median | normal impact speed, median m/s |");
            let _ = writeln!(s, "|---|---|---|---|---|");
            for b in &r.bounces {
                let set = if b.set == "holdout" { "held-out" } else { "calibration" };
                for (name, summary) in [
                    ("observed", Some(&b.observed)),
                    ("baseline", b.baseline.as_ref()),
                    ("final", b.final_model.as_ref()),
                ] {
                    if let Some(i) = summary {
                        let opt = |v: Option<f64>| v.map_or("–".to_string(), fmt);
                        let en = match (i.normal_restitution_median, i.normal_restitution_iqr) {
                            (Some(m), Some([a, b])) => format!("{} ({}–{})", fmt(m), fmt(a), fmt(b)),
                            _ => "–".into(),
                        };
                        let _ = writeln!(
                            s,
                            "| {name}, {set} ({}) | {:.2} | {en} | {} | {} |",
                            i.paths,
                            i.per_path,
                            opt(i.tangential_restitution_median),
                            opt(i.normal_speed_in_median_mps)
                        );
                    }
                }
            }
            let _ = writeln!(s);
            let ranked: Vec<String> = [("baseline", &r.diagnostics), ("final", &r.diagnostics_final)]
                .iter()
                .flat_map(|(model, ds)| {
                    ds.iter().filter(|d| d.residual == BOUNCE_RESIDUAL).map(move |d| {
                        format!(
                            "{model}, {}: rho {:.2} (p {:.3}, {} bounces)",
                            d.covariate, d.spearman_rho, d.p_value, d.n
                        )
                    })
                })
                .collect();
            if !ranked.is_empty() {
                let _ = writeln!(s, "Each observed bounce of a calibration run ranked among the model's {} simulated bounces of the same run nearest in normal impact speed (or incidence), by normal restitution: where the model is right the rank does not change with the speed (or incidence); a rank falling with speed is a restitution falling with speed that the model lacks (`bounce_restitution` in the diagnostics). {}.\n", BOUNCE_NEIGHBOURS, ranked.join("; "));
            }
        }
        let _ = writeln!(s, "| model, runs | rebound_mae_m | rebound_crps_m |");
        let _ = writeln!(s, "|---|---|---|");
        for (name, st) in [("baseline", &r.baseline), ("final", &r.final_stage)] {
            for (set, m) in [("held-out", &st.holdout), ("calibration", &st.calibration)] {
                if let (Some(mae), Some(c)) = (m.rebound_mae_m, m.rebound_crps_m) {
                    let _ = writeln!(s, "| {name}, {set} | {} | {} |", fmt(mae), fmt(c));
                }
            }
        }
    }
    let band = if r.back_analysis.is_empty() && r.spread_profiles.is_empty() {
        ""
    } else {
        "; which values the calibration runs cannot tell from the best: the last column of the back-analysis tables below"
    };
    let _ = writeln!(
        s,
        "\n## Parameters\n\nOne fit on one set of random numbers; how far these values move with the runs fitted \
         and the random numbers: `talus calibrate --kfold 5 --kfold-repeats 3` (each fold's values, and their spread, \
         in `cv_repeats.md`){band}.\n"
    );
    let _ = writeln!(s, "| parameter | baseline | final |");
    let _ = writeln!(s, "|---|---|---|");
    let mut names: Vec<&String> = r.baseline.parameters.0.keys().chain(r.final_stage.parameters.0.keys()).collect();
    names.sort();
    names.dedup();
    for n in names {
        let g = |p: &Params| p.get(n).map(|v| format!("{v:.4}")).unwrap_or_else(|| "–".into());
        let _ = writeln!(s, "| {n} | {} | {} |", g(&r.baseline.parameters), g(&r.final_stage.parameters));
    }
    for m in &r.measured_from_tracks {
        let key = format!("{}.{}", m.material, m.parameter);
        let how = if m.fixed {
            "fixed there (`fix_rt_from_tracks`)".to_string()
        } else {
            let fitted = |p: &Params| p.get(&key).map_or("–".to_string(), fmt);
            format!(
                "not fixed: fitted {} (baseline) and {} (final); `fix_rt_from_tracks = true` fixes it where the settings leave it unset",
                fitted(&r.baseline.parameters),
                fitted(&r.final_stage.parameters)
            )
        };
        let _ = writeln!(s, "\n`{key}` measured by the calibration runs' tracks: {}, the median tangential restitution of {} bounces on it (quartiles {}–{}; mean ± sd {} ± {}); {how} (docs/calibration.md, \"Rt from the tracks\").", fmt(m.value), m.bounces, fmt(m.quartiles[0]), fmt(m.quartiles[1]), fmt(m.mean), fmt(m.sd));
    }
    match scenario {
        Some(f) if f == super::scenario_file::PROFILE_SCENARIO => {
            let _ = writeln!(s, "\nThe final model as a profile scenario: `{f}`. `talus profile {f} --out MAP` re-runs the field releases with it on the calibrated profile; replace its `profile` and `[campaign]` to run another slope.");
        }
        Some(f) => {
            let _ = writeln!(s, "\nThe final model as a scenario: `{f}`. `talus run {f} --out MAP` re-runs the field releases with it; replace its `[[sources]]` to map another slope.");
        }
        None => {}
    }
    let searches: Vec<super::fit::SearchRecord> =
        serde_json::from_value(r.population_fit["searches"].clone()).unwrap_or_default();
    if !searches.is_empty() {
        let _ = writeln!(s, "\nThe population fit ran {} searches (the seed of their random numbers and their start below); the one with the lowest objective on fresh numbers is the baseline.\n", searches.len());
        let _ = writeln!(
            s,
            "| search seed | start | start screened, m | objective on its numbers, m | on fresh numbers, m | evaluations | parameters |"
        );
        let _ = writeln!(s, "|---|---|---|---|---|---|---|");
        let list = |m: &std::collections::BTreeMap<String, f64>| {
            m.iter().map(|(k, v)| format!("{k} {v:.3}")).collect::<Vec<_>>().join(", ")
        };
        for x in &searches {
            let _ = writeln!(
                s,
                "| {} | {} | {} | {:.2} | {:.2} | {} | {} |",
                x.seed,
                list(&x.start),
                x.start_screened_m.map_or("–".into(), |v| format!("{v:.2}")),
                x.objective_m,
                x.selection_objective_m,
                x.evaluations,
                list(&x.parameters)
            );
        }
    }
    if !r.back_analysis.is_empty() || !r.spread_profiles.is_empty() {
        let _ = writeln!(s, "\n## Per-run back-analysis (mean ± sd over calibration runs)\n");
    }
    if !r.back_analysis.is_empty() {
        let _ = writeln!(s, "Each run's own value of one parameter, the others held at the population fit; censored: runs the parameter cannot bring to their observation within its bounds. As good as the best: the values of the grid (across the bounds) at which the calibration runs' mean score is within d standard errors of the lowest (paired over the runs; simulated on random numbers the fits did not use, so no value looks better by the luck a fit found; d = Φ⁻¹(1 − 0.05/(k − 1)) on a grid of k values, 2.39 for 7: comparisons with the best, so the band holds the best grid value with 95 % confidence; a value out between two that are in is named, \"but not\"): where every grid value is in, the runs leave the parameter open whatever the fit reports. The population fit, scored on the same numbers, is given against the lowest (within Φ⁻¹(1 − 0.05/k) standard errors, one comparison more): outside its band, by the rule that makes the band it would not be in it (the search stopped short of the valley, its own random numbers flattered it, or these are unlucky for it: more `[back_analysis] repeats` tell which; docs/calibration.md, \"How sharply the runs pin the parameters\", \"Bands on fresh numbers\" and \"Bands that hold the truth\").\n");
        let refit = r.profiles().map(|(_, _, p)| p.others_refit_evaluations).max().unwrap_or(0);
        let others = if refit > 0 {
            format!("At each value of a band the other free parameters were fitted again ({refit} evaluations), so the band follows their trade-offs.")
        } else {
            "Each band holds the other parameters at the population fit: where two trade off (Cr against friction, say), the runs leave more open jointly than the two bands say (`[back_analysis] refit_evaluations` fits them again at each value).".to_string()
        };
        let _ = writeln!(s, "{others}\n");
        let _ = writeln!(s, "| material | parameter | population fit | mean ± sd (n) | censored | per block | as good as the best (grid) |");
        let _ = writeln!(s, "|---|---|---|---|---|---|---|");
        for row in &r.back_analysis {
            let blocks: Vec<String> =
                row.by_block.iter().map(|(b, sp)| format!("{b}: {:.3} ± {:.3} ({})", sp.mean, sp.sd, sp.n)).collect();
            let good = row.profile.as_ref().map_or("–".to_string(), |p| p.describe());
            let _ = writeln!(
                s,
                "| {} | {} | {:.3} | {:.3} ± {:.3} ({}) | {} | {} | {good} |",
                row.material,
                row.parameter,
                row.population,
                row.all.mean,
                row.all.sd,
                row.all.n,
                row.censored,
                blocks.join("; ")
            );
        }
    }
    if !r.spread_profiles.is_empty() {
        let _ = writeln!(s, "\nSpreads between rocks have no per-run value, but the same grid tells how far the runs pin them (their scores are CRPS, which a spread too wide or too narrow raises):\n");
        let _ = writeln!(s, "| material | parameter | population fit | as good as the best (grid) |");
        let _ = writeln!(s, "|---|---|---|---|");
        for sp in &r.spread_profiles {
            let good = sp.profile.as_ref().map_or("–".to_string(), |p| p.describe());
            let _ = writeln!(s, "| {} | {} | {:.3} | {good} |", sp.material, sp.parameter, sp.population);
        }
    }
    let _ = writeln!(s, "\n## Effects loop\n");
    if r.effects_added.is_empty() {
        let _ = writeln!(s, "No effect was kept: none improved the cross-validated score clearly.\n");
    }
    for e in &r.effects_added {
        let _ =
            writeln!(s, "- **{}** kept: {}", e.label, e.evidence.get("formula").and_then(|v| v.as_str()).unwrap_or(""));
        let params: Vec<String> = e.parameters.iter().map(|(k, v)| format!("{k} = {v:.4}")).collect();
        let _ = writeln!(s, "  parameters: {}", params.join(", "));
        let rivals: Vec<String> = e.evidence["rivals"]
            .as_array()
            .into_iter()
            .flatten()
            .map(|r| {
                format!(
                    "{} ({:+.1} %, {} added parameters{})",
                    r["label"].as_str().unwrap_or(""),
                    -100.0 * r["relative_improvement"].as_f64().unwrap_or(f64::NAN),
                    r["added_parameters"],
                    if r["within_one_se_of_best"].as_bool() == Some(true) { ", within one SE of the best" } else { "" }
                )
            })
            .collect();
        if !rivals.is_empty() {
            let _ = writeln!(
                s,
                "  also passed, not kept ({}): {}",
                e.evidence["selection"].as_str().unwrap_or(""),
                rivals.join("; ")
            );
        }
    }
    if !r.effects_tried.is_empty() {
        let _ = writeln!(
            s,
            "\nOut-of-fold scores inside the calibration runs (CRPS decides; run-out MAE shown beside it).\n"
        );
        let _ = writeln!(s, "| round | effect | proposed by | CV CRPS before (m) | after (m) | cut | p (needed) | folds better (fold p) | CV MAE before → after (m) | kept |");
        let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|");
        for t in &r.effects_tried {
            let by: Vec<String> = t
                .proposed_by
                .iter()
                .map(|d| format!("{} ({} {:.2}, p {:.3})", d.covariate, d.statistic_label(), d.spearman_rho, d.p_value))
                .collect();
            let _ = writeln!(
                s,
                "| {} | {} | {} | {:.2} | {:.2} | {:+.1} % | {:.3} (≤ {:.4}) | {} of {} ({:.3}) | {:.2} → {:.2} | {} |",
                t.round,
                t.label,
                by.join("; "),
                t.cv_crps_before_m,
                t.cv_crps_after_m,
                -100.0 * t.relative_improvement,
                t.p_value,
                t.p_threshold,
                t.folds_better(),
                t.fold_cuts_m.len(),
                t.fold_p_value,
                t.cv_runout_mae_before_m,
                t.cv_runout_mae_after_m,
                if t.kept { "yes" } else { "no" }
            );
        }
    }
    let _ = writeln!(s, "\n## Residual diagnosis (baseline, calibration runs)\n");
    if let Some(z) = &r.zone_check {
        let _ = writeln!(
            s,
            "Zone check: largest deposition excess {:.2} (p {:.3}); {:.1} % of simulations run farther than every \
             observed run of their release group (p {:.3}); check p = {:.3}.\n",
            z.deposition_excess,
            z.deposition_p_value,
            100.0 * z.overrun_share,
            z.overrun_p_value,
            z.p_value
        );
    }
    if !charted.is_empty() {
        let _ = writeln!(s, "Each run-out row links to its chart of residual against the covariate.\n");
    }
    let _ = writeln!(s, "| covariate | residual | Spearman rho | p |");
    let _ = writeln!(s, "|---|---|---|---|");
    for d in &r.diagnostics {
        let name = match d.residual == "runout" && charted.contains(&d.covariate) {
            true => format!("[{}]({})", d.covariate, residual_chart(&d.covariate)),
            false => d.covariate.clone(),
        };
        let _ = writeln!(s, "| {name} | {} | {:.3} | {:.3} |", d.residual, d.spearman_rho, d.p_value);
    }
    let _ = writeln!(s, "\n## Figures\n");
    for (f, caption) in figures {
        let _ = writeln!(s, "![{caption}]({f})\n\n*{caption}*\n");
    }
    let _ = writeln!(s, "## Time\n");
    let t = &r.timing;
    let _ = writeln!(
        s,
        "Population fit {:.0} s, back-analysis {:.0} s, effects loop {:.0} s, final evaluation and report {:.0} s; total {:.0} s, {} simulations, {} threads.",
        t.population_fit_s, t.back_analysis_s, t.effects_loop_s, t.final_evaluation_s, t.total_s, t.simulations, t.threads
    );
    s
}

/// How far [`field_box_m`] reaches past the field's points, m (ours: a few rock lengths and a DEM cell or two, so
/// that a rock the model sends a little past the longest field run still meets ground it can stop on).
pub const FIELD_BOX_MARGIN_M: f64 = 10.0;

/// The polygon around every run's release point and the rest points of calibration runs `cal`, widened by
/// [`FIELD_BOX_MARGIN_M`] (a box in the horizontal axes of `up`'s files, corners counter-clockwise from the lowest):
/// where the field says the ground is, for `[terrain] level_beyond`. The rest points are outcomes, so only calibration
/// runs' go in: held-out runs choose no setting. The release points are where each run starts, known before its rock
/// falls, and a held-out run must start on the ground as surveyed.
pub fn field_box_m(runs: &[FieldRun], cal: &[usize], up: UpAxis) -> Vec<[f64; 2]> {
    let points = runs.iter().map(|r| r.release_m).chain(cal.iter().map(|&i| runs[i].rest_m));
    let [x0, y0, x1, y1] = crate::terrain::bbox_xy(points.map(|p| up.horizontal_of_internal(p[0], p[1])));
    let m = FIELD_BOX_MARGIN_M;
    let [x0, y0, x1, y1] = [x0 - m, y0 - m, x1 + m, y1 + m];
    vec![[x0, y0], [x1, y0], [x1, y1], [x0, y1]]
}

/// A polygon as a settings file writes it, to 0.1 m.
fn polygon_toml(p: &[[f64; 2]]) -> String {
    let corners: Vec<String> = p.iter().map(|[x, y]| format!("[{x:.1}, {y:.1}]")).collect();
    format!("[{}]", corners.join(", "))
}

/// What a calibration with `[terrain] level_beyond = "field"` says of the ground it levelled past `polygon`.
pub fn levelled_note(polygon: &[[f64; 2]]) -> String {
    format!(
        "the ground is levelled past {} (`[terrain] level_beyond = \"field\"`: the runs' release points and the \
         calibration runs' rest points, widened by {FIELD_BOX_MARGIN_M:.0} m)",
        polygon_toml(polygon)
    )
}

/// The spread check's p-value ([`super::diagnose::spread_check`]) on the final model's calibration runs at or below
/// which the report warns that its ranges are too narrow (ours: the 1 % at which the loop's signals are read).
pub const NARROW_WARNING_P: f64 = 0.01;

/// The warning for a final model whose simulated run-outs are too narrow for its calibration runs: more of them lie
/// outside every one of their `repeats` simulations than the 2/(repeats + 1) a right model leaves out, at
/// `spread` ([`super::diagnose::spread_check`]) p ≤ [`NARROW_WARNING_P`]. Rest points recorded with a survey error
/// scatter past a model that predicts where rocks stopped (docs/calibration.md, "The survey's error on the rest
/// points"), so where `rest_noise_m` is not declared that is the first remedy named; the other is scatter the
/// model lacks. None otherwise.
pub fn narrow_warning(
    spread: &Diagnostic,
    repeats: usize,
    rest_noise_declared: bool,
    kind: ModelKind,
) -> Option<String> {
    (spread.p_value <= NARROW_WARNING_P).then(|| {
        let spreads = match kind {
            ModelKind::Rigid3d => "free or widen `cr_sd` and `dynamic_friction_sd_deg`, or declare `roughness`",
            ModelKind::Lumped2d => "free `rn_sd` and `rt_sd`",
        };
        let remedy = if rest_noise_declared {
            format!(
                "The declared `rest_noise_m` does not account for it: the model lacks scatter between rocks; \
                 {spreads}."
            )
        } else {
            format!(
                "If the rest points carry a survey error (a handheld GPS or pacing: a metre is common), declare its sd \
                 in the settings file (`rest_noise_m = SD`, m) so that simulated rest points are read as the field's \
                 were; otherwise the model lacks scatter between rocks: {spreads}."
            )
        };
        format!(
            "the final model's run-out ranges are too narrow for its calibration runs: {:.0} % of them lie outside \
             every one of their {repeats} simulations, where a right model leaves about {:.0} % out (spread check p = \
             {:.3}), so `coverage_90` reads low. {remedy}",
            100.0 * spread.spearman_rho,
            200.0 / (repeats as f64 + 1.0),
            spread.p_value,
        )
    })
}

/// Share of a model's simulations of the calibration runs not at rest above which the report warns (ours).
pub const UNRESTED_WARNING_SHARE: f64 = 0.1;

/// The warning for a calibration whose simulations of the calibration runs often do not come to rest, from the
/// baseline's and the final model's metrics of them (`not_stopped_fraction`, `left_terrain_fraction`); none when
/// both shares are at most [`UNRESTED_WARNING_SHARE`]. Such a run-out is taken where the rock left the terrain or
/// stood at the time limit, short of where it would stop, so the fit and its errors say less about where rocks stop.
/// The remedy it names follows how they ended: a larger terrain for those that left it, a longer time for the rest.
/// `field_box_m` ([`field_box_m`], given where `[terrain] level_beyond` could help) is written out as the
/// `level_beyond` polygon that levels the ground past it, beside `"field"`, which levels past each calibration's own.
pub fn unrested_warning(baseline: &Metrics, final_model: &Metrics, field_box_m: Option<&[[f64; 2]]>) -> Option<String> {
    let (b, f) = (baseline.not_stopped_fraction, final_model.not_stopped_fraction);
    let (b_left, f_left) = (baseline.left_terrain_fraction, final_model.left_terrain_fraction);
    (b.max(f) > UNRESTED_WARNING_SHARE).then(|| {
        let (b_limit, f_limit) = (b - b_left, f - f_left);
        let mut how = Vec::new();
        let mut remedies = Vec::new();
        if b_left.max(f_left) > 0.0 {
            how.push(format!("{:.0} % and {:.0} % left the terrain", 100.0 * b_left, 100.0 * f_left));
            remedies.push(match field_box_m {
                None => "extend the terrain beyond the field's rest points".to_string(),
                Some(p) => format!(
                    "extend the terrain beyond the field's rest points (where the ground past the field's data is a \
                     DEM's extrapolated margin, not surveyed, `[terrain] level_beyond = {}` in the settings file \
                     continues it level past the runs' release points and the calibration runs' rest points, widened \
                     by {FIELD_BOX_MARGIN_M:.0} m; `level_beyond = \"field\"` levels past that box as each \
                     calibration, each fold of `--kfold`, draws it from its own runs; where the survey's extent is \
                     known, level past it instead, on every side: docs/calibration.md, \"Where to level the \
                     Tschamut proxy\")",
                    polygon_toml(p)
                ),
            });
        }
        if b_limit.max(f_limit) > 0.0 {
            how.push(format!("{:.0} % and {:.0} % ran to the time limit", 100.0 * b_limit, 100.0 * f_limit));
            remedies.push("raise `[simulation] max_time_s`".to_string());
        }
        format!(
            "{:.0} % of the baseline's and {:.0} % of the final model's simulations of the calibration runs did not \
             come to rest ({}): their run-out is where they were then, short of where they would stop, so the fit and \
             its errors say less about where rocks stop. To let simulated rocks stop, {}",
            100.0 * b,
            100.0 * f,
            how.join("; "),
            remedies.join(", or ")
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibrate::metrics::metrics;
    use crate::calibrate::metrics::tests::{run, sims};

    #[test]
    fn ranges_too_narrow_for_the_calibration_runs_are_warned_of_with_the_survey_error_first() {
        let spread = |share: f64, p_value: f64| Diagnostic {
            covariate: super::super::diagnose::OUTSIDE_RANGE.into(),
            residual: "runout".into(),
            spearman_rho: share,
            p_value,
            n: 40,
        };
        // At chance, or short of the 1 % level: quiet.
        assert_eq!(narrow_warning(&spread(0.1, 0.5), 20, false, ModelKind::Rigid3d), None);
        assert_eq!(narrow_warning(&spread(0.2, 0.011), 20, false, ModelKind::Rigid3d), None);
        // Too narrow, no survey error declared: the share, what a right model leaves out, then the remedies.
        let w = narrow_warning(&spread(0.25, 0.002), 20, false, ModelKind::Rigid3d).unwrap();
        assert!(w.contains("25 % of them lie outside every one of their 20 simulations"), "{w}");
        assert!(w.contains("about 10 % out") && w.contains("p = 0.002"), "{w}");
        let (noise, scatter) = (w.find("`rest_noise_m = SD`").unwrap(), w.find("`cr_sd`").unwrap());
        assert!(noise < scatter && w.contains("`roughness`"), "{w}");
        // Declared: the scatter the model lacks only.
        let w = narrow_warning(&spread(0.25, 0.002), 20, true, ModelKind::Lumped2d).unwrap();
        assert!(w.contains("does not account for it") && w.contains("`rn_sd`") && !w.contains("SD`"), "{w}");
    }

    #[test]
    fn a_calibration_whose_rocks_often_do_not_stop_is_warned_of() {
        let m = |not_stopped_fraction, left_terrain_fraction| Metrics {
            not_stopped_fraction,
            left_terrain_fraction,
            ..metrics(&[run(0, 0, 10.0)], &[sims(0, &[10.0])])
        };
        assert_eq!(unrested_warning(&m(0.015, 0.015), &m(0.1, 0.0), None), None);
        let w = unrested_warning(&m(1.0, 1.0), &m(0.14, 0.14), None).unwrap();
        assert!(w.starts_with("100 % of the baseline's and 14 % of the final model's"), "{w}");
        assert!(w.contains("(100 % and 14 % left the terrain") && w.ends_with("the field's rest points"), "{w}");
        let w = unrested_warning(&m(0.05, 0.0), &m(0.2, 0.0), None).unwrap();
        assert!(w.ends_with("raise `[simulation] max_time_s`"), "{w}");
        assert!(w.contains("(5 % and 20 % ran to the time limit)"), "{w}");
        let w = unrested_warning(&m(0.3, 0.1), &m(0.3, 0.1), None).unwrap();
        assert!(w.contains("left the terrain; 20 % and 20 % ran to") && w.contains("rest points, or raise"), "{w}");
        // Where levelling could help, the polygon to paste, and only where rocks left the terrain.
        let field = [[-3.0, 120.5], [136.44, 120.5], [136.44, 270.0], [-3.0, 270.0]];
        let field = Some(&field[..]);
        let w = unrested_warning(&m(0.14, 0.14), &m(0.14, 0.14), field).unwrap();
        let polygon = "`[terrain] level_beyond = [[-3.0, 120.5], [136.4, 120.5], [136.4, 270.0], [-3.0, 270.0]]`";
        assert!(w.contains(polygon) && w.contains("widened by 10 m; `level_beyond = \"field\"`"), "{w}");
        assert!(w.contains("each fold of `--kfold`, draws it from its own runs; where the survey's extent"), "{w}");
        let w = unrested_warning(&m(0.2, 0.0), &m(0.2, 0.0), field).unwrap();
        assert!(!w.contains("level_beyond"), "{w}");
    }

    #[test]
    fn the_field_box_holds_the_release_points_the_calibration_runs_rest_points_and_a_margin() {
        let at = |release: [f64; 2], rest: [f64; 2]| FieldRun {
            release_m: [release[0], release[1], 50.0],
            rest_m: [rest[0], rest[1], 0.0],
            ..run(0, 0, 10.0)
        };
        let runs =
            [at([30.0, 250.0], [90.0, 140.0]), at([10.0, 230.0], [120.0, 160.0]), at([20.0, 245.0], [500.0, 500.0])];
        // The third run is held out: its rest point sets nothing; its release point lies inside.
        let box_m = [[0.0, 130.0], [130.0, 130.0], [130.0, 260.0], [0.0, 260.0]];
        assert_eq!(field_box_m(&runs, &[0, 1], UpAxis::Z), box_m);
        // A held-out release point outside stays on the ground as surveyed.
        let runs = [runs[0].clone(), runs[1].clone(), at([140.0, 280.0], [500.0, 500.0])];
        let box_m = [[0.0, 130.0], [150.0, 130.0], [150.0, 290.0], [0.0, 290.0]];
        assert_eq!(field_box_m(&runs, &[0, 1], UpAxis::Z), box_m);
        // For a y-up terrain the runs are in talus's axes (x, −z, y) and the polygon in the files' x and z.
        let y_up = [[0.0, -290.0], [150.0, -290.0], [150.0, -130.0], [0.0, -130.0]];
        assert_eq!(field_box_m(&runs, &[0, 1], UpAxis::Y), y_up);
    }

    #[test]
    fn a_missed_aim_that_a_right_model_would_miss_too_is_marked_apart() {
        let m0 = metrics(&[run(0, 0, 10.0)], &[sims(0, &[9.0, 10.0, 11.0, 12.0])]);
        let row = |m: &Metrics| {
            let mut s = String::new();
            metrics_rows(&mut s, "x", m);
            s
        };
        // W1 of 8 m: missed; a right model's 3 m would meet the aim, its 6 m would not.
        let wrong = Metrics { runout_w1_m: 8.0, runout_w1_if_right_m: 3.0, ..m0 };
        assert!(row(&wrong).contains("| 8.00 ✗ | 3.00 |"), "{}", row(&wrong));
        let small_sample = Metrics { runout_w1_if_right_m: 6.0, ..wrong };
        assert!(row(&small_sample).contains("| 8.00 ✗† | 6.00 |"), "{}", row(&small_sample));
        // A bias of 4 m where the right model's RMS is 5 m; a coverage of 0.7 where the right model's is 0.75.
        let b = Metrics {
            runout_bias_m: 4.0,
            runout_bias_if_right_m: 5.0,
            coverage_90: 0.7,
            coverage_90_if_right: 0.75,
            ..m0
        };
        assert!(row(&b).contains("| +4.00 ✗† | 5.00 |") && row(&b).contains("| 0.70 ✗† | 0.75 |"), "{}", row(&b));
        assert_eq!(aims_if_right(&m0), [true, true, false]);
    }
}
