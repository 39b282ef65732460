//! Pictures of results: PNG maps of hazard rasters over a hillshade, and SVG charts of distributions.
//!
//! Everything here is dependency-light on purpose: PNGs are encoded with `png`, text comes from a built-in bitmap
//! font, and SVG is written as text. Every file goes through [`crate::io::write_atomic`].
//!
//! - [`colormap`]: perceptual colour ramps and class colours.
//! - [`font`]: the bitmap font and text drawing.
//! - [`canvas`]: an RGBA pixel canvas with lines, shapes, alpha blending and PNG output.
//! - [`ticks`]: "nice" 1-2-5 axis ticks and number formatting shared by maps and charts.
//! - [`map`]: a raster layer over a hillshade with title, colour bar, scale bar and north arrow.
//! - [`chart`]: SVG line, marker, step, histogram and grouped bar charts.

pub mod canvas;
pub mod chart;
pub mod colormap;
pub mod font;
pub mod map;
pub mod ticks;

pub use canvas::{opaque, with_alpha, Canvas, Marker, Rect, Rgba};
pub use chart::{bar_chart, escape_xml, histogram_chart, to_svg, write_svg, Chart, Series, SeriesStyle};
pub use colormap::{class_colours, hazard_classes, Class, Colormap};
pub use font::{draw_text, draw_text_halo, text_height, text_width};
pub use map::{hillshade, render_hillshade, render_map, MapInfo, MapLayer, OverlayLine, Overlays, ValueScale};
pub use ticks::{format_tick, format_value, log_ticks, nice_length, nice_step, nice_ticks};

/// Example pictures of every kind, written to `outputs/render_examples/` for a person to look at:
/// `cargo test --lib render::examples -- --ignored`.
#[cfg(test)]
mod examples {
    use super::*;
    use crate::random::{standard_normal, stream, uniform};
    use crate::raster::{Crs, Grid};
    use std::path::PathBuf;

    const X0: f64 = 2_600_000.0;
    const Y0: f64 = 1_200_000.0;

    /// A slope falling to the south: valley floor, talus, a cliff band, gullies.
    fn z(x: f64, y: f64) -> f64 {
        let (u, v) = (x - X0, y - Y0);
        let sig = |t: f64| 1.0 / (1.0 + (-t).exp());
        let softplus = |t: f64| if t > 30.0 { t } else { t.exp().ln_1p() };
        700.0 + 0.06 * v + 0.75 * 40.0 * softplus((v - 110.0) / 40.0) + 55.0 * sig((v - 262.0) / 5.0)
            - 14.0 * (-((u - 180.0) / 28.0).powi(2)).exp() * sig((v - 80.0) / 25.0)
            - 9.0 * (-((u - 430.0) / 35.0).powi(2)).exp() * sig((v - 80.0) / 25.0)
            + 5.0 * (u / 47.0).sin() * (v / 90.0).cos()
    }

    fn out_dir() -> PathBuf {
        let d = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("outputs/render_examples");
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    #[ignore = "writes example pictures to outputs/; run by hand and look at them"]
    fn example_pictures() {
        let dir = out_dir();
        let mut dem = Grid::filled(300, 200, X0, Y0 + 400.0, 2.0, 0.0);
        dem.crs = Crs::epsg(2056);
        for r in 0..dem.nrows {
            for c in 0..dem.ncols {
                let (x, y) = dem.cell_centre(c, r);
                dem.values[r * dem.ncols + c] = z(x, y) as f32;
            }
        }
        // The north-east corner of the DEM is missing, as on real survey tiles.
        for r in 0..30 {
            for c in 260..300 {
                dem.values[r * dem.ncols + c] = f32::NAN;
            }
        }

        // Toy rock paths: steepest descent with noise and a sliding-friction energy line.
        let mut passages = Grid::filled(120, 80, X0, Y0 + 400.0, 5.0, 0.0);
        passages.crs = Crs::epsg(2056);
        let mut energy = passages.clone();
        let mut ends = Vec::new();
        let mut runout = Vec::new();
        for i in 0..2500u64 {
            let mut rng = stream(7, i);
            let (mut x, mut y) = (X0 + 90.0 + 460.0 * uniform(&mut rng), Y0 + 272.0 + 6.0 * uniform(&mut rng));
            let mu = (0.72 + 0.08 * standard_normal(&mut rng)).clamp(0.5, 0.9);
            let (mut v2, mut dir) = (1.0, (0.0f64, -1.0f64));
            let mut seen = std::collections::HashSet::new();
            let start_y = y;
            for _ in 0..2000 {
                let (gx, gy) = ((z(x + 1.0, y) - z(x - 1.0, y)) / 2.0, (z(x, y + 1.0) - z(x, y - 1.0)) / 2.0);
                let g = (gx * gx + gy * gy).sqrt().max(1e-9);
                let wobble = 0.25 * standard_normal(&mut rng);
                let (dx, dy) = (0.8 * dir.0 - 0.2 * gx / g, 0.8 * dir.1 - 0.2 * gy / g);
                let a = dy.atan2(dx) + wobble;
                dir = (a.cos(), a.sin());
                let (nx, ny) = (x + 2.0 * dir.0, y + 2.0 * dir.1);
                v2 += 2.0 * 9.81 * (z(x, y) - z(nx, ny)) - 2.0 * 9.81 * mu * 2.0;
                if v2 <= 0.0 || ny < Y0 + 2.0 {
                    break;
                }
                (x, y) = (nx, ny);
                if let Some((c, r)) = passages.cell_of(x, y) {
                    let k = r * passages.ncols + c;
                    if seen.insert(k) {
                        passages.values[k] += 1.0;
                    }
                    energy.values[k] = energy.values[k].max((0.5 * 1500.0 * v2 / 1000.0) as f32);
                }
            }
            ends.push((x, y));
            runout.push(start_y - y);
        }
        for r in 0..10 {
            for c in 0..12 {
                passages.values[r * 120 + c] = f32::NAN;
            }
        }

        let profile = OverlayLine {
            xy: vec![(X0 + 300.0, Y0 + 390.0), (X0 + 300.0, Y0 + 200.0), (X0 + 290.0, Y0 + 20.0)],
            colour: [20, 20, 20],
            width_px: 2.0,
            label: Some("Profile A".into()),
        };
        let barrier = OverlayLine {
            xy: vec![(X0 + 60.0, Y0 + 95.0), (X0 + 250.0, Y0 + 88.0), (X0 + 420.0, Y0 + 92.0)],
            colour: [220, 30, 30],
            width_px: 4.0,
            label: Some("Barrier 500 kJ".into()),
        };
        let overlays = Overlays {
            points: ends.iter().copied().step_by(5).collect(),
            point_label: Some("end points (1 in 5)".into()),
            lines: vec![profile.clone(), barrier],
            ..Default::default()
        };

        let mut layer = MapLayer::new(&passages, "Rock passages per cell", "passages");
        layer.transparent_zero = true;
        let info = render_map(&dir.join("passages.png"), &layer, Some(&dem), &overlays).unwrap();
        eprintln!("passages: {info:?}");

        let mut layer = MapLayer::new(&energy, "Maximum kinetic energy", "kJ");
        layer.colormap = Colormap::Magma;
        layer.scale = ValueScale::Log;
        layer.transparent_zero = true;
        render_map(&dir.join("energy_log.png"), &layer, Some(&dem), &Overlays::default()).unwrap();

        layer.title = "Energy classes".into();
        layer.scale = ValueScale::Linear;
        layer.classes = Some(hazard_classes(
            &["< 30 kJ", "30-300 kJ", "300-1000 kJ", "> 1000 kJ"],
            &[30.0, 300.0, 1000.0, f32::INFINITY],
        ));
        render_map(&dir.join("energy_classes.png"), &layer, Some(&dem), &Overlays::default()).unwrap();

        let mut residual = passages.clone();
        for r in 0..residual.nrows {
            for c in 0..residual.ncols {
                let k = r * residual.ncols + c;
                if residual.values[k] > 0.0 {
                    let (x, y) = residual.cell_centre(c, r);
                    residual.values[k] = (0.35 * ((x - X0) / 70.0).sin() * ((y - Y0) / 50.0).cos()) as f32;
                }
            }
        }
        let mut layer = MapLayer::new(&residual, "Residual: simulated - observed passage fraction", "fraction");
        layer.colormap = Colormap::Diverging;
        layer.transparent_zero = true;
        render_map(&dir.join("residual.png"), &layer, Some(&dem), &Overlays::default()).unwrap();

        // A narrow strip along the fall line: a tall map.
        let (c0, nc) = (30, 16);
        let mut strip = Grid::filled(nc, passages.nrows, X0 + c0 as f64 * 5.0, Y0 + 400.0, 5.0, 0.0);
        for r in 0..strip.nrows {
            for c in 0..nc {
                strip.values[r * nc + c] = passages.values[r * passages.ncols + c0 + c];
            }
        }
        let mut layer = MapLayer::new(&strip, "Gully strip", "passages");
        layer.transparent_zero = true;
        layer.scale = ValueScale::Log;
        render_map(&dir.join("strip_log.png"), &layer, Some(&dem), &Overlays::default()).unwrap();

        let hs = Overlays { lines: vec![profile], ..Default::default() };
        render_hillshade(&dir.join("hillshade.png"), &dem, &hs).unwrap();

        // Charts.
        let observed: Vec<f64> = runout.iter().step_by(40).map(|r| r * 0.95 + 6.0).collect();
        let h = histogram_chart(
            "Run-out distance: observed vs simulated",
            "run-out from release (m)",
            &[("observed", &observed), ("simulated", &runout)],
            24,
        );
        write_svg(&dir.join("runout_histogram.svg"), &h).unwrap();

        let xs: Vec<f64> = (0..9).map(|i| i as f64 * 5.0 - 20.0).collect();
        let mut sim = Series::new(
            "simulated",
            xs.iter().map(|&x| (x, 100.0 * (-(x / 12.0).powi(2)).exp())).collect(),
            SeriesStyle::LineMarkers,
            colormap::CATEGORICAL[0],
        );
        sim.error_bars = Some(sim.points.iter().map(|p| (p.1 * 0.85, p.1 * 1.15)).collect());
        let obs = Series::new(
            "observed (2019 survey)",
            xs.iter().map(|&x| (x + 1.0, 95.0 * (-(x / 14.0).powi(2)).exp())).collect(),
            SeriesStyle::Markers,
            colormap::CATEGORICAL[1],
        );
        let chart = Chart {
            title: "Lateral spread at the toe".into(),
            x_label: "offset from fall line (m)".into(),
            y_label: "rocks per 5 m bin".into(),
            series: vec![sim, obs],
            vlines: vec![(-14.5, "Modified Ritchie width".into()), (14.5, "Modified Ritchie width".into())],
            hlines: vec![(50.0, "half maximum".into())],
            ..Default::default()
        };
        write_svg(&dir.join("lateral_spread.svg"), &chart).unwrap();

        let mut b = bar_chart(
            "Captured fraction per bench",
            &["bench 1", "bench 2", "bench 3", "bench 4"],
            &[
                ("3DRB", &[0.92, 0.81, 0.64, 0.4]),
                ("2DLM", &[0.88, 0.75, 0.70, 0.35]),
                ("field", &[0.9, 0.78, f64::NAN, 0.42]),
            ],
        );
        b.y_label = "captured fraction".into();
        b.y_range = Some((0.0, 1.0));
        write_svg(&dir.join("captured_bars.svg"), &b).unwrap();
    }
}
