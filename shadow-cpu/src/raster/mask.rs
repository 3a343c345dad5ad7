//! A computation mask (Chan, thesis 3.2 and 3.4.2): one bit per pixel saying whether later draws may touch
//! it, and one per square tile saying whether any of its pixels may, so the rasterizer rejects unmasked
//! tiles whole, as hardware culls tiles early, before any depth or stencil work. The pixels' bits are
//! kept in 64-bit words per row, so a span meets the mask a word at a time.

/// Which pixels a draw may touch, with a coarse per-tile summary.
#[derive(Clone, Debug, PartialEq)]
pub struct ComputationMask {
    width: u32,
    height: u32,
    tile: u32,
    /// Per tile, row-major over `ceil(width / tile) x ceil(height / tile)` tiles.
    tiles: Vec<bool>,
    /// Summed-area table of `tiles`, one row and column larger: any rectangle of tiles in O(1).
    sums: Vec<u32>,
    /// Per row, `words` 64-bit words of one bit a pixel (bit `x % 64` of word `x / 64`): a span meets
    /// the mask in a word or two, whatever the pixels in it.
    bits: Vec<u64>,
    words: usize,
}

impl ComputationMask {
    /// The mask of a `width x height` target whose pixel `(x, y)` is masked in when `f(x, y)`, summarized
    /// in tiles of side `tile` (at least 1).
    #[must_use]
    pub fn from_fn(width: u32, height: u32, tile: u32, f: impl Fn(u32, u32) -> bool) -> Self {
        let tile = tile.max(1);
        let tiles_x = width.div_ceil(tile);
        let words = (width as usize).div_ceil(64);
        let mut bits = vec![0u64; words * height as usize];
        let mut tiles = vec![false; (tiles_x * height.div_ceil(tile)) as usize];
        for y in 0..height {
            for x in (0..width).filter(|&x| f(x, y)) {
                bits[y as usize * words + x as usize / 64] |= 1 << (x % 64);
                tiles[((y / tile) * tiles_x + x / tile) as usize] = true;
            }
        }
        let (tw, th) = (tiles_x as usize, height.div_ceil(tile) as usize);
        let mut sums = vec![0u32; (tw + 1) * (th + 1)];
        for ty in 0..th {
            for tx in 0..tw {
                sums[(ty + 1) * (tw + 1) + tx + 1] =
                    u32::from(tiles[ty * tw + tx]) + sums[ty * (tw + 1) + tx + 1] + sums[(ty + 1) * (tw + 1) + tx]
                        - sums[ty * (tw + 1) + tx];
            }
        }
        Self { width, height, tile, tiles, sums, bits, words }
    }

    /// Whether any tile meeting the pixel rectangle `x0..=x1`, `y0..=y1` (clamped to the target) has a
    /// pixel masked in.
    #[must_use]
    pub fn any_in(&self, x0: u32, y0: u32, x1: u32, y1: u32) -> bool {
        let tw = self.width.div_ceil(self.tile) as usize + 1;
        let (x1, y1) = (x1.min(self.width.saturating_sub(1)), y1.min(self.height.saturating_sub(1)));
        if x0 > x1 || y0 > y1 {
            return false;
        }
        let (a, b) = ((x0 / self.tile) as usize, (x1 / self.tile) as usize + 1);
        let (c, d) = ((y0 / self.tile) as usize, (y1 / self.tile) as usize + 1);
        self.sums[d * tw + b] + self.sums[c * tw + a] > self.sums[c * tw + b] + self.sums[d * tw + a]
    }

    /// The side of the tiles, in pixels.
    #[must_use]
    pub fn tile(&self) -> u32 {
        self.tile
    }

    /// Target size.
    #[must_use]
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Whether pixel `(x, y)` is masked in.
    #[must_use]
    pub fn get(&self, x: u32, y: u32) -> bool {
        self.bits[y as usize * self.words + x as usize / 64] >> (x % 64) & 1 == 1
    }

    /// How many pixels are masked in.
    #[must_use]
    pub fn count(&self) -> usize {
        self.bits.iter().map(|w| w.count_ones() as usize).sum()
    }

    /// How many tiles have a pixel masked in, of how many.
    #[must_use]
    pub fn tiles_in(&self) -> (usize, usize) {
        (self.tiles.iter().filter(|&&t| t).count(), self.tiles.len())
    }

    /// Calls `f(first, last)` for each masked-in run of columns `xs..=xe` of row `y` (inclusive, left to
    /// right, `xe` below the width): a word of the row's bits at a time, so a span with nothing masked
    /// in costs a word or two.
    #[inline]
    pub fn each_run(&self, y: u32, xs: u32, xe: u32, mut f: impl FnMut(u32, u32)) {
        let row = &self.bits[y as usize * self.words..][..self.words];
        let (first_word, last_word) = (xs / 64, xe / 64);
        // A run reaching a word's last bit may go on in the next word: it is held until it ends.
        let mut open: Option<(u32, u32)> = None;
        for wi in first_word..=last_word {
            let mut word = row[wi as usize];
            if wi == first_word {
                word &= !0 << (xs % 64);
            }
            if wi == last_word && xe % 64 < 63 {
                word &= (1 << (xe % 64 + 1)) - 1;
            }
            let base = wi * 64;
            if word & 1 == 0
                && let Some((a, b)) = open.take()
            {
                f(a, b);
            }
            while word != 0 {
                let a = word.trailing_zeros();
                let len = (!(word >> a)).trailing_zeros();
                let (first, last) = (base + a, base + a + len - 1);
                let run = match open.take() {
                    Some((start, end)) if end + 1 == first => (start, last),
                    Some(done) => {
                        f(done.0, done.1);
                        (first, last)
                    }
                    None => (first, last),
                };
                word = if a + len >= 64 { 0 } else { word & (!0 << (a + len)) };
                if last % 64 == 63 {
                    open = Some(run);
                } else {
                    f(run.0, run.1);
                }
            }
        }
        if let Some((a, b)) = open {
            f(a, b);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::ComputationMask;

    #[test]
    fn runs_are_the_masked_in_columns_merged_across_words() {
        // Runs ending on a word's last column, starting on its first, one column long, across two words.
        let (w, h) = (200, 5);
        let on = |x: u32, y: u32| match y {
            0 => (60..70).contains(&x) || x == 127 || x == 128 || (180..200).contains(&x),
            1 => x.is_multiple_of(3) || x == 64,
            2 => true,
            3 => false,
            _ => (x * 37 + 11) % 7 < 3,
        };
        let mask = ComputationMask::from_fn(w, h, 8, on);
        for y in 0..h {
            for (xs, xe) in [(0, w - 1), (63, 64), (64, 127), (5, 190), (127, 128), (199, 199), (0, 0), (62, 130)] {
                let mut got = Vec::new();
                mask.each_run(y, xs, xe, |a, b| got.push((a, b)));
                let mut want: Vec<(u32, u32)> = Vec::new();
                for x in (xs..=xe).filter(|&x| on(x, y)) {
                    match want.last_mut() {
                        Some((_, b)) if *b + 1 == x => *b = x,
                        _ => want.push((x, x)),
                    }
                }
                assert_eq!(got, want, "row {y}, columns {xs}..={xe}");
            }
        }
    }
}
