//! A shadow atlas: the maps of a frame's lights as square tiles of one texture, each light's size chosen
//! by how much of the view it lights, under a budget of texels the user sets.
//!
//! A light asks for its technique's map side; it is granted that side times the square root of the share
//! of the view its reach covers (the texels a pixel of it gets stay about the same however much of the
//! view it covers), a power of two no smaller than [`MIN_TILE`]. While the tiles overflow the atlas, the
//! largest tile is halved (of equal ones, the least important light's first). The tiles are laid in the
//! atlas largest first along a Z-order curve: powers of two sorted from large to small then fill the square
//! without gaps or overlaps.

use glam::UVec2;

/// The smallest tile side granted.
pub const MIN_TILE: u32 = 32;

/// What one light asks of the atlas.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TileRequest {
    /// Tiles it needs: 1 for a spot light, 6 for a point light's cube faces, 0 for a light that takes none
    /// (a directional light, a light out of view, a technique without maps).
    pub faces: u32,
    /// The map side its technique asks for.
    pub side: u32,
    /// The share of the view it lights, in [0, 1].
    pub coverage: f32,
}

/// Where a light's maps lie in the atlas.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LightTiles {
    /// The side of each of its tiles, in texels: at most the side asked for, each tile in a cell of the
    /// atlas whose side is the power of two at or above it.
    pub side: u32,
    /// Each tile's corner in the atlas, in texels, one per face.
    pub origins: Vec<UVec2>,
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
        // Each light's cell, a power of two; its tiles are the side asked for where that is smaller.
        let mut cells: Vec<u32> = requests.iter().map(|r| wanted(r, side)).collect();
        while area(&cells) > u64::from(side) * u64::from(side) {
            // The largest cell above the smallest, the least important light's first.
            let largest = (0..requests.len())
                .filter(|&k| requests[k].faces > 0 && cells[k] > MIN_TILE)
                .max_by(|&a, &b| cells[a].cmp(&cells[b]).then(requests[b].coverage.total_cmp(&requests[a].coverage)))
                .unwrap_or_else(|| unreachable!("the smallest tiles fit, checked above"));
            cells[largest] /= 2;
        }
        // Largest first (the light's order among equals), each face at the next place of its size on the
        // Z-order curve.
        let mut order: Vec<usize> = (0..requests.len()).filter(|&k| requests[k].faces > 0).collect();
        order.sort_by_key(|&k| std::cmp::Reverse(cells[k]));
        let mut lights: Vec<Option<LightTiles>> = vec![None; requests.len()];
        let mut filled = 0u64;
        for k in order {
            let c = cells[k];
            let origins = (0..requests[k].faces)
                .map(|_| {
                    let cell = u64::from(c) * u64::from(c);
                    let origin = z_order(filled / cell) * c;
                    filled += cell;
                    origin
                })
                .collect();
            lights[k] = Some(LightTiles { side: c.min(requests[k].side), origins });
        }
        Ok(Self { side, lights })
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
        TileRequest { faces, side, coverage }
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
