//! A scenario's rocks: what each one is and where it starts (drawn from its own random stream), and running it.

use crate::error::{Error, Result};
use crate::random::{stream, uniform, Rng};
use crate::rock::{RockBody, RockSize, ShapeKind};
use crate::scenario::{MassSpec, Scenario, ShapeRef};
use crate::sim::{simulate, Observer, Outcome, RigidState, SimParams};
use crate::source::Sources;
use crate::terrain::Terrain;
use nalgebra::Vector3;

/// Everything needed to run any rock of a scenario, shared read-only by all threads.
#[derive(Debug, Clone)]
pub struct Setup {
    /// The terrain.
    pub terrain: Terrain,
    /// Release zones with their rock counts.
    pub sources: Sources,
    /// One reference body per shape entry.
    pub shapes: Vec<RockBody>,
    /// Mass of each rock, when drawn (`None` when the rocks are given by dimensions).
    pub mass: Option<MassSpec>,
    /// Engine settings.
    pub params: SimParams,
    /// Seed of all draws.
    pub seed: u64,
}

/// One rock as drawn: its body and release state.
#[derive(Debug, Clone)]
pub struct RockDraw {
    /// Rock index.
    pub index: usize,
    /// Source index.
    pub source: usize,
    /// Body.
    pub body: RockBody,
    /// Release state.
    pub start: RigidState,
}

/// The end of one rock's run.
#[derive(Debug, Clone)]
pub struct RockRecord {
    /// Rock index.
    pub index: usize,
    /// Source index.
    pub source: usize,
    /// Shape name.
    pub shape: String,
    /// Mass, kg.
    pub mass_kg: f64,
    /// Release position (local frame), m.
    pub release_m: Vector3<f64>,
    /// How it ended.
    pub outcome: Outcome,
    /// Horizontal distance from release to end, m.
    pub runout_m: f64,
}

/// Reference mass of the shape bodies, kg (rocks are scaled from it).
const REFERENCE_MASS_KG: f64 = 1000.0;

impl Setup {
    /// Builds the rock shapes of a scenario; the terrain and sources are given (so callers may share a terrain).
    pub fn new(sc: &Scenario, terrain: Terrain, sources: Sources, seed: u64) -> Result<Setup> {
        let field = format!("{}: rocks", sc.path.display());
        let mut shapes = Vec::new();
        let Some(rocks) = &sc.file.rocks else {
            return Ok(Setup { terrain, sources, shapes, mass: None, params: sc.file.simulation.params.clone(), seed });
        };
        for s in &sc.shapes {
            let kind = match s {
                ShapeRef::Builtin(name) => ShapeKind::builtin(name).ok_or_else(|| {
                    Error::invalid(&field, format!("unknown shape {name}"), "use cube, flat_box or smartie")
                })?,
                ShapeRef::Hull(path) => ShapeKind::Hull {
                    name: path.file_stem().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| "hull".into()),
                    points: crate::io::points::read_hull_points(path)?,
                },
            };
            let size = match (rocks.mass_kg, rocks.dimensions_m) {
                (Some(MassSpec::One(m)), Some(d)) => RockSize::DimensionsAndMass { size_m: d, mass_kg: m },
                (_, Some(d)) => RockSize::Dimensions { size_m: d, density_kg_m3: rocks.density_kg_m3 },
                (_, None) => RockSize::Mass { mass_kg: REFERENCE_MASS_KG, density_kg_m3: rocks.density_kg_m3 },
            };
            shapes.push(RockBody::new(&kind, size, &field)?);
        }
        let mass = if rocks.dimensions_m.is_some() { None } else { rocks.mass_kg };
        Ok(Setup { terrain, sources, shapes, mass, params: sc.file.simulation.params.clone(), seed })
    }

    /// Number of rocks.
    pub fn rock_count(&self) -> usize {
        self.sources.total()
    }

    /// Draws rock `index` and returns it with its random stream, positioned to continue with the run's draws.
    pub fn draw(&self, index: usize) -> (RockDraw, Rng) {
        let mut rng = stream(self.seed, index as u64);
        let source = self.sources.source_of(index);
        let shape_draw = uniform(&mut rng);
        let mass_draw = uniform(&mut rng);
        let body = match &self.sources.sources[source].rock {
            Some(fixed) => fixed.clone(),
            None => {
                // Scenario checks guarantee shapes when a source does not fix its rock.
                let shape = &self.shapes[((shape_draw * self.shapes.len() as f64) as usize).min(self.shapes.len() - 1)];
                match self.mass {
                    Some(MassSpec::One(m)) => shape.with_mass(m),
                    Some(MassSpec::Range([lo, hi])) => {
                        shape.with_mass((lo.ln() + mass_draw * (hi.ln() - lo.ln())).exp())
                    }
                    None => shape.clone(),
                }
            }
        };
        let clear_edges = self.params.terrain_edge_contacts;
        let start = self.sources.release(source, &self.terrain, &body, &mut rng, clear_edges);
        (RockDraw { index, source, body, start }, rng)
    }

    /// Runs rock `index` with `observer`.
    pub fn run_rock(&self, index: usize, observer: &mut impl Observer) -> RockRecord {
        let (draw, rng) = self.draw(index);
        self.run_drawn(draw, rng, observer)
    }

    /// Runs a rock already drawn with [`Setup::draw`] (with the stream it returned) with `observer`.
    pub fn run_drawn(&self, draw: RockDraw, mut rng: Rng, observer: &mut impl Observer) -> RockRecord {
        let index = draw.index;
        let outcome = simulate(&self.terrain, &draw.body, draw.start, &self.params, &mut rng, observer);
        let d = outcome.final_state.position_m - draw.start.position_m;
        RockRecord {
            index,
            source: draw.source,
            shape: draw.body.shape.clone(),
            mass_kg: draw.body.mass_kg,
            release_m: draw.start.position_m,
            outcome,
            runout_m: (d.x * d.x + d.y * d.y).sqrt(),
        }
    }
}
