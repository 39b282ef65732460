//! Flexible rockfall barriers (fences) inside the simulation.
//!
//! A barrier is a vertical fence along a polyline, `height_m` tall above the ground, that absorbs up to
//! `capacity_j` of kinetic energy (its energy class, as in EAD 340059-00-0106 / ETAG 027 practice). A rock whose
//! path crosses the line with its lowest point below the fence top hits it: if its kinetic energy is within the
//! capacity it is caught (stop reason `barrier`); otherwise it breaks through with its kinetic energy reduced by
//! the capacity, its velocity and spin scaled by √((E − C)/E) (ours: the simplest energy balance). A rock that
//! passes over the top is not touched. Each barrier acts at most once on a rock.

/// A barrier in the terrain's local frame.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Barrier {
    /// Name for outputs.
    pub name: String,
    /// Polyline vertices (x, y), local frame, m.
    pub line_m: Vec<[f64; 2]>,
    /// Height above the ground, m.
    pub height_m: f64,
    /// Energy it can absorb, J.
    pub capacity_j: f64,
}

/// A rock meeting a barrier.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BarrierHit {
    /// Index of the barrier.
    pub barrier: usize,
    /// Time, s.
    pub t_s: f64,
    /// Centre of mass at the crossing, m (local frame).
    pub point_m: nalgebra::Vector3<f64>,
    /// Total kinetic energy at the crossing, J.
    pub kinetic_j: f64,
    /// Height of the rock's lowest point above the ground at the crossing, m.
    pub clearance_m: f64,
    /// True if the rock was caught.
    pub caught: bool,
}

impl Barrier {
    /// The fraction s in [0, 1] along the horizontal segment a → b where it first crosses the barrier line, if it
    /// does.
    pub fn crossing(&self, a: [f64; 2], b: [f64; 2]) -> Option<f64> {
        let mut best: Option<f64> = None;
        for w in self.line_m.windows(2) {
            if let Some(s) = segment_intersection(a, b, w[0], w[1]) {
                if best.is_none_or(|t| s < t) {
                    best = Some(s);
                }
            }
        }
        best
    }
}

/// Parameter s along p → q where it meets segment u → v (both closed), if it does.
pub fn segment_intersection(p: [f64; 2], q: [f64; 2], u: [f64; 2], v: [f64; 2]) -> Option<f64> {
    let r = [q[0] - p[0], q[1] - p[1]];
    let d = [v[0] - u[0], v[1] - u[1]];
    let den = r[0] * d[1] - r[1] * d[0];
    if den.abs() < 1e-15 {
        return None;
    }
    let w = [u[0] - p[0], u[1] - p[1]];
    let s = (w[0] * d[1] - w[1] * d[0]) / den;
    let t = (w[0] * r[1] - w[1] * r[0]) / den;
    ((0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&t)).then_some(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crossings() {
        let b = Barrier {
            name: "b".into(),
            line_m: vec![[0.0, 0.0], [10.0, 0.0], [10.0, 10.0]],
            height_m: 3.0,
            capacity_j: 1e5,
        };
        assert_eq!(b.crossing([5.0, -1.0], [5.0, 1.0]), Some(0.5));
        assert_eq!(b.crossing([5.0, 1.0], [5.0, 2.0]), None);
        let s = b.crossing([9.0, 5.0], [13.0, 5.0]).unwrap();
        assert!((s - 0.25).abs() < 1e-12);
    }
}
