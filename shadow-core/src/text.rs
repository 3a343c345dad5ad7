//! Labels on contact sheets and plots, in Hack (a monospaced typeface under the MIT and Bitstream Vera
//! licences, embedded by `epaint_default_fonts`) rasterized with anti-aliasing by `ab_glyph`.
//!
//! Sizes are given as a `scale`: at scale 1 a character cell is [`CELL_WIDTH`] pixels wide and a line
//! [`LINE_HEIGHT`] pixels tall, so layouts can be computed without the font.

use std::sync::OnceLock;

use ab_glyph::{Font, FontRef, PxScale, ScaleFont};

use crate::image::{Image, Rgb8};

/// Width of one character cell at scale 1.
pub const CELL_WIDTH: u32 = 6;
/// Height of one line at scale 1.
pub const LINE_HEIGHT: u32 = 13;

fn font() -> &'static FontRef<'static> {
    static FONT: OnceLock<FontRef<'static>> = OnceLock::new();
    // The font is a constant of the build, and `the_embedded_font_parses` parses it.
    FONT.get_or_init(|| FontRef::try_from_slice(epaint_default_fonts::HACK_REGULAR).expect("Hack parses"))
}

/// The glyph size whose advance (the same for every glyph of a monospaced face) fills `scale` cells.
fn cell_scale(scale: f32) -> PxScale {
    let unit = font().as_scaled(PxScale::from(1.0)).h_advance(font().glyph_id('m'));
    PxScale::from(CELL_WIDTH as f32 * scale / unit)
}

/// Width in pixels of `text` at `scale`.
#[must_use]
pub fn text_width(text: &str, scale: u32) -> u32 {
    text.chars().count() as u32 * CELL_WIDTH * scale.max(1)
}

/// Draws `text` with its top-left corner at (x, y), blending each glyph's coverage over the image;
/// pixels outside the image are skipped.
pub fn draw_text(img: &mut Image<Rgb8>, x: i32, y: i32, text: &str, color: Rgb8, scale: u32) {
    let s = scale.max(1) as f32;
    let scaled = font().as_scaled(cell_scale(s));
    // The line's ascent sits in the middle of the line's extra height, so text is centred in it.
    let baseline = y as f32 + (LINE_HEIGHT as f32 * s - (scaled.ascent() - scaled.descent())) / 2.0 + scaled.ascent();
    for (k, ch) in text.chars().enumerate() {
        let pen = ab_glyph::point(x as f32 + k as f32 * CELL_WIDTH as f32 * s, baseline);
        let mut glyph = scaled.scaled_glyph(ch);
        glyph.position = pen;
        let Some(outline) = font().outline_glyph(glyph) else { continue };
        let bounds = outline.px_bounds();
        outline.draw(|gx, gy, coverage| {
            let (px, py) = (bounds.min.x as i32 + gx as i32, bounds.min.y as i32 + gy as i32);
            if px < 0 || py < 0 || px as u32 >= img.width() || py as u32 >= img.height() {
                return;
            }
            let under = img.get_mut(px as u32, py as u32);
            let a = coverage.clamp(0.0, 1.0);
            for c in 0..3 {
                under[c] = (f32::from(under[c]) * (1.0 - a) + f32::from(color[c]) * a).round() as u8;
            }
        });
    }
}

/// Fills a rectangle, clipped to the image.
pub fn fill_rect(img: &mut Image<Rgb8>, x: i32, y: i32, w: u32, h: u32, color: Rgb8) {
    for py in y.max(0)..(y + h as i32).min(img.height() as i32) {
        for px in x.max(0)..(x + w as i32).min(img.width() as i32) {
            *img.get_mut(px as u32, py as u32) = color;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_embedded_font_parses_and_advances_one_cell_a_character() {
        let scaled = font().as_scaled(cell_scale(1.0));
        let advance = scaled.h_advance(font().glyph_id('m'));
        assert!((advance - CELL_WIDTH as f32).abs() < 0.1, "advance {advance}");
    }

    #[test]
    fn text_draws_inside_its_box_with_descenders() {
        let (w, h) = (60, 2 * LINE_HEIGHT);
        let mut img = Image::new(w, h, [0u8; 3]);
        draw_text(&mut img, 1, 1, "gyp-1%", [255; 3], 1);
        let lit: Vec<(u32, u32)> =
            (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).filter(|&(x, y)| img.get(x, y)[0] > 64).collect();
        assert!(lit.len() > 20, "{} pixels drawn", lit.len());
        assert!(
            lit.iter()
                .all(|&(x, y)| (1..1 + text_width("gyp-1%", 1)).contains(&x) && (1..1 + LINE_HEIGHT).contains(&y))
        );
        // 'g', 'y' and 'p' reach below the baseline that '1' stands on.
        let bottom = |x0: u32, x1: u32| lit.iter().filter(|p| p.0 >= x0 && p.0 < x1).map(|p| p.1).max();
        let (descender, digit) = (bottom(1, 1 + CELL_WIDTH), bottom(1 + 4 * CELL_WIDTH, 1 + 5 * CELL_WIDTH));
        assert!(descender > digit, "'g' ends at {descender:?}, '1' at {digit:?}");
    }
}
