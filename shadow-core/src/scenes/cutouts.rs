//! The scenes of alpha-tested casters: cards that a texture's alpha cuts out (glTF `MASK`), their
//! textures made here.

use glam::{Mat4, Vec2, Vec3};

use super::builders::{OUTDOOR_HALF, SUN_ELEVATION, Stage, branch};
use super::{Rng, SceneParams, built};
use crate::material::{AlphaMode, Filter, Sampler, Texture, TextureRef, UvTransform, Wrap};
use crate::mesh::Mesh;
use crate::procedural;
use crate::scene::{Camera, Light, Material, Scene};

/// Squares along each side of `cutout`'s checkerboard.
pub const CHECKER_SQUARES: u32 = 8;
/// The side of `cutout`'s card, in metres.
pub const CARD_SIDE: f32 = 1.0;
/// The height of `cutout`'s card over the ground.
pub const CARD_HEIGHT: f32 = 1.0;

/// How much of the card's shadow in `cutout` is lit: the mean visibility of the pixels that show the
/// ground under the card (each given as its surface's world position and its visibility), and how many
/// there are. The board's squares are half of it, so an exact shadow lights half.
pub fn card_shadow_lit_share(pixels: impl IntoIterator<Item = (Vec3, f32)>) -> (f64, usize) {
    let half = CARD_SIDE * 0.5;
    let (sum, count) = pixels
        .into_iter()
        .filter(|(p, _)| p.y.abs() < 1e-3 && p.x.abs() < half && p.z.abs() < half)
        .fold((0.0, 0), |(sum, count), (_, v)| (sum + f64::from(v), count + 1));
    (sum / count.max(1) as f64, count)
}

/// A checkerboard card of 1 x 1 m held level 1 m over the ground, under a directional light straight
/// above it: its shadow is the board's pattern, exactly half of it lit. The camera sees the whole shadow
/// past the card's near edge.
pub(super) fn cutout(_: &SceneParams) -> Scene {
    let mut s = Stage::new().ground(10.0);
    let crisp = Sampler {
        mag: Filter::Nearest,
        min: Filter::Nearest,
        mipmap: None,
        wrap_u: Wrap::Repeat,
        wrap_v: Wrap::Repeat,
    };
    let board = (checkerboard(CHECKER_SQUARES, [224, 150, 80]), crisp);
    add_masked(&mut s, "card", card(CARD_SIDE), board, Mat4::from_translation(Vec3::Y * CARD_HEIGHT));
    s.finish(
        Camera::look_at(Vec3::new(0.0, 1.6, 2.2), Vec3::new(0.0, 0.15, -0.2), 45.0),
        Light::directional(Vec3::NEG_Y),
    )
}

/// Leaf cards around each twig of `foliage`'s tree.
const LEAF_CARDS_PER_TWIG: usize = 36;

/// A tree of bare branches (`tree`'s, two levels fewer) in leaves: around each of its 81 twigs, 36 cards
/// of a spray of five leaves, each card 0.25 m across and turned at random, 2916 cards in all, under a
/// spot light placed as `tree`'s.
pub(super) fn foliage(p: &SceneParams) -> Scene {
    let mut rng = Rng::new(p.seed);
    let mut s = Stage::new().ground(12.0);
    let (mut parts, mut twigs) = (Vec::new(), Vec::new());
    branch(&mut rng, (Vec3::ZERO, Vec3::Y), (0.9, 0.09), 4, (&mut parts, &mut twigs));
    let bark = Mesh::merged(&parts).unwrap_or_else(|e| panic!("built-in scene: {e}"));
    s.add("branches", bark, Vec3::new(0.55, 0.4, 0.25), Mat4::IDENTITY);
    let mut cards = Cards::default();
    for &(base, tip) in &twigs {
        for _ in 0..LEAF_CARDS_PER_TWIG {
            // Along the twig's outer two thirds and a little past its tip, up to 0.2 m off it.
            let along = base + (tip - base) * rng.range(0.35, 1.15);
            let off = Vec3::new(rng.range(-1.0, 1.0), rng.range(-0.6, 1.0), rng.range(-1.0, 1.0)) * 0.3;
            let normal = Vec3::new(rng.range(-1.0, 1.0), rng.range(-0.2, 1.0), rng.range(-1.0, 1.0));
            let spin = rng.range(0.0, std::f32::consts::TAU);
            cards.push_turned(along + off, normal.normalize_or(Vec3::Y), spin, 0.25);
        }
    }
    add_masked(&mut s, "leaves", cards.mesh(), (leaf_spray(128), Sampler::default()), Mat4::IDENTITY);
    s.finish(
        Camera::look_at(Vec3::new(2.2, 2.6, 4.6), Vec3::new(-0.6, 0.8, -0.8), 45.0),
        Light::spot(Vec3::new(2.2, 5.0, 1.8), Vec3::new(-0.3, 0.6, -0.3), 70.0),
    )
}

/// The width of one picket and the gap beside it, along a fence, in metres.
const PICKET_PERIOD: f32 = 0.15;
/// A fence's height.
const FENCE_HEIGHT: f32 = 1.2;

/// Picket fences along both sides of a 6 m street at the outdoor scenes' scale (a ground of 200 x 200 m,
/// the camera at head height looking down the street), each side four cards 40 m long and 1.2 m high, their
/// texture one picket and its gap every 0.15 m; under `outdoor`'s low sun, which throws the fences'
/// shadows across the street.
pub(super) fn fence(_: &SceneParams) -> Scene {
    let mut s = Stage::new().ground(2.0 * OUTDOOR_HALF);
    let mut cards = Cards::default();
    for x in [-3.0, 3.0] {
        for k in 0..4 {
            // From 3 m ahead of the camera down the street.
            let z0 = OUTDOOR_HALF - 8.0 - 40.0 * k as f32;
            let z1 = z0 - 40.0;
            let repeats = (z0 - z1) / PICKET_PERIOD;
            let corners = [
                Vec3::new(x, FENCE_HEIGHT, z0),
                Vec3::new(x, FENCE_HEIGHT, z1),
                Vec3::new(x, 0.0, z1),
                Vec3::new(x, 0.0, z0),
            ];
            cards.push(corners, [Vec2::ZERO, Vec2::new(repeats, 0.0), Vec2::new(repeats, 1.0), Vec2::new(0.0, 1.0)]);
        }
    }
    let sampler = Sampler { wrap_v: Wrap::ClampToEdge, ..Sampler::default() };
    add_masked(&mut s, "fences", cards.mesh(), (picket(64, 256), sampler), Mat4::IDENTITY);
    // The sun of `outdoor`: to the right and behind, across the street at 45 degrees, 20 degrees high.
    let elevation = SUN_ELEVATION.to_radians();
    let travel = Vec3::new(-0.71, 0.0, -0.71) * elevation.cos() - Vec3::Y * elevation.sin();
    s.finish(
        Camera::look_at(Vec3::new(0.0, 1.7, OUTDOOR_HALF - 5.0), Vec3::new(0.0, 1.2, -OUTDOOR_HALF), 60.0),
        Light::directional(travel),
    )
}

/// Adds `mesh` at `transform`, drawn with a two-sided material of its own (named after the texture) whose
/// texture's alpha cuts it out at glTF's default cutoff, read through `sampler`.
fn add_masked(s: &mut Stage, name: &str, mesh: Mesh, (texture, sampler): (Texture, Sampler), transform: Mat4) {
    let material = Material {
        name: texture.name().to_string(),
        base_color: Vec3::ONE,
        alpha_mode: AlphaMode::Mask { cutoff: AlphaMode::DEFAULT_CUTOFF },
        two_sided: true,
        ..Material::default()
    };
    let texture = s.scene.add_texture(texture);
    let base_color_texture = Some(TextureRef { texture, sampler, transform: UvTransform::IDENTITY });
    let material = s.scene.add_material(Material { base_color_texture, ..material });
    let mesh = s.scene.add_mesh(mesh);
    if let Err(e) = s.scene.add_instance(name, mesh, material, transform) {
        panic!("built-in scene: {e}");
    }
}

/// Quads, each with texture coordinates of its own, gathered into one mesh.
#[derive(Default)]
struct Cards {
    positions: Vec<Vec3>,
    uvs: Vec<Vec2>,
    triangles: Vec<[u32; 3]>,
}

impl Cards {
    /// A quad of the four corners in turn (counter-clockwise seen from its front) and their texture
    /// coordinates.
    fn push(&mut self, corners: [Vec3; 4], uvs: [Vec2; 4]) {
        let first = self.positions.len() as u32;
        self.positions.extend(corners);
        self.uvs.extend(uvs);
        self.triangles.extend([[first, first + 1, first + 2], [first, first + 2, first + 3]]);
    }

    /// A square of side `side` centred at `centre`, facing `normal` and turned `spin` about it, the
    /// texture once over it, upright (v down the card) before the turn.
    fn push_turned(&mut self, centre: Vec3, normal: Vec3, spin: f32, side: f32) {
        let (u, v) = normal.any_orthonormal_pair();
        let (sin, cos) = spin.sin_cos();
        let (right, up) = ((u * cos + v * sin) * side * 0.5, (v * cos - u * sin) * side * 0.5);
        let corners = [centre - right + up, centre - right - up, centre + right - up, centre + right + up];
        self.push(corners, [Vec2::ZERO, Vec2::new(0.0, 1.0), Vec2::ONE, Vec2::new(1.0, 0.0)]);
    }

    fn mesh(self) -> Mesh {
        Mesh::new(self.positions, self.triangles)
            .and_then(|m| m.with_uvs(self.uvs))
            .unwrap_or_else(|e| panic!("built-in scene: {e}"))
    }
}

/// A level square card of side `side` centred at the origin, facing +y, its texture coordinates
/// spanning the texture once: u along +x, v along +z.
fn card(side: f32) -> Mesh {
    let uvs = vec![Vec2::new(0.0, 0.0), Vec2::new(0.0, 1.0), Vec2::new(1.0, 1.0), Vec2::new(1.0, 0.0)];
    built(procedural::plane(side, side)).with_uvs(uvs).unwrap_or_else(|e| panic!("built-in scene: {e}"))
}

/// The share of a texel's area inside a shape, from 4 x 4 samples: `inside` takes texture coordinates.
fn coverage(x: u32, y: u32, (width, height): (u32, u32), inside: impl Fn(Vec2) -> bool) -> f32 {
    let hits = (0..16)
        .filter(|k| {
            let sub = Vec2::new((k % 4) as f32 + 0.5, (k / 4) as f32 + 0.5) / 4.0;
            inside((Vec2::new(x as f32, y as f32) + sub) / Vec2::new(width as f32, height as f32))
        })
        .count();
    hits as f32 / 16.0
}

/// A `side` x `side` texture of five leaves fanned up from a stem at the bottom, each a pointed oval in
/// a green of its own; clear around them, with edges as smooth as the texels allow.
fn leaf_spray(side: u32) -> Texture {
    // Each leaf: its turn from straight up (radians), length and half-width, in texture units.
    let leaves = [(-1.0, 0.4, 0.12), (-0.5, 0.47, 0.14), (0.0, 0.52, 0.15), (0.5, 0.46, 0.14), (1.0, 0.41, 0.12)];
    let greens = [[70, 130, 40], [90, 150, 50], [60, 120, 35], [85, 145, 45], [75, 135, 40]];
    let stem = Vec2::new(0.5, 0.97);
    let leaf_at = |uv: Vec2| {
        leaves.iter().position(|&(turn, length, half_width): &(f32, f32, f32)| {
            let (sin, cos) = turn.sin_cos();
            let d = uv - stem;
            // Along the leaf (up the texture is -v) and across it.
            let (along, across) = (-d.y * cos + d.x * sin, d.x * cos + d.y * sin);
            let t = (along - 0.04) / length;
            (0.0..1.0).contains(&t) && across.abs() < half_width * (std::f32::consts::PI * t).sin().powf(0.7)
        })
    };
    let texels = (0..side * side)
        .map(|i| {
            let (x, y) = (i % side, i / side);
            let alpha = coverage(x, y, (side, side), |uv| leaf_at(uv).is_some());
            let centre = (Vec2::new(x as f32, y as f32) + 0.5) / side as f32;
            let [r, g, b] = leaf_at(centre).map_or([60, 110, 35], |k| greens[k]);
            [r, g, b, (alpha * 255.0).round() as u8]
        })
        .collect();
    Texture::from_rgba8("leaf spray", side, side, texels).unwrap_or_else(|e| panic!("built-in scene: {e}"))
}

/// A `width` x `height` texture of one white picket with a pointed top and the gap beside it, crossed by
/// two rails; v runs down from the fence's top.
fn picket(width: u32, height: u32) -> Texture {
    let inside = |uv: Vec2| {
        // The picket: the middle 60% of the width, its top a point 0.1 of the height tall.
        let from_middle = (uv.x - 0.5).abs();
        let picket = from_middle < 0.3 && uv.y > 0.1 * from_middle / 0.3;
        let rail = (0.22..0.3).contains(&uv.y) || (0.72..0.8).contains(&uv.y);
        picket || rail
    };
    let texels = (0..width * height)
        .map(|i| {
            let alpha = coverage(i % width, i / width, (width, height), inside);
            [235, 232, 222, (alpha * 255.0).round() as u8]
        })
        .collect();
    Texture::from_rgba8("picket", width, height, texels).unwrap_or_else(|e| panic!("built-in scene: {e}"))
}

/// A `squares` x `squares` texture of one texel a square, opaque `color` (sRGB) and clear in turn, the
/// first texel opaque.
fn checkerboard(squares: u32, [r, g, b]: [u8; 3]) -> Texture {
    let texels = (0..squares * squares)
        .map(|i| if (i % squares + i / squares).is_multiple_of(2) { [r, g, b, 255] } else { [r, g, b, 0] });
    Texture::from_rgba8("checkerboard", squares, squares, texels.collect())
        .unwrap_or_else(|e| panic!("built-in scene: {e}"))
}
