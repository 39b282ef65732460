//! The release shared by both models, and which rock (shape, mass) each run is.
//!
//! # The release (ours)
//! The paper does not state how its design-study rocks were released. We release every rock at the top crest,
//! as a mine engineer would check a catch bench against rocks leaving the crest of the face above it:
//! - the centre of mass is `setback_m` behind the crest edge of face 1 (default 0: right above the edge), in the
//!   middle of the 3DRB terrain's width;
//! - the rock's lowest point is `clearance_m` above the crest floor (default 0.1 m; for the 2DLM point mass, the
//!   point itself). 3DRB rocks get a uniformly random orientation (Shoemake 1992) and are lifted so that no vertex
//!   is lower than that above the ground under it;
//! - the velocity is horizontal, towards the slope, with a speed drawn uniformly in `speed_mps` (default 1–2 m/s:
//!   the seed paper's field tests threw or pushed small rocks at 1–2 m/s); no initial spin.
//!
//! Both models draw the speed first from rock i's stream `(seed, i)`, so run i of 2DLM and run i of 3DRB leave
//! the crest at the same speed; and every configuration uses the same streams (common random
//! numbers, physics.md §5), so the differences between bench widths and face angles are not blurred by different
//! draws.
//!
//! # Which rock is run i (ours)
//! A balanced design instead of random draws: shape `i % S` and mass `(i / S) % M` for S shapes and M masses, so
//! 90 runs over 3 shapes and 3 masses give exactly 10 rocks per shape and mass. 2DLM runs `runs` point masses per
//! mass, rock i with mass `i % M` (mass only scales energies and sizes the point for the arrow-height switch).

use crate::random::{uniform, Rng};

/// The start shared by both models, drawn for one rock.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CrestRelease {
    /// x of the centre of mass (the crest of face 1 minus the setback), m.
    pub x_m: f64,
    /// Height of the lowest point above the crest floor, m.
    pub clearance_m: f64,
    /// Horizontal speed towards the slope, m/s.
    pub speed_mps: f64,
}

/// Draws rock `i`'s release speed (the first draw of its stream, always consumed) and sets its position.
pub fn draw_release(
    crest_x_m: f64,
    setback_m: f64,
    clearance_m: f64,
    speed_mps: [f64; 2],
    rng: &mut Rng,
) -> CrestRelease {
    let u = uniform(rng);
    CrestRelease {
        x_m: crest_x_m - setback_m,
        clearance_m,
        speed_mps: speed_mps[0] + u * (speed_mps[1] - speed_mps[0]),
    }
}

/// Index of the shape of run `i` among `n_shapes`.
pub fn shape_index(i: usize, n_shapes: usize) -> usize {
    i % n_shapes.max(1)
}

/// Index of the mass of run `i` among `n_masses`, for `n_shapes` shapes.
pub fn mass_index(i: usize, n_shapes: usize, n_masses: usize) -> usize {
    (i / n_shapes.max(1)) % n_masses.max(1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn balanced_design() {
        let mut cells = [[0usize; 3]; 3];
        for i in 0..90 {
            cells[shape_index(i, 3)][mass_index(i, 3, 3)] += 1;
        }
        assert!(cells.iter().flatten().all(|&c| c == 10), "{cells:?}");
    }
}
