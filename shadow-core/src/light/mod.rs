//! World-space light views for map-based techniques: a spot light is one perspective view, a directional
//! light one orthographic view fitted to the scene, a point light six 90-degree cube faces. Near and far
//! planes are fitted to the scene's instance bounds (McCool 6.1: the tighter the range, the better the
//! depth precision).
//!
//! Shadow-map lookup (DESIGN 4), written once here and mirrored in WGSL: a world point projects to light
//! NDC; `uv = (x * 0.5 + 0.5, 0.5 - y * 0.5)`; texel `i` of an `N`-texel side is centred at `(i + 0.5) / N`;
//! the point is lit when its depth minus the bias is at most the stored depth.
//!
//! A map-based technique may render other projections than the fitted ones, made for the camera's view:
//! cascades ([`cascades`]), a light-space perspective ([`lispsm`]) or the camera's post-perspective space
//! ([`psm`]), the last two fitted to the part of the view the scene fills ([`focus`]). The view it renders then says how a receiver picks its projection
//! ([`LightView::projection_index`]).

pub mod atlas;
pub mod cascades;
pub mod focus;
pub mod lispsm;
pub mod psm;
pub mod reach;

use glam::camera::rh::proj::directx;
use glam::camera::rh::view::look_to_mat4;
use glam::{Mat4, Vec2, Vec3, Vec3Swizzles, Vec4, Vec4Swizzles};

use crate::bounds::Aabb;
use crate::geometry::LightSource;
use crate::scene::{Light, LightKind, SceneError};
pub use atlas::{AtlasPlan, LightTiles, TileRequest};
pub use cascades::{CascadeFit, CascadePick, Cascades, Stabilize};
pub use reach::{PixelRect, Reach};

/// Why a light view could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LightViewError {
    /// The light's own parameters are unusable.
    #[error(transparent)]
    Invalid(#[from] SceneError),
    /// There is nothing to fit the view to.
    #[error("the scene is empty: no bounds to fit the light view to")]
    EmptyScene,
}

/// One projection of a light view: world to clip, and the fitted depth range.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightProjection {
    /// World to light view (right-handed, looking down -Z).
    pub view_from_world: Mat4,
    /// Light view to clip, depth 0..1.
    pub clip_from_view: Mat4,
    /// World to clip.
    pub clip_from_world: Mat4,
    /// Takes a world-space plane `(n, d)` to the same plane in clip space (the inverse transpose of
    /// `clip_from_world`), for [`LightProjection::depth_gradient`].
    pub clip_plane_from_world_plane: Mat4,
    /// Near plane distance.
    pub near: f32,
    /// Far plane distance.
    pub far: f32,
    /// Orthographic (directional light) rather than perspective.
    pub orthographic: bool,
}

impl LightProjection {
    fn new(view_from_world: Mat4, clip_from_view: Mat4, near: f32, far: f32, orthographic: bool) -> Self {
        Self {
            view_from_world,
            clip_from_view,
            clip_from_world: clip_from_view * view_from_world,
            clip_plane_from_world_plane: (clip_from_view * view_from_world).inverse().transpose(),
            near,
            far,
            orthographic,
        }
    }

    /// Whether part of box `b` may lie in this projection's frustum: false only where it lies wholly
    /// outside one of its planes, so that none of its triangles is drawn into the map (casters so culled
    /// change no texel).
    #[must_use]
    pub fn may_hold(&self, b: Aabb) -> bool {
        !b.is_empty() && frustum_may_hold(self.clip_from_world, b)
    }

    /// Light NDC of a world point (x, y in [-1, 1] inside the view, z depth in [0, 1]).
    #[must_use]
    pub fn ndc(&self, p: Vec3) -> Vec3 {
        self.clip_from_world.project_point3(p)
    }

    /// Map coordinates and depth of a world point: `uv` with (0, 0) at the top-left of the map.
    #[must_use]
    #[inline]
    pub fn uv_depth(&self, p: Vec3) -> (Vec2, f32) {
        let c = self.clip_from_world * p.extend(1.0);
        let ndc = c.xyz() / c.w;
        (ndc_to_uv(ndc.xy()), ndc.z)
    }

    /// How the NDC depth of the plane through `p` with normal `n` changes with map coordinates: the
    /// receiver plane's `(dz/du, dz/dv)`. NDC depth is affine in `uv` over a plane (that is why
    /// rasterizers interpolate it linearly), so `depth + gradient . (uv' - uv)` is the plane's depth at
    /// `uv'` exactly. Zero for a plane seen edge-on from the light (a gradient over about 1e6 per unit of
    /// uv, where rounding decides the sign: such a plane's depth says nothing about its neighbours).
    /// WGSL twin: `depth_gradient` in shadow_map.wgsl.
    #[must_use]
    pub fn depth_gradient(&self, p: Vec3, n: Vec3) -> Vec2 {
        // The plane a x + b y + c z + d = 0 in NDC: z = -(a x + b y + d) / c, with x = 2u - 1, y = 1 - 2v.
        let c = self.clip_plane_from_world_plane * n.extend(-n.dot(p));
        if c.z.abs() <= 1e-6 * (c.x.abs() + c.y.abs()) {
            return Vec2::ZERO;
        }
        Vec2::new(-2.0 * c.x / c.z, 2.0 * c.y / c.z)
    }

    /// The world point at map coordinates `uv` and NDC depth `depth` (McCool's back-projection).
    #[must_use]
    pub fn world_from_uv_depth(&self, uv: Vec2, depth: f32) -> Vec3 {
        let ndc = Vec3::new(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0, depth);
        self.clip_from_world.inverse().project_point3(ndc)
    }

    /// NDC depth of a distance along the view axis (the inverse of [`LightProjection::linear_depth`]).
    #[must_use]
    pub fn ndc_depth(&self, linear: f32) -> f32 {
        if self.orthographic {
            (linear - self.near) / (self.far - self.near)
        } else {
            self.far * (linear - self.near) / (linear * (self.far - self.near))
        }
    }

    /// Distance along the view axis for an NDC depth.
    #[must_use]
    pub fn linear_depth(&self, depth: f32) -> f32 {
        if self.orthographic {
            self.near + depth * (self.far - self.near)
        } else {
            // directx::perspective: z_ndc = far (d - near) / (d (far - near)).
            self.near * self.far / (self.far - depth * (self.far - self.near))
        }
    }
}

/// Light NDC x, y to map coordinates (DESIGN 4).
#[must_use]
pub fn ndc_to_uv(ndc: Vec2) -> Vec2 {
    Vec2::new(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5)
}

/// A light with its fitted projections.
#[derive(Clone, Debug, PartialEq)]
pub struct LightView {
    /// The light.
    pub light: Light,
    /// One projection (a spot light's perspective view, a directional light's orthographic one), or a
    /// point light's six cube faces in the order +X, -X, +Y, -Y, +Z, -Z.
    pub projections: Vec<LightProjection>,
    /// When the projections are cascades over a camera's view: how a receiver's view depth picks one.
    pub cascades: Option<Cascades>,
}

/// Look direction and up vector of the six cube faces, in the order of [`LightView::projections`].
pub const CUBE_FACES: [(Vec3, Vec3); 6] = [
    (Vec3::X, Vec3::NEG_Y),
    (Vec3::NEG_X, Vec3::NEG_Y),
    (Vec3::Y, Vec3::Z),
    (Vec3::NEG_Y, Vec3::NEG_Z),
    (Vec3::Z, Vec3::NEG_Y),
    (Vec3::NEG_Z, Vec3::NEG_Y),
];

/// The cube face whose frustum holds direction `d` (its major axis; ties go to the lower face index).
#[must_use]
pub fn cube_face(d: Vec3) -> usize {
    let a = d.abs();
    if a.x >= a.y && a.x >= a.z {
        if d.x >= 0.0 { 0 } else { 1 }
    } else if a.y >= a.z {
        if d.y >= 0.0 { 2 } else { 3 }
    } else if d.z >= 0.0 {
        4
    } else {
        5
    }
}

/// The near and far planes of an orthographic view whose casters lie between distances `lo` and `hi`
/// along the light (padded already): the casters fill the far half of the depth range, [0.5, 1].
///
/// The map's constant bias is counted in f32 steps of the depth it offsets (Vulkan's rule, DESIGN 4), but
/// a depth is computed as a sum of terms, `clip_from_world`'s row times the world point, which are as
/// large as the point's offset along the light over the depth range. In a range fitted tight, a caster
/// on the near side (a roof or a card squarely facing an overhead sun) has a depth near 0 whose f32 step
/// is a hundred times finer than the rounding of those terms: its receivers' depths then come out
/// rounded above its stored depth in bands across it, and nothing else covers that, since a surface
/// facing the light has no depth slope and so no slope bias. On [0.5, 1] every depth has the same f32
/// step, that of the terms for a scene whose extent along the light reaches the origin, so the four
/// steps of the default constant bias settle those ties everywhere. The price is one bit of depth
/// resolution, far below any bias.
pub(crate) fn orthographic_range(lo: f32, hi: f32) -> (f32, f32) {
    (lo - (hi - lo), hi)
}

fn safe_up(dir: Vec3) -> Vec3 {
    if dir.cross(Vec3::Y).length_squared() < 1e-6 { Vec3::Z } else { Vec3::Y }
}

/// Fitted near and far for a perspective view from `eye` along `dir`: far is the deepest box corner; near the
/// shallowest (depth along the axis is linear over a box, so its extremes are at corners), at least
/// far / 2000, and that floor wherever a box reaches behind the eye's plane. A near plane set from the
/// Euclidean distance to the closest box instead clips geometry seen off-axis, since depth is distance
/// times the cosine of the angle off the axis: on `room`, the beam near a point light vanished from a cube
/// face that way.
fn perspective_range(eye: Vec3, dir: Vec3, boxes: &[Aabb]) -> (f32, f32) {
    let depths = |b: &Aabb| b.corners().map(|c| (c - eye).dot(dir));
    let far = boxes.iter().flat_map(depths).fold(0.0f32, f32::max);
    let far = (far * 1.01).max(1e-3);
    let floor = far / 2000.0;
    let shallowest = boxes
        .iter()
        .map(|b| depths(b).into_iter().fold(f32::INFINITY, f32::min))
        .filter(|&d| d < far)
        .fold(f32::INFINITY, f32::min);
    let near = (shallowest * 0.99).clamp(floor, far * 0.5);
    (near, far)
}

/// Whether part of box `b` may lie in the frustum of `clip_from_world` (x and y within w, depth within
/// [0, w]): false only where all its corners lie beyond one plane, by a ten-thousandth of the clip volume
/// against rounding. Each plane is a plane of world space, so the test holds behind the eye too.
fn frustum_may_hold(clip_from_world: Mat4, b: Aabb) -> bool {
    let clip = b.corners().map(|c| clip_from_world * c.extend(1.0));
    let planes: [fn(Vec4) -> f32; 6] =
        [|c| c.w + c.x, |c| c.w - c.x, |c| c.w + c.y, |c| c.w - c.y, |c| c.z, |c| c.w - c.z];
    !planes.iter().any(|inside| clip.iter().all(|&c| inside(c) < -1e-4 * c.w.abs()))
}

impl LightView {
    /// Fits the light's projections to the given world-space boxes (one per instance keeps it tight).
    ///
    /// # Errors
    /// An invalid light, or no non-empty box.
    pub fn fit(light: &Light, boxes: &[Aabb]) -> Result<Self, LightViewError> {
        light.validate()?;
        let boxes: Vec<Aabb> = boxes.iter().copied().filter(|b| !b.is_empty()).collect();
        if boxes.is_empty() {
            return Err(LightViewError::EmptyScene);
        }
        let projections = match light.kind {
            LightKind::Spot { position, direction, cone_angle } => {
                let dir = direction.normalize();
                let (near, far) = perspective_range(position, dir, &boxes);
                let view = look_to_mat4(position, dir, safe_up(dir));
                let proj = directx::perspective(cone_angle, 1.0, near, far);
                vec![LightProjection::new(view, proj, near, far, false)]
            }
            LightKind::Directional { direction } => {
                let dir = direction.normalize();
                let all = boxes.iter().fold(Aabb::EMPTY, |a, b| a.union(*b));
                let center = all.center();
                let radius = all.size().length() * 0.5 + 1e-3;
                let view = look_to_mat4(center - dir * (radius * 2.0), dir, safe_up(dir));
                let in_view = all.transformed(view);
                // Square texels: the larger extent on both axes, centred.
                let half = (in_view.max.xy() - in_view.min.xy()).max_element() * 0.5 * 1.01;
                let mid = in_view.center().xy();
                let (near, far) = (-in_view.max.z, -in_view.min.z);
                let pad = (far - near) * 0.01 + 1e-4;
                let (near, far) = orthographic_range(near - pad, far + pad);
                let proj = directx::orthographic(mid.x - half, mid.x + half, mid.y - half, mid.y + half, near, far);
                vec![LightProjection::new(view, proj, near, far, true)]
            }
            LightKind::Point { position } => CUBE_FACES
                .iter()
                .map(|&(dir, up)| {
                    let (near, far) = perspective_range(position, dir, &boxes);
                    let view = look_to_mat4(position, dir, up);
                    let proj = directx::perspective(std::f32::consts::FRAC_PI_2, 1.0, near, far);
                    LightProjection::new(view, proj, near, far, false)
                })
                .collect(),
        };
        Ok(Self { light: *light, projections, cascades: None })
    }

    /// The same view with a point light's six cube faces widened so that an `n x n` map's outermost
    /// sample centres lie exactly on the 90-degree face boundaries: neighbouring faces then sample the
    /// same rays along their shared edge, and surfaces reconstructed from their maps meet there without
    /// cracks (McCool section 5, Fig. 6: overlapping partitions). Other lights are returned unchanged.
    #[must_use]
    pub fn with_seamless_faces(&self, n: u32) -> Self {
        let LightKind::Point { position } = self.light.kind else { return self.clone() };
        // Sample i sits at NDC -1 + (2i + 1) / n; the outermost ones at tan(half fov) (1 - 1/n) = 1.
        let fov = 2.0 * (n as f32 / (n.max(2) - 1) as f32).atan();
        let projections = CUBE_FACES
            .iter()
            .zip(&self.projections)
            .map(|(&(dir, up), p)| {
                let view = look_to_mat4(position, dir, up);
                LightProjection::new(view, directx::perspective(fov, 1.0, p.near, p.far), p.near, p.far, false)
            })
            .collect();
        Self { projections, ..self.clone() }
    }

    /// Whether part of `bounds` may lie in one of the light's views: false only for a box that lies wholly
    /// outside every projection's frustum, whose triangles no pass drawn in the light's views rasterizes.
    #[must_use]
    pub fn sees(&self, bounds: Aabb) -> bool {
        !bounds.is_empty() && self.projections.iter().any(|p| frustum_may_hold(p.clip_from_world, bounds))
    }

    /// The light as the geometry kernels take it, in world space.
    #[must_use]
    pub fn source(&self) -> LightSource {
        match self.light.kind {
            LightKind::Spot { position, .. } | LightKind::Point { position } => LightSource::Point(position),
            LightKind::Directional { direction } => LightSource::Directional(direction.normalize()),
        }
    }

    /// Index of the projection that covers world point `p`: the cube face for point lights, the cascade of
    /// its view depth for cascades (without their blending: see [`LightView::cascade_pick`]).
    #[must_use]
    #[inline]
    pub fn projection_index(&self, p: Vec3) -> usize {
        if let Some(c) = &self.cascades {
            return c.pick(c.depth(p)).cascade;
        }
        match self.light.kind {
            LightKind::Point { position } => cube_face(p - position),
            _ => 0,
        }
    }

    /// For cascades, the cascade `p` reads and the next one it fades into.
    #[must_use]
    #[inline]
    pub fn cascade_pick(&self, p: Vec3) -> Option<CascadePick> {
        self.cascades.as_ref().map(|c| c.pick(c.depth(p)))
    }

    /// True where the light can reach at all: inside a spot light's cone and within a light's range.
    /// Metrics leave the rest out: no technique has anything to say there (a frame does not even ask, see
    /// [`Reach`]).
    #[must_use]
    pub fn in_domain(&self, p: Vec3) -> bool {
        let within_range = match (self.light.range, self.light.position()) {
            (Some(range), Some(position)) => (p - position).length() < range,
            _ => true,
        };
        within_range
            && match self.light.kind {
                LightKind::Spot { position, direction, cone_angle } => {
                    let d = (p - position).normalize_or_zero();
                    d.dot(direction.normalize()) >= (cone_angle * 0.5).cos()
                }
                _ => true,
            }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn boxes() -> Vec<Aabb> {
        vec![
            Aabb::new(Vec3::new(-5.0, -0.01, -5.0), Vec3::new(5.0, 0.0, 5.0)),
            Aabb::new(Vec3::splat(-0.5), Vec3::splat(0.5)),
        ]
    }

    #[test]
    fn spot_projects_its_target_to_the_map_centre() {
        let v = LightView::fit(&Light::spot(Vec3::new(2.0, 4.0, 1.5), Vec3::ZERO, 60.0), &boxes()).unwrap();
        let (uv, depth) = v.projections[0].uv_depth(Vec3::ZERO);
        assert!((uv - Vec2::splat(0.5)).length() < 1e-5);
        assert!(depth > 0.0 && depth < 1.0);
        let back = v.projections[0].world_from_uv_depth(uv, depth);
        assert!(back.length() < 1e-3);
        let p = &v.projections[0];
        assert!((p.linear_depth(depth) - Vec3::new(2.0, 4.0, 1.5).length()).abs() < 1e-3);
        assert!((p.ndc_depth(p.linear_depth(0.37)) - 0.37).abs() < 1e-5);
    }

    #[test]
    fn depth_gradient_extrapolates_along_the_plane() {
        for light in
            [Light::spot(Vec3::new(2.0, 4.0, 1.5), Vec3::ZERO, 60.0), Light::directional(Vec3::new(0.3, -1.0, 0.2))]
        {
            let v = LightView::fit(&light, &boxes()).unwrap();
            let proj = &v.projections[0];
            let (p, n) = (Vec3::new(0.1, 0.2, -0.3), Vec3::new(0.3, 0.9, -0.2).normalize());
            let t = n.cross(Vec3::X).normalize();
            let q = p + t * 0.05 + n.cross(t) * 0.03;
            let ((up, zp), (uq, zq)) = (proj.uv_depth(p), proj.uv_depth(q));
            let g = proj.depth_gradient(p, n);
            assert!((zp + g.dot(uq - up) - zq).abs() < 1e-5, "{light:?}: {} vs {zq}", zp + g.dot(uq - up));
            // A plane seen edge-on has no gradient.
            let along = match light.kind {
                LightKind::Directional { direction } => direction,
                _ => p - Vec3::new(2.0, 4.0, 1.5),
            };
            assert_eq!(proj.depth_gradient(p, along.cross(Vec3::Y).normalize()), Vec2::ZERO);
        }
    }

    #[test]
    fn directional_view_holds_the_scene() {
        let v = LightView::fit(&Light::directional(Vec3::new(0.3, -1.0, 0.2)), &boxes()).unwrap();
        for c in boxes().iter().flat_map(|b| b.corners()) {
            let ndc = v.projections[0].ndc(c);
            assert!(ndc.x.abs() <= 1.0 && ndc.y.abs() <= 1.0 && (0.0..=1.0).contains(&ndc.z), "{c} -> {ndc}");
        }
    }

    #[test]
    fn near_planes_keep_off_axis_geometry() {
        // A box close to the light but well off the +Z axis: its shallowest depth along +Z is 0.8, less
        // than its distance to the light (1.11). The near plane must not clip it.
        let boxes = [
            Aabb::new(Vec3::new(-0.7, 2.375, 0.8), Vec3::new(0.7, 2.625, 1.7)),
            Aabb::new(Vec3::new(-3.0, 0.0, -3.0), Vec3::new(3.0, 0.0, 4.0)),
        ];
        let v = LightView::fit(&Light::point(Vec3::new(0.0, 3.4, 0.0)), &boxes).unwrap();
        for c in boxes[0].corners() {
            let p = &v.projections[v.projection_index(c)];
            assert!(p.ndc(c).z >= 0.0, "corner {c} clipped by the near plane of its face");
        }
    }

    #[test]
    fn cube_faces_cover_their_directions() {
        let v = LightView::fit(&Light::point(Vec3::new(0.0, 2.0, 0.0)), &boxes()).unwrap();
        // Points on the ground, seen through every lower face and the side faces.
        for p in [
            Vec3::new(4.0, 0.0, 0.1),
            Vec3::new(0.3, 0.0, 0.1),
            Vec3::new(-4.5, 0.0, 2.0),
            Vec3::new(1.0, 0.0, -4.9),
            Vec3::new(-2.0, 0.0, 4.0),
        ] {
            let d = p - Vec3::new(0.0, 2.0, 0.0);
            let ndc = v.projections[v.projection_index(p)].ndc(p);
            assert!(ndc.x.abs() <= 1.0 && ndc.y.abs() <= 1.0 && ndc.z > 0.0, "{d} -> {ndc}");
        }
    }
}
