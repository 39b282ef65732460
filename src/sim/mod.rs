//! The 3D rigid-body (3DRB) engine: one rock at a time, many rocks in parallel.

pub mod barrier;
pub mod body;
pub mod contact;
pub mod params;
pub mod rockfall;

pub use barrier::{Barrier, BarrierHit};
pub use body::RigidState;
pub use params::{CrDraw, Effects, SimParams, MAX_SOLVER_TOLERANCE_MPS};
pub use rockfall::{simulate, Impact, Observer, Outcome, Sample, StopReason, GRAVITY_MPS2};
