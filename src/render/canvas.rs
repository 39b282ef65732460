//! An RGBA pixel canvas: alpha-blended drawing of lines, rectangles, circles, markers and polygons, and PNG output
//! through the atomic writer.
//!
//! Coordinates are continuous with pixel (i, j) covering [i, i+1) × [j, j+1), y down; a 1-pixel line at y = 10.5
//! fills row 10 exactly. Colours are straight (not premultiplied) RGBA. Shapes are anti-aliased by coverage:
//! distance to the shape for lines and circles, exact horizontal spans over four sub-rows for polygons.

use crate::error::{Error, Result};
use crate::io::write_atomic;
use std::io::Write;
use std::path::Path;

/// An sRGB colour with alpha, straight (not premultiplied).
pub type Rgba = [u8; 4];

/// An opaque colour from RGB.
pub fn opaque(c: [u8; 3]) -> Rgba {
    [c[0], c[1], c[2], 255]
}

/// `c` with alpha `alpha` in [0, 1].
pub fn with_alpha(c: [u8; 3], alpha: f64) -> Rgba {
    [c[0], c[1], c[2], (alpha.clamp(0.0, 1.0) * 255.0).round() as u8]
}

/// An axis-aligned rectangle of whole pixels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Rect {
    /// Left column.
    pub x: i32,
    /// Top row.
    pub y: i32,
    /// Width in pixels.
    pub w: u32,
    /// Height in pixels.
    pub h: u32,
}

impl Rect {
    /// A rectangle from its top-left corner and size.
    pub fn new(x: i32, y: i32, w: u32, h: u32) -> Self {
        Rect { x, y, w, h }
    }

    /// True if pixel (x, y) is inside.
    pub fn contains(&self, x: i32, y: i32) -> bool {
        x >= self.x && y >= self.y && x < self.x + self.w as i32 && y < self.y + self.h as i32
    }
}

/// Marker shapes for points.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Marker {
    /// Filled disc.
    Circle,
    /// Filled square.
    Square,
    /// Filled upward triangle.
    Triangle,
    /// Filled diamond.
    Diamond,
    /// An × of two strokes.
    Cross,
}

/// A pixel canvas with a clip rectangle.
#[derive(Debug, Clone, PartialEq)]
pub struct Canvas {
    width: u32,
    height: u32,
    data: Vec<u8>,
    clip: Rect,
}

impl Canvas {
    /// A `width` × `height` canvas filled with `background`.
    pub fn new(width: u32, height: u32, background: Rgba) -> Self {
        let mut data = Vec::with_capacity(width as usize * height as usize * 4);
        for _ in 0..width as usize * height as usize {
            data.extend_from_slice(&background);
        }
        Canvas { width, height, data, clip: Rect::new(0, 0, width, height) }
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The pixels, row-major RGBA.
    pub fn rgba(&self) -> &[u8] {
        &self.data
    }

    /// Restricts drawing to `clip` (intersected with the canvas); `None` lifts the restriction.
    pub fn set_clip(&mut self, clip: Option<Rect>) {
        let full = Rect::new(0, 0, self.width, self.height);
        self.clip = match clip {
            None => full,
            Some(r) => {
                let x0 = r.x.max(0);
                let y0 = r.y.max(0);
                let x1 = (r.x + r.w as i32).min(self.width as i32).max(x0);
                let y1 = (r.y + r.h as i32).min(self.height as i32).max(y0);
                Rect::new(x0, y0, (x1 - x0) as u32, (y1 - y0) as u32)
            }
        };
    }

    /// The pixel at (x, y); panics outside the canvas.
    pub fn get(&self, x: u32, y: u32) -> Rgba {
        assert!(x < self.width && y < self.height, "pixel ({x}, {y}) outside {}×{}", self.width, self.height);
        let i = (y as usize * self.width as usize + x as usize) * 4;
        [self.data[i], self.data[i + 1], self.data[i + 2], self.data[i + 3]]
    }

    /// Overwrites the pixel at (x, y) (no blending); ignored outside the clip rectangle.
    pub fn set(&mut self, x: i32, y: i32, c: Rgba) {
        if self.clip.contains(x, y) {
            let i = (y as usize * self.width as usize + x as usize) * 4;
            self.data[i..i + 4].copy_from_slice(&c);
        }
    }

    /// Blends `c` over the pixel at (x, y) with its alpha scaled by `coverage` in [0, 1] ("source over").
    pub fn blend(&mut self, x: i32, y: i32, c: Rgba, coverage: f64) {
        if !self.clip.contains(x, y) {
            return;
        }
        let sa = c[3] as f64 / 255.0 * coverage.clamp(0.0, 1.0);
        if sa <= 0.0 {
            return;
        }
        let i = (y as usize * self.width as usize + x as usize) * 4;
        let d = &mut self.data[i..i + 4];
        let da = d[3] as f64 / 255.0;
        let oa = sa + da * (1.0 - sa);
        if oa <= 0.0 {
            return;
        }
        for k in 0..3 {
            let v = (c[k] as f64 * sa + d[k] as f64 * da * (1.0 - sa)) / oa;
            d[k] = v.round().clamp(0.0, 255.0) as u8;
        }
        d[3] = (oa * 255.0).round() as u8;
    }

    /// Fills whole pixels [x, x+w) × [y, y+h) with `c`, blended.
    pub fn fill_rect(&mut self, x: i32, y: i32, w: u32, h: u32, c: Rgba) {
        let x0 = x.max(self.clip.x);
        let y0 = y.max(self.clip.y);
        let x1 = (x + w as i32).min(self.clip.x + self.clip.w as i32);
        let y1 = (y + h as i32).min(self.clip.y + self.clip.h as i32);
        for py in y0..y1 {
            for px in x0..x1 {
                self.blend(px, py, c, 1.0);
            }
        }
    }

    /// Outlines the whole-pixel rectangle [x, x+w) × [y, y+h) with a border `thickness` pixels wide, inside it.
    pub fn stroke_rect(&mut self, x: i32, y: i32, w: u32, h: u32, thickness: u32, c: Rgba) {
        let t = thickness.min(w.div_ceil(2)).min(h.div_ceil(2));
        self.fill_rect(x, y, w, t, c);
        self.fill_rect(x, y + h as i32 - t as i32, w, t, c);
        self.fill_rect(x, y + t as i32, t, h.saturating_sub(2 * t), c);
        self.fill_rect(x + w as i32 - t as i32, y + t as i32, t, h.saturating_sub(2 * t), c);
    }

    /// A straight line from `a` to `b`, `width` pixels wide with round caps.
    pub fn line(&mut self, a: (f64, f64), b: (f64, f64), width: f64, c: Rgba, antialias: bool) {
        self.polyline(&[a, b], width, c, antialias);
    }

    /// A connected line through `points`, `width` pixels wide with round joins and caps. Each pixel is blended
    /// once, so translucent lines do not darken at joins. Non-finite points are skipped.
    pub fn polyline(&mut self, points: &[(f64, f64)], width: f64, c: Rgba, antialias: bool) {
        let pts: Vec<(f64, f64)> = points.iter().copied().filter(|p| p.0.is_finite() && p.1.is_finite()).collect();
        if pts.is_empty() || width <= 0.0 {
            return;
        }
        let hw = (width / 2.0).max(0.5);
        let alpha_scale = width.min(1.0);
        let reach = hw + 1.0;
        let (mut xmin, mut ymin, mut xmax, mut ymax) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
        for p in &pts {
            xmin = xmin.min(p.0);
            ymin = ymin.min(p.1);
            xmax = xmax.max(p.0);
            ymax = ymax.max(p.1);
        }
        let Some(bb) = self.clipped_box(xmin - reach, ymin - reach, xmax + reach, ymax + reach) else { return };
        let bw = bb.w as usize;
        let mut cov = vec![0f32; bw * bb.h as usize];
        let segs: Vec<((f64, f64), (f64, f64))> =
            if pts.len() == 1 { vec![(pts[0], pts[0])] } else { pts.windows(2).map(|w| (w[0], w[1])).collect() };
        for (a, b) in segs {
            let Some(sb) = self.clipped_box(
                a.0.min(b.0) - reach,
                a.1.min(b.1) - reach,
                a.0.max(b.0) + reach,
                a.1.max(b.1) + reach,
            ) else {
                continue;
            };
            for py in sb.y..sb.y + sb.h as i32 {
                for px in sb.x..sb.x + sb.w as i32 {
                    let d = dist_to_segment((px as f64 + 0.5, py as f64 + 0.5), a, b);
                    let k = if antialias {
                        (hw + 0.5 - d).clamp(0.0, 1.0)
                    } else if d <= hw {
                        1.0
                    } else {
                        0.0
                    };
                    let i = (py - bb.y) as usize * bw + (px - bb.x) as usize;
                    cov[i] = cov[i].max(k as f32);
                }
            }
        }
        self.blend_mask(bb, &cov, c, alpha_scale);
    }

    /// The closed outline of a polygon.
    pub fn polygon(&mut self, points: &[(f64, f64)], width: f64, c: Rgba, antialias: bool) {
        let mut closed = points.to_vec();
        if let Some(&first) = points.first() {
            closed.push(first);
        }
        self.polyline(&closed, width, c, antialias);
    }

    /// Fills a polygon (even-odd rule), anti-aliased.
    pub fn fill_polygon(&mut self, points: &[(f64, f64)], c: Rgba) {
        if points.len() < 3 {
            return;
        }
        let (mut xmin, mut ymin, mut xmax, mut ymax) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
        for p in points {
            xmin = xmin.min(p.0);
            ymin = ymin.min(p.1);
            xmax = xmax.max(p.0);
            ymax = ymax.max(p.1);
        }
        let Some(bb) = self.clipped_box(xmin, ymin, xmax + 1.0, ymax + 1.0) else { return };
        let bw = bb.w as usize;
        let mut cov = vec![0f32; bw * bb.h as usize];
        const SUB: usize = 4;
        let mut xs = Vec::new();
        for py in bb.y..bb.y + bb.h as i32 {
            let row = &mut cov[(py - bb.y) as usize * bw..(py - bb.y + 1) as usize * bw];
            for s in 0..SUB {
                let sy = py as f64 + (s as f64 + 0.5) / SUB as f64;
                xs.clear();
                for i in 0..points.len() {
                    let (a, b) = (points[i], points[(i + 1) % points.len()]);
                    if (a.1 <= sy) != (b.1 <= sy) {
                        xs.push(a.0 + (sy - a.1) / (b.1 - a.1) * (b.0 - a.0));
                    }
                }
                xs.sort_by(|p, q| p.total_cmp(q));
                for span in xs.chunks_exact(2) {
                    add_span(row, bb.x, span[0], span[1], 1.0 / SUB as f32);
                }
            }
        }
        self.blend_mask(bb, &cov, c, 1.0);
    }

    /// A filled disc of radius `r` pixels centred at (cx, cy), anti-aliased.
    pub fn fill_circle(&mut self, cx: f64, cy: f64, r: f64, c: Rgba) {
        self.ring_or_disc(cx, cy, r, None, c);
    }

    /// A circle of radius `r` with a stroke `width` pixels wide, anti-aliased.
    pub fn stroke_circle(&mut self, cx: f64, cy: f64, r: f64, width: f64, c: Rgba) {
        self.ring_or_disc(cx, cy, r, Some(width), c);
    }

    fn ring_or_disc(&mut self, cx: f64, cy: f64, r: f64, stroke: Option<f64>, c: Rgba) {
        let reach = r + stroke.unwrap_or(0.0) / 2.0 + 1.0;
        let Some(bb) = self.clipped_box(cx - reach, cy - reach, cx + reach, cy + reach) else { return };
        for py in bb.y..bb.y + bb.h as i32 {
            for px in bb.x..bb.x + bb.w as i32 {
                let d = ((px as f64 + 0.5 - cx).powi(2) + (py as f64 + 0.5 - cy).powi(2)).sqrt();
                let k = match stroke {
                    None => (r + 0.5 - d).clamp(0.0, 1.0),
                    Some(w) => ((w / 2.0).max(0.5) + 0.5 - (d - r).abs()).clamp(0.0, 1.0),
                };
                if k > 0.0 {
                    self.blend(px, py, c, k);
                }
            }
        }
    }

    /// A marker of `size` pixels (its diameter or side) centred at (cx, cy).
    pub fn marker(&mut self, cx: f64, cy: f64, shape: Marker, size: f64, c: Rgba) {
        let h = size / 2.0;
        match shape {
            Marker::Circle => self.fill_circle(cx, cy, h, c),
            Marker::Square => {
                self.fill_polygon(&[(cx - h, cy - h), (cx + h, cy - h), (cx + h, cy + h), (cx - h, cy + h)], c)
            }
            Marker::Triangle => self.fill_polygon(&[(cx, cy - h), (cx + h, cy + h * 0.8), (cx - h, cy + h * 0.8)], c),
            Marker::Diamond => self.fill_polygon(&[(cx, cy - h), (cx + h, cy), (cx, cy + h), (cx - h, cy)], c),
            Marker::Cross => {
                let w = (size / 4.0).max(1.0);
                self.line((cx - h, cy - h), (cx + h, cy + h), w, c, true);
                self.line((cx - h, cy + h), (cx + h, cy - h), w, c, true);
            }
        }
    }

    /// True if every pixel is opaque.
    pub fn is_opaque(&self) -> bool {
        self.data.chunks_exact(4).all(|p| p[3] == 255)
    }

    /// The canvas as PNG bytes: 8-bit RGB when every pixel is opaque, RGBA otherwise.
    pub fn encode_png(&self) -> Result<Vec<u8>> {
        let mut out = Vec::new();
        self.write_png(&mut out, Path::new("<memory>"))?;
        Ok(out)
    }

    /// Writes the canvas to `path` as PNG (see [`Canvas::encode_png`]), atomically.
    pub fn save_png(&self, path: &Path) -> Result<()> {
        write_atomic(path, |w| self.write_png(w, path))
    }

    fn write_png<W: Write>(&self, w: W, path: &Path) -> Result<()> {
        let err = |e: png::EncodingError| Error::io(path, std::io::Error::other(e));
        let mut enc = png::Encoder::new(w, self.width, self.height);
        let opaque = self.is_opaque();
        enc.set_color(if opaque { png::ColorType::Rgb } else { png::ColorType::Rgba });
        enc.set_depth(png::BitDepth::Eight);
        enc.set_compression(png::Compression::Balanced);
        let mut writer = enc.write_header().map_err(err)?;
        if opaque {
            let rgb: Vec<u8> = self.data.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect();
            writer.write_image_data(&rgb).map_err(err)?;
        } else {
            writer.write_image_data(&self.data).map_err(err)?;
        }
        writer.finish().map_err(err)
    }

    /// The whole pixels touched by the box [x0, x1] × [y0, y1], intersected with the clip; `None` if empty.
    fn clipped_box(&self, x0: f64, y0: f64, x1: f64, y1: f64) -> Option<Rect> {
        if !(x0.is_finite() && y0.is_finite() && x1.is_finite() && y1.is_finite()) {
            return None;
        }
        let cx1 = (self.clip.x + self.clip.w as i32) as f64;
        let cy1 = (self.clip.y + self.clip.h as i32) as f64;
        let px0 = x0.floor().max(self.clip.x as f64);
        let py0 = y0.floor().max(self.clip.y as f64);
        let px1 = x1.ceil().min(cx1);
        let py1 = y1.ceil().min(cy1);
        (px1 > px0 && py1 > py0).then(|| Rect::new(px0 as i32, py0 as i32, (px1 - px0) as u32, (py1 - py0) as u32))
    }

    fn blend_mask(&mut self, bb: Rect, cov: &[f32], c: Rgba, scale: f64) {
        let bw = bb.w as usize;
        for (i, &k) in cov.iter().enumerate() {
            if k > 0.0 {
                self.blend(bb.x + (i % bw) as i32, bb.y + (i / bw) as i32, c, k as f64 * scale);
            }
        }
    }
}

/// Adds `weight` × the covered fraction of each pixel of `row` (whose first pixel is column `x0`) for the span
/// [xa, xb).
fn add_span(row: &mut [f32], x0: i32, xa: f64, xb: f64, weight: f32) {
    let lo = (xa - x0 as f64).max(0.0);
    let hi = (xb - x0 as f64).min(row.len() as f64);
    if hi <= lo {
        return;
    }
    let (i0, i1) = (lo.floor() as usize, (hi.ceil() as usize).min(row.len()));
    for (i, cell) in row.iter_mut().enumerate().take(i1).skip(i0) {
        let covered = (hi.min(i as f64 + 1.0) - lo.max(i as f64)).max(0.0);
        *cell = (*cell + weight * covered as f32).min(1.0);
    }
}

/// Distance from `p` to the segment `a`–`b`.
fn dist_to_segment(p: (f64, f64), a: (f64, f64), b: (f64, f64)) -> f64 {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 { (((p.0 - a.0) * dx + (p.1 - a.1) * dy) / len2).clamp(0.0, 1.0) } else { 0.0 };
    ((p.0 - a.0 - t * dx).powi(2) + (p.1 - a.1 - t * dy).powi(2)).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    const WHITE: Rgba = [255, 255, 255, 255];
    const BLACK: Rgba = [0, 0, 0, 255];

    #[test]
    fn blending_and_clipping() {
        let mut c = Canvas::new(10, 10, WHITE);
        c.blend(1, 1, [0, 0, 0, 128], 1.0);
        assert_eq!(c.get(1, 1), [127, 127, 127, 255]);
        c.set_clip(Some(Rect::new(5, 5, 10, 10)));
        c.fill_rect(0, 0, 10, 10, BLACK);
        assert_eq!(c.get(4, 4), WHITE);
        assert_eq!(c.get(5, 5), BLACK);
        c.set_clip(None);
        c.fill_rect(0, 0, 1, 1, BLACK);
        assert_eq!(c.get(0, 0), BLACK);
    }

    #[test]
    fn lines_circles_and_polygons_cover_what_they_should() {
        let mut c = Canvas::new(40, 40, WHITE);
        c.line((2.0, 10.5), (30.0, 10.5), 1.0, BLACK, false);
        assert_eq!(c.get(15, 10), BLACK);
        assert_eq!(c.get(15, 9), WHITE);
        assert_eq!(c.get(15, 11), WHITE);
        // A translucent thick polyline is blended once per pixel, joins included.
        c.polyline(&[(5.0, 20.0), (20.0, 20.0), (20.0, 35.0)], 4.0, [0, 0, 0, 128], true);
        assert_eq!(c.get(20, 20), [127, 127, 127, 255]);
        c.fill_circle(30.0, 30.0, 4.0, BLACK);
        assert_eq!(c.get(30, 30), BLACK);
        assert_eq!(c.get(30, 36), WHITE);
        let mut p = Canvas::new(20, 20, WHITE);
        p.fill_polygon(&[(2.0, 2.0), (12.0, 2.0), (12.0, 12.0), (2.0, 12.0)], BLACK);
        assert_eq!(p.get(2, 2), BLACK);
        assert_eq!(p.get(11, 11), BLACK);
        assert_eq!(p.get(12, 12), WHITE);
        assert_eq!(p.get(1, 5), WHITE);
        // Half-covered pixels are half blended.
        let mut h = Canvas::new(4, 4, WHITE);
        h.fill_polygon(&[(0.0, 0.0), (1.5, 0.0), (1.5, 4.0), (0.0, 4.0)], BLACK);
        assert_eq!(h.get(1, 1), [128, 128, 128, 255]);
    }

    #[test]
    fn png_round_trip_keeps_size_and_pixels() {
        let mut c = Canvas::new(7, 5, WHITE);
        c.set(3, 2, [10, 20, 30, 255]);
        let bytes = c.encode_png().unwrap();
        let dec = png::Decoder::new(std::io::Cursor::new(bytes));
        let mut r = dec.read_info().unwrap();
        let mut buf = vec![0; r.output_buffer_size().unwrap()];
        let info = r.next_frame(&mut buf).unwrap();
        assert_eq!((info.width, info.height, info.color_type), (7, 5, png::ColorType::Rgb));
        let i = (2 * 7 + 3) * 3;
        assert_eq!(&buf[i..i + 3], &[10, 20, 30]);
    }
}
