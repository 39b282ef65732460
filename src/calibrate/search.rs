//! The optimiser: Nelder–Mead on the unit cube of the free parameters, with one restart.
//!
//! Why our own (about 100 lines) rather than a crate such as `argmin`: the objective is a stochastic simulation
//! made smooth by common random numbers, every evaluation costs seconds, and we need a hard evaluation budget,
//! bounds (points are clamped to the cube), the full evaluation history for the report, and bit-identical
//! behaviour on every platform. That is the textbook algorithm (Nelder & Mead 1965, with the standard coefficients
//! of Lagarias et al. 1998: reflection 1, expansion 2, contraction ½, shrink ½) plus clamping; a dependency would
//! add an API layer without adding any of these. The restart from the best point with a half-size simplex is the
//! usual remedy for Nelder–Mead's premature collapse on noisy objectives.

/// The result of a minimisation.
#[derive(Debug, Clone, PartialEq)]
pub struct SearchResult {
    /// Best point (unit cube).
    pub x: Vec<f64>,
    /// Its value.
    pub f: f64,
    /// Objective evaluations used.
    pub evaluations: usize,
    /// Best value after each evaluation.
    pub history: Vec<f64>,
}

struct Budget<'a, F: FnMut(&[f64]) -> f64> {
    f: &'a mut F,
    used: usize,
    max: usize,
    best: (Vec<f64>, f64),
    history: Vec<f64>,
}

impl<F: FnMut(&[f64]) -> f64> Budget<'_, F> {
    fn eval(&mut self, x: &[f64]) -> Option<f64> {
        if self.used >= self.max {
            return None;
        }
        self.used += 1;
        let v = (self.f)(x);
        let v = if v.is_finite() { v } else { f64::INFINITY };
        if v < self.best.1 {
            self.best = (x.to_vec(), v);
        }
        self.history.push(self.best.1);
        Some(v)
    }
}

fn clamp(x: Vec<f64>) -> Vec<f64> {
    x.into_iter().map(|v| v.clamp(0.0, 1.0)).collect()
}

/// Minimises `f` over [0, 1]ⁿ from `x0` with an initial simplex of edge `step`, within `max_evaluations`. Stops
/// when the simplex is smaller than `x_tol` (sup norm) and its values differ by less than `f_tol`, then restarts
/// once from the best point with half the step if evaluations remain.
pub fn nelder_mead<F: FnMut(&[f64]) -> f64>(
    mut f: F,
    x0: &[f64],
    step: f64,
    max_evaluations: usize,
    x_tol: f64,
    f_tol: f64,
) -> SearchResult {
    let mut b = Budget {
        f: &mut f,
        used: 0,
        max: max_evaluations.max(1),
        best: (x0.to_vec(), f64::INFINITY),
        history: Vec::new(),
    };
    let x0 = clamp(x0.to_vec());
    if x0.is_empty() {
        b.eval(&x0);
    } else {
        run(&mut b, &x0, step, x_tol, f_tol);
        if b.used < b.max {
            let start = b.best.0.clone();
            run(&mut b, &start, 0.5 * step, x_tol, f_tol);
        }
    }
    SearchResult { x: b.best.0.clone(), f: b.best.1, evaluations: b.used, history: b.history }
}

fn run<F: FnMut(&[f64]) -> f64>(b: &mut Budget<F>, x0: &[f64], step: f64, x_tol: f64, f_tol: f64) {
    let n = x0.len();
    let mut simplex: Vec<(Vec<f64>, f64)> = Vec::with_capacity(n + 1);
    let Some(f0) = b.eval(x0) else { return };
    simplex.push((x0.to_vec(), f0));
    for i in 0..n {
        let mut x = x0.to_vec();
        x[i] = if x[i] + step <= 1.0 { x[i] + step } else { x[i] - step };
        let x = clamp(x);
        let Some(v) = b.eval(&x) else { return };
        simplex.push((x, v));
    }
    loop {
        simplex.sort_by(|a, c| a.1.total_cmp(&c.1));
        let size = simplex[1..]
            .iter()
            .map(|(x, _)| x.iter().zip(&simplex[0].0).map(|(a, c)| (a - c).abs()).fold(0.0, f64::max))
            .fold(0.0, f64::max);
        let spread = simplex[n].1 - simplex[0].1;
        if size <= x_tol && spread <= f_tol {
            return;
        }
        let centroid: Vec<f64> =
            (0..n).map(|k| simplex[..n].iter().map(|(x, _)| x[k]).sum::<f64>() / n as f64).collect();
        let worst = simplex[n].clone();
        let along = |t: f64| clamp(centroid.iter().zip(&worst.0).map(|(c, w)| c + t * (c - w)).collect());
        let xr = along(1.0);
        let Some(fr) = b.eval(&xr) else { return };
        if fr < simplex[0].1 {
            let xe = along(2.0);
            let Some(fe) = b.eval(&xe) else { return };
            simplex[n] = if fe < fr { (xe, fe) } else { (xr, fr) };
        } else if fr < simplex[n - 1].1 {
            simplex[n] = (xr, fr);
        } else {
            let (xc, limit) = if fr < worst.1 { (along(0.5), fr) } else { (along(-0.5), worst.1) };
            let Some(fc) = b.eval(&xc) else { return };
            if fc < limit {
                simplex[n] = (xc, fc);
            } else {
                let best = simplex[0].0.clone();
                for item in simplex.iter_mut().skip(1) {
                    let x = clamp(best.iter().zip(&item.0).map(|(a, c)| a + 0.5 * (c - a)).collect());
                    let Some(v) = b.eval(&x) else { return };
                    *item = (x, v);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_the_minimum_of_a_quadratic_and_respects_bounds_and_budget() {
        let r = nelder_mead(|x| (x[0] - 0.3).powi(2) + 2.0 * (x[1] - 0.7).powi(2), &[0.5, 0.5], 0.25, 200, 1e-6, 1e-12);
        assert!((r.x[0] - 0.3).abs() < 1e-3 && (r.x[1] - 0.7).abs() < 1e-3, "{:?}", r.x);
        assert!(r.evaluations <= 200);
        assert!(r.history.windows(2).all(|w| w[1] <= w[0]));
        // Minimum outside the cube: lands on the bound.
        let r = nelder_mead(|x| (x[0] - 2.0).powi(2), &[0.5], 0.25, 60, 1e-6, 1e-12);
        assert!((r.x[0] - 1.0).abs() < 1e-9);
        let r = nelder_mead(|x| x[0], &[0.5, 0.5, 0.5], 0.25, 7, 1e-9, 1e-12);
        assert_eq!(r.evaluations, 7);
    }
}
