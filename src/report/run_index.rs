//! A run's `index.html`: the summary (stop reasons, run-out and energy statistics, barriers, collectors,
//! parameters) and every map, with links to the data files.

use super::html::{escape, figure, num, table, Page};
use super::{RunProducts, ZONE_RASTERS};
use crate::error::Result;
use crate::run::{RunSummary, Stats, RASTERS};

/// The order maps are shown in: (file stem, caption title).
const MAP_ORDER: [(&str, &str); 8] = [
    ("reach_probability", "Reach probability"),
    ("hazard_zones", "Hazard zones"),
    ("kinetic_energy_p95_kj", "Kinetic energy, P95"),
    ("kinetic_energy_max_kj", "Kinetic energy, maximum"),
    ("bounce_height_p95_m", "Passing height, P95"),
    ("bounce_height_max_m", "Passing height, maximum"),
    ("endpoint_density", "End-point density"),
    ("terrain", "Terrain"),
];

fn stats_row(name: &str, s: &Stats) -> Vec<String> {
    vec![escape(name), num(s.min), num(s.p50), num(s.p90), num(s.p95), num(s.max), num(s.mean)]
}

/// The summary tables of a run (stop reasons, statistics, barriers, collectors) as HTML.
pub fn summary_html(summary: &RunSummary) -> String {
    let mut s = String::from("<div class=\"row\"><div>");
    let n = summary.rocks.max(1) as f64;
    let reasons: Vec<Vec<String>> = summary
        .stop_reasons
        .iter()
        .map(|(k, v)| vec![escape(&k.replace('_', " ")), v.to_string(), format!("{:.1} %", 100.0 * *v as f64 / n)])
        .collect();
    s.push_str("<h3>Stop reasons</h3>");
    s.push_str(&table(&["reason", "rocks", "share"], &reasons, &[0], &[]));
    s.push_str("</div><div><h3>Per rock</h3>");
    let rows = vec![
        stats_row("run-out (m)", &summary.runout_m),
        stats_row("travel time (s)", &summary.travel_time_s),
        stats_row("largest kinetic energy (kJ)", &summary.max_kinetic_kj),
        stats_row("largest passing height (m)", &summary.max_bounce_m),
    ];
    s.push_str(&table(&["quantity", "min", "P50", "P90", "P95", "max", "mean"], &rows, &[0], &[]));
    s.push_str("</div></div>");
    if !summary.barriers.is_empty() {
        let rows: Vec<Vec<String>> = summary
            .barriers
            .iter()
            .map(|b| {
                vec![
                    escape(&b.name),
                    num(b.height_m),
                    num(b.capacity_kj),
                    b.caught.to_string(),
                    b.broke_through.to_string(),
                ]
            })
            .collect();
        s.push_str("<h3>Barriers</h3>");
        s.push_str(&table(
            &["barrier", "height (m)", "capacity (kJ)", "rocks caught", "rocks through"],
            &rows,
            &[0],
            &[],
        ));
    }
    if !summary.collectors.is_empty() {
        let rows: Vec<Vec<String>> = summary
            .collectors
            .iter()
            .map(|c| {
                let o = |v: Option<f64>| num(v.unwrap_or(f64::NAN));
                vec![
                    escape(&c.name),
                    num(c.length_m),
                    c.rocks_crossing.to_string(),
                    format!("{:.1} %", 100.0 * c.fraction_crossing),
                    o(c.kinetic_kj_p95),
                    o(c.kinetic_kj_max),
                    o(c.passing_height_m_p95),
                    o(c.passing_height_m_max),
                ]
            })
            .collect();
        s.push_str("<h3>Collector lines</h3>");
        s.push_str(&table(
            &[
                "line",
                "length (m)",
                "rocks crossing",
                "share",
                "energy P95 (kJ)",
                "energy max (kJ)",
                "height P95 (m)",
                "height max (m)",
            ],
            &rows,
            &[0],
            &[],
        ));
        s.push_str("<p class=\"note\">Per stretch: <a href=\"collectors.csv\">collectors.csv</a>, <a href=\"collectors.geojson\">collectors.geojson</a>.</p>");
    }
    s
}

/// Writes `index.html` of a run into its folder.
pub fn write_run_index(p: &RunProducts, summary: &RunSummary) -> Result<()> {
    let title = if summary.title.is_empty() { "talus run".to_string() } else { summary.title.clone() };
    let sub = format!(
        "talus {} · scenario {} · seed {} · {} rocks · {:.1} s",
        summary.talus_version, summary.scenario, summary.seed, summary.rocks, summary.wall_time_s
    );
    let mut page = Page::new(&title, &sub);
    page.h2("Summary");
    for w in &summary.warnings {
        page.note(&format!("Warning: {w}"));
    }
    page.raw(&summary_html(summary));
    page.h2("Maps");
    let descriptions: Vec<(&str, &str)> = RASTERS.iter().chain(ZONE_RASTERS.iter()).copied().collect();
    let ascii = p.scenario.file.output.ascii_grids;
    let mut figs = String::from("<div class=\"grid\">");
    for (stem, name) in MAP_ORDER.iter() {
        let text = match *stem {
            "terrain" => "hillshade with contours, barriers and collector lines.".to_string(),
            "hazard_zones" => {
                let z = &p.scenario.file.hazard_zones;
                format!(
                    "intensity (energy ≤ {} / ≤ {} / > {} kJ) × reach probability (≤ {} % / ≤ {} % / above), Swiss diagram.",
                    super::maps::fmt_num(z.energy_kj[0]),
                    super::maps::fmt_num(z.energy_kj[1]),
                    super::maps::fmt_num(z.energy_kj[1]),
                    super::maps::fmt_num(100.0 * z.reach[0]),
                    super::maps::fmt_num(100.0 * z.reach[1])
                )
            }
            s => descriptions.iter().find(|d| d.0 == s).map(|d| format!("{}.", d.1)).unwrap_or_default(),
        };
        let mut links: Vec<(&str, String)> = Vec::new();
        if *stem != "terrain" {
            links.push(("GeoTIFF", format!("{stem}.tif")));
            if ascii {
                links.push(("ASCII grid", format!("{stem}.asc")));
            }
        }
        if *stem == "hazard_zones" {
            links.push(("matrix GeoTIFF", "hazard_matrix.tif".to_string()));
        }
        figs.push_str(&figure(&format!("{stem}.png"), name, &text, &links));
    }
    figs.push_str("</div>");
    page.raw(&figs);
    page.h2("Files");
    let files: Vec<String> =
        summary.outputs.iter().map(|f| format!("<li><a href=\"{0}\">{0}</a></li>", escape(f))).collect();
    page.raw(&format!("<ul class=\"files\">{}</ul>", files.join("")));
    page.h2("Parameters");
    let params = serde_json::to_string_pretty(&summary.parameters).unwrap_or_default();
    page.raw(&format!(
        "<details><summary>The scenario as used (defaults filled in; also in <a href=\"summary.json\">summary.json</a>)</summary><pre>{}</pre></details>",
        escape(&params)
    ));
    crate::io::write_bytes_atomic(&p.dir.join("index.html"), page.finish().as_bytes())
}
