//! Building a [`Terrain`] from the scenario's files: read, put z up, shift to a local origin, merge, and give each
//! triangle its material.

use super::split::{centre_inside, paint_polygon, split_at_polygon};
use super::{horizontal_to_local, point_in_polygon, Material, Terrain, UpAxis};
use crate::error::{Error, Result};
use crate::io::MeshData;
use crate::raster::{Crs, Grid};
use crate::scenario::{MaterialsBy, TerrainSpec, DEFAULT_SLOPE_FACE_DEG};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use nalgebra::Vector3;
use std::path::{Path, PathBuf};

/// Reads one terrain file by its extension: `.obj`, `.stl`, `.tif`/`.tiff` (GeoTIFF DEM) or `.asc` (ESRI ASCII
/// DEM). DEMs are triangulated; their grid is returned too.
pub fn read_terrain_file(path: &Path) -> Result<(MeshData, Option<Grid>)> {
    match read_terrain_part(path)? {
        TerrainPart::Mesh(mesh) => Ok((mesh, None)),
        TerrainPart::Dem(grid) => Ok((dem_mesh(path, &grid, None)?, Some(grid))),
    }
}

/// A terrain file as read: a mesh, or a DEM grid not yet triangulated (so that DEM tiles can be joined first).
enum TerrainPart {
    Mesh(MeshData),
    Dem(Grid),
}

impl TerrainPart {
    fn dem(&self) -> Option<&Grid> {
        match self {
            TerrainPart::Dem(g) => Some(g),
            TerrainPart::Mesh(_) => None,
        }
    }
}

/// A file's extension in lower case (empty if it has none).
fn extension(path: &Path) -> String {
    path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase()
}

/// True for a file of a kind read as a terrain surface (by its extension: OBJ, STL, GeoTIFF, ESRI ASCII grid).
pub fn is_terrain_file(path: &Path) -> bool {
    matches!(extension(path).as_str(), "obj" | "stl" | "tif" | "tiff" | "asc")
}

/// Reads a terrain file by its extension; DEMs are checked ([`super::dem_check`]) but not triangulated.
fn read_terrain_part(path: &Path) -> Result<TerrainPart> {
    if path.is_dir() {
        return Err(Error::format(
            path.display().to_string(),
            "is a folder, not a terrain file",
            "give a terrain file (.obj, .stl, .tif/.tiff or .asc), not the folder that holds it",
        ));
    }
    let ext = extension(path);
    match ext.as_str() {
        "obj" => Ok(TerrainPart::Mesh(crate::io::obj::read_obj(path)?)),
        "stl" => Ok(TerrainPart::Mesh(crate::io::stl::read_stl(path)?)),
        "tif" | "tiff" | "asc" => {
            let grid = if ext == "asc" {
                crate::io::ascii_grid::read_grid(path)?
            } else {
                crate::io::geotiff::read_dem(path)?
            };
            super::dem_check::check_dem(path, &grid)?;
            Ok(TerrainPart::Dem(grid))
        }
        _ => Err(Error::format(
            path.display().to_string(),
            format!("unknown terrain file type '.{ext}'"),
            "use .obj, .stl, .tif/.tiff (GeoTIFF DEM) or .asc (ESRI ASCII grid)",
        )),
    }
}

/// The most cells of a DEM talus triangulates (ours: 4,000 × 4,000, about 14 GB at the 0.88 kB a cell measured; a 1 m
/// DEM of a 4 km pit, or a 2 m DEM of an 8 km valley side).
pub const MAX_DEM_CELLS: usize = 16_000_000;

/// The peak memory of a run per DEM cell, bytes (measured: a 3,000 × 3,000 DEM's run peaked at 7.9 GB, 2026-12-02).
const DEM_BYTES_PER_CELL: f64 = 880.0;

/// Triangulates the DEM read from `path`, over `joined` (the grid with the cells of neighbouring tiles added, see
/// [`join_tiles`]) when given; refuses a DEM with no triangle of its own.
fn dem_mesh(path: &Path, grid: &Grid, joined: Option<&Grid>) -> Result<MeshData> {
    let cells = grid.ncols * grid.nrows;
    if cells > MAX_DEM_CELLS {
        return Err(Error::format(
            path.display().to_string(),
            format!(
                "the DEM has {} × {} = {cells} cells, more than talus triangulates ({MAX_DEM_CELLS}): it would take \
                 about {:.0} GB of memory",
                grid.ncols,
                grid.nrows,
                cells as f64 * DEM_BYTES_PER_CELL / 1e9
            ),
            "crop it to the slope of interest or resample it to a coarser cell, e.g. `gdalwarp -tr 2 2 in.tif out.tif`",
        ));
    }
    let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    // A triangle needs 3 valid nodes of a square of 4 (see grid_to_mesh).
    let valid = |c: usize, r: usize| usize::from(grid.get(c, r).is_some());
    let has_triangle = (0..grid.nrows.saturating_sub(1)).any(|r| {
        (0..grid.ncols.saturating_sub(1))
            .any(|c| valid(c, r) + valid(c + 1, r) + valid(c, r + 1) + valid(c + 1, r + 1) >= 3)
    });
    if !has_triangle {
        return Err(Error::format(
            path.display().to_string(),
            format!(
                "the DEM has {} valid cells of {}: no 3 neighbouring cells hold data",
                grid.count_valid(),
                grid.values.len()
            ),
            "check the nodata value and that the grid holds elevations",
        ));
    }
    Ok(grid_to_mesh(joined.unwrap_or(grid), &stem))
}

/// Relative tolerance on cell sizes and on cell-centre positions for two DEMs to count as one grid (ours: far
/// below any survey precision, far above the rounding of an origin written with 9 decimals).
const SAME_GRID_TOLERANCE: f64 = 1e-6;

/// DEM tiles on one grid, joined: a DEM is triangulated between its cell centres, so two tiles that meet edge to
/// edge leave a strip one cell wide between their outer centres with no surface, where rocks would leave the
/// terrain. Each tile gets one more column to the east and one more row to the south, holding the cells of the
/// other tiles there (when they lie on the same grid: equal cell sizes and cell centres that coincide), so the
/// strips are triangulated once, by the tile west or north of them. `None` when no other tile adds a cell.
fn join_tiles(grid: &Grid, others: &[&Grid]) -> Option<Grid> {
    let neighbours: Vec<&&Grid> = others.iter().filter(|o| on_one_grid(grid, o)).collect();
    if neighbours.is_empty() {
        return None;
    }
    let (nc, nr) = (grid.ncols + 1, grid.nrows + 1);
    let mut joined = Grid::filled(nc, nr, grid.x_min_m, grid.y_max_m, grid.cell_x_m, f32::NAN);
    joined.cell_y_m = grid.cell_y_m;
    joined.crs = grid.crs.clone();
    for r in 0..grid.nrows {
        joined.values[r * nc..r * nc + grid.ncols].copy_from_slice(&grid.values[r * grid.ncols..(r + 1) * grid.ncols]);
    }
    let mut added = false;
    let edge = (0..nr).map(|r| (grid.ncols, r)).chain((0..grid.ncols).map(|c| (c, grid.nrows)));
    for (c, r) in edge {
        let (x, y) = joined.cell_centre(c, r);
        for o in &neighbours {
            // On one grid, the neighbour's cell under this centre has the same centre.
            let Some((oc, or)) = o.cell_of(x, y) else { continue };
            if let Some(z) = o.get(oc, or) {
                joined.values[r * nc + c] = z;
                added = true;
                break;
            }
        }
    }
    added.then_some(joined)
}

/// Two DEMs on one grid: equal cell sizes, and cell edges that line up (within [`SAME_GRID_TOLERANCE`] of a cell).
fn on_one_grid(a: &Grid, b: &Grid) -> bool {
    let whole = |d: f64, cell: f64| ((d / cell) - (d / cell).round()).abs() <= SAME_GRID_TOLERANCE;
    (a.cell_x_m - b.cell_x_m).abs() <= SAME_GRID_TOLERANCE * a.cell_x_m
        && (a.cell_y_m - b.cell_y_m).abs() <= SAME_GRID_TOLERANCE * a.cell_y_m
        && whole(a.x_min_m - b.x_min_m, a.cell_x_m)
        && whole(a.y_max_m - b.y_max_m, a.cell_y_m)
}

/// Notes on DEM tiles that meet (their extents come within a cell of each other) without lying on one grid: they
/// cannot be joined, and the strip between their outer cell centres has no surface.
fn seam_notes(files: &[PathBuf], parts: &[TerrainPart]) -> Vec<String> {
    let dems: Vec<(&PathBuf, &Grid)> = files.iter().zip(parts).filter_map(|(p, part)| Some((p, part.dem()?))).collect();
    let extent = |g: &Grid| {
        [g.x_min_m, g.y_max_m - g.nrows as f64 * g.cell_y_m, g.x_min_m + g.ncols as f64 * g.cell_x_m, g.y_max_m]
    };
    let mut notes = Vec::new();
    for (i, (pa, a)) in dems.iter().enumerate() {
        for (pb, b) in &dems[i + 1..] {
            let (ea, eb) = (extent(a), extent(b));
            let reach = a.cell_x_m.max(a.cell_y_m).max(b.cell_x_m).max(b.cell_y_m);
            let meet =
                ea[0] <= eb[2] + reach && eb[0] <= ea[2] + reach && ea[1] <= eb[3] + reach && eb[1] <= ea[3] + reach;
            if meet && !on_one_grid(a, b) {
                let name = |p: &PathBuf| p.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
                notes.push(format!(
                    "DEM tiles {} ({} × {} m cells) and {} ({} × {} m cells) meet but are not on one grid (cell sizes \
                     or cell edges differ), so they are not joined: the strip between their outer cell centres has no \
                     surface and rocks that reach it leave the terrain; resample them onto one grid, e.g. \
                     `gdalwarp -tr {} {} -tap {} {} joined.tif`, and give joined.tif",
                    name(pa),
                    a.cell_x_m,
                    a.cell_y_m,
                    name(pb),
                    b.cell_x_m,
                    b.cell_y_m,
                    a.cell_x_m,
                    a.cell_y_m,
                    name(pa),
                    name(pb)
                ));
            }
        }
    }
    notes
}

/// Triangulates a DEM: nodes at cell centres, two triangles per square of four valid nodes (one when only three are
/// valid), so nodata holes stay holes. Split along the diagonal that keeps the surface closest to the four
/// corners' mean (ours; either diagonal is exact at the nodes).
pub fn grid_to_mesh(grid: &Grid, name: &str) -> MeshData {
    let (nc, nr) = (grid.ncols, grid.nrows);
    let mut index = vec![u32::MAX; nc * nr];
    let mut vertices = Vec::new();
    for r in 0..nr {
        for c in 0..nc {
            if let Some(z) = grid.get(c, r) {
                let (x, y) = grid.cell_centre(c, r);
                index[r * nc + c] = vertices.len() as u32;
                vertices.push([x, y, z as f64]);
            }
        }
    }
    let mut triangles = Vec::new();
    for r in 0..nr.saturating_sub(1) {
        for c in 0..nc.saturating_sub(1) {
            // Corners counter-clockwise seen from above: rows grow southward.
            let sw = index[(r + 1) * nc + c];
            let se = index[(r + 1) * nc + c + 1];
            let ne = index[r * nc + c + 1];
            let nw = index[r * nc + c];
            let valid = [sw, se, ne, nw].iter().filter(|&&v| v != u32::MAX).count();
            if valid == 4 {
                let z = |k: u32| vertices[k as usize][2];
                if (z(sw) - z(ne)).abs() <= (z(se) - z(nw)).abs() {
                    triangles.push([sw, se, ne]);
                    triangles.push([sw, ne, nw]);
                } else {
                    triangles.push([sw, se, nw]);
                    triangles.push([se, ne, nw]);
                }
            } else if valid == 3 {
                let t: Vec<u32> = [sw, se, ne, nw].into_iter().filter(|&v| v != u32::MAX).collect();
                triangles.push([t[0], t[1], t[2]]);
            }
        }
    }
    let n = triangles.len();
    MeshData {
        vertices,
        triangles,
        group: vec![0; n],
        group_names: vec![name.to_string()],
        material: vec![0; n],
        material_names: vec![String::new()],
    }
}

/// Builds the terrain of a scenario: `files` (absolute) as described by `spec`, with `materials` (in the order
/// the scenario defines them).
pub fn build_terrain(
    files: &[PathBuf],
    spec: &TerrainSpec,
    materials: &[Material],
    scenario: &Path,
) -> Result<Terrain> {
    // Every file is read before any DEM is triangulated, so that DEM tiles can be joined.
    let parts = files.iter().map(|p| read_terrain_part(p)).collect::<Result<Vec<_>>>()?;
    let dems: Vec<&Grid> = parts.iter().filter_map(TerrainPart::dem).collect();
    let anchor = dems.first().map(|g| [g.x_min_m, g.y_max_m]);
    let joined: Vec<Option<Grid>> = (parts.iter())
        .map(|part| {
            let grid = part.dem()?;
            join_tiles(grid, &dems.iter().copied().filter(|o| !std::ptr::eq(*o, grid)).collect::<Vec<_>>())
        })
        .collect();
    let seams = seam_notes(files, &parts);
    let mut meshes = Vec::new();
    let mut crs = Crs::default();
    for ((p, part), joined) in files.iter().zip(parts).zip(joined) {
        let (mesh, c) = match part {
            TerrainPart::Mesh(mesh) => (mesh, Crs::default()),
            TerrainPart::Dem(grid) => (dem_mesh(p, &grid, joined.as_ref())?, grid.crs),
        };
        if crs.is_unknown() {
            crs = c;
        }
        meshes.push((p.clone(), mesh));
    }
    let mut terrain = assemble_terrain(&meshes, crs, spec, materials, scenario)?;
    terrain.grid_anchor_xy = anchor;
    terrain.notes.extend(seams);
    Ok(terrain)
}

/// Builds a terrain from meshes already in memory, each with the path it came from (whose stem names its
/// material with `materials_by = "file"`); `spec.files` is not used.
pub fn assemble_terrain(
    meshes: &[(PathBuf, MeshData)],
    mut crs: Crs,
    spec: &TerrainSpec,
    materials: &[Material],
    scenario: &Path,
) -> Result<Terrain> {
    if meshes.is_empty() {
        return Err(Error::invalid(
            format!("{}: terrain.files", scenario.display()),
            "no terrain mesh",
            "list at least one terrain file",
        ));
    }
    if let Some(code) = spec.crs_epsg {
        crs = Crs { epsg: Some(code), geokeys: None, wkt: crs.wkt };
    }
    let up = spec.up;
    // Local origin: the lower corner of the first file, to the metre, in z-up axes (z origin kept at 0 so that
    // local heights read as elevations).
    let first = &meshes[0].1;
    let (mut ox, mut oy) = (f64::INFINITY, f64::INFINITY);
    for v in &first.vertices {
        let p = up.to_internal(*v);
        ox = ox.min(p.x);
        oy = oy.min(p.y);
    }
    let origin = Vector3::new(ox.floor(), oy.floor(), 0.0);
    let mut vertices = Vec::new();
    let mut triangles = Vec::new();
    let mut names = Vec::new();
    for (path, mesh) in meshes {
        let base = vertices.len() as u32;
        for (i, v) in mesh.vertices.iter().enumerate() {
            if !v.iter().all(|c| c.is_finite()) {
                return Err(Error::format(
                    path.display().to_string(),
                    format!("vertex {} has a non-finite coordinate", i + 1),
                    "fix or remove that vertex",
                ));
            }
            vertices.push(up.to_internal(*v) - origin);
        }
        let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        for (t, tri) in mesh.triangles.iter().enumerate() {
            triangles.push(tri.map(|k| k + base));
            names.push(match spec.materials_by {
                MaterialsBy::Group => mesh.group_names[mesh.group[t] as usize].clone(),
                MaterialsBy::Material => mesh.material_names[mesh.material[t] as usize].clone(),
                MaterialsBy::File => stem.clone(),
                MaterialsBy::Slope | MaterialsBy::Single => String::new(),
            });
        }
    }
    let to_local =
        |poly: &[[f64; 2]]| -> Vec<[f64; 2]> { poly.iter().map(|p| horizontal_to_local(up, &origin, *p)).collect() };
    if let Some(level) = &spec.level_beyond {
        if !level_beyond(&mut vertices, &to_local(level)) {
            return Err(Error::invalid(
                format!("{}: terrain.level_beyond", scenario.display()),
                "no vertex of the terrain lies inside the polygon",
                "give the polygon in the terrain files' horizontal coordinates, around the ground you trust",
            ));
        }
    }
    if let Some(clip) = &spec.clip {
        let poly = to_local(clip);
        (triangles, names) = split_at_polygon(&mut vertices, triangles, names, &poly);
        (triangles, names) =
            triangles.into_iter().zip(names).filter(|(tri, _)| centre_inside(&vertices, tri, &poly)).unzip();
        if triangles.is_empty() {
            return Err(Error::invalid(
                format!("{}: terrain.clip", scenario.display()),
                "no triangle of the terrain has its centre inside the clip polygon",
                "give the polygon in the terrain files' horizontal coordinates",
            ));
        }
    }
    if triangles.is_empty() {
        return Err(Error::invalid(
            format!("{}: terrain.files", scenario.display()),
            "the terrain files hold no triangles",
            "check the files",
        ));
    }
    let index_of = |name: &str| materials.iter().position(|m| m.name == name);
    let single = if materials.len() == 1 { 0 } else { index_of("default").unwrap_or(0) };
    let mut tri_mat = Vec::with_capacity(triangles.len());
    let mut unknown: Vec<String> = Vec::new();
    for (t, name) in triangles.iter().zip(&names) {
        let m = match spec.materials_by {
            MaterialsBy::Single => single,
            MaterialsBy::Slope => {
                let [a, b, c] = t.map(|k| vertices[k as usize]);
                let n: Vector3<f64> = (b - a).cross(&(c - a));
                let slope = (n.z.abs() / n.norm().max(1e-300)).clamp(0.0, 1.0).acos().to_degrees();
                index_of(if slope > spec.slope_face_deg.unwrap_or(DEFAULT_SLOPE_FACE_DEG) { "face" } else { "floor" })
                    .unwrap_or(0)
            }
            _ => {
                let target = spec.material_names.get(name).map(String::as_str).unwrap_or(name);
                match index_of(target) {
                    Some(i) => i,
                    None => {
                        if !unknown.contains(name) {
                            unknown.push(name.clone());
                        }
                        0
                    }
                }
            }
        };
        tri_mat.push(m as u16);
    }
    if !unknown.is_empty() {
        let by = spec.materials_by.as_str();
        return Err(Error::invalid(
            format!("{}: terrain.materials_by", scenario.display()),
            format!(
                "the terrain has {by} names with no material: {}",
                unknown.iter().map(|n| format!("'{n}'")).collect::<Vec<_>>().join(", ")
            ),
            format!(
                "define [materials.NAME] for each, or map them with [terrain.material_names] (defined: {})",
                materials.iter().map(|m| m.name.as_str()).collect::<Vec<_>>().join(", ")
            ),
        ));
    }
    // Each zone ends exactly on its polygon, as the clip does (and as the calibration's zones do,
    // [`Terrain::paint_zone`]): the triangles its edges cross are split first.
    for (z, zone) in spec.zones.iter().enumerate() {
        let m = index_of(&zone.material).unwrap_or(0) as u16;
        if paint_polygon(&mut vertices, &mut triangles, &mut tri_mat, &to_local(&zone.polygon), m) == 0 {
            return Err(Error::invalid(
                format!("{}: terrain.zones[{z}].polygon", scenario.display()),
                "the polygon covers no part of the terrain",
                "give the polygon in the terrain's coordinates (the CRS of the DEM, or the mesh's x and y), over the \
                 terrain",
            ));
        }
    }
    check_spread(&format!("{}: terrain.files", scenario.display()), &vertices, &triangles)?;
    let mut terrain = Terrain::from_local(vertices, &triangles, &tri_mat, materials.to_vec()).map_err(|_| {
        Error::invalid(
            format!("{}: terrain.files", scenario.display()),
            "every triangle is degenerate or vertical",
            "check the files and the `up` axis",
        )
    })?;
    terrain.origin = origin;
    terrain.up = up;
    terrain.crs = crs;
    terrain.notes = unused_keys(&terrain, spec, &names);
    terrain.notes.extend(up_axis_note(&terrain, up));
    Ok(terrain)
}

/// Refuses triangles spread so far apart that the surface's index could not hold their bounding box
/// ([`crate::terrain::surface::MAX_INDEX_BINS`]); `field` names the terrain in the error.
pub fn check_spread(field: &str, vertices: &[Vector3<f64>], triangles: &[[u32; 3]]) -> Result<()> {
    use crate::terrain::surface::{index_bins, MAX_INDEX_BINS};
    let (bins, width_m, height_m) = index_bins(vertices, triangles);
    if bins <= MAX_INDEX_BINS {
        return Ok(());
    }
    Err(Error::invalid(
        field,
        format!(
            "the terrain's {} triangles lie far apart, over {:.3e} × {:.3e} m: indexing that would take {bins:.1e} \
             bins (at most {MAX_INDEX_BINS:.0e})",
            triangles.len(),
            width_m,
            height_m
        ),
        "check that `up` in [terrain] is the files' up axis (a y-up mesh read z-up stands on its side, its \
         triangles seen edge-on from above), that every terrain file is in the same CRS and that no file holds \
         vertices far from the rest (a vertex at 0, 0 in a georeferenced mesh, say)",
    ))
}

/// Share of the surface's footprint that lies under other triangles, above which a run notes it, with the other up
/// axis as a likely cause (ours): a 2.5D terrain read with its own up axis hides only its overhangs (none in a DEM,
/// a few per cent in a scan of a face), while one read on its side stacks its ridges over one another (11 % for
/// the Tyrol crop exported y-up and read z-up, 0 % read y-up).
pub const HIDDEN_SHARE_NOTE: f64 = 0.05;

/// A note when more than [`HIDDEN_SHARE_NOTE`] of the terrain's footprint (triangle areas projected on the
/// horizontal) lies more than 1 cm under the ground, the highest triangle there.
fn up_axis_note(terrain: &Terrain, up: UpAxis) -> Option<String> {
    let surface = &terrain.surface;
    let (mut hidden, mut all) = (0.0, 0.0);
    for t in 0..surface.triangles().len() as u32 {
        let area = surface.footprint_area_m2(t);
        if !area.is_finite() {
            continue;
        }
        let c = surface.corners(t).iter().sum::<Vector3<f64>>() / 3.0;
        all += area;
        if surface.height(c.x, c.y).is_some_and(|z| z > c.z + 0.01) {
            hidden += area;
        }
    }
    let share = if all > 0.0 { hidden / all } else { 0.0 };
    let other = match up {
        UpAxis::Z => "y",
        UpAxis::Y => "z",
    };
    (share > HIDDEN_SHARE_NOTE).then(|| {
        format!(
            "terrain.up: {:.0} % of the terrain's area lies under other triangles and is closed over (a terrain \
             read with its own up axis hides only its overhangs): if the files are {other}-up, set up = \"{other}\" \
             in [terrain]",
            100.0 * share
        )
    })
}

/// What `spec` asks that the built terrain does not use: materials no triangle has, and `material_names` entries
/// no group, material or file of the terrain files (`names`, one per triangle) carries.
fn unused_keys(terrain: &Terrain, spec: &TerrainSpec, names: &[String]) -> Vec<String> {
    let by = spec.materials_by.as_str();
    let mut notes = Vec::new();
    for (m, n) in terrain.materials.iter().zip(terrain.triangles_per_material()) {
        if n == 0 {
            notes.push(format!(
                "[materials.{}] is defined but no triangle of the terrain has it (materials_by = \"{by}\"{}): it \
                 changes nothing",
                m.name,
                if spec.zones.is_empty() { "" } else { " and the zones" }
            ));
        }
    }
    if spec.slope_face_deg.is_some() && spec.materials_by != MaterialsBy::Slope {
        notes.push(format!("terrain.slope_face_deg is not used: materials_by is \"{by}\", not \"slope\""));
    }
    let by_name = matches!(spec.materials_by, MaterialsBy::Group | MaterialsBy::Material | MaterialsBy::File);
    let mut held: Vec<&str> = names.iter().map(String::as_str).collect();
    held.sort_unstable();
    held.dedup();
    for from in spec.material_names.keys() {
        if !by_name {
            notes.push(format!(
                "terrain.material_names.{from} is not used: materials_by = \"{by}\" does not read names from the files"
            ));
        } else if held.binary_search(&from.as_str()).is_err() {
            notes.push(format!(
                "terrain.material_names.{from}: the terrain files hold no {by} named '{from}' (they hold: {})",
                held.iter().map(|n| format!("'{n}'")).collect::<Vec<_>>().join(", ")
            ));
        }
    }
    notes
}

/// Gives every vertex outside `poly` the height of the nearest vertex inside it (horizontal distance, a kiddo k-d
/// tree): nearest-neighbour extrapolation of the ground inside, level along the polygon's normal (ours; the
/// alternative to a DEM's own extrapolated margin). False when no vertex lies inside.
fn level_beyond(vertices: &mut [Vector3<f64>], poly: &[[f64; 2]]) -> bool {
    let (inside, outside): (Vec<usize>, Vec<usize>) =
        (0..vertices.len()).partition(|&i| point_in_polygon(vertices[i].x, vertices[i].y, poly));
    let points: Vec<[f64; 2]> = inside.iter().map(|&i| [vertices[i].x, vertices[i].y]).collect();
    if points.is_empty() {
        return false;
    }
    let Ok(tree) = ImmutableKdTree::<f64, 2>::new_from_slice(&points) else { return false };
    for i in outside {
        let nearest = tree.query(&[vertices[i].x, vertices[i].y]).nearest_one::<SquaredEuclidean<f64>>().execute();
        vertices[i].z = vertices[inside[nearest.item as usize]].z;
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The `w` × `h` block of `g` whose north-west cell is (c0, r0).
    fn tile(g: &Grid, c0: usize, r0: usize, w: usize, h: usize) -> Grid {
        let mut t =
            Grid::filled(w, h, g.x_min_m + c0 as f64 * g.cell_x_m, g.y_max_m - r0 as f64 * g.cell_y_m, 2.0, 0.0);
        for r in 0..h {
            for c in 0..w {
                t.values[r * w + c] = g.values[(r0 + r) * g.ncols + c0 + c];
            }
        }
        t
    }

    #[test]
    fn joined_tiles_triangulate_as_the_whole_grid() {
        let mut g = Grid::filled(9, 7, 248_000.123, 352_000.456, 2.0, 0.0);
        for (k, v) in g.values.iter_mut().enumerate() {
            *v = 1000.0 + (k % 9) as f32 * 1.5 + (k / 9) as f32 * 0.75 + ((k * 7) % 5) as f32 * 0.1;
        }
        g.values[30] = f32::NAN;
        let whole = grid_to_mesh(&g, "dem").triangles.len();
        let tiles = [tile(&g, 0, 0, 4, 3), tile(&g, 4, 0, 5, 3), tile(&g, 0, 3, 4, 4), tile(&g, 4, 3, 5, 4)];
        let mut joined = 0;
        let mut apart = 0;
        for (i, t) in tiles.iter().enumerate() {
            let others: Vec<&Grid> = tiles.iter().enumerate().filter(|(j, _)| *j != i).map(|(_, o)| o).collect();
            let j = join_tiles(t, &others);
            joined += grid_to_mesh(j.as_ref().unwrap_or(t), "dem").triangles.len();
            apart += grid_to_mesh(t, "dem").triangles.len();
        }
        assert_eq!(joined, whole);
        assert!(apart < whole, "tiles alone leave the seams open");
        // A tile on another grid (shifted by a third of a cell) is not joined.
        let mut shifted = tiles[1].clone();
        shifted.x_min_m += 2.0 / 3.0;
        assert!(join_tiles(&tiles[0], &[&shifted]).is_none());
        // Which the terrain notes, naming both files; tiles on one grid, and a tile far away, are not noted.
        let files: Vec<PathBuf> = ["a.tif", "b.tif", "c.tif", "d.tif"].iter().map(PathBuf::from).collect();
        let mut far = shifted.clone();
        far.x_min_m += 1000.0;
        let parts = |grids: [&Grid; 3]| grids.map(|g| TerrainPart::Dem(g.clone()));
        assert!(seam_notes(&files, &parts([&tiles[0], &tiles[1], &far])).is_empty());
        let notes = seam_notes(&files, &parts([&tiles[0], &far, &shifted]));
        assert_eq!(notes.len(), 1, "{notes:?}");
        assert!(notes[0].starts_with("DEM tiles a.tif (2 × 2 m cells) and c.tif (2 × 2 m cells) meet"), "{notes:?}");
    }

    #[test]
    fn a_dem_with_no_three_neighbouring_cells_is_refused() {
        // A checkerboard of data and nodata: every square of four cells has two valid nodes, no triangle.
        let mut g = Grid::filled(4, 4, 0.0, 8.0, 2.0, 100.0);
        for (k, v) in g.values.iter_mut().enumerate() {
            if (k % 4 + k / 4) % 2 == 1 {
                *v = f32::NAN;
            }
        }
        let e = dem_mesh(Path::new("holes.asc"), &g, None).unwrap_err().to_string();
        assert!(e.contains("holes.asc") && e.contains("8 valid cells of 16"), "{e}");
        g.values[1] = 100.0;
        assert_eq!(dem_mesh(Path::new("holes.asc"), &g, None).unwrap().triangles.len(), 2);
    }

    #[test]
    fn a_terrain_read_on_its_side_is_noted_and_one_read_upright_is_not() {
        // Ridges and valleys on a slope, 60 m square in 1 m cells, written as a y-up file (x, z, -y).
        let z = |x: f64, y: f64| 0.5 * x + 6.0 * (x / 5.0).sin() + 6.0 * (y / 7.0).cos();
        let mut vertices = Vec::new();
        for j in 0..=60 {
            for i in 0..=60 {
                let (x, y) = (i as f64, j as f64);
                vertices.push([x, z(x, y), -y]);
            }
        }
        let k = |i: u32, j: u32| j * 61 + i;
        let triangles: Vec<[u32; 3]> = (0..60)
            .flat_map(|j| {
                (0..60).flat_map(move |i| {
                    [[k(i, j), k(i + 1, j), k(i + 1, j + 1)], [k(i, j), k(i + 1, j + 1), k(i, j + 1)]]
                })
            })
            .collect();
        let n = triangles.len();
        let mesh = MeshData {
            vertices,
            triangles,
            group: vec![0; n],
            group_names: vec!["g".into()],
            material: vec![0; n],
            material_names: vec![String::new()],
        };
        let meshes = [(PathBuf::from("t.obj"), mesh)];
        let materials = [Material::preset("face_all").unwrap()];
        let notes = |up: &str| {
            let spec: TerrainSpec = toml::from_str(&format!("files = [\"t.obj\"]\nup = \"{up}\"")).unwrap();
            assemble_terrain(&meshes, Crs::default(), &spec, &materials, Path::new("s.toml")).unwrap().notes
        };
        assert!(notes("y").is_empty(), "{:?}", notes("y"));
        let read_z = notes("z");
        assert!(read_z.len() == 1 && read_z[0].contains("set up = \"y\""), "{read_z:?}");
    }

    #[test]
    fn a_zone_takes_exactly_the_ground_inside_its_polygon_and_painting_it_later_gives_the_same_terrain() {
        // A design surface: a 100 m square plane of two triangles, and a zone across its diagonal. Taking whole
        // triangles by their centre, the zone would have been one triangle (half the square) or none.
        let z = |x: f64, y: f64| 0.3 * x + 0.1 * y;
        let corners = [[0.0, 0.0], [100.0, 0.0], [100.0, 100.0], [0.0, 100.0]];
        let mesh = MeshData {
            vertices: corners.iter().map(|&[x, y]| [x, y, z(x, y)]).collect(),
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            group: vec![0; 2],
            group_names: vec!["g".into()],
            material: vec![0; 2],
            material_names: vec![String::new()],
        };
        let meshes = [(PathBuf::from("t.obj"), mesh)];
        let materials =
            ["default", "soft"].map(|name| Material { name: name.into(), ..Material::preset("face_all").unwrap() });
        let poly = [[20.0, 10.0], [70.0, 15.0], [60.0, 80.0], [30.0, 55.0]];
        let poly_area = 0.5
            * (0..4)
                .map(|i| {
                    let (a, b) = (poly[i], poly[(i + 1) % 4]);
                    a[0] * b[1] - b[0] * a[1]
                })
                .sum::<f64>()
                .abs();
        let zone = format!("[[zones]]\nmaterial = \"soft\"\npolygon = {poly:?}\n");
        let build = |zones: &str| {
            let spec: TerrainSpec = toml::from_str(&format!("files = [\"t.obj\"]\n{zones}")).unwrap();
            assemble_terrain(&meshes, Crs::default(), &spec, &materials, Path::new("s.toml")).unwrap()
        };
        let zoned = build(&zone);
        let s = &zoned.surface;
        let zone_area: f64 = (0..s.triangles().len() as u32)
            .filter(|&t| zoned.triangle_material[t as usize] == 1)
            .map(|t| s.footprint_area_m2(t))
            .sum();
        assert!((zone_area - poly_area).abs() < 1e-9 * poly_area, "{zone_area} against {poly_area}");
        // Heights unchanged, and the material at a point is the zone's exactly inside the polygon.
        let o = zoned.origin;
        for i in 0..40 {
            for j in 0..40 {
                let (x, y) = (1.1 + 2.45 * i as f64, 0.7 + 2.47 * j as f64);
                let p = s.at(x - o.x, y - o.y).unwrap();
                assert!((p.z_m + o.z - z(x, y)).abs() < 1e-9);
                let inside = point_in_polygon(x, y, &poly);
                assert_eq!(zoned.triangle_material[p.triangle as usize] == 1, inside, "({x}, {y})");
            }
        }
        // The calibration's zones: painting the polygon on the terrain built without it gives the same terrain.
        let mut painted = build("");
        let local: Vec<[f64; 2]> = poly.iter().map(|&p| horizontal_to_local(painted.up, &painted.origin, p)).collect();
        assert!(painted.paint_zone(&local, 1).unwrap() > 0);
        assert_eq!(painted.surface.triangles(), s.triangles());
        assert_eq!(painted.surface.vertices(), s.vertices());
        assert_eq!(painted.triangle_material, zoned.triangle_material);
    }

    #[test]
    fn nodes_outside_take_the_height_of_the_nearest_node_inside() {
        // A 3 × 2 grid of nodes 1 m apart; the polygon holds the left column only.
        let mut v: Vec<Vector3<f64>> =
            [(0.0, 0.0, 5.0), (1.0, 0.0, 4.0), (2.0, 0.0, 3.0), (0.0, 1.0, 7.0), (1.0, 1.0, 6.0), (2.0, 1.0, 1.0)]
                .iter()
                .map(|&(x, y, z)| Vector3::new(x, y, z))
                .collect();
        assert!(level_beyond(&mut v, &[[-0.5, -0.5], [0.5, -0.5], [0.5, 1.5], [-0.5, 1.5]]));
        let z: Vec<f64> = v.iter().map(|p| p.z).collect();
        assert_eq!(z, [5.0, 5.0, 5.0, 7.0, 7.0, 7.0]);
        assert!(!level_beyond(&mut v, &[[10.0, 10.0], [11.0, 10.0], [11.0, 11.0]]));
    }
}
