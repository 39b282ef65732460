//! One rock on a profile: event-driven and analytic, with no time step in flight or while sliding
//! (physics.md §3 and §8, "2DLM update rule").
//!
//! - **Flight**: exact parabola; the landing is the earliest downward crossing of a segment, found from the roots of
//!   a quadratic per segment, visiting only the segments under the path in the order the rock reaches them.
//! - **Impact**: the segment angle is perturbed by the roughness N(0, σ) truncated at ±3σ (halved until the
//!   outgoing velocity leaves the real ground, then dropped); v_n′ = −Rn_eff·v_n and v_t′ = Rt·v_t (or a
//!   rotational form, see [`Rotation`](super::Rotation)). Rn, Rt (and φ) are drawn per impact.
//! - **Switch to sliding** when the normal speed leaving the ground is below `switch_speed_mps` or the next
//!   parabola's arrow height v_n′²/(2g cos θ) is below `arrow_height_ratio`·R.
//! - **Sliding** in closed form with a = g(sin θ − cos θ tan φ) along the segment; at a convex vertex the rock takes
//!   off, at a concave one it keeps only its velocity component along the new segment.
//! - **Stop** when the closed-form stopping point is reached where friction holds the rock, or when it slides slower
//!   than `stop_speed_mps` without accelerating; also on leaving the profile, `max_events` or `max_time_s`.
//!
//! # Units
//! Positions in m, speeds in m/s, times in s, masses in kg, energies in J.

use super::options::{FrictionSource, Options2d, Rotation};
use super::path::{FlightPiece, ImpactEvent, PathObserver, SlidePiece};
use super::slope::{FlightEnd, Slope2d};
use crate::random::{Rng, TruncNormal};
use serde::Serialize;

/// Gravitational acceleration, m/s².
pub const G_MPS2: f64 = 9.81;

/// Pfeiffer & Bowen's reference normal speed for scaling Rn, m/s (30 ft/s).
pub const PFEIFFER_BOWEN_MPS: f64 = 9.144;

/// Why a rock's simulation ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    /// Came to rest on the profile.
    Stopped,
    /// Passed either end of the profile.
    LeftProfile,
    /// Reached `Options2d::max_events`.
    MaxEvents,
    /// Reached `Options2d::max_time_s`.
    MaxTime,
}

impl StopReason {
    /// All reasons, in the order they are reported.
    pub const ALL: [StopReason; 4] =
        [StopReason::Stopped, StopReason::LeftProfile, StopReason::MaxEvents, StopReason::MaxTime];

    /// The name used in outputs: `stopped`, `left_profile`, `max_events`, `max_time`.
    pub fn as_str(&self) -> &'static str {
        match self {
            StopReason::Stopped => "stopped",
            StopReason::LeftProfile => "left_profile",
            StopReason::MaxEvents => "max_events",
            StopReason::MaxTime => "max_time",
        }
    }
}

/// The initial state of one rock.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RockStart2d {
    /// Position x, m.
    pub x_m: f64,
    /// Position z, m (at or above the profile; a rock below it is put on it).
    pub z_m: f64,
    /// Horizontal velocity, m/s.
    pub vx_mps: f64,
    /// Vertical velocity (up positive), m/s.
    pub vz_mps: f64,
    /// Spin, rad/s, clockwise positive in the x–z view (forward rolling towards +x); used by the rotational rules.
    pub spin_radps: f64,
    /// Mass, kg: scales energies and sizes the rock (radius of a sphere at the rock density).
    pub mass_kg: f64,
}

/// What one rock did.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RockResult2d {
    /// Rock index in the ensemble.
    pub rock_id: u64,
    /// Release position x, m.
    pub release_x_m: f64,
    /// End position x, m.
    pub end_x_m: f64,
    /// End position z, m.
    pub end_z_m: f64,
    /// Why the simulation ended.
    pub stop_reason: StopReason,
    /// Horizontal distance from release to the end position, m.
    pub runout_m: f64,
    /// Travel time, s.
    pub travel_time_s: f64,
    /// Largest translational kinetic energy ½mv², J.
    pub max_kinetic_j: f64,
    /// Largest speed, m/s.
    pub max_speed_mps: f64,
    /// Largest height of the point mass above the profile, measured vertically (not normal to the slope), m. The
    /// release height counts.
    pub max_bounce_m: f64,
    /// Number of impacts (touch-downs that applied restitution).
    pub impacts: u32,
    /// Number of events (flights, impacts, slide pieces).
    pub events: u32,
}

/// Simulates one rock on `slope`, drawing its random numbers from `rng` and handing the path to `observer`.
///
/// A start outside the profile's x range ends at once with [`StopReason::LeftProfile`]. `rock_id` of the result is
/// 0: set it yourself.
///
/// # Examples
/// ```
/// use talus::lumped2d::{simulate_rock, Material2d, Options2d, Profile, RockStart2d, Slope2d, StopReason};
/// let profile = Profile::new(&[[0.0, 10.0], [10.0, 0.0], [40.0, 0.0]], vec![0, 1],
///                            vec!["face".into(), "floor".into()], "example").unwrap();
/// let slope = Slope2d::new(profile, vec![Material2d::face_all(), Material2d::floor_all()]).unwrap();
/// let start = RockStart2d { x_m: 0.5, z_m: 11.0, vx_mps: 1.0, vz_mps: 0.0, spin_radps: 0.0, mass_kg: 100.0 };
/// let mut rng = talus::random::stream(42, 0);
/// let r = simulate_rock(&slope, &start, &Options2d::default(), &mut rng, &mut ());
/// assert_eq!(r.stop_reason, StopReason::Stopped);
/// assert!(r.end_x_m > 10.0);
/// ```
pub fn simulate_rock<O: PathObserver + ?Sized>(
    slope: &Slope2d,
    start: &RockStart2d,
    options: &Options2d,
    rng: &mut Rng,
    observer: &mut O,
) -> RockResult2d {
    let radius = options.radius_m(start.mass_kg);
    let mut e = Engine {
        slope,
        opt: options,
        rng,
        obs: observer,
        radius,
        rn_mass_factor: options.rn_mass_factor(start.mass_kg),
        spin: start.spin_radps,
        t: 0.0,
        events: 0,
        impacts: 0,
        max_speed: start.vx_mps.hypot(start.vz_mps),
        max_bounce: 0.0,
    };
    let (end, reason) = e.run(start);
    let end_x = end[0];
    RockResult2d {
        rock_id: 0,
        release_x_m: start.x_m,
        end_x_m: end_x,
        end_z_m: end[1],
        stop_reason: reason,
        runout_m: (end_x - start.x_m).abs(),
        travel_time_s: e.t,
        max_kinetic_j: 0.5 * start.mass_kg * e.max_speed * e.max_speed,
        max_speed_mps: e.max_speed,
        max_bounce_m: e.max_bounce,
        impacts: e.impacts,
        events: e.events,
    }
}

/// Rn scaled by the normal impact speed (Pfeiffer & Bowen 1989): Rn/(1 + (|v_n|/K)²), their K = 9.144 m/s.
pub fn pfeiffer_bowen_rn(rn: f64, normal_speed_mps: f64, k_mps: f64) -> f64 {
    let r = normal_speed_mps / k_mps;
    rn / (1.0 + r * r)
}

#[derive(Debug, Clone, Copy)]
enum State {
    Flight {
        p: [f64; 2],
        v: [f64; 2],
        departure: Option<usize>,
    },
    /// On segment `seg`, `s` m from its start, with signed speed `u` along its direction.
    Slide {
        seg: usize,
        s: f64,
        u: f64,
        tan_phi: f64,
    },
    /// At rest on vertex `k`.
    AtVertex {
        k: usize,
    },
    Done {
        p: [f64; 2],
        reason: StopReason,
    },
}

struct Engine<'a, O: ?Sized> {
    slope: &'a Slope2d,
    opt: &'a Options2d,
    rng: &'a mut Rng,
    obs: &'a mut O,
    radius: f64,
    /// Factor on Rn from the rock's mass ([`Options2d::rn_mass_factor`]).
    rn_mass_factor: f64,
    spin: f64,
    t: f64,
    events: u32,
    impacts: u32,
    max_speed: f64,
    max_bounce: f64,
}

fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

impl<O: PathObserver + ?Sized> Engine<'_, O> {
    fn run(&mut self, start: &RockStart2d) -> ([f64; 2], StopReason) {
        let mut state = self.initial(start);
        loop {
            if let State::Done { p, reason } = state {
                return (p, reason);
            }
            if self.events >= self.opt.max_events {
                return (self.position(&state), StopReason::MaxEvents);
            }
            self.events += 1;
            state = match state {
                State::Flight { p, v, departure } => self.fly(p, v, departure),
                State::Slide { seg, s, u, tan_phi } => self.slide(seg, s, u, tan_phi),
                State::AtVertex { k } => self.rest_at_vertex(k),
                State::Done { .. } => unreachable!("handled above"),
            };
        }
    }

    fn position(&self, state: &State) -> [f64; 2] {
        match *state {
            State::Flight { p, .. } | State::Done { p, .. } => p,
            State::Slide { seg, s, .. } => self.point_on(seg, s),
            State::AtVertex { k } => self.slope.profile().vertex(k),
        }
    }

    fn point_on(&self, seg: usize, s: f64) -> [f64; 2] {
        let g = &self.slope.segs[seg];
        [g.a[0] + g.t[0] * s, g.a[1] + g.t[1] * s]
    }

    fn initial(&mut self, st: &RockStart2d) -> State {
        let p = [st.x_m, st.z_m];
        let v = [st.vx_mps, st.vz_mps];
        let (x0, x1) = self.slope.profile().x_range_m();
        if !(st.x_m >= x0 && st.x_m <= x1 && st.z_m.is_finite() && v[0].is_finite() && v[1].is_finite()) {
            return State::Done { p, reason: StopReason::LeftProfile };
        }
        let zs = self.slope.profile().z_at(st.x_m).unwrap_or(st.z_m);
        if st.z_m > zs + 1e-9 {
            return State::Flight { p, v, departure: None };
        }
        // On the ground: fly off if the velocity leaves it clearly, otherwise slide.
        let seg = self.slope.top_segment_at(st.x_m).unwrap_or(0);
        let g = self.slope.segs[seg];
        let s = ((st.x_m - g.a[0]) * g.t[0] + (zs - g.a[1]) * g.t[1]).clamp(0.0, g.len);
        if dot(v, g.n) > self.opt.switch_speed_mps {
            State::Flight { p: self.point_on(seg, s), v, departure: Some(seg) }
        } else {
            self.start_slide(seg, s, dot(v, g.t))
        }
    }

    fn draw_tan_phi(&mut self, seg: usize) -> f64 {
        let m = self.slope.material_of(seg);
        match self.opt.friction_angle {
            FrictionSource::Material => m.draw_tan_friction(self.rng),
            FrictionSource::FromRt => super::material::tan_friction_from_rt(m.rt.sample(self.rng)),
            FrictionSource::Zero => 0.0,
        }
    }

    fn start_slide(&mut self, seg: usize, s: f64, u: f64) -> State {
        let tan_phi = self.draw_tan_phi(seg);
        State::Slide { seg, s, u, tan_phi }
    }

    fn fly(&mut self, p: [f64; 2], v: [f64; 2], departure: Option<usize>) -> State {
        let (end, h) = self.slope.land(p, v, departure);
        self.max_bounce = self.max_bounce.max(h);
        let mut piece = FlightPiece {
            t0_s: self.t,
            duration_s: match end {
                FlightEnd::Hit { t, .. } | FlightEnd::Left { t } => t,
            },
            x0_m: p[0],
            z0_m: p[1],
            vx_mps: v[0],
            vz_mps: v[1],
        };
        if self.t + piece.duration_s > self.opt.max_time_s {
            piece.duration_s = (self.opt.max_time_s - self.t).max(0.0);
            return self.finish_flight(&piece, StopReason::MaxTime);
        }
        match end {
            FlightEnd::Left { .. } => self.finish_flight(&piece, StopReason::LeftProfile),
            FlightEnd::Hit { seg, s, .. } => {
                self.obs.flight(&piece);
                self.t += piece.duration_s;
                let vin = piece.velocity_at(piece.duration_s);
                self.max_speed = self.max_speed.max(vin[0].hypot(vin[1]));
                self.impact(seg, s, vin)
            }
        }
    }

    fn finish_flight(&mut self, piece: &FlightPiece, reason: StopReason) -> State {
        self.obs.flight(piece);
        self.t += piece.duration_s;
        let v = piece.velocity_at(piece.duration_s);
        self.max_speed = self.max_speed.max(v[0].hypot(v[1]));
        let mut p = piece.end_position();
        if reason == StopReason::LeftProfile {
            let (x0, x1) = self.slope.profile().x_range_m();
            p[0] = if piece.vx_mps > 0.0 { x1 } else { x0 };
        }
        State::Done { p, reason }
    }

    /// The tangential speed and spin after an impact, for normal and tangential incoming speeds `vn` (< 0) and `vt`.
    fn tangential_rule(&self, vt: f64, vn: f64, rn: f64, rt: f64) -> (f64, f64) {
        let r = self.radius;
        let factor = match self.opt.rotation {
            Rotation::Off => return (rt * vt, self.spin),
            Rotation::Rocfall => rt,
            Rotation::Crsp => {
                let slip = (vt - self.spin * r) / 6.096;
                let ff = rt + (1.0 - rt) / (slip * slip + 1.2);
                let ratio = if rn > 0.0 { vn / (76.2 * rn) } else { f64::INFINITY };
                let sf = rt / (ratio * ratio + 1.0);
                ff * sf
            }
        };
        // Solid sphere, I = 0.4 m R²: v_t′² = R²(Iω² + m v_t²)·F/(I + mR²) = (0.4 R²ω² + v_t²)·F/1.4.
        let mag = ((0.4 * r * r * self.spin * self.spin + vt * vt) * factor / 1.4).max(0.0).sqrt();
        let sign = if vt != 0.0 { vt.signum() } else { self.spin.signum() };
        let vt_out = sign * mag;
        (vt_out, vt_out / r)
    }

    fn impact(&mut self, seg: usize, s: f64, v: [f64; 2]) -> State {
        let g = self.slope.segs[seg];
        let n_act = dot(v, g.n);
        if n_act >= 0.0 || -n_act < self.opt.soft_landing_mps {
            // Touch-down without restitution: keep the tangential component.
            return self.start_slide(seg, s, dot(v, g.t));
        }
        let mat = *self.slope.material_of(seg);
        let sd = mat.roughness_sd_deg;
        let delta =
            if sd > 0.0 { TruncNormal { mean: 0.0, sd, min: -3.0 * sd, max: 3.0 * sd }.sample(self.rng) } else { 0.0 };
        let rn = (mat.rn.sample(self.rng) * self.rn_mass_factor).min(1.0);
        let rt = mat.rt.sample(self.rng);
        const HALVINGS: i32 = 8;
        let mut out = None;
        for k in 0..=HALVINGS {
            let d = if k == HALVINGS { 0.0 } else { delta / f64::powi(2.0, k) };
            let (sn, c) = d.to_radians().sin_cos();
            let t = [g.t[0] * c - g.t[1] * sn, g.t[0] * sn + g.t[1] * c];
            let n = [-t[1], t[0]];
            let (vn, vt) = (dot(v, n), dot(v, t));
            if vn >= 0.0 && k < HALVINGS {
                continue; // not approaching the tilted surface
            }
            let rn_eff = if self.opt.scale_rn_by_velocity {
                pfeiffer_bowen_rn(rn, vn.abs(), self.opt.rn_velocity_scale_mps)
            } else {
                rn
            };
            let (vt_out, spin_out) = self.tangential_rule(vt, vn, rn, rt);
            let vn_out = -rn_eff * vn;
            let vo = [vt_out * t[0] + vn_out * n[0], vt_out * t[1] + vn_out * n[1]];
            if dot(vo, g.n) > 0.0 || k == HALVINGS {
                out = Some((vo, spin_out, rn_eff, d));
                break;
            }
        }
        let (vo, spin_out, rn_eff, d) = out.expect("the last try is always taken");
        self.impacts += 1;
        let vn_out = dot(vo, g.n);
        let arrow = if g.n[1] > 1e-12 { vn_out * vn_out / (2.0 * G_MPS2 * g.n[1]) } else { f64::INFINITY };
        let slides = vn_out < self.opt.switch_speed_mps || arrow < self.opt.arrow_height_ratio * self.radius;
        let p = self.point_on(seg, s);
        self.obs.impact(&ImpactEvent {
            t_s: self.t,
            x_m: p[0],
            z_m: p[1],
            segment: seg,
            velocity_in_mps: v,
            velocity_out_mps: vo,
            spin_radps: [self.spin, spin_out],
            rn: rn_eff,
            rt,
            angle_offset_deg: d,
            slides_after: slides,
        });
        self.spin = spin_out;
        if slides {
            self.start_slide(seg, s, dot(vo, g.t))
        } else {
            State::Flight { p, v: vo, departure: Some(seg) }
        }
    }

    fn slide(&mut self, seg: usize, s: f64, u: f64, tan_phi: f64) -> State {
        let g = self.slope.segs[seg];
        let a_g = -G_MPS2 * g.t[1]; // gravity along the segment direction
        let fric = G_MPS2 * g.t[0] * tan_phi; // friction deceleration magnitude
        let holds = a_g.abs() <= fric;
        let tol = 1e-12 * g.len.max(1.0);
        let dir = if u != 0.0 {
            u.signum()
        } else if holds {
            // At rest where friction holds: stopped, unless on a vertex where the next segment may pull.
            if s <= tol {
                return State::AtVertex { k: seg };
            }
            if s >= g.len - tol {
                return State::AtVertex { k: seg + 1 };
            }
            return State::Done { p: self.point_on(seg, s), reason: StopReason::Stopped };
        } else {
            a_g.signum()
        };
        if u == 0.0 && ((dir < 0.0 && s <= tol) || (dir > 0.0 && s >= g.len - tol)) {
            return State::AtVertex { k: if dir < 0.0 { seg } else { seg + 1 } };
        }
        let alpha = a_g * dir - fric; // acceleration along the motion
        let w = u.abs();
        if w < self.opt.stop_speed_mps && alpha <= 0.0 && holds {
            return State::Done { p: self.point_on(seg, s), reason: StopReason::Stopped };
        }
        let room = if dir > 0.0 { g.len - s } else { s }.max(0.0);
        let (dt, dist, w_end, at_vertex) = if alpha < 0.0 && w * w <= -2.0 * alpha * room {
            (w / -alpha, w * w / (-2.0 * alpha), 0.0, false)
        } else {
            let w_end = (w * w + 2.0 * alpha * room).max(0.0).sqrt();
            let dt = if w + w_end > 0.0 { 2.0 * room / (w + w_end) } else { 0.0 };
            (dt, room, w_end, true)
        };
        let p = self.point_on(seg, s);
        let mut piece = SlidePiece {
            t0_s: self.t,
            duration_s: dt,
            segment: seg,
            x0_m: p[0],
            z0_m: p[1],
            direction: [g.t[0] * dir, g.t[1] * dir],
            speed0_mps: w,
            accel_mps2: alpha,
        };
        if self.t + dt > self.opt.max_time_s {
            piece.duration_s = (self.opt.max_time_s - self.t).max(0.0);
            self.obs.slide(&piece);
            self.t += piece.duration_s;
            self.max_speed = self.max_speed.max(piece.speed_at(piece.duration_s));
            let s_end = (s + dir * piece.length_m()).clamp(0.0, g.len);
            return State::Done { p: self.point_on(seg, s_end), reason: StopReason::MaxTime };
        }
        self.obs.slide(&piece);
        self.t += dt;
        self.max_speed = self.max_speed.max(w_end);
        if !at_vertex {
            let s_end = (s + dir * dist).clamp(0.0, g.len);
            return State::Slide { seg, s: s_end, u: 0.0, tan_phi };
        }
        let n_seg = self.slope.segs.len();
        if dir > 0.0 {
            if seg + 1 == n_seg {
                return State::Done { p: g.b, reason: StopReason::LeftProfile };
            }
            if self.slope.is_convex(seg) {
                return State::Flight { p: g.b, v: [w_end * g.t[0], w_end * g.t[1]], departure: Some(seg) };
            }
            let c = dot(g.t, self.slope.segs[seg + 1].t);
            if w_end * c <= 0.0 {
                return State::AtVertex { k: seg + 1 };
            }
            self.start_slide(seg + 1, 0.0, w_end * c)
        } else {
            if seg == 0 {
                return State::Done { p: g.a, reason: StopReason::LeftProfile };
            }
            if self.slope.is_convex(seg - 1) {
                return State::Flight { p: g.a, v: [-w_end * g.t[0], -w_end * g.t[1]], departure: Some(seg) };
            }
            let prev = self.slope.segs[seg - 1];
            let c = dot(g.t, prev.t);
            if w_end * c <= 0.0 {
                return State::AtVertex { k: seg };
            }
            self.start_slide(seg - 1, prev.len, -w_end * c)
        }
    }

    /// At rest on vertex `k`: slide away down whichever neighbouring segment pulls harder, or stop.
    fn rest_at_vertex(&mut self, k: usize) -> State {
        let n_seg = self.slope.segs.len();
        let mut best: Option<(f64, State)> = None;
        if k < n_seg {
            let tan_phi = self.draw_tan_phi(k);
            let g = self.slope.segs[k];
            let acc = -G_MPS2 * g.t[1] - G_MPS2 * g.t[0] * tan_phi;
            if acc > 0.0 {
                best = Some((acc, State::Slide { seg: k, s: 0.0, u: 0.0, tan_phi }));
            }
        }
        if k > 0 {
            let tan_phi = self.draw_tan_phi(k - 1);
            let g = self.slope.segs[k - 1];
            let acc = G_MPS2 * g.t[1] - G_MPS2 * g.t[0] * tan_phi;
            if acc > 0.0 && best.is_none_or(|(b, _)| acc > b) {
                best = Some((acc, State::Slide { seg: k - 1, s: g.len, u: 0.0, tan_phi }));
            }
        }
        match best {
            Some((_, state)) => state,
            None => State::Done { p: self.slope.profile().vertex(k), reason: StopReason::Stopped },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lumped2d::material::{FrictionAngle, Material2d};
    use crate::lumped2d::profile::Profile;
    use crate::random::{stream, TruncNormal};

    fn slope(v: &[[f64; 2]], m: Material2d) -> Slope2d {
        let p = Profile::new(v, vec![0; v.len() - 1], vec!["m".into()], "t").unwrap();
        Slope2d::new(p, vec![m]).unwrap()
    }

    fn fixed(rn: f64, rt: f64, phi_deg: f64) -> Material2d {
        Material2d {
            rn: TruncNormal::fixed(rn),
            rt: TruncNormal::fixed(rt),
            friction: FrictionAngle::Given(TruncNormal::fixed(phi_deg)),
            roughness_sd_deg: 0.0,
        }
    }

    #[test]
    fn pfeiffer_bowen_halves_at_reference_speed() {
        assert!((pfeiffer_bowen_rn(0.5, 9.144, PFEIFFER_BOWEN_MPS) - 0.25).abs() < 1e-15);
        assert!((pfeiffer_bowen_rn(0.5, 3.0, 3.0) - 0.25).abs() < 1e-15);
        assert_eq!(pfeiffer_bowen_rn(0.5, 0.0, PFEIFFER_BOWEN_MPS), 0.5);
    }

    #[test]
    fn rest_in_a_v_stops_at_the_bottom() {
        let s = slope(&[[0.0, 10.0], [10.0, 0.0], [20.0, 10.0]], fixed(0.0, 0.9, 30.0));
        let start = RockStart2d { x_m: 1.0, z_m: 9.0, vx_mps: 0.0, vz_mps: 0.0, spin_radps: 0.0, mass_kg: 1.0 };
        let r = simulate_rock(&s, &start, &Options2d::default(), &mut stream(1, 0), &mut ());
        assert_eq!(r.stop_reason, StopReason::Stopped);
        assert!((r.end_x_m - 10.0).abs() < 1e-9 && r.end_z_m.abs() < 1e-9, "{r:?}");
    }

    #[test]
    fn limits_end_the_run_with_their_reason() {
        let s = slope(&[[0.0, 0.0], [1000.0, 0.0]], fixed(0.0, 1.0, 0.0));
        let start = RockStart2d { x_m: 5.0, z_m: 0.0, vx_mps: 1.0, vz_mps: 0.0, spin_radps: 0.0, mass_kg: 1.0 };
        let opt = Options2d { max_time_s: 30.0, ..Default::default() };
        let r = simulate_rock(&s, &start, &opt, &mut stream(1, 0), &mut ());
        assert_eq!(r.stop_reason, StopReason::MaxTime);
        assert!((r.travel_time_s - 30.0).abs() < 1e-9 && (r.end_x_m - 35.0).abs() < 1e-9, "{r:?}");
        // A frictionless V: the rock swings with ever shorter passes until the event cap.
        let s = slope(&[[0.0, 2.0], [10.0, 0.0], [20.0, 2.0]], fixed(0.0, 1.0, 0.0));
        let start = RockStart2d { x_m: 5.0, z_m: 1.0, vx_mps: 0.0, vz_mps: 0.0, spin_radps: 0.0, mass_kg: 1.0 };
        let opt = Options2d { max_events: 7, ..Default::default() };
        let r = simulate_rock(&s, &start, &opt, &mut stream(1, 0), &mut ());
        assert_eq!(r.stop_reason, StopReason::MaxEvents);
        assert_eq!(r.events, 7);
    }

    #[test]
    fn rolls_off_the_end_when_frictionless() {
        let s = slope(&[[0.0, 1.0], [10.0, 0.0], [30.0, 0.0]], fixed(0.3, 0.8, 0.0));
        let start = RockStart2d { x_m: 0.0, z_m: 1.0, vx_mps: 0.0, vz_mps: 0.0, spin_radps: 0.0, mass_kg: 1.0 };
        let r = simulate_rock(&s, &start, &Options2d::default(), &mut stream(1, 0), &mut ());
        assert_eq!(r.stop_reason, StopReason::LeftProfile);
        assert_eq!(r.end_x_m, 30.0);
    }

    #[test]
    fn rotational_rules_do_not_add_energy() {
        let s = slope(&[[0.0, 0.0], [100.0, 0.0]], fixed(0.4, 0.8, 30.0));
        for rotation in [Rotation::Rocfall, Rotation::Crsp] {
            let opt = Options2d { rotation, ..Default::default() };
            let e = Engine {
                slope: &s,
                opt: &opt,
                rng: &mut stream(1, 0),
                obs: &mut (),
                radius: 0.3,
                rn_mass_factor: 1.0,
                spin: 5.0,
                t: 0.0,
                events: 0,
                impacts: 0,
                max_speed: 0.0,
                max_bounce: 0.0,
            };
            let (vt, vn) = (6.0, -4.0);
            let (vt2, w2) = e.tangential_rule(vt, vn, 0.4, 0.8);
            let energy = |vt: f64, w: f64| vt * vt + 0.4 * 0.09 * w * w; // per unit mass, ×2, normal part apart
            assert!(energy(vt2, w2) <= energy(vt, e.spin) + 1e-12, "{rotation:?}");
            assert!((w2 * 0.3 - vt2).abs() < 1e-12);
        }
    }
}
