//! `collectors.csv` and `collectors.geojson`: one row (feature) per line, then one per stretch.
//!
//! Columns: `collector`, `stretch` (`all` for the whole line, else its index from 0), `from_m` and `to_m` along the
//! line, the stretch's end points `x_from`, `y_from`, `x_to`, `y_to` (map coordinates), `rocks_crossing`,
//! `fraction_crossing` (of all rocks released), then for each quantity its P50, P90, P95, P99 and maximum:
//! `translational_kj_*`, `kinetic_kj_*`, `passing_height_m_*`, `speed_mps_*`, `crossing_angle_deg_*`,
//! `rock_size_m_*` (empty where no rock crossed).

use super::stats::{CollectorStats, Quantity, QuantityDists, PERCENTILES};
use super::Collector;
use crate::error::{Error, Result};
use crate::io::csv_text::{field, number};
use crate::io::geojson::{self, Feature, Geometry};
use crate::raster::Crs;
use crate::terrain::frame::{ground_xyz, map_xy};
use crate::terrain::Terrain;
use std::io::Write;
use std::path::Path;

/// Column names of the statistics, in order.
pub fn stat_columns() -> Vec<String> {
    let mut out = Vec::new();
    for q in Quantity::ALL {
        for p in PERCENTILES {
            out.push(format!("{}_p{}", q.column(), (p * 100.0).round()));
        }
        out.push(format!("{}_max", q.column()));
    }
    out
}

/// The statistics of `d` in [`stat_columns`] order (`NaN` where empty).
pub fn stat_values(d: Option<&QuantityDists>) -> Vec<f64> {
    let mut out = Vec::new();
    for q in Quantity::ALL {
        for p in PERCENTILES {
            out.push(d.map_or(f64::NAN, |d| d.quantile(q, p)));
        }
        out.push(d.map_or(f64::NAN, |d| d.max(q)));
    }
    out
}

struct Row<'a> {
    collector: &'a str,
    stretch: Option<usize>,
    span: (f64, f64),
    from: [f64; 2],
    to: [f64; 2],
    geometry: Vec<[f64; 2]>,
    crossing: u64,
    dists: Option<&'a QuantityDists>,
}

fn rows<'a>(collectors: &'a [Collector], stats: &'a CollectorStats) -> Vec<Row<'a>> {
    let mut out = Vec::new();
    for (c, l) in collectors.iter().zip(&stats.lines) {
        let len = c.length_m();
        out.push(Row {
            collector: &c.name,
            stretch: None,
            span: (0.0, len),
            from: c.point_at(0.0),
            to: c.point_at(len),
            geometry: c.line_m.clone(),
            crossing: l.crossing,
            dists: (l.crossing > 0).then_some(&l.dists),
        });
        for (k, s) in l.stretches.iter().enumerate() {
            let (a, b) = c.stretch_span_m(k);
            out.push(Row {
                collector: &c.name,
                stretch: Some(k),
                span: (a, b),
                from: c.point_at(a),
                to: c.point_at(b),
                geometry: c.sub_line(a, b),
                crossing: s.crossing as u64,
                dists: s.dists(),
            });
        }
    }
    out
}

/// Writes `collectors.csv` and `collectors.geojson` into `dir`; `n_rocks` is the number released.
pub fn write_collectors(
    dir: &Path,
    collectors: &[Collector],
    stats: &CollectorStats,
    terrain: &Terrain,
    crs: &Crs,
) -> Result<()> {
    let n = stats.rocks.max(1) as f64;
    let rows = rows(collectors, stats);
    let csv_path = dir.join("collectors.csv");
    crate::io::write_atomic(&csv_path, |w| {
        let err = |e| Error::io(&csv_path, e);
        let head = [
            "collector",
            "stretch",
            "from_m",
            "to_m",
            "x_from",
            "y_from",
            "x_to",
            "y_to",
            "rocks_crossing",
            "fraction_crossing",
        ];
        writeln!(w, "{},{}", head.join(","), stat_columns().join(",")).map_err(err)?;
        for r in &rows {
            let (f, t) = (map_xy(terrain, r.from), map_xy(terrain, r.to));
            let stretch = r.stretch.map_or("all".to_string(), |k| k.to_string());
            let stats: Vec<String> = stat_values(r.dists).into_iter().map(|v| number(v, 4)).collect();
            writeln!(
                w,
                "{},{stretch},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{},{:.6},{}",
                field(r.collector),
                r.span.0,
                r.span.1,
                f[0],
                f[1],
                t[0],
                t[1],
                r.crossing,
                r.crossing as f64 / n,
                stats.join(",")
            )
            .map_err(err)?;
        }
        Ok(())
    })?;
    let cols = stat_columns();
    let features: Vec<Feature> = rows
        .iter()
        .map(|r| {
            let mut f =
                Feature::new(Geometry::LineString(r.geometry.iter().map(|p| ground_xyz(terrain, *p)).collect()))
                    .with("collector", r.collector)
                    .with("level", if r.stretch.is_some() { "stretch" } else { "line" })
                    .with("stretch", r.stretch.map_or(serde_json::Value::from("all"), serde_json::Value::from))
                    .with("from_m", r.span.0)
                    .with("to_m", r.span.1)
                    .with("rocks_crossing", r.crossing)
                    .with("fraction_crossing", r.crossing as f64 / n);
            for (k, v) in cols.iter().zip(stat_values(r.dists)) {
                f.set(k, v);
            }
            f
        })
        .collect();
    geojson::write(&dir.join("collectors.geojson"), "collectors", crs, &features)
}
