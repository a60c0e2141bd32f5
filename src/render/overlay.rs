//! Pictures drawn on the CPU: the image of a slice with the contours'
//! cross-sections over it, and the legend of the visible contours and
//! the contours' name labels that PNG exports carry (the 3D view draws
//! the same legend and labels with egui).
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

/// Text laid out by egui's fonts, ready to be drawn into an image.
struct Texts {
    fonts: egui::epaint::text::Fonts,
    galleys: Vec<std::sync::Arc<egui::Galley>>,
}

impl Texts {
    /// Lays out each of `texts` on one line, `size` pixels high.
    fn new<'a>(texts: impl IntoIterator<Item = &'a str>, size: f32) -> Texts {
        use egui::epaint::text::{FontDefinitions, Fonts, TextOptions};
        let mut fonts = Fonts::new(TextOptions::default(), FontDefinitions::default());
        let galleys = {
            let mut view = fonts.with_pixels_per_point(1.0);
            texts
                .into_iter()
                .map(|t| {
                    view.layout_no_wrap(
                        t.to_owned(),
                        egui::FontId::proportional(size),
                        egui::Color32::WHITE,
                    )
                })
                .collect()
        };
        Texts { fonts, galleys }
    }

    /// Width and height of text `i`.
    fn size(&self, i: usize) -> [f32; 2] {
        let r = self.galleys[i].rect;
        [r.width(), r.height()]
    }

    /// Blends text `i` in `colour` into `img`, its top-left at `(tx, ty)`.
    fn draw(&self, img: &mut image::RgbaImage, i: usize, tx: f32, ty: f32, colour: [u8; 3]) {
        let atlas = self.fonts.image();
        let (w, h) = img.dimensions();
        let g = &self.galleys[i];
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
                            blend(img, x as u32, y as u32, colour, a);
                        }
                    }
                }
            }
        }
    }
}

/// Blends `colour` with coverage `a` over the pixels of a rectangle
/// (clipped to the image).
fn fill(img: &mut image::RgbaImage, x0: f32, y0: f32, x1: f32, y1: f32, colour: [u8; 3], a: u8) {
    let (w, h) = img.dimensions();
    let c = |v: f32, max: u32| (v.round().max(0.0) as u32).min(max);
    for y in c(y0, h)..c(y1, h) {
        for x in c(x0, w)..c(x1, w) {
            blend(img, x, y, colour, a);
        }
    }
}

/// Draws the legend of `entries` into the top-left corner of `img`: a
/// dark translucent box, one line per entry with a colour swatch and the
/// name. Nothing when `entries` is empty.
pub fn draw_legend(img: &mut image::RgbaImage, entries: &[LegendEntry]) {
    if entries.is_empty() {
        return;
    }
    let (w, h) = img.dimensions();
    let size = legend_font_px(h);
    let texts = Texts::new(entries.iter().map(|e| e.name.as_str()), size);
    let pad = (size * 0.5).round();
    let line = (size * 1.35).round();
    let swatch = (size * 0.8).round();
    let text_w = (0..entries.len())
        .map(|i| texts.size(i)[0])
        .fold(0.0, f32::max);
    let box_w = (pad * 3.0 + swatch + text_w).ceil() as u32;
    let box_h = (pad * 2.0 + line * entries.len() as f32).ceil() as u32;
    let (x0, y0) = (pad as u32, pad as u32);
    for y in y0..(y0 + box_h).min(h) {
        for x in x0..(x0 + box_w).min(w) {
            blend(img, x, y, [20, 20, 22], 190);
        }
    }
    for (i, e) in entries.iter().enumerate() {
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
        let ty = top + 0.5 * (line - texts.size(i)[1]);
        texts.draw(img, i, tx, ty, [235, 235, 235]);
    }
}

/// A contour's name drawn beside a point of it in a picture.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageLabel {
    /// The name.
    pub text: String,
    /// The contour's colour (sRGB): the dot, the leader line and the
    /// box's border.
    pub colour: [u8; 3],
    /// Where the contour is, in pixels of the picture.
    pub at: [f32; 2],
}

/// The pixel of the picture (`width × height`) where world point `p`
/// shows through the camera's `view_proj`, None behind the eye.
pub fn project_to_image(
    view_proj: glam::Mat4,
    p: [f32; 3],
    width: u32,
    height: u32,
) -> Option<[f32; 2]> {
    let q = view_proj * glam::Vec3::from(p).extend(1.0);
    if q.w <= 0.0 {
        return None;
    }
    let ndc = q.truncate() / q.w;
    Some([
        (0.5 + 0.5 * ndc.x) * width as f32,
        (0.5 - 0.5 * ndc.y) * height as f32,
    ])
}

/// How far up a box `[x0, y0, x1, y1]` must move to overlap none of
/// `placed` (with `gap` between), trying above each in turn.
pub fn clear_of(placed: &[[f32; 4]], b: [f32; 4], gap: f32) -> f32 {
    let mut lift = 0.0;
    for _ in 0..=placed.len() {
        let hit = placed.iter().find(|p| {
            b[0] < p[2] && p[0] < b[2] && b[1] - lift < p[3] + gap && p[1] - gap < b[3] - lift
        });
        match hit {
            Some(p) => lift = b[3] - p[1] + gap,
            None => break,
        }
    }
    lift
}

/// Draws each label as the 3D view does: a dot in the contour's colour
/// at its point, a leader line to a dark box up and to the right holding
/// the name in white, the box bordered in the colour.
pub fn draw_labels(img: &mut image::RgbaImage, labels: &[ImageLabel]) {
    if labels.is_empty() {
        return;
    }
    let (_, h) = img.dimensions();
    let size = 0.9 * legend_font_px(h);
    let texts = Texts::new(labels.iter().map(|l| l.text.as_str()), size);
    let pad = (0.25 * size).round().max(2.0);
    let off = (0.6 * size).round();
    let mut placed: Vec<[f32; 4]> = Vec::new();
    for (i, l) in labels.iter().enumerate() {
        let [px, py] = l.at;
        if !(px.is_finite() && py.is_finite()) {
            continue;
        }
        let [tw, th] = texts.size(i);
        let (tx, ty) = (px + off, py - off - th);
        let (bx0, by0, bx1, by1) = (tx - pad, ty - pad, tx + tw + pad, ty + th + pad);
        // Labels of nearby points would cover each other: one moves up
        // above the other, its leader line longer.
        let lift = clear_of(&placed, [bx0, by0, bx1, by1], 2.0 * pad);
        let (ty, by0, by1) = (ty - lift, by0 - lift, by1 - lift);
        placed.push([bx0, by0, bx1, by1]);
        draw_segment(img, [px, py], [bx0, by1], l.colour, (size / 12.0).max(1.0));
        fill(img, bx0, by0, bx1, by1, [0, 0, 0], 170);
        let b = (size / 12.0).max(1.0);
        fill(img, bx0 - b, by0 - b, bx1 + b, by0, l.colour, 255);
        fill(img, bx0 - b, by1, bx1 + b, by1 + b, l.colour, 255);
        fill(img, bx0 - b, by0, bx0, by1, l.colour, 255);
        fill(img, bx1, by0, bx1 + b, by1, l.colour, 255);
        draw_segment(img, [px, py], [px, py], l.colour, (size / 2.2).max(4.0));
        texts.draw(img, i, tx, ty, [255, 255, 255]);
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
    fn a_label_draws_its_colour_at_its_point_and_its_name_beside_it() {
        let mut img = image::RgbaImage::from_pixel(400, 300, image::Rgba([0, 0, 0, 255]));
        let label = ImageLabel {
            text: "brain".into(),
            colour: [228, 115, 51],
            at: [100.0, 200.0],
        };
        draw_labels(&mut img, std::slice::from_ref(&label));
        // The dot at its point.
        assert_eq!(img.get_pixel(100, 200).0, [228, 115, 51, 255]);
        // The name up and to the right: white text.
        let white_right_above = (100..400)
            .flat_map(|x| (0..200).map(move |y| (x, y)))
            .filter(|&(x, y)| img.get_pixel(x, y).0[..3].iter().all(|&c| c > 200))
            .count();
        assert!(white_right_above > 30, "{white_right_above} text pixels");
        // Nothing left of the point or below it.
        assert!(
            (0..90)
                .flat_map(|x| (0..300).map(move |y| (x, y)))
                .chain((0..400).flat_map(|x| (210..300).map(move |y| (x, y))))
                .all(|(x, y)| img.get_pixel(x, y).0 == [0, 0, 0, 255])
        );
        // A point behind the eye projects nowhere.
        let vp = glam::Mat4::perspective_rh(1.0, 1.0, 0.1, 10.0);
        assert!(project_to_image(vp, [0.0, 0.0, 1.0], 400, 300).is_none());
        let c = project_to_image(vp, [0.0, 0.0, -1.0], 400, 300).expect("in front");
        assert!((c[0] - 200.0).abs() < 1e-3 && (c[1] - 150.0).abs() < 1e-3);
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
