//! The scenes of alpha-tested casters: cards that a texture's alpha cuts out (glTF `MASK`), their
//! textures made here.

use glam::{Vec2, Vec3};

use super::builders::Stage;
use super::{SceneParams, built};
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
    let texture = s.scene.add_texture(checkerboard(CHECKER_SQUARES, [224, 150, 80]));
    let crisp = Sampler {
        mag: Filter::Nearest,
        min: Filter::Nearest,
        mipmap: None,
        wrap_u: Wrap::Repeat,
        wrap_v: Wrap::Repeat,
    };
    let material = s.scene.add_material(Material {
        name: "checkerboard".into(),
        base_color: Vec3::ONE,
        base_color_texture: Some(TextureRef { texture, sampler: crisp, transform: UvTransform::IDENTITY }),
        alpha_mode: AlphaMode::Mask { cutoff: AlphaMode::DEFAULT_CUTOFF },
        two_sided: true,
        ..Material::default()
    });
    let card = s.scene.add_mesh(card(CARD_SIDE));
    let lift = glam::Mat4::from_translation(Vec3::Y * CARD_HEIGHT);
    if let Err(e) = s.scene.add_instance("card", card, material, lift) {
        panic!("built-in scene: {e}");
    }
    s.finish(
        Camera::look_at(Vec3::new(0.0, 1.6, 2.2), Vec3::new(0.0, 0.15, -0.2), 45.0),
        Light::directional(Vec3::NEG_Y),
    )
}

/// A level square card of side `side` centred at the origin, facing +y, its texture coordinates
/// spanning the texture once: u along +x, v along +z.
fn card(side: f32) -> Mesh {
    let uvs = vec![Vec2::new(0.0, 0.0), Vec2::new(0.0, 1.0), Vec2::new(1.0, 1.0), Vec2::new(1.0, 0.0)];
    built(procedural::plane(side, side)).with_uvs(uvs).unwrap_or_else(|e| panic!("built-in scene: {e}"))
}

/// A `squares` x `squares` texture of one texel a square, opaque `color` (sRGB) and clear in turn, the
/// first texel opaque.
fn checkerboard(squares: u32, [r, g, b]: [u8; 3]) -> Texture {
    let texels = (0..squares * squares)
        .map(|i| if (i % squares + i / squares).is_multiple_of(2) { [r, g, b, 255] } else { [r, g, b, 0] });
    Texture::from_rgba8("checkerboard", squares, squares, texels.collect())
        .unwrap_or_else(|e| panic!("built-in scene: {e}"))
}
