//! Rocks: shapes, sizes and mass properties.

pub mod shape;

pub use shape::{RockBody, RockSize, ShapeKind, DEFAULT_DENSITY_KG_M3};

use crate::random::{uniform, Rng};
use nalgebra::{Quaternion, UnitQuaternion};

/// A uniformly distributed random orientation (Shoemake 1992, "Uniform random rotations").
pub fn random_orientation(rng: &mut Rng) -> UnitQuaternion<f64> {
    let (u1, u2, u3) = (uniform(rng), uniform(rng), uniform(rng));
    let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
    let tau = std::f64::consts::TAU;
    UnitQuaternion::from_quaternion(Quaternion::new(
        b * (tau * u3).cos(),
        a * (tau * u2).sin(),
        a * (tau * u2).cos(),
        b * (tau * u3).sin(),
    ))
}
