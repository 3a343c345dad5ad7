//! Labelled contact sheets: pictures in a grid, each with its error map under it and its label, and a
//! magnified inset of one region (where the techniques disagree most) in the corner of every picture, so
//! a shadow map's staircase, a silhouette map's straight edge and a penumbra can be told apart at a glance.

use shadow_core::Image;
use shadow_core::image::Rgb8;
use shadow_core::text::{LINE_HEIGHT, draw_text, fill_rect, text_width};

/// Nearest-neighbour resize (pictures are shrunk a little at most; labels carry the numbers).
#[must_use]
pub fn resize(img: &Image<Rgb8>, width: u32) -> Image<Rgb8> {
    let height = (u64::from(img.height()) * u64::from(width) / u64::from(img.width().max(1))).max(1) as u32;
    Image::from_fn(width, height, |x, y| {
        let sx = (u64::from(x) * u64::from(img.width()) / u64::from(width)) as u32;
        let sy = (u64::from(y) * u64::from(img.height()) / u64::from(height)) as u32;
        *img.get(sx.min(img.width() - 1), sy.min(img.height() - 1))
    })
}

/// One tile of a sheet.
pub struct SheetItem {
    /// The label, one or more lines.
    pub label: String,
    /// The picture.
    pub picture: Image<Rgb8>,
    /// Its error map (a reference: its visibility), shown under it.
    pub errors: Option<Image<Rgb8>>,
}

/// A square region of the view, in view pixels, shown magnified in every tile.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Inset {
    /// Left edge.
    pub x: u32,
    /// Top edge.
    pub y: u32,
    /// Side.
    pub side: u32,
}

const FRAME: Rgb8 = [255, 200, 0];

/// Copies `src` into `dst` at (x0, y0), clipped.
fn blit(dst: &mut Image<Rgb8>, src: &Image<Rgb8>, x0: u32, y0: u32) {
    for y in 0..src.height().min(dst.height().saturating_sub(y0)) {
        for x in 0..src.width().min(dst.width().saturating_sub(x0)) {
            *dst.get_mut(x0 + x, y0 + y) = *src.get(x, y);
        }
    }
}

/// A one-pixel outline of a rectangle.
fn outline(img: &mut Image<Rgb8>, x: i32, y: i32, w: u32, h: u32, colour: Rgb8) {
    fill_rect(img, x, y, w, 1, colour);
    fill_rect(img, x, y + h as i32 - 1, w, 1, colour);
    fill_rect(img, x, y, 1, h, colour);
    fill_rect(img, x + w as i32 - 1, y, 1, h, colour);
}

/// `picture` shrunk to `tile` wide, with the inset's region outlined and shown magnified in the
/// bottom-right corner.
fn tile_with_inset(picture: &Image<Rgb8>, tile: u32, inset: Option<Inset>) -> Image<Rgb8> {
    let mut small = resize(picture, tile);
    let Some(i) = inset else { return small };
    let k = f64::from(tile) / f64::from(picture.width().max(1));
    let (rx, ry, rs) =
        ((f64::from(i.x) * k) as i32, (f64::from(i.y) * k) as i32, ((f64::from(i.side) * k) as u32).max(2));
    outline(&mut small, rx, ry, rs, rs, FRAME);
    let zoom_side = (tile * 2 / 5).max(8);
    let zoom = Image::from_fn(zoom_side, zoom_side, |x, y| {
        let sx = i.x + (u64::from(x) * u64::from(i.side) / u64::from(zoom_side)) as u32;
        let sy = i.y + (u64::from(y) * u64::from(i.side) / u64::from(zoom_side)) as u32;
        *picture.get(sx.min(picture.width() - 1), sy.min(picture.height() - 1))
    });
    let (zx, zy) = (small.width().saturating_sub(zoom_side + 3), small.height().saturating_sub(zoom_side + 3));
    blit(&mut small, &zoom, zx, zy);
    outline(&mut small, zx as i32 - 1, zy as i32 - 1, zoom_side + 2, zoom_side + 2, FRAME);
    small
}

/// A grid of `tile`-wide pictures (at most four per row), each with its error map under it when it has
/// one, and labelled underneath.
#[must_use]
pub fn contact_sheet(items: &[SheetItem], tile: u32, inset: Option<Inset>) -> Image<Rgb8> {
    let cols = items.len().clamp(1, 4) as u32;
    let rows = (items.len() as u32).div_ceil(cols).max(1);
    let scale = 2;
    let lines = items.iter().map(|i| i.label.lines().count()).max().unwrap_or(1).max(1) as u32;
    let label_h = LINE_HEIGHT * scale * lines + 6;
    let tile_h = items.first().map_or(tile, |i| {
        (u64::from(i.picture.height()) * u64::from(tile) / u64::from(i.picture.width().max(1))) as u32
    });
    let errors_h = if items.iter().any(|i| i.errors.is_some()) { tile_h + 4 } else { 0 };
    let (pad, cell_w, cell_h) = (8, tile + 8, tile_h + errors_h + label_h + 8);
    let mut sheet = Image::new(cols * cell_w + pad, rows * cell_h + pad, [250u8, 250, 250]);
    for (k, item) in items.iter().enumerate() {
        let (c, r) = (k as u32 % cols, k as u32 / cols);
        let (x0, y0) = (pad + c * cell_w, pad + r * cell_h);
        blit(&mut sheet, &tile_with_inset(&item.picture, tile, inset), x0, y0);
        if let Some(errors) = &item.errors {
            blit(&mut sheet, &tile_with_inset(errors, tile, inset), x0, y0 + tile_h + 4);
        }
        let label_y = (y0 + tile_h + errors_h) as i32;
        fill_rect(&mut sheet, x0 as i32, label_y, tile, label_h, [40, 40, 48]);
        for (k, line) in item.label.lines().enumerate() {
            let mut s = scale;
            while s > 1 && text_width(line, s) > tile - 6 {
                s -= 1;
            }
            let y = label_y + 3 + (k as u32 * LINE_HEIGHT * scale) as i32;
            draw_text(&mut sheet, x0 as i32 + 4, y, line, [255, 255, 255], s);
        }
    }
    sheet
}

/// The square of `side` view pixels where the techniques disagree most with their references (each test
/// paired with its own, summed over tests) and `reference`'s shadow edges are densest: an edge weighs
/// about as much as one technique's error there, so a view that one technique gets wrong everywhere still
/// shows an edge, and a view that every technique gets right shows the densest edges. The centre when
/// there is neither.
#[must_use]
pub fn disagreement_inset(
    tests: &[(&Image<f32>, &Image<f32>)],
    reference: &Image<f32>,
    measured: &Image<bool>,
    side: u32,
) -> Inset {
    let (w, h) = (reference.width(), reference.height());
    let side = side.clamp(1, w.min(h));
    let shadowed = |img: &Image<f32>, x: u32, y: u32| *img.get(x, y) < 0.5;
    let weight = |x: u32, y: u32| -> u64 {
        if !*measured.get(x, y) {
            return 0;
        }
        let r = shadowed(reference, x, y);
        let wrong = tests.iter().filter(|(t, own)| shadowed(t, x, y) != shadowed(own, x, y)).count() as u64;
        let edge =
            (x + 1 < w && shadowed(reference, x + 1, y) != r) || (y + 1 < h && shadowed(reference, x, y + 1) != r);
        wrong * 4 + u64::from(edge) * 3
    };
    // Summed-area table of the weights, then every window's sum in constant time.
    let mut sum = vec![0u64; ((w + 1) * (h + 1)) as usize];
    let at = |x: u32, y: u32| (y * (w + 1) + x) as usize;
    for y in 0..h {
        for x in 0..w {
            sum[at(x + 1, y + 1)] = weight(x, y) + sum[at(x, y + 1)] + sum[at(x + 1, y)] - sum[at(x, y)];
        }
    }
    let mut best = (0u64, (w - side) / 2, (h - side) / 2);
    let step = (side / 4).max(1);
    for y in (0..=h - side).step_by(step as usize) {
        for x in (0..=w - side).step_by(step as usize) {
            let s = sum[at(x + side, y + side)] + sum[at(x, y)] - sum[at(x + side, y)] - sum[at(x, y + side)];
            if s > best.0 {
                best = (s, x, y);
            }
        }
    }
    Inset { x: best.1, y: best.2, side }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_inset_finds_the_disagreement() {
        let reference = Image::new(64, 64, 1.0f32);
        let mut test = reference.clone();
        for y in 40..44 {
            for x in 10..14 {
                *test.get_mut(x, y) = 0.0;
            }
        }
        let measured = Image::new(64, 64, true);
        let i = disagreement_inset(&[(&test, &reference)], &reference, &measured, 16);
        assert!(i.x <= 10 && i.x + 16 >= 14 && i.y <= 40 && i.y + 16 >= 44, "{i:?}");
    }
}
