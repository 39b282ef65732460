//! Release zones: where each rock starts, and its initial velocity and spin.
//!
//! Rocks are dealt to sources in blocks by their index (the first `count₀` rocks from source 0, and so on), and
//! each rock draws its position from its own random stream, so a rock's release never depends on the others.

use crate::error::{Error, Result};
use crate::random::{uniform, uniform_in, Rng};
use crate::rock::{random_orientation, RockBody};
use crate::scenario::{SourceKind, SourceSpec};
use crate::sim::RigidState;
use crate::terrain::Terrain;
use crate::terrain::{horizontal_to_local, point_in_polygon};
use nalgebra::Vector3;

/// Most rocks of a 3D run. Ours: memory does not grow with the rocks ([`crate::run::StatsAccumulator`],
/// [`crate::hazard::EndpointDensity`]), but 10⁷ rocks take hours at a few thousand rocks a second: ten times the
/// largest ensembles hazard maps use. Split a larger ensemble into runs with different seeds.
pub const MAX_ROCKS: usize = 10_000_000;

/// Largest release speed, m/s (ours): a free fall of 510 m, over three times the speeds rockfall codes are made for
/// (at most 30 m/s, physics.md §6); a rock thrown at 10³⁰ m/s never finishes its run.
pub const MAX_RELEASE_SPEED_MPS: f64 = 100.0;

/// Largest release spin, rad/s (ours): the rim of a 0.3 m block spinning at 200 rad/s moves at 30 m/s, as fast as
/// rockfall blocks fly (physics.md §6).
pub const MAX_RELEASE_SPIN_RADPS: f64 = 200.0;

/// Largest release height above the ground, m (ours): a cliff is part of the terrain, not a gap to drop across.
pub const MAX_RELEASE_HEIGHT_M: f64 = 1000.0;

#[derive(Debug, Clone)]
enum Geometry {
    Point([f64; 2]),
    Polyline { pts: Vec<[f64; 2]>, cum: Vec<f64> },
    Polygon { pts: Vec<[f64; 2]>, bbox: [f64; 4] },
    Scatter { triangles: Vec<u32>, cum_area: Vec<f64> },
}

/// One release zone, ready to sample.
#[derive(Debug, Clone)]
pub struct Source {
    /// Name for outputs.
    pub name: String,
    /// Rocks released from it.
    pub count: usize,
    /// The rock released here, when the source fixes it (campaign releases); otherwise drawn from `[rocks]`.
    pub rock: Option<RockBody>,
    /// The exact release (campaign releases): position in the local frame, velocity and spin (world frame).
    pub release: Option<(Vector3<f64>, Vector3<f64>, Vector3<f64>)>,
    geometry: Geometry,
    spec: SourceSpec,
}

/// All release zones of a run.
#[derive(Debug, Clone)]
pub struct Sources {
    /// The zones, in scenario order.
    pub sources: Vec<Source>,
    /// What building them noticed: a polygon partly off the terrain (its rocks start from the part over it).
    pub notes: Vec<String>,
}

impl Sources {
    /// Builds and checks the sources against the terrain. `total` (if given) rescales the counts to that many
    /// rocks in all; `field` locates the sources in errors (e.g. `scenario.toml: sources`).
    pub fn build(specs: &[SourceSpec], terrain: &Terrain, total: Option<usize>, field: &str) -> Result<Sources> {
        let mut sources = Vec::with_capacity(specs.len());
        let mut notes = Vec::new();
        for (i, spec) in specs.iter().enumerate() {
            let f = format!("{field}[{i}]");
            if spec.kind == SourceKind::Campaign {
                let dir = spec
                    .campaign
                    .as_deref()
                    .ok_or_else(|| Error::invalid(format!("{f}.campaign"), "is missing", "give the campaign folder"))?;
                let campaign = crate::campaign::Campaign::read_on(dir, crate::campaign::Ground::Terrain)?;
                for r in &campaign.releases {
                    let body = campaign.body(&campaign.blocks[&r.block_id])?;
                    let p = terrain.from_file_frame(r.position_m);
                    if terrain.surface.at(p.x, p.y).is_none() {
                        return Err(Error::invalid(
                            format!("{f}: run {}", r.trajectory_id),
                            format!("release point {:?} is not over the terrain", r.position_m),
                            "check that the campaign and the terrain share a frame",
                        ));
                    }
                    let v = terrain.up.to_internal(r.velocity_mps);
                    let w = terrain.up.to_internal(r.spin_radps);
                    sources.push(Source {
                        name: r.trajectory_id.clone(),
                        count: spec.repeats.unwrap_or(1),
                        rock: Some(body),
                        release: Some((p, v, w)),
                        geometry: Geometry::Point([p.x, p.y]),
                        spec: spec.clone(),
                    });
                }
                continue;
            }
            let to_local = |p: &[f64; 2]| horizontal_to_local(terrain.up, &terrain.origin, *p);
            let pts: Vec<[f64; 2]> = spec.points.iter().map(to_local).collect();
            let (geometry, area) = match spec.kind {
                SourceKind::Point | SourceKind::Polyline | SourceKind::Campaign => {
                    for (k, p) in pts.iter().enumerate() {
                        if terrain.surface.at(p[0], p[1]).is_none() {
                            return Err(Error::invalid(
                                format!("{f}.points[{k}]"),
                                format!("{:?} is not over the terrain", spec.points[k]),
                                "give coordinates in the terrain's frame, inside its extent (see summary.json of a run, or the terrain's README)",
                            ));
                        }
                    }
                    if spec.kind == SourceKind::Point {
                        (Geometry::Point(pts[0]), 0.0)
                    } else {
                        let mut cum = vec![0.0];
                        for w in pts.windows(2) {
                            cum.push(
                                cum.last().copied().unwrap_or(0.0)
                                    + ((w[1][0] - w[0][0]).powi(2) + (w[1][1] - w[0][1]).powi(2)).sqrt(),
                            );
                        }
                        (Geometry::Polyline { pts, cum }, 0.0)
                    }
                }
                SourceKind::Polygon => {
                    let bbox = crate::terrain::bbox_xy(pts.iter().copied());
                    // Area over the terrain, by a fixed 64 × 64 lattice over the bounding box.
                    let (mut inside, mut covered) = (0usize, 0usize);
                    for a in 0..64 {
                        for b in 0..64 {
                            let x = bbox[0] + (a as f64 + 0.5) / 64.0 * (bbox[2] - bbox[0]);
                            let y = bbox[1] + (b as f64 + 0.5) / 64.0 * (bbox[3] - bbox[1]);
                            if point_in_polygon(x, y, &pts) {
                                inside += 1;
                                covered += terrain.surface.at(x, y).is_some() as usize;
                            }
                        }
                    }
                    // Over a tenth off the terrain is worth a word (ours): its rocks all start from the rest.
                    if covered > 0 && 10 * covered < 9 * inside {
                        notes.push(format!(
                            "{f}.points: {:.0} % of the polygon lies off the terrain; its rocks start from the part \
                             over it",
                            100.0 * (inside - covered) as f64 / inside as f64
                        ));
                    }
                    if covered == 0 {
                        return Err(Error::invalid(
                            format!("{f}.points"),
                            "the polygon does not overlap the terrain",
                            "give coordinates in the terrain's frame, inside its extent",
                        ));
                    }
                    let area = (bbox[2] - bbox[0]) * (bbox[3] - bbox[1]) * covered as f64 / 4096.0;
                    (Geometry::Polygon { pts, bbox }, area)
                }
                SourceKind::Scatter => {
                    let within: Vec<[f64; 2]> = spec.within.iter().flatten().map(to_local).collect();
                    let mat = spec.material.as_ref().and_then(|m| terrain.material_index(m));
                    let mut triangles = Vec::new();
                    let mut cum_area = Vec::new();
                    let mut total_area = 0.0;
                    for t in 0..terrain.triangle_material.len() as u32 {
                        if let Some(m) = mat {
                            if terrain.triangle_material[t as usize] as usize != m {
                                continue;
                            }
                        }
                        let slope = terrain.surface.slope_deg(t);
                        if spec.min_slope_deg.is_some_and(|s| slope < s)
                            || spec.max_slope_deg.is_some_and(|s| slope > s)
                            || slope >= 89.999
                        {
                            continue;
                        }
                        let [a, b, c] = terrain.surface.corners(t);
                        if !within.is_empty() {
                            let centre = (a + b + c) / 3.0;
                            if !point_in_polygon(centre.x, centre.y, &within) {
                                continue;
                            }
                        }
                        total_area += 0.5 * (b - a).cross(&(c - a)).norm();
                        triangles.push(t);
                        cum_area.push(total_area);
                    }
                    if triangles.is_empty() {
                        return Err(Error::invalid(
                            f.clone(),
                            "no terrain triangle matches the scatter selection (material, slope range, polygon)",
                            "widen the slope range, check the material name, or check that `within` overlaps the terrain",
                        ));
                    }
                    (Geometry::Scatter { triangles, cum_area }, total_area)
                }
            };
            let count = match (spec.count, spec.density_per_m2) {
                (Some(c), _) => c,
                (None, Some(d)) => (d * area).round().max(1.0) as usize,
                (None, None) => 0,
            };
            sources.push(Source {
                name: spec.name.clone().unwrap_or_else(|| format!("source_{i}")),
                count,
                rock: None,
                release: None,
                geometry,
                spec: spec.clone(),
            });
        }
        let n = total.unwrap_or_else(|| sources.iter().fold(0usize, |sum, s| sum.saturating_add(s.count)));
        check_rock_count(field, n)?;
        if let Some(n) = total {
            rescale(&mut sources, n);
        }
        if sources.iter().map(|s| s.count).sum::<usize>() == 0 {
            return Err(Error::invalid(
                field,
                "the sources release no rock",
                "give count = N on a source, or --rocks N",
            ));
        }
        Ok(Sources { sources, notes })
    }

    /// Total rocks.
    pub fn total(&self) -> usize {
        self.sources.iter().map(|s| s.count).sum()
    }

    /// The source rock `index` comes from.
    pub fn source_of(&self, index: usize) -> usize {
        let mut acc = 0;
        for (i, s) in self.sources.iter().enumerate() {
            acc += s.count;
            if index < acc {
                return i;
            }
        }
        self.sources.len() - 1
    }

    /// Draws the release state of `rock` from source `s`; with `clear_edges`, clear of the terrain's edges too
    /// ([`place_above_ground`]).
    pub fn release(
        &self,
        s: usize,
        terrain: &Terrain,
        rock: &RockBody,
        rng: &mut Rng,
        clear_edges: bool,
    ) -> RigidState {
        let src = &self.sources[s];
        if let Some((p, v, w)) = src.release {
            return measured_release(terrain, rock, p, v, w, rng, clear_edges);
        }
        let [x, y] = src.sample_xy(terrain, rng);
        let orientation = random_orientation(rng);
        let ground = terrain.surface.at(x, y);
        let z0 = ground.map(|g| g.z_m).unwrap_or(0.0);
        let mut state = RigidState {
            position_m: Vector3::new(x, y, z0),
            velocity_mps: Vector3::zeros(),
            orientation,
            omega_body_radps: Vector3::zeros(),
        };
        place_above_ground(terrain, rock, &mut state, src.spec.height_m, clear_edges);
        if let Some(v) = src.spec.velocity_mps {
            state.velocity_mps = Vector3::new(v[0], v[1], v[2]);
        } else if let Some([lo, hi]) = src.spec.speed_mps {
            let n = ground.map(|g| g.normal).unwrap_or(Vector3::z());
            state.velocity_mps = downslope(&n) * uniform_in(rng, lo, hi);
        }
        if let Some([lo, hi]) = src.spec.spin_radps {
            let axis = random_orientation(rng) * Vector3::z();
            state.omega_body_radps = orientation.inverse_transform_vector(&axis) * uniform_in(rng, lo, hi);
        }
        state
    }
}

impl Source {
    fn sample_xy(&self, terrain: &Terrain, rng: &mut Rng) -> [f64; 2] {
        match &self.geometry {
            Geometry::Point(p) => *p,
            Geometry::Polyline { pts, cum } => {
                let total = *cum.last().unwrap_or(&0.0);
                let d = uniform(rng) * total;
                let k = cum.partition_point(|&c| c <= d).clamp(1, pts.len() - 1);
                let seg = cum[k] - cum[k - 1];
                let f = if seg > 0.0 { (d - cum[k - 1]) / seg } else { 0.0 };
                [pts[k - 1][0] + f * (pts[k][0] - pts[k - 1][0]), pts[k - 1][1] + f * (pts[k][1] - pts[k - 1][1])]
            }
            Geometry::Polygon { pts, bbox } => {
                // Rejection sampling; the polygon is known to overlap the terrain, so this ends.
                let mut last = [bbox[0], bbox[1]];
                for _ in 0..100_000 {
                    let p = [uniform_in(rng, bbox[0], bbox[2]), uniform_in(rng, bbox[1], bbox[3])];
                    last = p;
                    if point_in_polygon(p[0], p[1], pts) && terrain.surface.at(p[0], p[1]).is_some() {
                        return p;
                    }
                }
                last
            }
            Geometry::Scatter { triangles, cum_area } => {
                let total = *cum_area.last().unwrap_or(&0.0);
                let a = uniform(rng) * total;
                let k = cum_area.partition_point(|&c| c <= a).min(triangles.len() - 1);
                let [p, q, r] = terrain.surface.corners(triangles[k]);
                let (mut u, mut v) = (uniform(rng), uniform(rng));
                if u + v > 1.0 {
                    (u, v) = (1.0 - u, 1.0 - v);
                }
                let pt = p + (q - p) * u + (r - p) * v;
                [pt.x, pt.y]
            }
        }
    }
}

/// Refuses more than [`MAX_ROCKS`] rocks in all; `field` locates the sources.
fn check_rock_count(field: &str, n: usize) -> Result<()> {
    if n <= MAX_ROCKS {
        return Ok(());
    }
    Err(Error::invalid(
        field,
        format!("{n} rocks in all is more than the limit of {MAX_ROCKS} rocks a run"),
        "give fewer rocks (--rocks, simulation.rocks, or the sources' count or density_per_m2), or split the \
         ensemble into runs with different seeds (--seed)",
    ))
}

/// Largest-remainder rescaling of source counts to `n` rocks in all (proportional to the counts as given).
fn rescale(sources: &mut [Source], n: usize) {
    let given = sources.iter().any(|s| s.count > 0);
    let weights: Vec<f64> =
        if !given { vec![1.0; sources.len()] } else { sources.iter().map(|s| s.count as f64).collect() };
    let wsum: f64 = weights.iter().sum();
    let exact: Vec<f64> = weights.iter().map(|w| w / wsum * n as f64).collect();
    let mut counts: Vec<usize> = exact.iter().map(|e| e.floor() as usize).collect();
    let mut rest = n - counts.iter().sum::<usize>();
    let mut order: Vec<usize> = (0..sources.len()).collect();
    order.sort_by(|&a, &b| (exact[b] - exact[b].floor()).total_cmp(&(exact[a] - exact[a].floor())).then(a.cmp(&b)));
    for &i in order.iter().cycle() {
        if rest == 0 {
            break;
        }
        counts[i] += 1;
        rest -= 1;
    }
    for (s, c) in sources.iter_mut().zip(counts) {
        s.count = c;
    }
}

/// The unit vector down the steepest slope of a plane with upward normal `n` (along the plane); +x on flat ground.
pub fn downslope(n: &Vector3<f64>) -> Vector3<f64> {
    let d = Vector3::new(n.x * n.z, n.y * n.z, -(n.x * n.x + n.y * n.y));
    d.try_normalize(1e-12).unwrap_or(Vector3::x())
}

/// Lifts a rock so that its lowest vertex is `gap_m` above the ground under it (vertically), checking every
/// vertex against the ground under that vertex; with `clear_edges` (the engine's `terrain_edge_contacts`), also
/// so that every terrain edge under the rock lies `gap_m` below its underside (a ridge between its vertices).
pub fn place_above_ground(terrain: &Terrain, rock: &RockBody, state: &mut RigidState, gap_m: f64, clear_edges: bool) {
    let rot = state.orientation.to_rotation_matrix();
    let mut lift = f64::NEG_INFINITY;
    let c = state.position_m;
    for b in &rock.vertices_m {
        let p = rot * b;
        let ground =
            terrain.surface.height(c.x + p.x, c.y + p.y).or_else(|| terrain.surface.height(c.x, c.y)).unwrap_or(c.z);
        lift = lift.max(ground + gap_m - p.z);
    }
    if clear_edges {
        lift = lift.max(clear_of_edges(terrain, rock, &rot, &c) + gap_m);
    }
    state.position_m.z = lift;
}

/// The lowest height of the centre at (c.x, c.y) that leaves every terrain edge under the rock (oriented `rot`) at
/// or below its underside, the edges sampled every twentieth of the rock's bounding radius (ours).
fn clear_of_edges(terrain: &Terrain, rock: &RockBody, rot: &nalgebra::Rotation3<f64>, c: &Vector3<f64>) -> f64 {
    let r = rock.bounding_radius_m;
    let mut edges = Vec::new();
    terrain.surface.edges_in(c.x - r, c.x + r, c.y - r, c.y + r, &mut edges);
    let vertices = terrain.surface.vertices();
    let up = rot.inverse_transform_vector(&Vector3::z());
    let mut lift = f64::NEG_INFINITY;
    for (ia, ib, _) in edges {
        let (a, b) = (vertices[ia as usize], vertices[ib as usize]);
        let n = ((b - a).xy().norm() / (0.05 * r)).ceil().max(1.0) as usize;
        for k in 0..=n {
            let p = a + (b - a) * (k as f64 / n as f64);
            let offset = rot.inverse_transform_vector(&Vector3::new(p.x - c.x, p.y - c.y, 0.0));
            if let Some(under) = underside(&rock.faces, &offset, &up) {
                lift = lift.max(p.z - under);
            }
        }
    }
    lift
}

/// The lowest t at which the line `b0 + t·e` (body frame) lies inside the hull of outward face planes `faces`
/// (n·x ≤ d inside), or `None` if the line misses the hull.
fn underside(faces: &[(Vector3<f64>, f64)], b0: &Vector3<f64>, e: &Vector3<f64>) -> Option<f64> {
    let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
    for (n, d) in faces {
        let (along, room) = (n.dot(e), d - n.dot(b0));
        if along.abs() < 1e-12 {
            if room < 0.0 {
                return None;
            }
        } else if along > 0.0 {
            hi = hi.min(room / along);
        } else {
            lo = lo.max(room / along);
        }
    }
    (lo <= hi).then_some(lo)
}

/// A measured release (position, velocity and spin in the terrain's internal frame): the centre of mass where it
/// was, in a random orientation, lifted only if that orientation buries a vertex.
pub fn measured_release(
    terrain: &Terrain,
    rock: &RockBody,
    position_m: Vector3<f64>,
    velocity_mps: Vector3<f64>,
    spin_radps: Vector3<f64>,
    rng: &mut Rng,
    clear_edges: bool,
) -> RigidState {
    let orientation = random_orientation(rng);
    let mut state = RigidState {
        position_m,
        velocity_mps,
        orientation,
        omega_body_radps: orientation.inverse_transform_vector(&spin_radps),
    };
    let mut lifted = state;
    place_above_ground(terrain, rock, &mut lifted, 0.0, clear_edges);
    state.position_m.z = state.position_m.z.max(lifted.position_m.z);
    state
}
