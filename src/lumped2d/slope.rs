//! A profile with its materials resolved and its segment geometry precomputed, and the exact landing search of a
//! parabola against the segments.

use super::engine::G_MPS2;
use super::material::Material2d;
use super::profile::Profile;
use crate::error::{Error, Result};
use std::collections::BTreeMap;

/// One segment's geometry: start point, unit direction (towards the next vertex), upward unit normal, length.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Seg {
    pub a: [f64; 2],
    pub b: [f64; 2],
    /// Unit direction (b − a)/len; `t[0] >= 0` because x never decreases.
    pub t: [f64; 2],
    /// Unit normal pointing out of the ground: t rotated by +90°, `(-t_z, t_x)`.
    pub n: [f64; 2],
    pub len: f64,
    pub material: usize,
}

impl Seg {
    pub fn is_vertical(&self) -> bool {
        self.t[0] == 0.0
    }
}

/// A profile and one [`Material2d`] per profile material, checked and ready to simulate on.
#[derive(Debug, Clone, PartialEq)]
pub struct Slope2d {
    profile: Profile,
    materials: Vec<Material2d>,
    pub(crate) segs: Vec<Seg>,
}

/// How a flight ends.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum FlightEnd {
    /// Lands on segment `seg` after `t` s, `s` m along it.
    Hit { t: f64, seg: usize, s: f64 },
    /// Leaves the profile's x range after `t` s.
    Left { t: f64 },
}

/// Sin of the turning angle below which a vertex counts as straight (not convex).
const CONVEX_TOL: f64 = 1e-9;

impl Slope2d {
    /// A slope from a profile and one material per profile material name (same order as
    /// [`Profile::material_names`]).
    ///
    /// # Errors
    /// When the number of materials does not match, or a material is out of range.
    pub fn new(profile: Profile, materials: Vec<Material2d>) -> Result<Slope2d> {
        if materials.len() != profile.material_names().len() {
            return Err(Error::invalid(
                "materials",
                format!(
                    "{} materials for a profile with {} ({})",
                    materials.len(),
                    profile.material_names().len(),
                    profile.material_names().join(", ")
                ),
                "give one material per profile material, in the profile's order",
            ));
        }
        for (m, name) in materials.iter().zip(profile.material_names()) {
            m.validate(&format!("materials.{name}"))?;
        }
        let segs = (0..profile.n_segments())
            .map(|i| {
                let a = profile.vertex(i);
                let b = profile.vertex(i + 1);
                let (dx, dz) = (b[0] - a[0], b[1] - a[1]);
                let len = dx.hypot(dz);
                let t = [dx / len, dz / len];
                Seg { a, b, t, n: [-t[1], t[0]], len, material: profile.segment_materials()[i] }
            })
            .collect();
        Ok(Slope2d { profile, materials, segs })
    }

    /// A slope whose materials are looked up by name in `materials`.
    ///
    /// # Errors
    /// When a profile material has no entry (the error lists what is there).
    pub fn with_named_materials(profile: Profile, materials: &BTreeMap<String, Material2d>) -> Result<Slope2d> {
        let mut list = Vec::new();
        for name in profile.material_names() {
            let m = materials.get(name).ok_or_else(|| {
                Error::invalid(
                    format!("materials.{name}"),
                    format!(
                        "the profile uses material '{name}', which is not defined (defined: {})",
                        materials.keys().cloned().collect::<Vec<_>>().join(", ")
                    ),
                    format!("add a [materials.{name}] table, e.g. with preset = \"floor_all\""),
                )
            })?;
            list.push(*m);
        }
        Slope2d::new(profile, list)
    }

    /// The profile.
    pub fn profile(&self) -> &Profile {
        &self.profile
    }

    /// The materials, indexed like [`Profile::material_names`].
    pub fn materials(&self) -> &[Material2d] {
        &self.materials
    }

    /// The material of segment `seg`.
    pub(crate) fn material_of(&self, seg: usize) -> &Material2d {
        &self.materials[self.segs[seg].material]
    }

    /// Whether the vertex between segments `i` and `i + 1` is convex (the ground falls away).
    pub(crate) fn is_convex(&self, i: usize) -> bool {
        let (p, q) = (self.segs[i].t, self.segs[i + 1].t);
        p[0] * q[1] - p[1] * q[0] < -CONVEX_TOL
    }

    /// The earliest landing of the parabola from `p0` with velocity `v0`, and the greatest height of the path
    /// above the profile (measured vertically) before it. `departure` is the segment the rock is leaving, on which
    /// `p0` lies exactly.
    pub(crate) fn land(&self, p0: [f64; 2], v0: [f64; 2], departure: Option<usize>) -> (FlightEnd, f64) {
        let n = self.segs.len();
        let xs = self.profile.x_m();
        let mut max_h = f64::NEG_INFINITY;
        if v0[0] > 0.0 {
            let a = xs.partition_point(|&v| v < p0[0]);
            for i in a.max(1) - 1..n {
                if let Some(hit) = self.visit(i, p0, v0, departure, &mut max_h) {
                    return (hit, max_h);
                }
            }
            let t = (xs[n] - p0[0]) / v0[0];
            (FlightEnd::Left { t: t.max(0.0) }, max_h)
        } else if v0[0] < 0.0 {
            let b = xs.partition_point(|&v| v <= p0[0]);
            for i in (0..b.min(n)).rev() {
                if let Some(hit) = self.visit(i, p0, v0, departure, &mut max_h) {
                    return (hit, max_h);
                }
            }
            let t = (xs[0] - p0[0]) / v0[0];
            (FlightEnd::Left { t: t.max(0.0) }, max_h)
        } else {
            let mut best: Option<FlightEnd> = None;
            for i in self.profile.segments_at(p0[0]) {
                let mut h = f64::NEG_INFINITY;
                if let Some(hit @ FlightEnd::Hit { t, .. }) = self.visit(i, p0, v0, departure, &mut h) {
                    if best.is_none_or(|b| matches!(b, FlightEnd::Hit { t: tb, .. } if t < tb)) {
                        best = Some(hit);
                    }
                }
            }
            let zs = self.profile.z_at(p0[0]).unwrap_or(p0[1]);
            let end = best.unwrap_or_else(|| {
                // Only reachable through rounding (the rock a hair below the ground): land where the fall meets
                // the surface.
                let seg = self.top_segment_at(p0[0]).unwrap_or(0);
                let drop = (p0[1] - zs).max(0.0);
                let t = (v0[1] + (v0[1] * v0[1] + 2.0 * G_MPS2 * drop).sqrt()) / G_MPS2;
                let s = ((p0[0] - self.segs[seg].a[0]) * self.segs[seg].t[0]
                    + (zs - self.segs[seg].a[1]) * self.segs[seg].t[1])
                    .clamp(0.0, self.segs[seg].len);
                FlightEnd::Hit { t, seg, s }
            });
            let apex = p0[1] + if v0[1] > 0.0 { v0[1] * v0[1] / (2.0 * G_MPS2) } else { 0.0 };
            (end, apex - zs)
        }
    }

    /// The non-vertical segment with the highest ground at `x_m`, or a vertical one if that is all there is.
    pub(crate) fn top_segment_at(&self, x_m: f64) -> Option<usize> {
        let range = self.profile.segments_at(x_m);
        let z_of = |i: usize| {
            let s = &self.segs[i];
            if s.is_vertical() {
                s.a[1].max(s.b[1])
            } else {
                s.a[1] + s.t[1] / s.t[0] * (x_m - s.a[0])
            }
        };
        range.max_by(|&i, &j| z_of(i).total_cmp(&z_of(j)).then(j.cmp(&i)))
    }

    /// Landing test against segment `i` (and the height above it over the part of the flight within its x range).
    fn visit(
        &self,
        i: usize,
        p0: [f64; 2],
        v0: [f64; 2],
        departure: Option<usize>,
        max_h: &mut f64,
    ) -> Option<FlightEnd> {
        let s = &self.segs[i];
        // Signed distance from the segment line: d(t) = c0 + c1 t + c2 t², concave (c2 <= 0).
        let c0 = if departure == Some(i) { 0.0 } else { s.n[0] * (p0[0] - s.a[0]) + s.n[1] * (p0[1] - s.a[1]) };
        let c1 = s.n[0] * v0[0] + s.n[1] * v0[1];
        let c2 = -0.5 * G_MPS2 * s.n[1];
        // The root where the path crosses the line downwards (d' < 0) is the larger root.
        let root = if departure == Some(i) {
            (c2 < 0.0 && c1 > 0.0).then(|| -c1 / c2)
        } else if c2 < 0.0 {
            let disc = c1 * c1 - 4.0 * c2 * c0;
            if disc < 0.0 {
                None
            } else {
                let q = -0.5 * (c1 + c1.signum() * disc.sqrt());
                let (r1, r2) = if q == 0.0 { (0.0, 0.0) } else { (q / c2, c0 / q) };
                Some(r1.max(r2))
            }
        } else if c1 < 0.0 {
            Some(-c0 / c1)
        } else {
            None
        };
        // Time window in which x lies within the segment.
        let (mut ta, mut tb) = if v0[0] != 0.0 {
            let (u, w) = ((s.a[0] - p0[0]) / v0[0], (s.b[0] - p0[0]) / v0[0]);
            (u.min(w), u.max(w))
        } else {
            (0.0, f64::INFINITY)
        };
        ta = ta.max(0.0);
        let mut hit = None;
        if let Some(t) = root.filter(|&t| t >= -1e-12 && t.is_finite()) {
            let t = t.max(0.0);
            let p = [p0[0] + v0[0] * t, p0[1] + v0[1] * t - 0.5 * G_MPS2 * t * t];
            let along = (p[0] - s.a[0]) * s.t[0] + (p[1] - s.a[1]) * s.t[1];
            let tol = 1e-9 * s.len.max(1.0);
            let outside_departure = departure != Some(i) || t > 1e-12;
            if along >= -tol && along <= s.len + tol && outside_departure {
                hit = Some(FlightEnd::Hit { t, seg: i, s: along.clamp(0.0, s.len) });
                tb = tb.min(t);
            }
        }
        if !s.is_vertical() && ta <= tb {
            // h(t) = z(t) − z_seg(x(t)), a concave quadratic in t: its maximum on [ta, tb].
            let k = s.t[1] / s.t[0];
            let h1 = v0[1] - k * v0[0];
            let tm = (h1 / G_MPS2).clamp(ta, tb.min(1e12));
            let h = p0[1] - s.a[1] - k * (p0[0] - s.a[0]) + h1 * tm - 0.5 * G_MPS2 * tm * tm;
            *max_h = max_h.max(h);
        }
        hit
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn slope(v: &[[f64; 2]]) -> Slope2d {
        let p = Profile::new(v, vec![0; v.len() - 1], vec!["m".into()], "t").unwrap();
        Slope2d::new(p, vec![Material2d::floor_all()]).unwrap()
    }

    #[test]
    fn lands_on_flat_ground_where_the_parabola_says() {
        let s = slope(&[[0.0, 0.0], [10.0, 0.0], [20.0, 0.0], [30.0, 0.0]]);
        let (end, h) = s.land([1.0, 5.0], [3.0, 2.0], None);
        let t = (2.0 + (4.0 + 2.0 * G_MPS2 * 5.0f64).sqrt()) / G_MPS2;
        match end {
            FlightEnd::Hit { t: th, seg, s } => {
                assert!((th - t).abs() < 1e-12);
                assert_eq!(seg, 0);
                assert!((s - (1.0 + 3.0 * t)).abs() < 1e-12);
            }
            e => panic!("{e:?}"),
        }
        assert!((h - (5.0 + 4.0 / (2.0 * G_MPS2))).abs() < 1e-12);
    }

    #[test]
    fn hits_a_wall_and_leaves_past_the_end() {
        // Floor, then a wall rising at x = 10.
        let s = slope(&[[0.0, 0.0], [10.0, 0.0], [10.0, 5.0], [20.0, 5.0]]);
        let (end, _) = s.land([8.0, 2.0], [4.0, 0.0], None);
        assert!(matches!(end, FlightEnd::Hit { seg: 1, .. }), "{end:?}");
        let (end, _) = s.land([15.0, 100.0], [10.0, 0.0], None);
        assert!(matches!(end, FlightEnd::Left { t } if (t - 0.5).abs() < 1e-12), "{end:?}");
        // Leaving segment 0 from its middle with an upward velocity lands back on it.
        let (end, _) = s.land([2.0, 0.0], [1.0, 1.0], Some(0));
        assert!(matches!(end, FlightEnd::Hit { seg: 0, t, .. } if (t - 2.0 / G_MPS2).abs() < 1e-12), "{end:?}");
        // A vertical drop lands on the segment below.
        let (end, _) = s.land([4.0, 3.0], [0.0, 0.0], None);
        assert!(matches!(end, FlightEnd::Hit { seg: 0, .. }), "{end:?}");
    }
}
