//! Field campaigns: release points, observed rest points and blocks, in the CSV format of `data.md`.
//!
//! Column names are fixed, extra columns are ignored, units are SI and in the names. Every error names the file,
//! the line and the column.

use crate::error::{Error, Result};
use crate::io::csv_text::{Row, Table};
use crate::rock::{RockBody, RockSize, ShapeKind};
use crate::scenario::{MAX_ROCK_MASS_KG, MIN_ROCK_MASS_KG, MIN_ROCK_SIZE_M};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// One released rock.
#[derive(Debug, Clone, PartialEq)]
pub struct Release {
    /// Run id.
    pub trajectory_id: String,
    /// Release position of the centre of mass, m.
    pub position_m: [f64; 3],
    /// Initial velocity, m/s.
    pub velocity_mps: [f64; 3],
    /// Initial spin, rad/s (zero if absent).
    pub spin_radps: [f64; 3],
    /// Block id.
    pub block_id: String,
    /// 1-based line of `release_points.csv` the release was read from, for error messages.
    pub line: usize,
}

/// How far below the ground a release's centre may lie before the campaign is refused, m (ours): a measured
/// centre sits a few decimetres off a gridded terrain (at Tschamut up to 0.41 m below the 5 m proxy); metres
/// below it is a wrong datum, a wrong column or a typo.
pub const RELEASE_BELOW_GROUND_M: f64 = 1.0;

/// Release height above the ground under it past which a campaign gets a warning, m (ours): field releases are
/// a few metres up (drops from a crane or a helicopter some tens); hundreds of metres is more likely a typo.
pub const RELEASE_ABOVE_GROUND_NOTE_M: f64 = 100.0;

/// One observed rest point.
#[derive(Debug, Clone, PartialEq)]
pub struct Deposition {
    /// Run id.
    pub trajectory_id: String,
    /// Rest position, m.
    pub position_m: [f64; 3],
    /// Horizontal distance from release to rest, m (computed if absent from the file).
    pub runout_m: f64,
    /// 1-based line of `observed_deposition.csv` the rest point was read from, for error messages.
    pub line: usize,
}

/// One point of a tracked path.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackPoint {
    /// Time, s.
    pub time_s: f64,
    /// Position of the centre of mass, m.
    pub position_m: [f64; 3],
}

/// A block.
#[derive(Debug, Clone, PartialEq)]
pub struct Block {
    /// Id.
    pub block_id: String,
    /// Name, if given.
    pub name: String,
    /// Mass, kg.
    pub mass_kg: f64,
    /// Bounding dimensions, m.
    pub size_m: [f64; 3],
    /// Shape: `cube`, `flat_box`, `smartie`, a hull file, or empty (inferred from the sizes).
    pub shape: String,
}

/// A field campaign.
#[derive(Debug, Clone)]
pub struct Campaign {
    /// Folder.
    pub dir: PathBuf,
    /// Releases, in file order.
    pub releases: Vec<Release>,
    /// Observed rest points by run id.
    pub depositions: BTreeMap<String, Deposition>,
    /// Blocks by id.
    pub blocks: BTreeMap<String, Block>,
    /// Tracked paths by run id (`observed_trajectories.csv`, optional), in time order.
    pub tracks: BTreeMap<String, Vec<TrackPoint>>,
}

/// What a campaign's rocks move on, which decides the columns its files must have.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Ground {
    /// A 3D terrain (3DRB): positions need `y_m` and releases `vy_mps`.
    Terrain,
    /// A 2D profile (2DLM): `y_m` and `vy_mps` may be left out (they are then 0).
    Profile,
}

/// Hint for a missing campaign column.
const COLUMN_HINT: &str = "add the column (see the campaign format in docs/campaign.md)";

/// Hint for a missing velocity column.
const VELOCITY_HINT: &str = "add the column: the initial velocity in m/s, 0 for a block dropped at rest";

/// Hint for a missing `y_m` column.
const Y_HINT: &str = "add the column: a campaign on a 3D terrain gives every point its y_m (only a profile campaign \
                      may leave it out)";

impl Campaign {
    /// Reads `release_points.csv`, `observed_deposition.csv` (optional: a campaign to predict has none),
    /// `block_metadata.csv` and `observed_trajectories.csv` (optional) from `dir`, on the ground its release file
    /// implies: a 3D terrain when it has a `y_m` column, a profile otherwise. A caller that knows the ground uses
    /// [`Campaign::read_on`].
    ///
    /// # Errors
    /// As [`Campaign::read_on`].
    pub fn read(dir: &Path) -> Result<Campaign> {
        let rel = Table::read(&dir.join("release_points.csv"), false)?;
        let ground = if rel.col("y_m").is_some() { Ground::Terrain } else { Ground::Profile };
        Campaign::from_release_table(dir, &rel, ground)
    }

    /// Reads the campaign in `dir` (see [`Campaign::read`]) for rocks moving on `ground`.
    ///
    /// # Errors
    /// I/O errors; a malformed CSV file (see [`Table`]); a missing column (`y_m` and `vy_mps` are required on a
    /// terrain only, the spin and `observed_runout_m` never); a value that is not a number; an id that appears
    /// twice in a file; a block that is not positive; a release of an unknown block; a rest point of an unknown
    /// run, of another block or with a negative run-out. Each names the file, the line and the column.
    pub fn read_on(dir: &Path, ground: Ground) -> Result<Campaign> {
        Campaign::from_release_table(dir, &Table::read(&dir.join("release_points.csv"), false)?, ground)
    }

    /// The campaign in `dir` whose release file is `rel`.
    fn from_release_table(dir: &Path, rel: &Table, ground: Ground) -> Result<Campaign> {
        let releases = read_releases(rel, ground)?;
        let blocks = read_blocks(&dir.join("block_metadata.csv"))?;
        for r in &releases {
            if !blocks.contains_key(&r.block_id) {
                return Err(Error::format(
                    rel.source.clone(),
                    format!(
                        "run '{}' uses block '{}', which block_metadata.csv does not list",
                        r.trajectory_id, r.block_id
                    ),
                    "add the block to block_metadata.csv or fix the block_id",
                ));
            }
        }
        let depositions = read_depositions(&dir.join("observed_deposition.csv"), &releases, ground)?;
        let tracks = read_tracks(&dir.join("observed_trajectories.csv"), &releases)?;
        Ok(Campaign { dir: dir.to_path_buf(), releases, depositions, blocks, tracks })
    }

    /// Refuses a rest point that is not over the ground: `over(p)` tells whether the rest point `p` (campaign
    /// frame) lies over the terrain or profile, which `ground` describes for the message (e.g. `the terrain, which
    /// spans x [0, 100] and y [0, 200]`).
    ///
    /// # Errors
    /// The first such rest point in file order, at its line of `observed_deposition.csv`, naming the run, the
    /// point and `ground`.
    pub fn check_rest_points(&self, over: impl Fn([f64; 3]) -> bool, ground: &str) -> Result<()> {
        let off = self.depositions.values().filter(|d| !over(d.position_m)).min_by_key(|d| d.line);
        match off {
            None => Ok(()),
            Some(d) => Err(Error::at_line(
                self.dir.join("observed_deposition.csv"),
                d.line,
                format!("the rest point {:?} of run '{}' is not over {ground}", d.position_m, d.trajectory_id),
                "check that the campaign and the terrain (or profile) share a frame, and the point's coordinates",
            )),
        }
    }

    /// A note naming the releases without a rest point in `observed_deposition.csv` (runs not observed to stop,
    /// which calibration leaves out), if any.
    pub fn unobserved_note(&self) -> Option<String> {
        let ids: Vec<&str> = self
            .releases
            .iter()
            .filter(|r| !self.depositions.contains_key(&r.trajectory_id))
            .map(|r| r.trajectory_id.as_str())
            .collect();
        (!ids.is_empty()).then(|| {
            let shown = ids.iter().take(10).copied().collect::<Vec<_>>().join(", ");
            let more = if ids.len() > 10 { format!(" and {} more", ids.len() - 10) } else { String::new() };
            format!(
                "{} of {} releases have no rest point in observed_deposition.csv and are left out (not observed to \
                 stop; if they ran off the surveyed ground, the campaign lacks its longest runs): {shown}{more}",
                ids.len(),
                self.releases.len()
            )
        })
    }

    /// Checks that every release lies over the ground and no more than [`RELEASE_BELOW_GROUND_M`] below it;
    /// `height_m` gives a point's height above the ground under it (`None` off the ground), `ground` names the
    /// ground as [`Campaign::check_rest_points`] does. Returns a note naming the releases more than
    /// [`RELEASE_ABOVE_GROUND_NOTE_M`] above the ground, if any.
    ///
    /// # Errors
    /// The first such release in file order, at its line of `release_points.csv`, naming the run and the point.
    pub fn check_release_points(
        &self,
        height_m: impl Fn([f64; 3]) -> Option<f64>,
        ground: &str,
    ) -> Result<Option<String>> {
        let mut high = Vec::new();
        for r in &self.releases {
            let at = |message: String, hint: &str| {
                Err(Error::at_line(self.dir.join("release_points.csv"), r.line, message, hint))
            };
            let point = format!("the release point {:?} of run '{}'", r.position_m, r.trajectory_id);
            match height_m(r.position_m) {
                None => return at(
                    format!("{point} is not over {ground}"),
                    "check that the campaign and the terrain (or profile) share a frame, and the point's coordinates",
                ),
                Some(h) if h < -RELEASE_BELOW_GROUND_M => return at(
                    format!("{point} lies {:.2} m below the ground under it", -h),
                    "check z_m (the rock's centre, in the terrain's vertical datum) and that the columns are in order; \
                     a centre measured on a steep face of a coarse DEM can lie under its interpolated ground: give \
                     it the ground's height there plus half the block",
                ),
                Some(h) if h > RELEASE_ABOVE_GROUND_NOTE_M => {
                    high.push(format!("{} ({h:.0} m, line {})", r.trajectory_id, r.line))
                }
                Some(_) => {}
            }
        }
        Ok((!high.is_empty()).then(|| {
            format!(
                "{} releases lie more than {RELEASE_ABOVE_GROUND_NOTE_M} m above the ground under them: {}; check \
                 their z_m in release_points.csv",
                high.len(),
                high.join(", ")
            )
        }))
    }

    /// The rock body of a block. The shape is the block's own if given; otherwise inferred from its sizes (our
    /// rule): sorted sizes a ≥ b ≥ c give a `flat_box` when c/a < 0.5 and a `cube`-family box otherwise, in both
    /// cases a box with the block's dimensions and exact mass.
    pub fn body(&self, block: &Block) -> Result<RockBody> {
        let field = format!("{}: block {}", self.dir.join("block_metadata.csv").display(), block.block_id);
        let kind = match block.shape.as_str() {
            "" => {
                let mut s = block.size_m;
                s.sort_by(|a, b| b.total_cmp(a));
                if s[2] / s[0] < 0.5 {
                    ShapeKind::FlatBox
                } else {
                    ShapeKind::Cube
                }
            }
            name => match ShapeKind::builtin(name) {
                Some(k) => k,
                None => {
                    let p = self.dir.join(name);
                    if !p.is_file() {
                        return Err(Error::invalid(
                            format!("{field}: shape"),
                            format!("'{name}' is neither a built-in shape nor a file of the campaign folder"),
                            "use cube, flat_box or smartie, a hull file's name relative to the campaign folder, or \
                             leave the column empty to infer the shape from the sizes",
                        ));
                    }
                    ShapeKind::Hull { name: name.to_string(), points: crate::io::points::read_hull_points(&p)? }
                }
            },
        };
        RockBody::new(&kind, RockSize::DimensionsAndMass { size_m: block.size_m, mass_kg: block.mass_kg }, &field)
    }
}

/// Notes the id `id` of column `name` in `row` of `t`; `seen` holds the ids met so far with their lines.
///
/// # Errors
/// The id was met before: an error at this line naming both lines, with `hint`.
fn note_unique(
    t: &Table,
    row: &Row,
    name: &str,
    id: &str,
    seen: &mut BTreeMap<String, usize>,
    hint: &str,
) -> Result<()> {
    match seen.insert(id.to_string(), row.line) {
        None => Ok(()),
        Some(first) => {
            Err(t.error(row, format!("{name} '{id}' appears twice, on lines {first} and {}", row.line), hint))
        }
    }
}

/// The column of `name` (`y_m`, `vy_mps`) that only a terrain campaign needs: required on a terrain (an error
/// naming it, with `hint`), `None` on a profile.
fn terrain_column(t: &Table, name: &str, ground: Ground, hint: &str) -> Result<Option<usize>> {
    match ground {
        Ground::Terrain => t.need(name, hint).map(Some),
        Ground::Profile => Ok(None),
    }
}

/// The number of column `name` in `row`: from the column `required` by a terrain campaign, else (a profile) the
/// optional column's value, 0 when it is absent or empty.
///
/// # Errors
/// A field that is not a number; an empty field of a required column.
fn terrain_value(t: &Table, row: &Row, required: Option<usize>, name: &str) -> Result<f64> {
    match required {
        Some(c) => t.number(row, c, name),
        None => Ok(t.optional_number(row, name)?.unwrap_or(0.0)),
    }
}

/// Reads the releases of `release_points.csv` (the table `rel`) for a campaign on `ground`.
///
/// # Errors
/// See [`Campaign::read_on`]; no release at all.
fn read_releases(rel: &Table, ground: Ground) -> Result<Vec<Release>> {
    let (id, x, z, b) = (
        rel.need("trajectory_id", COLUMN_HINT)?,
        rel.need("x_m", COLUMN_HINT)?,
        rel.need("z_m", COLUMN_HINT)?,
        rel.need("block_id", COLUMN_HINT)?,
    );
    let (vx, vz) = (rel.need("vx_mps", VELOCITY_HINT)?, rel.need("vz_mps", VELOCITY_HINT)?);
    let (y, vy) = (terrain_column(rel, "y_m", ground, Y_HINT)?, terrain_column(rel, "vy_mps", ground, VELOCITY_HINT)?);
    let mut releases = Vec::new();
    let mut seen = BTreeMap::new();
    for row in &rel.rows {
        let trajectory_id = rel.text(row, id, "trajectory_id")?.to_string();
        note_unique(rel, row, "trajectory_id", &trajectory_id, &mut seen, "give every run its own id")?;
        let spin = |n: &str| rel.optional_number(row, n).map(|v| v.unwrap_or(0.0));
        releases.push(Release {
            trajectory_id,
            position_m: [rel.number(row, x, "x_m")?, terrain_value(rel, row, y, "y_m")?, rel.number(row, z, "z_m")?],
            velocity_mps: [
                rel.number(row, vx, "vx_mps")?,
                terrain_value(rel, row, vy, "vy_mps")?,
                rel.number(row, vz, "vz_mps")?,
            ],
            spin_radps: [spin("wx_radps")?, spin("wy_radps")?, spin("wz_radps")?],
            block_id: rel.text(row, b, "block_id")?.to_string(),
            line: row.line,
        });
    }
    if releases.is_empty() {
        return Err(Error::format(rel.source.clone(), "holds no release", "add one row per released rock"));
    }
    Ok(releases)
}

/// Reads the blocks of `block_metadata.csv` at `path`, by id.
///
/// # Errors
/// See [`Campaign::read_on`].
fn read_blocks(path: &Path) -> Result<BTreeMap<String, Block>> {
    let blk = Table::read(path, false)?;
    let (bid, m) = (blk.need("block_id", COLUMN_HINT)?, blk.need("mass_kg", COLUMN_HINT)?);
    let (sx, sy, sz) =
        (blk.need("size_x_m", COLUMN_HINT)?, blk.need("size_y_m", COLUMN_HINT)?, blk.need("size_z_m", COLUMN_HINT)?);
    let mut blocks = BTreeMap::new();
    let mut seen = BTreeMap::new();
    for row in &blk.rows {
        let block = Block {
            block_id: blk.text(row, bid, "block_id")?.to_string(),
            name: blk.field(row, blk.col("name")).to_string(),
            mass_kg: blk.number(row, m, "mass_kg")?,
            size_m: [
                blk.number(row, sx, "size_x_m")?,
                blk.number(row, sy, "size_y_m")?,
                blk.number(row, sz, "size_z_m")?,
            ],
            shape: blk.field(row, blk.col("shape")).to_string(),
        };
        note_unique(&blk, row, "block_id", &block.block_id, &mut seen, "give every block its own id")?;
        if block.mass_kg <= 0.0 || block.size_m.iter().any(|&s| s <= 0.0) {
            return Err(blk.error(row, "mass and sizes must be positive", "fix the block's mass_kg and size_*_m"));
        }
        if block.mass_kg > MAX_ROCK_MASS_KG || block.size_m.iter().any(|&s| s > MAX_BLOCK_SIZE_M) {
            return Err(blk.error(
                row,
                format!(
                    "block '{}' of {} kg and {:?} m is larger than the largest block talus takes ({MAX_ROCK_MASS_KG} \
                     kg, {MAX_BLOCK_SIZE_M} m a side)",
                    block.block_id, block.mass_kg, block.size_m
                ),
                "give the block's mass in kg and its sizes in metres (sizes in millimetres read 1000 times too large)",
            ));
        }
        if block.mass_kg < MIN_ROCK_MASS_KG || block.size_m.iter().any(|&s| s < MIN_ROCK_SIZE_M) {
            return Err(blk.error(
                row,
                format!(
                    "block '{}' of {} kg and {:?} m is smaller than the smallest block talus takes ({MIN_ROCK_MASS_KG} \
                     kg, {MIN_ROCK_SIZE_M} m a side: rockfall hazard begins at about 10 cm)",
                    block.block_id, block.mass_kg, block.size_m
                ),
                "give the block's mass in kg and its sizes in metres",
            ));
        }
        blocks.insert(block.block_id.clone(), block);
    }
    Ok(blocks)
}

/// The largest side of a campaign block, m (ours: past any rockfall block, so that sizes in millimetres are caught;
/// 10¹⁵ m was read).
pub const MAX_BLOCK_SIZE_M: f64 = 100.0;

/// Reads the rest points of `observed_deposition.csv` at `path` (none if the file does not exist), by run id, for
/// the `releases` of a campaign on `ground`.
///
/// # Errors
/// See [`Campaign::read_on`].
fn read_depositions(path: &Path, releases: &[Release], ground: Ground) -> Result<BTreeMap<String, Deposition>> {
    let mut depositions = BTreeMap::new();
    if !path.is_file() {
        return Ok(depositions);
    }
    let dep = Table::read(path, false)?;
    let (id, x, z) =
        (dep.need("trajectory_id", COLUMN_HINT)?, dep.need("x_m", COLUMN_HINT)?, dep.need("z_m", COLUMN_HINT)?);
    let y = terrain_column(&dep, "y_m", ground, Y_HINT)?;
    let mut seen = BTreeMap::new();
    for row in &dep.rows {
        let tid = dep.text(row, id, "trajectory_id")?.to_string();
        note_unique(&dep, row, "trajectory_id", &tid, &mut seen, "keep one rest point per run")?;
        let Some(rel) = releases.iter().find(|r| r.trajectory_id == tid) else {
            return Err(dep.error(
                row,
                format!("run '{tid}' has no release in release_points.csv"),
                "fix the trajectory_id",
            ));
        };
        let b = dep.field(row, dep.col("block_id"));
        if !b.is_empty() && b != rel.block_id {
            return Err(dep.error(
                row,
                format!("run '{tid}' rests as block '{b}' but was released as block '{}'", rel.block_id),
                "make block_id agree with release_points.csv (or leave it empty here)",
            ));
        }
        let p = [dep.number(row, x, "x_m")?, terrain_value(&dep, row, y, "y_m")?, dep.number(row, z, "z_m")?];
        let computed = ((p[0] - rel.position_m[0]).powi(2) + (p[1] - rel.position_m[1]).powi(2)).sqrt();
        let runout_m = match dep.optional_number(row, "observed_runout_m")? {
            Some(r) if r < 0.0 => {
                return Err(dep.error(
                    row,
                    format!("observed_runout_m is {r}: a run-out is a distance and cannot be negative"),
                    "give the horizontal distance from release to rest, or leave the field empty to compute it",
                ))
            }
            r => r.unwrap_or(computed),
        };
        depositions.insert(tid.clone(), Deposition { trajectory_id: tid, position_m: p, runout_m, line: row.line });
    }
    Ok(depositions)
}

/// Reads tracked paths (`trajectory_id`, `time_s`, `x_m`, `y_m` (absent on a profile), `z_m`), if the file
/// exists. A run's rows may be anywhere in the file but must come in increasing time.
fn read_tracks(path: &Path, releases: &[Release]) -> Result<BTreeMap<String, Vec<TrackPoint>>> {
    let mut tracks: BTreeMap<String, Vec<TrackPoint>> = BTreeMap::new();
    if !path.is_file() {
        return Ok(tracks);
    }
    let t = Table::read(path, false)?;
    let known: std::collections::BTreeSet<&str> = releases.iter().map(|r| r.trajectory_id.as_str()).collect();
    let (id, time, x, z) = (
        t.need("trajectory_id", COLUMN_HINT)?,
        t.need("time_s", COLUMN_HINT)?,
        t.need("x_m", COLUMN_HINT)?,
        t.need("z_m", COLUMN_HINT)?,
    );
    for row in &t.rows {
        let tid = t.text(row, id, "trajectory_id")?;
        if !known.contains(tid) {
            return Err(t.error(
                row,
                format!("run '{tid}' has no release in release_points.csv"),
                "fix the trajectory_id",
            ));
        }
        let point = TrackPoint {
            time_s: t.number(row, time, "time_s")?,
            position_m: [
                t.number(row, x, "x_m")?,
                t.optional_number(row, "y_m")?.unwrap_or(0.0),
                t.number(row, z, "z_m")?,
            ],
        };
        let track = tracks.entry(tid.to_string()).or_default();
        if let Some(last) = track.last() {
            if point.time_s <= last.time_s {
                return Err(t.error(
                    row,
                    format!("run '{tid}' goes back in time: time_s {} after {}", point.time_s, last.time_s),
                    "list each run's points in increasing time_s",
                ));
            }
        }
        track.push(point);
    }
    Ok(tracks)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn campaign(release: &str, blocks: &str, deposition: &str) -> (tempfile::TempDir, Result<Campaign>) {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("release_points.csv"), release).unwrap();
        std::fs::write(dir.path().join("block_metadata.csv"), blocks).unwrap();
        std::fs::write(dir.path().join("observed_deposition.csv"), deposition).unwrap();
        let c = Campaign::read(dir.path());
        (dir, c)
    }

    const RELEASE: &str =
        "trajectory_id,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps,block_id\nr1,0,0,10,0,0,0,1\nr2,0,1,10,0,0,0,2\n";
    const BLOCKS: &str = "block_id,mass_kg,size_x_m,size_y_m,size_z_m\n1,69,0.37,0.32,0.37\n2,79,0.5,0.3,0.39\n";
    const DEPOSITION: &str = "trajectory_id,x_m,y_m,z_m,block_id\nr1,20,0,0,1\nr2,25,1,0,2\n";

    #[test]
    fn errors_name_the_file_line_the_user_sees() {
        let (_d, c) = campaign(RELEASE, BLOCKS, DEPOSITION);
        let c = c.unwrap();
        assert_eq!(c.depositions["r2"].runout_m, 25.0);
        let err = |r: Result<Campaign>| r.unwrap_err().to_string();
        let bad = BLOCKS.replace("79", "abc");
        let (_d, c) = campaign(RELEASE, &bad, DEPOSITION);
        let e = err(c);
        assert!(e.contains("block_metadata.csv:3") && e.contains("mass_kg") && e.contains("abc"), "{e}");
        let dup = format!("{RELEASE}r1,1,1,10,0,0,0,1\n");
        let (_d, c) = campaign(&dup, BLOCKS, DEPOSITION);
        let e = err(c);
        assert!(e.contains("release_points.csv:4") && e.contains("twice"), "{e}");
        // Windows line ends (the Tschamut files have them) count the same.
        let (_d, c) = campaign(&dup.replace('\n', "\r\n"), &bad.replace('\n', "\r\n"), DEPOSITION);
        let e = err(c);
        assert!(e.contains("release_points.csv:4") && e.contains("twice"), "{e}");
        let (_d, c) = campaign(RELEASE, &bad.replace('\n', "\r\n"), DEPOSITION);
        let e = err(c);
        assert!(e.contains("block_metadata.csv:3"), "{e}");
    }

    #[test]
    fn tracked_paths_are_read_in_time_order_and_bad_ones_named() {
        let (d, c) = campaign(RELEASE, BLOCKS, DEPOSITION);
        assert!(c.unwrap().tracks.is_empty());
        let file = d.path().join("observed_trajectories.csv");
        std::fs::write(&file, "trajectory_id,time_s,x_m,y_m,z_m\nr1,0,0,0,10\nr2,0,0,1,10\nr1,0.1,0.5,0,9.9\n")
            .unwrap();
        let c = Campaign::read(d.path()).unwrap();
        assert_eq!(c.tracks["r1"].len(), 2);
        assert_eq!(c.tracks["r1"][1].position_m, [0.5, 0.0, 9.9]);
        std::fs::write(&file, "trajectory_id,time_s,x_m,y_m,z_m\nr1,0,0,0,10\nr1,0,0.5,0,9.9\n").unwrap();
        let e = Campaign::read(d.path()).unwrap_err().to_string();
        assert!(e.contains("observed_trajectories.csv:3") && e.contains("back in time"), "{e}");
        std::fs::write(&file, "trajectory_id,time_s,x_m,y_m,z_m\nr9,0,0,0,10\n").unwrap();
        let e = Campaign::read(d.path()).unwrap_err().to_string();
        assert!(e.contains("observed_trajectories.csv:2") && e.contains("r9"), "{e}");
        std::fs::write(&file, "trajectory_id,x_m,y_m,z_m\nr1,0,0,10\n").unwrap();
        let e = Campaign::read(d.path()).unwrap_err().to_string();
        assert!(e.contains("observed_trajectories.csv") && e.contains("time_s"), "{e}");
    }

    #[test]
    fn a_rest_point_whose_block_differs_from_its_release_is_refused() {
        let bad = DEPOSITION.replace("r2,25,1,0,2", "r2,25,1,0,1");
        let (_d, c) = campaign(RELEASE, BLOCKS, &bad);
        let e = c.unwrap_err().to_string();
        assert!(e.contains("observed_deposition.csv:3") && e.contains("block") && e.contains("r2"), "{e}");
    }
}
