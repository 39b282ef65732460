//! CSV text: fields written by hand (RFC 4180 quoting; empty for numbers that are not finite), and tables read
//! with the `csv` crate whose rows know their file line.

use crate::error::{Error, Result};
use std::path::Path;

/// Largest number a CSV field may hold (ours: 10¹⁵ is past any coordinate, time stamp in milliseconds or mass
/// in a field campaign, and far below where squares and products of coordinates overflow: 1e308 passed the
/// reading and failed after a whole calibration).
pub const MAX_NUMBER: f64 = 1e15;

/// A CSV file read whole: its header and its rows, fields trimmed, rows of empty fields skipped, each row with
/// the file line it came from, so that every reader names the line of a bad value the same way.
///
/// Every row has one field per header column: a row with more or fewer is refused (a decimal comma, `77,17`, or
/// an unquoted comma in a text would otherwise shift the values into the wrong columns). A quoted field
/// (`"a, b"`) is one field. One extra empty field at the end of a row (a trailing comma) holds no value and is
/// dropped. A header of one column holding `;` is refused: the file is semicolon-separated.
#[derive(Debug)]
pub struct Table {
    /// The file (or other source) the table came from, for error messages.
    pub source: String,
    /// Column names.
    pub header: Vec<String>,
    /// Rows with their 1-based file line.
    pub rows: Vec<Row>,
}

/// One row of a [`Table`].
#[derive(Debug)]
pub struct Row {
    /// 1-based line in the file.
    pub line: usize,
    /// Fields, trimmed; one per header column.
    pub fields: Vec<String>,
}

impl Table {
    /// Reads the CSV file `path`; with `comments`, lines starting with `#` are skipped.
    ///
    /// # Errors
    /// I/O errors, and CSV syntax errors naming the file and line.
    pub fn read(path: &Path, comments: bool) -> Result<Table> {
        let text = std::fs::read(path).map_err(|e| Error::io(path, e))?;
        Table::parse(&text, &path.display().to_string(), comments)
    }

    /// Parses CSV `text`; `source` names it in errors.
    ///
    /// # Errors
    /// CSV syntax errors naming `source` and the line; a semicolon-separated header; a row with more or fewer
    /// fields than the header (see [`Table`]).
    pub fn parse(text: &[u8], source: &str, comments: bool) -> Result<Table> {
        let lines = Lines::new(text, comments);
        let syntax = |e: csv::Error| match lines.of(e.position()) {
            0 => Error::format(source, e.to_string(), "fix the CSV syntax"),
            l => Error::at_line(source, l, e.to_string(), "fix the CSV syntax on this line"),
        };
        let mut rdr = csv::ReaderBuilder::new()
            .trim(csv::Trim::All)
            .flexible(true)
            .comment(comments.then_some(b'#'))
            .from_reader(text);
        let header: Vec<String> = rdr.headers().map_err(syntax)?.iter().map(str::to_string).collect();
        semicolon_header(&header, source)?;
        let mut rows = Vec::new();
        for rec in rdr.records() {
            let rec = rec.map_err(syntax)?;
            if rec.iter().any(|f| !f.is_empty()) {
                let mut row = Row { line: lines.of(rec.position()), fields: rec.iter().map(str::to_string).collect() };
                check_field_count(&mut row, header.len(), source)?;
                rows.push(row);
            }
        }
        Ok(Table { source: source.to_string(), header, rows })
    }

    /// The index of column `name`, if the header has it.
    pub fn col(&self, name: &str) -> Option<usize> {
        self.header.iter().position(|h| h == name)
    }

    /// The index of column `name`.
    ///
    /// # Errors
    /// The header has no such column: an error at line 1 listing the columns found, with `hint`.
    pub fn need(&self, name: &str, hint: &str) -> Result<usize> {
        self.col(name).ok_or_else(|| {
            Error::at_line(
                &self.source,
                1,
                format!("the header has no column `{name}` (found: {})", self.header.join(",")),
                hint,
            )
        })
    }

    /// An error at `row`'s line.
    pub fn error(&self, row: &Row, message: impl Into<String>, hint: impl Into<String>) -> Error {
        Error::at_line(&self.source, row.line, message, hint)
    }

    /// The field of column `col` in `row`; empty when there is no such column.
    pub fn field<'r>(&self, row: &'r Row, col: Option<usize>) -> &'r str {
        col.and_then(|c| row.fields.get(c)).map_or("", String::as_str)
    }

    /// The non-empty field of column `col` (named `name`) in `row`.
    ///
    /// # Errors
    /// The field is empty, naming the file, line and column.
    pub fn text<'r>(&self, row: &'r Row, col: usize, name: &str) -> Result<&'r str> {
        match self.field(row, Some(col)) {
            "" => Err(self.error(row, format!("column `{name}` is empty"), "fill it in")),
            s => Ok(s),
        }
    }

    /// The finite number in column `col` (named `name`) of `row`, at most [`MAX_NUMBER`] in size.
    ///
    /// # Errors
    /// The field is empty, not a finite number or larger, naming the file, line and column.
    pub fn number(&self, row: &Row, col: usize, name: &str) -> Result<f64> {
        let s = self.text(row, col, name)?;
        s.parse::<f64>().ok().filter(|v| v.is_finite() && v.abs() <= MAX_NUMBER).ok_or_else(|| {
            self.error(
                row,
                format!("column `{name}` holds '{s}', not a finite number within ±{MAX_NUMBER:e}"),
                "write a plain number in SI units",
            )
        })
    }

    /// The number in column `name` of `row`, `None` when the header has no such column or the field is empty.
    ///
    /// # Errors
    /// A field that is not a finite number.
    pub fn optional_number(&self, row: &Row, name: &str) -> Result<Option<f64>> {
        match self.col(name) {
            Some(c) if !self.field(row, Some(c)).is_empty() => Ok(Some(self.number(row, c, name)?)),
            _ => Ok(None),
        }
    }
}

/// Refuses a header that is one column holding `;`: the file uses `;` as separator (as spreadsheets do where the
/// decimal mark is a comma), and talus reads commas.
fn semicolon_header(header: &[String], source: &str) -> Result<()> {
    match header {
        [only] if only.contains(';') => Err(Error::at_line(
            source,
            1,
            format!("the header `{only}` has `;` and no `,`: the file seems to use `;` as separator"),
            "talus reads commas: save the file as CSV with `,` between fields and `.` as the decimal mark",
        )),
        _ => Ok(()),
    }
}

/// Drops one trailing empty field of `row` beyond the `columns` of the header (a trailing comma), then refuses a
/// row whose field count differs from the header's, naming `source` and the line.
fn check_field_count(row: &mut Row, columns: usize, source: &str) -> Result<()> {
    if row.fields.len() == columns + 1 && row.fields.last().is_some_and(String::is_empty) {
        row.fields.pop();
    }
    let n = row.fields.len();
    if n == columns {
        return Ok(());
    }
    let hint = if n > columns {
        "a decimal comma or an unquoted comma in a field? Write decimals with a point (77.17) and put a field that \
         holds a comma in double quotes"
    } else {
        "a missing field? Every row needs one field per column: leave an empty one as nothing between two commas"
    };
    Err(Error::at_line(source, row.line, format!("the row has {n} fields but the header has {columns} columns"), hint))
}

/// The lines of a CSV text, to name the line of a record (used by [`Table`]). The `csv` crate's own `Position::line` is one short after
/// a header ended by CRLF (csv 1.4; the Tschamut files have CRLF), and a record's byte offset is where its
/// reading began: before the line end of the record above and any blank or comment lines. The record's line is
/// that of its first byte past them.
struct Lines<'a> {
    text: &'a [u8],
    starts: Vec<usize>,
    comments: bool,
}

impl<'a> Lines<'a> {
    /// Indexes the line starts of `text`.
    fn new(text: &'a [u8], comments: bool) -> Lines<'a> {
        let breaks = text.iter().enumerate().filter(|(_, &b)| b == b'\n').map(|(i, _)| i + 1);
        Lines { text, starts: std::iter::once(0).chain(breaks).collect(), comments }
    }

    /// The 1-based line at a record's (or an error's) position; 0 when there is none.
    fn of(&self, position: Option<&csv::Position>) -> usize {
        position.map_or(0, |p| {
            let mut b = (p.byte() as usize).min(self.text.len());
            loop {
                match self.text.get(b) {
                    Some(b'\r' | b'\n') => b += 1,
                    Some(b'#') if self.comments => {
                        b = self.text[b..].iter().position(|&c| c == b'\n').map_or(self.text.len(), |i| b + i + 1)
                    }
                    _ => break,
                }
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
    fn rows_are_placed_on_their_file_line_with_either_line_end() {
        for text in ["a,b\n1,2\n\n , \n3,x\n", "a,b\r\n1,2\r\n\r\n , \r\n3,x\r\n"] {
            let t = Table::parse(text.as_bytes(), "t.csv", false).unwrap();
            assert_eq!(t.rows.iter().map(|r| r.line).collect::<Vec<_>>(), [2, 5], "{text:?}");
            assert_eq!(t.number(&t.rows[0], 1, "b").unwrap(), 2.0);
            let e = t.number(&t.rows[1], 1, "b").unwrap_err().to_string();
            assert!(e.contains("t.csv:5") && e.contains("'x'"), "{e}");
            let t = Table::parse(text.replace('x', "-1e308").as_bytes(), "t.csv", false).unwrap();
            let e = t.number(&t.rows[1], 1, "b").unwrap_err().to_string();
            assert!(e.contains("t.csv:5") && e.contains("'-1e308'") && e.contains("within ±1e15"), "{e}");
            let e = t.need("c", "add it").unwrap_err().to_string();
            assert!(e.contains("t.csv:1") && e.contains("`c`") && e.contains("found: a,b"), "{e}");
        }
        let t = Table::parse(b"# note\na\n# again\n1\n", "t.csv", true).unwrap();
        assert_eq!((t.header.clone(), t.rows[0].line), (vec!["a".to_string()], 4));
        let e = Table::parse(b"a\n1\n\xff\n", "t.csv", false).unwrap_err().to_string();
        assert!(e.contains("t.csv:3") && e.contains("UTF-8"), "{e}");
    }
}
