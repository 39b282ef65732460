//! The study's files: `candidates.csv`/`.geojson` (every candidate), `proposals.csv`/`.md`/`.geojson` (the best
//! ones), `proposals.png`, the reach probability without and with the barrier on one colour scale and their
//! difference (`reach_probability_reduction.tif`/`.png`), `barrier_study.json` and `index.html`.

use super::candidates::CandidateKind;
use super::classes::thousands;
use super::design::{Assessment, Status};
use super::{run_folder, BarrierStudy};
use crate::error::{Error, Result};
use crate::io::csv_text::{field, number};
use crate::io::geojson::{self, Feature, Geometry};
use crate::render::colormap::CATEGORICAL;
use crate::render::{Colormap, OverlayLine, Overlays, ValueScale};
use crate::report::html::{escape, figure, num, table, Page};
use crate::report::maps::{self, fmt_num, Style, BARRIER_COLOUR};
use crate::run::RunOutput;
use crate::scenario::Scenario;
use crate::terrain::frame::{ground_xyz, map_xy};
use crate::terrain::Terrain;
use serde_json::{json, Value};
use std::io::Write;
use std::path::Path;

/// A short name of a candidate kind.
pub fn kind_name(k: &CandidateKind) -> &'static str {
    match k {
        CandidateKind::Contour { .. } => "contour",
        CandidateKind::BenchCrest { .. } => "bench crest",
        CandidateKind::BenchToe { .. } => "bench toe",
        CandidateKind::FloorOffset { .. } => "floor offset",
        CandidateKind::ToeOffset { .. } => "toe line offset",
        CandidateKind::AssetOffset { .. } => "asset line offset",
    }
}

const CSV_HEAD: &str = "rank,name,kind,candidate_length_m,rocks_reaching,status,from_m,to_m,length_m,intercepted,share,share_of_released,meets_target,rocks_crossing,passing_height_p95_m,passing_height_max_m,rock_size_p95_m,design_height_m,fence_height_m,energy_p95_kj,energy_p99_kj,energy_max_kj,speed_p95_mps,crossing_angle_p50_deg,class_kj,cost,x_from,y_from,x_to,y_to,height_from,energy_from,note";

fn csv_row(a: &Assessment, terrain: &Terrain) -> String {
    let ends = match (a.line_m.first(), a.line_m.last()) {
        (Some(p), Some(q)) => {
            let (p, q) = (map_xy(terrain, *p), map_xy(terrain, *q));
            format!("{:.3},{:.3},{:.3},{:.3}", p[0], p[1], q[0], q[1])
        }
        _ => ",,,".into(),
    };
    let status = match a.status {
        Status::Sized => "sized",
        Status::TooFewRocks => "too_few_rocks",
    };
    format!(
        "{},{},{},{:.2},{},{status},{:.2},{:.2},{:.2},{},{:.4},{:.4},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{ends},{},{},{}",
        a.rank.map_or(String::new(), |r| r.to_string()),
        field(&a.name),
        kind_name(&a.kind),
        a.candidate_length_m,
        a.rocks_reaching,
        a.from_m,
        a.to_m,
        a.length_m,
        a.intercepted,
        a.share,
        a.share_of_released,
        a.meets_target,
        a.rocks_crossing,
        number(a.passing_height_p95_m, 3),
        number(a.passing_height_max_m, 3),
        number(a.rock_size_p95_m, 3),
        number(a.design_height_m, 3),
        number(a.fence_height_m, 1),
        number(a.energy_p95_kj, 1),
        number(a.energy_p99_kj, 1),
        number(a.energy_max_kj, 1),
        number(a.speed_p95_mps, 2),
        number(a.crossing_angle_p50_deg, 1),
        a.class_kj.map_or(String::new(), |c| format!("{c}")),
        a.cost.map_or(String::new(), |c| format!("{c:.1}")),
        field(&a.height_from),
        field(&a.energy_from),
        field(&a.note)
    )
}

fn write_csv(path: &Path, rows: &[&Assessment], terrain: &Terrain) -> Result<()> {
    crate::io::write_atomic(path, |w| {
        let err = |e| Error::io(path, e);
        writeln!(w, "{CSV_HEAD}").map_err(err)?;
        for a in rows {
            writeln!(w, "{}", csv_row(a, terrain)).map_err(err)?;
        }
        Ok(())
    })
}

fn properties(a: &Assessment) -> serde_json::Map<String, Value> {
    let mut m = match serde_json::to_value(a) {
        Ok(Value::Object(m)) => m,
        _ => serde_json::Map::new(),
    };
    m.remove("kind");
    m.insert("kind".into(), json!(kind_name(&a.kind)));
    m
}

/// The best `n` sized, ranked assessments.
fn best(study: &BarrierStudy, n: usize) -> Vec<&Assessment> {
    study.ranked().into_iter().filter(|a| a.status == Status::Sized).take(n).collect()
}

fn rank_colour(rank: usize) -> [u8; 3] {
    match rank {
        1 => BARRIER_COLOUR,
        r => [CATEGORICAL[0], CATEGORICAL[3], CATEGORICAL[2], CATEGORICAL[4], CATEGORICAL[6]][(r - 2) % 5],
    }
}

fn overlay(terrain: &Terrain, line: &[[f64; 2]], colour: [u8; 3], width_px: f64, label: Option<String>) -> OverlayLine {
    OverlayLine {
        xy: line.iter().map(|p| map_xy(terrain, *p)).map(|p| (p[0], p[1])).collect(),
        colour,
        width_px,
        label,
    }
}

fn proposal_label(a: &Assessment) -> String {
    format!(
        "#{} {}: {} m, {} m, {}",
        a.rank.unwrap_or(0),
        a.name,
        fmt_num(a.length_m),
        fmt_num(a.fence_height_m),
        a.class_label
    )
}

fn zone_overlay(sc: &Scenario, terrain: &Terrain) -> Option<OverlayLine> {
    let zone = super::protected_zone(&sc.file.barrier_design, terrain)?;
    let (mut pts, label) = match zone {
        crate::collector::ProtectedZone::Line(l) => (l, "asset line"),
        crate::collector::ProtectedZone::Polygon(p) => (p, "asset polygon"),
    };
    if label == "asset polygon" {
        if let Some(first) = pts.first().copied() {
            pts.push(first);
        }
    }
    Some(overlay(terrain, &pts, [20, 20, 20], 3.0, Some(label.into())))
}

/// Writes the study's files into `dir`; returns their names.
pub fn write_study(dir: &Path, sc: &Scenario, terrain: &Terrain, study: &BarrierStudy) -> Result<Vec<String>> {
    let spec = &sc.file.barrier_design;
    let mut out = Vec::new();
    let first = &study.models[0];
    let crs = first.without.grids[0].crs.clone();
    let n_rocks = first.without.summary.rocks;

    // Every candidate, ranked ones first.
    let mut all: Vec<&Assessment> = study.assessments.iter().collect();
    all.sort_by_key(|a| (a.rank.is_none(), a.rank, a.candidate));
    write_csv(&dir.join("candidates.csv"), &all, terrain)?;
    out.push("candidates.csv".into());
    let features: Vec<Feature> = all
        .iter()
        .map(|a| {
            let line = &study.candidates[a.candidate].line_m;
            let mut feat = Feature::new(Geometry::LineString(line.iter().map(|p| ground_xyz(terrain, *p)).collect()));
            feat.properties = properties(a);
            feat
        })
        .collect();
    geojson::write(&dir.join("candidates.geojson"), "barrier candidates", &crs, &features)?;
    out.push("candidates.geojson".into());

    let best = best(study, spec.best);
    write_csv(&dir.join("proposals.csv"), &best, terrain)?;
    out.push("proposals.csv".into());
    let features: Vec<Feature> = best
        .iter()
        .map(|a| {
            let mut feat =
                Feature::new(Geometry::LineString(a.line_m.iter().map(|p| ground_xyz(terrain, *p)).collect()));
            feat.properties = properties(a);
            feat
        })
        .collect();
    geojson::write(&dir.join("proposals.geojson"), "proposed barriers", &crs, &features)?;
    out.push("proposals.geojson".into());

    // Maps.
    let reach_without = &first.without.grids[1];
    let dem = maps::dem_for(terrain, reach_without);
    let mut lines: Vec<OverlayLine> =
        study.candidates.iter().map(|c| overlay(terrain, &c.line_m, [95, 95, 95], 1.2, None)).collect();
    // Lines unlabelled on the map (labels of nearby lines would overlap), described in the legend by colour.
    for a in best.iter().rev() {
        let r = a.rank.unwrap_or(0);
        lines.push(overlay(terrain, &a.line_m, rank_colour(r), if r == 1 { 5.0 } else { 3.5 }, None));
    }
    for a in best.iter() {
        let r = a.rank.unwrap_or(0);
        lines.push(OverlayLine {
            xy: Vec::new(),
            colour: rank_colour(r),
            width_px: if r == 1 { 5.0 } else { 3.5 },
            label: Some(proposal_label(a)),
        });
    }
    lines.extend(zone_overlay(sc, terrain));
    let mut style = maps::raster_style("reach_probability");
    style.title =
        format!("Proposed barriers over the reach probability ({} candidates in grey)", study.candidates.len());
    maps::render(
        &dir.join("proposals.png"),
        reach_without,
        &style,
        Some(&dem),
        &Overlays { lines, ..Default::default() },
    )?;
    out.push("proposals.png".into());

    if let (Some(with), Some(barrier)) = (&first.with, &study.barrier) {
        let reach_with = &with.grids[1];
        let hi = reach_without.min_max().map_or(1.0, |m| m.1).max(reach_with.min_max().map_or(1.0, |m| m.1));
        let lo = 1.0 / n_rocks.max(1) as f32;
        let best_line = best.first().map(|a| a.line_m.clone()).unwrap_or_default();
        let barrier_line = overlay(
            terrain,
            &best_line,
            BARRIER_COLOUR,
            5.0,
            Some(format!("barrier ({} m, {} kJ)", fmt_num(barrier.height_m), thousands(barrier.capacity_kj))),
        );
        let mut lines = vec![barrier_line];
        lines.extend(zone_overlay(sc, terrain));
        let ov = Overlays { lines, ..Default::default() };
        for (name, g, title) in [
            ("reach_probability_without.png", reach_without, "Reach probability without the barrier"),
            ("reach_probability_with.png", reach_with, "Reach probability with the barrier"),
        ] {
            let mut st = maps::raster_style("reach_probability");
            st.title = title.into();
            st.range = Some((lo, hi.max(lo * 10.0)));
            maps::render(&dir.join(name), g, &st, Some(&dem), &ov)?;
            out.push(name.into());
        }
        let mut diff = reach_without.clone();
        for (d, w) in diff.values.iter_mut().zip(&reach_with.values) {
            *d = if d.is_nan() || w.is_nan() { f32::NAN } else { *d - *w };
        }
        crate::io::geotiff::write_grid(&dir.join("reach_probability_reduction.tif"), &diff)?;
        out.push("reach_probability_reduction.tif".into());
        let st = Style {
            title: "Reach probability removed by the barrier (without - with)".into(),
            unit: "fraction of rocks".into(),
            colormap: Colormap::Diverging,
            scale: ValueScale::Linear,
            classes: None,
            range: None,
        };
        maps::render(&dir.join("reach_probability_reduction.png"), &diff, &st, Some(&dem), &ov)?;
        out.push("reach_probability_reduction.png".into());
    }

    let md = markdown(sc, study, &best);
    crate::io::write_bytes_atomic(&dir.join("proposals.md"), md.as_bytes())?;
    out.push("proposals.md".into());
    let json = json!({
        "scenario": sc.path.display().to_string(),
        "title": sc.file.title,
        "rocks": n_rocks,
        "seed": first.without.summary.seed,
        "settings": spec,
        "protected_zone": protected_zone_text(sc),
        "candidates": study.candidates.len(),
        "proposals": best.iter().map(|a| {
            let mut p = properties(a);
            p.insert("per_model".into(), json!(a.per_model));
            p
        }).collect::<Vec<_>>(),
        "rerun_barrier": study.barrier,
        "residual": first.residual,
        "models": study.models.iter().map(|m| json!({
            "name": m.name,
            "title": m.without.summary.title,
            "residual": m.residual,
            "zone_areas_m2": {
                "levels": ["low", "medium", "high"],
                "without": zone_areas(sc, &m.without),
                "with": m.with.as_ref().map(|w| zone_areas(sc, w)),
            },
        })).collect::<Vec<_>>(),
    });
    crate::io::write_json_atomic(&dir.join("barrier_study.json"), &json)?;
    out.push("barrier_study.json".into());
    out.push("index.html".into());
    let html = index_html(sc, study, &best, &out);
    crate::io::write_bytes_atomic(&dir.join("index.html"), html.as_bytes())?;
    Ok(out)
}

/// The protected zone in words.
pub fn protected_zone_text(sc: &Scenario) -> String {
    let s = &sc.file.barrier_design;
    if !s.asset_line.is_empty() {
        "the asset line: a rock reaches it when it crosses the line".into()
    } else if !s.asset_polygon.is_empty() {
        "the asset polygon: a rock reaches it when its path enters the polygon".into()
    } else {
        "beyond each candidate: a rock reaches it when it crosses the candidate line".into()
    }
}

fn class_energy_text(sc: &Scenario) -> &'static str {
    match sc.file.barrier_design.class_energy {
        super::ClassEnergy::P95 => "P95",
        super::ClassEnergy::P99 => "P99",
        super::ClassEnergy::Max => "maximum",
    }
}

/// One proposal's table cells: rank, position, length, fence height (design height), energies, class, share, cost,
/// note.
/// The rocks released behind a proposal's counts: one model's run, or with `across_models = "pooled"` every
/// model's.
fn released_behind_counts(sc: &Scenario, study: &BarrierStudy) -> usize {
    let pooled = sc.file.barrier_design.across_models == super::AcrossModels::Pooled;
    study.models[0].without.summary.rocks * if pooled { study.models.len() } else { 1 }
}

fn proposal_cells(a: &Assessment, n_rocks: usize) -> Vec<String> {
    vec![
        a.rank.map_or(String::new(), |r| r.to_string()),
        a.name.clone(),
        fmt_num(a.length_m),
        format!("{} ({} + {})", fmt_num(a.fence_height_m), num(a.passing_height_p95_m), num(a.rock_size_p95_m)),
        format!("{} / {}", thousands(a.energy_p95_kj), thousands(a.energy_max_kj)),
        a.class_label.clone(),
        format!(
            "{:.1} % of {} ({:.1} % of all {n_rocks})",
            100.0 * a.share,
            a.rocks_reaching,
            100.0 * a.share_of_released
        ),
        a.cost.map_or("–".into(), |c| format!("{c:.0}")),
        a.note.clone(),
    ]
}

const PROPOSAL_HEAD: [&str; 9] = [
    "#",
    "position",
    "length (m)",
    "fence height (m) (P95 pass + rock)",
    "energy P95 / max (kJ)",
    "class",
    "rocks intercepted",
    "cost",
    "note",
];

/// "A barrier on bench 100 m crest, 50 m long, 3 m high, 500 kJ".
fn rerun_sentence(study: &BarrierStudy, b: &crate::scenario::BarrierSpec) -> String {
    let best = study.ranked().into_iter().next();
    let model = if study.models.len() > 1 {
        format!(" (model {}; every model in the table of the models)", study.models[0].name)
    } else {
        String::new()
    };
    format!(
        "A barrier on {}, {} m long, {} m high, {} kJ{model}",
        best.map_or("the best candidate", |a| a.name.as_str()),
        fmt_num(best.map_or(f64::NAN, |a| a.length_m)),
        fmt_num(b.height_m),
        thousands(b.capacity_kj)
    )
}

/// Each hazard zone's area (low, medium, high) of a run, m² (the scenario's `[hazard_zones]`).
fn zone_areas(sc: &Scenario, run: &RunOutput) -> [f64; 3] {
    crate::zones::areas_m2(&sc.file.hazard_zones.run_grids(&run.grids).0)
}

fn residual_rows(sc: &Scenario, study: &BarrierStudy) -> Vec<(String, String, String)> {
    let m = &study.models[0];
    let (Some(r), Some(with)) = (&m.residual, &m.with) else { return Vec::new() };
    let pct = |k: u64| format!("{k} ({:.1} %)", 100.0 * k as f64 / r.rocks.max(1) as f64);
    let (a, b) = (zone_areas(sc, &m.without), zone_areas(sc, with));
    let ha = |x: f64| format!("{:.2} ha", x / 1e4);
    let zones = crate::zones::LEVELS.iter().rev().map(|(l, name, _)| {
        let k = *l as usize - 1;
        (format!("hazard zone {name}"), ha(a[k]), ha(b[k]))
    });
    let mut rows: Vec<(String, String, String)> = vec![
        ("rocks reaching the protected zone".into(), pct(r.reaching_without), pct(r.reaching_with)),
        ("caught by the barrier".into(), "–".into(), pct(r.caught)),
        ("… of those reaching: broke through".into(), "–".into(), pct(r.through)),
        ("… passed over the top".into(), "–".into(), pct(r.over)),
        ("… passed round the ends".into(), "–".into(), pct(r.around)),
        ("… reached it elsewhere".into(), "–".into(), pct(r.elsewhere)),
    ];
    rows.extend(zones);
    rows
}

const MODEL_HEAD: [&str; 7] = [
    "model",
    "rocks intercepted",
    "height (m) (P95 pass + rock)",
    "energy P95 / max (kJ)",
    "with the barrier: reaching the zone",
    "caught",
    "over / through / around",
];

/// Per model: the best proposal's figures and, if re-run, what still reaches the zone with it in place.
fn model_rows(study: &BarrierStudy, a: &Assessment) -> Vec<Vec<String>> {
    a.per_model
        .iter()
        .zip(&study.models)
        .map(|(d, m)| {
            let governs = [(a.height_from == d.model, "height"), (a.energy_from == d.model, "class")]
                .iter()
                .filter(|(g, _)| *g)
                .map(|(_, w)| *w)
                .collect::<Vec<_>>();
            let name = if governs.is_empty() {
                d.model.clone()
            } else {
                format!("{} (sets the {})", d.model, governs.join(", "))
            };
            let (reach, caught, past) = match &m.residual {
                Some(r) => {
                    let pct = |k: u64| format!("{k} ({:.1} %)", 100.0 * k as f64 / r.rocks.max(1) as f64);
                    (
                        format!("{} -> {}", pct(r.reaching_without), pct(r.reaching_with)),
                        pct(r.caught),
                        format!("{} / {} / {}", r.over, r.through, r.around),
                    )
                }
                None => ("–".into(), "–".into(), "–".into()),
            };
            vec![
                name,
                if d.sizes {
                    format!("{:.1} % of {}", 100.0 * d.share, d.rocks_reaching)
                } else {
                    format!("{} reach (too few to size)", d.rocks_reaching)
                },
                format!("{} ({} + {})", num(d.design_height_m), num(d.passing_height_p95_m), num(d.rock_size_p95_m)),
                format!("{} / {}", thousands(d.energy_p95_kj), thousands(d.energy_max_kj)),
                reach,
                caught,
                past,
            ]
        })
        .collect()
}

/// What seeds alone ask for on the models' proposal #1, in a sentence (`None` without a floor or a proposal).
pub fn floor_sentence(study: &BarrierStudy) -> Option<String> {
    let floor = study.floor.as_ref()?;
    let best = study.ranked().into_iter().next()?;
    let design = |x: &Assessment| match x.status {
        Status::Sized => {
            format!("{} m long, {} m high, {}", fmt_num(x.length_m), fmt_num(x.fence_height_m), x.class_label)
        }
        Status::TooFewRocks => "nothing (too few rocks reach its zone)".to_string(),
    };
    let heights = |a: &Assessment| {
        let h: Vec<f64> = a.per_model.iter().filter(|d| d.sizes).map(|d| d.design_height_m).collect();
        let lo = h.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = h.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        if h.is_empty() {
            "–".to_string()
        } else {
            format!("{}–{} m", num(lo), num(hi))
        }
    };
    let same = &floor.assessments[best.candidate];
    Some(format!(
        "Seeds alone (model {} with {} seeds): on {} they ask {} (design heights {} over the seeds, {} over the models); \
         their own #1: {}",
        study.models[0].name,
        floor.models.len(),
        best.name,
        design(same),
        heights(same),
        heights(best),
        floor.ranked().first().map_or("none".to_string(), |x| format!("{}, {}", x.name, design(x)))
    ))
}

/// What the models are, in a sentence.
fn models_sentence(sc: &Scenario, study: &BarrierStudy) -> String {
    let rule = match sc.file.barrier_design.across_models {
        super::AcrossModels::Worst => {
            "the proposals intercept the target share in every model, with the height and class of the model that \
             asks most"
        }
        super::AcrossModels::Pooled => {
            "their rocks are pooled into one ensemble (`across_models = \"pooled\"`): the proposals intercept the \
             target share of all of them, with the P95s of all of them"
        }
    };
    format!(
        "{} models run the same rocks: {rule} (per model below; maps are the first model's, {}).",
        study.models.len(),
        study.models[0].name
    )
}

fn markdown(sc: &Scenario, study: &BarrierStudy, best: &[&Assessment]) -> String {
    let spec = &sc.file.barrier_design;
    let n = study.models[0].without.summary.rocks;
    let mut s =
        format!("# Proposed barriers: {}\n\n", if sc.file.title.is_empty() { "talus barrier" } else { &sc.file.title });
    s.push_str(&format!(
        "{} candidate lines, {n} rocks (seed {}). Protected zone: {}. Target: intercept {} % of the rocks reaching it. Class by the {} kinetic energy; cost = length × cost per metre of the class ({}).\n\n",
        study.candidates.len(),
        study.models[0].without.summary.seed,
        protected_zone_text(sc),
        fmt_num(100.0 * spec.target_share),
        class_energy_text(sc),
        spec.classes_kj.iter().zip(&spec.class_cost_per_m).map(|(c, p)| format!("{} kJ: {p}", thousands(*c))).collect::<Vec<_>>().join(", ")
    ));
    s.push_str(&format!("| {} |\n|{}\n", PROPOSAL_HEAD.join(" | "), "---|".repeat(PROPOSAL_HEAD.len())));
    for a in best {
        s.push_str(&format!("| {} |\n", proposal_cells(a, released_behind_counts(sc, study)).join(" | ")));
    }
    if best.is_empty() {
        s.push_str("\nNo candidate could be sized: too few rocks reach any candidate's protected zone.\n");
    }
    if let (Some(a), true) = (best.first(), study.models.len() > 1) {
        s.push_str(&format!(
            "\n## The models\n\n{}\n\nProposal #1, {}:\n\n| {} |\n|{}\n",
            models_sentence(sc, study),
            a.name,
            MODEL_HEAD.join(" | "),
            "---|".repeat(MODEL_HEAD.len())
        ));
        for row in model_rows(study, a) {
            s.push_str(&format!("| {} |\n", row.join(" | ")));
        }
        if let Some(text) = floor_sentence(study) {
            s.push_str(&format!("\n{text} (`floor/proposals.md`).\n"));
        }
    }
    if let (Some(b), false) = (&study.barrier, study.models[0].residual.is_none()) {
        s.push_str(&format!(
            "\n## With the best barrier in place\n\n{}. The same rocks run again.\n\n| | without | with |\n|---|---|---|\n",
            rerun_sentence(study, b)
        ));
        for (k, a, w) in residual_rows(sc, study) {
            s.push_str(&format!("| {k} | {a} | {w} |\n"));
        }
    }
    s
}

fn index_html(sc: &Scenario, study: &BarrierStudy, best: &[&Assessment], files: &[String]) -> String {
    let spec = &sc.file.barrier_design;
    let first = &study.models[0];
    let n = first.without.summary.rocks;
    let title = format!(
        "Barrier study: {}",
        if sc.file.title.is_empty() { sc.path.display().to_string() } else { sc.file.title.clone() }
    );
    let sub = format!(
        "talus {} · scenario {} · seed {} · {n} rocks per run · {} candidate lines",
        first.without.summary.talus_version,
        sc.path.display(),
        first.without.summary.seed,
        study.candidates.len()
    );
    let mut page = Page::new(&title, &sub);
    page.h2("Proposed barriers");
    let rows: Vec<Vec<String>> = best
        .iter()
        .map(|a| proposal_cells(a, released_behind_counts(sc, study)).iter().map(|c| escape(c)).collect())
        .collect();
    page.raw(&table(&PROPOSAL_HEAD, &rows, &[1, 8], &[0]));
    page.note(&format!(
        "Protected zone: {}. Each proposal is the shortest stretch of its candidate line that intercepts {} % of the rocks reaching the zone; fence height = P95 passing height of the rocks' lowest point + P95 rock size, rounded up to 0.5 m; class by the {} kinetic energy among the standard classes {} kJ; cost in relative units (length × {} per metre by class). All candidates: candidates.csv.",
        protected_zone_text(sc),
        fmt_num(100.0 * spec.target_share),
        class_energy_text(sc),
        spec.classes_kj.iter().map(|c| thousands(*c)).collect::<Vec<_>>().join(", "),
        spec.class_cost_per_m.iter().map(|c| fmt_num(*c)).collect::<Vec<_>>().join(", ")
    ));
    page.raw(&format!(
        "<div class=\"pair\">{}</div>",
        figure(
            "proposals.png",
            "Proposals",
            "the best proposals over the reach probability without a barrier; candidates in grey.",
            &[
                ("GeoJSON", "proposals.geojson".into()),
                ("CSV", "proposals.csv".into()),
                ("all candidates", "candidates.geojson".into())
            ]
        )
    ));
    if let (Some(a), true) = (best.first(), study.models.len() > 1) {
        page.h2("The models");
        page.note(&models_sentence(sc, study));
        let rows: Vec<Vec<String>> =
            model_rows(study, a).into_iter().map(|r| r.iter().map(|c| escape(c)).collect()).collect();
        // The models that set the height and the class stand out.
        let governing: Vec<usize> = (a.per_model.iter().enumerate())
            .filter(|(_, d)| d.model == a.height_from || d.model == a.energy_from)
            .map(|(i, _)| i)
            .collect();
        page.raw(&table(&MODEL_HEAD, &rows, &[0], &governing));
        if let Some(text) = floor_sentence(study) {
            page.raw(&format!("<p>{} (<a href=\"floor/index.html\">floor</a>).</p>", escape(&text)));
        }
    }
    if let (Some(b), Some(_)) = (&study.barrier, &first.residual) {
        page.h2("With the best barrier in place");
        page.raw(&format!("<p class=\"big\">{}. The same rocks run again.</p>", escape(&rerun_sentence(study, b))));
        let rows: Vec<Vec<String>> =
            residual_rows(sc, study).into_iter().map(|(k, a, w)| vec![escape(&k), escape(&a), escape(&w)]).collect();
        page.raw(&table(&["", "without", "with"], &rows, &[0], &[0]));
        page.raw(&format!(
            "<div class=\"pair\">{}{}</div><div class=\"pair\">{}</div>",
            figure(
                "reach_probability_without.png",
                "Without the barrier",
                "reach probability.",
                &[("run", format!("{}/index.html", run_folder(study.models.len(), &first.name, "without_barrier")))]
            ),
            figure(
                "reach_probability_with.png",
                "With the barrier",
                "reach probability, same colour scale.",
                &[("run", format!("{}/index.html", run_folder(study.models.len(), &first.name, "with_barrier")))]
            ),
            figure(
                "reach_probability_reduction.png",
                "Reduction",
                "reach probability without minus with the barrier.",
                &[("GeoTIFF", "reach_probability_reduction.tif".into())]
            )
        ));
    }
    page.h2("Runs");
    page.raw("<ul>");
    for m in &study.models {
        let of = if study.models.len() > 1 { format!("{}: ", escape(&m.name)) } else { String::new() };
        let without = run_folder(study.models.len(), &m.name, "without_barrier");
        page.raw(&format!("<li>{of}<a href=\"{without}/index.html\">without the barrier</a> (every candidate is a collector line: <a href=\"{without}/collectors.csv\">collectors.csv</a>)"));
        if m.with.is_some() {
            let with = run_folder(study.models.len(), &m.name, "with_barrier");
            page.raw(&format!(", <a href=\"{with}/index.html\">with the barrier</a>"));
        }
        page.raw("</li>");
    }
    page.raw("</ul>");
    page.h2("Files");
    let items: Vec<String> = files.iter().map(|f| format!("<li><a href=\"{0}\">{0}</a></li>", escape(f))).collect();
    page.raw(&format!("<ul class=\"files\">{}</ul>", items.join("")));
    page.finish()
}
