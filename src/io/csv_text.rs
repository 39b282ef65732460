//! CSV text: fields written by hand (RFC 4180 quoting; empty for numbers that are not finite), and the file line
//! of a record read with the `csv` crate.

/// The lines of a CSV text, to name the line of a record. The `csv` crate's own `Position::line` is one short after
/// a header ended by CRLF (csv 1.4; the Tschamut files have CRLF), and a record's byte offset is where its
/// reading began: before the line end of the record above and any blank lines. The record's line is that of its
/// first byte past them.
pub struct Lines<'a> {
    text: &'a [u8],
    starts: Vec<usize>,
}

impl<'a> Lines<'a> {
    /// Indexes the line starts of `text`.
    pub fn new(text: &'a [u8]) -> Lines<'a> {
        let breaks = text.iter().enumerate().filter(|(_, &b)| b == b'\n').map(|(i, _)| i + 1);
        Lines { text, starts: std::iter::once(0).chain(breaks).collect() }
    }

    /// The 1-based line at a record's (or an error's) position; 0 when there is none.
    pub fn of(&self, position: Option<&csv::Position>) -> usize {
        position.map_or(0, |p| {
            let mut b = (p.byte() as usize).min(self.text.len());
            while self.text.get(b).is_some_and(|c| matches!(c, b'\r' | b'\n')) {
                b += 1;
            }
            self.starts.partition_point(|&start| start <= b)
        })
    }
}

/// A text field, quoted when it holds a comma, a quote or a line break.
pub fn field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// A number with `decimals` decimals, or an empty field when it is not finite.
pub fn number(v: f64, decimals: usize) -> String {
    if v.is_finite() {
        format!("{v:.decimals$}")
    } else {
        String::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quotes_only_when_needed() {
        assert_eq!(field("bench 1"), "bench 1");
        assert_eq!(field("a,\"b\""), "\"a,\"\"b\"\"\"");
        assert_eq!(number(1.23456, 2), "1.23");
        assert_eq!(number(f64::NAN, 2), "");
    }

    #[test]
    fn records_are_placed_on_their_file_line_with_either_line_end() {
        for text in ["a,b\n1,2\n\n3,4\n", "a,b\r\n1,2\r\n\r\n3,4\r\n"] {
            let lines = Lines::new(text.as_bytes());
            let mut rdr = csv::ReaderBuilder::new().from_reader(text.as_bytes());
            let found: Vec<usize> = rdr.records().map(|r| lines.of(r.unwrap().position())).collect();
            assert_eq!(found, [2, 4], "{text:?}");
        }
    }
}
