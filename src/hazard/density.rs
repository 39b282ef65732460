//! End-point density: the probability per cell that a rock stops there, smoothed with a kernel over a kiddo k-d
//! tree of the end points.
//!
//! Each stopped rock spreads a probability of 1/N (N = all rocks released) with the quartic (biweight) kernel
//! K(d) = 3/(π h²)·(1 − d²/h²)² for d < h, which integrates to one; the cell value is K summed over the end points
//! within h of the cell centre, times the cell area. Summed over all cells it gives the fraction of rocks that
//! stopped on the terrain (exactly in the limit of small cells). The bandwidth h is a setting.

use super::grid::RasterFrame;
use kiddo::{ImmutableKdTree, SquaredEuclidean};

/// End points held before their kernels are added to the cells (ours): up to this many rocks the density is one
/// k-d tree over all of them; a larger run adds them in batches of this size, so memory does not grow with the run.
pub const ENDPOINT_BATCH: usize = 100_000;

/// The end-point density of a run, accumulated while simulating: end points are held in a batch of at most
/// [`ENDPOINT_BATCH`], whose kernel sums are added to the cells (over a k-d tree of the batch) when it is full and
/// at the end. The same sums as one tree over every end point, added in batches.
#[derive(Debug, Clone)]
pub struct EndpointDensity {
    frame: RasterFrame,
    bandwidth_m: f64,
    batch: Vec<[f64; 2]>,
    sums: Vec<f64>,
}

impl EndpointDensity {
    /// An empty density over `frame` with kernel bandwidth `bandwidth_m`.
    pub fn new(frame: &RasterFrame, bandwidth_m: f64) -> Self {
        EndpointDensity { frame: *frame, bandwidth_m, batch: Vec::new(), sums: vec![0.0; frame.len()] }
    }

    /// Adds the end point of a rock that stopped, local frame.
    pub fn add(&mut self, p: [f64; 2]) {
        self.batch.push(p);
        if self.batch.len() >= ENDPOINT_BATCH {
            self.flush();
        }
    }

    /// Adds the batch's kernel sums (Σ (1 − d²/h²)² over its points within h of each cell centre) to the cells.
    fn flush(&mut self) {
        if self.batch.is_empty() {
            return;
        }
        if let Ok(tree) = ImmutableKdTree::<f64, 2>::new_from_slice(&self.batch) {
            let h2 = self.bandwidth_m * self.bandwidth_m;
            for (k, v) in self.sums.iter_mut().enumerate() {
                let (x, y) = self.frame.local_centre(k);
                let hits = tree.query(&[x, y]).within::<SquaredEuclidean<f64>>(h2).execute();
                let mut sum = 0.0;
                for hit in hits {
                    let u = 1.0 - hit.distance / h2;
                    if u > 0.0 {
                        sum += u * u;
                    }
                }
                *v += sum;
            }
        }
        self.batch.clear();
    }

    /// Density per cell (row-major, the frame's), `n_rocks` the number of rocks released.
    pub fn finish(mut self, n_rocks: usize) -> Vec<f64> {
        self.flush();
        if n_rocks == 0 {
            return vec![0.0; self.sums.len()];
        }
        let h2 = self.bandwidth_m * self.bandwidth_m;
        let norm = 3.0 / (std::f64::consts::PI * h2) * self.frame.cell_m * self.frame.cell_m / n_rocks as f64;
        self.sums.iter().map(|s| s * norm).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn batches_add_up_to_the_kernel_sum_over_every_end_point() {
        // 5 × 4 cells of 2 m; 2.5 batches of end points spread over them and a little beyond.
        let frame = RasterFrame { ncols: 5, nrows: 4, cell_m: 2.0, x_min_m: 0.0, y_max_m: 8.0, origin_xy: [0.0, 0.0] };
        let h = 3.0;
        let n = 2 * ENDPOINT_BATCH + ENDPOINT_BATCH / 2;
        let point =
            |i: usize| [-1.0 + 12.0 * ((i as f64 * 0.618_034) % 1.0), -1.0 + 10.0 * ((i as f64 * 0.414_214) % 1.0)];
        let mut d = EndpointDensity::new(&frame, h);
        (0..n).for_each(|i| d.add(point(i)));
        let density = d.finish(2 * n);
        let norm = 3.0 / (std::f64::consts::PI * h * h) * 4.0 / (2 * n) as f64;
        for (k, v) in density.iter().enumerate() {
            let (x, y) = frame.local_centre(k);
            let exact: f64 = (0..n)
                .map(|i| {
                    let p = point(i);
                    (1.0 - ((p[0] - x).powi(2) + (p[1] - y).powi(2)) / (h * h)).max(0.0).powi(2)
                })
                .sum::<f64>()
                * norm;
            assert!((v - exact).abs() < 1e-9 * exact, "cell {k}: {v} against {exact}");
        }
        // Half the rocks stopped, nearly all of them over the frame: the cells hold about half the probability.
        let total: f64 = density.iter().sum();
        assert!(total > 0.3 && total < 0.5, "{total}");
    }
}
