//! The envelope of 2DLM profile models: several profile scenarios (the fold models of a 2DLM `talus calibrate
//! --kfold`, `fold_*/calibrated_profile.toml`) run with one seed, and their envelopes along the profile
//! (`envelopes.csv`: bounce height, speed and energy at each station) and collectors combined station by station
//! into the lowest, median and highest value over the models; with the share each bench catches. Ours, as the
//! map envelope of the parent module.

use super::Spread3;
use crate::error::{Error, Result};
use crate::lumped2d::{run_profile, ProfileScenario};
use serde::Serialize;
use std::io::Write;
use std::path::Path;
use std::time::Instant;

/// One profile model of an envelope, as it ran.
#[derive(Debug, Clone, Serialize)]
pub struct ProfileModel {
    /// Name (its run is in `models/NAME/`).
    pub name: String,
    /// Scenario file.
    pub scenario: String,
    /// Seed of its run.
    pub seed: u64,
    /// Rocks run.
    pub rocks: usize,
    /// Median run-out along x, m.
    pub runout_p50_m: Option<f64>,
    /// 95th percentile of the run-out, m.
    pub runout_p95_m: Option<f64>,
    /// Share of the rocks each bench catches (index 0: past the last bench), on a benched profile.
    pub bench_fractions: Option<Vec<f64>>,
    /// The largest 95th percentile of the bounce height at any station, m.
    pub highest_bounce_p95_m: Option<f64>,
    /// The largest 95th percentile of the kinetic energy at any station, kJ.
    pub highest_kinetic_p95_kj: Option<f64>,
}

/// What `talus envelope` writes as `envelope.json` for profile models.
#[derive(Debug, Clone, Serialize)]
pub struct ProfileEnvelope {
    /// talus version.
    pub talus_version: String,
    /// The models, in the order given.
    pub models: Vec<ProfileModel>,
    /// Each bench's share over the models (index 0: past the last bench); empty on a profile without benches.
    pub bench_fractions: Vec<Spread3>,
    /// With `--floor`: the first model's runs with other seeds, summarised alike.
    pub floor: Option<Box<ProfileEnvelope>>,
    /// Wall-clock time, s.
    pub wall_time_s: f64,
}

/// A CSV table as text: its header and rows.
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    /// Column names.
    pub header: Vec<String>,
    /// Rows of fields.
    pub rows: Vec<Vec<String>>,
}

impl Table {
    /// Reads `path` (a CSV written by `talus profile`).
    pub fn read(path: &Path) -> Result<Table> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        let mut lines = text.lines().map(|l| l.split(',').map(str::to_string).collect::<Vec<_>>());
        let header = lines.next().unwrap_or_default();
        Ok(Table { header, rows: lines.collect() })
    }

    /// The largest number in column `name`, if any.
    pub fn column_max(&self, name: &str) -> Option<f64> {
        let c = self.header.iter().position(|h| h == name)?;
        self.rows.iter().filter_map(|r| r.get(c)?.parse::<f64>().ok()).filter(|v| v.is_finite()).reduce(f64::max)
    }
}

/// Combines `tables` (one per model, named by `names`) row by row: the first `keys` columns must agree and are
/// kept; every other column becomes its lowest, median and highest value over the models with a number there
/// (`_min`, `_median`, `_max`; empty where none has one).
pub fn combine_tables(tables: &[Table], names: &[String], keys: usize) -> Result<Table> {
    let first = &tables[0];
    for (t, name) in tables.iter().zip(names).skip(1) {
        let same_keys = t.rows.len() == first.rows.len()
            && t.rows.iter().zip(&first.rows).all(|(a, b)| a.get(..keys) == b.get(..keys));
        if t.header != first.header || !same_keys {
            return Err(Error::invalid(
                format!("{name}: envelopes"),
                format!("its stations or columns differ from {}'s", names[0]),
                "an envelope combines models of one profile: give every scenario the same profile, \
                 envelope_spacing_m and collectors_x_m",
            ));
        }
    }
    let mut header: Vec<String> = first.header[..keys].to_vec();
    for col in &first.header[keys..] {
        header.extend(super::STATISTICS.iter().map(|s| format!("{col}_{s}")));
    }
    let rows = (0..first.rows.len())
        .map(|r| {
            let mut row: Vec<String> = first.rows[r][..keys].to_vec();
            for c in keys..first.header.len() {
                let s = Spread3::of(tables.iter().map(|t| t.rows[r].get(c).and_then(|v| v.parse::<f64>().ok())));
                row.extend([s.min, s.median, s.max].map(|v| v.map_or(String::new(), |v| format!("{v}"))));
            }
            row
        })
        .collect();
    Ok(Table { header, rows })
}

/// Runs every profile scenario into `out_dir/models/NAME/` with `seed`, then writes `envelopes.csv` and
/// `collectors.csv` over the models, `envelope.json` and `envelope.md` into `out_dir`; with `floor`, the first
/// scenario again once per model with the seeds that follow, in `out_dir/floor/`.
pub fn run_profile_envelope(
    scenarios: &[(ProfileScenario, String)],
    seed: u64,
    out_dir: &Path,
    floor: bool,
) -> Result<ProfileEnvelope> {
    let t0 = Instant::now();
    if scenarios.len() < 2 {
        return Err(Error::invalid(
            "scenarios",
            format!("an envelope needs at least two models, got {}", scenarios.len()),
            "give two or more profile scenarios, e.g. every fold_*/calibrated_profile.toml of `talus calibrate --kfold`",
        ));
    }
    check_profiles_before(scenarios)?;
    let members: Vec<(&ProfileScenario, String, u64)> = scenarios.iter().map(|(s, n)| (s, n.clone(), seed)).collect();
    let mut summary = profile_envelope_of(&members, out_dir)?;
    if floor {
        let members: Vec<(&ProfileScenario, String, u64)> = (super::floor_seeds(seed, scenarios.len()).into_iter())
            .map(|(name, seed)| (&scenarios[0].0, name, seed))
            .collect();
        let f = profile_envelope_of(&members, &out_dir.join("floor"))?;
        write_charts(&out_dir.join("floor"), false)?;
        write_profile_summary(&out_dir.join("floor"), &f)?;
        summary.floor = Some(Box::new(f));
    }
    summary.wall_time_s = t0.elapsed().as_secs_f64();
    write_charts(out_dir, floor)?;
    write_profile_summary(out_dir, &summary)?;
    Ok(summary)
}

/// Checks, before anything runs or is written, that the scenarios share what makes their envelopes' stations and
/// columns: the profile's geometry (its materials may differ, as fold models' zones do), `envelope_spacing_m` and
/// `collectors_x_m`.
///
/// # Errors
/// A scenario does not resolve (named by its file), or differs from the first in one of these.
fn check_profiles_before(scenarios: &[(ProfileScenario, String)]) -> Result<()> {
    let key = |sc: &ProfileScenario| -> Result<Vec<u64>> {
        // Named by its file: the scenario's own checks name only the field.
        let resolved = sc.resolve().map_err(|e| match &sc.source {
            Some(file) => e.in_file(file),
            None => e,
        })?;
        let p = resolved.slope.profile();
        let vertices = (0..=p.n_segments()).flat_map(|i| p.vertex(i));
        let spacing = std::iter::once(sc.envelope_spacing_m);
        Ok(vertices.chain(spacing).chain(sc.collectors_x_m.iter().copied()).map(f64::to_bits).collect())
    };
    let (first, first_name) = &scenarios[0];
    let first_key = key(first)?;
    for (sc, name) in &scenarios[1..] {
        if key(sc)? != first_key {
            return Err(Error::invalid(
                format!("{name}: profile"),
                format!("its profile, envelope_spacing_m or collectors_x_m differ from {first_name}'s"),
                "an envelope combines models of one profile: give every scenario the same profile, \
                 envelope_spacing_m and collectors_x_m",
            ));
        }
    }
    Ok(())
}

/// The charts of `envelope.md`: bounce height and kinetic energy P95 along the profile, lowest, median and highest
/// over the models, with the lowest and highest over the floor's seeds when there is a floor.
const CHARTS: [(&str, &str, &str, f64); 2] = [
    ("bounce_p95_m", "Bounce height, 95th percentile", "bounce height (m)", 1.0),
    ("kinetic_p95_j", "Kinetic energy, 95th percentile", "kinetic energy (kJ)", 1e-3),
];

fn write_charts(dir: &Path, floor: bool) -> Result<()> {
    use crate::render::colormap::CATEGORICAL;
    use crate::render::{write_svg, Chart, Series, SeriesStyle};
    let models = Table::read(&dir.join("envelopes.csv"))?;
    let seeds = if floor { Some(Table::read(&dir.join("floor").join("envelopes.csv"))?) } else { None };
    for (column, title, y_label, scale) in CHARTS {
        let series = |t: &Table, stat: &str| -> Vec<(f64, f64)> {
            let Some(c) = t.header.iter().position(|h| *h == format!("{column}_{stat}")) else { return Vec::new() };
            t.rows
                .iter()
                .filter_map(|r| Some((r[0].parse::<f64>().ok()?, r.get(c)?.parse::<f64>().ok()? * scale)))
                .collect()
        };
        let mut chart = Chart {
            title: format!("{title} along the profile"),
            x_label: "x (m)".into(),
            y_label: y_label.into(),
            ..Default::default()
        };
        for (stat, colour) in [("max", CATEGORICAL[1]), ("median", CATEGORICAL[0]), ("min", CATEGORICAL[2])] {
            chart.series.push(Series::new(format!("models, {stat}"), series(&models, stat), SeriesStyle::Line, colour));
        }
        if let Some(t) = &seeds {
            for (stat, colour) in [("max", CATEGORICAL[3]), ("min", CATEGORICAL[4])] {
                let s = Series::new(format!("seeds alone, {stat}"), series(t, stat), SeriesStyle::Markers, colour);
                chart.series.push(s);
            }
        }
        write_svg(&dir.join(format!("{column}.svg")), &chart)?;
    }
    Ok(())
}

fn profile_envelope_of(members: &[(&ProfileScenario, String, u64)], out_dir: &Path) -> Result<ProfileEnvelope> {
    let t0 = Instant::now();
    let mut models = Vec::new();
    for (scenario, name, seed) in members {
        let mut sc = (*scenario).clone();
        sc.seed = *seed;
        let s = run_profile(&sc, &out_dir.join("models").join(name))?;
        models.push(ProfileModel {
            name: name.clone(),
            scenario: sc.source.clone().unwrap_or_default(),
            seed: *seed,
            rocks: s.rocks,
            runout_p50_m: s.runout_m.p50,
            runout_p95_m: s.runout_m.p95,
            bench_fractions: s.bench_capture.map(|c| c.fraction_per_bench),
            highest_bounce_p95_m: None,
            highest_kinetic_p95_kj: None,
        });
    }
    let names: Vec<String> = members.iter().map(|m| m.1.clone()).collect();
    // Keys: the station (x and the ground there), and for collectors their number too. Both tables are combined
    // before either is written, so that models whose collectors differ leave no envelope behind.
    let mut combined_tables = Vec::new();
    for (file, keys) in [("envelopes.csv", 2), ("collectors.csv", 3)] {
        let tables = names
            .iter()
            .map(|n| Table::read(&out_dir.join("models").join(n).join(file)))
            .collect::<Result<Vec<_>>>()?;
        if file == "envelopes.csv" {
            for (m, t) in models.iter_mut().zip(&tables) {
                m.highest_bounce_p95_m = t.column_max("bounce_p95_m");
                m.highest_kinetic_p95_kj = t.column_max("kinetic_p95_j").map(|j| j / 1000.0);
            }
        }
        combined_tables.push((file, combine_tables(&tables, &names, keys)?));
    }
    for (file, combined) in combined_tables {
        let path = out_dir.join(file);
        crate::io::write_atomic(&path, |w| {
            for line in std::iter::once(&combined.header).chain(&combined.rows) {
                writeln!(w, "{}", line.join(",")).map_err(|e| Error::io(&path, e))?;
            }
            Ok(())
        })?;
    }
    let benches = models[0].bench_fractions.as_ref().map_or(0, Vec::len);
    let bench_fractions = (0..benches)
        .map(|k| Spread3::of(models.iter().map(|m| m.bench_fractions.as_ref().and_then(|f| f.get(k).copied()))))
        .collect();
    Ok(ProfileEnvelope {
        talus_version: env!("CARGO_PKG_VERSION").to_string(),
        models,
        bench_fractions,
        floor: None,
        wall_time_s: t0.elapsed().as_secs_f64(),
    })
}

fn write_profile_summary(dir: &Path, s: &ProfileEnvelope) -> Result<()> {
    crate::io::write_json_atomic(&dir.join("envelope.json"), s)?;
    let f = super::fmt_opt;
    let mut md = format!(
        "# Envelope over {} profile runs\n\n`envelopes.csv` and `collectors.csv` give each column of the runs' own \
         files (`models/NAME/`) as its lowest, median and highest value over the runs, station by station.\n\n\
         | run | scenario | seed | rocks | run-out P50 (m) | run-out P95 (m) | highest bounce P95 (m) | highest \
         energy P95 (kJ) | first bench catches |\n|---|---|---:|---:|---:|---:|---:|---:|---:|\n",
        s.models.len()
    );
    for m in &s.models {
        let first = m.bench_fractions.as_ref().and_then(|b| b.get(1).copied());
        md += &format!(
            "| {} | `{}` | {} | {} | {} | {} | {} | {} | {} |\n",
            m.name,
            m.scenario,
            m.seed,
            m.rocks,
            f(m.runout_p50_m, 1),
            f(m.runout_p95_m, 1),
            f(m.highest_bounce_p95_m, 2),
            f(m.highest_kinetic_p95_kj, 1),
            f(first, 3)
        );
    }
    if let Some(fl) = &s.floor {
        // The seeds alone, as ranges over the floor's runs, so that the models' rows can be read against them.
        let range =
            |get: &dyn Fn(&ProfileModel) -> Option<f64>, digits: usize| match Spread3::of(fl.models.iter().map(get)) {
                Spread3 { min: Some(lo), max: Some(hi), .. } => format!("{lo:.digits$}–{hi:.digits$}"),
                _ => "–".to_string(),
            };
        let first = |m: &ProfileModel| m.bench_fractions.as_ref().and_then(|b| b.get(1).copied());
        md += &format!(
            "| seeds alone ({} runs of {}; [floor/envelope.md](floor/envelope.md)) | | | | {} | {} | {} | {} | {} |\n",
            fl.models.len(),
            s.models.first().map_or("", |m| m.name.as_str()),
            range(&|m| m.runout_p50_m, 1),
            range(&|m| m.runout_p95_m, 1),
            range(&|m| m.highest_bounce_p95_m, 2),
            range(&|m| m.highest_kinetic_p95_kj, 1),
            range(&first, 3)
        );
    }
    md += "\n";
    for (column, title, _, _) in CHARTS {
        md += &format!("![{title}]({column}.svg)\n");
    }
    if !s.bench_fractions.is_empty() {
        md += "\n| bench | share caught, min / median / max over the runs |";
        let floor = s.floor.as_ref().filter(|f| f.bench_fractions.len() == s.bench_fractions.len());
        md += if floor.is_some() { " seeds alone, min – max |\n|---|---|---|\n" } else { "\n|---|---|\n" };
        for (k, b) in s.bench_fractions.iter().enumerate() {
            let label = if k == 0 { "past the last".to_string() } else { k.to_string() };
            md += &format!("| {label} | {} / {} / {} |", f(b.min, 3), f(b.median, 3), f(b.max, 3));
            if let Some(fl) = floor {
                md += &format!(" {} – {} |", f(fl.bench_fractions[k].min, 3), f(fl.bench_fractions[k].max, 3));
            }
            md += "\n";
        }
    }
    crate::io::write_bytes_atomic(&dir.join("envelope.md"), md.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(rows: &[&str]) -> Table {
        Table {
            header: ["x_m", "h_m"].map(String::from).to_vec(),
            rows: rows.iter().map(|r| r.split(',').map(str::to_string).collect()).collect(),
        }
    }

    #[test]
    fn tables_combine_row_by_row_and_refuse_other_stations() {
        let names: Vec<String> = ["a", "b", "c"].map(String::from).to_vec();
        let t = [table(&["0,1", "1,"]), table(&["0,3", "1,"]), table(&["0,2", "1,5"])];
        let c = combine_tables(&t, &names, 1).unwrap();
        assert_eq!(c.header, ["x_m", "h_m_min", "h_m_median", "h_m_max"]);
        assert_eq!(c.rows, [["0", "1", "2", "3"], ["1", "5", "5", "5"]]);
        let other = [table(&["0,1", "1,2"]), table(&["0,1", "2,2"])];
        let err = combine_tables(&other, &names[..2], 1).unwrap_err().to_string();
        assert!(err.contains("b: envelopes") && err.contains("envelope_spacing_m"), "{err}");
        assert_eq!(t[2].column_max("h_m"), Some(5.0));
        assert_eq!(t[0].column_max("h_m"), Some(1.0));
        assert_eq!(t[0].column_max("nope"), None);
    }
}
