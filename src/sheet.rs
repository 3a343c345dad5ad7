//! Labelled contact sheets: pictures in a grid, each with its label under it.

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

/// A grid of `tile`-wide pictures (at most four per row), each labelled underneath.
#[must_use]
pub fn contact_sheet(items: &[(String, Image<Rgb8>)], tile: u32) -> Image<Rgb8> {
    let cols = items.len().clamp(1, 4) as u32;
    let rows = (items.len() as u32).div_ceil(cols).max(1);
    let scale = 2;
    let lines = items.iter().map(|(l, _)| l.lines().count()).max().unwrap_or(1).max(1) as u32;
    let label_h = LINE_HEIGHT * scale * lines + 6;
    let tile_h = items
        .first()
        .map_or(tile, |(_, i)| (u64::from(i.height()) * u64::from(tile) / u64::from(i.width().max(1))) as u32);
    let (pad, cell_w, cell_h) = (8, tile + 8, tile_h + label_h + 8);
    let mut sheet = Image::new(cols * cell_w + pad, rows * cell_h + pad, [250u8, 250, 250]);
    for (k, (label, img)) in items.iter().enumerate() {
        let (c, r) = (k as u32 % cols, k as u32 / cols);
        let (x0, y0) = ((pad + c * cell_w) as i32, (pad + r * cell_h) as i32);
        let small = resize(img, tile);
        for y in 0..small.height().min(tile_h) {
            for x in 0..small.width() {
                *sheet.get_mut(x0 as u32 + x, y0 as u32 + y) = *small.get(x, y);
            }
        }
        fill_rect(&mut sheet, x0, y0 + tile_h as i32, tile, label_h, [40, 40, 48]);
        for (k, line) in label.lines().enumerate() {
            let mut s = scale;
            while s > 1 && text_width(line, s) > tile - 6 {
                s -= 1;
            }
            draw_text(
                &mut sheet,
                x0 + 4,
                y0 + tile_h as i32 + 4 + (k as u32 * LINE_HEIGHT * scale) as i32,
                line,
                [255, 255, 255],
                s,
            );
        }
    }
    sheet
}
