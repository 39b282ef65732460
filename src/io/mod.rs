//! File formats: terrain meshes and grids in, rasters and tables out. Formats only, no physics.

/// Largest coordinate a mesh vertex may have, m (ours: a million kilometres, far past any projected or geocentric
/// coordinate; beyond it a triangle's products overflow and the terrain reads as degenerate).
pub const MAX_COORDINATE_M: f64 = 1e9;

/// True if `c` is a coordinate a mesh may hold: finite and within [`MAX_COORDINATE_M`].
pub fn coordinate_ok(c: f64) -> bool {
    c.is_finite() && c.abs() <= MAX_COORDINATE_M
}

pub mod ascii_grid;
pub mod atomic;
pub mod csv_text;
pub mod geojson;
pub mod geotiff;
mod grid_check;
pub mod obj;
pub mod points;
pub mod stl;

pub use atomic::{write_atomic, write_bytes_atomic, write_json_atomic};

/// Creates the folder `dir` and its parents. An error names the folder, says that it could not be made and how to
/// fix that ([`crate::Error::io`]'s hint for the operating system's error).
pub fn create_folder(dir: &std::path::Path) -> crate::error::Result<()> {
    std::fs::create_dir_all(dir)
        .map_err(|e| crate::Error::io(dir, std::io::Error::new(e.kind(), format!("cannot create this folder: {e}"))))
}

/// A triangle mesh as read from a file, in the file's own frame and axes (no origin shift, no axis swap).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MeshData {
    /// Vertex positions.
    pub vertices: Vec<[f64; 3]>,
    /// Triangles as indices into `vertices`, in the file's winding.
    pub triangles: Vec<[u32; 3]>,
    /// Per triangle: index into `group_names` (OBJ object or group; a single group for STL).
    pub group: Vec<u32>,
    /// Group names (OBJ `o`/`g` names; the file stem for STL).
    pub group_names: Vec<String>,
    /// Per triangle: index into `material_names` (OBJ `usemtl`; 0 when absent).
    pub material: Vec<u32>,
    /// Material names (OBJ `usemtl` names; `""` when absent).
    pub material_names: Vec<String>,
}

/// A TOML error's message in a user's words: serde's Rust type names (`expected f64`, `expected usize`) as what
/// the value should be, and a duplicate key named (`text` is the file's text).
pub fn toml_message(text: &str, e: &toml::de::Error) -> String {
    let mut m = e.message().trim().to_string();
    if m == "duplicate key" {
        if let Some(key) = e.span().and_then(|s| text.get(s)).map(str::trim).filter(|k| !k.is_empty()) {
            m = format!("duplicate key `{key}` (a key or table given twice)");
        }
    }
    for (rust, words) in [
        ("f64", "a number"),
        ("usize", "a whole number of 0 or more"),
        ("u64", "a whole number of 0 or more"),
        ("u32", "a whole number from 0 to 4294967295"),
        ("i64", "a whole number"),
        ("bool", "true or false"),
    ] {
        m = m.replace(&format!("expected {rust}"), &format!("expected {words}"));
    }
    m
}

/// A TOML error as talus reports it: at `source:line`, in a user's words ([`toml_message`]), with `hint`.
pub fn toml_error(text: &str, source: &str, e: &toml::de::Error, hint: &str) -> crate::Error {
    crate::Error::format(toml_location(text, source, e), toml_message(text, e), hint)
}

/// Where a TOML error lies: `source:line` (1-based, the line of the error's span), or `source` without a span.
pub fn toml_location(text: &str, source: &str, e: &toml::de::Error) -> String {
    match e.span() {
        Some(span) => format!("{source}:{}", text[..span.start.min(text.len())].matches('\n').count() + 1),
        None => source.to_string(),
    }
}

#[cfg(test)]
mod tests {
    /// A u32 key given a larger whole number is told the range (it read "expected a whole number of 0 or more").
    #[test]
    fn a_toml_message_gives_a_whole_numbers_range() {
        #[derive(serde::Deserialize, Debug)]
        struct S {
            #[allow(dead_code)]
            n: u32,
        }
        let text = "n = 4294967297\n";
        let e = toml::from_str::<S>(text).unwrap_err();
        let m = super::toml_message(text, &e);
        assert!(m.contains("expected a whole number from 0 to 4294967295"), "{m}");
    }
}
