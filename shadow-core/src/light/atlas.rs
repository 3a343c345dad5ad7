//! A shadow atlas: the maps of a frame's lights as square tiles of one texture, each light's size chosen
//! by how much of the view it lights, under a budget of texels the user sets.
//!
//! A light asks for its technique's map side; it is granted that side times the square root of the share
//! of the view its reach covers (the texels a pixel of it gets stay about the same however much of the
//! view it covers), a power of two no smaller than [`MIN_TILE`]. While the tiles overflow the atlas, the
//! largest tile is halved (of equal ones, the least important light's first). The tiles are laid in the
//! atlas largest first along a Z-order curve: powers of two sorted from large to small then fill the square
//! without gaps or overlaps.
//!
//! A light keeps the tiles it holds from an earlier frame (where its build lies, kept while nothing it
//! reads changes) as long as the cell it would be granted now is within a factor of 2 of the cell it holds
//! and no halving for the budget reaches it: a static light keeps its build while the camera moves. The
//! others are laid around the kept ones, each at the first free place of its size along the curve; where
//! one finds none, the less important half of the lights keeping theirs give them up, and so on down to
//! every tile laid afresh.

use glam::UVec2;

/// The smallest tile side granted.
pub const MIN_TILE: u32 = 32;

/// What one light asks of the atlas.
#[derive(Clone, Debug, PartialEq)]
pub struct TileRequest {
    /// Tiles it needs: 1 for a spot light, 6 for a point light's cube faces, 0 for a light that takes none
    /// (a directional light, a light out of view, a technique without maps).
    pub faces: u32,
    /// The map side its technique asks for.
    pub side: u32,
    /// The share of the view it lights, in [0, 1].
    pub coverage: f32,
    /// The tiles it holds from an earlier frame, if any.
    pub held: Option<LightTiles>,
}

/// Where a light's maps lie in the atlas.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LightTiles {
    /// The side of each of its tiles, in texels: at most the side asked for, each tile in a cell of the
    /// atlas whose side is the power of two at or above it.
    pub side: u32,
    /// Each tile's corner in the atlas, in texels, one per face.
    pub origins: Vec<UVec2>,
    /// The side of the atlas they lie in.
    pub atlas: u32,
}

/// Why the tiles do not fit.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "a shadow atlas of {side}x{side} texels cannot hold {tiles} tiles of {MIN_TILE}x{MIN_TILE}, the smallest it grants: raise its side"
)]
pub struct AtlasFull {
    /// The atlas side.
    pub side: u32,
    /// The tiles asked for.
    pub tiles: u32,
}

/// The frame's atlas: its side and each light's tiles (`None` for a light that asked for none).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AtlasPlan {
    /// The atlas side, in texels.
    pub side: u32,
    /// Per light, in the order of the requests.
    pub lights: Vec<Option<LightTiles>>,
}

impl AtlasPlan {
    /// Tiles for `requests` in an atlas of `side x side` texels (a power of two).
    ///
    /// # Errors
    /// [`AtlasFull`] when even the smallest tiles do not fit.
    pub fn new(side: u32, requests: &[TileRequest]) -> Result<Self, AtlasFull> {
        let side = side.next_power_of_two();
        let tiles: u32 = requests.iter().map(|r| r.faces).sum();
        let area = |cells: &[u32]| -> u64 {
            requests.iter().zip(cells).map(|(r, &s)| u64::from(r.faces) * u64::from(s) * u64::from(s)).sum()
        };
        if u64::from(tiles) * u64::from(MIN_TILE * MIN_TILE) > u64::from(side) * u64::from(side) {
            return Err(AtlasFull { side, tiles });
        }
        // Each light's cell, a power of two; its tiles are the side asked for where that is smaller. A
        // light keeps the cell it holds where that is within a factor of 2 of the one it would get.
        let mut cells: Vec<u32> = requests.iter().map(|r| wanted(r, side)).collect();
        for (cell, r) in cells.iter_mut().zip(requests) {
            if let Some(held) = holding(r, side)
                && held <= *cell * 2
                && held * 2 >= *cell
            {
                *cell = held;
            }
        }
        while area(&cells) > u64::from(side) * u64::from(side) {
            // The largest cell above the smallest, the least important light's first.
            let largest = (0..requests.len())
                .filter(|&k| requests[k].faces > 0 && cells[k] > MIN_TILE)
                .max_by(|&a, &b| cells[a].cmp(&cells[b]).then(requests[b].coverage.total_cmp(&requests[a].coverage)))
                .unwrap_or_else(|| unreachable!("the smallest tiles fit, checked above"));
            cells[largest] /= 2;
        }
        // The lights that may keep their tiles, most important first.
        let mut holders: Vec<usize> =
            (0..requests.len()).filter(|&k| holding(&requests[k], side) == Some(cells[k])).collect();
        holders.sort_by(|&a, &b| requests[b].coverage.total_cmp(&requests[a].coverage).then(a.cmp(&b)));
        let lay = |keep: &[usize]| {
            let mut free = Occupancy::new(side, &cells);
            let mut lights: Vec<Option<LightTiles>> = vec![None; requests.len()];
            // The tiles kept where they lie, then the others largest first (the light's order among equals).
            for &k in keep {
                let Some(held) = requests[k].held.as_ref() else { continue };
                let before = free.taken.clone();
                if held.origins.iter().all(|&o| free.take(o, cells[k])) {
                    lights[k] = Some(held.clone());
                } else {
                    free.taken = before;
                }
            }
            let mut order: Vec<usize> =
                (0..requests.len()).filter(|&k| requests[k].faces > 0 && lights[k].is_none()).collect();
            order.sort_by_key(|&k| std::cmp::Reverse(cells[k]));
            for k in order {
                let c = cells[k];
                let origins = (0..requests[k].faces).map(|_| free.first(c)).collect::<Option<Vec<_>>>()?;
                lights[k] = Some(LightTiles { side: c.min(requests[k].side), origins, atlas: side });
            }
            Some(lights)
        };
        // Where the others find no room around the kept tiles, the least important lights give theirs up,
        // half of those keeping at a time, down to none (the square filled afresh, which always fits).
        let mut keeping = holders.len();
        let lights = loop {
            if let Some(lights) = lay(&holders[..keeping]) {
                break lights;
            }
            assert!(keeping > 0, "powers of two from large to small fill the square in Z-order");
            keeping /= 2;
        };
        Ok(Self { side, lights })
    }
}

/// The cell of the tiles a request holds, where they were laid in an atlas of `side` for the faces and
/// side it asks for now.
fn holding(r: &TileRequest, side: u32) -> Option<u32> {
    let held = r.held.as_ref()?;
    let cell = held.side.next_power_of_two();
    let same = held.atlas == side && held.origins.len() == r.faces as usize && held.side == cell.min(r.side);
    same.then_some(cell)
}

/// Which squares of the atlas hold a tile, in squares of the smallest cell's side.
struct Occupancy {
    side: u32,
    unit: u32,
    taken: Vec<bool>,
}

impl Occupancy {
    fn new(side: u32, cells: &[u32]) -> Self {
        let unit = cells.iter().copied().filter(|&c| c > 0).min().unwrap_or(side).min(side).max(1);
        let n = (side / unit) as usize;
        Self { side, unit, taken: vec![false; n * n] }
    }

    /// Takes the cell of side `c` at `origin` if it lies in the atlas, aligned and free.
    fn take(&mut self, origin: UVec2, c: u32) -> bool {
        let aligned = origin.x.is_multiple_of(c) && origin.y.is_multiple_of(c);
        let fits = aligned && origin.x + c <= self.side && origin.y + c <= self.side;
        if !fits || !self.is_free(origin, c) {
            return false;
        }
        let (n, u) = ((self.side / self.unit) as usize, self.unit);
        for y in origin.y / u..(origin.y + c) / u {
            for x in origin.x / u..(origin.x + c) / u {
                self.taken[y as usize * n + x as usize] = true;
            }
        }
        true
    }

    fn is_free(&self, origin: UVec2, c: u32) -> bool {
        let (n, u) = ((self.side / self.unit) as usize, self.unit);
        (origin.y / u..(origin.y + c) / u)
            .all(|y| (origin.x / u..(origin.x + c) / u).all(|x| !self.taken[y as usize * n + x as usize]))
    }

    /// Takes the first free cell of side `c` along the Z-order curve.
    fn first(&mut self, c: u32) -> Option<UVec2> {
        let places = u64::from(self.side / c).pow(2);
        let origin = (0..places).map(|i| z_order(i) * c).find(|&o| self.is_free(o, c))?;
        self.take(origin, c).then_some(origin)
    }
}

/// The cell a request is granted before the budget: its side times the square root of its coverage,
/// rounded up to a power of two, at least [`MIN_TILE`] and at most the power of two that holds the side
/// asked for (and the atlas).
fn wanted(r: &TileRequest, atlas: u32) -> u32 {
    if r.faces == 0 {
        return 0;
    }
    let cap = r.side.max(1).next_power_of_two().min(atlas);
    let scaled = (r.side as f32 * r.coverage.clamp(0.0, 1.0).sqrt()).ceil() as u32;
    scaled.next_power_of_two().clamp(MIN_TILE.min(cap), cap)
}

/// The cell at index `i` along the Z-order curve (x from the even bits, y from the odd ones).
fn z_order(i: u64) -> UVec2 {
    let (mut x, mut y) = (0u32, 0u32);
    for bit in 0..32 {
        x |= (((i >> (2 * bit)) & 1) as u32) << bit;
        y |= (((i >> (2 * bit + 1)) & 1) as u32) << bit;
    }
    UVec2::new(x, y)
}

#[cfg(test)]
mod tests {
    use super::{AtlasFull, AtlasPlan, TileRequest};

    fn request(faces: u32, side: u32, coverage: f32) -> TileRequest {
        TileRequest { faces, side, coverage, held: None }
    }

    /// Every tile inside the atlas and no two overlapping.
    fn assert_packed(plan: &AtlasPlan) {
        let mut used = vec![false; (plan.side * plan.side) as usize];
        for tiles in plan.lights.iter().flatten() {
            for o in &tiles.origins {
                assert!(o.x + tiles.side <= plan.side && o.y + tiles.side <= plan.side, "{o} outside");
                for y in o.y..o.y + tiles.side {
                    for x in o.x..o.x + tiles.side {
                        let texel = &mut used[(y * plan.side + x) as usize];
                        assert!(!*texel, "tiles overlap at ({x}, {y})");
                        *texel = true;
                    }
                }
            }
        }
    }

    #[test]
    fn a_light_gets_its_side_scaled_by_its_coverage_within_the_budget() {
        let plan = AtlasPlan::new(4096, &[request(1, 2048, 1.0), request(6, 2048, 0.25), request(1, 1024, 0.01)])
            .expect("fits");
        let sides: Vec<u32> = plan.lights.iter().map(|t| t.as_ref().map_or(0, |t| t.side)).collect();
        // 2048 * 1, 2048 * 0.5, 1024 * 0.1 -> 128 (the power of two above 102.4).
        assert_eq!(sides, [2048, 1024, 128]);
        assert_eq!(plan.lights[1].as_ref().map(|t| t.origins.len()), Some(6));
        assert_packed(&plan);
    }

    #[test]
    fn tiles_over_the_budget_are_halved_largest_and_least_important_first() {
        // 64 point lights of full coverage asking 2048: 384 tiles, 16 million texels hold 384 of 128 and
        // more (16 777 216 / 16 384 = 1024), and not of 256 (256 of them): every light 128 or 256.
        let requests: Vec<TileRequest> = (0..64).map(|k| request(6, 2048, 1.0 - k as f32 / 128.0)).collect();
        let plan = AtlasPlan::new(4096, &requests).expect("fits");
        let sides: Vec<u32> = plan.lights.iter().map(|t| t.as_ref().expect("tiles").side).collect();
        assert!(sides.iter().all(|&s| s == 128 || s == 256), "{sides:?}");
        assert!(sides.windows(2).all(|w| w[0] >= w[1]), "the more important keep the larger tiles: {sides:?}");
        let area: u64 = sides.iter().map(|&s| 6 * u64::from(s * s)).sum();
        assert!(area <= 4096 * 4096 && area > 4096 * 4096 / 2, "{area} texels");
        assert_packed(&plan);
    }

    #[test]
    fn lights_keep_their_tiles_while_their_share_stays_within_a_factor_of_2() {
        let first: Vec<TileRequest> = (0..24).map(|k| request(1 + 5 * (k % 2), 1024, 0.5 / (k + 1) as f32)).collect();
        let before = AtlasPlan::new(8192, &first).expect("fits");
        assert_packed(&before);
        // No halving in an atlas this large. The camera moves: every share changes a little, light 3's fourfold (its side twofold: a cell
        // of 2x is still within reach of the one it holds), light 15's sixteenfold, light 7 is gone.
        let mut next: Vec<TileRequest> = first
            .iter()
            .zip(&before.lights)
            .map(|(r, t)| TileRequest { coverage: r.coverage * 1.2, held: t.clone(), ..r.clone() })
            .collect();
        next[3].coverage *= 4.0;
        next[15].coverage *= 16.0;
        next[7] = TileRequest { faces: 0, held: None, ..next[7].clone() };
        let after = AtlasPlan::new(8192, &next).expect("fits");
        assert_packed(&after);
        for k in (0..24).filter(|&k| k != 15 && k != 7) {
            assert_eq!(after.lights[k], before.lights[k], "light {k} moved");
        }
        let side = |plan: &AtlasPlan, k: usize| plan.lights[k].as_ref().map_or(0, |t| t.side);
        assert_eq!(side(&after, 15), 4 * side(&before, 15), "light 15 is granted its new share");
        assert_eq!(after.lights[7], None);
        // Held tiles of another atlas, or overlapping ones, are laid afresh.
        let mut clash = next.clone();
        clash[1].held = clash[0].held.clone().map(|t| super::LightTiles { origins: vec![t.origins[0]; 6], ..t });
        assert_packed(&AtlasPlan::new(8192, &clash).expect("fits"));
        let moved = AtlasPlan::new(16384, &next).expect("fits");
        assert!(moved.lights.iter().flatten().all(|t| t.atlas == 16384));
    }

    #[test]
    fn where_a_new_tile_finds_no_room_the_least_important_lights_give_theirs_up() {
        // A 64 texel tile held in each 128 quadrant of a 256 atlas leaves no room for a new 128 tile.
        let held =
            |x: u32, y: u32| Some(super::LightTiles { side: 64, origins: vec![glam::UVec2::new(x, y)], atlas: 256 });
        let mut requests: Vec<TileRequest> = [(0, 0), (128, 0), (0, 128), (128, 128)]
            .iter()
            .enumerate()
            .map(|(k, &(x, y))| TileRequest { held: held(x, y), ..request(1, 64, 1.0 - k as f32 / 8.0) })
            .collect();
        requests.push(request(1, 128, 1.0));
        let plan = AtlasPlan::new(256, &requests).expect("fits");
        assert_packed(&plan);
        assert_eq!(plan.lights[4].as_ref().map(|t| t.side), Some(128));
        for (k, r) in requests.iter().enumerate().take(2) {
            assert_eq!(plan.lights[k], r.held, "the more important light {k} keeps its tile");
        }
    }

    #[test]
    fn lights_without_maps_get_none_and_too_many_tiles_are_refused() {
        let plan = AtlasPlan::new(1024, &[request(0, 2048, 1.0), request(1, 16, 1.0)]).expect("fits");
        assert_eq!(plan.lights[0], None);
        assert_eq!(plan.lights[1].as_ref().map(|t| t.side), Some(16), "no tile over the side asked");
        let odd = AtlasPlan::new(4096, &[request(1, 1000, 1.0), request(1, 1000, 0.01)]).expect("fits");
        let sides: Vec<u32> = odd.lights.iter().map(|t| t.as_ref().map_or(0, |t| t.side)).collect();
        assert_eq!(sides, [1000, 128], "a side not a power of two, granted whole, in a cell that is");
        let over = vec![request(6, 512, 1.0); 200];
        assert_eq!(AtlasPlan::new(256, &over), Err(AtlasFull { side: 256, tiles: 1200 }));
    }
}
