//! A built-in 5×7 bitmap font (with two descender rows) and text drawing on a [`Canvas`].
//!
//! Glyphs are 5 pixels wide on a 6-pixel advance. Rows 0–6 hold capitals and digits (row 6 is the baseline row),
//! rows 7–8 hold descenders (g, j, p, q, y, comma). Text is scaled by an integer factor with nearest-neighbour
//! replication: ×2 is the usual size for labels, ×3 for titles. Characters without a glyph are drawn as a hollow
//! box so that missing glyphs are visible rather than silently dropped.

use super::canvas::{Canvas, Rgba};

/// Glyph width in font pixels.
pub const GLYPH_WIDTH: u32 = 5;
/// Horizontal advance per character in font pixels (glyph plus one pixel of spacing).
pub const ADVANCE: u32 = 6;
/// Height of capitals and digits in font pixels.
pub const CAP_HEIGHT: u32 = 7;
/// Height of the glyph box, descenders included, in font pixels.
pub const GLYPH_HEIGHT: u32 = 9;

type Glyph = [&'static str; 9];

const E: &str = ".....";

/// The glyphs, one per line: `#` is ink, `.` is paper.
#[rustfmt::skip]
const GLYPHS: &[(char, Glyph)] = &[
    (' ', [E, E, E, E, E, E, E, E, E]),
    ('0', [".###.", "#...#", "#..##", "#.#.#", "##..#", "#...#", ".###.", E, E]),
    ('1', ["..#..", ".##..", "..#..", "..#..", "..#..", "..#..", ".###.", E, E]),
    ('2', [".###.", "#...#", "....#", "...#.", "..#..", ".#...", "#####", E, E]),
    ('3', ["#####", "...#.", "..#..", "...#.", "....#", "#...#", ".###.", E, E]),
    ('4', ["...#.", "..##.", ".#.#.", "#..#.", "#####", "...#.", "...#.", E, E]),
    ('5', ["#####", "#....", "####.", "....#", "....#", "#...#", ".###.", E, E]),
    ('6', ["..##.", ".#...", "#....", "####.", "#...#", "#...#", ".###.", E, E]),
    ('7', ["#####", "....#", "...#.", "..#..", ".#...", ".#...", ".#...", E, E]),
    ('8', [".###.", "#...#", "#...#", ".###.", "#...#", "#...#", ".###.", E, E]),
    ('9', [".###.", "#...#", "#...#", ".####", "....#", "...#.", ".##..", E, E]),
    ('A', [".###.", "#...#", "#...#", "#####", "#...#", "#...#", "#...#", E, E]),
    ('B', ["####.", "#...#", "#...#", "####.", "#...#", "#...#", "####.", E, E]),
    ('C', [".###.", "#...#", "#....", "#....", "#....", "#...#", ".###.", E, E]),
    ('D', ["###..", "#..#.", "#...#", "#...#", "#...#", "#..#.", "###..", E, E]),
    ('E', ["#####", "#....", "#....", "####.", "#....", "#....", "#####", E, E]),
    ('F', ["#####", "#....", "#....", "####.", "#....", "#....", "#....", E, E]),
    ('G', [".###.", "#...#", "#....", "#.###", "#...#", "#...#", ".####", E, E]),
    ('H', ["#...#", "#...#", "#...#", "#####", "#...#", "#...#", "#...#", E, E]),
    ('I', [".###.", "..#..", "..#..", "..#..", "..#..", "..#..", ".###.", E, E]),
    ('J', ["..###", "...#.", "...#.", "...#.", "...#.", "#..#.", ".##..", E, E]),
    ('K', ["#...#", "#..#.", "#.#..", "##...", "#.#..", "#..#.", "#...#", E, E]),
    ('L', ["#....", "#....", "#....", "#....", "#....", "#....", "#####", E, E]),
    ('M', ["#...#", "##.##", "#.#.#", "#.#.#", "#...#", "#...#", "#...#", E, E]),
    ('N', ["#...#", "#...#", "##..#", "#.#.#", "#..##", "#...#", "#...#", E, E]),
    ('O', [".###.", "#...#", "#...#", "#...#", "#...#", "#...#", ".###.", E, E]),
    ('P', ["####.", "#...#", "#...#", "####.", "#....", "#....", "#....", E, E]),
    ('Q', [".###.", "#...#", "#...#", "#...#", "#.#.#", "#..#.", ".##.#", E, E]),
    ('R', ["####.", "#...#", "#...#", "####.", "#.#..", "#..#.", "#...#", E, E]),
    ('S', [".####", "#....", "#....", ".###.", "....#", "....#", "####.", E, E]),
    ('T', ["#####", "..#..", "..#..", "..#..", "..#..", "..#..", "..#..", E, E]),
    ('U', ["#...#", "#...#", "#...#", "#...#", "#...#", "#...#", ".###.", E, E]),
    ('V', ["#...#", "#...#", "#...#", "#...#", "#...#", ".#.#.", "..#..", E, E]),
    ('W', ["#...#", "#...#", "#...#", "#.#.#", "#.#.#", "#.#.#", ".#.#.", E, E]),
    ('X', ["#...#", "#...#", ".#.#.", "..#..", ".#.#.", "#...#", "#...#", E, E]),
    ('Y', ["#...#", "#...#", ".#.#.", "..#..", "..#..", "..#..", "..#..", E, E]),
    ('Z', ["#####", "....#", "...#.", "..#..", ".#...", "#....", "#####", E, E]),
    ('a', [E, E, ".###.", "....#", ".####", "#...#", ".####", E, E]),
    ('b', ["#....", "#....", "#.##.", "##..#", "#...#", "#...#", "####.", E, E]),
    ('c', [E, E, ".###.", "#....", "#....", "#...#", ".###.", E, E]),
    ('d', ["....#", "....#", ".##.#", "#..##", "#...#", "#...#", ".####", E, E]),
    ('e', [E, E, ".###.", "#...#", "#####", "#....", ".###.", E, E]),
    ('f', ["..##.", ".#..#", ".#...", "###..", ".#...", ".#...", ".#...", E, E]),
    ('g', [E, E, ".####", "#...#", "#...#", "#...#", ".####", "....#", ".###."]),
    ('h', ["#....", "#....", "#.##.", "##..#", "#...#", "#...#", "#...#", E, E]),
    ('i', ["..#..", E, ".##..", "..#..", "..#..", "..#..", ".###.", E, E]),
    ('j', ["...#.", E, "..##.", "...#.", "...#.", "...#.", "...#.", "#..#.", ".##.."]),
    ('k', ["#....", "#....", "#..#.", "#.#..", "##...", "#.#..", "#..#.", E, E]),
    ('l', [".##..", "..#..", "..#..", "..#..", "..#..", "..#..", ".###.", E, E]),
    ('m', [E, E, "##.#.", "#.#.#", "#.#.#", "#.#.#", "#.#.#", E, E]),
    ('n', [E, E, "#.##.", "##..#", "#...#", "#...#", "#...#", E, E]),
    ('o', [E, E, ".###.", "#...#", "#...#", "#...#", ".###.", E, E]),
    ('p', [E, E, "####.", "#...#", "#...#", "#...#", "####.", "#....", "#...."]),
    ('q', [E, E, ".####", "#...#", "#...#", "#...#", ".####", "....#", "....#"]),
    ('r', [E, E, "#.##.", "##..#", "#....", "#....", "#....", E, E]),
    ('s', [E, E, ".####", "#....", ".###.", "....#", "####.", E, E]),
    ('t', [".#...", ".#...", "###..", ".#...", ".#...", ".#..#", "..##.", E, E]),
    ('u', [E, E, "#...#", "#...#", "#...#", "#..##", ".##.#", E, E]),
    ('v', [E, E, "#...#", "#...#", "#...#", ".#.#.", "..#..", E, E]),
    ('w', [E, E, "#...#", "#...#", "#.#.#", "#.#.#", ".#.#.", E, E]),
    ('x', [E, E, "#...#", ".#.#.", "..#..", ".#.#.", "#...#", E, E]),
    ('y', [E, E, "#...#", "#...#", "#...#", "#...#", ".####", "....#", ".###."]),
    ('z', [E, E, "#####", "...#.", "..#..", ".#...", "#####", E, E]),
    ('ä', [".#.#.", E, ".###.", "....#", ".####", "#...#", ".####", E, E]),
    ('ö', [".#.#.", E, ".###.", "#...#", "#...#", "#...#", ".###.", E, E]),
    ('ü', [".#.#.", E, "#...#", "#...#", "#...#", "#..##", ".##.#", E, E]),
    ('é', ["...#.", "..#..", ".###.", "#...#", "#####", "#....", ".###.", E, E]),
    ('è', [".#...", "..#..", ".###.", "#...#", "#####", "#....", ".###.", E, E]),
    ('à', [".#...", "..#..", ".###.", "....#", ".####", "#...#", ".####", E, E]),
    ('.', [E, E, E, E, E, ".##..", ".##..", E, E]),
    (',', [E, E, E, E, E, ".##..", ".##..", "..#..", ".#..."]),
    (';', [E, ".##..", ".##..", E, ".##..", ".##..", "..#..", ".#...", E]),
    (':', [E, ".##..", ".##..", E, ".##..", ".##..", E, E, E]),
    ('-', [E, E, E, "#####", E, E, E, E, E]),
    ('−', [E, E, E, "#####", E, E, E, E, E]),
    ('–', [E, E, E, "#####", E, E, E, E, E]),
    ('+', [E, "..#..", "..#..", "#####", "..#..", "..#..", E, E, E]),
    ('±', ["..#..", "..#..", "#####", "..#..", "..#..", E, "#####", E, E]),
    ('×', [E, "#...#", ".#.#.", "..#..", ".#.#.", "#...#", E, E, E]),
    ('·', [E, E, E, "..#..", E, E, E, E, E]),
    ('=', [E, E, "#####", E, "#####", E, E, E, E]),
    ('<', ["...#.", "..#..", ".#...", "#....", ".#...", "..#..", "...#.", E, E]),
    ('>', [".#...", "..#..", "...#.", "....#", "...#.", "..#..", ".#...", E, E]),
    ('≤', ["...#.", "..#..", ".#...", "..#..", "...#.", E, "#####", E, E]),
    ('≥', [".#...", "..#..", "...#.", "..#..", ".#...", E, "#####", E, E]),
    ('%', ["##...", "##..#", "...#.", "..#..", ".#...", "#..##", "...##", E, E]),
    ('/', [E, "....#", "...#.", "..#..", ".#...", "#....", E, E, E]),
    ('\\', [E, "#....", ".#...", "..#..", "...#.", "....#", E, E, E]),
    ('(', ["...#.", "..#..", ".#...", ".#...", ".#...", "..#..", "...#.", E, E]),
    (')', [".#...", "..#..", "...#.", "...#.", "...#.", "..#..", ".#...", E, E]),
    ('[', [".###.", ".#...", ".#...", ".#...", ".#...", ".#...", ".###.", E, E]),
    (']', [".###.", "...#.", "...#.", "...#.", "...#.", "...#.", ".###.", E, E]),
    ('|', ["..#..", "..#..", "..#..", "..#..", "..#..", "..#..", "..#..", "..#..", E]),
    ('°', [".##..", "#..#.", "#..#.", ".##..", E, E, E, E, E]),
    ('²', ["###..", "...#.", ".##..", "#....", "####.", E, E, E, E]),
    ('³', ["###..", "...#.", ".##..", "...#.", "###..", E, E, E, E]),
    ('_', [E, E, E, E, E, E, E, "#####", E]),
    ('\'', ["..#..", "..#..", ".#...", E, E, E, E, E, E]),
    ('"', [".#.#.", ".#.#.", E, E, E, E, E, E, E]),
    ('!', ["..#..", "..#..", "..#..", "..#..", "..#..", E, "..#..", E, E]),
    ('?', [".###.", "#...#", "....#", "...#.", "..#..", E, "..#..", E, E]),
    ('*', [E, "..#..", "#.#.#", ".###.", "#.#.#", "..#..", E, E, E]),
    ('#', [".#.#.", ".#.#.", "#####", ".#.#.", "#####", ".#.#.", ".#.#.", E, E]),
    ('&', [".##..", "#..#.", "#.#..", ".#...", "#.#.#", "#..#.", ".##.#", E, E]),
    ('^', ["..#..", ".#.#.", "#...#", E, E, E, E, E, E]),
    ('µ', [E, E, "#...#", "#...#", "#...#", "#..##", "###.#", "#....", "#...."]),
    ('σ', [E, E, ".####", "#..#.", "#...#", "#...#", ".###.", E, E]),
];

/// Drawn for characters without a glyph.
const MISSING: Glyph = ["#####", "#...#", "#...#", "#...#", "#...#", "#...#", "#####", E, E];

fn glyph(c: char) -> &'static Glyph {
    GLYPHS.iter().find(|(g, _)| *g == c).map(|(_, rows)| rows).unwrap_or(&MISSING)
}

/// True if `c` has its own glyph (anything else is drawn as a hollow box).
pub fn has_glyph(c: char) -> bool {
    GLYPHS.iter().any(|(g, _)| *g == c)
}

/// Width in pixels of `text` drawn at `scale` (no trailing spacing; 0 for empty text).
pub fn text_width(text: &str, scale: u32) -> u32 {
    let n = text.chars().count() as u32;
    if n == 0 {
        0
    } else {
        (n * ADVANCE - (ADVANCE - GLYPH_WIDTH)) * scale.max(1)
    }
}

/// Height in pixels of a line of text at `scale`, descenders included.
pub fn text_height(scale: u32) -> u32 {
    GLYPH_HEIGHT * scale.max(1)
}

/// Draws `text` with the top-left corner of its first glyph box at (`x`, `y`), each font pixel a `scale`×`scale`
/// block of `colour` (alpha-blended). Returns the width drawn, as [`text_width`].
pub fn draw_text(canvas: &mut Canvas, x: i32, y: i32, text: &str, scale: u32, colour: Rgba) -> u32 {
    let s = scale.max(1);
    let mut cx = x;
    for c in text.chars() {
        for (r, row) in glyph(c).iter().enumerate() {
            for (col, b) in row.bytes().enumerate() {
                if b == b'#' {
                    canvas.fill_rect(cx + (col as u32 * s) as i32, y + (r as u32 * s) as i32, s, s, colour);
                }
            }
        }
        cx += (ADVANCE * s) as i32;
    }
    text_width(text, scale)
}

/// Draws `text` as [`draw_text`] over a `halo` outline one font pixel wide, so that it reads over any background
/// (labels on maps).
pub fn draw_text_halo(canvas: &mut Canvas, x: i32, y: i32, text: &str, scale: u32, colour: Rgba, halo: Rgba) -> u32 {
    let s = scale.max(1);
    let w = text_width(text, scale);
    // The halo is the ink dilated by one font pixel, drawn once into a mask so that a translucent halo does not
    // darken where offsets overlap.
    let cols = (text.chars().count() as u32 * ADVANCE + 2) as usize;
    let rows = (GLYPH_HEIGHT + 2) as usize;
    let mut ink = vec![false; cols * rows];
    for (i, c) in text.chars().enumerate() {
        for (r, row) in glyph(c).iter().enumerate() {
            for (col, b) in row.bytes().enumerate() {
                if b == b'#' {
                    ink[(r + 1) * cols + i * ADVANCE as usize + col + 1] = true;
                }
            }
        }
    }
    for r in 0..rows {
        for c in 0..cols {
            let near = (r.saturating_sub(1)..=(r + 1).min(rows - 1))
                .any(|rr| (c.saturating_sub(1)..=(c + 1).min(cols - 1)).any(|cc| ink[rr * cols + cc]));
            if near {
                let px = x + (c as i32 - 1) * s as i32;
                let py = y + (r as i32 - 1) * s as i32;
                canvas.fill_rect(px, py, s, s, halo);
            }
        }
    }
    draw_text(canvas, x, y, text, scale, colour);
    w
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn glyphs_are_well_formed_and_cover_the_required_set() {
        for (c, rows) in GLYPHS {
            assert!(rows.iter().all(|r| r.len() == 5 && r.bytes().all(|b| b == b'#' || b == b'.')), "{c:?}");
        }
        let required = "0123456789ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz.,-+:%/()°²³_=<> ";
        for c in required.chars() {
            assert!(has_glyph(c), "missing glyph {c:?}");
        }
        let mut seen = std::collections::HashSet::new();
        assert!(GLYPHS.iter().all(|(c, _)| seen.insert(*c)), "duplicate glyph");
    }

    #[test]
    fn text_is_measured_and_drawn_where_measured() {
        assert_eq!(text_width("", 2), 0);
        assert_eq!(text_width("A", 1), 5);
        assert_eq!(text_width("100 m", 2), (5 * 6 - 1) * 2);
        assert_eq!(text_height(2), 18);
        let mut c = Canvas::new(80, 30, [255, 255, 255, 255]);
        let w = draw_text(&mut c, 3, 4, "HgE", 2, [0, 0, 0, 255]);
        assert_eq!(w, text_width("HgE", 2));
        // Ink inside the measured box only, and some in the descender rows (the g).
        let mut ink_box = (u32::MAX, u32::MAX, 0, 0);
        for y in 0..30 {
            for x in 0..80 {
                if c.get(x, y)[0] < 128 {
                    ink_box = (ink_box.0.min(x), ink_box.1.min(y), ink_box.2.max(x), ink_box.3.max(y));
                }
            }
        }
        assert_eq!((ink_box.0, ink_box.1), (3, 4));
        assert_eq!(ink_box.2, 3 + w - 1);
        assert_eq!(ink_box.3, 4 + text_height(2) - 1);
    }
}
