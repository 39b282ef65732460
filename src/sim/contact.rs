//! Contacts between a rock and the ground, and the impulses that resolve them.
//!
//! **Detection** (physics.md §8): a hull vertex is in contact when it lies below the surface under it; the normal is
//! that of the triangle there, the depth the distance to its plane. This is RAMMS's vertex-versus-terrain contact
//! (Leine et al. 2014).
//!
//! **Impulses** (physics.md §1.2, §8): all contacts of a step are solved together by projected Gauss–Seidel on the
//! contact impulses, sweeping forward and backward alternately until the impulses stop changing, so that a cube
//! landing flat gets four equal impulses and no spin. Each contact gets:
//! - a Newton restitution target u_n⁺ ≥ −Cr·u_n⁻ when its approach speed −u_n⁻ exceeds the bounce threshold, and
//!   u_n⁺ ≥ 0 otherwise (resting or rolling contact);
//! - Coulomb friction with a stick test (physics.md §1.1, Stronge 2000): the contacts are first solved with the
//!   static cone |P_t| ≤ tan φ_static·P_n; contacts whose friction saturates that cone and still slip are then
//!   solved again with |P_t| = tan φ_dynamic·P_n opposite to their slip. Unlike a slip-speed threshold
//!   (physics.md §8), this test does not depend on the time step: a block resting on a slope below φ_static stays
//!   put whatever Δt is, and a sliding one is braked by φ_dynamic.
//!
//! Newton restitution with friction can create energy (physics.md §1.1), so the solution is checked: if the kinetic
//! energy after the impulses exceeds that before, the step is solved again with Cr = 0, which cannot.

use crate::rock::RockBody;
use nalgebra::{Matrix2, UnitQuaternion, Vector2, Vector3};

/// One vertex–ground contact at the step's midpoint configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    /// Index of the rock's hull vertex; for a terrain edge inside the rock ([`SimParams::terrain_edge_contacts`]),
    /// an index past the hull's vertices that names the edge (from its two terrain vertex indices).
    ///
    /// [`SimParams::terrain_edge_contacts`]: super::SimParams::terrain_edge_contacts
    pub vertex: usize,
    /// World position of the contact point (the vertex, or the deepest point of the terrain edge), m.
    pub point_m: Vector3<f64>,
    /// The contact point in the body frame (the hull vertex itself for a vertex contact), m.
    pub arm_body_m: Vector3<f64>,
    /// Upward unit normal of the ground.
    pub normal: Vector3<f64>,
    /// Penetration depth along the normal, m (≥ 0).
    pub depth_m: f64,
    /// Impulses (normal, tangential in the contact's own basis) to start the solver from: the previous step's
    /// for a contact that persists (warm start), zero otherwise.
    pub warm: (f64, [f64; 2]),
    /// Ground triangle.
    pub triangle: u32,
    /// Restitution coefficient for this contact (after the effects).
    pub cr: f64,
    /// The coefficient as drawn from the material, before the effects (kept while the contact persists).
    pub cr_drawn: f64,
    /// tan of the static friction angle.
    pub mu_static: f64,
    /// tan of the dynamic friction angle.
    pub mu_dynamic: f64,
}

/// Velocities of a rock: centre-of-mass velocity (world) and angular velocity (body frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Velocities {
    /// m/s, world frame.
    pub linear_mps: Vector3<f64>,
    /// rad/s, body frame.
    pub angular_body_radps: Vector3<f64>,
}

impl Velocities {
    /// Kinetic energy, J.
    pub fn kinetic_energy_j(&self, rock: &RockBody) -> f64 {
        let w = &self.angular_body_radps;
        0.5 * rock.mass_kg * self.linear_mps.norm_squared() + 0.5 * w.component_mul(&rock.inertia_kg_m2).dot(w)
    }
}

/// What the solver did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SolveReport {
    /// Sweeps used.
    pub iterations: usize,
    /// True if the energy guard re-solved the step with Cr = 0.
    pub energy_guard: bool,
    /// Largest approach speed −u_n⁻ among the contacts, m/s.
    pub max_approach_mps: f64,
}

/// Solver settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolverSettings {
    /// Approach speed below which no bounce is applied, m/s.
    pub bounce_threshold_mps: f64,
    /// Most sweeps.
    pub max_iterations: usize,
    /// Largest impulse change of a sweep, as a velocity, below which the sweeps stop, m/s.
    pub tolerance_mps: f64,
}

/// Reusable solver memory (one per rock run), so that a step allocates nothing.
#[derive(Debug, Default)]
pub struct Scratch(Vec<Row>);

/// Per-contact rows in body-frame form: u_d = v·d + Ω·J_d for d in (n, t1, t2).
#[derive(Debug)]
struct Row {
    n: Vector3<f64>,
    t1: Vector3<f64>,
    t2: Vector3<f64>,
    jn: Vector3<f64>,
    jt1: Vector3<f64>,
    jt2: Vector3<f64>,
    /// Θ⁻¹ J for each direction.
    mn: Vector3<f64>,
    mt1: Vector3<f64>,
    mt2: Vector3<f64>,
    k_nn: f64,
    k_tt: Matrix2<f64>,
    /// Step of the friction prox iteration, 1/λ_max(K_tt).
    r_t: f64,
    target: f64,
    mu_static: f64,
    mu_dynamic: f64,
    /// The friction coefficient in use: μ_s in the stick pass, μ_d for contacts found slipping.
    mu: f64,
    lambda_n: f64,
    lambda_t: Vector2<f64>,
}

/// Resolves `contacts` for a rock at orientation `q` (the step's midpoint). `before` are the velocities at the start
/// of the step (they set the restitution targets), `free` those after gravity and free rotation over the step.
/// Returns the velocities at the end of the step, and writes the final impulses into each contact's `warm`.
pub fn solve(
    rock: &RockBody,
    q: &UnitQuaternion<f64>,
    contacts: &mut [Contact],
    before: &Velocities,
    free: &Velocities,
    settings: &SolverSettings,
    scratch: &mut Scratch,
) -> (Velocities, SolveReport) {
    let inv_m = 1.0 / rock.mass_kg;
    let inv_i = rock.inertia_kg_m2.map(|v| 1.0 / v);
    let mut max_approach = 0.0f64;
    let rows = &mut scratch.0;
    rows.clear();
    rows.extend(contacts.iter().map(|c| {
        let n = c.normal;
        let t1 = any_perpendicular(&n);
        let t2 = n.cross(&t1);
        let b = c.arm_body_m;
        let to_body = |d: &Vector3<f64>| q.inverse_transform_vector(d);
        let (jn, jt1, jt2) = (b.cross(&to_body(&n)), b.cross(&to_body(&t1)), b.cross(&to_body(&t2)));
        let (mn, mt1, mt2) = (jn.component_mul(&inv_i), jt1.component_mul(&inv_i), jt2.component_mul(&inv_i));
        let k_nn = inv_m + jn.dot(&mn);
        let k_tt = Matrix2::new(inv_m + jt1.dot(&mt1), jt1.dot(&mt2), jt2.dot(&mt1), inv_m + jt2.dot(&mt2));
        // Largest eigenvalue of the symmetric 2×2 K_tt.
        let (a, b, d) = (k_tt[(0, 0)], 0.5 * (k_tt[(0, 1)] + k_tt[(1, 0)]), k_tt[(1, 1)]);
        let lambda_max = 0.5 * (a + d) + (0.25 * (a - d) * (a - d) + b * b).sqrt();
        let r_t = 1.0 / lambda_max;
        let u = |v: &Velocities, d: &Vector3<f64>, j: &Vector3<f64>| v.linear_mps.dot(d) + v.angular_body_radps.dot(j);
        let un = u(before, &n, &jn);
        max_approach = max_approach.max(-un);
        let target = if -un > settings.bounce_threshold_mps { -c.cr * un } else { 0.0 };
        let (wn, wt) = c.warm;
        let lambda_t = Vector2::new(wt[0], wt[1]);
        let lambda_n = wn.max(0.0);
        Row {
            n,
            t1,
            t2,
            jn,
            jt1,
            jt2,
            mn,
            mt1,
            mt2,
            k_nn,
            k_tt,
            r_t,
            target,
            mu_static: c.mu_static,
            mu_dynamic: c.mu_dynamic,
            mu: c.mu_static,
            lambda_n,
            lambda_t,
        }
    }));
    let (mut after, mut iterations) = sweep(rows, free, inv_m, settings);
    // Contacts whose friction saturated the static cone and still slip: dynamic friction, solved again.
    let mut slipping = false;
    for r in rows.iter_mut() {
        let slip = Vector2::new(
            after.linear_mps.dot(&r.t1) + after.angular_body_radps.dot(&r.jt1),
            after.linear_mps.dot(&r.t2) + after.angular_body_radps.dot(&r.jt2),
        );
        if r.mu_dynamic < r.mu_static
            && slip.norm() > SLIP_MPS
            && r.lambda_t.norm() >= r.mu_static * r.lambda_n * (1.0 - 1e-9)
        {
            r.mu = r.mu_dynamic;
            slipping = true;
        }
    }
    if slipping {
        let (again, it) = sweep(rows, free, inv_m, settings);
        after = again;
        iterations += it;
    }
    let mut report = SolveReport { iterations, energy_guard: false, max_approach_mps: max_approach };
    let e_free = free.kinetic_energy_j(rock);
    if after.kinetic_energy_j(rock) > e_free * (1.0 + 1e-12) + 1e-12 {
        for r in rows.iter_mut() {
            r.target = 0.0;
            r.lambda_n = 0.0;
            r.lambda_t = Vector2::zeros();
        }
        let (again, it2) = sweep(rows, free, inv_m, settings);
        report.iterations += it2;
        report.energy_guard = true;
        after = again;
    }
    for (c, r) in contacts.iter_mut().zip(rows.iter()) {
        c.warm = (r.lambda_n, [r.lambda_t.x, r.lambda_t.y]);
    }
    (after, report)
}

/// Slip speed left by the static pass above which a saturated contact counts as slipping, m/s (ours): 1 mm/s, far
/// above the solver's residual and below any slip that matters over a step.
const SLIP_MPS: f64 = 1e-3;

fn sweep(rows: &mut [Row], free: &Velocities, inv_m: f64, settings: &SolverSettings) -> (Velocities, usize) {
    let mut v = free.linear_mps;
    let mut w = free.angular_body_radps;
    // Apply the warm-start impulses.
    for r in rows.iter() {
        v += (r.n * r.lambda_n + r.t1 * r.lambda_t.x + r.t2 * r.lambda_t.y) * inv_m;
        w += r.mn * r.lambda_n + r.mt1 * r.lambda_t.x + r.mt2 * r.lambda_t.y;
    }
    let n = rows.len();
    let mut used = 0;
    for it in 0..settings.max_iterations {
        used = it + 1;
        let mut change = 0.0f64;
        for k in 0..n {
            let r = if it % 2 == 0 { &mut rows[k] } else { &mut rows[n - 1 - k] };
            // Normal impulse.
            let un = v.dot(&r.n) + w.dot(&r.jn);
            let new_n = (r.lambda_n + (r.target - un) / r.k_nn).max(0.0);
            let dn = new_n - r.lambda_n;
            r.lambda_n = new_n;
            v += r.n * (dn * inv_m);
            w += r.mn * dn;
            // Friction impulse: a proximal step λ_t ← prox_{|λ_t| ≤ μ λ_n}(λ_t − r·u_t) with r = 1/λ_max(K_tt)
            // (Leine et al. 2014, physics.md §1.2). Its fixed point is exact Coulomb friction: sticking inside the
            // cone, or sliding with |λ_t| = μ λ_n opposite to the slip (maximal dissipation).
            let ut = Vector2::new(v.dot(&r.t1) + w.dot(&r.jt1), v.dot(&r.t2) + w.dot(&r.jt2));
            let mut lt = r.lambda_t - ut * r.r_t;
            let cap = r.mu * r.lambda_n;
            let norm = lt.norm();
            if norm > cap {
                lt *= cap / norm;
            }
            let dt = lt - r.lambda_t;
            r.lambda_t = lt;
            v += (r.t1 * dt.x + r.t2 * dt.y) * inv_m;
            w += r.mt1 * dt.x + r.mt2 * dt.y;
            change = change.max(dn.abs() * r.k_nn).max((r.k_tt * dt).norm());
        }
        if change <= settings.tolerance_mps {
            break;
        }
    }
    (Velocities { linear_mps: v, angular_body_radps: w }, used)
}

/// A unit vector perpendicular to unit `n`.
pub(crate) fn any_perpendicular(n: &Vector3<f64>) -> Vector3<f64> {
    let a = if n.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() };
    (a - n * n.dot(&a)).normalize()
}
