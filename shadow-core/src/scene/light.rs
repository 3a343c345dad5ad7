//! Lights: spot, directional and point, in world space, with glTF's colour, intensity, cones and range.

use glam::{Mat4, Vec3};

use super::SceneError;
use crate::technique::settings::TechniqueSpec;

/// What kind of light, with its placement in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    /// A point light with a cone: `cone_angle` is the full apex angle in radians.
    Spot {
        /// Position.
        position: Vec3,
        /// Unit direction the cone points along.
        direction: Vec3,
        /// Full cone angle in radians, in (0, pi).
        cone_angle: f32,
    },
    /// Parallel light travelling along `direction` (unit).
    Directional {
        /// Direction the light travels.
        direction: Vec3,
    },
    /// Omnidirectional point light.
    Point {
        /// Position.
        position: Vec3,
    },
}

/// How a light casts shadows (set per light with [`super::Scene::set_light_shadow`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LightShadow {
    /// Whether it casts shadows; one that does not lights everything it reaches (its visibility is 1).
    pub casts: bool,
    /// The technique that shadows it, with its settings (a map's size and bias where the technique has
    /// them); `None`: the frame's technique. Lights of one frame may each name another.
    pub technique: Option<TechniqueSpec>,
    /// When its shadow is built again.
    pub update: ShadowUpdate,
}

/// When a light's shadow is built again (its maps, volumes or whatever its technique builds); its query
/// runs every frame whatever this says.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum ShadowUpdate {
    /// Every frame.
    EveryFrame,
    /// When what its build reads changed: the light, the casters in its views and its atlas tiles (a
    /// technique whose build reads the camera builds every frame).
    #[default]
    OnChange,
    /// On its first frame and then every `n`th one, whatever changed in between (`n` of 0 or 1: every
    /// frame).
    Every(u32),
    /// On its first frame only; its build is kept until the technique forgets it
    /// ([`crate::technique::DynShadowTechnique::invalidate`]).
    Once,
}

impl ShadowUpdate {
    /// Parses `every-frame`, `on-change`, `every-N` or `once`.
    ///
    /// # Errors
    /// Anything else, named.
    pub fn parse(s: &str) -> Result<Self, SceneError> {
        let bad = || {
            SceneError::Invalid(format!("bad shadow update '{s}': expected every-frame, on-change, every-N or once"))
        };
        match s {
            "every-frame" => Ok(Self::EveryFrame),
            "on-change" => Ok(Self::OnChange),
            "once" => Ok(Self::Once),
            _ => s
                .strip_prefix("every-")
                .and_then(|n| n.parse().ok())
                .filter(|&n| n > 0)
                .map(Self::Every)
                .ok_or_else(bad),
        }
    }
}

impl Default for LightShadow {
    /// Casting, with the frame's technique.
    fn default() -> Self {
        Self { casts: true, technique: None, update: ShadowUpdate::OnChange }
    }
}

impl LightShadow {
    /// Casting with `technique` (a spec such as `shadow-map:res=1024`).
    #[must_use]
    pub fn with(technique: TechniqueSpec) -> Self {
        Self { casts: true, technique: Some(technique), update: ShadowUpdate::OnChange }
    }

    /// Casting no shadow.
    pub const NONE: Self = Self { casts: false, technique: None, update: ShadowUpdate::OnChange };
}

/// A light source.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    /// Type and placement.
    pub kind: LightKind,
    /// Linear-RGB colour.
    pub color: Vec3,
    /// Scale on `color`.
    pub intensity: f32,
    /// Radius of the emitting sphere, for soft shadows (hard-shadow techniques treat the light as a point).
    pub radius: f32,
    /// A spot light's inner cone, its full apex angle in radians: full light inside it, fading to none at
    /// the cone's rim (glTF's `innerConeAngle`, doubled). `None`: the last fifth of the half-angle fades.
    pub inner_cone_angle: Option<f32>,
    /// Where a point or spot light ends (glTF's `range`): its direct term is scaled by
    /// clamp(1 - (d / range)^4, 0, 1) at distance d, reaching zero at the range. `None`: it never ends.
    pub range: Option<f32>,
}

impl Light {
    /// A white spot light at `position` aiming at `target`.
    #[must_use]
    pub fn spot(position: Vec3, target: Vec3, cone_angle_deg: f32) -> Self {
        let direction = (target - position).normalize_or(Vec3::NEG_Y);
        Self::white(LightKind::Spot { position, direction, cone_angle: cone_angle_deg.to_radians() })
    }

    /// A white directional light travelling along `direction`.
    #[must_use]
    pub fn directional(direction: Vec3) -> Self {
        Self::white(LightKind::Directional { direction: direction.normalize_or(Vec3::NEG_Y) })
    }

    /// A white point light.
    #[must_use]
    pub fn point(position: Vec3) -> Self {
        Self::white(LightKind::Point { position })
    }

    fn white(kind: LightKind) -> Self {
        Self { kind, color: Vec3::ONE, intensity: 1.0, radius: 0.05, inner_cone_angle: None, range: None }
    }

    /// The light moved by the affine transform `m`: its position and direction are, its cone, radius,
    /// range and intensity are not (a scaled node does not scale its lamp, as glTF has it).
    #[must_use]
    pub fn transformed(&self, m: Mat4) -> Self {
        let direction = |d: Vec3| m.transform_vector3(d).normalize_or(d);
        let kind = match self.kind {
            LightKind::Spot { position, direction: d, cone_angle } => {
                LightKind::Spot { position: m.transform_point3(position), direction: direction(d), cone_angle }
            }
            LightKind::Point { position } => LightKind::Point { position: m.transform_point3(position) },
            LightKind::Directional { direction: d } => LightKind::Directional { direction: direction(d) },
        };
        Self { kind, ..*self }
    }

    /// Position for spot and point lights, `None` for directional ones.
    #[must_use]
    pub fn position(&self) -> Option<Vec3> {
        match self.kind {
            LightKind::Spot { position, .. } | LightKind::Point { position } => Some(position),
            LightKind::Directional { .. } => None,
        }
    }

    /// The short name of the light type: "spot", "directional" or "point".
    #[must_use]
    pub fn type_name(&self) -> &'static str {
        match self.kind {
            LightKind::Spot { .. } => "spot",
            LightKind::Directional { .. } => "directional",
            LightKind::Point { .. } => "point",
        }
    }

    /// Unit vector from `p` towards the light.
    #[must_use]
    #[inline]
    pub fn to_light(&self, p: Vec3) -> Vec3 {
        match self.kind {
            LightKind::Spot { position, .. } | LightKind::Point { position } => (position - p).normalize_or_zero(),
            LightKind::Directional { direction } => -direction,
        }
    }

    /// Checks that the light can be used: finite, unit-able direction, cone in (0, 180) degrees.
    ///
    /// # Errors
    /// [`SceneError::Invalid`] naming the bad parameter.
    pub fn validate(&self) -> Result<(), SceneError> {
        let bad = |what: &str| Err(SceneError::Invalid(format!("light {what}")));
        match self.kind {
            LightKind::Spot { position, direction, cone_angle } => {
                if !position.is_finite() {
                    return bad("position is not finite");
                }
                if !direction.is_finite() || direction.length_squared() < 1e-12 {
                    return bad("direction is zero or not finite");
                }
                if !(cone_angle > 0.0 && cone_angle < std::f32::consts::PI) {
                    return bad("cone angle must be between 0 and 180 degrees");
                }
                if self.inner_cone_angle.is_some_and(|inner| !(inner >= 0.0 && inner < cone_angle)) {
                    return bad("inner cone angle must be at least 0 and below the cone angle");
                }
            }
            LightKind::Directional { direction } => {
                if !direction.is_finite() || direction.length_squared() < 1e-12 {
                    return bad("direction is zero or not finite");
                }
            }
            LightKind::Point { position } => {
                if !position.is_finite() {
                    return bad("position is not finite");
                }
            }
        }
        if self.range.is_some_and(|r| !(r > 0.0 && r.is_finite())) {
            return bad("range must be positive");
        }
        if !(self.radius.is_finite() && self.radius >= 0.0 && self.color.is_finite() && self.intensity.is_finite()) {
            return bad("colour, intensity or radius is not finite and non-negative");
        }
        Ok(())
    }
}
