//! What a command renders: a scene (built-in or model file) with optional camera and light overrides
//! (DESIGN 11 flag syntax), resolved into a [`Scene`].

use glam::Vec3;
use shadow_core::Scene;
use shadow_core::scene::{Camera, Light, LightKind, LightShadow, ShadowUpdate};
use shadow_core::scenes::{LightType, SceneParams};

use shadow_core::assets::{FileAccess, LoadOptions};

use crate::{SceneSourceError, load_scene_with};

/// A malformed `--camera`, `--light` or `--size` value.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("bad {flag} '{value}': {why}")]
pub struct OptionError {
    /// The flag.
    pub flag: &'static str,
    /// Its value.
    pub value: String,
    /// What is wrong.
    pub why: String,
}

/// The `key=value` pairs of a flag, by the one parser technique settings use too.
fn pairs(flag: &'static str, text: &str) -> Result<Vec<(String, String)>, OptionError> {
    shadow_core::technique::key_values(text).map_err(|why| OptionError { flag, value: text.into(), why })
}

fn vec3(flag: &'static str, whole: &str, key: &str, v: &str) -> Result<Vec3, OptionError> {
    let parts: Vec<f32> = v
        .split(',')
        .map(|p| p.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| OptionError { flag, value: whole.into(), why: format!("{key} must be three numbers X,Y,Z") })?;
    match parts.as_slice() {
        [x, y, z] if x.is_finite() && y.is_finite() && z.is_finite() => Ok(Vec3::new(*x, *y, *z)),
        _ => Err(OptionError { flag, value: whole.into(), why: format!("{key} must be three finite numbers X,Y,Z") }),
    }
}

fn number(flag: &'static str, whole: &str, key: &str, v: &str) -> Result<f32, OptionError> {
    v.parse::<f32>().ok().filter(|x| x.is_finite()).ok_or_else(|| OptionError {
        flag,
        value: whole.into(),
        why: format!("{key} must be a number"),
    })
}

/// `--camera eye=X,Y,Z,target=X,Y,Z[,fov=DEG]`.
///
/// # Errors
/// Unknown keys, missing eye or target, bad numbers, or an unusable camera.
pub fn parse_camera(text: &str) -> Result<Camera, OptionError> {
    const F: &str = "--camera";
    let (mut eye, mut target, mut fov) = (None, None, 45.0);
    for (k, v) in pairs(F, text)? {
        match k.as_str() {
            "eye" => eye = Some(vec3(F, text, "eye", &v)?),
            "target" => target = Some(vec3(F, text, "target", &v)?),
            "fov" => fov = number(F, text, "fov", &v)?,
            other => {
                return Err(OptionError {
                    flag: F,
                    value: text.into(),
                    why: format!("unknown key '{other}' (eye, target, fov)"),
                });
            }
        }
    }
    let missing = |what: &str| OptionError { flag: F, value: text.into(), why: format!("{what} is required") };
    let cam = Camera::look_at(eye.ok_or_else(|| missing("eye"))?, target.ok_or_else(|| missing("target"))?, fov);
    cam.validate().map_err(|e| OptionError { flag: F, value: text.into(), why: e.to_string() })?;
    Ok(cam)
}

/// `--light spot|directional|point[,pos=X,Y,Z][,target=X,Y,Z][,fov=DEG][,radius=R]`, filling what is not
/// given from `default` (the scene's own light).
///
/// # Errors
/// An unknown type or key, bad numbers, or an unusable light.
pub fn parse_light(text: &str, default: &Light, scene_center: Vec3) -> Result<Light, OptionError> {
    const F: &str = "--light";
    let (kind, rest) = text.split_once(',').unwrap_or((text, ""));
    let t: LightType = kind.trim().parse().map_err(|e: String| OptionError {
        flag: F,
        value: text.into(),
        why: format!("type must be {e}"),
    })?;
    let (mut pos, mut dir) = match default.kind {
        LightKind::Spot { position, direction, .. } => (position, direction),
        LightKind::Point { position } => (position, (scene_center - position).normalize_or(Vec3::NEG_Y)),
        LightKind::Directional { direction } => (scene_center - direction * 5.0, direction),
    };
    let mut fov = match default.kind {
        LightKind::Spot { cone_angle, .. } => cone_angle.to_degrees(),
        _ => 60.0,
    };
    let mut radius = default.radius;
    let mut target = None;
    let mut fov_given = false;
    let refuse = |why: String| OptionError { flag: F, value: text.into(), why };
    for (k, v) in pairs(F, rest)? {
        match k.as_str() {
            "pos" => pos = vec3(F, text, "pos", &v)?,
            "target" if t == LightType::Point => {
                return Err(refuse("a point light shines every way: it takes no target".into()));
            }
            "target" => target = Some(vec3(F, text, "target", &v)?),
            "fov" if t != LightType::Spot => {
                return Err(refuse(format!("fov is a spot light's cone; a {kind} light has none", kind = kind.trim())));
            }
            "fov" => {
                fov = number(F, text, "fov", &v)?;
                fov_given = true;
            }
            "radius" => radius = number(F, text, "radius", &v)?,
            other => {
                return Err(OptionError {
                    flag: F,
                    value: text.into(),
                    why: format!("unknown key '{other}' (pos, target, fov, radius)"),
                });
            }
        }
    }
    if let Some(tg) = target {
        if (tg - pos).length_squared() < 1e-12 {
            return Err(OptionError { flag: F, value: text.into(), why: "light pos and target coincide".into() });
        }
        dir = (tg - pos).normalize();
    }
    let kind = match t {
        LightType::Spot => LightKind::Spot { position: pos, direction: dir, cone_angle: fov.to_radians() },
        LightType::Directional => LightKind::Directional { direction: dir },
        LightType::Point => LightKind::Point { position: pos },
    };
    // A new cone, or no cone, leaves the old inner cone behind.
    let inner_cone_angle = if t == LightType::Spot && !fov_given { default.inner_cone_angle } else { None };
    let range = if t == LightType::Directional { None } else { default.range };
    let light = Light { kind, radius, inner_cone_angle, range, ..*default };
    light.validate().map_err(|e| OptionError { flag: F, value: text.into(), why: e.to_string() })?;
    Ok(light)
}

/// `WxH`, both at least 1.
///
/// # Errors
/// Anything else.
pub fn parse_size(text: &str) -> Result<(u32, u32), OptionError> {
    let bad = |why: &str| OptionError { flag: "--size", value: text.into(), why: why.into() };
    let (w, h) = text.split_once(['x', 'X']).ok_or_else(|| bad("expected WxH, e.g. 512x512"))?;
    let (w, h) = (
        w.trim().parse::<u32>().map_err(|_| bad("width is not a whole number"))?,
        h.trim().parse::<u32>().map_err(|_| bad("height is not a whole number"))?,
    );
    if w == 0 || h == 0 {
        return Err(bad("width and height must be at least 1"));
    }
    Ok((w, h))
}

/// Which scene, and how it is set up.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneSetup {
    /// Built-in scene name or model file.
    pub source: String,
    /// Give a model file its ground quad.
    pub ground: bool,
    /// Light type and seed.
    pub params: SceneParams,
    /// Replaces the scene's camera.
    pub camera: Option<String>,
    /// Replaces the scene's light.
    pub light: Option<String>,
    /// Which files a model file may name besides itself.
    pub file_access: FileAccess,
    /// Pose the scene's animations at this time in seconds; at rest (as built or loaded) without one.
    pub time: Option<f32>,
    /// Give every node a copy of its own of a mesh other nodes draw too
    /// ([`shadow_core::Scene::unshare_meshes`]): the scene without instancing, to measure against.
    pub unshare: bool,
    /// Give the scene this many lights ([`shadow_core::Scene::set_light_count`]): its first ones, or its
    /// own and turned copies of them.
    pub lights: Option<usize>,
    /// When every light's shadow is built again ([`shadow_core::LightShadow::update`]); as the scene
    /// has it without one.
    pub shadow_update: Option<ShadowUpdate>,
}

impl SceneSetup {
    /// A built-in scene or model file with its own camera and light.
    #[must_use]
    pub fn new(source: &str) -> Self {
        Self {
            source: source.into(),
            ground: true,
            params: SceneParams::default(),
            camera: None,
            light: None,
            file_access: FileAccess::default(),
            time: None,
            unshare: false,
            lights: None,
            shadow_update: None,
        }
    }

    /// Loads the scene and applies the overrides.
    ///
    /// # Errors
    /// Unknown scene, bad model file, or bad overrides.
    pub fn build(&self) -> Result<Scene, SetupError> {
        let options = LoadOptions { file_access: self.file_access, ..LoadOptions::default() };
        let mut scene = load_scene_with(&self.source, &self.params, self.ground, &options)?;
        if self.unshare {
            scene.unshare_meshes();
        }
        if let Some(t) = self.time {
            if scene.animations().next().is_none() {
                scene.add_warning(format!("{}: no animations to pose at {t} s; shown as it stands", self.source));
            }
            scene.pose(t).map_err(|e| OptionError { flag: "--time", value: t.to_string(), why: e.to_string() })?;
        }
        if let Some(c) = &self.camera {
            let cam = parse_camera(c)?;
            scene.clear_cameras();
            scene.add_camera(cam);
        }
        if let Some(l) = &self.light {
            let default = scene
                .lights()
                .next()
                .map(|(_, l)| l)
                .unwrap_or_else(|| Light::spot(Vec3::new(2.0, 4.0, 1.5), Vec3::ZERO, 60.0));
            let light = parse_light(l, &default, scene.bounds().center())?;
            scene.clear_lights();
            scene.add_light(light);
        }
        if let Some(n) = self.lights {
            let why = |e: shadow_core::scene::SceneError| OptionError {
                flag: "--lights",
                value: n.to_string(),
                why: e.to_string(),
            };
            scene.set_light_count(n).map_err(why)?;
        }
        if let Some(update) = self.shadow_update {
            let keys: Vec<_> = scene.lights().map(|(k, _)| k).collect();
            for k in keys {
                let shadow = LightShadow { update, ..scene.light_shadow(k) };
                scene.set_light_shadow(k, shadow).unwrap_or_else(|_| unreachable!("a light of the scene"));
            }
        }
        Ok(scene)
    }
}

/// Why a scene setup failed.
#[derive(Debug, thiserror::Error)]
pub enum SetupError {
    /// The scene itself.
    #[error(transparent)]
    Source(#[from] SceneSourceError),
    /// An override.
    #[error(transparent)]
    Option(#[from] OptionError),
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_light_count_flag_sets_the_lights_or_names_itself() {
        let setup = |n: usize| SceneSetup { lights: Some(n), ..SceneSetup::new("cylinder") };
        assert_eq!(setup(3).build().expect("three lights").lights().count(), 3);
        assert_eq!(
            SceneSetup { lights: Some(5), ..SceneSetup::new("yard") }.build().expect("yard").lights().count(),
            5
        );
        let Err(e) = setup(0).build() else { panic!("a scene of no lights") };
        let e = e.to_string();
        assert!(e.contains("--lights") && e.contains("at least 1"), "{e}");
    }

    #[test]
    fn camera_and_light_flags() {
        let c = parse_camera("eye=1,2,3,target=0,0.5,0,fov=30").unwrap();
        assert_eq!(c.eye, Vec3::new(1.0, 2.0, 3.0));
        assert!((c.fov_y.to_degrees() - 30.0).abs() < 1e-4);
        assert!(parse_camera("eye=1,2,target=0,0,0").is_err());
        assert!(parse_camera("eye=1,2,3").is_err());
        assert!(parse_camera("eye=1,2,3,target=1,2,3").is_err());
        let d = Light::spot(Vec3::new(2.0, 4.0, 1.5), Vec3::ZERO, 60.0);
        let l = parse_light("point,pos=0,5,0", &d, Vec3::ZERO).unwrap();
        assert_eq!(l.kind, LightKind::Point { position: Vec3::new(0.0, 5.0, 0.0) });
        let l = parse_light("directional", &d, Vec3::ZERO).unwrap();
        assert!(matches!(l.kind, LightKind::Directional { .. }));
        assert!(parse_light("laser", &d, Vec3::ZERO).is_err());
        assert!(parse_light("spot,fov=200", &d, Vec3::ZERO).is_err());
        let same = parse_light("spot,pos=1,2,3,target=1,2,3", &d, Vec3::ZERO).unwrap_err();
        assert!(same.to_string().contains("coincide"), "{same}");
        assert_eq!(parse_size("640x480").unwrap(), (640, 480));
        assert!(parse_size("0x480").is_err());
        assert!(parse_size("640").is_err());
    }
}
