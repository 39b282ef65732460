//! One rock from release to rest: the 3DRB time loop.
//!
//! Near the ground, each step of `dt_s` is a Moreau midpoint step (Leine et al. 2014, physics.md §1.2 and §6):
//! move half a step, find the contacts there, solve the impulses together ([`super::contact`]), move the second half
//! with the new velocities. A step in which a hull vertex newly meets the ground faster than the bounce threshold
//! is taken as `impact_substeps` Moreau steps (default 8; ours: at 2 ms a rock hopping over uneven ground otherwise
//! runs too far; README, "Performance and convergence"). Rotation between contacts follows the
//! implicit midpoint rule ([`super::body`]).
//! Clear of the ground, the rock moves in long exact ballistic steps: a step is taken only if the bounding sphere,
//! swept along the parabola, stays above an upper bound of the ground under it (conservative advancement,
//! physics.md §6), so nothing is tunnelled through however fast the rock goes.
//!
//! The loop ends with an explicit reason: `stopped` (speed and spin below the rest thresholds for the rest
//! duration), `left_terrain` (no surface under the centre of mass), `max_time`, or `barrier` (caught by a
//! barrier, [`super::barrier`]).
//!
//! Optional effects ([`super::params::Effects`]) modify the restitution of each contact, tilt impact normals, and
//! brake rocks in contact; all are off by default.

use super::barrier::BarrierHit;
use super::body::{free_rotation, free_spin, rotate, RigidState};
use super::contact::{solve, Contact, Scratch, SolverSettings, Velocities};
use super::params::{CrDraw, SimParams};
use crate::random::{uniform, Rng};
use crate::rock::RockBody;
use crate::terrain::Terrain;
use nalgebra::{UnitQuaternion, Vector3};

/// Gravity, m/s² (standard gravity, pointing down −z).
pub const GRAVITY_MPS2: f64 = 9.80665;

/// Why a rock's run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    /// At rest on the ground.
    Stopped,
    /// No surface under the rock (outside the terrain or over a nodata hole).
    LeftTerrain,
    /// The simulated time limit was reached.
    MaxTime,
    /// Caught by a barrier.
    Barrier,
}

impl StopReason {
    /// The name written to outputs.
    pub fn as_str(self) -> &'static str {
        match self {
            StopReason::Stopped => "stopped",
            StopReason::LeftTerrain => "left_terrain",
            StopReason::MaxTime => "max_time",
            StopReason::Barrier => "barrier",
        }
    }

    /// All reasons, in output order.
    pub const ALL: [StopReason; 4] =
        [StopReason::Stopped, StopReason::LeftTerrain, StopReason::MaxTime, StopReason::Barrier];
}

/// A point of the path, emitted about every `sample_spacing_m` of horizontal travel (and at least every 0.1 s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Time since release, s.
    pub t_s: f64,
    /// Centre of mass, m (local frame).
    pub position_m: Vector3<f64>,
    /// Velocity, m/s.
    pub velocity_mps: Vector3<f64>,
    /// Angular speed, rad/s.
    pub spin_radps: f64,
    /// Translational kinetic energy, J.
    pub translational_j: f64,
    /// Total (translational + rotational) kinetic energy, J.
    pub kinetic_j: f64,
    /// Height of the rock's lowest point above the ground under its centre of mass, measured vertically, m (≥ 0).
    pub clearance_m: f64,
    /// True if the rock touched the ground in the step that produced the sample.
    pub in_contact: bool,
}

/// An impact: a step in which a hull vertex newly touched the ground faster than the bounce threshold.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Impact {
    /// Time, s.
    pub t_s: f64,
    /// Contact point, m (local frame).
    pub point_m: Vector3<f64>,
    /// Ground normal.
    pub normal: Vector3<f64>,
    /// Ground triangle.
    pub triangle: u32,
    /// Normal approach speed of the contact point, m/s.
    pub approach_speed_mps: f64,
    /// Speed of the centre of mass before the impact, m/s.
    pub speed_mps: f64,
    /// Angle between the incoming centre-of-mass velocity and the ground plane, degrees.
    pub impact_angle_deg: f64,
    /// Restitution coefficient used.
    pub cr: f64,
    /// Kinetic energy before the impulses (after the step's gravity), J.
    pub kinetic_before_j: f64,
    /// Kinetic energy after the impulses, J.
    pub kinetic_after_j: f64,
    /// True if the energy guard had to re-solve with Cr = 0.
    pub energy_guard: bool,
}

/// Receives a rock's path as it is computed, so that rasters, collectors and diagnostics never need the whole
/// trajectory in memory.
pub trait Observer {
    /// A path sample.
    fn sample(&mut self, _sample: &Sample) {}
    /// True to be sent a sample after every step (contact steps are `dt_s` apart; a flight step sends one every
    /// 0.1 s or `sample_spacing_m` anyway) instead of about every `sample_spacing_m`: for recording a path as a
    /// tracking system would. Observing changes nothing in the motion.
    fn every_step(&self) -> bool {
        false
    }
    /// An impact.
    fn impact(&mut self, _impact: &Impact) {}
    /// A barrier met.
    fn barrier(&mut self, _hit: &BarrierHit) {}
}

impl Observer for () {}

impl<O: Observer + ?Sized> Observer for &mut O {
    fn sample(&mut self, s: &Sample) {
        (**self).sample(s);
    }
    fn every_step(&self) -> bool {
        (**self).every_step()
    }
    fn impact(&mut self, i: &Impact) {
        (**self).impact(i);
    }
    fn barrier(&mut self, h: &BarrierHit) {
        (**self).barrier(h);
    }
}

impl<A: Observer, B: Observer> Observer for (A, B) {
    fn sample(&mut self, s: &Sample) {
        self.0.sample(s);
        self.1.sample(s);
    }
    fn every_step(&self) -> bool {
        self.0.every_step() || self.1.every_step()
    }
    fn impact(&mut self, i: &Impact) {
        self.0.impact(i);
        self.1.impact(i);
    }
    fn barrier(&mut self, h: &BarrierHit) {
        self.0.barrier(h);
        self.1.barrier(h);
    }
}

impl<O: Observer> Observer for Option<O> {
    fn sample(&mut self, s: &Sample) {
        if let Some(o) = self {
            o.sample(s)
        }
    }
    fn every_step(&self) -> bool {
        self.as_ref().is_some_and(|o| o.every_step())
    }
    fn impact(&mut self, i: &Impact) {
        if let Some(o) = self {
            o.impact(i)
        }
    }
    fn barrier(&mut self, h: &BarrierHit) {
        if let Some(o) = self {
            o.barrier(h)
        }
    }
}

/// The result of one rock's run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Outcome {
    /// State at the end.
    pub final_state: RigidState,
    /// Why it ended.
    pub stop_reason: StopReason,
    /// Stopped by [`SimParams::stop_in_place_s`]: in place that long, however it spun, rather than by the rest test.
    pub stopped_in_place: bool,
    /// Simulated time, s.
    pub travel_time_s: f64,
    /// Largest total kinetic energy, J.
    pub max_kinetic_j: f64,
    /// Largest clearance of the lowest point above the ground, m.
    pub max_bounce_m: f64,
    /// Number of impacts.
    pub impacts: u32,
    /// Steps taken near the ground (a cost measure).
    pub contact_steps: u64,
    /// Times the energy guard fired.
    pub energy_guards: u32,
    /// Contact-solver sweeps over all steps (a cost measure).
    pub solver_sweeps: u64,
}

/// Runs one rock from `start` until it stops. `rng` supplies the restitution draws.
pub fn simulate(
    terrain: &Terrain,
    rock: &RockBody,
    start: RigidState,
    params: &SimParams,
    rng: &mut Rng,
    observer: &mut impl Observer,
) -> Outcome {
    Run::new(terrain, rock, start, params, rng).go(observer)
}

struct Run<'a> {
    terrain: &'a Terrain,
    rock: &'a RockBody,
    params: &'a SimParams,
    rng: &'a mut Rng,
    s: RigidState,
    t: f64,
    cr: Vec<f64>,
    /// tan of the static and dynamic friction angles of each material for this rock (the terrain's, or drawn
    /// where a material has a dynamic friction spread).
    friction: Vec<(f64, f64)>,
    /// Steps a touch counts as contact for (`contact_duration_s` over the step, at least 1).
    touch_steps: u32,
    /// Per hull vertex: steps it still counts as touching the ground (0: a touch now is a new impact).
    touch_left: Vec<u32>,
    /// Per hull vertex: the restitution drawn at its last touch (kept while it counts as touching).
    vertex_cr: Vec<f64>,
    /// The terrain edges' contacts that count as touching ([`SimParams::terrain_edge_contacts`]), as the vertex
    /// contacts of `touch_left` and `vertex_cr` do.
    edge_touch: Vec<EdgeTouch>,
    /// How long what acts in contact still acts after the last touch, s.
    brake_left_s: f64,
    /// The averaged normal of the last touch, which rolling resistance acts against (set only when it is on).
    roll_normal: Vector3<f64>,
    /// The soft-ground drag rate of the last touch, 1/s.
    touch_drag_per_s: f64,
    barrier_met: Vec<bool>,
    /// Soft-ground drag rate of each material, 1/s: its own, or the `soft_drag_per_s` effect's where that acts.
    drag_per_s: Vec<f64>,
    /// Drag rate of the `vegetation_drag_kg_s` effect on any ground, 1/s.
    vegetation_drag_per_s: f64,
    /// Rate of the quadratic `scar_drag_coefficient` effect on any ground, 1/m.
    scar_drag_per_m: f64,
    /// The slippage of the `slip_friction_max_deg` effect, m: the distance travelled in contact, decaying in flight.
    slippage_m: f64,
    contacts: Vec<Contact>,
    previous: Vec<Contact>,
    scratch: Scratch,
    /// The terrain edges near where the rock was when they were listed ([`SimParams::terrain_edge_contacts`],
    /// [`Run::list_edges`]), listed again once the rock has moved a radius from there.
    edges: Vec<ListedEdge>,
    /// The edges of the triangles binned near the rock, before [`Run::list_edges`] keeps those in `edges`.
    binned_edges: Vec<(u32, u32, u32)>,
    /// Where the rock was when `edges` were listed.
    edges_listed_at: Option<Vector3<f64>>,
    last_sample: Option<(Vector3<f64>, f64)>,
    out: Outcome,
    settings: SolverSettings,
}

/// What a barrier did to a rock in one move.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum BarrierEffect {
    None,
    Caught,
    Slowed,
}

const GRAVITY: Vector3<f64> = Vector3::new(0.0, 0.0, -GRAVITY_MPS2);
/// Extra clearance required of a ballistic step, m (ours).
const FLIGHT_MARGIN_M: f64 = 0.05;
/// Most Moreau steps a contact step is cut into by `max_contact_travel_m` (ours: at the shortest travel, 1 cm, and
/// a 10 ms step, points moving up to 1 km/s; a bound on the work of one step whatever the input).
const MAX_TRAVEL_SUBSTEPS: usize = 1000;

/// The first time in (`on_s`, `off_s`] at which `off` holds, to 1 µs, by bisection, given that it does not hold at
/// `on_s` and holds at `off_s` (ours: a flight piece is at most `sample_spacing_m` long, so it crosses an edge once).
fn first_time_off(mut on_s: f64, mut off_s: f64, off: impl Fn(f64) -> bool) -> f64 {
    while off_s - on_s > 1e-6 {
        let mid = 0.5 * (on_s + off_s);
        if off(mid) {
            off_s = mid;
        } else {
            on_s = mid;
        }
    }
    off_s
}

impl<'a> Run<'a> {
    fn new(
        terrain: &'a Terrain,
        rock: &'a RockBody,
        start: RigidState,
        params: &'a SimParams,
        rng: &'a mut Rng,
    ) -> Self {
        let cr = terrain.materials.iter().map(|m| m.cr.sample(rng)).collect();
        let friction =
            terrain.materials.iter().zip(&terrain.friction).map(|(m, &f)| m.friction_for_rock(f, rng)).collect();
        let settings = SolverSettings {
            bounce_threshold_mps: params.bounce_threshold_mps,
            max_iterations: params.solver_iterations,
            tolerance_mps: params.solver_tolerance_mps,
        };
        let out = Outcome {
            final_state: start,
            stop_reason: StopReason::MaxTime,
            travel_time_s: 0.0,
            max_kinetic_j: 0.0,
            max_bounce_m: 0.0,
            impacts: 0,
            contact_steps: 0,
            energy_guards: 0,
            stopped_in_place: false,
            solver_sweeps: 0,
        };
        Run {
            terrain,
            rock,
            params,
            rng,
            s: start,
            t: 0.0,
            cr,
            friction,
            touch_steps: ((params.contact_duration_s / params.dt_s).round() as u32).max(1),
            touch_left: vec![0; rock.vertices_m.len()],
            vertex_cr: vec![0.0; rock.vertices_m.len()],
            edge_touch: Vec::new(),
            brake_left_s: 0.0,
            roll_normal: Vector3::z(),
            touch_drag_per_s: 0.0,
            barrier_met: vec![false; terrain.barriers.len()],
            drag_per_s: terrain
                .materials
                .iter()
                .map(|m| {
                    let fx = &params.effects;
                    let listed = fx.soft_materials.is_empty() || fx.soft_materials.contains(&m.name);
                    match fx.soft_drag_per_s {
                        Some(c) if listed => c.max(m.drag_per_s),
                        _ => m.drag_per_s,
                    }
                })
                .collect(),
            vegetation_drag_per_s: params.effects.vegetation_drag_per_s(rock.mass_kg),
            scar_drag_per_m: params.effects.scar_drag_per_m(rock.mass_kg, rock.equivalent_radius_m()),
            slippage_m: 0.0,
            contacts: Vec::with_capacity(16),
            previous: Vec::with_capacity(16),
            scratch: Scratch::default(),
            edges: Vec::new(),
            binned_edges: Vec::new(),
            edges_listed_at: None,
            last_sample: None,
            out,
            settings,
        }
    }

    fn kinetic(&self, s: &RigidState) -> (f64, f64) {
        let tr = s.translational_energy_j(self.rock.mass_kg);
        (tr, tr + s.rotational_energy_j(&self.rock.inertia_kg_m2))
    }

    fn go(mut self, observer: &mut impl Observer) -> Outcome {
        let p = self.params;
        let mut rest_s = 0.0;
        // Where and when the rock's present stay in contact within its bounding radius of one place began
        // ([`SimParams::stop_in_place_s`]).
        let mut in_place_since: Option<(Vector3<f64>, f64)> = None;
        let in_place_m = self.rock.bounding_radius_m;
        let mut flight_h = p.max_flight_step_s;
        self.emit(observer, false, true);
        let reason = loop {
            if self.terrain.surface.at(self.s.position_m.x, self.s.position_m.y).is_none() {
                break StopReason::LeftTerrain;
            }
            if self.t >= p.max_time_s {
                break StopReason::MaxTime;
            }
            // Long exact ballistic step when clear of the ground.
            let mut h = (2.0 * flight_h).min(p.max_flight_step_s).min(p.max_time_s - self.t);
            let min_flight = 8.0 * p.dt_s;
            while h >= min_flight && !self.flight_is_clear(h) {
                h *= 0.5;
            }
            if h >= min_flight {
                flight_h = h;
                rest_s = 0.0;
                in_place_since = None;
                if self.fly(h, observer) {
                    break StopReason::Barrier;
                }
                continue;
            }
            flight_h = min_flight;
            let from = self.s.position_m;
            let in_contact = self.contact_step(observer);
            if self.cross_barriers(from, observer) == BarrierEffect::Caught {
                break StopReason::Barrier;
            }
            self.emit(observer, in_contact, false);
            let v = self.s.velocity_mps.norm();
            let w = self.s.omega_body_radps.norm();
            if in_contact && v < p.stop_speed_mps && w < p.stop_spin_radps {
                rest_s += p.dt_s;
                if rest_s >= p.stop_duration_s - 1e-12 {
                    break StopReason::Stopped;
                }
            } else {
                rest_s = 0.0;
            }
            let x = self.s.position_m;
            match in_place_since {
                Some((anchor, since)) if in_contact && (x - anchor).norm() <= in_place_m => {
                    if self.t - since >= p.stop_in_place_s - 1e-12 {
                        self.out.stopped_in_place = true;
                        break StopReason::Stopped;
                    }
                }
                _ => in_place_since = in_contact.then_some((x, self.t)),
            }
        };
        self.emit(observer, true, true);
        self.out.final_state = self.s;
        self.out.stop_reason = reason;
        self.out.travel_time_s = self.t;
        self.out
    }

    /// Whether the bounding sphere stays clear of the ground along the parabola over `h` seconds.
    fn flight_is_clear(&self, h: f64) -> bool {
        let x0 = self.s.position_m;
        let x1 = x0 + self.s.velocity_mps * h + GRAVITY * (0.5 * h * h);
        let r = self.rock.bounding_radius_m + FLIGHT_MARGIN_M;
        let top = self.terrain.surface.max_height_in(
            x0.x.min(x1.x) - r,
            x0.x.max(x1.x) + r,
            x0.y.min(x1.y) - r,
            x0.y.max(x1.y) + r,
        );
        // z(t) is concave, so its minimum over the step is at an end.
        x0.z.min(x1.z) - r > top
    }

    /// Exact ballistic motion over `h`, with free rotation, emitting samples along the parabola. Returns true if a
    /// barrier caught the rock on the way. A rock whose centre of mass passes off the terrain (its edge, a clip
    /// polygon's or a hole's) stops its flight just past the crossing, so it is recorded where it left.
    fn fly(&mut self, h: f64, observer: &mut impl Observer) -> bool {
        // A flight ends any contact (a rock is clear of the ground only steps after its last touch, so with the
        // default contact duration nothing counts as touching here already).
        self.touch_left.fill(0);
        self.edge_touch.clear();
        self.brake_left_s = 0.0;
        let (x0, v0) = (self.s.position_m, self.s.velocity_mps);
        let horizontal = (v0.x * v0.x + v0.y * v0.y).sqrt() * h;
        let pieces =
            ((horizontal / self.params.sample_spacing_m).ceil() as usize).max((h / 0.1).ceil() as usize).max(1);
        let at = |t: f64| x0 + v0 * t + GRAVITY * (0.5 * t * t);
        let off = |t: f64| {
            let x = at(t);
            self.terrain.surface.at(x.x, x.y).is_none()
        };
        let mut t_done = 0.0;
        for k in 1..=pieces {
            let mut tk = h * k as f64 / pieces as f64;
            let leaves = off(tk);
            if leaves {
                tk = first_time_off(t_done, tk, off);
            }
            let dt = tk - t_done;
            t_done = tk;
            // Rotation in sub-steps of at most 10 ms (ours): accurate phase for spins up to tens of rad/s.
            let sub = (dt / 0.01).ceil().max(1.0) as usize;
            for _ in 0..sub {
                let (q1, w1) = free_rotation(
                    Some(&self.s.orientation),
                    &self.s.omega_body_radps,
                    &self.rock.inertia_kg_m2,
                    dt / sub as f64,
                );
                self.s.orientation = q1.unwrap_or(self.s.orientation);
                self.s.omega_body_radps = w1;
            }
            let from = self.s.position_m;
            self.s.position_m = at(tk);
            self.s.velocity_mps = v0 + GRAVITY * tk;
            self.t += dt;
            self.advance_slippage(false, dt);
            match self.cross_barriers(from, observer) {
                BarrierEffect::Caught => return true,
                BarrierEffect::Slowed => {
                    // The rest of this ballistic step no longer holds.
                    self.emit(observer, false, true);
                    return false;
                }
                BarrierEffect::None => {}
            }
            self.emit(observer, false, true);
            if leaves {
                break;
            }
        }
        false
    }

    /// Checks the move from `from` to the current position against the barriers not met yet. A barrier crossed
    /// below its top catches the rock or slows it (see [`super::barrier`]).
    fn cross_barriers(&mut self, from: Vector3<f64>, observer: &mut impl Observer) -> BarrierEffect {
        if self.terrain.barriers.is_empty() {
            return BarrierEffect::None;
        }
        let to = self.s.position_m;
        let mut first: Option<(f64, usize)> = None;
        for (k, b) in self.terrain.barriers.iter().enumerate() {
            if self.barrier_met[k] {
                continue;
            }
            if let Some(f) = b.crossing([from.x, from.y], [to.x, to.y]) {
                if first.is_none_or(|(g, _)| f < g) {
                    first = Some((f, k));
                }
            }
        }
        let Some((f, k)) = first else { return BarrierEffect::None };
        self.barrier_met[k] = true;
        let point = from + (to - from) * f;
        let rot = self.s.orientation.to_rotation_matrix();
        let lowest = self.rock.lowest_dz_m(&rot);
        let ground = self.terrain.surface.height(point.x, point.y).unwrap_or(point.z);
        let clearance = (point.z + lowest - ground).max(0.0);
        let barrier = &self.terrain.barriers[k];
        if clearance >= barrier.height_m {
            return BarrierEffect::None;
        }
        let (_, kinetic) = self.kinetic(&self.s);
        let caught = kinetic <= barrier.capacity_j;
        observer.barrier(&BarrierHit {
            barrier: k,
            t_s: self.t,
            point_m: point,
            kinetic_j: kinetic,
            clearance_m: clearance,
            caught,
        });
        if caught {
            self.s.position_m = point;
            self.s.velocity_mps = Vector3::zeros();
            self.s.omega_body_radps = Vector3::zeros();
            return BarrierEffect::Caught;
        }
        let scale = ((kinetic - barrier.capacity_j) / kinetic).sqrt();
        self.s.velocity_mps *= scale;
        self.s.omega_body_radps *= scale;
        BarrierEffect::Slowed
    }

    /// One step of `dt_s` near the ground, taken as `impact_substeps` Moreau steps when an impact lies ahead in it
    /// (ours: the motion between impacts keeps `dt_s`), and as at least as many as keep every point of the rock
    /// within `max_contact_travel_m` a step (ours). A touch counts as a contact for whole steps of `dt_s` (the
    /// counters move once a step). Returns whether there was a contact.
    fn contact_step(&mut self, observer: &mut impl Observer) -> bool {
        let h = self.params.dt_s;
        let n = self.params.impact_substeps;
        let by_travel = self.steps_by_travel(h);
        let steps = if n > by_travel && self.impact_ahead(h) { n } else { by_travel };
        let in_contact = (0..steps).fold(false, |any, _| self.moreau_step(observer, h / steps as f64) | any);
        for t in self.touch_left.iter_mut() {
            *t = t.saturating_sub(1);
        }
        self.edge_touch.retain_mut(|e| {
            e.steps_left -= 1;
            e.steps_left > 0
        });
        in_contact
    }

    /// The fewest equal Moreau steps over `h` that keep every hull vertex within `max_contact_travel_m` a step at
    /// its present speed (at most [`MAX_TRAVEL_SUBSTEPS`]).
    fn steps_by_travel(&self, h: f64) -> usize {
        let w = &self.s.omega_body_radps;
        let bound_mps = self.s.velocity_mps.norm() + w.norm() * self.rock.bounding_radius_m;
        if bound_mps * h <= self.params.max_contact_travel_m {
            return 1;
        }
        let v_body = self.s.orientation.inverse_transform_vector(&self.s.velocity_mps);
        let fastest_mps =
            self.rock.vertices_m.iter().map(|b| (v_body + w.cross(b)).norm_squared()).fold(0.0, f64::max).sqrt();
        let steps = (fastest_mps * h / self.params.max_contact_travel_m).ceil();
        if steps > 1.0 {
            (steps as usize).min(MAX_TRAVEL_SUBSTEPS)
        } else {
            1
        }
    }

    /// Whether a hull vertex (or, with `terrain_edge_contacts`, a terrain edge) that does not count as touching
    /// lies below the ground (inside the rock) at the end pose of a free step of `h` and approaches it (along the
    /// untilted normal) faster than the bounce threshold. The end pose, not the midpoint one the step detects
    /// contacts at: a vertex that crosses the ground in the step's second half would otherwise be met below it by
    /// the next step, and resolved late.
    fn impact_ahead(&mut self, h: f64) -> bool {
        let x = self.s.position_m + self.s.velocity_mps * h;
        let Some(top) = self.ground_top_under(&x) else { return false };
        let rot = rotate(&self.s.orientation, &self.s.omega_body_radps, h).to_rotation_matrix();
        let (v, w) = (self.s.velocity_mps, self.s.orientation * self.s.omega_body_radps);
        let approaches = |arm: Vector3<f64>, normal: Vector3<f64>| {
            -(v + w.cross(&arm)).dot(&normal) > self.params.bounce_threshold_mps
        };
        let vertex_impact = self.rock.vertices_m.iter().enumerate().any(|(i, b)| {
            let arm = rot * b;
            self.touch_left[i] == 0
                && self.vertex_penetration(&(x + arm), top).is_some_and(|(_, normal, _)| approaches(arm, normal))
        });
        if vertex_impact || !self.params.terrain_edge_contacts {
            return vertex_impact;
        }
        self.list_edges(&x);
        let lowest = x.z + self.rock.lowest_dz_m(&rot);
        self.edges.iter().any(|edge| {
            self.edge_inside(&x, &rot, lowest, edge).is_some_and(|e| approaches(rot * e.deepest, -(rot * e.outward)))
                && self.edge_touching(edge.ia, edge.ib).is_none()
        })
    }

    /// The highest ground under the bounding sphere of the rock centred at `x`, or `None` when the sphere is clear
    /// of it (no vertex can touch).
    fn ground_top_under(&self, x: &Vector3<f64>) -> Option<f64> {
        let r = self.rock.bounding_radius_m;
        let top = self.terrain.surface.max_height_in(x.x - r, x.x + r, x.y - r, x.y + r);
        (x.z - r <= top).then_some(top)
    }

    /// Depth, normal and triangle of the ground at the world point `p` if it lies below it, after the cheap
    /// rejections against `top` ([`Run::ground_top_under`]) and the bound of its bin
    /// ([`crate::terrain::surface::Surface::upper_bound_at`]).
    fn vertex_penetration(&self, p: &Vector3<f64>, top: f64) -> Option<(f64, Vector3<f64>, u32)> {
        let surface = &self.terrain.surface;
        if p.z > top || p.z > surface.upper_bound_at(p.x, p.y) {
            return None;
        }
        surface.penetration(p)
    }

    /// One Moreau midpoint step of `h` near the ground. Returns whether there was a contact.
    fn moreau_step(&mut self, observer: &mut impl Observer, h: f64) -> bool {
        let rock = self.rock;
        let before = Velocities { linear_mps: self.s.velocity_mps, angular_body_radps: self.s.omega_body_radps };
        let x_mid = self.s.position_m + self.s.velocity_mps * (0.5 * h);
        let q_mid = rotate(&self.s.orientation, &self.s.omega_body_radps, 0.5 * h);
        self.detect(&x_mid, &q_mid);
        let w_free = free_spin(&self.s.omega_body_radps, &rock.inertia_kg_m2, h);
        let mut free = Velocities { linear_mps: self.s.velocity_mps + GRAVITY * h, angular_body_radps: w_free };
        let in_contact = !self.contacts.is_empty();
        if in_contact && self.params.effects.rolling_resistance.is_some() {
            // Rolling resistance in contact acts on what the solver starts from, so that the contacts it solves
            // hold: applied after the solve (as the drags are), it took the spin and the speed along the ground
            // but not the normal speed that went with them, and a rock at rest on a slope lifted off every few
            // dozen steps and never counted as stopped.
            self.roll_normal = self.contacts.iter().fold(Vector3::zeros(), |a, c| a + c.normal).normalize();
            self.roll(&mut free, h);
        }
        let mut after = free;
        if in_contact {
            self.out.contact_steps += 1;
            // Warm start: a contact that persists from the previous step (same vertex, same triangle) starts from its
            // previous impulses.
            for c in self.contacts.iter_mut() {
                if let Some(p) = self.previous.iter().find(|p| p.vertex == c.vertex && p.triangle == c.triangle) {
                    c.warm = p.warm;
                }
            }
            let (solved, report) =
                solve(rock, &q_mid, &mut self.contacts, &before, &free, &self.settings, &mut self.scratch);
            after = solved;
            self.out.solver_sweeps += report.iterations as u64;
            if report.energy_guard {
                self.out.energy_guards += 1;
            }
            if let Some(c) = self.new_impact(&before, &q_mid) {
                self.out.impacts += 1;
                let v = before.linear_mps;
                let speed = v.norm();
                let angle =
                    if speed > 0.0 { (-v.dot(&c.normal) / speed).clamp(-1.0, 1.0).asin().to_degrees() } else { 0.0 };
                observer.impact(&super::Impact {
                    t_s: self.t + 0.5 * h,
                    point_m: c.point_m,
                    normal: c.normal,
                    triangle: c.triangle,
                    approach_speed_mps: report.max_approach_mps,
                    speed_mps: speed,
                    impact_angle_deg: angle,
                    cr: c.cr,
                    kinetic_before_j: free.kinetic_energy_j(rock),
                    kinetic_after_j: after.kinetic_energy_j(rock),
                    energy_guard: report.energy_guard,
                });
            }
        }
        // A terrain edge's contact has an index past the hull vertices.
        let hull_vertices = self.touch_left.len();
        // One more than the contact's steps: `contact_step` takes one off at the end of the step.
        let left = self.touch_steps + 1;
        for c in &self.contacts {
            if c.vertex < hull_vertices {
                self.touch_left[c.vertex] = left;
                self.vertex_cr[c.vertex] = c.cr_drawn;
            } else if let Some(e) = self.edge_touch.iter_mut().find(|e| e.index == c.vertex) {
                e.steps_left = left;
            } else {
                self.edge_touch.push(EdgeTouch { index: c.vertex, steps_left: left, cr_drawn: c.cr_drawn });
            }
        }
        if in_contact {
            let drag = self
                .contacts
                .iter()
                .map(|k| self.drag_per_s[self.terrain.triangle_material[k.triangle as usize] as usize])
                .fold(0.0, f64::max);
            self.touch_drag_per_s = drag;
            self.brake_left_s = self.params.contact_duration_s;
        }
        // Acting for the rest of the contact's duration only (all of `h` but in the step that ends it).
        let braking = self.brake_left_s > 1e-12;
        if braking {
            let d = h.min(self.brake_left_s);
            if !in_contact {
                self.roll(&mut after, d);
            }
            self.brake(&mut after, d);
            self.brake_left_s -= d;
        }
        self.s.velocity_mps = after.linear_mps;
        self.s.omega_body_radps = after.angular_body_radps;
        self.s.position_m = x_mid + after.linear_mps * (0.5 * h);
        self.s.orientation = rotate(&q_mid, &after.angular_body_radps, 0.5 * h);
        // Project out penetration beyond the slop (position only; velocities are untouched).
        let (mut push, mut deepest) = (Vector3::zeros(), 0.0f64);
        for c in &self.contacts {
            push += c.normal * c.depth_m;
            deepest = deepest.max(c.depth_m);
        }
        if deepest > self.params.penetration_slop_m {
            self.s.position_m += push.normalize() * (0.5 * (deepest - self.params.penetration_slop_m));
        }
        std::mem::swap(&mut self.previous, &mut self.contacts);
        self.t += h;
        self.advance_slippage(braking, h);
        in_contact
    }

    /// Advances the slippage of the `slip_friction_max_deg` effect over `h`: the distance travelled in contact, a
    /// decay in flight (nothing when the effect is off).
    fn advance_slippage(&mut self, in_contact: bool, h: f64) {
        let effects = &self.params.effects;
        if effects.slip_friction_max_deg.is_none() {
            return;
        }
        if in_contact {
            self.slippage_m += h * self.s.velocity_mps.norm();
        } else {
            self.slippage_m *= effects.slippage_decay(h);
        }
    }

    /// Rolling resistance (when on) over `h` on a rock in contact, against the averaged normal of its last touch:
    /// in a step in contact on the velocities the solver starts from, after the last touch on the step's result.
    fn roll(&self, vel: &mut Velocities, h: f64) {
        let n = self.roll_normal;
        if let Some(mu_r) = self.params.effects.rolling_resistance {
            let v = vel.linear_mps;
            let along = v - n * v.dot(&n);
            let speed = along.norm();
            if speed > 0.0 {
                // Azzoni et al. (1995), physics.md §4 and §8: a = −A·g·cos α·μ_r with A = m/(m + I/R²), the share
                // of a rolling rock's kinetic energy in translation; here that share for any motion (1 sliding,
                // 5/7 rolling as a sphere; ours for a tumbling rock), so that the force μ_r·N does its work on
                // the whole kinetic energy along the ground.
                let w = vel.angular_body_radps;
                let translational = 0.5 * self.rock.mass_kg * speed * speed;
                let rotational = 0.5 * w.component_mul(&self.rock.inertia_kg_m2).dot(&w);
                let share = translational / (translational + rotational);
                let drop = (share * mu_r * GRAVITY_MPS2 * n.z.abs() * h).min(speed);
                let f = 1.0 - drop / speed;
                vel.linear_mps = v - along * (1.0 - f);
                vel.angular_body_radps *= f;
            }
        }
    }

    /// Drag (the largest soft-ground rate among the touched materials plus the vegetation drag, then the scarring
    /// drag) on a rock in contact over a step of `h`, with the soft-ground rate of its last touch.
    fn brake(&self, vel: &mut Velocities, h: f64) {
        let c = self.touch_drag_per_s + self.vegetation_drag_per_s;
        if c > 0.0 {
            let f = (-c * h).exp();
            vel.linear_mps *= f;
            vel.angular_body_radps *= f;
        }
        if self.scar_drag_per_m > 0.0 {
            // dv/dt = −k v² over h, exactly: v' = v / (1 + k v h).
            let f = 1.0 / (1.0 + self.scar_drag_per_m * vel.linear_mps.norm() * h);
            vel.linear_mps *= f;
            vel.angular_body_radps *= f;
        }
    }

    /// Fills `self.contacts` with the hull vertices below the ground at the pose (x, q), each with its restitution
    /// (drawn anew for a new contact when Cr is drawn per impact, then modified by the restitution effects) and, for
    /// a new contact with the roughness effect on, a tilted normal.
    fn detect(&mut self, x: &Vector3<f64>, q: &UnitQuaternion<f64>) {
        self.contacts.clear();
        let Some(top) = self.ground_top_under(x) else { return };
        let rot = q.to_rotation_matrix();
        let effects = &self.params.effects;
        let v = self.s.velocity_mps;
        let w = self.s.orientation * self.s.omega_body_radps;
        for (i, b) in self.rock.vertices_m.iter().enumerate() {
            let p = x + rot * b;
            let Some((depth, mut normal, triangle)) = self.vertex_penetration(&p, top) else { continue };
            let m = self.terrain.triangle_material[triangle as usize] as usize;
            let (mu_static, mu_dynamic) = self.friction_of(m);
            let touching = self.touching(i);
            let new = touching.is_none();
            let mut cr = self.cr_at(touching, m);
            let cr_drawn = cr;
            if new {
                if let Some(rough) = effects.roughness_m {
                    let tilt = uniform(self.rng) * (rough / self.rock.equivalent_radius_m()).atan();
                    let azimuth = std::f64::consts::TAU * uniform(self.rng);
                    let t1 = super::contact::any_perpendicular(&normal);
                    let t2 = normal.cross(&t1);
                    normal = (normal * tilt.cos() + (t1 * azimuth.cos() + t2 * azimuth.sin()) * tilt.sin()).normalize();
                }
            }
            let u = v + w.cross(&(rot * b));
            let approach = (-u.dot(&normal)).max(0.0);
            let angle = incidence_deg(&v, &normal);
            cr = effects.restitution(cr, approach, angle, self.rock.mass_kg);
            self.contacts.push(Contact {
                vertex: i,
                point_m: p,
                arm_body_m: *b,
                normal,
                depth_m: depth,
                warm: (0.0, [0.0; 2]),
                triangle,
                cr,
                cr_drawn,
                mu_static,
                mu_dynamic,
            });
        }
        if self.params.terrain_edge_contacts {
            self.detect_edges(x, &rot);
        }
    }

    /// tan of the static and dynamic friction angles of material `m` now (the dynamic one moved by the slippage of
    /// `slip_friction_max_deg` when on, the static one at least as high).
    fn friction_of(&self, m: usize) -> (f64, f64) {
        let effects = &self.params.effects;
        let (mu_static, mu_dynamic) = self.friction[m];
        if effects.slip_friction_max_deg.is_none() {
            return (mu_static, mu_dynamic);
        }
        let mu_dynamic = effects.slip_friction(mu_dynamic, self.slippage_m);
        (mu_static.max(mu_dynamic), mu_dynamic)
    }

    /// The restitution drawn at the last touch of a contact that still counts as touching: hull vertex `vertex`, or
    /// a terrain edge's contact (an index past the hull vertices), whichever triangle it was met on.
    fn touching(&self, vertex: usize) -> Option<f64> {
        match self.touch_left.get(vertex) {
            Some(&left) => (left > 0).then(|| self.vertex_cr[vertex]),
            None => self.edge_touch.iter().find(|e| e.index == vertex).map(|e| e.cr_drawn),
        }
    }

    /// The restitution of a contact on material `m`: kept while it counts as touching, else drawn anew when drawn
    /// per impact, else the rock's draw.
    fn cr_at(&mut self, touching: Option<f64>, m: usize) -> f64 {
        match touching {
            Some(cr) => cr,
            None if self.params.cr_draw == CrDraw::PerImpact => self.terrain.materials[m].cr.sample(self.rng),
            None => self.cr[m],
        }
    }

    /// The restitution drawn at the last touch of the terrain edge between vertices `ia` and `ib` if either of its
    /// contacts still counts as touching: one restitution for both.
    fn edge_touching(&self, ia: u32, ib: u32) -> Option<f64> {
        (0..2).find_map(|k| self.touching(self.edge_index(ia, ib, k)))
    }

    /// The contact index of end `k` (0 or 1) of the terrain edge between vertices `ia` and `ib`: one of its own,
    /// past the hull's vertices.
    fn edge_index(&self, ia: u32, ib: u32, k: usize) -> usize {
        let edge = ia as usize * self.terrain.surface.vertices().len() + ib as usize;
        self.rock.vertices_m.len() + 2 * edge + k
    }

    /// Lists in `edges` the terrain edges of the triangles binned within twice the bounding radius of `x` that pass
    /// horizontally within 2.5 radii of it, unless they were listed within a radius of it (in x and in y): from
    /// anywhere the rock can be before they are listed again (within √2 radii), the others lie beyond its bounding
    /// sphere, where [`Run::edge_inside`] would turn them down each step (ours; on a 5 m DEM most edges of the
    /// triangles under a small rock do).
    fn list_edges(&mut self, x: &Vector3<f64>) {
        let r = self.rock.bounding_radius_m;
        if self.edges_listed_at.is_none_or(|c| (c.x - x.x).abs().max((c.y - x.y).abs()) > r) {
            let surface = &self.terrain.surface;
            surface.edges_in(x.x - 2.0 * r, x.x + 2.0 * r, x.y - 2.0 * r, x.y + 2.0 * r, &mut self.binned_edges);
            let (vertices, reach) = (surface.vertices(), 2.5 * r);
            let flat = |v: &Vector3<f64>| Vector3::new(v.x, v.y, 0.0);
            self.edges.clear();
            for &(ia, ib, triangle) in &self.binned_edges {
                let (a, b) = (vertices[ia as usize], vertices[ib as usize]);
                if segment_distance(&flat(&a), &flat(&b), &flat(x)) <= reach {
                    self.edges.push(ListedEdge { ia, ib, triangle, top_z: a.z.max(b.z) });
                }
            }
            self.edges_listed_at = Some(*x);
        }
    }

    /// Where the terrain edge `edge` passes more than half `penetration_slop_m` inside the rock at the pose (x, rot),
    /// whose lowest point is at height `lowest` ([`deepest_inside`], in the body frame).
    /// Met at half the slop (ours): the depth is projected out beyond the slop, so a rock held by edges alone rests
    /// between the two; met at the slop itself, it was pushed clear every few steps, fell a step, and never counted
    /// as at rest (a 660 t slab on a flat top's edges).
    fn edge_inside(
        &self,
        x: &Vector3<f64>,
        rot: &nalgebra::Rotation3<f64>,
        lowest: f64,
        edge: &ListedEdge,
    ) -> Option<EdgeInside> {
        // An edge wholly below the rock's lowest point, or beyond its bounding sphere, cannot meet it.
        if edge.top_z < lowest {
            return None;
        }
        let vertices = self.terrain.surface.vertices();
        let (ea, eb) = (vertices[edge.ia as usize], vertices[edge.ib as usize]);
        if segment_distance(&ea, &eb, x) > self.rock.bounding_radius_m {
            return None;
        }
        let to_body = |p: Vector3<f64>| rot.inverse_transform_vector(&(p - x));
        deepest_inside(&self.rock.faces, &to_body(ea), &to_body(eb), 0.5 * self.params.penetration_slop_m)
    }

    /// Adds the terrain edges that pass through the rock at the pose (x, rot) more than half `penetration_slop_m`
    /// deep as contacts ([`SimParams::terrain_edge_contacts`]): at the edge's deepest point, with the normal of the
    /// hull face nearest to it or of the hull edge it meets there ([`deepest_inside`]), pointing into the rock; the
    /// restitution is drawn as a hull vertex's is (kept while the edge counts as touching), but with no roughness
    /// tilt. Edges meeting at a buried terrain vertex give it once.
    fn detect_edges(&mut self, x: &Vector3<f64>, rot: &nalgebra::Rotation3<f64>) {
        let rock = self.rock;
        self.list_edges(x);
        let edges = std::mem::take(&mut self.edges);
        let first_edge_contact = self.contacts.len();
        let (v, w) = (self.s.velocity_mps, self.s.orientation * self.s.omega_body_radps);
        let lowest = x.z + rock.lowest_dz_m(rot);
        for edge in &edges {
            let Some(inside) = self.edge_inside(x, rot, lowest, edge) else { continue };
            let &ListedEdge { ia, ib, triangle, .. } = edge;
            let normal = -(rot * inside.outward);
            let angle = incidence_deg(&v, &normal);
            let m = self.terrain.triangle_material[triangle as usize] as usize;
            let (mu_static, mu_dynamic) = self.friction_of(m);
            let cr_drawn = self.cr_at(self.edge_touching(ia, ib), m);
            for (k, &(arm, depth)) in inside.stretch().iter().enumerate() {
                if self.contacts[first_edge_contact..].iter().any(|c| (c.arm_body_m - arm).norm() < 1e-6) {
                    continue;
                }
                let approach = (-(v + w.cross(&(rot * arm))).dot(&normal)).max(0.0);
                self.contacts.push(Contact {
                    vertex: self.edge_index(ia, ib, k),
                    point_m: x + rot * arm,
                    arm_body_m: arm,
                    normal,
                    depth_m: depth,
                    warm: (0.0, [0.0; 2]),
                    triangle,
                    cr: self.params.effects.restitution(cr_drawn, approach, angle, rock.mass_kg),
                    cr_drawn,
                    mu_static,
                    mu_dynamic,
                });
            }
        }
        self.edges = edges;
    }

    /// The fastest contact that did not count as touching before this step and approaches faster than the bounce
    /// threshold, if any.
    fn new_impact(&self, before: &Velocities, q: &UnitQuaternion<f64>) -> Option<Contact> {
        let mut best: Option<(f64, Contact)> = None;
        for c in &self.contacts {
            if self.touching(c.vertex).is_some() {
                continue;
            }
            let b = c.arm_body_m;
            let u = before.linear_mps + q * before.angular_body_radps.cross(&b);
            let approach = -u.dot(&c.normal);
            if approach > self.params.bounce_threshold_mps && best.is_none_or(|(a, _)| approach > a) {
                best = Some((approach, *c));
            }
        }
        best.map(|(_, c)| c)
    }

    /// Emits a sample if the rock moved `sample_spacing_m` horizontally (or 0.1 s passed) since the last one, or
    /// if `force`.
    fn emit(&mut self, observer: &mut impl Observer, in_contact: bool, force: bool) {
        let (tr, total) = self.kinetic(&self.s);
        self.out.max_kinetic_j = self.out.max_kinetic_j.max(total);
        let x = self.s.position_m;
        if !force && !observer.every_step() {
            if let Some((last, t_last)) = self.last_sample {
                let d2 = (x.x - last.x).powi(2) + (x.y - last.y).powi(2);
                if d2 < self.params.sample_spacing_m.powi(2) && self.t - t_last < 0.1 {
                    return;
                }
            }
        }
        let rot = self.s.orientation.to_rotation_matrix();
        let lowest = self.rock.lowest_dz_m(&rot);
        let clearance = match self.terrain.surface.height(x.x, x.y) {
            Some(z) => (x.z + lowest - z).max(0.0),
            None => 0.0,
        };
        self.out.max_bounce_m = self.out.max_bounce_m.max(clearance);
        self.last_sample = Some((x, self.t));
        observer.sample(&Sample {
            t_s: self.t,
            position_m: x,
            velocity_mps: self.s.velocity_mps,
            spin_radps: self.s.omega_body_radps.norm(),
            translational_j: tr,
            kinetic_j: total,
            clearance_m: clearance,
            in_contact,
        });
    }
}

/// The angle between the velocity `v` and the ground of upward `normal`, degrees (90 at rest: ours, a drop).
fn incidence_deg(v: &Vector3<f64>, normal: &Vector3<f64>) -> f64 {
    let speed = v.norm();
    if speed > 0.0 {
        (-v.dot(normal) / speed).clamp(-1.0, 1.0).asin().to_degrees()
    } else {
        90.0
    }
}

/// The distance from `p` to the segment a–b.
fn segment_distance(a: &Vector3<f64>, b: &Vector3<f64>, p: &Vector3<f64>) -> f64 {
    let ab = b - a;
    let t = ((p - a).dot(&ab) / ab.norm_squared().max(1e-300)).clamp(0.0, 1.0);
    (a + ab * t - p).norm()
}

/// A terrain edge's contact that counts as touching ([`Run::edge_touch`]).
struct EdgeTouch {
    /// Its contact index ([`Run::edge_index`]): the edge's, whichever of its triangles it was met on.
    index: usize,
    /// Steps it still counts as touching.
    steps_left: u32,
    /// The restitution drawn at its last touch.
    cr_drawn: f64,
}

/// A terrain edge near the rock ([`Run::list_edges`]).
struct ListedEdge {
    /// Its lower and higher vertex indices.
    ia: u32,
    ib: u32,
    /// The lowest-numbered of its triangles binned near the rock, whose material its contacts take. For an edge that
    /// can meet the rock before the next listing that is the same triangle at every listing: such an edge passes
    /// within the binned box, and both its triangles are binned wherever it passes.
    triangle: u32,
    /// The height of its higher end, m: an edge below the rock is turned down without reading its vertices.
    top_z: f64,
}

/// Where a terrain edge passes inside the rock ([`deepest_inside`]), in the body frame.
struct EdgeInside {
    /// The edge's deepest point inside the hull.
    deepest: Vector3<f64>,
    /// The outward normal of the contact at the deepest point.
    outward: Vector3<f64>,
    /// The contact points with their depths (the distance to the nearest face plane), m: the ends of the stretch
    /// within the least depth asked for of the deepest, or the deepest point alone (the first `ends` of `n_ends`)
    /// where that stretch is shorter than [`MIN_EDGE_STRETCH_M`].
    ends: [(Vector3<f64>, f64); 2],
    n_ends: usize,
}

impl EdgeInside {
    /// The contact points with their depths ([`EdgeInside::ends`]).
    fn stretch(&self) -> &[(Vector3<f64>, f64)] {
        &self.ends[..self.n_ends]
    }
}

/// Shortest stretch of a terrain edge taken as two contacts rather than one, m (ours: a centimetre, under the
/// smallest rock side allowed, 5 cm).
const MIN_EDGE_STRETCH_M: f64 = 0.01;

/// The deepest point of the segment a–b (body frame) inside the convex hull whose outward face planes are `faces`
/// (n·x ≤ d inside), its depth (the distance to the nearest face plane), the outward normal of the contact there
/// (the nearest face's, or for two faces as near, that of the hull's edge between them against the segment) and
/// the stretch of the segment within `min_depth` of that depth; `None` if the segment misses the hull or lies
/// nowhere deeper than `min_depth`.
/// The segment is clipped to the hull's half-spaces, and the depth, a concave function along it (the minimum of linear
/// ones), is maximised by golden-section search to 10⁻⁸ of the segment's length.
fn deepest_inside(
    faces: &[(Vector3<f64>, f64)],
    a: &Vector3<f64>,
    b: &Vector3<f64>,
    min_depth: f64,
) -> Option<EdgeInside> {
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (n, d) in faces {
        let (da, db) = (d - n.dot(a), d - n.dot(b));
        if da < 0.0 && db < 0.0 {
            return None;
        }
        if da < 0.0 {
            t0 = t0.max(da / (da - db));
        } else if db < 0.0 {
            t1 = t1.min(da / (da - db));
        }
        if t0 >= t1 {
            return None;
        }
    }
    // Each face's distance is linear along the segment, so the larger of its values at the clipped ends bounds it.
    let (p0, p1) = (a + (b - a) * t0, a + (b - a) * t1);
    if faces.iter().map(|(n, d)| (d - n.dot(&p0)).max(d - n.dot(&p1))).fold(f64::INFINITY, f64::min) <= min_depth {
        return None;
    }
    let depth_at = |t: f64| {
        let p = a + (b - a) * t;
        faces.iter().map(|(n, d)| d - n.dot(&p)).fold(f64::INFINITY, f64::min)
    };
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let (mut lo, mut hi) = (t0, t1);
    let (mut c, mut d) = (hi - g * (hi - lo), lo + g * (hi - lo));
    let (mut fc, mut fd) = (depth_at(c), depth_at(d));
    for _ in 0..40 {
        if fc < fd {
            (lo, c, fc) = (c, d, fd);
            d = lo + g * (hi - lo);
            fd = depth_at(d);
        } else {
            (hi, d, fd) = (d, c, fc);
            c = hi - g * (hi - lo);
            fc = depth_at(c);
        }
    }
    let t = 0.5 * (lo + hi);
    let p = a + (b - a) * t;
    let depth = depth_at(t);
    if depth <= min_depth {
        return None;
    }
    // The stretch within `min_depth` of the deepest (ours; depth is concave along the segment, so it is one
    // interval, its ends found by bisection): a terrain edge lying along a face meets it along a line, which two
    // contacts at the stretch's ends carry as two hull vertices carry an edge of the rock. The deepest point alone
    // is, on such a plateau, wherever the search stopped on it, and a cube dropped flat on a crest spun off it.
    let floor = depth - min_depth.max(1e-6);
    let end_towards = |mut outside: f64| {
        if depth_at(outside) >= floor {
            return outside;
        }
        let mut inside = t;
        for _ in 0..40 {
            let mid = 0.5 * (inside + outside);
            if depth_at(mid) >= floor {
                inside = mid;
            } else {
                outside = mid;
            }
        }
        inside
    };
    let (t_lo, t_hi) = (end_towards(t0), end_towards(t1));
    let at = |u: f64| (a + (b - a) * u, depth_at(u));
    let (ends, n_ends) = if (t_hi - t_lo) * (b - a).norm() < MIN_EDGE_STRETCH_M {
        ([(p, depth); 2], 1)
    } else {
        ([at(t_lo), at(t_hi)], 2)
    };
    // Where two faces are as near, the segment meets the hull's edge between them: the normal of that edge-edge
    // contact is perpendicular to both edges (as in the separating-axis test), which for a segment lying along one
    // of the faces is that face's normal (a terrain edge under a flat face is pressed against that face). Taking
    // either face's normal instead let the rock move into the segment along the other, unresisted, and the depth
    // projected out every step lifted it (a 57 t box tipping over a bench crest gained 0.05 MJ). A segment along
    // the hull's edge itself takes the mean of the two normals.
    // The nearest face, then the next nearest that meets it in an edge (not one parallel to it, as across a thin
    // slab), among those within 1 µm of the depth; the first in `faces` of any as near.
    let nearest = |meets: &dyn Fn(&Vector3<f64>) -> bool| {
        let mut best: Option<(f64, &Vector3<f64>)> = None;
        for (n, d) in faces {
            let dist = d - n.dot(&p);
            if dist <= depth + 1e-6 && meets(n) && best.is_none_or(|(b, _)| dist < b) {
                best = Some((dist, n));
            }
        }
        best.map(|(_, n)| n)
    };
    let n1 = nearest(&|_| true)?;
    let Some(n2) = nearest(&|n| n1.cross(n).norm() > 1e-6) else {
        return Some(EdgeInside { deepest: p, outward: *n1, ends, n_ends });
    };
    let hull_edge = n1.cross(n2).normalize();
    let across = (b - a).normalize().cross(&hull_edge);
    let outward = if across.norm() > 1e-3 {
        let c = across.normalize();
        if c.dot(&(n1 + n2)) < 0.0 {
            -c
        } else {
            c
        }
    } else {
        (n1 + n2).normalize()
    };
    Some(EdgeInside { deepest: p, outward, ends, n_ends })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The faces of the cube [−1, 1]³: outward unit normals, offset 1.
    fn cube_faces() -> Vec<(Vector3<f64>, f64)> {
        (0..3).flat_map(|a| [1.0, -1.0].map(|s| (Vector3::ith(a, s), 1.0))).collect()
    }

    #[test]
    fn a_segment_is_met_at_its_deepest_point_inside_the_hull() {
        let faces = cube_faces();
        // Through the middle along x: deepest at the centre, 1 from every face but ±x.
        let deepest = |a: Vector3<f64>, b: Vector3<f64>| {
            let e = deepest_inside(&faces, &a, &b, 0.0).unwrap();
            assert_eq!(e.stretch().len(), 1, "a segment peaking once is met at one point");
            (e.deepest, e.stretch()[0].1, e.outward)
        };
        let (p, depth, outward) = deepest(Vector3::new(-3.0, 0.0, 0.0), Vector3::new(3.0, 0.0, 0.0));
        assert!(p.norm() < 1e-6 && (depth - 1.0).abs() < 1e-7, "{p} {depth}");
        assert!(outward.x == 0.0, "the face met is one the segment lies along, not ±x: {outward}");
        // Along the bottom face, 0.1 inside at x = 0 and rising 1 in 60: deepest where it meets the +x face as deep,
        // x = 0.9 / (1 + 1/60), on the cube's edge between the two faces: the normal is perpendicular to both edges,
        // (1/60, 0, −1), nearly the bottom face's, which the segment nearly lies along.
        let (a, b) = (Vector3::new(-3.0, 0.2, -0.95), Vector3::new(3.0, 0.2, -0.85));
        let (p, depth, outward) = deepest(a, b);
        assert!((outward - Vector3::new(1.0 / 60.0, 0.0, -1.0).normalize()).norm() < 1e-9, "{outward}");
        let x = 0.9 / (1.0 + 1.0 / 60.0);
        assert!((p.x - x).abs() < 1e-6 && (depth - (1.0 - x)).abs() < 1e-6, "{p} {depth}");
        // Through a corner region only: the edge leaves across the rim of x = 1 and z = −1, and the cube's edge there
        // (along y) crosses it square: the normal bisects the two faces'.
        let (a, b) = (Vector3::new(0.0, 0.0, -1.5), Vector3::new(1.5, 0.0, 0.0));
        let (p, depth, outward) = deepest(a, b);
        assert!((depth - 0.25).abs() < 1e-6 && (p - Vector3::new(0.75, 0.0, -0.75)).norm() < 1e-5, "{p} {depth}");
        assert!((outward - Vector3::new(1.0, 0.0, -1.0).normalize()).norm() < 1e-9, "{outward}");
        // Across the same rim at a slant (rising along y too): perpendicular to the segment and to the cube's edge.
        let (a, b) = (Vector3::new(0.0, -0.5, -1.5), Vector3::new(1.5, 0.5, 0.0));
        let (_, _, outward) = deepest(a, b);
        let expected = (b - a).cross(&Vector3::y()).normalize();
        assert!((outward - expected).norm() < 1e-9 || (outward + expected).norm() < 1e-9, "{outward}");
        assert!(outward.x > 0.0 && outward.z < 0.0, "{outward}");
        // Along the bottom face, 0.1 inside: met along it, by contacts at the ends of the stretch within the least
        // depth asked for (1 mm) of the deepest, where the ±x faces are 0.099 away.
        let e = deepest_inside(&faces, &Vector3::new(-3.0, 0.2, -0.9), &Vector3::new(3.0, 0.2, -0.9), 0.001).unwrap();
        assert!((e.outward + Vector3::z()).norm() < 1e-9, "{}", e.outward);
        assert_eq!(e.stretch().len(), 2);
        for ((p, depth), x) in e.stretch().iter().zip([-0.901, 0.901]) {
            assert!((p.x - x).abs() < 1e-6 && (depth - 0.099).abs() < 1e-6, "{p} {depth}");
        }
        // Nowhere deeper than asked: the segment above is at most 0.25 inside.
        assert!(deepest_inside(&faces, &a, &b, 0.26).is_none() && deepest_inside(&faces, &a, &b, 0.24).is_some());
        // Missing the cube, and touching nothing but a plane beyond it.
        assert!(deepest_inside(&faces, &Vector3::new(-3.0, 2.0, 0.0), &Vector3::new(3.0, 2.0, 0.0), 0.0).is_none());
        assert!(deepest_inside(&faces, &Vector3::new(1.5, -3.0, 0.0), &Vector3::new(1.5, 3.0, 0.0), 0.0).is_none());
    }
}
