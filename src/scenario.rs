//! The 3DRB scenario file (TOML): what terrain, which materials, where rocks start, what rocks, and how to run.
//!
//! Reading happens in two stages, as in ripgrep: [`ScenarioFile`] is the file as written (serde, unknown keys are
//! errors that name the key), and [`ScenarioFile::resolve`] checks every value and turns relative paths into paths
//! next to the scenario file. Nothing is simulated until the whole scenario has been checked.
//!
//! ```toml
//! [terrain]
//! files = ["../meshes/bench_stack/bench_stack.obj"]
//! materials_by = "group"          # group | material | file | slope | single
//!
//! [materials.face]
//! preset = "face_all"             # the seed paper's Table 2 rows
//! [materials.floor]
//! preset = "floor_all"
//!
//! [[sources]]
//! type = "scatter"                # point | polyline | polygon | scatter
//! material = "face"
//! count = 1000
//!
//! [rocks]
//! shapes = ["cube", "flat_box", "smartie"]
//! mass_kg = [100.0, 10000.0]
//!
//! [simulation]
//! seed = 1
//!
//! [output]
//! cell_size_m = 2.0
//! ```

use crate::campaign::MAX_BLOCK_SIZE_M;
use crate::error::{number_text, Error, Result};
use crate::random::TruncNormal;
use crate::sim::SimParams;
use crate::source::{MAX_RELEASE_HEIGHT_M, MAX_RELEASE_SPEED_MPS, MAX_RELEASE_SPIN_RADPS};
use crate::terrain::{Material, UpAxis};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A scenario as written in its TOML file.
#[derive(Debug, Clone, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct ScenarioFile {
    /// A title for reports.
    #[serde(default)]
    pub title: String,
    /// The terrain.
    pub terrain: TerrainSpec,
    /// Materials by name.
    pub materials: BTreeMap<String, MaterialSpec>,
    /// Release zones.
    pub sources: Vec<SourceSpec>,
    /// The rocks (not needed when every source is a campaign, whose releases name their blocks).
    pub rocks: Option<RockSpec>,
    /// Engine settings and seed.
    #[serde(default)]
    pub simulation: SimulationSpec,
    /// Output settings.
    #[serde(default)]
    pub output: OutputSpec,
    /// Barriers standing on the terrain.
    #[serde(default)]
    pub barriers: Vec<BarrierSpec>,
    /// Data collector lines ([`crate::collector`]).
    #[serde(default)]
    pub collectors: Vec<crate::collector::CollectorSpec>,
    /// Hazard zone thresholds ([`crate::zones`]).
    #[serde(default)]
    pub hazard_zones: crate::zones::ZoneSettings,
    /// Settings of `talus barrier` ([`crate::barrier`]).
    #[serde(default)]
    pub barrier_design: crate::barrier::DesignSpec,
}

/// `[[barriers]]`: a flexible barrier (fence) in the simulation.
#[derive(Debug, Clone, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct BarrierSpec {
    /// Name for outputs (default: `barrier_N`).
    pub name: Option<String>,
    /// Polyline vertices (x, y) in the terrain's horizontal frame.
    pub line: Vec<[f64; 2]>,
    /// Height above the ground, m.
    pub height_m: f64,
    /// Energy capacity, kJ.
    pub capacity_kj: f64,
}

/// How materials are assigned to terrain triangles.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum MaterialsBy {
    /// One material for everything (the only one defined, or the one named `default`).
    #[default]
    Single,
    /// By OBJ object or group name.
    Group,
    /// By OBJ `usemtl` material name.
    Material,
    /// By file: each file's stem names its material (a quarry split into zone files).
    File,
    /// By slope: faces steeper than `slope_face_deg` are `face`, the rest `floor`.
    Slope,
}

impl MaterialsBy {
    /// The name as written in a scenario (`materials_by = "group"`).
    pub fn as_str(self) -> &'static str {
        match self {
            MaterialsBy::Single => "single",
            MaterialsBy::Group => "group",
            MaterialsBy::Material => "material",
            MaterialsBy::File => "file",
            MaterialsBy::Slope => "slope",
        }
    }
}

/// `[terrain]`.
#[derive(Debug, Clone, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct TerrainSpec {
    /// Terrain files (OBJ, STL, GeoTIFF `.tif`/`.tiff`, ESRI ASCII `.asc`), relative to the scenario file. Several
    /// files form one surface.
    pub files: Vec<PathBuf>,
    /// Which axis is up in the files (default: z).
    #[serde(default)]
    pub up: UpAxis,
    /// EPSG code of the CRS, for outputs (default: taken from a GeoTIFF DEM, if any).
    #[serde(default)]
    pub crs_epsg: Option<u32>,
    /// How triangles get their materials (default: single).
    #[serde(default)]
    pub materials_by: MaterialsBy,
    /// With `materials_by = "slope"`: faces steeper than this are `face`, degrees (default:
    /// [`DEFAULT_SLOPE_FACE_DEG`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub slope_face_deg: Option<f64>,
    /// Renames: group, material or file name → material name (default: the same name).
    #[serde(default)]
    pub material_names: BTreeMap<String, String>,
    /// Polygons that override the material of the ground inside them, applied in order (the triangles their edges
    /// cross are split along them, as for `clip`, so a zone ends exactly on its polygon).
    #[serde(default)]
    pub zones: Vec<ZoneSpec>,
    /// Keep only the part of the terrain inside this polygon (x, y in the files' horizontal frame; the triangles its
    /// edges cross are split along them, [`crate::terrain::split`]): the part of the files where the surface is
    /// known, for DEMs with padded or extrapolated margins. A rock that crosses its edge leaves the terrain (default:
    /// keep everything).
    #[serde(default)]
    pub clip: Option<Vec<[f64; 2]>>,
    /// Outside this polygon each vertex takes the height of the nearest vertex inside it (x, y in the files'
    /// horizontal frame): the known ground continued level past its edge, for DEMs whose margins are extrapolated
    /// by a trend the ground does not follow. Unlike `clip`, rocks go on across the edge (default: heights as in
    /// the files).
    #[serde(default, deserialize_with = "level_polygon")]
    pub level_beyond: Option<Vec<[f64; 2]>>,
}

/// `level_beyond` of a scenario: a polygon. A word is refused with what to write instead: `"field"` is a calibration
/// setting ([`crate::calibrate::config::LevelBeyond`]), the box of the field's runs, which a scenario has not got.
fn level_polygon<'de, D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Option<Vec<[f64; 2]>>, D::Error> {
    #[derive(Deserialize)]
    #[serde(untagged, expecting = "expected a polygon [[x, y], ...]")]
    enum Raw {
        Polygon(Vec<[f64; 2]>),
        Word(String),
    }
    match Raw::deserialize(d)? {
        Raw::Polygon(p) => Ok(Some(p)),
        Raw::Word(w) => Err(serde::de::Error::custom(format!(
            "`{w}` is not a polygon: a scenario levels past a polygon [[x, y], ...] (`\"field\"` is for `talus \
             calibrate` settings; the `calibrated.toml` a calibration writes gives the polygon it drew)"
        ))),
    }
}

/// The slope that parts `face` from `floor` with `materials_by = "slope"` when `slope_face_deg` is not given,
/// degrees (ours).
pub const DEFAULT_SLOPE_FACE_DEG: f64 = 45.0;

/// `[[terrain.zones]]`: a polygon of another material.
#[derive(Debug, Clone, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct ZoneSpec {
    /// Material name.
    pub material: String,
    /// Polygon vertices (x, y) in the terrain's horizontal frame.
    pub polygon: Vec<[f64; 2]>,
}

/// `[materials.NAME]`: a Table 2 preset, explicit values, or a preset with some values overridden.
#[derive(Debug, Clone, Default, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    /// One of `floor_bench`, `floor_haul_road`, `floor_all`, `face_weathered`, `face_fresh`, `face_all`.
    pub preset: Option<String>,
    /// Mean coefficient of restitution.
    pub cr_mean: Option<f64>,
    /// Its standard deviation.
    pub cr_sd: Option<f64>,
    /// Lower truncation (default: max(0, mean − 3 sd)).
    pub cr_min: Option<f64>,
    /// Upper truncation (default: min(1, mean + 3 sd)).
    pub cr_max: Option<f64>,
    /// Static friction angle, degrees.
    pub static_friction_deg: Option<f64>,
    /// Dynamic friction angle, degrees.
    pub dynamic_friction_deg: Option<f64>,
    /// Spread of the dynamic friction angle between rocks, degrees (default 0: none; see
    /// [`Material::dynamic_friction_sd_deg`]).
    pub dynamic_friction_sd_deg: Option<f64>,
    /// Soft-ground drag rate while in contact, 1/s (default 0: none).
    pub drag_per_s: Option<f64>,
}

/// `[[sources]]`.
#[derive(Debug, Clone, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct SourceSpec {
    /// A name for outputs (default: `source_N`).
    pub name: Option<String>,
    /// `point`, `polyline`, `polygon` or `scatter`.
    #[serde(rename = "type")]
    pub kind: SourceKind,
    /// Vertices (x, y) for point (one), polyline and polygon sources.
    #[serde(default)]
    pub points: Vec<[f64; 2]>,
    /// Scatter: only triangles of this material.
    pub material: Option<String>,
    /// Scatter: only triangles at least this steep, degrees.
    pub min_slope_deg: Option<f64>,
    /// Scatter: only triangles at most this steep, degrees.
    pub max_slope_deg: Option<f64>,
    /// Scatter: only inside this polygon.
    pub within: Option<Vec<[f64; 2]>>,
    /// Number of rocks from this source.
    pub count: Option<usize>,
    /// Polygon and scatter: rocks per m² of horizontal area instead of a count.
    pub density_per_m2: Option<f64>,
    /// Gap between the rock's lowest point and the ground at release, m (default: 0.1).
    #[serde(default = "default_height_m")]
    pub height_m: f64,
    /// A fixed initial velocity (vx, vy, vz), m/s.
    pub velocity_mps: Option<[f64; 3]>,
    /// Or an initial speed range [min, max], m/s, pointing down the steepest slope under the release point.
    pub speed_mps: Option<[f64; 2]>,
    /// Initial spin magnitude range [min, max], rad/s, about a random axis (default: none).
    pub spin_radps: Option<[f64; 2]>,
    /// Campaign sources: the campaign folder (relative to the scenario), whose releases become point sources with
    /// their own blocks, positions, velocities and spins.
    pub campaign: Option<PathBuf>,
    /// Campaign sources: rocks per release (default: 1).
    pub repeats: Option<usize>,
}

fn default_height_m() -> f64 {
    0.1
}

/// Source geometry.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SourceKind {
    /// One point.
    Point,
    /// Uniformly along a polyline.
    Polyline,
    /// Uniformly over a polygon's horizontal area.
    Polygon,
    /// Uniformly over the surface area of the triangles selected by material, slope and polygon.
    Scatter,
    /// The releases of a field campaign (see [`crate::campaign`]).
    Campaign,
}

/// `[rocks]`.
#[derive(Debug, Clone, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct RockSpec {
    /// Shapes, drawn uniformly per rock: `cube`, `flat_box`, `smartie`, or a hull file (OBJ, STL or points).
    pub shapes: Vec<String>,
    /// Mass, kg: one value, or [min, max] drawn log-uniformly per rock.
    pub mass_kg: Option<MassSpec>,
    /// Or bounding dimensions (a, b, c), m; with one `mass_kg` as well, the density is set to match it.
    pub dimensions_m: Option<[f64; 3]>,
    /// Density, kg/m³ (default: 2650).
    #[serde(default = "default_density")]
    pub density_kg_m3: f64,
}

fn default_density() -> f64 {
    crate::rock::DEFAULT_DENSITY_KG_M3
}

/// The largest block mass a scenario may give, kg. Ours: about 370,000 m³ of rock, far beyond rockfall (rock
/// avalanches move as a mass, not as one rigid block), and far below where the engine's numbers overflow (10³⁰⁰ kg
/// gave infinite bounce heights).
pub const MAX_ROCK_MASS_KG: f64 = 1e9;

/// The smallest block mass a scenario or campaign may give, kg. Ours: 1 kg is a block of about 7 cm, where rockfall
/// hazard begins (about 10 cm), and the engine's fixed lengths (2 mm of penetration left uncorrected, a 5 cm flight
/// margin) stay small against it; 10⁻³⁰⁰ kg ended at NaN. (Blocks of a few centimetres also gained energy, a 0.03 kg
/// flat box 257 kJ of the 38 J its drop on the bench stack holds, until the free rotation split the steps Newton's
/// method does not converge on: [`crate::sim::body::free_rotation`].)
pub const MIN_ROCK_MASS_KG: f64 = 1.0;

/// The smallest side of a block given by its dimensions, m (ours, for the same reason as [`MIN_ROCK_MASS_KG`]).
pub const MIN_ROCK_SIZE_M: f64 = 0.05;

/// One mass or a range.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, serde::Serialize)]
#[serde(untagged, expecting = "a mass in kg (a number) or a range [min, max]")]
pub enum MassSpec {
    /// A fixed mass.
    One(f64),
    /// [min, max], drawn log-uniformly.
    Range([f64; 2]),
}

/// `[simulation]`: the seed, an optional total rock count and the engine settings.
#[derive(Debug, Clone, Default, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct SimulationSpec {
    /// Seed of all random draws (default: 1).
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// Total rocks; if set, the sources' counts are scaled to it.
    pub rocks: Option<usize>,
    /// Threads (default: all cores).
    pub threads: Option<usize>,
    /// Engine settings.
    #[serde(flatten)]
    pub params: SimParams,
}

fn default_seed() -> u64 {
    1
}

/// `[output]`.
#[derive(Debug, Clone, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct OutputSpec {
    /// Raster cell size, m (default: 2).
    pub cell_size_m: f64,
    /// Kernel radius of the end-point density, m (default: 2 cells).
    pub endpoint_bandwidth_m: Option<f64>,
    /// Paths of this many rocks (the first ones) as CSV, VTK and GeoJSON (default: 0).
    pub paths: usize,
    /// Also write every raster as an ESRI ASCII grid (`.asc`, with `.prj` when the CRS WKT is known).
    pub ascii_grids: bool,
    /// Put the raster cell edges on the terrain DEM's cell edges instead of on multiples of the cell size, so
    /// that with the DEM's cell size the rasters match its cells one for one (default: false).
    pub align_to_dem: bool,
}

impl Default for OutputSpec {
    fn default() -> Self {
        OutputSpec { cell_size_m: 2.0, endpoint_bandwidth_m: None, paths: 0, ascii_grids: false, align_to_dem: false }
    }
}

/// A checked scenario with absolute paths and built materials.
#[derive(Debug, Clone)]
pub struct Scenario {
    /// The scenario file.
    pub path: PathBuf,
    /// As written, with overrides applied (for the run manifest).
    pub file: ScenarioFile,
    /// Terrain files, absolute.
    pub terrain_files: Vec<PathBuf>,
    /// Materials, in name order.
    pub materials: Vec<Material>,
    /// Rock shape entries: built-in name or absolute hull path.
    pub shapes: Vec<ShapeRef>,
}

/// A rock shape as the scenario names it.
#[derive(Debug, Clone, PartialEq)]
pub enum ShapeRef {
    /// `cube`, `flat_box` or `smartie`.
    Builtin(String),
    /// A hull file.
    Hull(PathBuf),
}

/// The keys of `[simulation]`, quoted as serde lists expected keys.
fn simulation_keys() -> String {
    let params = serde_json::to_value(SimParams::default()).unwrap_or_default();
    let engine = params.as_object().into_iter().flat_map(|m| m.keys().cloned());
    let keys: Vec<String> = ["seed", "rocks", "threads"].map(String::from).into_iter().chain(engine).collect();
    keys.iter().map(|k| format!("`{k}`")).collect::<Vec<_>>().join(", ")
}

impl ScenarioFile {
    /// Reads and parses `path` (no checks beyond the TOML structure).
    pub fn read(path: &Path) -> Result<ScenarioFile> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        toml::from_str(&text).map_err(|e| {
            let location = crate::io::toml_location(&text, &path.display().to_string(), &e);
            let mut message = crate::io::toml_message(&text, &e);
            // [simulation] is the only table with flattened keys, where serde cannot list the keys it expects.
            if message.starts_with("unknown field") && !message.contains("expected") {
                message.push_str(&format!(", expected one of {}", simulation_keys()));
            }
            Error::format(
                location,
                message,
                "see the scenario format in README.md, \"Scenario files\" ([[collectors]], [hazard_zones] and \
                 [barrier_design] in docs/barrier.md); keys are case-sensitive",
            )
        })
    }

    /// Checks what a model carries onto another site ([`crate::envelope::on_site`]: `talus envelope --site`,
    /// `talus barrier --models`), its materials and its `[simulation]` engine settings (effects included), as
    /// [`ScenarioFile::resolve`] does, naming the model's file at `path` in errors: resolved on the site, they
    /// would be named by the site's file.
    pub fn check_carried(&self, path: &Path) -> Result<()> {
        let f = |k: &str| format!("{}: {k}", path.display());
        for (name, spec) in &self.materials {
            spec.build(name, &f(&format!("materials.{name}")))?;
        }
        self.check_soft_materials(&f)?;
        let mut params = self.simulation.params.clone();
        params.effects.fill_defaults();
        params.validate(&f("simulation."))
    }

    /// Refuses a `simulation.effects.soft_materials` entry that names no material; `f` makes a field's name.
    fn check_soft_materials(&self, f: &dyn Fn(&str) -> String) -> Result<()> {
        for (i, m) in self.simulation.params.effects.soft_materials.iter().enumerate() {
            if !self.materials.contains_key(m) {
                return Err(Error::invalid(
                    f(&format!("simulation.effects.soft_materials[{i}]")),
                    format!("'{m}' is not defined (the soft-ground drag would apply nowhere)"),
                    format!(
                        "use one of: {} (or leave soft_materials out: the drag then applies on every material)",
                        self.materials.keys().cloned().collect::<Vec<_>>().join(", ")
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Checks every value and resolves paths relative to the scenario file at `path`.
    pub fn resolve(self, path: &Path) -> Result<Scenario> {
        let base = path.parent().unwrap_or(Path::new("."));
        let f = |k: &str| format!("{}: {k}", path.display());
        if self.terrain.files.is_empty() {
            return Err(Error::invalid(f("terrain.files"), "is empty", "list at least one terrain file"));
        }
        let terrain_files: Vec<PathBuf> = self.terrain.files.iter().map(|p| base.join(p)).collect();
        for (i, p) in terrain_files.iter().enumerate() {
            if p.is_dir() {
                return Err(Error::invalid(
                    f(&format!("terrain.files[{i}]")),
                    format!("{} is a folder, not a terrain file", p.display()),
                    "list the terrain files themselves (.obj, .stl, .tif/.tiff or .asc), not the folder that holds \
                     them",
                ));
            }
            if !p.is_file() {
                return Err(Error::invalid(
                    f(&format!("terrain.files[{i}]")),
                    format!("{} does not exist", p.display()),
                    "paths are relative to the scenario file",
                ));
            }
        }
        if let Some(code) = self.terrain.crs_epsg.filter(|c| !crate::io::geotiff::EPSG_CODES.contains(c)) {
            return Err(Error::invalid(
                f("terrain.crs_epsg"),
                format!("EPSG code {code} cannot be stored in a GeoTIFF (1 to 32766)"),
                "use the EPSG code of a projected or geographic CRS, e.g. 2056 (Swiss LV95), or leave the key out",
            ));
        }
        if let Some(deg) = self.terrain.slope_face_deg.filter(|d| !(*d > 0.0 && *d < 90.0)) {
            return Err(Error::invalid(
                f("terrain.slope_face_deg"),
                format!("must be in (0, 90), got {deg}"),
                "use e.g. 45",
            ));
        }
        if self.materials.is_empty() {
            return Err(Error::invalid(
                f("materials"),
                "no material is defined",
                "add e.g. [materials.default] with preset = \"face_all\"",
            ));
        }
        let mut materials = Vec::new();
        for (name, spec) in &self.materials {
            materials.push(spec.build(name, &f(&format!("materials.{name}")))?);
        }
        let known = |m: &str| self.materials.contains_key(m);
        let defined = || self.materials.keys().cloned().collect::<Vec<_>>().join(", ");
        for (from, to) in &self.terrain.material_names {
            if !known(to) {
                return Err(Error::invalid(
                    f(&format!("terrain.material_names.{from}")),
                    format!("names material '{to}', which is not defined"),
                    format!("define [materials.{to}] or use one of: {}", defined()),
                ));
            }
        }
        if self.terrain.materials_by == MaterialsBy::Slope {
            for m in ["face", "floor"] {
                if !known(m) {
                    return Err(Error::invalid(
                        f("materials"),
                        format!("materials_by = \"slope\" needs a material named '{m}'"),
                        format!("add [materials.{m}]"),
                    ));
                }
            }
        }
        if self.terrain.materials_by == MaterialsBy::Single && self.materials.len() > 1 && !known("default") {
            return Err(Error::invalid(
                f("terrain.materials_by"),
                "is \"single\" (the default) but several materials are defined and none is named 'default'",
                "set materials_by to group, material, file or slope, or name the material 'default'",
            ));
        }
        self.check_soft_materials(&f)?;
        for (i, z) in self.terrain.zones.iter().enumerate() {
            if !known(&z.material) {
                return Err(Error::invalid(
                    f(&format!("terrain.zones[{i}].material")),
                    format!("'{}' is not defined", z.material),
                    "define it under [materials]",
                ));
            }
            check_polygon(&f(&format!("terrain.zones[{i}].polygon")), &z.polygon)?;
        }
        if let Some(clip) = &self.terrain.clip {
            check_polygon(&f("terrain.clip"), clip)?;
        }
        if let Some(level) = &self.terrain.level_beyond {
            check_polygon(&f("terrain.level_beyond"), level)?;
        }
        for (i, b) in self.barriers.iter().enumerate() {
            let field = f(&format!("barriers[{i}]"));
            if b.line.len() < 2 {
                return Err(Error::invalid(
                    format!("{field}.line"),
                    format!("has {} vertices", b.line.len()),
                    "give at least 2 [x, y] vertices",
                ));
            }
            check_finite(&format!("{field}.line"), &b.line)?;
            if !(b.height_m.is_finite() && b.height_m > 0.0) {
                return Err(Error::invalid(
                    format!("{field}.height_m"),
                    format!("must be positive, got {}", b.height_m),
                    "give the fence height in m, e.g. 4",
                ));
            }
            if !(b.capacity_kj.is_finite() && b.capacity_kj > 0.0) {
                return Err(Error::invalid(
                    format!("{field}.capacity_kj"),
                    format!("must be positive, got {}", b.capacity_kj),
                    "give the energy class in kJ, e.g. 1000",
                ));
            }
        }
        if self.sources.is_empty() {
            return Err(Error::invalid(f("sources"), "no source is defined", "add a [[sources]] table"));
        }
        let mut file = self;
        for (i, s) in file.sources.iter_mut().enumerate() {
            s.check(&f(&format!("sources[{i}]")), &|m| file.materials.contains_key(m))?;
            if let Some(c) = &s.campaign {
                let dir = base.join(c);
                if !dir.join("release_points.csv").is_file() {
                    return Err(Error::invalid(
                        f(&format!("sources[{i}].campaign")),
                        format!("{} has no release_points.csv", dir.display()),
                        "point to a campaign folder (relative to the scenario file)",
                    ));
                }
                s.campaign = Some(dir);
            }
        }
        for (i, c) in file.collectors.iter_mut().enumerate() {
            c.check(&f(&format!("collectors[{i}]")), base)?;
        }
        file.hazard_zones.check(&f("hazard_zones"))?;
        file.barrier_design.check(&f("barrier_design"))?;
        let mut this = file;
        this.simulation.params.effects.fill_defaults();
        let shapes = match &this.rocks {
            Some(r) => r.check(&f("rocks"), base)?,
            None if this.sources.iter().all(|s| s.kind == SourceKind::Campaign) => Vec::new(),
            None => {
                return Err(Error::invalid(f("rocks"), "is missing", "add a [rocks] table with shapes and mass_kg"))
            }
        };
        this.simulation.params.validate(&f("simulation."))?;
        if this.simulation.rocks == Some(0) {
            return Err(Error::invalid(f("simulation.rocks"), "is 0", "give at least 1 rock"));
        }
        if this.simulation.threads == Some(0) {
            return Err(Error::invalid(
                f("simulation.threads"),
                "is 0",
                "give at least 1 thread, or leave it out to use all cores",
            ));
        }
        crate::parallel::check_threads(&f("simulation.threads"), this.simulation.threads.unwrap_or(0))?;
        if !(this.output.cell_size_m.is_finite() && this.output.cell_size_m > 0.0) {
            return Err(Error::invalid(
                f("output.cell_size_m"),
                format!("must be positive, got {}", this.output.cell_size_m),
                "use e.g. 2",
            ));
        }
        if let Some(b) = this.output.endpoint_bandwidth_m {
            if !(b.is_finite() && b > 0.0) {
                return Err(Error::invalid(
                    f("output.endpoint_bandwidth_m"),
                    format!("must be positive, got {b}"),
                    "use about 2 cell sizes",
                ));
            }
        }
        Ok(Scenario { path: path.to_path_buf(), file: this, terrain_files, materials, shapes })
    }
}

impl MaterialSpec {
    /// Builds the material named `name`; `field` locates it in errors.
    pub fn build(&self, name: &str, field: &str) -> Result<Material> {
        let mut m = match &self.preset {
            Some(p) => Material::preset(p).ok_or_else(|| {
                let names: Vec<&str> = crate::terrain::material::TABLE2_PRESETS.iter().map(|p| p.0).collect();
                Error::invalid(
                    format!("{field}.preset"),
                    format!("unknown preset '{p}'"),
                    format!("use one of: {}", names.join(", ")),
                )
            })?,
            None => {
                let need = |v: Option<f64>, k: &str| {
                    v.ok_or_else(|| {
                        Error::invalid(
                            format!("{field}.{k}"),
                            "is missing",
                            "give it, or use a preset (e.g. preset = \"face_all\")",
                        )
                    })
                };
                let mean = need(self.cr_mean, "cr_mean")?;
                Material {
                    name: String::new(),
                    cr: TruncNormal::three_sigma(mean, self.cr_sd.unwrap_or(0.0), 0.0, 1.0),
                    static_friction_deg: need(self.static_friction_deg, "static_friction_deg")?,
                    dynamic_friction_deg: need(self.dynamic_friction_deg, "dynamic_friction_deg")?,
                    dynamic_friction_sd_deg: 0.0,
                    drag_per_s: 0.0,
                }
            }
        };
        m.name = name.to_string();
        if self.preset.is_some() && (self.cr_mean.is_some() || self.cr_sd.is_some()) {
            m.cr = TruncNormal::three_sigma(self.cr_mean.unwrap_or(m.cr.mean), self.cr_sd.unwrap_or(m.cr.sd), 0.0, 1.0);
        }
        if let Some(v) = self.static_friction_deg {
            m.static_friction_deg = v;
        }
        if let Some(v) = self.dynamic_friction_deg {
            m.dynamic_friction_deg = v;
        }
        if let Some(v) = self.dynamic_friction_sd_deg {
            m.dynamic_friction_sd_deg = v;
        }
        if let Some(v) = self.cr_min {
            m.cr.min = v;
        }
        if let Some(v) = self.cr_max {
            m.cr.max = v;
        }
        if let Some(v) = self.drag_per_s {
            m.drag_per_s = v;
        }
        m.validate(field)?;
        Ok(m)
    }
}

pub(crate) fn check_polygon(field: &str, pts: &[[f64; 2]]) -> Result<()> {
    if pts.len() < 3 {
        return Err(Error::invalid(field, format!("has {} vertices", pts.len()), "give at least 3 [x, y] vertices"));
    }
    check_finite(field, pts)
}

fn check_finite(field: &str, pts: &[[f64; 2]]) -> Result<()> {
    if let Some(i) = pts.iter().position(|p| !p.iter().all(|v| v.is_finite())) {
        return Err(Error::invalid(format!("{field}[{i}]"), "is not a finite [x, y] pair", "give plain numbers"));
    }
    Ok(())
}

impl SourceSpec {
    fn check(&self, field: &str, known: &dyn Fn(&str) -> bool) -> Result<()> {
        let n = self.points.len();
        match self.kind {
            SourceKind::Point if n != 1 => {
                return Err(Error::invalid(
                    format!("{field}.points"),
                    format!("a point source needs 1 point, got {n}"),
                    "give points = [[x, y]]",
                ))
            }
            SourceKind::Polyline if n < 2 => {
                return Err(Error::invalid(
                    format!("{field}.points"),
                    format!("a polyline needs at least 2 points, got {n}"),
                    "give points = [[x1, y1], [x2, y2], ...]",
                ))
            }
            SourceKind::Polygon => check_polygon(&format!("{field}.points"), &self.points)?,
            _ => {}
        }
        check_finite(&format!("{field}.points"), &self.points)?;
        // Keys of another source type would be ignored: refuse them, so that a user's selection is not lost.
        for (key, given, owner) in [
            ("material", self.material.is_some(), SourceKind::Scatter),
            ("min_slope_deg", self.min_slope_deg.is_some(), SourceKind::Scatter),
            ("max_slope_deg", self.max_slope_deg.is_some(), SourceKind::Scatter),
            ("within", self.within.is_some(), SourceKind::Scatter),
            ("campaign", self.campaign.is_some(), SourceKind::Campaign),
            ("repeats", self.repeats.is_some(), SourceKind::Campaign),
        ] {
            if given && self.kind != owner {
                let name = |k: SourceKind| format!("{k:?}").to_lowercase();
                return Err(Error::invalid(
                    format!("{field}.{key}"),
                    format!("only applies to {} sources, and this one is `{}`", name(owner), name(self.kind)),
                    "remove the key, or set `type` to the source type it belongs to",
                ));
            }
        }
        if let Some(within) = &self.within {
            check_polygon(&format!("{field}.within"), within)?;
        }
        if let Some(m) = &self.material {
            if !known(m) {
                return Err(Error::invalid(
                    format!("{field}.material"),
                    format!("'{m}' is not defined"),
                    "name a material defined under [materials]",
                ));
            }
        }
        if self.kind == SourceKind::Campaign {
            if self.campaign.is_none() {
                return Err(Error::invalid(
                    format!("{field}.campaign"),
                    "is missing",
                    "give the campaign folder, e.g. campaign = \"../meshes/tschamut2014\"",
                ));
            }
            if self.repeats == Some(0) {
                return Err(Error::invalid(format!("{field}.repeats"), "is 0", "give at least 1 rock per release"));
            }
            return Ok(());
        }
        match (self.count, self.density_per_m2) {
            (Some(_), Some(_)) => {
                return Err(Error::invalid(field, "has both count and density_per_m2", "keep one of them"))
            }
            (None, None) => {
                return Err(Error::invalid(
                    field,
                    "has neither count nor density_per_m2",
                    "give count = N (or density_per_m2 for polygon and scatter sources)",
                ))
            }
            (None, Some(d)) => {
                if !matches!(self.kind, SourceKind::Polygon | SourceKind::Scatter) {
                    return Err(Error::invalid(
                        format!("{field}.density_per_m2"),
                        "only applies to polygon and scatter sources",
                        "use count",
                    ));
                }
                if !(d.is_finite() && d > 0.0) {
                    return Err(Error::invalid(
                        format!("{field}.density_per_m2"),
                        format!("must be positive, got {d}"),
                        "give rocks per m², e.g. 0.01",
                    ));
                }
            }
            (Some(_), None) => {}
        }
        if !(self.height_m.is_finite() && (0.0..=MAX_RELEASE_HEIGHT_M).contains(&self.height_m)) {
            return Err(Error::invalid(
                format!("{field}.height_m"),
                format!("must be 0 to {MAX_RELEASE_HEIGHT_M} m, got {}", self.height_m),
                "give the release gap above the ground in m, e.g. 0.1 (a cliff to fall from belongs in the terrain)",
            ));
        }
        if self.velocity_mps.is_some() && self.speed_mps.is_some() {
            return Err(Error::invalid(field, "has both velocity_mps and speed_mps", "keep one of them"));
        }
        if let Some(v) = self.velocity_mps {
            let speed = v.iter().map(|x| x * x).sum::<f64>().sqrt();
            if !(speed.is_finite() && speed <= MAX_RELEASE_SPEED_MPS) {
                return Err(Error::invalid(
                    format!("{field}.velocity_mps"),
                    format!("{v:?} is not a speed of at most {MAX_RELEASE_SPEED_MPS} m/s"),
                    "give [vx, vy, vz] in m/s",
                ));
            }
        }
        for (k, r, max, unit) in [
            ("speed_mps", self.speed_mps, MAX_RELEASE_SPEED_MPS, "m/s"),
            ("spin_radps", self.spin_radps, MAX_RELEASE_SPIN_RADPS, "rad/s"),
        ] {
            if let Some([a, b]) = r {
                if !(a.is_finite() && b.is_finite() && 0.0 <= a && a <= b && b <= max) {
                    return Err(Error::invalid(
                        format!("{field}.{k}"),
                        format!(
                            "[{}, {}] is not a range of values from 0 to {max} {unit}",
                            number_text(a),
                            number_text(b)
                        ),
                        format!("give [min, max] with 0 <= min <= max <= {max}"),
                    ));
                }
            }
        }
        for (k, v) in [("min_slope_deg", self.min_slope_deg), ("max_slope_deg", self.max_slope_deg)] {
            if let Some(v) = v {
                if !(0.0..=90.0).contains(&v) {
                    return Err(Error::invalid(
                        format!("{field}.{k}"),
                        format!("must be in [0, 90], got {v}"),
                        "give a slope in degrees",
                    ));
                }
            }
        }
        Ok(())
    }
}

impl RockSpec {
    fn check(&self, field: &str, base: &Path) -> Result<Vec<ShapeRef>> {
        if self.shapes.is_empty() {
            return Err(Error::invalid(
                format!("{field}.shapes"),
                "is empty",
                "list shapes, e.g. [\"cube\", \"flat_box\", \"smartie\"]",
            ));
        }
        let mut out = Vec::new();
        for (i, s) in self.shapes.iter().enumerate() {
            if crate::rock::ShapeKind::builtin(s).is_some() {
                out.push(ShapeRef::Builtin(s.clone()));
            } else {
                let p = base.join(s);
                if !p.is_file() {
                    return Err(Error::invalid(
                        format!("{field}.shapes[{i}]"),
                        format!("'{s}' is neither a built-in shape nor an existing hull file"),
                        "use cube, flat_box, smartie, or a path (relative to the scenario) to an OBJ, STL or point file",
                    ));
                }
                out.push(ShapeRef::Hull(p));
            }
        }
        let positive = |k: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(Error::invalid(
                    format!("{field}.{k}"),
                    format!("must be positive, got {v}"),
                    "give a positive value",
                ))
            }
        };
        positive("density_kg_m3", self.density_kg_m3)?;
        let rock_mass = |m: f64| {
            positive("mass_kg", m)?;
            if m > MAX_ROCK_MASS_KG {
                return Err(Error::invalid(
                    format!("{field}.mass_kg"),
                    format!("{m} kg is more than the largest block talus takes, {MAX_ROCK_MASS_KG} kg"),
                    "give the block's mass in kg (10⁹ kg is a block of about 370,000 m³: a rock avalanche, not a rockfall)",
                ));
            }
            if m < MIN_ROCK_MASS_KG {
                return Err(Error::invalid(
                    format!("{field}.mass_kg"),
                    format!("{} kg is less than the smallest block talus takes, {MIN_ROCK_MASS_KG} kg", number_text(m)),
                    "give the block's mass in kg (1 kg is a block of about 7 cm; rockfall hazard begins at 10 cm)",
                ));
            }
            Ok(())
        };
        match (self.mass_kg, self.dimensions_m) {
            (Some(MassSpec::Range(_)), Some(_)) => {
                return Err(Error::invalid(
                    field,
                    "has a mass range together with dimensions_m",
                    "give dimensions_m with one mass_kg (or none, to use the density), or a mass range alone",
                ))
            }
            (None, None) => {
                return Err(Error::invalid(
                    field,
                    "has neither mass_kg nor dimensions_m",
                    "give mass_kg = 1000 (or [100, 10000]), or dimensions_m = [a, b, c]",
                ))
            }
            (Some(MassSpec::One(m)), _) => rock_mass(m)?,
            (Some(MassSpec::Range([a, b])), _) => {
                rock_mass(a)?;
                rock_mass(b)?;
                if a > b {
                    return Err(Error::invalid(
                        format!("{field}.mass_kg"),
                        format!("range [{a}, {b}] is reversed"),
                        "give [min, max]",
                    ));
                }
            }
            (None, Some(d)) => {
                let box_mass_kg = self.density_kg_m3 * d.iter().product::<f64>();
                if !(box_mass_kg.is_finite() && box_mass_kg <= MAX_ROCK_MASS_KG) {
                    return Err(Error::invalid(
                        format!("{field}.dimensions_m"),
                        format!("{d:?} m at {} kg/m³ weigh up to {box_mass_kg:.3e} kg", self.density_kg_m3),
                        format!("give the block's sides in m: it may weigh at most {MAX_ROCK_MASS_KG} kg"),
                    ));
                }
            }
        }
        if let Some(d) = self.dimensions_m {
            if !d.iter().all(|v| (MIN_ROCK_SIZE_M..=MAX_BLOCK_SIZE_M).contains(v)) {
                return Err(Error::invalid(
                    format!("{field}.dimensions_m"),
                    format!("{d:?} has a side outside {MIN_ROCK_SIZE_M} to {MAX_BLOCK_SIZE_M} m"),
                    "give the block's three sides in m (sides in mm read 1000 times too large)",
                ));
            }
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::MaterialsBy;

    #[test]
    fn materials_by_names_itself_as_a_scenario_writes_it() {
        for m in [MaterialsBy::Single, MaterialsBy::Group, MaterialsBy::Material, MaterialsBy::File, MaterialsBy::Slope]
        {
            assert_eq!(serde_json::to_string(&m).unwrap(), format!("\"{}\"", m.as_str()));
        }
    }
}
