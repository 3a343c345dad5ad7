//! A line plot as a PNG: one line per series, axes with ticks, a legend. For `bench --sweep`.

use shadow_core::Image;
use shadow_core::image::Rgb8;
use shadow_core::text::{CELL_WIDTH, LINE_HEIGHT, draw_text, fill_rect, text_width};

const PALETTE: [Rgb8; 8] = [
    [31, 119, 180],
    [255, 127, 14],
    [44, 160, 44],
    [214, 39, 40],
    [148, 103, 189],
    [140, 86, 75],
    [227, 119, 194],
    [127, 127, 127],
];

fn line(img: &mut Image<Rgb8>, (x0, y0): (f32, f32), (x1, y1): (f32, f32), c: Rgb8) {
    let n = (x1 - x0).abs().max((y1 - y0).abs()).ceil().max(1.0) as i32;
    for k in 0..=n {
        let t = k as f32 / n as f32;
        let (x, y) = (x0 + (x1 - x0) * t, y0 + (y1 - y0) * t);
        fill_rect(img, x as i32 - 1, y as i32 - 1, 3, 3, c);
    }
}

/// Plots `series` (name, points) against a log2 x axis when every x is positive, else a linear one.
#[must_use]
pub fn line_plot(title: &str, x_label: &str, y_label: &str, series: &[(String, Vec<(f64, f64)>)]) -> Image<Rgb8> {
    let (w, h) = (900u32, 560u32);
    let (left, right, top, bottom) = (80.0f32, 250.0f32, 70.0f32, 60.0f32);
    let mut img = Image::new(w, h, [255u8, 255, 255]);
    let pts: Vec<(f64, f64)> = series.iter().flat_map(|(_, p)| p.iter().copied()).collect();
    let log_x = pts.iter().all(|p| p.0 > 0.0);
    let fx = |x: f64| if log_x { x.log2() } else { x };
    let (mut x0, mut x1) =
        pts.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(fx(p.0)), b.max(fx(p.0))));
    let y1 = pts.iter().fold(0.0f64, |m, p| m.max(p.1)) * 1.1 + 1e-9;
    if x1 <= x0 {
        x0 -= 1.0;
        x1 += 1.0;
    }
    let px = |x: f64| left + ((fx(x) - x0) / (x1 - x0)) as f32 * (w as f32 - left - right);
    let py = |y: f64| h as f32 - bottom - (y / y1) as f32 * (h as f32 - top - bottom);
    let ink = [40, 40, 40];
    line(&mut img, (left, h as f32 - bottom), (w as f32 - right, h as f32 - bottom), ink);
    line(&mut img, (left, top), (left, h as f32 - bottom), ink);
    for k in 0..=4 {
        let y = y1 * f64::from(k) / 4.0;
        let label = format!("{y:.0}");
        let y_text = py(y) as i32 - LINE_HEIGHT as i32 / 2;
        draw_text(&mut img, (left - 8.0) as i32 - text_width(&label, 1) as i32, y_text, &label, ink, 1);
    }
    let mut xs: Vec<f64> = pts.iter().map(|p| p.0).collect();
    xs.sort_by(f64::total_cmp);
    xs.dedup();
    for x in &xs {
        let label = format!("{x}");
        draw_text(
            &mut img,
            px(*x) as i32 - (text_width(&label, 1) / 2) as i32,
            (h as f32 - bottom + 8.0) as i32,
            &label,
            ink,
            1,
        );
    }
    draw_text(&mut img, 10, 10, title, ink, 2);
    draw_text(&mut img, (w as f32 / 2.0 - right / 2.0) as i32, h as i32 - 24, x_label, ink, 1);
    draw_text(&mut img, 8, top as i32 - LINE_HEIGHT as i32 - 8, y_label, ink, 1);
    for (i, (name, p)) in series.iter().enumerate() {
        let c = PALETTE[i % PALETTE.len()];
        for w2 in p.windows(2) {
            line(&mut img, (px(w2[0].0), py(w2[0].1)), (px(w2[1].0), py(w2[1].1)), c);
        }
        for q in p {
            fill_rect(&mut img, px(q.0) as i32 - 3, py(q.1) as i32 - 3, 7, 7, c);
        }
        let ly = top as i32 + 18 * i as i32;
        fill_rect(&mut img, w as i32 - right as i32 + 12, ly, 14, 8, c);
        let text_y = ly + 4 - LINE_HEIGHT as i32 / 2;
        draw_text(&mut img, w as i32 - right as i32 + 12 + 3 * CELL_WIDTH as i32, text_y, name, ink, 1);
    }
    img
}
