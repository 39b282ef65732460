//! Colour ramps for continuous values and class colours for categorical maps.
//!
//! The ramps are sampled from small tables of anchor colours (11 evenly spaced samples of the matplotlib
//! `viridis`, `magma` and `inferno` maps, and of ColorBrewer `RdBu` for the diverging one) with linear
//! interpolation in sRGB. With 11 anchors the interpolation error is below what the eye notices on a map.

use serde::{Deserialize, Serialize};

/// A continuous colour ramp, sampled by [`Colormap::sample`] at `t` in [0, 1].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Colormap {
    /// Sequential, perceptually uniform, dark blue-purple to yellow (matplotlib `viridis`). For counts and
    /// probabilities.
    #[default]
    Viridis,
    /// Sequential, black-purple-orange to pale yellow (matplotlib `magma`). For energies and heights.
    Magma,
    /// Sequential, black-red-orange to yellow (matplotlib `inferno`). For energies when more contrast is wanted.
    Inferno,
    /// Diverging, blue (negative) through near-white (zero) to red (positive) (ColorBrewer `RdBu`, reversed). For
    /// residuals ±; maps centre it on zero.
    Diverging,
    /// Sequential greys, black to white.
    Greys,
}

const VIRIDIS: [[u8; 3]; 11] = [
    [0x44, 0x01, 0x54],
    [0x48, 0x24, 0x75],
    [0x41, 0x44, 0x87],
    [0x35, 0x5f, 0x8d],
    [0x2a, 0x78, 0x8e],
    [0x21, 0x91, 0x8c],
    [0x22, 0xa8, 0x84],
    [0x44, 0xbf, 0x70],
    [0x7a, 0xd1, 0x51],
    [0xbd, 0xdf, 0x26],
    [0xfd, 0xe7, 0x25],
];

const MAGMA: [[u8; 3]; 11] = [
    [0x00, 0x00, 0x04],
    [0x14, 0x0e, 0x36],
    [0x3b, 0x0f, 0x70],
    [0x64, 0x1a, 0x80],
    [0x8c, 0x29, 0x81],
    [0xb7, 0x37, 0x79],
    [0xde, 0x49, 0x68],
    [0xf7, 0x70, 0x5c],
    [0xfe, 0x9f, 0x6d],
    [0xfe, 0xcf, 0x92],
    [0xfc, 0xfd, 0xbf],
];

const INFERNO: [[u8; 3]; 11] = [
    [0x00, 0x00, 0x04],
    [0x16, 0x0b, 0x39],
    [0x42, 0x0a, 0x68],
    [0x6a, 0x17, 0x6e],
    [0x93, 0x26, 0x67],
    [0xbc, 0x37, 0x54],
    [0xdd, 0x51, 0x3a],
    [0xf3, 0x78, 0x19],
    [0xfc, 0xa5, 0x0a],
    [0xf6, 0xd7, 0x46],
    [0xfc, 0xff, 0xa4],
];

const DIVERGING: [[u8; 3]; 11] = [
    [0x05, 0x30, 0x61],
    [0x21, 0x66, 0xac],
    [0x43, 0x93, 0xc3],
    [0x92, 0xc5, 0xde],
    [0xd1, 0xe5, 0xf0],
    [0xf7, 0xf7, 0xf7],
    [0xfd, 0xdb, 0xc7],
    [0xf4, 0xa5, 0x82],
    [0xd6, 0x60, 0x4d],
    [0xb2, 0x18, 0x2b],
    [0x67, 0x00, 0x1f],
];

const GREYS: [[u8; 3]; 2] = [[0, 0, 0], [255, 255, 255]];

impl Colormap {
    /// The anchor colours, evenly spaced over [0, 1].
    pub fn anchors(self) -> &'static [[u8; 3]] {
        match self {
            Colormap::Viridis => &VIRIDIS,
            Colormap::Magma => &MAGMA,
            Colormap::Inferno => &INFERNO,
            Colormap::Diverging => &DIVERGING,
            Colormap::Greys => &GREYS,
        }
    }

    /// True for ramps whose middle means zero ([`Colormap::Diverging`]).
    pub fn is_diverging(self) -> bool {
        matches!(self, Colormap::Diverging)
    }

    /// The colour at `t` in [0, 1] (clamped; `NaN` gives the low end), interpolated linearly between anchors.
    pub fn sample(self, t: f64) -> [u8; 3] {
        let a = self.anchors();
        let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
        let pos = t * (a.len() - 1) as f64;
        let i = (pos.floor() as usize).min(a.len() - 2);
        let f = pos - i as f64;
        let mix = |k: usize| (a[i][k] as f64 + (a[i + 1][k] as f64 - a[i][k] as f64) * f).round() as u8;
        [mix(0), mix(1), mix(2)]
    }
}

/// A class of a classified map: values up to and including `max_value` (and above the previous class's) get
/// `colour`. Classes are listed in increasing `max_value`; values above the last class take the last colour.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Class {
    /// Legend text, e.g. `"low (< 30 kJ)"`.
    pub label: String,
    /// Fill colour.
    pub colour: [u8; 3],
    /// Upper bound of the class, inclusive, in the layer's unit.
    pub max_value: f32,
}

impl Class {
    /// A class from its parts.
    pub fn new(label: impl Into<String>, colour: [u8; 3], max_value: f32) -> Self {
        Class { label: label.into(), colour, max_value }
    }

    /// The index of the class `value` falls in (`None` for `NaN` or an empty class list).
    pub fn index_of(classes: &[Class], value: f32) -> Option<usize> {
        if value.is_nan() || classes.is_empty() {
            return None;
        }
        Some(classes.iter().position(|c| value <= c.max_value).unwrap_or(classes.len() - 1))
    }
}

/// Distinct colours for categories, safe for colour-blind readers (Okabe & Ito 2008), in the order they are
/// handed out. Also used for chart series.
pub const CATEGORICAL: [[u8; 3]; 8] = [
    [0, 114, 178],   // blue
    [213, 94, 0],    // vermillion
    [0, 158, 115],   // bluish green
    [230, 159, 0],   // orange
    [86, 180, 233],  // sky blue
    [204, 121, 167], // reddish purple
    [240, 228, 66],  // yellow
    [0, 0, 0],       // black
];

/// Hazard class colours from low to high: green, yellow, orange, red, dark red.
pub const HAZARD: [[u8; 3]; 5] = [[26, 152, 80], [254, 224, 139], [252, 141, 89], [215, 48, 39], [127, 0, 0]];

/// One colour per label from [`CATEGORICAL`] (cycling after eight), as `(label, colour)` pairs.
pub fn class_colours(labels: &[&str]) -> Vec<(String, [u8; 3])> {
    labels.iter().enumerate().map(|(i, l)| (l.to_string(), CATEGORICAL[i % CATEGORICAL.len()])).collect()
}

/// Hazard classes for increasing upper bounds `max_values`, coloured from [`HAZARD`] (green to dark red, spread
/// over the palette when there are fewer than five classes). `labels` and `max_values` pair up by index.
pub fn hazard_classes(labels: &[&str], max_values: &[f32]) -> Vec<Class> {
    let n = labels.len().min(max_values.len());
    (0..n)
        .map(|i| {
            let k = if n <= 1 { 0 } else { (i * (HAZARD.len() - 1) + (n - 1) / 2) / (n - 1) };
            Class::new(labels[i], HAZARD[k.min(HAZARD.len() - 1)], max_values[i])
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ramps_hit_their_anchors_and_interpolate() {
        assert_eq!(Colormap::Viridis.sample(0.0), [0x44, 0x01, 0x54]);
        assert_eq!(Colormap::Viridis.sample(1.0), [0xfd, 0xe7, 0x25]);
        assert_eq!(Colormap::Viridis.sample(2.0), [0xfd, 0xe7, 0x25]);
        assert_eq!(Colormap::Viridis.sample(f64::NAN), [0x44, 0x01, 0x54]);
        assert_eq!(Colormap::Diverging.sample(0.5), [0xf7, 0xf7, 0xf7]);
        assert_eq!(Colormap::Greys.sample(0.5), [128, 128, 128]);
        // Sequential ramps get lighter monotonically (sum of channels as a rough lightness).
        for cm in [Colormap::Viridis, Colormap::Magma, Colormap::Inferno] {
            let l: Vec<u32> = (0..=20).map(|i| cm.sample(i as f64 / 20.0).iter().map(|&c| c as u32).sum()).collect();
            assert!(l.windows(2).all(|w| w[1] + 8 >= w[0]), "{cm:?}: {l:?}");
            assert!(l[20] > l[0] + 300);
        }
    }

    #[test]
    fn classes_pick_the_first_bound_at_or_above() {
        let c = hazard_classes(&["low", "medium", "high"], &[1.0, 10.0, 100.0]);
        assert_eq!(c[0].colour, HAZARD[0]);
        assert_eq!(c[2].colour, HAZARD[4]);
        assert_eq!(Class::index_of(&c, 0.5), Some(0));
        assert_eq!(Class::index_of(&c, 1.0), Some(0));
        assert_eq!(Class::index_of(&c, 5.0), Some(1));
        assert_eq!(Class::index_of(&c, 1e6), Some(2));
        assert_eq!(Class::index_of(&c, f32::NAN), None);
        let cc = class_colours(&["a", "b"]);
        assert_eq!(cc[1], ("b".to_string(), CATEGORICAL[1]));
    }
}
