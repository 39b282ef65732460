//! Point files for convex-hull rock shapes, and the dispatcher that reads hull points from any supported format.
//!
//! A point file holds one `x y z` per line, separated by whitespace or commas (so CSV works). `#` starts a comment;
//! blank lines are ignored; a first line whose first field is not a number is a header and is skipped.

use crate::error::{Error, Result};
use crate::io::{obj, stl};
use std::path::Path;

/// The fewest points that can span a solid hull.
pub const MIN_HULL_POINTS: usize = 4;

/// Reads a point file (see the module documentation); at least [`MIN_HULL_POINTS`] points.
pub fn read_points(path: &Path) -> Result<Vec<[f64; 3]>> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let text = String::from_utf8_lossy(&bytes);
    let mut points = Vec::new();
    let mut seen_content = false;
    for (i, raw) in text.split('\n').enumerate() {
        let line_no = i + 1;
        let content = raw.split('#').next().unwrap_or("");
        let fields: Vec<&str> =
            content.split(|c: char| c == ',' || c.is_whitespace()).filter(|f| !f.is_empty()).collect();
        if fields.is_empty() {
            continue;
        }
        let first_content = !seen_content;
        seen_content = true;
        if first_content && fields[0].parse::<f64>().is_err() {
            continue; // header
        }
        if fields.len() != 3 {
            return Err(Error::at_line(
                path,
                line_no,
                format!("expected 3 numbers (x y z), found {} fields", fields.len()),
                "write one point per line as `x y z` or `x,y,z`",
            ));
        }
        let mut p = [0.0; 3];
        for (k, f) in fields.iter().enumerate() {
            p[k] = f.parse::<f64>().ok().filter(|&v| crate::io::coordinate_ok(v)).ok_or_else(|| {
                Error::at_line(
                    path,
                    line_no,
                    format!(
                        "{} = '{f}' is not a finite number within ±{:e} m",
                        ["x", "y", "z"][k],
                        crate::io::MAX_COORDINATE_M
                    ),
                    "write one point per line as `x y z` or `x,y,z`",
                )
            })?;
        }
        points.push(p);
    }
    check_count(path, points)
}

/// Reads the points of a hull shape by extension: `.obj` → its `v` lines (faces are checked but not needed, so a
/// bare point cloud works), `.stl` → the vertices of [`stl::read_stl`], anything else → [`read_points`].
pub fn read_hull_points(path: &Path) -> Result<Vec<[f64; 3]>> {
    let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
    match ext.as_str() {
        "obj" => check_count(path, obj::read_obj_vertices(path)?),
        "stl" => check_count(path, stl::read_stl(path)?.vertices),
        _ => read_points(path),
    }
}

/// Requires at least [`MIN_HULL_POINTS`] points.
fn check_count(path: &Path, points: Vec<[f64; 3]>) -> Result<Vec<[f64; 3]>> {
    if points.len() < MIN_HULL_POINTS {
        return Err(Error::format(
            path.display().to_string(),
            format!("a convex hull needs at least {MIN_HULL_POINTS} points, found {}", points.len()),
            "give at least 4 points that are not all in one plane",
        ));
    }
    Ok(points)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(name: &str, text: &str) -> (tempfile::TempDir, std::path::PathBuf) {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        (dir, p)
    }

    #[test]
    fn header_comments_commas() {
        let (_d, p) = write("r.csv", "x,y,z\n# a rock\n0,0,0\n1, 0, 0 # corner\n\n0 1 0\n0\t0\t1\n");
        let pts = read_points(&p).unwrap();
        assert_eq!(pts, vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);
    }

    #[test]
    fn errors() {
        let (_d, p) = write("r.xyz", "0 0 0\n1 0 0\n0 1\n0 0 1\n");
        let err = read_points(&p).unwrap_err().to_string();
        assert!(err.contains("r.xyz:3") && err.contains("found 2 fields"), "{err}");
        let (_d, p) = write("r.xyz", "0 0 0\n1 0 0\n0 y 0\n0 0 1\n");
        let err = read_points(&p).unwrap_err().to_string();
        assert!(err.contains("r.xyz:3") && err.contains("y = 'y'"), "{err}");
        let (_d, p) = write("r.xyz", "0 0 0\n1 0 0\n0 1 0\n0 0 1e300\n");
        let err = read_points(&p).unwrap_err().to_string();
        assert!(err.contains("r.xyz:4") && err.contains("z = '1e300' is not a finite number within ±1e9 m"), "{err}");
        let (_d, p) = write("r.xyz", "0 0 0\n1 0 0\n0 1 0\n");
        let err = read_points(&p).unwrap_err().to_string();
        assert!(err.contains("at least 4 points, found 3"), "{err}");
    }

    #[test]
    fn obj_point_cloud() {
        let (_d, p) = write("r.OBJ", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n");
        assert_eq!(read_hull_points(&p).unwrap().len(), 4);
    }
}
