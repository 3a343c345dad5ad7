//! Surface appearance: a base colour with its alpha, an optional base-colour texture read through a
//! sampler and a texture-coordinate transform, and how alpha decides coverage (glTF 2.0 3.9).
//!
//! The texture rule both backends follow lives in [`sampler`]; decoded images and their mip chains in
//! [`texture`]. A material names its texture by [`TextureKey`], so a texture used by many materials is
//! decoded and stored once, in the scene.

pub mod sampler;
pub mod texture;

use glam::{Mat3, Vec2, Vec3, Vec4};

pub use sampler::{Filter, Footprint, Sampler, Wrap};
pub use texture::{MAX_TEXTURE_SIDE, Texture, TextureError, TextureLevel};

use crate::scene::TextureKey;

/// How a material's alpha decides whether a point of its surface is there.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum AlphaMode {
    /// Alpha is ignored: the surface is everywhere (glTF `OPAQUE`).
    #[default]
    Opaque,
    /// The surface is there where alpha is at least `cutoff`, and absent elsewhere (glTF `MASK`).
    Mask {
        /// The alpha at and above which the surface is there (glTF's default is 0.5).
        cutoff: f32,
    },
    /// The surface lets `1 - alpha` of the light through (glTF `BLEND`).
    Blend,
}

impl AlphaMode {
    /// glTF's default cutoff for `MASK`.
    pub const DEFAULT_CUTOFF: f32 = 0.5;

    /// The name glTF gives the mode.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Opaque => "OPAQUE",
            Self::Mask { .. } => "MASK",
            Self::Blend => "BLEND",
        }
    }
}

/// The transform from a mesh's texture coordinates to the texture's (glTF's `KHR_texture_transform`):
/// scale, then rotate about the origin, then offset.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvTransform {
    /// Added last, in texture coordinates.
    pub offset: Vec2,
    /// Radians; positive turns the coordinates from +u towards -v (the image turns clockwise on screen,
    /// v pointing down it).
    pub rotation: f32,
    /// Applied first, per axis.
    pub scale: Vec2,
}

impl Default for UvTransform {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl UvTransform {
    /// No change.
    pub const IDENTITY: Self = Self { offset: Vec2::ZERO, rotation: 0.0, scale: Vec2::ONE };

    /// True when the transform changes nothing.
    #[must_use]
    pub fn is_identity(&self) -> bool {
        *self == Self::IDENTITY
    }

    /// The transform as a 3 x 3 affine matrix on `(u, v, 1)`: `T * R * S`, with `R`'s columns
    /// `(cos, -sin)` and `(sin, cos)` as the extension writes it.
    #[must_use]
    pub fn matrix(&self) -> Mat3 {
        let (s, c) = self.rotation.sin_cos();
        Mat3::from_cols(
            Vec3::new(c * self.scale.x, -s * self.scale.x, 0.0),
            Vec3::new(s * self.scale.y, c * self.scale.y, 0.0),
            self.offset.extend(1.0),
        )
    }

    /// Transforms a texture coordinate.
    #[must_use]
    pub fn apply(&self, uv: Vec2) -> Vec2 {
        self.matrix().transform_point2(uv)
    }
}

/// A material's use of a texture: which, read how, and through which coordinate transform.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextureRef {
    /// The texture, in the scene.
    pub texture: TextureKey,
    /// How it is read.
    pub sampler: Sampler,
    /// From the mesh's coordinates to the texture's.
    pub transform: UvTransform,
}

impl TextureRef {
    /// The texture's linear colour and alpha at mesh coordinate `uv`, over a footprint in mesh
    /// coordinates: the transform moves the point and turns and scales the footprint with it, then the
    /// sampler reads the texture ([`Sampler::sample`]).
    #[must_use]
    pub fn sample(&self, texture: &Texture, uv: Vec2, footprint: Footprint) -> Vec4 {
        let m = self.transform.matrix();
        let footprint = Footprint { dx: m.transform_vector2(footprint.dx), dy: m.transform_vector2(footprint.dy) };
        self.sampler.sample(texture, m.transform_point2(uv), footprint)
    }
}

/// Surface appearance and shadow flags.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name, for reports.
    pub name: String,
    /// Linear-RGB albedo (multiplied by the texture's colour where there is one).
    pub base_color: Vec3,
    /// Alpha of the base colour (multiplied by the texture's alpha where there is one).
    pub alpha: f32,
    /// The base-colour texture, read at the mesh's texture coordinates.
    pub base_color_texture: Option<TextureRef>,
    /// How alpha decides coverage.
    pub alpha_mode: AlphaMode,
    /// Lit from both sides (the shading normal faces the viewer).
    pub two_sided: bool,
    /// The camera does not see its back faces (glTF's `doubleSided: false`): an open surface seen from
    /// behind is not drawn, nor a closed one's inside. They still cast shadows.
    pub cull_back_faces: bool,
    /// Whether surfaces with this material block light.
    pub casts_shadow: bool,
    /// Whether shadows are computed on surfaces with this material.
    pub receives_shadow: bool,
}

impl Default for Material {
    fn default() -> Self {
        Self {
            name: "default".into(),
            base_color: Vec3::splat(0.8),
            alpha: 1.0,
            base_color_texture: None,
            alpha_mode: AlphaMode::Opaque,
            two_sided: false,
            cull_back_faces: false,
            casts_shadow: true,
            receives_shadow: true,
        }
    }
}

impl Material {
    /// A default material of the given colour.
    #[must_use]
    pub fn colored(name: &str, base_color: Vec3) -> Self {
        Self { name: name.into(), base_color, ..Self::default() }
    }

    /// True when alpha can make part of the surface absent or see-through: every mode but opaque.
    #[must_use]
    pub fn uses_alpha(&self) -> bool {
        self.alpha_mode != AlphaMode::Opaque
    }

    /// The base colour (linear RGB) and alpha at mesh coordinate `uv` over `footprint`: the factor times
    /// the texture's sample. `texture` is the one [`Self::base_color_texture`] names (the scene's
    /// [`crate::Scene::texture`]); without it, or without coordinates to read it at, the factor alone.
    #[must_use]
    pub fn base_color_at(&self, texture: Option<&Texture>, uv: Option<Vec2>, footprint: Footprint) -> Vec4 {
        let factor = self.base_color.extend(self.alpha);
        match (&self.base_color_texture, texture, uv) {
            (Some(r), Some(t), Some(uv)) => factor * r.sample(t, uv, footprint),
            _ => factor,
        }
    }

    /// The alpha test: whether the surface is there at `uv`. Opaque and blended surfaces are everywhere;
    /// a masked one where its alpha ([`Self::base_color_at`]) is at least the cutoff. Rays pass
    /// [`Footprint::POINT`] (level 0, the magnification filter); rasterized passes the footprint of their
    /// pixel or map texel.
    #[must_use]
    pub fn passes(&self, texture: Option<&Texture>, uv: Option<Vec2>, footprint: Footprint) -> bool {
        self.alpha_test(texture).is_none_or(|test| test.passes(uv, footprint))
    }

    /// The alpha test of a masked material ([`Self::passes`]) made ready for many reads, `texture` the
    /// one [`Self::base_color_texture`] names; `None` for an opaque or blended one, which is everywhere.
    #[must_use]
    pub fn alpha_test<'a>(&'a self, texture: Option<&'a Texture>) -> Option<AlphaTest<'a>> {
        let AlphaMode::Mask { cutoff } = self.alpha_mode else { return None };
        let read = self.base_color_texture.as_ref().zip(texture).map(|(r, t)| (r.sampler, t, r.transform.matrix()));
        Some(AlphaTest { cutoff, alpha: self.alpha, read })
    }
}

/// A masked material's alpha test ([`Material::alpha_test`]): its texture-coordinate transform worked out
/// once and the alpha channel alone read, with the answers of [`Material::passes`] to the bit.
#[derive(Clone, Copy, Debug)]
pub struct AlphaTest<'a> {
    cutoff: f32,
    /// The base colour's alpha factor.
    alpha: f32,
    /// The texture: its sampler, its texels and the transform into it.
    read: Option<(Sampler, &'a Texture, Mat3)>,
}

impl AlphaTest<'_> {
    /// Whether the surface is there at mesh coordinate `uv` over `footprint` (see [`Material::passes`]).
    #[must_use]
    #[inline]
    pub fn passes(&self, uv: Option<Vec2>, footprint: Footprint) -> bool {
        let alpha = match (self.read, uv) {
            // As `TextureRef::sample` moves the point and the footprint.
            (Some((sampler, texture, m)), Some(uv)) => {
                let footprint =
                    Footprint { dx: m.transform_vector2(footprint.dx), dy: m.transform_vector2(footprint.dy) };
                self.alpha * sampler.sample_alpha(texture, m.transform_point2(uv), footprint)
            }
            _ => self.alpha,
        };
        alpha >= self.cutoff
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A PNG of the given RGBA8 texels.
    pub(crate) fn png(width: u32, height: u32, texels: &[[u8; 4]]) -> Vec<u8> {
        let mut out = Vec::new();
        let raw: Vec<u8> = texels.iter().flatten().copied().collect();
        image::ImageEncoder::write_image(
            image::codecs::png::PngEncoder::new(&mut out),
            &raw,
            width,
            height,
            image::ExtendedColorType::Rgba8,
        )
        .expect("encode");
        out
    }

    /// A `width` x `height` PNG whose header claims `claimed_width` x `claimed_height` (with a header
    /// checksum that agrees, so only the size is wrong).
    pub(crate) fn png_claiming(width: u32, height: u32, claimed_width: u32, claimed_height: u32) -> Vec<u8> {
        let mut bytes = png(width, height, &vec![[0, 0, 0, 255]; (width * height) as usize]);
        // IHDR follows the 8-byte signature: its length (4 bytes), type (4), then width and height.
        bytes[16..20].copy_from_slice(&claimed_width.to_be_bytes());
        bytes[20..24].copy_from_slice(&claimed_height.to_be_bytes());
        let mut crc = flate2::Crc::new();
        crc.update(&bytes[12..29]);
        bytes[29..33].copy_from_slice(&crc.sum().to_be_bytes());
        bytes
    }

    #[test]
    fn the_extension_example_reads_the_lower_left_quadrant_turned() {
        // KHR_texture_transform's example: offset (0, 1), a quarter turn, scale 1/2 maps the unit square
        // onto the image's lower-left quadrant (v down), u running up it.
        let t =
            UvTransform { offset: Vec2::new(0.0, 1.0), rotation: std::f32::consts::FRAC_PI_2, scale: Vec2::splat(0.5) };
        let close = |a: Vec2, b: Vec2| (a - b).length() < 1e-6;
        assert!(close(t.apply(Vec2::ZERO), Vec2::new(0.0, 1.0)));
        assert!(close(t.apply(Vec2::new(1.0, 0.0)), Vec2::new(0.0, 0.5)));
        assert!(close(t.apply(Vec2::new(0.0, 1.0)), Vec2::new(0.5, 1.0)));
        assert!(UvTransform::default().is_identity());
    }

    /// A `side` x `side` texture whose texels alternate clear and opaque, one by one.
    fn alternating(side: u32) -> Texture {
        let texels =
            (0..side * side).map(|i| if (i % side + i / side).is_multiple_of(2) { [0; 4] } else { [255; 4] }).collect();
        Texture::from_rgba8("alternating", side, side, texels).unwrap()
    }

    #[test]
    fn the_transform_moves_the_point_and_turns_the_footprint() {
        // A quarter turn maps +u onto -v: a footprint one texel along u reads as one along v.
        let t = alternating(16);
        let r = TextureRef {
            texture: TextureKey::default(),
            sampler: Sampler {
                mag: Filter::Nearest,
                min: Filter::Nearest,
                mipmap: Some(Filter::Nearest),
                ..Sampler::default()
            },
            transform: UvTransform {
                offset: Vec2::new(0.5, 0.5),
                rotation: std::f32::consts::FRAC_PI_2,
                scale: Vec2::splat(2.0),
            },
        };
        let uv = Vec2::new(0.1, 0.2);
        let moved = r.transform.apply(uv);
        let footprint = Footprint { dx: Vec2::new(4.0 / 32.0, 0.0), dy: Vec2::ZERO };
        let turned = Footprint { dx: r.transform.matrix().transform_vector2(footprint.dx), dy: Vec2::ZERO };
        assert!((turned.dx - Vec2::new(0.0, -0.25)).length() < 1e-6, "{:?}", turned.dx);
        assert_eq!(r.sample(&t, uv, footprint), r.sampler.sample(&t, moved, turned));
        assert_eq!(r.sample(&t, uv, Footprint::POINT), r.sampler.sample(&t, moved, Footprint::POINT));
    }

    #[test]
    fn the_alpha_test_reads_the_level_of_the_footprint() {
        // One-texel squares: level 0 is clear or opaque texel by texel, every level above half clear.
        let t = alternating(16);
        let nearest =
            Sampler { mag: Filter::Nearest, min: Filter::Nearest, mipmap: Some(Filter::Nearest), ..Sampler::default() };
        let r = TextureRef { texture: TextureKey::default(), sampler: nearest, transform: UvTransform::IDENTITY };
        let card = |cutoff| Material {
            base_color_texture: Some(r),
            alpha_mode: AlphaMode::Mask { cutoff },
            ..Material::default()
        };
        let (clear, opaque) = (Vec2::new(0.5 / 16.0, 0.5 / 16.0), Vec2::new(1.5 / 16.0, 0.5 / 16.0));
        let texels = |n: f32| Footprint { dx: Vec2::new(n / 16.0, 0.0), dy: Vec2::new(0.0, n / 16.0) };
        for n in [0.125, 0.5, 1.0] {
            assert!(!card(0.5).passes(Some(&t), Some(clear), texels(n)), "{n} texels");
            assert!(card(0.5).passes(Some(&t), Some(opaque), texels(n)), "{n} texels");
        }
        // Four texels a pixel read level 2, whose alpha is 128 / 255 everywhere.
        assert!(card(0.5).passes(Some(&t), Some(clear), texels(4.0)));
        assert!(!card(0.51).passes(Some(&t), Some(opaque), texels(4.0)));
        // The factor's alpha multiplies the texel's; opaque and blended surfaces are everywhere.
        let faded = Material { alpha: 0.4, ..card(0.5) };
        assert!(!faded.passes(Some(&t), Some(opaque), Footprint::POINT));
        for mode in [AlphaMode::Opaque, AlphaMode::Blend] {
            assert!(Material { alpha_mode: mode, ..card(0.5) }.passes(Some(&t), Some(clear), Footprint::POINT));
        }
        // Without its texture, or without coordinates, a masked material is its factor.
        assert!(card(0.5).passes(None, Some(clear), Footprint::POINT));
        assert!(!faded.passes(Some(&t), None, Footprint::POINT));
    }

    /// The alpha test reads the alpha alone and answers as the full colour's alpha against the cutoff
    /// does, to the bit: over random points, footprints from magnified to the top level, every filter and
    /// wrap, a turned and scaled transform, and cutoffs at, just under and just over the alpha read.
    #[test]
    fn the_alpha_test_is_the_colours_alpha_to_the_bit() {
        let mut rng = crate::scenes::Rng::new(9);
        let texels = (0..24 * 20).map(|_| [0, 0, 0, (rng.unit() * 256.0) as u8]).collect();
        let t = Texture::from_rgba8("noise", 24, 20, texels).unwrap();
        let (mut checked, mut at_the_cutoff) = (0, 0);
        for k in 0..4000 {
            let filter = |bit: usize| if (k >> bit) & 1 == 0 { Filter::Nearest } else { Filter::Linear };
            let wraps = [Wrap::Repeat, Wrap::MirroredRepeat, Wrap::ClampToEdge];
            let sampler = Sampler {
                mag: filter(0),
                min: filter(1),
                mipmap: [None, Some(Filter::Nearest), Some(Filter::Linear)][k % 3],
                wrap_u: wraps[k % 3],
                wrap_v: wraps[(k / 3) % 3],
            };
            let transform = if k % 2 == 0 {
                UvTransform::IDENTITY
            } else {
                UvTransform { offset: Vec2::new(0.2, -0.7), rotation: 0.9, scale: Vec2::new(1.7, 0.6) }
            };
            let r = TextureRef { texture: TextureKey::default(), sampler, transform };
            let uv = Vec2::new(rng.range(-2.0, 3.0), rng.range(-2.0, 3.0));
            let size = 2f32.powf(rng.range(-3.0, 6.0)) / 24.0;
            let footprint = Footprint { dx: Vec2::new(size, rng.range(-size, size)), dy: Vec2::new(0.0, size) };
            let factor = if k % 5 == 0 { 0.7 } else { 1.0 };
            let alpha = Material { base_color_texture: Some(r), alpha: factor, ..Material::default() }
                .base_color_at(Some(&t), Some(uv), footprint)
                .w;
            for cutoff in [alpha, alpha.next_down(), alpha.next_up(), 0.5] {
                let m = Material {
                    base_color_texture: Some(r),
                    alpha: factor,
                    alpha_mode: AlphaMode::Mask { cutoff },
                    ..Material::default()
                };
                let test = m.alpha_test(Some(&t)).expect("a masked material");
                assert_eq!(test.passes(Some(uv), footprint), alpha >= cutoff, "{k}: {uv} {footprint:?} {cutoff}");
                checked += 1;
            }
            at_the_cutoff += usize::from(alpha > 0.0 && alpha < 1.0);
        }
        assert!(checked == 16_000 && at_the_cutoff > 2000, "{at_the_cutoff}");
    }
}
