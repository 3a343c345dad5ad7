//! Cones and sheets (Wyman and Hansen 2003), shared by both backends: from the casters' silhouette edges
//! (shadow-core's extraction) to world-space triangles that bound, seen from the light's centre, the
//! outer penumbra of a spherical light of radius `r`.
//!
//! The rays from the light's rim through a silhouette vertex `v` at distance `z_v` form a cone with apex
//! `v`, opening away from the light, whose radius at distance `s` past `v` is `r s / z_v`. Along a
//! silhouette edge the cones of its ends are joined by a sheet made of the two generators that point
//! outward, perpendicular to the edge and to the rays. Where a receiver lies inside the cone or under the
//! sheet, it is in the penumbra; how far in is what the penumbra map stores.
//!
//! Every vertex carries the linear depth (along the light's axis) of the silhouette vertex it hangs from,
//! which the map's pass interpolates across a sheet.

use shadow_core::FrameInputs;
use shadow_core::geometry::silhouette::Silhouette;
use shadow_core::glam::{Vec3, Vec4};
use shadow_core::light::LightProjection;

/// The largest angle one step of a cone spans (Wyman and Hansen tessellate cones; the thesis notes they
/// must be fine enough for smooth corners).
const CONE_STEP: f32 = std::f32::consts::PI / 12.0;

/// One triangle of a cone or sheet: world-space corners and, per corner, the linear depth of its
/// silhouette vertex.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PenumbraTriangle {
    /// World-space corners.
    pub corners: [Vec3; 3],
    /// Linear depth of the silhouette vertex each corner hangs from.
    pub vertex_depth: [f32; 3],
}

/// The cones and sheets of one light, and what was built.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ConesAndSheets {
    /// Sheets, then cones.
    pub triangles: Vec<PenumbraTriangle>,
    /// Silhouette edges (each gives a sheet).
    pub edges: usize,
    /// Silhouette vertices that are not the meeting of exactly two edges: they get a whole cone, the
    /// others only the sector between their edges' sheets.
    pub whole_cones: usize,
}

/// A silhouette edge's sheet data at one of its ends.
#[derive(Clone, Copy, Debug)]
struct SheetEnd {
    outward: Vec3,
}

/// Builds the cones and sheets of the casters' `silhouettes` for a spot light at `light` of radius
/// `radius`, in its projection `proj`.
///
/// An edge's outward side comes from its orientation, as for smoothies: the blocker lies to the left of
/// an edge in the light's view (to its right in a mirrored instance).
#[must_use]
pub fn build(
    frame: &FrameInputs,
    silhouettes: &[(usize, Silhouette)],
    light: Vec3,
    radius: f32,
    proj: &LightProjection,
) -> ConesAndSheets {
    let mut out = ConesAndSheets::default();
    let axis_depth = |p: Vec3| -proj.view_from_world.transform_point3(p).z;
    // Generators run out to the far plane and beyond; the rasterizer clips them there.
    let reach = proj.far * 2.0;
    let generator = |v: Vec3, outward: Vec3| {
        let to = v - light;
        let z = to.length();
        v + (to / z + outward * (radius / z)) * reach
    };
    for (i, silhouette) in silhouettes {
        let inst = &frame.instances[*i];
        let world = |v: u32| inst.world_from_local.transform_point3(inst.adjacency.positions()[v as usize]);
        let mut at_vertex: std::collections::HashMap<u32, Vec<SheetEnd>> = std::collections::HashMap::new();
        for e in &silhouette.edges {
            let (a, b) = (world(e.a), world(e.b));
            if axis_depth(a) <= proj.near || axis_depth(b) <= proj.near {
                continue;
            }
            // Perpendicular to the edge and to both ends' rays; to the edge's right seen from the light.
            let Some(right) = (a - light).cross(b - a).try_normalize() else { continue };
            let outward = if inst.mirrored { -right } else { right };
            let (za, zb) = (axis_depth(a), axis_depth(b));
            let (fa, fb) = (generator(a, outward), generator(b, outward));
            out.triangles.push(PenumbraTriangle { corners: [a, b, fb], vertex_depth: [za, zb, zb] });
            out.triangles.push(PenumbraTriangle { corners: [a, fb, fa], vertex_depth: [za, zb, za] });
            out.edges += 1;
            at_vertex.entry(e.a).or_default().push(SheetEnd { outward });
            at_vertex.entry(e.b).or_default().push(SheetEnd { outward });
        }
        for (v, ends) in &at_vertex {
            let p = world(*v);
            let ray = (p - light).normalize();
            let (start, sweep) = match ends.as_slice() {
                // The sector between the two sheets, the smaller way round about the ray: outside a convex
                // corner; inside a concave one it lies under the sheets, whose lower values win.
                [e0, e1] => (e0.outward, e0.outward.cross(e1.outward).dot(ray).atan2(e0.outward.dot(e1.outward))),
                _ => {
                    out.whole_cones += 1;
                    (ends[0].outward, std::f32::consts::TAU)
                }
            };
            push_cone(&mut out.triangles, p, axis_depth(p), ray, start, sweep, |d| generator(p, d));
        }
    }
    out
}

/// The cone at silhouette vertex `apex` (linear depth `depth`) from the generator direction `start`
/// (perpendicular to `ray`) turned by `sweep` about the ray, in steps of at most [`CONE_STEP`].
fn push_cone(
    out: &mut Vec<PenumbraTriangle>,
    apex: Vec3,
    depth: f32,
    ray: Vec3,
    start: Vec3,
    sweep: f32,
    generator: impl Fn(Vec3) -> Vec3,
) {
    let steps = (sweep.abs() / CONE_STEP).ceil().max(1.0) as usize;
    let turn = |k: usize| {
        let (s, c) = (sweep * k as f32 / steps as f32).sin_cos();
        generator(start * c + ray.cross(start) * s)
    };
    for k in 0..steps {
        out.push(PenumbraTriangle { corners: [apex, turn(k), turn(k + 1)], vertex_depth: [depth; 3] });
    }
}

/// The triangles in the projection's clip space, for a rasterizer.
#[must_use]
pub fn clip_space(triangles: &[PenumbraTriangle], proj: &LightProjection) -> Vec<[Vec4; 3]> {
    triangles.iter().map(|t| t.corners.map(|c| proj.clip_from_world * c.extend(1.0))).collect()
}

#[cfg(test)]
mod tests {
    use shadow_core::glam::Mat4;
    use shadow_core::procedural;
    use shadow_core::scene::{Camera, Light, Material, Scene};

    use super::*;

    /// One unit cube on the origin under a spot light of radius 0.2 at height 4.
    fn frame() -> FrameInputs {
        let mut scene = Scene::new();
        let mesh = scene.add_mesh(procedural::cuboid(Vec3::splat(1.0)).expect("shape"));
        let material = scene.add_material(Material::colored("grey", Vec3::splat(0.5)));
        scene.add_instance("caster", mesh, material, Mat4::IDENTITY).unwrap();
        let camera = scene.add_camera(Camera::look_at(Vec3::new(0.0, 3.0, 4.0), Vec3::ZERO, 45.0));
        let mut light = Light::spot(Vec3::new(0.0, 4.0, 0.0), Vec3::ZERO, 60.0);
        light.radius = 0.2;
        scene.add_light(light);
        FrameInputs::from_scene(&scene, camera).unwrap()
    }

    #[test]
    fn sheets_and_cones_bound_the_outer_penumbra() {
        let frame = frame();
        let view = frame.light_view(&frame.lights[0]).unwrap();
        let proj = &view.projections[0];
        let light = Vec3::new(0.0, 4.0, 0.0);
        let built = build(&frame, &frame.caster_silhouettes(&view), light, 0.2, proj);
        // The top face's outline: four edges, four convex corners with a sector each.
        assert_eq!((built.edges, built.whole_cones), (4, 0));
        // Each sheet opens outward at the rate the light's rim sets: a point on it at distance s past the
        // edge along the ray lies r s / z_v out from the ray through the edge.
        let centre = proj.uv_depth(Vec3::ZERO).0;
        for (k, t) in built.triangles[..8].iter().enumerate() {
            // [a, b, b's generator] then [a, b's generator, a's generator].
            let (a, far) = if k % 2 == 0 { (t.corners[1], t.corners[2]) } else { (t.corners[0], t.corners[2]) };
            let z = (a - light).length();
            let along = (far - a).dot((a - light) / z);
            let out = ((far - a) - (a - light) / z * along).length();
            assert!((out / along - 0.2 / z).abs() < 1e-4, "opening {} vs {}", out / along, 0.2 / z);
            let away = proj.uv_depth(a.lerp(far, 1e-3)).0 - proj.uv_depth(a).0;
            assert!(away.dot(proj.uv_depth(a).0 - centre) > 0.0, "a sheet opens inward");
        }
        // The corners' sectors turn a quarter turn each, on the outside.
        for t in &built.triangles[8..] {
            let apex = proj.uv_depth(t.corners[0]).0;
            let mid = proj.uv_depth(t.corners[0].lerp((t.corners[1] + t.corners[2]) * 0.5, 1e-3)).0;
            assert!((mid - apex).dot(apex - centre) > 0.0, "a cone sector turns inward");
        }
        let sector_steps = built.triangles.len() - 8;
        assert_eq!(sector_steps, 4 * 6, "a quarter turn in steps of pi/12");
    }
}
