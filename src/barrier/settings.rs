//! `[barrier_design]`: the settings of `talus barrier`, all optional.
//!
//! ```toml
//! [barrier_design]
//! target_share = 0.99                 # share of the rocks reaching the protected zone to intercept
//! asset_line = [[150.0, 0.0], [150.0, 100.0]]   # or asset_polygon = [...]; default: beyond each candidate
//! toe_line = [[114.3, 0.0], [114.3, 100.0]]     # offsets of it become candidates
//! offsets_m = [5.0, 10.0, 20.0, 40.0]
//! contour_interval_m = 10.0           # default: about 20 levels over the relief
//! max_slope_deg = 45.0
//! class_energy = "p95"                # p95 | p99 | max
//! max_fence_height_m = 8.0
//! class_cost_per_m = [1.0, 1.6, 2.2, 3.2, 3.9, 4.5, 5.5, 6.7]
//! best = 5
//! across_models = "worst"             # worst | pooled (with `talus barrier --models`)
//! ```

use crate::collector::{DEFAULT_SEGMENT_M, MIN_SEGMENT_M};
use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

/// Which energy of the rocks crossing a barrier picks its energy class.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ClassEnergy {
    /// 95th percentile of the total kinetic energy (default).
    #[default]
    P95,
    /// 99th percentile.
    P99,
    /// The largest.
    Max,
}

/// How a barrier designed against several models (`talus barrier --models`) takes them (ours).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum AcrossModels {
    /// It must hold under every model: the target share in each, the height and class of the model that asks most
    /// (default). Grows with the number of models even when they agree (the worst of n).
    #[default]
    Worst,
    /// The models' rocks pooled, as one ensemble: the predictive distribution that averages the models with equal
    /// weights (Bayesian model averaging with equal weights, Hoeting et al. 1999, Statistical Science 14(4)); the
    /// target share and the P95s of the pooled rocks. Does not grow with the number of models.
    Pooled,
}

/// The standard energy classes of flexible rockfall barriers, kJ (EAD 340059-00-0106, formerly ETAG 027: classes
/// 0 to 8 by maximum energy level, MEL).
pub const STANDARD_CLASSES_KJ: [f64; 8] = [100.0, 250.0, 500.0, 1000.0, 1500.0, 2000.0, 3000.0, 4500.0];

/// Default cost per metre of each class, in relative units (ours: √(class / 100 kJ), rounded; a stand-in for
/// local prices, which the user should give).
pub const DEFAULT_CLASS_COST_PER_M: [f64; 8] = [1.0, 1.6, 2.2, 3.2, 3.9, 4.5, 5.5, 6.7];

/// `[barrier_design]`.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct DesignSpec {
    /// Share of the rocks that would reach the protected zone that the barrier must intercept (default 0.99).
    pub target_share: f64,
    /// Asset line (x, y) in the terrain's horizontal frame: a rock reaches the protected zone when it crosses it.
    pub asset_line: Vec<[f64; 2]>,
    /// Or an asset polygon: a rock reaches it when its path enters it.
    pub asset_polygon: Vec<[f64; 2]>,
    /// A toe line (x, y): its downslope offsets by `offsets_m` become candidates.
    pub toe_line: Vec<[f64; 2]>,
    /// Offsets, m: downslope of the toe line and of a pit's lowest toe, upslope of the asset line (default
    /// [5, 10, 20, 40]).
    pub offsets_m: Vec<f64>,
    /// Contour candidates every this many metres of elevation (default: a 1-2-5 step giving about 20 levels).
    pub contour_interval_m: Option<f64>,
    /// Contour candidates only where the ground is at most this steep, degrees (default 45).
    pub max_slope_deg: f64,
    /// Use contour lines as candidates (default true).
    pub contours: bool,
    /// Detect benches (flat bands between steep faces) and use their crests and toes (default true).
    pub benches: bool,
    /// Stretch length of the candidates, m (default 5).
    pub segment_m: f64,
    /// A candidate is sized only if at least this many rocks would reach its protected zone (default 20).
    pub min_rocks: usize,
    /// A proposal must intercept at least this share of all released rocks (default 0.05).
    pub min_share_of_released: f64,
    /// Which energy picks the class (default p95).
    pub class_energy: ClassEnergy,
    /// Fences higher than this are flagged and ranked after buildable ones, m (default 8; ours: the tallest
    /// standard flexible barriers are about that high, **unverified** as a general limit).
    pub max_fence_height_m: f64,
    /// Barrier energy classes, kJ, increasing (default the standard classes 100 to 4,500 kJ).
    pub classes_kj: Vec<f64>,
    /// Cost per metre of each class (default: relative units, see [`DEFAULT_CLASS_COST_PER_M`]).
    pub class_cost_per_m: Vec<f64>,
    /// Number of proposals written (default 5).
    pub best: usize,
    /// Re-run with the best proposal in place (default true).
    pub rerun: bool,
    /// With several models: `worst` (default) or `pooled`, see [`AcrossModels`].
    pub across_models: AcrossModels,
}

impl Default for DesignSpec {
    fn default() -> Self {
        DesignSpec {
            target_share: 0.99,
            asset_line: Vec::new(),
            asset_polygon: Vec::new(),
            toe_line: Vec::new(),
            offsets_m: vec![5.0, 10.0, 20.0, 40.0],
            contour_interval_m: None,
            max_slope_deg: 45.0,
            contours: true,
            benches: true,
            segment_m: DEFAULT_SEGMENT_M,
            min_rocks: 20,
            min_share_of_released: 0.05,
            class_energy: ClassEnergy::P95,
            max_fence_height_m: 8.0,
            classes_kj: STANDARD_CLASSES_KJ.to_vec(),
            class_cost_per_m: DEFAULT_CLASS_COST_PER_M.to_vec(),
            best: 5,
            rerun: true,
            across_models: AcrossModels::Worst,
        }
    }
}

impl DesignSpec {
    /// Checks every value (`field` locates the table in errors).
    pub fn check(&self, field: &str) -> Result<()> {
        let k = |key: &str| format!("{field}.{key}");
        if !(self.target_share > 0.0 && self.target_share <= 1.0) {
            return Err(Error::invalid(
                k("target_share"),
                format!("must be in (0, 1], got {}", self.target_share),
                "use e.g. 0.99",
            ));
        }
        if !self.asset_line.is_empty() && !self.asset_polygon.is_empty() {
            return Err(Error::invalid(field, "has both asset_line and asset_polygon", "keep one of them"));
        }
        for (key, pts, min) in [
            ("asset_line", &self.asset_line, 2),
            ("asset_polygon", &self.asset_polygon, 3),
            ("toe_line", &self.toe_line, 2),
        ] {
            if pts.is_empty() {
                continue;
            }
            if pts.len() < min {
                return Err(Error::invalid(
                    k(key),
                    format!("has {} vertices", pts.len()),
                    format!("give at least {min} [x, y] vertices"),
                ));
            }
            if let Some(i) = pts.iter().position(|p| !p.iter().all(|v| v.is_finite())) {
                return Err(Error::invalid(
                    format!("{}[{i}]", k(key)),
                    "is not a finite [x, y] pair",
                    "give plain numbers",
                ));
            }
        }
        if let Some(o) = self.offsets_m.iter().find(|o| !(o.is_finite() && **o >= 0.0)) {
            return Err(Error::invalid(
                k("offsets_m"),
                format!("{o} is not a distance ≥ 0"),
                "give distances in m, e.g. [5, 10, 20, 40]",
            ));
        }
        if let Some(c) = self.contour_interval_m {
            if !(c.is_finite() && c > 0.0) {
                return Err(Error::invalid(
                    k("contour_interval_m"),
                    format!("must be positive, got {c}"),
                    "give an elevation step in m, e.g. 10",
                ));
            }
        }
        if !(self.max_slope_deg > 0.0 && self.max_slope_deg <= 90.0) {
            return Err(Error::invalid(
                k("max_slope_deg"),
                format!("must be in (0, 90], got {}", self.max_slope_deg),
                "use e.g. 45",
            ));
        }
        if !(self.segment_m.is_finite() && self.segment_m >= MIN_SEGMENT_M) {
            return Err(Error::invalid(
                k("segment_m"),
                format!("must be at least {MIN_SEGMENT_M} m, got {}", self.segment_m),
                "use e.g. 5",
            ));
        }
        if !(0.0..=1.0).contains(&self.min_share_of_released) {
            return Err(Error::invalid(
                k("min_share_of_released"),
                format!("must be in [0, 1], got {}", self.min_share_of_released),
                "use e.g. 0.05",
            ));
        }
        if self.classes_kj.is_empty()
            || !self.classes_kj.windows(2).all(|w| w[0] < w[1])
            || !self.classes_kj.iter().all(|c| c.is_finite() && *c > 0.0)
        {
            return Err(Error::invalid(
                k("classes_kj"),
                format!("{:?} is not an increasing list of positive energies", self.classes_kj),
                "use e.g. [100, 250, 500, 1000, 1500, 2000, 3000, 4500]",
            ));
        }
        if self.class_cost_per_m.len() != self.classes_kj.len()
            || !self.class_cost_per_m.iter().all(|c| c.is_finite() && *c > 0.0)
        {
            return Err(Error::invalid(
                k("class_cost_per_m"),
                format!(
                    "needs one positive cost per class ({} classes), got {:?}",
                    self.classes_kj.len(),
                    self.class_cost_per_m
                ),
                "give one cost per metre for each entry of classes_kj",
            ));
        }
        if !(self.max_fence_height_m.is_finite() && self.max_fence_height_m > 0.0) {
            return Err(Error::invalid(
                k("max_fence_height_m"),
                format!("must be positive, got {}", self.max_fence_height_m),
                "use e.g. 8",
            ));
        }
        if self.best == 0 {
            return Err(Error::invalid(k("best"), "is 0", "write at least 1 proposal"));
        }
        Ok(())
    }
}
