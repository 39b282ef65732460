//! End-point density: the probability per cell that a rock stops there, smoothed with a kernel over a kiddo k-d
//! tree of the end points.
//!
//! Each stopped rock spreads a probability of 1/N (N = all rocks released) with the quartic (biweight) kernel
//! K(d) = 3/(π h²)·(1 − d²/h²)² for d < h, which integrates to one; the cell value is K summed over the end points
//! within h of the cell centre, times the cell area. Summed over all cells it gives the fraction of rocks that
//! stopped on the terrain (exactly in the limit of small cells). The bandwidth h is a setting.

use super::grid::RasterFrame;
use kiddo::{ImmutableKdTree, SquaredEuclidean};

/// Density per cell (row-major, same frame), from end points in the local frame. `n_rocks` is the number released.
pub fn endpoint_density(frame: &RasterFrame, endpoints: &[[f64; 2]], n_rocks: usize, bandwidth_m: f64) -> Vec<f64> {
    let mut out = vec![0.0; frame.len()];
    if endpoints.is_empty() || n_rocks == 0 {
        return out;
    }
    let tree: ImmutableKdTree<f64, 2> = match ImmutableKdTree::new_from_slice(endpoints) {
        Ok(t) => t,
        Err(_) => return out,
    };
    let h2 = bandwidth_m * bandwidth_m;
    let norm = 3.0 / (std::f64::consts::PI * h2) * frame.cell_m * frame.cell_m / n_rocks as f64;
    for (k, v) in out.iter_mut().enumerate() {
        let (x, y) = frame.local_centre(k);
        let hits = tree.query(&[x, y]).within::<SquaredEuclidean<f64>>(h2).execute();
        let mut sum = 0.0;
        for hit in hits {
            let u = 1.0 - hit.distance / h2;
            if u > 0.0 {
                sum += u * u;
            }
        }
        *v = sum * norm;
    }
    out
}
