//! Pictures drawn on the CPU: the image of a slice with the contours'
//! cross-sections over it, and the legend of the visible contours that
//! PNG exports carry (the 3D view draws the same legend with egui).
//!
//! Text is laid out and rasterised by egui's own font code (epaint, with
//! egui's default fonts), so the exported legend reads like the window's.

use crate::field::slice::{Slice, slice_axes};

/// One line of a legend: a colour swatch and a name.
#[derive(Clone, Debug, PartialEq)]
pub struct LegendEntry {
    /// The contour's name (or a description when it has none).
    pub name: String,
    /// sRGB.
    pub colour: [u8; 3],
}

/// A contour's cross-section on a slice: segments in the plane's world
/// `(u, v)` coordinates ([`axis_section`](crate::contour::section::axis_section))
/// and the colour to draw them in.
#[derive(Clone, Copy, Debug)]
pub struct Section<'a> {
    /// The segments.
    pub segments: &'a [[[f32; 2]; 2]],
    /// sRGB.
    pub colour: [u8; 3],
}

/// The image of `slice` at `upscale` pixels per sample (1..=8): its grey
/// values, bilinearly interpolated, with each section drawn over them in
/// its colour, lines `line_width` pixels wide. The image spans the
/// slice's rectangle ([`Slice::corners`]) edge to edge: pixel centre
/// `(c, r)` shows grid position `u = (c + ½) (width − 1) / W`, `v` likewise
/// from the bottom.
pub fn slice_image(
    slice: &Slice,
    spacing: [f64; 3],
    upscale: u32,
    sections: &[Section<'_>],
    line_width: f32,
) -> image::RgbaImage {
    let s = upscale.clamp(1, 8);
    let (w, h) = (slice.width as u32 * s, slice.height as u32 * s);
    let su = slice.width.saturating_sub(1) as f32;
    let sv = slice.height.saturating_sub(1) as f32;
    let mut img = image::RgbaImage::from_fn(w.max(1), h.max(1), |c, r| {
        let u = (c as f32 + 0.5) * su / w.max(1) as f32;
        let v = (h.max(1) - 1 - r) as f32 + 0.5;
        let v = v * sv / h.max(1) as f32;
        let g = (slice.sample(u, v).clamp(0.0, 1.0) * 255.0).round() as u8;
        image::Rgba([g, g, g, 255])
    });
    // World (u, v) → pixel coordinates.
    let (ua, va) = slice_axes(slice.axis);
    let (du, dv) = (spacing[ua] as f32, spacing[va] as f32);
    let to_px = |p: [f32; 2]| {
        let gu = if du > 0.0 { p[0] / du } else { 0.0 };
        let gv = if dv > 0.0 { p[1] / dv } else { 0.0 };
        let x = if su > 0.0 { gu / su * w as f32 } else { 0.0 };
        let y = if sv > 0.0 {
            h as f32 - gv / sv * h as f32
        } else {
            0.0
        };
        [x, y]
    };
    for sec in sections {
        for seg in sec.segments {
            draw_segment(
                &mut img,
                to_px(seg[0]),
                to_px(seg[1]),
                sec.colour,
                line_width,
            );
        }
    }
    img
}

/// Draws a segment `width` pixels wide (round ends, hard edges).
pub fn draw_segment(
    img: &mut image::RgbaImage,
    a: [f32; 2],
    b: [f32; 2],
    colour: [u8; 3],
    width: f32,
) {
    let r = (0.5 * width).max(0.5);
    let (w, h) = img.dimensions();
    let (x0, x1) = (a[0].min(b[0]) - r, a[0].max(b[0]) + r);
    let (y0, y1) = (a[1].min(b[1]) - r, a[1].max(b[1]) + r);
    if !(x0.is_finite() && x1.is_finite() && y0.is_finite() && y1.is_finite()) {
        return;
    }
    let cx = |x: f32| (x.floor().max(0.0) as u32).min(w);
    let cy = |y: f32| (y.floor().max(0.0) as u32).min(h);
    let (d0, d1) = (b[0] - a[0], b[1] - a[1]);
    let len2 = d0 * d0 + d1 * d1;
    for y in cy(y0)..cy(y1 + 1.0) {
        for x in cx(x0)..cx(x1 + 1.0) {
            let (px, py) = (x as f32 + 0.5 - a[0], y as f32 + 0.5 - a[1]);
            let t = if len2 > 0.0 {
                ((px * d0 + py * d1) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let (ex, ey) = (px - t * d0, py - t * d1);
            if ex * ex + ey * ey <= r * r {
                let [cr, cg, cb] = colour;
                img.put_pixel(x, y, image::Rgba([cr, cg, cb, 255]));
            }
        }
    }
}

/// Blends `colour` with coverage `a` (0..=255) into pixel `(x, y)`.
fn blend(img: &mut image::RgbaImage, x: u32, y: u32, colour: [u8; 3], a: u8) {
    let p = img.get_pixel_mut(x, y);
    let a = u16::from(a);
    for (c, v) in colour.iter().zip(&mut p.0) {
        *v = ((u16::from(*c) * a + u16::from(*v) * (255 - a) + 127) / 255) as u8;
    }
}

/// The legend's size in pixels for an image `height` pixels high: the
/// font size.
pub fn legend_font_px(height: u32) -> f32 {
    (height as f32 / 48.0).clamp(12.0, 28.0)
}

/// Draws the legend of `entries` into the top-left corner of `img`: a
/// dark translucent box, one line per entry with a colour swatch and the
/// name. Nothing when `entries` is empty.
pub fn draw_legend(img: &mut image::RgbaImage, entries: &[LegendEntry]) {
    use egui::epaint::text::{FontDefinitions, Fonts, TextOptions};
    if entries.is_empty() {
        return;
    }
    let (w, h) = img.dimensions();
    let size = legend_font_px(h);
    let mut fonts = Fonts::new(TextOptions::default(), FontDefinitions::default());
    let galleys: Vec<_> = {
        let mut view = fonts.with_pixels_per_point(1.0);
        entries
            .iter()
            .map(|e| {
                view.layout_no_wrap(
                    e.name.clone(),
                    egui::FontId::proportional(size),
                    egui::Color32::WHITE,
                )
            })
            .collect()
    };
    let atlas = fonts.image();
    let pad = (size * 0.5).round();
    let line = (size * 1.35).round();
    let swatch = (size * 0.8).round();
    let text_w = galleys.iter().map(|g| g.rect.width()).fold(0.0, f32::max);
    let box_w = (pad * 3.0 + swatch + text_w).ceil() as u32;
    let box_h = (pad * 2.0 + line * entries.len() as f32).ceil() as u32;
    let (x0, y0) = (pad as u32, pad as u32);
    for y in y0..(y0 + box_h).min(h) {
        for x in x0..(x0 + box_w).min(w) {
            blend(img, x, y, [20, 20, 22], 190);
        }
    }
    for (i, (e, g)) in entries.iter().zip(&galleys).enumerate() {
        let top = y0 as f32 + pad + i as f32 * line;
        let sx = x0 as f32 + pad;
        let sy = top + 0.5 * (line - swatch);
        for y in sy as u32..((sy + swatch) as u32).min(h) {
            for x in sx as u32..((sx + swatch) as u32).min(w) {
                let [r, gg, b] = e.colour;
                img.put_pixel(x, y, image::Rgba([r, gg, b, 255]));
            }
        }
        let tx = sx + swatch + pad;
        let ty = top + 0.5 * (line - g.rect.height());
        for row in &g.rows {
            for glyph in &row.row.glyphs {
                let uv = glyph.uv_rect;
                if uv.is_nothing() {
                    continue;
                }
                let left = (tx + row.pos.x + glyph.pos.x + uv.offset.x).round() as i64;
                let top = (ty + row.pos.y + glyph.pos.y + uv.offset.y).round() as i64;
                for ay in uv.min[1]..uv.max[1] {
                    for ax in uv.min[0]..uv.max[0] {
                        let a = atlas[(ax as usize, ay as usize)].a();
                        let x = left + i64::from(ax - uv.min[0]);
                        let y = top + i64::from(ay - uv.min[1]);
                        if a > 0 && x >= 0 && y >= 0 && (x as u32) < w && (y as u32) < h {
                            blend(img, x as u32, y as u32, [235, 235, 235], a);
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_legend_shows_each_swatch_and_some_text() {
        let mut img = image::RgbaImage::from_pixel(400, 300, image::Rgba([0, 0, 0, 255]));
        let entries = [
            LegendEntry {
                name: "brain".into(),
                colour: [228, 115, 51],
            },
            LegendEntry {
                name: "scalp".into(),
                colour: [77, 153, 217],
            },
        ];
        draw_legend(&mut img, &entries);
        for e in &entries {
            let [r, g, b] = e.colour;
            assert!(
                img.pixels().any(|p| p.0 == [r, g, b, 255]),
                "no swatch of {}",
                e.name
            );
        }
        // Text: light pixels.
        let light = img
            .pixels()
            .filter(|p| p.0[0] > 150 && p.0[1] > 150 && p.0[2] > 150)
            .count();
        assert!(light > 30, "{light} text pixels");
    }

    #[test]
    fn segments_are_drawn_where_the_slice_maps_them() {
        let slice = Slice {
            axis: 2,
            index: 0,
            width: 11,
            height: 11,
            grey: vec![0.5; 121],
        };
        let seg = [[[0.0, 5.0], [10.0, 5.0]]];
        let img = slice_image(
            &slice,
            [1.0; 3],
            2,
            &[Section {
                segments: &seg,
                colour: [255, 0, 0],
            }],
            2.0,
        );
        assert_eq!(img.dimensions(), (22, 22));
        // v = 5 of 0..10 is the middle row; grey elsewhere.
        assert_eq!(img.get_pixel(11, 11).0, [255, 0, 0, 255]);
        assert_eq!(img.get_pixel(11, 2).0, [128, 128, 128, 255]);
    }
}
