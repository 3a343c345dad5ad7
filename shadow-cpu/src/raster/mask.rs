//! A computation mask (Chan, thesis 3.2 and 3.4.2): one bit per pixel saying whether later draws may touch
//! it, and one per square tile saying whether any of its pixels may, so the rasterizer rejects unmasked
//! tiles whole, as hardware culls tiles early, before any depth or stencil work. The masked-in pixels are
//! kept as runs, by row and by tile, for the rasterizer's two walks.

/// Which pixels a draw may touch, with a coarse per-tile summary.
#[derive(Clone, Debug, PartialEq)]
pub struct ComputationMask {
    width: u32,
    height: u32,
    tile: u32,
    /// Per pixel, row-major.
    pixels: Vec<bool>,
    /// Per tile, row-major over `ceil(width / tile) x ceil(height / tile)` tiles.
    tiles: Vec<bool>,
    /// Summed-area table of `tiles`, one row and column larger: any rectangle of tiles in O(1).
    sums: Vec<u32>,
    /// Per row, its masked-in runs of columns, inclusive, left to right: a span meets them by a binary
    /// search, not pixel by pixel.
    row_runs: Vec<Vec<(u32, u32)>>,
    /// The same runs cut at tile boundaries and grouped by tile, as `(row, first, last)`: tile `i`'s are
    /// `tile_runs[tile_start[i]..tile_start[i + 1]]`, by row.
    tile_runs: Vec<(u32, u32, u32)>,
    tile_start: Vec<u32>,
}

impl ComputationMask {
    /// The mask of a `width x height` target whose pixel `(x, y)` is masked in when `f(x, y)`, summarized
    /// in tiles of side `tile` (at least 1).
    #[must_use]
    pub fn from_fn(width: u32, height: u32, tile: u32, f: impl Fn(u32, u32) -> bool) -> Self {
        let tile = tile.max(1);
        let tiles_x = width.div_ceil(tile);
        let mut pixels = Vec::with_capacity(width as usize * height as usize);
        let mut tiles = vec![false; (tiles_x * height.div_ceil(tile)) as usize];
        for y in 0..height {
            for x in 0..width {
                let on = f(x, y);
                pixels.push(on);
                if on {
                    tiles[((y / tile) * tiles_x + x / tile) as usize] = true;
                }
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
        let row_runs: Vec<Vec<(u32, u32)>> = (0..height as usize)
            .map(|y| {
                let row = &pixels[y * width as usize..][..width as usize];
                let mut runs = Vec::new();
                let mut x = 0;
                while x < row.len() {
                    if row[x] {
                        let start = x;
                        while x < row.len() && row[x] {
                            x += 1;
                        }
                        runs.push((start as u32, x as u32 - 1));
                    }
                    x += 1;
                }
                runs
            })
            .collect();
        let (tile_runs, tile_start) = group_by_tile(&row_runs, tile, tw, tiles.len());
        Self { width, height, tile, pixels, tiles, sums, row_runs, tile_runs, tile_start }
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
        self.pixels[(y * self.width + x) as usize]
    }

    /// How many pixels are masked in.
    #[must_use]
    pub fn count(&self) -> usize {
        self.pixels.iter().filter(|&&p| p).count()
    }

    /// How many tiles have a pixel masked in, of how many.
    #[must_use]
    pub fn tiles_in(&self) -> (usize, usize) {
        (self.tiles.iter().filter(|&&t| t).count(), self.tiles.len())
    }

    /// The masked-in runs of tile `(tx, ty)` as `(row, first, last)`, by row; none outside the target.
    #[must_use]
    pub fn tile_runs(&self, tx: u32, ty: u32) -> &[(u32, u32, u32)] {
        let tiles_x = self.width.div_ceil(self.tile);
        if tx >= tiles_x || ty >= self.height.div_ceil(self.tile) {
            return &[];
        }
        let i = (ty * tiles_x + tx) as usize;
        &self.tile_runs[self.tile_start[i] as usize..self.tile_start[i + 1] as usize]
    }

    /// Appends to `runs` the masked-in runs of columns `xs..=xe` of row `y`, as inclusive `(first, last)`
    /// pairs.
    pub fn runs(&self, y: u32, xs: u32, xe: u32, runs: &mut Vec<(u32, u32)>) {
        let row = &self.row_runs[y as usize];
        let first = row.partition_point(|&(_, last)| last < xs);
        for &(a, b) in row[first..].iter().take_while(|&&(a, _)| a <= xe) {
            runs.push((a.max(xs), b.min(xe)));
        }
    }
}

/// The row runs cut at tile boundaries and grouped by tile (a counting sort, rows kept in order), with
/// each tile's start in the list.
fn group_by_tile(
    row_runs: &[Vec<(u32, u32)>],
    tile: u32,
    tiles_x: usize,
    tiles: usize,
) -> (Vec<(u32, u32, u32)>, Vec<u32>) {
    let mut pieces = Vec::new();
    for (y, runs) in row_runs.iter().enumerate() {
        for &(a, b) in runs {
            let mut x = a;
            while x <= b {
                let last = (x / tile * tile + tile - 1).min(b);
                let t = (y as u32 / tile) as usize * tiles_x + (x / tile) as usize;
                pieces.push((t, (y as u32, x, last)));
                x = last + 1;
            }
        }
    }
    let mut start = vec![0u32; tiles + 1];
    for &(t, _) in &pieces {
        start[t + 1] += 1;
    }
    for i in 0..tiles {
        start[i + 1] += start[i];
    }
    let mut next = start.clone();
    let mut grouped = vec![(0, 0, 0); pieces.len()];
    for (t, run) in pieces {
        grouped[next[t] as usize] = run;
        next[t] += 1;
    }
    (grouped, start)
}
