//! The library's error type.
//!
//! Every variant that comes from user input says where (file, line or field), what is wrong and how to fix it, so
//! that the binary can print it as it is and exit with code 2.

use std::path::{Path, PathBuf};

/// Result with the talus [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// What can go wrong in talus.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A file could not be read or written. Check the path and its permissions.
    #[error("{}: {os_error}\n  how to fix: {}", path.display(), io_hint(os_error.kind()))]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error (in the message, not a separate source, so that it is printed once).
        os_error: std::io::Error,
    },
    /// A file is malformed: `location` is `file:line` or `file` plus a field name.
    #[error("{location}: {message}\n  how to fix: {hint}")]
    Format {
        /// Where: `path:line`, `path: field`, or `path`.
        location: String,
        /// What is wrong.
        message: String,
        /// How to fix it.
        hint: String,
    },
    /// A parameter value is out of range or inconsistent: `field` names it as the user wrote it.
    #[error("{field}: {message}\n  how to fix: {hint}")]
    Invalid {
        /// The parameter, e.g. `materials.face.cr_mean` or `scenario.toml: rocks.mass_kg`.
        field: String,
        /// What is wrong.
        message: String,
        /// How to fix it.
        hint: String,
    },
}

/// How to fix an I/O error of this kind.
fn io_hint(kind: std::io::ErrorKind) -> &'static str {
    use std::io::ErrorKind::*;
    match kind {
        NotFound => {
            "check the path: on the command line it is relative to the folder talus runs in, inside a scenario or \
             settings file relative to that file"
        }
        PermissionDenied => "check the permissions of the file and its folder",
        AlreadyExists => "a file of that name is in the way: an output folder must be a folder, not a file",
        IsADirectory => "give a file, not a folder",
        NotADirectory => "a part of the path is a file, not a folder",
        InvalidData => "the file is not text (UTF-8) or not of the expected kind",
        UnexpectedEof => "the file ends too early: it may be truncated; copy or export it again",
        _ => "check the path, the disk and the permissions",
    }
}

impl Error {
    /// An I/O error on `path`.
    pub fn io(path: impl AsRef<Path>, source: std::io::Error) -> Self {
        Error::Io { path: path.as_ref().to_path_buf(), os_error: source }
    }

    /// A format error at `location` (`file:line` or `file: field`).
    pub fn format(location: impl Into<String>, message: impl Into<String>, hint: impl Into<String>) -> Self {
        Error::Format { location: location.into(), message: message.into(), hint: hint.into() }
    }

    /// A format error at `line` (1-based) of `path`.
    pub fn at_line(path: impl AsRef<Path>, line: usize, message: impl Into<String>, hint: impl Into<String>) -> Self {
        Error::format(format!("{}:{line}", path.as_ref().display()), message, hint)
    }

    /// An invalid parameter named `field`.
    pub fn invalid(field: impl Into<String>, message: impl Into<String>, hint: impl Into<String>) -> Self {
        Error::Invalid { field: field.into(), message: message.into(), hint: hint.into() }
    }

    /// This error located in the file at `path`, for checks that name only the field (a profile scenario's,
    /// say) when several files are read: an [`Error::Invalid`] whose field names no file yet (has no `": "`)
    /// gets `path: ` before it; any other error names its file already and is returned as it is.
    pub fn in_file(self, path: impl AsRef<Path>) -> Self {
        match self {
            Error::Invalid { field, message, hint } if !field.contains(": ") => {
                Error::Invalid { field: format!("{}: {field}", path.as_ref().display()), message, hint }
            }
            other => other,
        }
    }
}

/// `v` as error messages show it: with at most 6 decimals between 0.001 and a million, otherwise in scientific
/// notation with 3 significant digits (so that 1e308 does not take 309 digits).
pub fn number_text(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        format!("{v}")
    } else if (1e-3..1e6).contains(&v.abs()) {
        let text = format!("{v:.6}");
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        format!("{v:.2e}")
    }
}

/// `v` (positive) rounded up to 3 significant digits: a least allowed value that a message can show and that is
/// still allowed as shown.
pub fn round_up_3_digits(v: f64) -> f64 {
    if !(v.is_finite() && v > 0.0) {
        return v;
    }
    let unit = 10f64.powi(v.log10().floor() as i32 - 2);
    (v / unit).ceil() * unit
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn in_file_names_the_file_of_a_field_that_names_none() {
        let e = Error::invalid("collectors_x_m[0]", "is outside", "move it").in_file("b.toml");
        assert!(e.to_string().starts_with("b.toml: collectors_x_m[0]: is outside"), "{e}");
        // A field that names its file already, a format error and an I/O error are left as they are.
        let e = Error::invalid("camp/release_points.csv: run 3", "is off", "fix it").in_file("b.toml");
        assert!(e.to_string().starts_with("camp/release_points.csv: run 3:"), "{e}");
        let e = Error::at_line("profile.csv", 4, "bad number", "fix it").in_file("b.toml");
        assert!(e.to_string().starts_with("profile.csv:4:"), "{e}");
    }
}
