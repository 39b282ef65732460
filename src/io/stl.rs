//! STL meshes, ASCII or binary, read with `stl_io`.
//!
//! A file is binary when its size is exactly 84 + 50·N bytes, N being the triangle count in its header (even if
//! the 80-byte header starts with `solid`, as some exporters write). Otherwise it is ASCII if it starts with
//! `solid` and holds no NUL byte, and a truncated or padded binary file if not.
//!
//! ASCII files are read line by line by our own parser (structure, numbers, finite vertices; a file that stops
//! inside a facet is reported with the line where that facet starts; a bare `solid` first line, a missing
//! `endsolid` or a `nan` normal are fine). Their coordinates are read as `f64`, as written: an exporter that writes
//! full-precision map coordinates (a UTM northing of 7,500,000.41 m, say) keeps them, where `f32` would round them
//! to steps of 0.5 m. Binary files hold `f32` coordinates; they are checked for non-finite vertices and parsed by
//! `stl_io`. Both merge bit-identical vertices.

use crate::error::{Error, Result};
use crate::io::MeshData;
use std::collections::HashMap;
use std::io::Cursor;
use std::path::Path;

/// Size of the binary header: 80 bytes of text plus the u32 triangle count.
const BINARY_HEADER_BYTES: usize = 84;
/// Size of one binary triangle record: normal, 3 vertices (12 f32) and a u16 attribute.
const BINARY_TRIANGLE_BYTES: usize = 50;

/// Reads an ASCII or binary STL as one group named after the file stem, with material `""`.
pub fn read_stl(path: &Path) -> Result<MeshData> {
    let mut bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let loc = path.display().to_string();
    let binary_count = (bytes.len() >= BINARY_HEADER_BYTES)
        .then(|| u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize);
    let is_binary = binary_count
        .is_some_and(|n| n.checked_mul(BINARY_TRIANGLE_BYTES).map(|b| b + BINARY_HEADER_BYTES) == Some(bytes.len()));

    let (vertices, triangles) = if is_binary {
        check_binary(path, &bytes)?;
        // stl_io treats a file whose first line starts with "solid " as ASCII: hide that word in the header.
        if bytes.starts_with(b"solid") {
            bytes[..5].copy_from_slice(b"SOLID");
        }
        read_binary(path, bytes)?
    } else if starts_with_solid(&bytes) && !bytes.contains(&0) {
        // Text never holds a NUL byte; a binary file whose header starts with `solid` does (attribute words,
        // zeros), so a truncated one falls through to the size message below rather than "no facets".
        read_ascii(path, &String::from_utf8_lossy(&bytes))?
    } else {
        return Err(match binary_count {
            Some(n) => Error::format(
                loc,
                format!(
                    "binary STL header says {n} triangles, so the file should be 84 + 50 × {n} = {} bytes, but it \
                     is {} bytes",
                    BINARY_HEADER_BYTES as u128 + BINARY_TRIANGLE_BYTES as u128 * n as u128,
                    bytes.len()
                ),
                "the file is truncated or damaged; export it again",
            ),
            None => Error::format(
                loc,
                format!(
                    "{} bytes is too short for a binary STL (84-byte header) and it does not start with `solid`",
                    bytes.len()
                ),
                "export the mesh again as STL",
            ),
        });
    };

    let n = triangles.len();
    let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "stl".to_string());
    Ok(MeshData {
        vertices,
        triangles,
        group: vec![0; n],
        group_names: vec![stem],
        material: vec![0; n],
        material_names: vec![String::new()],
    })
}

/// A parsed STL: vertices and triangles (indices into them).
type Parsed = (Vec<[f64; 3]>, Vec<[u32; 3]>);

/// Parses a checked binary STL with `stl_io`: vertices (f32 widened) and triangles.
fn read_binary(path: &Path, bytes: Vec<u8>) -> Result<Parsed> {
    let loc = path.display().to_string();
    let mesh = stl_io::read_stl(&mut Cursor::new(bytes)).map_err(|e| {
        Error::format(loc.clone(), format!("the STL parser (stl_io) failed: {e}"), "export the mesh again as STL")
    })?;
    if mesh.faces.is_empty() {
        return Err(Error::format(loc, "the STL has no triangles", "export the surface with its faces"));
    }
    let vertices: Vec<[f64; 3]> = mesh.vertices.iter().map(|v| v.0.map(f64::from)).collect();
    let triangles = mesh
        .faces
        .iter()
        .map(|f| {
            let mut t = [0u32; 3];
            for (k, &i) in f.vertices.iter().enumerate() {
                t[k] = u32::try_from(i)
                    .map_err(|_| Error::format(loc.clone(), "more than 2^32 vertices", "decimate the mesh"))?;
            }
            Ok(t)
        })
        .collect::<Result<Vec<_>>>()?;
    Ok((vertices, triangles))
}

/// True if the first word of the file is `solid`.
fn starts_with_solid(bytes: &[u8]) -> bool {
    let start = bytes.iter().position(|b| !b.is_ascii_whitespace()).unwrap_or(bytes.len());
    let rest = &bytes[start..];
    rest.starts_with(b"solid") && rest.get(5).is_none_or(|b| b.is_ascii_whitespace())
}

/// Checks a binary STL: at least one triangle, all vertex coordinates finite.
fn check_binary(path: &Path, bytes: &[u8]) -> Result<()> {
    let records = bytes[BINARY_HEADER_BYTES..].chunks_exact(BINARY_TRIANGLE_BYTES);
    if records.len() == 0 {
        return Err(Error::format(
            path.display().to_string(),
            "the binary STL has no triangles (its header says 0)",
            "export the surface with its faces",
        ));
    }
    for (t, rec) in records.enumerate() {
        for k in 0..9 {
            let o = 12 + 4 * k;
            let c = f32::from_le_bytes([rec[o], rec[o + 1], rec[o + 2], rec[o + 3]]);
            if !super::coordinate_ok(c as f64) {
                return Err(Error::format(
                    format!("{}: triangle {}", path.display(), t + 1),
                    format!(
                        "vertex {} has a coordinate that is not finite or beyond ±{:e} m: {} = {c} (byte offset {})",
                        k / 3 + 1,
                        super::MAX_COORDINATE_M,
                        ["x", "y", "z"][k % 3],
                        BINARY_HEADER_BYTES + BINARY_TRIANGLE_BYTES * t + o
                    ),
                    "fix the mesh in the modelling tool and export it again",
                ));
            }
        }
    }
    Ok(())
}

/// Reads an ASCII STL line by line: vertices in `f64` as written (bit-identical ones merged, in first-seen order)
/// and triangles.
fn read_ascii(path: &Path, text: &str) -> Result<Parsed> {
    let mut lines = text.split('\n').enumerate().map(|(i, l)| (i + 1, l.split_whitespace().collect::<Vec<_>>()));
    let mut lines = lines.by_ref().filter(|(_, t)| !t.is_empty());
    let mut vertices: Vec<[f64; 3]> = Vec::new();
    let mut index: HashMap<[u64; 3], u32> = HashMap::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    lines.next(); // the `solid name` line, checked by the caller
    let mut last_line = 1;
    // A missing `endsolid` is tolerated.
    while let Some((line_no, tokens)) = lines.next() {
        last_line = line_no;
        match tokens[0] {
            "endsolid" => {
                if let Some((extra, _)) = lines.next() {
                    return Err(Error::at_line(
                        path,
                        extra,
                        "content after `endsolid` (several solids in one file are not supported)",
                        "merge the solids into one, or export one surface per file",
                    ));
                }
                break;
            }
            "facet" => {}
            other => {
                return Err(Error::at_line(
                    path,
                    line_no,
                    format!("expected `facet normal nx ny nz` or `endsolid`, found `{other}`"),
                    "check the file against the ASCII STL format, or export it again",
                ))
            }
        }
        let start = line_no;
        let mut expect = |want: &str| -> Result<(usize, Vec<&str>)> {
            match lines.next() {
                Some((l, t)) if t[0] == want => Ok((l, t)),
                Some((l, t)) => Err(Error::at_line(
                    path,
                    l,
                    format!("expected `{want}` in the facet that starts at line {start}, found `{}`", t.join(" ")),
                    "check the file against the ASCII STL format, or export it again",
                )),
                None => Err(Error::at_line(
                    path,
                    start,
                    format!("the file ends inside the facet that starts here (expected `{want}`)"),
                    "the file is truncated; export it again",
                )),
            }
        };
        expect("outer")?;
        let mut tri = [0u32; 3];
        for corner in &mut tri {
            let (l, t) = expect("vertex")?;
            if t.len() != 4 {
                return Err(Error::at_line(
                    path,
                    l,
                    format!("a vertex line needs 3 numbers, found {}", t.len() - 1),
                    "write it as `vertex x y z`",
                ));
            }
            let mut v = [0.0f64; 3];
            for (k, tok) in t[1..].iter().enumerate() {
                let c: f64 = tok.parse().map_err(|_| {
                    Error::at_line(path, l, format!("'{tok}' is not a number"), "write it as `vertex x y z`")
                })?;
                if !super::coordinate_ok(c) {
                    return Err(Error::at_line(
                        path,
                        l,
                        format!(
                            "vertex has a coordinate that is not finite or beyond ±{:e} m ({} = {tok})",
                            super::MAX_COORDINATE_M,
                            ["x", "y", "z"][k]
                        ),
                        "fix the mesh in the modelling tool and export it again",
                    ));
                }
                v[k] = c;
            }
            let next = u32::try_from(vertices.len())
                .map_err(|_| Error::at_line(path, l, "more than 2^32 vertices", "decimate the mesh"))?;
            // `+ 0.0` makes −0 and 0 one vertex.
            *corner = *index.entry(v.map(|c| (c + 0.0).to_bits())).or_insert_with(|| {
                vertices.push(v);
                next
            });
        }
        expect("endloop")?;
        expect("endfacet")?;
        triangles.push(tri);
    }
    if triangles.is_empty() {
        return Err(Error::at_line(path, last_line, "the STL has no facets", "export the surface with its faces"));
    }
    Ok((vertices, triangles))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read_bytes(bytes: &[u8]) -> Result<MeshData> {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("s.stl");
        std::fs::write(&p, bytes).unwrap();
        read_stl(&p)
    }

    const FACET: &str =
        "facet normal 0 0 1\n outer loop\n  vertex 0 0 0\n  vertex 1 0 0\n  vertex 0 1 0\n endloop\nendfacet\n";

    #[test]
    fn ascii_variants() {
        let m = read_bytes(format!("solid\n{FACET}").as_bytes()).unwrap();
        assert_eq!(m.triangles.len(), 1);
        assert_eq!(m.group_names, vec!["s"]);
        let nan_normal = FACET.replace("0 0 1", "nan nan nan");
        let m = read_bytes(format!("  solid x\r\n{nan_normal}{FACET}endsolid x\n").as_bytes()).unwrap();
        assert_eq!((m.triangles.len(), m.vertices.len()), (2, 3));
    }

    #[test]
    fn ascii_errors_name_line() {
        let cut: String = FACET.lines().take(4).map(|l| format!("{l}\n")).collect();
        let err = read_bytes(format!("solid x\n{FACET}{cut}").as_bytes()).unwrap_err().to_string();
        assert!(err.contains("s.stl:9") && err.contains("ends inside the facet"), "{err}");
        let bad = FACET.replace("vertex 1 0 0", "vertex 1 nan 0");
        let err = read_bytes(format!("solid x\n{bad}").as_bytes()).unwrap_err().to_string();
        assert!(err.contains("s.stl:5") && err.contains("y = nan"), "{err}");
        let err = read_bytes(b"solid x\nendsolid x\n").unwrap_err().to_string();
        assert!(err.contains("no facets"), "{err}");
    }

    #[test]
    fn binary_with_solid_header() {
        let mut b = vec![0u8; 84];
        b[..10].copy_from_slice(b"solid junk");
        b[80] = 1;
        let mut rec = vec![0u8; 50];
        for (k, c) in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0].iter().enumerate() {
            rec[12 + 4 * k..16 + 4 * k].copy_from_slice(&c.to_le_bytes());
        }
        b.extend(&rec);
        let m = read_bytes(&b).unwrap();
        assert_eq!(m.triangles, vec![[0, 1, 2]]);
        rec[28..32].copy_from_slice(&f32::INFINITY.to_le_bytes());
        b.truncate(84);
        b.extend(&rec);
        let err = read_bytes(&b).unwrap_err().to_string();
        assert!(err.contains("triangle 1") && err.contains("vertex 2 has") && err.contains("y = inf"), "{err}");
    }
}
