//! The analytic pieces of a rock's path, handed to a [`PathObserver`] as the engine produces them, so that
//! envelopes, collectors or plots can be computed without storing trajectories.
//!
//! # Units
//! Positions in m, times in s, speeds in m/s, accelerations in m/s².

use super::engine::G_MPS2;

/// A free flight: an exact parabola from (`x0_m`, `z0_m`) with initial velocity (`vx_mps`, `vz_mps`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlightPiece {
    /// Time since release at the start of the piece, s.
    pub t0_s: f64,
    /// Duration, s.
    pub duration_s: f64,
    /// Start position x, m.
    pub x0_m: f64,
    /// Start position z, m.
    pub z0_m: f64,
    /// Initial horizontal velocity, m/s.
    pub vx_mps: f64,
    /// Initial vertical velocity (up positive), m/s.
    pub vz_mps: f64,
}

impl FlightPiece {
    /// Position `[x_m, z_m]` at `dt_s` after the start of the piece.
    pub fn position_at(&self, dt_s: f64) -> [f64; 2] {
        [self.x0_m + self.vx_mps * dt_s, self.z0_m + self.vz_mps * dt_s - 0.5 * G_MPS2 * dt_s * dt_s]
    }

    /// Velocity `[vx_mps, vz_mps]` at `dt_s` after the start of the piece.
    pub fn velocity_at(&self, dt_s: f64) -> [f64; 2] {
        [self.vx_mps, self.vz_mps - G_MPS2 * dt_s]
    }

    /// Position at the end of the piece.
    pub fn end_position(&self) -> [f64; 2] {
        self.position_at(self.duration_s)
    }

    /// The x range covered, `(min, max)`, m.
    pub fn x_range_m(&self) -> (f64, f64) {
        let x1 = self.x0_m + self.vx_mps * self.duration_s;
        (self.x0_m.min(x1), self.x0_m.max(x1))
    }

    /// Time after the start at which the rock is at horizontal position `x_m`, if it gets there in this piece
    /// (`None` for a vertical flight).
    pub fn time_at_x(&self, x_m: f64) -> Option<f64> {
        if self.vx_mps == 0.0 {
            return None;
        }
        let dt = (x_m - self.x0_m) / self.vx_mps;
        (0.0..=self.duration_s).contains(&dt).then_some(dt)
    }
}

/// Sliding (or rolling) along one profile segment with constant acceleration; the direction of motion does not
/// change within a piece.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlidePiece {
    /// Time since release at the start of the piece, s.
    pub t0_s: f64,
    /// Duration, s.
    pub duration_s: f64,
    /// Index of the profile segment.
    pub segment: usize,
    /// Start position x, m.
    pub x0_m: f64,
    /// Start position z, m.
    pub z0_m: f64,
    /// Unit direction of motion `[dx, dz]` (along the segment, forward or backward).
    pub direction: [f64; 2],
    /// Speed at the start, m/s (≥ 0).
    pub speed0_mps: f64,
    /// Acceleration along `direction`, m/s² (negative when slowing down).
    pub accel_mps2: f64,
}

impl SlidePiece {
    /// Distance travelled `dt_s` after the start, m.
    pub fn distance_at(&self, dt_s: f64) -> f64 {
        self.speed0_mps * dt_s + 0.5 * self.accel_mps2 * dt_s * dt_s
    }

    /// Position `[x_m, z_m]` at `dt_s` after the start.
    pub fn position_at(&self, dt_s: f64) -> [f64; 2] {
        let d = self.distance_at(dt_s);
        [self.x0_m + self.direction[0] * d, self.z0_m + self.direction[1] * d]
    }

    /// Speed at `dt_s` after the start, m/s.
    pub fn speed_at(&self, dt_s: f64) -> f64 {
        (self.speed0_mps + self.accel_mps2 * dt_s).max(0.0)
    }

    /// Speed after travelling `distance_m` from the start, m/s (from v² = v₀² + 2as).
    pub fn speed_at_distance(&self, distance_m: f64) -> f64 {
        (self.speed0_mps * self.speed0_mps + 2.0 * self.accel_mps2 * distance_m).max(0.0).sqrt()
    }

    /// Length of the piece, m.
    pub fn length_m(&self) -> f64 {
        self.distance_at(self.duration_s)
    }

    /// Position at the end of the piece.
    pub fn end_position(&self) -> [f64; 2] {
        self.position_at(self.duration_s)
    }

    /// The x range covered, `(min, max)`, m.
    pub fn x_range_m(&self) -> (f64, f64) {
        let x1 = self.x0_m + self.direction[0] * self.length_m();
        (self.x0_m.min(x1), self.x0_m.max(x1))
    }
}

/// An impact: the velocities just before and after, and the parameters drawn for it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImpactEvent {
    /// Time since release, s.
    pub t_s: f64,
    /// Impact point x, m.
    pub x_m: f64,
    /// Impact point z, m.
    pub z_m: f64,
    /// Index of the profile segment hit.
    pub segment: usize,
    /// Velocity before, `[vx, vz]` m/s.
    pub velocity_in_mps: [f64; 2],
    /// Velocity after, `[vx, vz]` m/s.
    pub velocity_out_mps: [f64; 2],
    /// Spin before and after (clockwise positive in the x–z view: forward rolling for a rock moving towards +x),
    /// rad/s; 0 unless a rotational rule is on.
    pub spin_radps: [f64; 2],
    /// Rn as applied (after the optional velocity scaling).
    pub rn: f64,
    /// Rt as drawn.
    pub rt: f64,
    /// Segment-angle perturbation applied (roughness, after clamping), degrees.
    pub angle_offset_deg: f64,
    /// Whether the rock slides after the impact rather than flying.
    pub slides_after: bool,
}

/// Receives the pieces of a rock's path, in order. Every method has an empty default.
pub trait PathObserver {
    /// A free flight.
    fn flight(&mut self, _piece: &FlightPiece) {}
    /// A slide along a segment.
    fn slide(&mut self, _piece: &SlidePiece) {}
    /// An impact.
    fn impact(&mut self, _event: &ImpactEvent) {}
}

/// The observer that ignores everything.
impl PathObserver for () {}

/// Keeps every piece: handy for plots and tests, not for large ensembles.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PathRecorder {
    /// The pieces in order.
    pub pieces: Vec<PathPiece>,
}

/// One recorded piece.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PathPiece {
    /// A flight.
    Flight(FlightPiece),
    /// A slide.
    Slide(SlidePiece),
    /// An impact.
    Impact(ImpactEvent),
}

impl PathObserver for PathRecorder {
    fn flight(&mut self, piece: &FlightPiece) {
        self.pieces.push(PathPiece::Flight(*piece));
    }
    fn slide(&mut self, piece: &SlidePiece) {
        self.pieces.push(PathPiece::Slide(*piece));
    }
    fn impact(&mut self, event: &ImpactEvent) {
        self.pieces.push(PathPiece::Impact(*event));
    }
}
