//! Wavefront OBJ meshes: read with `tobj`, written by hand.
//!
//! # How a file is read
//! 1. A **pre-scan** of our own walks the lines once. It parses every `v` line in `f64` (rejecting NaN and
//!    infinite coordinates, which `tobj` would accept silently), checks every `f` line (at least 3 corners, indices
//!    that exist), and records for each face the current group (`o`/`g` name) and material (`usemtl` name). This
//!    gives line numbers for errors, and names that do not depend on an `.mtl` file being present.
//! 2. `tobj` then parses the same text (`triangulate`, `single_index`, points and lines ignored). Polyline `l`
//!    lines are blanked first, so that a 3-point polyline does not become a triangle, and vertex colours are
//!    dropped, as tobj fails when only some vertices have them. A `tobj` error is reported at the line it stopped
//!    on.
//! 3. **Mapping back.** `tobj` returns models in file order (a new model at each `o`/`g` with pending faces) and
//!    fan-triangulates each face in order, so the concatenated triangles of all models are the file's faces in
//!    order, each face of `k` corners giving `k − 2` triangles. Triangle `t` therefore takes the group and material
//!    the pre-scan recorded for its face. Vertex positions are mapped back to the file's `v` indices by their exact
//!    `f64` bits (tobj is built with `use_f64`, and parses the same numbers the same way), so
//!    [`MeshData::vertices`] is every `v` line in file order, and identical positions share the first index.
//!
//! `group_names` are the names of groups that hold faces, in first-seen order (faces before any `o`/`g`, or under a
//! nameless one, are in `"default"`). `material_names` are the `usemtl` names used by faces, in first-seen order,
//! with `""` for faces before any `usemtl`.

use crate::error::{Error, Result};
use crate::io::{write_atomic, MeshData};
use std::borrow::Cow;
use std::collections::HashMap;
use std::io::{BufRead, Read, Write};
use std::path::Path;

/// The group name used for faces that have no `o`/`g` name.
pub const DEFAULT_GROUP: &str = "default";

/// Reads an OBJ file into one mesh: all objects and groups merged, faces triangulated as fans.
///
/// See the module documentation for how groups, materials and vertices are numbered.
pub fn read_obj(path: &Path) -> Result<MeshData> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let text = String::from_utf8_lossy(&bytes);
    // A byte-order mark (Windows editors write one) would hide a first `v` line and shift every face index.
    let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
    let scan = prescan(path, text)?;
    if scan.faces.is_empty() {
        return Err(Error::format(
            path.display().to_string(),
            format!("the mesh has no faces ({} vertices, no `f` lines with 3 or more corners)", scan.vertices.len()),
            "export the surface as a triangle mesh (faces, not only points or lines)",
        ));
    }
    if u32::try_from(scan.vertices.len()).is_err() {
        return Err(Error::format(
            path.display().to_string(),
            format!("{} vertices are more than talus can index (2^32)", scan.vertices.len()),
            "decimate the mesh",
        ));
    }

    // tobj parses the text with polylines blanked and vertex colours dropped (line numbers kept).
    let tobj_text: Cow<str> = if scan.rewrites.is_empty() {
        Cow::Borrowed(text)
    } else {
        let mut rewrites = scan.rewrites.iter().peekable();
        let mut out = String::with_capacity(text.len());
        for (i, line) in text.split('\n').enumerate() {
            if i > 0 {
                out.push('\n');
            }
            match rewrites.peek() {
                Some((j, replacement)) if *j == i => {
                    out.push_str(replacement);
                    rewrites.next();
                }
                _ => out.push_str(line),
            }
        }
        Cow::Owned(out)
    };
    let options = tobj::LoadOptions { triangulate: true, single_index: true, ignore_points: true, ignore_lines: true };
    let mut reader = LineTracker { data: tobj_text.as_bytes(), pos: 0 };
    let loaded = tobj::load_obj_buf(&mut reader, &options, |_| Ok((Vec::new(), Default::default())));
    let models = match loaded {
        Ok((models, _)) => models,
        Err(e) => {
            return Err(Error::at_line(
                path,
                reader.line(),
                format!("the OBJ parser (tobj) stopped here: {e}"),
                "fix or remove this line; check it against the OBJ format (`v x y z`, `f a b c`, ...)",
            ))
        }
    };

    let mut index_of: HashMap<[u64; 3], u32> = HashMap::with_capacity(scan.vertices.len());
    for (i, v) in scan.vertices.iter().enumerate() {
        index_of.entry(v.map(f64::to_bits)).or_insert(i as u32);
    }
    let mut triangles = Vec::with_capacity(scan.n_triangles);
    for model in &models {
        let pos = &model.mesh.positions;
        for tri in model.mesh.indices.chunks_exact(3) {
            let mut t = [0u32; 3];
            for (k, &vi) in tri.iter().enumerate() {
                let p = pos.get(3 * vi as usize..3 * vi as usize + 3).map(|p| [p[0], p[1], p[2]]);
                t[k] = p.and_then(|p| index_of.get(&p.map(f64::to_bits)).copied()).ok_or_else(|| {
                    internal(path, format!("tobj returned a vertex that is not in the file (model '{}')", model.name))
                })?;
            }
            triangles.push(t);
        }
    }
    if triangles.len() != scan.n_triangles {
        return Err(internal(
            path,
            format!("tobj made {} triangles, the pre-scan expected {}", triangles.len(), scan.n_triangles),
        ));
    }

    let mut group = Vec::with_capacity(triangles.len());
    let mut material = Vec::with_capacity(triangles.len());
    for f in &scan.faces {
        for _ in 0..f.n_triangles {
            group.push(f.group);
            material.push(f.material);
        }
    }
    Ok(MeshData {
        vertices: scan.vertices,
        triangles,
        group,
        group_names: scan.group_names,
        material,
        material_names: scan.material_names,
    })
}

/// Writes `mesh` as OBJ, atomically: all `v` lines (shortest exact `f64` form), then for each group a `g` line and
/// its faces (1-based), with a `usemtl` line whenever the material changes to a named one.
///
/// Groups without faces are skipped, as [`read_obj`] does not report them. OBJ cannot switch back to "no
/// material", so a triangle with material `""` after a named material in the file order is an error; put such
/// triangles first or name their material.
pub fn write_obj(path: &Path, mesh: &MeshData) -> Result<()> {
    check_mesh(path, mesh)?;
    let n = mesh.triangles.len();
    let group_of = |t: usize| mesh.group.get(t).copied().unwrap_or(0) as usize;
    let material_of = |t: usize| mesh.material.get(t).copied().unwrap_or(0) as usize;
    let n_groups = mesh.group_names.len().max(1);
    let mut by_group: Vec<Vec<usize>> = vec![Vec::new(); n_groups];
    for t in 0..n {
        by_group[group_of(t)].push(t);
    }
    for tris in &mut by_group {
        tris.sort_by_key(|&t| material_of(t));
    }

    write_atomic(path, |w| {
        let io = |e| Error::io(path, e);
        writeln!(w, "# written by talus {}", env!("CARGO_PKG_VERSION")).map_err(io)?;
        for v in &mesh.vertices {
            writeln!(w, "v {} {} {}", v[0], v[1], v[2]).map_err(io)?;
        }
        let mut current: Option<&str> = None;
        for (g, tris) in by_group.iter().enumerate() {
            if tris.is_empty() {
                continue;
            }
            let name = mesh.group_names.get(g).map(|s| s.trim()).filter(|s| !s.is_empty()).unwrap_or(DEFAULT_GROUP);
            writeln!(w, "g {name}").map_err(io)?;
            for &t in tris {
                let mat = mesh.material_names.get(material_of(t)).map_or("", |s| s.trim());
                if current != Some(mat) {
                    if mat.is_empty() {
                        if current.is_some() {
                            return Err(Error::invalid(
                                format!("{}: material of triangle {}", path.display(), t + 1),
                                "OBJ cannot switch back to no material after a `usemtl` line",
                                "give these triangles a material name, or order them before the named ones",
                            ));
                        }
                    } else {
                        writeln!(w, "usemtl {mat}").map_err(io)?;
                        current = Some(mat);
                    }
                }
                let [a, b, c] = mesh.triangles[t];
                writeln!(w, "f {} {} {}", a + 1, b + 1, c + 1).map_err(io)?;
            }
        }
        Ok(())
    })
}

/// Reads only the `v` lines of an OBJ (with the same checks as [`read_obj`]), so a file of bare points works too.
pub(crate) fn read_obj_vertices(path: &Path) -> Result<Vec<[f64; 3]>> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    Ok(prescan(path, &String::from_utf8_lossy(&bytes))?.vertices)
}

/// What the pre-scan learnt about one `f` line.
#[derive(Debug, Clone, Copy, PartialEq)]
struct FaceInfo {
    /// 1-based line number.
    line: usize,
    /// Number of triangles of the fan: corners − 2.
    n_triangles: usize,
    /// Index into `group_names`.
    group: u32,
    /// Index into `material_names`.
    material: u32,
    /// Largest 0-based position, texcoord and normal index used (checked once all lines are read).
    max_index: [Option<usize>; 3],
}

/// The result of the pre-scan.
#[derive(Debug, Default)]
struct Scan {
    vertices: Vec<[f64; 3]>,
    faces: Vec<FaceInfo>,
    n_triangles: usize,
    group_names: Vec<String>,
    material_names: Vec<String>,
    /// Lines (0-based) that tobj gets in another form: `l` lines blanked, `v x y z r g b` without the colour
    /// (tobj fails when only some vertices have colours, and we do not use them).
    rewrites: Vec<(usize, String)>,
}

/// One pass over the lines: vertices in `f64`, face checks, groups and materials per face.
fn prescan(path: &Path, text: &str) -> Result<Scan> {
    let mut scan = Scan::default();
    let mut counts = [0usize; 3]; // v, vt, vn seen so far
    let mut group_index: HashMap<String, u32> = HashMap::new();
    let mut material_index: HashMap<String, u32> = HashMap::new();
    let mut current_group = DEFAULT_GROUP.to_string();
    let mut current_material = String::new();

    for (i, raw) in text.split('\n').enumerate() {
        let line_no = i + 1;
        let line = raw.trim();
        let mut tokens = line.split_whitespace();
        let Some(keyword) = tokens.next() else { continue };
        let rest = line[keyword.len()..].trim();
        match keyword {
            "v" => {
                let tokens: Vec<&str> = tokens.collect();
                let v = parse_vertex(path, line_no, &tokens)?;
                if tokens.len() == 6 {
                    scan.rewrites.push((i, format!("v {} {} {}", tokens[0], tokens[1], tokens[2])));
                }
                scan.vertices.push(v);
                counts[0] += 1;
            }
            "vt" => counts[1] += 1,
            "vn" => counts[2] += 1,
            "l" => scan.rewrites.push((i, String::new())),
            "o" | "g" => current_group = if rest.is_empty() { DEFAULT_GROUP.to_string() } else { rest.to_string() },
            "usemtl" => {
                if rest.is_empty() {
                    return Err(Error::at_line(path, line_no, "`usemtl` without a material name", "name it"));
                }
                current_material = rest.to_string();
            }
            "f" => {
                let corners: Vec<&str> = tokens.collect();
                if corners.len() < 3 {
                    return Err(Error::at_line(
                        path,
                        line_no,
                        format!("a face needs at least 3 corners, found {}", corners.len()),
                        "remove the line or complete the face",
                    ));
                }
                let mut max_index = [None; 3];
                for corner in &corners {
                    let parts: Vec<&str> = corner.split('/').collect();
                    if parts.len() > 3 || parts[0].is_empty() {
                        return Err(Error::at_line(
                            path,
                            line_no,
                            format!("'{corner}' is not a face corner"),
                            "write corners as `v`, `v/vt`, `v//vn` or `v/vt/vn` with 1-based indices",
                        ));
                    }
                    for (k, part) in parts.iter().enumerate() {
                        if part.is_empty() {
                            continue;
                        }
                        let idx = resolve_index(path, line_no, part, counts[k], ["v", "vt", "vn"][k])?;
                        max_index[k] = max_index[k].max(Some(idx));
                    }
                }
                let n = group_index.len() as u32;
                let group = *group_index.entry(current_group.clone()).or_insert_with(|| {
                    scan.group_names.push(current_group.clone());
                    n
                });
                let n = material_index.len() as u32;
                let material = *material_index.entry(current_material.clone()).or_insert_with(|| {
                    scan.material_names.push(current_material.clone());
                    n
                });
                let n_triangles = corners.len() - 2;
                scan.n_triangles += n_triangles;
                scan.faces.push(FaceInfo { line: line_no, n_triangles, group, material, max_index });
            }
            _ => {}
        }
    }
    // Positive indices may point forward; check them against the whole file.
    for f in &scan.faces {
        for (k, name) in ["v", "vt", "vn"].iter().enumerate() {
            if let Some(idx) = f.max_index[k] {
                if idx >= counts[k] {
                    return Err(Error::at_line(
                        path,
                        f.line,
                        format!("face index {} is out of range: the file has {} `{name}` lines", idx + 1, counts[k]),
                        "fix the face indices (1-based) or add the missing vertices",
                    ));
                }
            }
        }
    }
    Ok(scan)
}

/// Parses the numbers after `v`: `x y z`, `x y z w` or `x y z r g b`.
fn parse_vertex(path: &Path, line_no: usize, tokens: &[&str]) -> Result<[f64; 3]> {
    if !matches!(tokens.len(), 3 | 4 | 6) {
        return Err(Error::at_line(
            path,
            line_no,
            format!("a vertex needs 3 coordinates (optionally w, or r g b), found {} values", tokens.len()),
            "write it as `v x y z`",
        ));
    }
    let mut nums = [0.0f64; 4];
    for (k, tok) in tokens.iter().take(4).enumerate() {
        if k == 3 && tokens.len() == 6 {
            break;
        }
        nums[k] = tok.parse::<f64>().map_err(|_| {
            Error::at_line(path, line_no, format!("'{tok}' is not a number"), "write the vertex as `v x y z`")
        })?;
    }
    let mut v = [nums[0], nums[1], nums[2]];
    if tokens.len() == 4 {
        let w = nums[3];
        if w == 0.0 || !w.is_finite() {
            return Err(Error::at_line(
                path,
                line_no,
                format!("vertex weight w = {w} cannot scale a position"),
                "remove w",
            ));
        }
        v = v.map(|c| c / w);
    }
    if let Some(bad) = v.iter().position(|&c| !super::coordinate_ok(c)) {
        return Err(Error::at_line(
            path,
            line_no,
            format!(
                "vertex has a coordinate that is not finite or beyond ±{:e} m ({} = {})",
                super::MAX_COORDINATE_M,
                ["x", "y", "z"][bad],
                tokens[bad]
            ),
            "fix or remove this vertex in the modelling tool and export again",
        ));
    }
    Ok(v)
}

/// Resolves a 1-based or negative (relative) OBJ index to 0-based, given how many elements came before.
fn resolve_index(path: &Path, line_no: usize, text: &str, before: usize, what: &str) -> Result<usize> {
    let x: i64 = text.parse().map_err(|_| {
        Error::at_line(path, line_no, format!("'{text}' is not a {what} index"), "indices are whole numbers from 1")
    })?;
    let resolved = if x > 0 { Some((x - 1) as usize) } else { (before as i64 + x).try_into().ok().filter(|_| x < 0) };
    resolved.ok_or_else(|| {
        Error::at_line(
            path,
            line_no,
            format!("{what} index {x} is out of range ({before} `{what}` lines before this face)"),
            "OBJ indices start at 1; negative indices count back from the last vertex",
        )
    })
}

/// Checks a mesh before writing it.
fn check_mesh(path: &Path, mesh: &MeshData) -> Result<()> {
    let field = |f: &str| format!("{}: mesh.{f}", path.display());
    if let Some(i) = mesh.vertices.iter().position(|v| v.iter().any(|c| !c.is_finite())) {
        return Err(Error::invalid(
            field("vertices"),
            format!("vertex {} is not finite: {:?}", i + 1, mesh.vertices[i]),
            "this is a bug in the code that built the mesh; please report it",
        ));
    }
    let nv = mesh.vertices.len();
    if let Some(t) = mesh.triangles.iter().position(|t| t.iter().any(|&i| i as usize >= nv)) {
        return Err(Error::invalid(
            field("triangles"),
            format!("triangle {} uses vertex {:?}, but there are {nv} vertices", t + 1, mesh.triangles[t]),
            "this is a bug in the code that built the mesh; please report it",
        ));
    }
    for (name, per_tri, names) in
        [("group", &mesh.group, &mesh.group_names), ("material", &mesh.material, &mesh.material_names)]
    {
        if !per_tri.is_empty() && per_tri.len() != mesh.triangles.len() {
            return Err(Error::invalid(
                field(name),
                format!("{} entries for {} triangles", per_tri.len(), mesh.triangles.len()),
                "this is a bug in the code that built the mesh; please report it",
            ));
        }
        let limit = names.len().max(1);
        if let Some(&bad) = per_tri.iter().find(|&&i| i as usize >= limit) {
            return Err(Error::invalid(
                field(name),
                format!("index {bad} but only {} {name} names", names.len()),
                "this is a bug in the code that built the mesh; please report it",
            ));
        }
        if let Some(bad) = names.iter().find(|n| n.contains(['\n', '\r'])) {
            return Err(Error::invalid(field(name), format!("{name} name {bad:?} has a line break"), "rename it"));
        }
    }
    Ok(())
}

fn internal(path: &Path, message: String) -> Error {
    Error::format(
        path.display().to_string(),
        message,
        "this is a talus bug; please report it with the file; as a workaround, re-export the OBJ with triangles only",
    )
}

/// A `BufRead` over bytes that knows how far it has been read, so a `tobj` error can be given a line number.
struct LineTracker<'a> {
    data: &'a [u8],
    pos: usize,
}

impl LineTracker<'_> {
    /// The 1-based line the reader stopped in or just after.
    fn line(&self) -> usize {
        let read = &self.data[..self.pos];
        let newlines = read.iter().filter(|&&b| b == b'\n').count();
        if read.last().is_some_and(|&b| b != b'\n') {
            newlines + 1
        } else {
            newlines.max(1)
        }
    }
}

impl Read for LineTracker<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = buf.len().min(self.data.len() - self.pos);
        buf[..n].copy_from_slice(&self.data[self.pos..self.pos + n]);
        self.pos += n;
        Ok(n)
    }
}

impl BufRead for LineTracker<'_> {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        Ok(&self.data[self.pos..])
    }

    fn consume(&mut self, amt: usize) {
        self.pos = (self.pos + amt).min(self.data.len());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read_str(text: &str) -> Result<MeshData> {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("m.obj");
        std::fs::write(&p, text).unwrap();
        read_obj(&p)
    }

    const SQUARE: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";

    #[test]
    fn quads_polygons_and_relative_indices() {
        let m = read_str(&format!("{SQUARE}v 2 0 0\nf 1 2 3 4\nf -4 5 -3\n")).unwrap();
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3], [1, 4, 2]]);
        assert_eq!(m.group_names, vec!["default"]);
        assert_eq!(m.material_names, vec![""]);
        assert_eq!(m.group, vec![0, 0, 0]);
    }

    #[test]
    fn texcoords_normals_and_polylines() {
        let text = format!("{SQUARE}vt 0 0\nvn 0 0 1\nl 1 2 3\nf 1/1/1 2/1/1 3//1\n");
        let m = read_str(&text).unwrap();
        assert_eq!(m.triangles, vec![[0, 1, 2]]);
        assert_eq!(m.vertices.len(), 4);
    }

    #[test]
    fn w_and_colours() {
        let m = read_str("v 2 4 6 2\nv 1 0 0 2\nv 0 1 0\nf 1 2 3\n").unwrap();
        assert_eq!(m.vertices[0], [1.0, 2.0, 3.0]);
        assert_eq!(m.vertices[1], [0.5, 0.0, 0.0]);
        // Vertex colours, on some vertices only (tobj alone would fail).
        let m = read_str("v 1 0 0 0.5 0.5 0.5\nv 0 1 0\nv 0 0 1 0 0 0\nf 1 2 3\n").unwrap();
        assert_eq!(m.vertices[1], [0.0, 1.0, 0.0]);
    }

    #[test]
    fn errors_name_line() {
        let err = read_str(&format!("{SQUARE}f 1 2 5\n")).unwrap_err().to_string();
        assert!(err.contains("m.obj:5") && err.contains("out of range"), "{err}");
        let err = read_str(&format!("{SQUARE}f 1 2 0\n")).unwrap_err().to_string();
        assert!(err.contains("m.obj:5") && err.contains("index 0"), "{err}");
        let err = read_str(&format!("{SQUARE}f 1 2\n")).unwrap_err().to_string();
        assert!(err.contains("m.obj:5") && err.contains("at least 3"), "{err}");
        let err = read_str("v 0 0 0\nv 1 x 0\n").unwrap_err().to_string();
        assert!(err.contains("m.obj:2") && err.contains("'x'"), "{err}");
        let err = read_str("v 0 0 0\nv 1 0 inf\n").unwrap_err().to_string();
        assert!(err.contains("m.obj:2") && err.contains("z = inf"), "{err}");
        // tobj's own error, with the line it stopped on.
        let err = read_str(&format!("{SQUARE}vt x y\nf 1 2 3\n")).unwrap_err().to_string();
        assert!(err.contains("m.obj:5") && err.contains("tobj"), "{err}");
    }

    #[test]
    fn line_tracker_counts_lines() {
        let mut r = LineTracker { data: b"a\nb\nc", pos: 0 };
        let mut s = String::new();
        r.read_line(&mut s).unwrap();
        assert_eq!(r.line(), 1);
        r.read_line(&mut s).unwrap();
        r.read_line(&mut s).unwrap();
        assert_eq!(r.line(), 3);
    }
}
