//! The built-in scenes of DESIGN 7: the papers' test scenes, built procedurally so nothing is downloaded.
//!
//! Each has a default camera and light (those of many objects a second light); [`SceneParams`] swaps the
//! light type and seeds the random placement (the same seed always gives the same scene). [`stage_model`]
//! puts a loaded model on a ground plane with the default spotlight and camera of DESIGN 11.

pub mod animated;
mod builders;
pub mod cutouts;
pub mod walker;

use glam::{Mat4, Vec3};

use crate::mesh::Mesh;
use crate::procedural;
use crate::scene::{Camera, CameraKey, Light, LightKey, LightKind, Material, Scene};

/// Options for building a scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneParams {
    /// Replace the default light with one of this type, placed where the default one is.
    pub light: Option<LightType>,
    /// Seed for random placement.
    pub seed: u64,
}

impl Default for SceneParams {
    fn default() -> Self {
        Self { light: None, seed: 1 }
    }
}

crate::named_enum! {
    /// A light type, by name.
    pub enum LightType {
        /// A spot light.
        Spot = "spot",
        /// A directional light.
        Directional = "directional",
        /// A point light.
        Point = "point",
    }
}

/// A built-in scene.
#[derive(Clone, Copy)]
pub struct SceneInfo {
    /// Its name.
    pub name: &'static str,
    /// After which paper figure.
    pub after: &'static str,
    /// What it holds and tests.
    pub description: &'static str,
    build: fn(&SceneParams) -> Scene,
}

/// Every built-in scene.
pub const ALL: &[SceneInfo] = &[
    SceneInfo {
        name: "cylinder",
        after: "Chan Fig. 3-4, 4-8",
        description: "a cylinder standing on a ground plane, spotlight",
        build: builders::cylinder,
    },
    SceneInfo {
        name: "primitives",
        after: "Chan Fig. 4-1d",
        description: "box, cylinder, sphere and torus on a plane",
        build: builders::primitives,
    },
    SceneInfo {
        name: "stacked-boxes",
        after: "Chan Fig. 4-10",
        description: "a floating box over a box on the ground: one shadow across two receivers",
        build: builders::stacked_boxes,
    },
    SceneInfo {
        name: "l-shape",
        after: "Weiskopf Fig. 5",
        description: "an L-shaped solid above a surface, directional light from above",
        build: builders::l_shape,
    },
    SceneInfo {
        name: "double-torus",
        after: "Weiskopf Fig. 6",
        description: "a genus-2 solid over a plane",
        build: builders::double_torus,
    },
    SceneInfo {
        name: "strike",
        after: "Sen Fig. 9",
        description: "ten bowling pins and a ball on a lane",
        build: builders::strike,
    },
    SceneInfo {
        name: "crowd",
        after: "Sen CROWD",
        description: "24 figures in front of a distant wall",
        build: builders::crowd,
    },
    SceneInfo {
        name: "cubes",
        after: "Chan Cubes",
        description: "a thousand cubes casting heavily overlapping shadows",
        build: builders::cubes,
    },
    SceneInfo {
        name: "cage",
        after: "Chan Dragon Cage",
        description: "the bars of a cage around a dense blob",
        build: builders::cage,
    },
    SceneInfo {
        name: "tree",
        after: "Chan Tree",
        description: "a branching tree with thin branches",
        build: builders::tree,
    },
    SceneInfo {
        name: "room",
        after: "Everitt-Kilgard, McCool 6.2",
        description: "the camera inside a shadow, an occluder crossing the near plane",
        build: builders::room,
    },
];

/// The outdoor scenes, for perspective aliasing: one ground of 200 x 200 m under a low sun, seen from head
/// height, with the sun beside the view, behind the camera, and facing it (the duelling frusta). They are
/// apart from [`ALL`], the papers' small scenes that the conformance loops hold to their bounds.
pub const OUTDOOR: &[SceneInfo] = &[
    SceneInfo {
        name: "outdoor",
        after: "Nealen Fig. 10",
        description: "a 200 x 200 m street of buildings, trees, poles and fences at head height, low sun beside the view",
        build: builders::outdoor,
    },
    SceneInfo {
        name: "outdoor-behind",
        after: "Stamminger-Drettakis",
        description: "the outdoor street with the sun behind the camera",
        build: builders::outdoor_behind,
    },
    SceneInfo {
        name: "outdoor-facing",
        after: "Stamminger-Drettakis",
        description: "the outdoor street with the sun facing the camera (the duelling frusta)",
        build: builders::outdoor_facing,
    },
];

/// The scenes of alpha-tested casters (glTF `MASK`), whose textures cut their cards out: the light passes
/// must discard clear texels, and the references test them. Apart from [`ALL`], as the techniques that
/// extrude silhouettes leave them out.
pub const CUTOUT: &[SceneInfo] = &[
    SceneInfo {
        name: "cutout",
        after: "alpha testing",
        description: "a checkerboard card cut out by its alpha under a sun straight above: half its shadow is lit",
        build: cutouts::cutout,
    },
    SceneInfo {
        name: "foliage",
        after: "Chan Tree, in leaves",
        description: "a tree of 2916 alpha-masked leaf cards on bare branches, spotlight",
        build: cutouts::foliage,
    },
    SceneInfo {
        name: "fence",
        after: "Nealen Fig. 10, fenced",
        description: "picket-fence cards along a 200 m street at head height, low sun across it",
        build: cutouts::fence,
    },
];

/// The animated scenes: casters that move over a clip ([`crate::Scene::pose`]). Apart from [`ALL`], as
/// they are measured at several times of their clips.
pub const ANIMATED: &[SceneInfo] = &[
    SceneInfo {
        name: "mill",
        after: "node animation",
        description: "a wind mill's three-bladed rotor turning under a sun, its shadow sweeping the tower and the ground",
        build: animated::mill,
    },
    SceneInfo {
        name: "walker",
        after: "skinning",
        description: "a skinned figure of eleven joints walking through a spot light's cone between a ground and a wall",
        build: walker::walker,
    },
];

/// The scenes of many objects: a few meshes placed thousands of times, which a backend keeps once and
/// draws as instances. Apart from [`ALL`], as their worth is measured against the same scene with every
/// mesh copied ([`crate::Scene::unshare_meshes`]).
pub const MANY: &[SceneInfo] = &[SceneInfo {
    name: "props",
    after: "instancing",
    description: "3000 rocks, crates and posts, instances of three meshes, on a field under a sun and a spot light",
    build: builders::props,
}];

/// The scenes of many lights, each light reaching part of the scene, for measuring how a frame grows
/// with its lights (`bench --lights N` keeps the first N).
pub const LIGHTS: &[SceneInfo] = &[SceneInfo {
    name: "yard",
    after: "many lights",
    description: "480 crates, posts and rocks under 64 spot and point lights of three ranges; the camera sees part of them",
    build: builders::yard,
}];

/// Every built-in scene: the papers' ([`ALL`]), the outdoor ones ([`OUTDOOR`]), those of cutouts
/// ([`CUTOUT`]), the animated ones ([`ANIMATED`]), those of many objects ([`MANY`]), then those of many
/// lights ([`LIGHTS`]).
pub fn every() -> impl Iterator<Item = &'static SceneInfo> {
    ALL.iter().chain(OUTDOOR).chain(CUTOUT).chain(ANIMATED).chain(MANY).chain(LIGHTS)
}

/// Why a scene could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("unknown scene '{0}' (built-in scenes: {names})", names = every().map(|s| s.name).collect::<Vec<_>>().join(", "))]
pub struct UnknownScene(pub String);

/// Names of the papers' scenes ([`ALL`]).
#[must_use]
pub fn names() -> Vec<&'static str> {
    ALL.iter().map(|s| s.name).collect()
}

/// The description of a built-in scene (of [`every`]).
#[must_use]
pub fn info(name: &str) -> Option<&'static SceneInfo> {
    every().find(|s| s.name == name)
}

/// Builds a built-in scene: its meshes, one camera and one light.
///
/// # Errors
/// [`UnknownScene`] for a name not in [`every`].
pub fn build(name: &str, params: &SceneParams) -> Result<Scene, UnknownScene> {
    let info = info(name).ok_or_else(|| UnknownScene(name.into()))?;
    let mut scene = (info.build)(params);
    if let Some(t) = params.light {
        retype_lights(&mut scene, t);
    }
    Ok(scene)
}

/// Replaces every light with one of type `t` placed and aimed like it.
pub fn retype_lights(scene: &mut Scene, t: LightType) {
    let target = scene.bounds().center();
    let lights: Vec<Light> = scene.lights().map(|(_, l)| l).collect();
    scene.clear_lights();
    for l in lights {
        let (position, direction) = match l.kind {
            LightKind::Spot { position, direction, .. } => (position, direction),
            LightKind::Point { position } => (position, (target - position).normalize_or(Vec3::NEG_Y)),
            LightKind::Directional { direction } => {
                (target - direction * scene.bounds().size().length().max(1.0) * 1.5, direction)
            }
        };
        let cone_angle = match l.kind {
            LightKind::Spot { cone_angle, .. } => cone_angle,
            _ => 60f32.to_radians(),
        };
        let kind = match t {
            LightType::Spot => LightKind::Spot { position, direction, cone_angle },
            LightType::Directional => LightKind::Directional { direction },
            LightType::Point => LightKind::Point { position },
        };
        scene.add_light(Light { kind, ..l });
    }
}

/// A shape of the built-in scenes, whose parameters are this module's own constants: a failure is a bug
/// here, not bad input.
pub(crate) fn built(shape: Result<Mesh, procedural::ShapeError>) -> Mesh {
    shape.unwrap_or_else(|e| panic!("built-in scene: {e}"))
}

/// The ground receiver of staged models: a 10 x 10 quad on y = 0.
#[must_use]
pub fn ground_quad() -> Mesh {
    built(procedural::plane(10.0, 10.0))
}

/// Puts a loaded model on stage (DESIGN 11): scaled so the largest side of its bounds is 1, centred over
/// the origin and set on y = 0.
///
/// A bare model (one without cameras and lights of its own) gets a 10 x 10 ground quad (unless `ground`
/// is false), the default spotlight at (2, 4, 1.5) aiming at the origin with a 60 degree cone and the
/// camera at (0, 1.1, 2.2) looking at (0, 0.35, 0) with a 45 degree vertical field of view. A file that
/// brings its own cameras or lights is a scene already: they are moved with it, it gets no second ground
/// (which would lie in its own floor and z-fight), and only what it lacks, a camera or a light, is
/// given the default.
pub fn stage_model(model: &mut Scene, ground: bool) {
    let b = model.bounds();
    let scale = 1.0 / b.size().max_element().max(1e-12);
    let offset = Vec3::new(-b.center().x, -b.min.y, -b.center().z);
    let place = Mat4::from_scale(Vec3::splat(scale)) * Mat4::from_translation(offset);
    // `place` is finite: the bounds are finite and the scale's divisor is at least 1e-12.
    let _ = model.group_roots("stage", place);
    let bare = model.cameras().next().is_none() && model.lights().next().is_none();
    // Lights and cameras that follow a node moved with the roots; the others are moved here. The stage's
    // scale shrinks the model, so a lamp's size and reach and a camera's near plane shrink with it.
    let lights: Vec<LightKey> = model.lights().map(|(k, _)| k).collect();
    for k in lights {
        let follows = model.light_node(k).is_some();
        if let Some(l) = model.light_mut(k) {
            let moved = if follows { *l } else { l.transformed(place) };
            *l = Light { radius: l.radius * scale, range: l.range.map(|r| r * scale), ..moved };
        }
    }
    let cameras: Vec<CameraKey> = model.cameras().map(|(k, _)| k).collect();
    for k in cameras {
        let follows = model.camera_node(k).is_some();
        if let Some(c) = model.camera_mut(k) {
            let moved = if follows { *c } else { c.transformed(place) };
            *c = Camera { near: c.near * scale, ..moved };
        }
    }
    if ground && bare {
        let mesh = model.add_mesh(ground_quad());
        let mat = model.add_material(Material::colored("ground", Vec3::splat(0.75)));
        let _ = model.add_instance("ground", mesh, mat, Mat4::IDENTITY);
    }
    if model.cameras().next().is_none() {
        model.add_camera(Camera::look_at(Vec3::new(0.0, 1.1, 2.2), Vec3::new(0.0, 0.35, 0.0), 45.0));
    }
    if model.lights().next().is_none() {
        model.add_light(Light::spot(Vec3::new(2.0, 4.0, 1.5), Vec3::ZERO, 60.0));
    }
}

/// A small deterministic generator (SplitMix64) for scene placement.
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    /// A generator from a seed.
    #[must_use]
    pub fn new(seed: u64) -> Self {
        Self(seed ^ 0x5DEE_CE66_D1CE_4E5B)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.unit()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_scene_builds_deterministically_with_a_camera_and_a_light() {
        for info in every() {
            let a = build(info.name, &SceneParams::default()).unwrap();
            let b = build(info.name, &SceneParams::default()).unwrap();
            assert_eq!(a.triangle_count(), b.triangle_count(), "{}", info.name);
            assert_eq!(a.bounds(), b.bounds(), "{}", info.name);
            assert_eq!(a.cameras().count(), 1, "{}", info.name);
            // One light, but under the sun of the scenes of many objects a spot light too, and the scenes
            // of many lights have 64.
            let lights = if MANY.iter().any(|m| m.name == info.name) {
                2
            } else if LIGHTS.iter().any(|m| m.name == info.name) {
                64
            } else {
                1
            };
            assert_eq!(a.lights().count(), lights, "{}", info.name);
            for (_, l) in a.lights() {
                l.validate().unwrap();
            }
        }
        assert!(build("nope", &SceneParams::default()).is_err());
    }

    /// The yard's lights are spot and point lights in turn, each with a range, and the camera sees some
    /// of them but not most.
    #[test]
    fn the_yard_camera_sees_part_of_its_lights() {
        let yard = build("yard", &SceneParams::default()).unwrap();
        let camera = yard.cameras().next().unwrap().1;
        let view = camera.clip_from_world(4.0 / 3.0);
        let (mut spots, mut seen) = (0, 0);
        for (_, l) in yard.lights() {
            assert!(l.range.is_some());
            spots += usize::from(matches!(l.kind, LightKind::Spot { .. }));
            let c = view * l.position().unwrap().extend(1.0);
            seen += usize::from(c.w > 0.0 && c.x.abs() < c.w && c.y.abs() < c.w);
        }
        assert_eq!(spots, 32);
        assert!((8..32).contains(&seen), "{seen} of 64 lights in view");
    }

    #[test]
    fn triangle_counts_are_near_the_papers() {
        let count = |n: &str| build(n, &SceneParams::default()).unwrap().triangle_count() as f64;
        for (name, target) in
            [("primitives", 9_400.0), ("crowd", 15_000.0), ("cubes", 12_000.0), ("cage", 12_000.0), ("tree", 40_000.0)]
        {
            let n = count(name);
            assert!((n - target).abs() / target < 0.15, "{name}: {n} triangles, paper about {target}");
        }
        // Strike: ten pins of about 450 triangles each, a ball and a lane.
        let strike = count("strike");
        assert!(strike > 4_500.0 && strike < 6_500.0, "strike: {strike}");
    }

    #[test]
    fn the_outdoor_scenes_are_a_street_at_head_height_under_a_low_sun() {
        let sun = |name: &str| {
            let s = build(name, &SceneParams::default()).unwrap();
            let (_, camera) = s.cameras().next().unwrap();
            let (_, light) = s.lights().next().unwrap();
            let LightKind::Directional { direction } = light.kind else { panic!("{name}: a sun") };
            let b = s.bounds();
            assert!(b.size().x >= 200.0 && b.size().z >= 200.0, "{name}: {b:?}");
            assert!(s.drawables().count() >= 3000, "{name}: {} casters", s.drawables().count());
            assert!((camera.eye.y - 1.7).abs() < 1e-6, "{name}: the eye at head height");
            let elevation = (-direction.y).asin().to_degrees();
            assert!((elevation - 20.0).abs() < 0.5, "{name}: the sun at {elevation} degrees");
            // How the sun travels along the view: with it (behind the camera) or against it (facing).
            direction.dot((camera.target - camera.eye).normalize())
        };
        let (side, behind, facing) = (sun("outdoor"), sun("outdoor-behind"), sun("outdoor-facing"));
        assert!(behind > 0.9 && facing < -0.9 && side.abs() < 0.8, "{side} {behind} {facing}");
    }

    /// Each scene of cut-out casters casts through its texture: its frame has cut-out casters, and
    /// `foliage` thousands of leaf cards.
    #[test]
    fn the_cutout_scenes_have_cut_out_casters() {
        for info in CUTOUT {
            let s = build(info.name, &SceneParams::default()).unwrap();
            let frame = crate::FrameInputs::from_first_camera(&s).unwrap();
            assert!(frame.has_cutout_casters(), "{}", info.name);
        }
        let foliage = build("foliage", &SceneParams::default()).unwrap();
        let leaves = foliage.drawables().find(|(_, n, _, _)| n.name() == "leaves").expect("the leaves").2;
        assert_eq!(foliage.mesh(leaves).unwrap().triangle_count(), 2 * 2916);
    }

    #[test]
    fn light_type_can_be_swapped() {
        let p = SceneParams { light: Some(LightType::Point), seed: 1 };
        let s = build("cylinder", &p).unwrap();
        assert!(s.lights().all(|(_, l)| matches!(l.kind, LightKind::Point { .. })));
        let p = SceneParams { light: Some(LightType::Spot), seed: 1 };
        let s = build("l-shape", &p).unwrap();
        assert!(s.lights().all(|(_, l)| matches!(l.kind, LightKind::Spot { .. }) && l.validate().is_ok()));
    }

    #[test]
    fn staged_models_stand_on_the_ground() {
        let mut s = Scene::new();
        let m = s.add_mesh(procedural::sphere(3.0, 16, 8).expect("shape"));
        let mat = s.add_material(Material::default());
        s.add_instance("ball", m, mat, Mat4::from_translation(Vec3::new(10.0, -5.0, 2.0))).unwrap();
        stage_model(&mut s, true);
        let ball = s
            .drawables()
            .find(|(_, n, _, _)| n.name() == "ball")
            .map(|(_, n, m, _)| s.mesh(m).unwrap().bounds().transformed(n.world_transform()))
            .unwrap();
        assert!((ball.min.y).abs() < 1e-5);
        assert!((ball.size().max_element() - 1.0).abs() < 1e-5);
        assert!(ball.center().x.abs() < 1e-5 && ball.center().z.abs() < 1e-5);
    }
}
