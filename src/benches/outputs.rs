//! The study's files: tables (CSV), the summary (JSON), a short report (Markdown) and the figures.
//!
//! - `capture.csv`: long form, exactly `model,face_angle_deg,bench_width_m,bench,runs,captured_fraction,ci_low,
//!   ci_high`; bench 1..=n_benches, then 0 (past the last bench); `runs` = rocks counted, pooled over repeats;
//!   Wilson 95 % interval.
//! - `spread.csv` (with 2 or more repeats): per model and configuration, the mean, sd, min and max of the
//!   first-bench capture over the repeats, and the sd that binomial sampling alone would give.
//! - `rocks.csv`: every rock: release, end point, stop reason and how it was counted.
//! - `records_capture.csv` (with records): the observed first-bench capture per width.
//! - `summary.json`, `report.md`, `figure7_*.svg`, `per_bench/figure6_*.svg`.

use super::figures::{short, write_first_bench, write_per_bench};
use super::records::{observed_capture, select, HistoricRecord, ObservedPoint};
use super::runner::{ModelTiming, RockClass, StudyResult};
use super::stats::{interpolate, wilson_interval, Spread, Z_95};
use super::StudyConfig;
use crate::error::{Error, Result};
use crate::io::{write_atomic, write_bytes_atomic};
use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::io::Write;
use std::path::Path;

/// The columns of `capture.csv`, in order.
pub const CAPTURE_COLUMNS: [&str; 8] =
    ["model", "face_angle_deg", "bench_width_m", "bench", "runs", "captured_fraction", "ci_low", "ci_high"];

/// First-bench capture of one model at one face angle, at the Modified Ritchie width.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HeadlinePoint {
    /// Face angle, degrees.
    pub face_angle_deg: f64,
    /// `2DLM`, `3DRB` or `records`.
    pub model: String,
    /// Captured fraction (`None` when the width is outside the simulated widths).
    pub captured_fraction: Option<f64>,
    /// Wilson 95 % interval, low end; between two simulated widths the lower of their two low ends (capture grows
    /// with the width, so the value lies between theirs; an interpolated interval can be far too narrow where
    /// capture jumps between the widths).
    pub ci_low: Option<f64>,
    /// Wilson 95 % interval, high end; between two simulated widths the higher of their two high ends.
    pub ci_high: Option<f64>,
    /// The simulated widths it was interpolated between, m (equal when simulated at that width).
    pub interpolated_between_m: Option<[f64; 2]>,
    /// Whether the fraction reaches the retention target.
    pub meets_target: Option<bool>,
}

/// The spread of one model's first-bench capture over repeats, summarised over configurations.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ModelSpread {
    /// `2DLM` or `3DRB`.
    pub model: String,
    /// Repeats per configuration.
    pub repeats: usize,
    /// Configurations.
    pub configurations: usize,
    /// Median over configurations of the sd of first-bench capture between repeats (fraction).
    pub median_sd: f64,
    /// Largest such sd.
    pub max_sd: f64,
    /// Largest max − min between repeats.
    pub max_range: f64,
    /// Median over configurations of the sd that binomial sampling alone gives, √(p(1 − p)/n).
    pub median_binomial_sd: f64,
}

/// Counts of one model.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ModelCounts {
    /// `2DLM` or `3DRB`.
    pub model: String,
    /// Rocks simulated.
    pub rocks: usize,
    /// Rocks counted in the capture fractions.
    pub counted: usize,
    /// Rocks that left the terrain by the back, or by a side before passing bench 1 (not counted).
    pub left: usize,
    /// Rocks that ended before the middle of the first face, on the crest floor or hung on its edge (not counted).
    pub crest: usize,
    /// Rocks by engine stop reason.
    pub stop_reasons: BTreeMap<String, usize>,
}

/// The records used.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RecordsSummary {
    /// Records in the file.
    pub records: usize,
    /// Records within the bench-height tolerance.
    pub used: usize,
    /// Of those, records caught by their own bench.
    pub caught_by_own_bench: usize,
}

/// What a study did; also written as `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct StudySummary {
    /// talus version.
    pub talus_version: String,
    /// The settings as used.
    pub config: StudyConfig,
    /// The Modified Ritchie width for the bench height, m.
    pub modified_ritchie_width_m: f64,
    /// Threads used.
    pub threads: usize,
    /// Wall time and speed per model.
    pub timings: Vec<ModelTiming>,
    /// Counts per model.
    pub models: Vec<ModelCounts>,
    /// First-bench capture at the Modified Ritchie width, per face angle and model (and records).
    pub first_bench_at_modified_ritchie: Vec<HeadlinePoint>,
    /// Spread between repeats per model (with 2 or more repeats).
    pub spread: Vec<ModelSpread>,
    /// The records used, if any.
    pub records: Option<RecordsSummary>,
    /// Files written in the output folder.
    pub outputs: Vec<String>,
}

fn f6(v: f64) -> String {
    format!("{v:.6}")
}

/// A fraction in per cent, without decimals unless that would round a fraction strictly between 0 and 1 to 0 or
/// 100.
fn pct_number(v: f64) -> String {
    let p = 100.0 * v;
    if (p.round() == 0.0 && v > 0.0) || (p.round() == 100.0 && v < 1.0) {
        format!("{p:.1}")
    } else {
        format!("{p:.0}")
    }
}

fn pct(v: f64) -> String {
    format!("{} %", pct_number(v))
}

fn io_err(path: &Path) -> impl Fn(std::io::Error) -> Error + '_ {
    move |e| Error::io(path, e)
}

/// Writes every output of `result` into `out_dir` (created if needed). `records` are the historic records read
/// from the configured file, if any.
///
/// # Errors
/// I/O errors.
pub fn write_outputs(result: &StudyResult, records: Option<&[HistoricRecord]>, out_dir: &Path) -> Result<StudySummary> {
    crate::io::create_folder(out_dir)?;
    let cfg = &result.config;
    let mut outputs = Vec::new();

    let path = out_dir.join("capture.csv");
    write_atomic(&path, |w| {
        let e = io_err(&path);
        writeln!(w, "{}", CAPTURE_COLUMNS.join(",")).map_err(&e)?;
        for model in result.models() {
            for (c, conf) in result.configurations.iter().enumerate() {
                let (per_bench, n) = result.pooled(model, c);
                for k in (1..=cfg.n_benches).chain(std::iter::once(0)) {
                    let (frac, lo, hi) = match wilson_interval(per_bench[k], n, Z_95) {
                        Some((lo, hi)) => (f6(per_bench[k] as f64 / n as f64), f6(lo), f6(hi)),
                        None => Default::default(),
                    };
                    let (a, wd) = (conf.face_angle_deg, conf.bench_width_m);
                    writeln!(w, "{},{a},{wd},{k},{n},{frac},{lo},{hi}", model.label()).map_err(&e)?;
                }
            }
        }
        Ok(())
    })?;
    outputs.push("capture.csv".to_string());

    let spread = if cfg.repeats >= 2 {
        outputs.push("spread.csv".to_string());
        write_spread(result, &out_dir.join("spread.csv"))?
    } else {
        Vec::new()
    };

    let path = out_dir.join("rocks.csv");
    write_atomic(&path, |w| {
        let e = io_err(&path);
        writeln!(
            w,
            "model,face_angle_deg,bench_width_m,repeat,seed,rock,shape,mass_kg,release_speed_mps,end_x_m,end_y_m,\
             stop_reason,bench"
        )
        .map_err(&e)?;
        for row in &result.rocks {
            let conf = result.configurations[row.config];
            let bench = match row.class {
                RockClass::Bench(k) => k.to_string(),
                RockClass::Left => "left".into(),
                RockClass::Crest => "crest".into(),
            };
            writeln!(
                w,
                "{},{},{},{},{},{},{},{},{},{},{},{},{bench}",
                row.model.label(),
                conf.face_angle_deg,
                conf.bench_width_m,
                row.repeat,
                cfg.seed.wrapping_add(row.repeat as u64),
                row.rock,
                result.shape_name(row),
                row.mass_kg,
                f6(row.speed_mps),
                f6(row.end_x_m),
                row.end_y_m.map(f6).unwrap_or_default(),
                row.stop_reason,
            )
            .map_err(&e)?;
        }
        Ok(())
    })?;
    outputs.push("rocks.csv".to_string());

    // Records: all angles within the height tolerance, and per angle.
    let rs = &cfg.records;
    let used: Vec<HistoricRecord> =
        records.map(|r| select(r, cfg.bench_height_m, rs.bench_height_tolerance_m, None)).unwrap_or_default();
    let mr = cfg.modified_ritchie_width_m();
    let mut widths: Vec<f64> = result.configurations.iter().map(|c| c.bench_width_m).collect();
    widths.sort_by(f64::total_cmp);
    widths.dedup();
    let observed = |angle: Option<f64>| -> Vec<ObservedPoint> {
        let sel = match angle {
            Some(a) => {
                select(&used, cfg.bench_height_m, rs.bench_height_tolerance_m, Some((a, rs.face_angle_tolerance_deg)))
            }
            None => used.clone(),
        };
        observed_capture(&sel, &widths)
    };
    let mut angles: Vec<f64> = result.configurations.iter().map(|c| c.face_angle_deg).collect();
    angles.dedup();
    let records_summary = records.map(|r| RecordsSummary {
        records: r.len(),
        used: used.len(),
        caught_by_own_bench: used.iter().filter(|r| r.caught_by_own_bench()).count(),
    });
    if records.is_some() {
        let path = out_dir.join("records_capture.csv");
        write_atomic(&path, |w| {
            let e = io_err(&path);
            writeln!(w, "face_angle_deg,bench_width_m,records,captured,captured_fraction,ci_low,ci_high")
                .map_err(&e)?;
            let mut at_widths = widths.clone();
            if !at_widths.contains(&mr) {
                at_widths.push(mr);
                at_widths.sort_by(f64::total_cmp);
            }
            for angle in angles.iter().map(|&a| Some(a)).chain(std::iter::once(None)) {
                let sel = match angle {
                    Some(a) => select(
                        &used,
                        cfg.bench_height_m,
                        rs.bench_height_tolerance_m,
                        Some((a, rs.face_angle_tolerance_deg)),
                    ),
                    None => used.clone(),
                };
                let label = angle.map_or("all".to_string(), |a| a.to_string());
                for p in observed_capture(&sel, &at_widths) {
                    writeln!(
                        w,
                        "{label},{},{},{},{},{},{}",
                        p.bench_width_m,
                        p.records,
                        p.captured,
                        f6(p.captured_fraction),
                        f6(p.ci_low),
                        f6(p.ci_high)
                    )
                    .map_err(&e)?;
                }
            }
            Ok(())
        })?;
        outputs.push("records_capture.csv".to_string());
    }

    // Headline: first-bench capture at the Modified Ritchie width.
    let mut headline = Vec::new();
    for &angle in &angles {
        for model in result.models() {
            let mut pts = Vec::new();
            for (c, conf) in result.configurations.iter().enumerate().filter(|(_, c)| c.face_angle_deg == angle) {
                let (per_bench, n) = result.pooled(model, c);
                if let Some((lo, hi)) = wilson_interval(per_bench[1], n, Z_95) {
                    pts.push((conf.bench_width_m, per_bench[1] as f64 / n as f64, lo, hi));
                }
            }
            let v = interpolate(&pts.iter().map(|p| (p.0, p.1)).collect::<Vec<_>>(), mr);
            // Capture grows with the width (every width sees the same rocks), so between two simulated widths it
            // lies between theirs: the interval spans both widths' intervals.
            let at = |w: f64| pts.iter().find(|p| p.0 == w).map_or((f64::NAN, f64::NAN), |p| (p.2, p.3));
            let ci = v.map(|(_, [a, b])| (at(a).0.min(at(b).0), at(a).1.max(at(b).1)));
            headline.push(HeadlinePoint {
                face_angle_deg: angle,
                model: model.label().to_string(),
                captured_fraction: v.map(|v| v.0),
                ci_low: ci.map(|c| c.0),
                ci_high: ci.map(|c| c.1),
                interpolated_between_m: v.map(|v| v.1),
                meets_target: v.map(|v| v.0 >= cfg.retention_target),
            });
        }
        if records.is_some() {
            let sel = select(
                &used,
                cfg.bench_height_m,
                rs.bench_height_tolerance_m,
                Some((angle, rs.face_angle_tolerance_deg)),
            );
            let p = observed_capture(&sel, &[mr]).first().copied();
            headline.push(HeadlinePoint {
                face_angle_deg: angle,
                model: "records".into(),
                captured_fraction: p.map(|p| p.captured_fraction),
                ci_low: p.map(|p| p.ci_low),
                ci_high: p.map(|p| p.ci_high),
                interpolated_between_m: None,
                meets_target: p.map(|p| p.captured_fraction >= cfg.retention_target),
            });
        }
    }

    outputs.extend(write_first_bench(result, &observed, out_dir)?);
    outputs.extend(write_per_bench(result, out_dir)?);

    let models: Vec<ModelCounts> = result
        .models()
        .into_iter()
        .map(|m| {
            let mut counts = ModelCounts {
                model: m.label().into(),
                rocks: 0,
                counted: 0,
                left: 0,
                crest: 0,
                stop_reasons: BTreeMap::new(),
            };
            for c in result.cells.iter().filter(|c| c.model == m) {
                counts.counted += c.counted();
                counts.left += c.left;
                counts.crest += c.crest;
                counts.rocks += c.counted() + c.left + c.crest;
                for (k, v) in &c.stop_reasons {
                    *counts.stop_reasons.entry(k.to_string()).or_insert(0) += v;
                }
            }
            counts
        })
        .collect();

    outputs.push("report.md".to_string());
    outputs.push("summary.json".to_string());
    let summary = StudySummary {
        talus_version: env!("CARGO_PKG_VERSION").to_string(),
        config: cfg.clone(),
        modified_ritchie_width_m: mr,
        threads: result.threads,
        timings: result.timings.clone(),
        models,
        first_bench_at_modified_ritchie: headline,
        spread,
        records: records_summary,
        outputs,
    };
    write_bytes_atomic(&out_dir.join("report.md"), report(result, &summary).as_bytes())?;
    crate::io::write_json_atomic(&out_dir.join("summary.json"), &summary)?;
    Ok(summary)
}

/// Writes `spread.csv` and returns the per-model summary.
fn write_spread(result: &StudyResult, path: &Path) -> Result<Vec<ModelSpread>> {
    let mut per_model = Vec::new();
    write_atomic(path, |w| {
        let e = io_err(path);
        writeln!(w, "model,face_angle_deg,bench_width_m,repeats,runs_per_repeat,mean,sd,min,max,binomial_sd")
            .map_err(&e)?;
        for model in result.models() {
            let (mut sds, mut ranges, mut binom) = (Vec::new(), Vec::new(), Vec::new());
            for (c, conf) in result.configurations.iter().enumerate() {
                let cells: Vec<_> = result.cells_of(model, c).collect();
                let fr: Vec<f64> = cells.iter().filter_map(|c| c.fraction(1)).collect();
                let Some(s) = Spread::of(&fr) else { continue };
                let n = cells.iter().map(|c| c.counted()).sum::<usize>() as f64 / cells.len() as f64;
                let b = (s.mean * (1.0 - s.mean) / n.max(1.0)).sqrt();
                writeln!(
                    w,
                    "{},{},{},{},{n:.1},{},{},{},{},{}",
                    model.label(),
                    conf.face_angle_deg,
                    conf.bench_width_m,
                    fr.len(),
                    f6(s.mean),
                    f6(s.sd),
                    f6(s.min),
                    f6(s.max),
                    f6(b)
                )
                .map_err(&e)?;
                sds.push(s.sd);
                ranges.push(s.max - s.min);
                binom.push(b);
            }
            let median = |v: &mut Vec<f64>| {
                v.sort_by(f64::total_cmp);
                if v.is_empty() {
                    0.0
                } else if v.len() % 2 == 1 {
                    v[v.len() / 2]
                } else {
                    0.5 * (v[v.len() / 2 - 1] + v[v.len() / 2])
                }
            };
            per_model.push(ModelSpread {
                model: model.label().into(),
                repeats: result.config.repeats,
                configurations: sds.len(),
                median_sd: median(&mut sds.clone()),
                max_sd: sds.iter().copied().fold(0.0, f64::max),
                max_range: ranges.iter().copied().fold(0.0, f64::max),
                median_binomial_sd: median(&mut binom),
            });
        }
        Ok(())
    })?;
    Ok(per_model)
}

/// One sentence per model on its spread between seeds.
pub fn spread_statement(s: &ModelSpread) -> String {
    format!(
        "{}: over {} seeds, first-bench capture varied by a median standard deviation of {:.1} percentage points \
         across the {} configurations (largest {:.1}; largest max − min {:.1}); binomial sampling of the same number \
         of rocks alone gives {:.1}.",
        s.model,
        s.repeats,
        100.0 * s.median_sd,
        s.configurations,
        100.0 * s.max_sd,
        100.0 * s.max_range,
        100.0 * s.median_binomial_sd
    )
}

fn list(v: &[f64], unit: &str) -> String {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    v.iter().map(|x| format!("{}{unit}", short(*x))).collect::<Vec<_>>().join(", ")
}

/// The Markdown report.
fn report(result: &StudyResult, s: &StudySummary) -> String {
    let c = &result.config;
    let mr = s.modified_ritchie_width_m;
    let mut r = String::new();
    let _ = writeln!(r, "# Bench design study\n");
    let _ = writeln!(
        r,
        "talus {}. Bench height {} m, {} catch benches; face angles {}; bench widths {}. Seed {}, {} repeat(s), {} \
         thread(s).\n",
        s.talus_version,
        short(c.bench_height_m),
        c.n_benches,
        list(&c.face_angles_deg, "°"),
        list(&c.bench_widths_m, " m"),
        c.seed,
        c.repeats,
        s.threads
    );
    if c.lumped2d.runs > 0 {
        let _ = writeln!(
            r,
            "- **2DLM** (2D lumped mass): {} runs per configuration, repeat and mass ({} point masses per \
             configuration); face {}, floor {} (Table 1); masses {}.",
            c.lumped2d.runs,
            result.runs(super::Model::Lumped2d),
            describe_2d(&c.lumped2d.face),
            describe_2d(&c.lumped2d.floor),
            list(&c.masses_kg, " kg")
        );
    }
    if c.rigid3d.runs > 0 {
        let _ = writeln!(
            r,
            "- **3DRB** (3D rigid body): {} runs per configuration and repeat; shapes {}; masses {}; face {}, floor \
             {} (Table 2); smooth faces.",
            c.rigid3d.runs,
            c.rigid3d.shapes.join(", "),
            list(&c.masses_kg, " kg"),
            c.rigid3d.face.preset.as_deref().unwrap_or("custom"),
            c.rigid3d.floor.preset.as_deref().unwrap_or("custom")
        );
    }
    let _ = writeln!(
        r,
        "- Release (both models): centre of mass {} m behind the top crest, lowest point {} m above the crest floor, \
         horizontal speed {}–{} m/s towards the slope{}.\n",
        short(c.release.setback_m),
        short(c.release.clearance_m),
        short(c.release.speed_mps[0]),
        short(c.release.speed_mps[1]),
        if c.rigid3d.runs > 0 { ", random orientation (3DRB)" } else { "" }
    );

    let _ = writeln!(r, "## First-bench capture at the Modified Ritchie width\n");
    let between: Option<[f64; 2]> = s.first_bench_at_modified_ritchie.iter().find_map(|h| h.interpolated_between_m);
    let how = match between {
        Some([a, b]) if a == b => format!("simulated at exactly {} m", short(a)),
        Some([a, b]) => format!("interpolated linearly between the simulated widths {} m and {} m", short(a), short(b)),
        None => "outside the simulated widths, so not estimated".to_string(),
    };
    let _ = writeln!(
        r,
        "BW = 0.2 × {} + 4.5 = {} m; {how}. Wilson 95 % intervals in brackets (between two widths, from the lower \
         end of both to the higher end of both: capture grows with the width). Design target: \
         {} of rocks on the first bench.\n",
        short(c.bench_height_m),
        short(mr),
        pct(c.retention_target)
    );
    let mut cols: Vec<String> = result.models().iter().map(|m| m.label().to_string()).collect();
    if s.records.is_some() {
        cols.push("records".into());
    }
    let _ = writeln!(r, "| face angle | {} |", cols.join(" | "));
    let _ = writeln!(r, "|---|{}", "---|".repeat(cols.len()));
    let mut angles: Vec<f64> = result.configurations.iter().map(|c| c.face_angle_deg).collect();
    angles.dedup();
    for a in angles {
        let cells: Vec<String> = cols
            .iter()
            .map(|m| {
                let h = s.first_bench_at_modified_ritchie.iter().find(|h| h.face_angle_deg == a && &h.model == m);
                match h.and_then(|h| Some((h.captured_fraction?, h.ci_low?, h.ci_high?, h.meets_target?))) {
                    Some((v, lo, hi, ok)) => {
                        format!("{} ({}–{}){}", pct(v), pct_number(lo), pct_number(hi), if ok { " ✓" } else { "" })
                    }
                    None => "–".into(),
                }
            })
            .collect();
        let _ = writeln!(r, "| {}° | {} |", short(a), cells.join(" | "));
    }
    let _ = write!(r, "\n✓ = reaches the {} target.", pct(c.retention_target));
    if matches!(between, Some([a, b]) if a != b) {
        let mut w: Vec<f64> = c.bench_widths_m.iter().copied().chain([mr]).collect();
        w.sort_by(f64::total_cmp);
        w.dedup();
        let _ = write!(
            r,
            " Capture can change abruptly between two widths (2DLM rocks that slide stop at an almost fixed \
             distance from the toe), so an interpolated value is only a guide: to simulate the criterion width \
             itself, add it to the widths (e.g. `--bench-widths-m {}`).",
            w.iter().map(|v| short(*v)).collect::<Vec<_>>().join(",")
        );
    }
    let _ = writeln!(r, "\n");

    if !s.spread.is_empty() {
        let _ = writeln!(r, "## Spread between seeds\n");
        for m in &s.spread {
            let _ = writeln!(r, "- {}", spread_statement(m));
        }
        let _ = writeln!(r);
    }

    let _ = writeln!(r, "## Counts and time\n");
    for (m, t) in s.models.iter().zip(&s.timings) {
        let _ = writeln!(
            r,
            "- {}: {} rocks in {:.2} s ({:.0} rocks/s); {} counted, {} left the terrain by the back or by a side \
             before passing bench 1, {} stayed at the crest; stop reasons: {}.",
            m.model,
            m.rocks,
            t.wall_time_s,
            t.rocks_per_second,
            m.counted,
            m.left,
            m.crest,
            m.stop_reasons.iter().map(|(k, v)| format!("{k} {v}")).collect::<Vec<_>>().join(", ")
        );
    }
    if let Some(rec) = &s.records {
        let _ = writeln!(
            r,
            "- Historic records: {} in the file, {} within ±{} m of the bench height; {} of those were caught by \
             their own bench.",
            rec.records,
            rec.used,
            short(c.records.bench_height_tolerance_m),
            rec.caught_by_own_bench
        );
    }
    let _ = writeln!(r, "\n## Files\n");
    let describe = |f: &str| -> &str {
        match f {
            "capture.csv" => "captured fraction per model, face angle, bench width and bench (1 = first below the release, 0 = past the last bench), with Wilson 95 % intervals; repeats pooled",
            "spread.csv" => "first-bench capture over the repeats: mean, sd, min, max, and the sd of binomial sampling alone",
            "rocks.csv" => "every rock: release speed, shape, mass, end point, stop reason and the bench it was counted on (`left`/`crest` = not counted)",
            "records_capture.csv" => "observed first-bench capture of the historic records per width (fraction of records with run-out from the toe at most the width)",
            "figure7_first_bench.svg" => "first-bench capture against bench width, all face angles, both models (the paper's Figure 7)",
            "report.md" => "this report",
            "summary.json" => "settings as used, counts, wall times and rocks/s per model, the headline numbers",
            f if f.starts_with("figure7_first_bench_") => "first-bench capture against bench width for one face angle, with the Modified Ritchie width, the retention target and the records",
            f if f.starts_with("per_bench/") => "rocks captured per bench, 2DLM beside 3DRB (the paper's Figure 6)",
            _ => "",
        }
    };
    let mut per_bench = 0;
    for f in &s.outputs {
        if f.starts_with("per_bench/") {
            per_bench += 1;
            continue;
        }
        let _ = writeln!(r, "- `{f}`: {}", describe(f));
    }
    if per_bench > 0 {
        let _ = writeln!(
            r,
            "- `per_bench/figure6_<angle>deg_<width>m.svg` ({per_bench} files): {}",
            describe("per_bench/")
        );
    }
    let _ = writeln!(
        r,
        "\n## How rocks are counted\n\nBench k holds the rocks whose centre of mass ends between the middle of face k \
         and the middle of face k + 1 (resting against the toe of face k, on its catch bench, or hung on its outer \
         edge); bench 0 the rocks that end past the last catch bench. Rocks that end before the middle of face 1 \
         (on the crest floor or hung on its edge: they never went down) and rocks that leave the terrain by the \
         back or by a side before passing bench 1 are not counted (numbers above); a 3DRB rock that leaves by a \
         side over bench k > 1 counts on bench k, and one that leaves beyond the toe floor as bench 0. 3DRB run \
         i has shape i mod S and mass (i div S) mod M of the S shapes and M masses; 2DLM run i has mass i mod M. \
         Run i draws from the random stream (seed + repeat, i) in every configuration, so all configurations see \
         the same release draws.\n"
    );
    r
}

fn describe_2d(m: &crate::lumped2d::MaterialSpec) -> String {
    let base = m.preset.clone().unwrap_or_else(|| "custom".into());
    match m.roughness_sd_deg {
        Some(r) => format!("{base} with roughness {}°", short(r)),
        None => base,
    }
}
