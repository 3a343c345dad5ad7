//! Animation: keyframed channels that move nodes, sampled as glTF 2.0 samples them, and the scene posed
//! at a time.
//!
//! A channel moves one property of one node (its translation, rotation or scale) along keyframes with
//! STEP, LINEAR or CUBICSPLINE interpolation. Before its first key a channel holds the first value, after
//! its last the last. An animated node keeps its rest transform as translation, rotation and scale
//! ([`Trs`]): posing starts from the rest of every animated node and overwrites the properties the
//! channels move, so a pose depends on the time alone, never on the pose before it.

use glam::{Mat4, Quat, Vec3, Vec4};

use super::{NodeKey, Scene, SceneError};

slotmap::new_key_type! {
    /// An animation of the scene.
    pub struct AnimationKey;
}

/// A transform as translation, rotation and scale, composed as `T * R * S` (glTF's order).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Trs {
    /// Translation.
    pub translation: Vec3,
    /// Rotation, a unit quaternion.
    pub rotation: Quat,
    /// Scale along the local axes.
    pub scale: Vec3,
}

impl Trs {
    /// No translation, rotation or scale.
    pub const IDENTITY: Self = Self { translation: Vec3::ZERO, rotation: Quat::IDENTITY, scale: Vec3::ONE };

    /// The matrix `T * R * S`.
    #[must_use]
    pub fn matrix(&self) -> Mat4 {
        Mat4::from_scale_rotation_translation(self.scale, self.rotation, self.translation)
    }

    /// The translation, rotation and scale of an affine matrix, or `None` where it has shear (or a row
    /// under it that is not `0 0 0 1`), which no [`Trs`] gives back.
    #[must_use]
    pub fn from_matrix(m: Mat4) -> Option<Self> {
        if !m.is_finite() || m.row(3) != Vec4::W {
            return None;
        }
        let (scale, rotation, translation) = m.to_scale_rotation_translation();
        let trs = Self { translation, rotation: rotation.normalize(), scale };
        let size = m.to_cols_array().iter().fold(1.0f32, |a, v| a.max(v.abs()));
        trs.matrix().abs_diff_eq(m, 1e-5 * size).then_some(trs)
    }
}

/// How a channel's value runs between two keys (glTF's sampler interpolation).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    /// The value of the key before, held until the next.
    Step,
    /// Straight between the keys; rotations along the shorter great arc (slerp).
    Linear,
    /// A cubic Hermite spline through the keys, each key an in-tangent, a value and an out-tangent.
    CubicSpline,
}

impl Interpolation {
    /// The glTF name.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Step => "STEP",
            Self::Linear => "LINEAR",
            Self::CubicSpline => "CUBICSPLINE",
        }
    }
}

/// The values of a channel's keys: one a key, or three (in-tangent, value, out-tangent) with
/// [`Interpolation::CubicSpline`].
#[derive(Clone, Debug, PartialEq)]
pub enum Keyframes {
    /// The node's translation.
    Translation(Vec<Vec3>),
    /// The node's rotation.
    Rotation(Vec<Quat>),
    /// The node's scale.
    Scale(Vec<Vec3>),
    /// The morph target weights of the node's mesh: `targets` values a key.
    Weights {
        /// Targets of the mesh, and so weights a key.
        targets: usize,
        /// Key after key.
        values: Vec<f32>,
    },
}

impl Keyframes {
    /// The property moved, as glTF names it.
    #[must_use]
    pub fn property(&self) -> &'static str {
        match self {
            Self::Translation(_) => "translation",
            Self::Rotation(_) => "rotation",
            Self::Scale(_) => "scale",
            Self::Weights { .. } => "weights",
        }
    }

    /// Number of values (of weights, one per `targets` of them).
    fn len(&self) -> usize {
        match self {
            Self::Translation(v) | Self::Scale(v) => v.len(),
            Self::Rotation(v) => v.len(),
            Self::Weights { targets, values } => values.len() / (*targets).max(1),
        }
    }

    fn finite(&self) -> bool {
        match self {
            Self::Translation(v) | Self::Scale(v) => v.iter().all(|x| x.is_finite()),
            Self::Rotation(v) => v.iter().all(|x| x.is_finite()),
            Self::Weights { values, .. } => values.iter().all(|x| x.is_finite()),
        }
    }
}

/// One property of one node, keyed over time.
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    /// The node it moves.
    pub node: NodeKey,
    /// Key times in seconds: at least one, none negative, strictly increasing.
    pub times: Vec<f32>,
    /// How the value runs between keys.
    pub interpolation: Interpolation,
    /// The values.
    pub values: Keyframes,
}

impl Channel {
    /// The time of its last key.
    #[must_use]
    pub fn duration(&self) -> f32 {
        self.times.last().copied().unwrap_or(0.0)
    }

    /// Checks the channel as [`Animation::new`] does and normalizes its rotations; says what is wrong.
    ///
    /// # Errors
    /// What is wrong, in a few words.
    pub fn check(&mut self) -> Result<(), String> {
        if self.times.is_empty() {
            return Err("no keys".into());
        }
        if let Some(t) = self.times.iter().find(|t| !(t.is_finite() && **t >= 0.0)) {
            return Err(format!("key time {t} is not a finite number of seconds of 0 or more"));
        }
        if let Some(k) = self.times.windows(2).position(|w| w[1] <= w[0]) {
            let (a, b) = (self.times[k], self.times[k + 1]);
            return Err(format!("key times are not increasing: key {} at {b} s after {a} s", k + 1));
        }
        let per_key = if self.interpolation == Interpolation::CubicSpline { 3 } else { 1 };
        if let Keyframes::Weights { targets, values } = &self.values
            && (*targets == 0 || values.len() % targets != 0)
        {
            return Err(format!("{} weights do not make keys of {targets} targets", values.len()));
        }
        if self.values.len() != per_key * self.times.len() {
            return Err(format!(
                "{} keys with {} interpolation need {} values, not {}",
                self.times.len(),
                self.interpolation.name(),
                per_key * self.times.len(),
                self.values.len()
            ));
        }
        if !self.values.finite() {
            return Err("a value is not finite".into());
        }
        if let Keyframes::Rotation(qs) = &mut self.values {
            // A spline's tangents may be anything; its values and every other key are rotations.
            let is_value = |j: usize| per_key == 1 || j % 3 == 1;
            if let Some(j) = (0..qs.len()).find(|&j| is_value(j) && qs[j].length_squared() < 1e-12) {
                return Err(format!("rotation {j} is zero, no rotation"));
            }
            for (j, q) in qs.iter_mut().enumerate() {
                if is_value(j) {
                    *q = q.normalize();
                }
            }
        }
        Ok(())
    }

    /// Where the time falls: the key before it, and how far towards the next (0 at a key; the last key
    /// with 0 after the end, the first with 0 before the start).
    fn locate(&self, t: f32) -> (usize, f32, f32) {
        let last = self.times.len() - 1;
        if t <= self.times[0] {
            return (0, 0.0, 0.0);
        }
        if t >= self.times[last] {
            return (last, 0.0, 0.0);
        }
        // The key before t: the last key at or before it, never the last key (t is before it).
        let k = self.times.partition_point(|&key| key <= t) - 1;
        let span = self.times[k + 1] - self.times[k];
        (k, (t - self.times[k]) / span, span)
    }

    /// The channel's value at time `t`, applied to `pose` (a channel of weights leaves it be).
    pub fn apply(&self, t: f32, pose: &mut Trs) {
        let (k, s, span) = self.locate(t);
        let ip = self.interpolation;
        match &self.values {
            Keyframes::Translation(v) => pose.translation = sample(|j| v[j], ip, k, s, span, Vec3::lerp),
            Keyframes::Scale(v) => pose.scale = sample(|j| v[j], ip, k, s, span, Vec3::lerp),
            Keyframes::Rotation(v) => {
                let q = sample(|j| v[j], ip, k, s, span, Quat::slerp);
                // A spline's quaternion leaves the unit sphere between keys; glTF normalizes it.
                pose.rotation = if ip == Interpolation::CubicSpline { q.normalize() } else { q };
            }
            Keyframes::Weights { .. } => {}
        }
    }

    /// The channel's morph weights at time `t`, written over `weights` (grown to the targets' count; a
    /// channel of another property leaves them be).
    pub fn apply_weights(&self, t: f32, weights: &mut Vec<f32>) {
        let Keyframes::Weights { targets, values } = &self.values else { return };
        let (k, s, span) = self.locate(t);
        if weights.len() < *targets {
            weights.resize(*targets, 0.0);
        }
        let lerp = |a: f32, b: f32, s: f32| a + (b - a) * s;
        for (i, w) in weights.iter_mut().take(*targets).enumerate() {
            *w = sample(|j| values[j * targets + i], self.interpolation, k, s, span, lerp);
        }
    }
}

/// A value between key `k` and the next, `s` of the way there over `span` seconds, of values `at(j)`
/// (key `j`'s, or with a spline the `j`th of the keys' in-tangents, values and out-tangents).
fn sample<T>(
    at: impl Fn(usize) -> T,
    ip: Interpolation,
    k: usize,
    s: f32,
    span: f32,
    lerp: impl Fn(T, T, f32) -> T,
) -> T
where
    T: Copy + std::ops::Add<Output = T> + std::ops::Mul<f32, Output = T>,
{
    let at_key = s == 0.0;
    match ip {
        Interpolation::Step => at(k),
        Interpolation::Linear if at_key => at(k),
        Interpolation::Linear => lerp(at(k), at(k + 1), s),
        // Keys of three: in-tangent a, value v, out-tangent b.
        Interpolation::CubicSpline if at_key => at(3 * k + 1),
        Interpolation::CubicSpline => {
            let (v0, b0) = (at(3 * k + 1), at(3 * k + 2));
            let (a1, v1) = (at(3 * k + 3), at(3 * k + 4));
            let (s2, s3) = (s * s, s * s * s);
            v0 * (2.0 * s3 - 3.0 * s2 + 1.0)
                + b0 * (span * (s3 - 2.0 * s2 + s))
                + v1 * (-2.0 * s3 + 3.0 * s2)
                + a1 * (span * (s3 - s2))
        }
    }
}

/// A named clip: channels played together.
#[derive(Clone, Debug, PartialEq)]
pub struct Animation {
    name: String,
    channels: Vec<Channel>,
}

impl Animation {
    /// A clip of `channels`, checked: each has key times that are finite, none negative and strictly
    /// increasing, as many values as keys (three a key for a spline), finite values and rotations away
    /// from zero (which are normalized).
    ///
    /// # Errors
    /// [`SceneError::Animation`] naming the clip, the channel and what is wrong.
    pub fn new(name: &str, mut channels: Vec<Channel>) -> Result<Self, SceneError> {
        for (i, c) in channels.iter_mut().enumerate() {
            c.check().map_err(|why| SceneError::Animation {
                animation: name.into(),
                channel: format!("channel {i} ({})", c.values.property()),
                why,
            })?;
        }
        Ok(Self { name: name.into(), channels })
    }

    /// Its name.
    #[must_use]
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Its channels.
    #[must_use]
    pub fn channels(&self) -> &[Channel] {
        &self.channels
    }

    /// The time of its last key, in seconds.
    #[must_use]
    pub fn duration(&self) -> f32 {
        self.channels.iter().map(Channel::duration).fold(0.0, f32::max)
    }

    /// Drops the channels of nodes that are gone.
    pub(super) fn retain_nodes<V>(&mut self, nodes: &slotmap::SlotMap<NodeKey, V>) {
        self.channels.retain(|c| nodes.contains_key(c.node));
    }
}

impl Scene {
    /// Adds an animation. Every node it moves keeps its present local transform as its rest pose.
    ///
    /// # Errors
    /// A channel that names an unknown node, or moves a node whose transform has shear (which
    /// translation, rotation and scale cannot give back).
    pub fn add_animation(&mut self, animation: Animation) -> Result<AnimationKey, SceneError> {
        for (i, c) in animation.channels.iter().enumerate() {
            let node = self.nodes.get(c.node).ok_or(SceneError::UnknownKey("node"))?;
            let moves = !matches!(c.values, Keyframes::Weights { .. });
            if moves && !self.rest.contains_key(c.node) && Trs::from_matrix(node.local).is_none() {
                return Err(SceneError::Animation {
                    animation: animation.name.clone(),
                    channel: format!("channel {i} ({})", c.values.property()),
                    why: format!("node '{}' has a transform with shear, which cannot be animated", node.name),
                });
            }
        }
        for c in animation.channels.iter().filter(|c| !matches!(c.values, Keyframes::Weights { .. })) {
            if !self.rest.contains_key(c.node)
                && let Some(trs) = Trs::from_matrix(self.nodes[c.node].local)
            {
                self.rest.insert(c.node, trs);
            }
        }
        Ok(self.animations.insert(animation))
    }

    /// An animation.
    #[must_use]
    pub fn animation(&self, key: AnimationKey) -> Option<&Animation> {
        self.animations.get(key)
    }

    /// Every animation, in the order they were added.
    pub fn animations(&self) -> impl Iterator<Item = (AnimationKey, &Animation)> {
        self.animations.iter()
    }

    /// The longest animation's duration in seconds (0 without animations).
    #[must_use]
    pub fn animation_duration(&self) -> f32 {
        self.animations.values().map(Animation::duration).fold(0.0, f32::max)
    }

    /// The rest pose of an animated node: its transform when no animation moves it.
    #[must_use]
    pub fn rest_pose(&self, node: NodeKey) -> Option<Trs> {
        self.rest.get(node).copied()
    }

    /// Poses the scene at `t` seconds with every animation playing, each from its start (and holding its
    /// last key after its end); where two move the same property the later one added wins.
    ///
    /// # Errors
    /// A time that is not finite.
    pub fn pose(&mut self, t: f32) -> Result<(), SceneError> {
        let all: Vec<AnimationKey> = self.animations.keys().collect();
        self.pose_with(&all, t)
    }

    /// Poses the scene at `t` seconds with one animation playing; the nodes only other animations move
    /// stand at rest.
    ///
    /// # Errors
    /// An unknown key, or a time that is not finite.
    pub fn pose_animation(&mut self, key: AnimationKey, t: f32) -> Result<(), SceneError> {
        self.animations.get(key).ok_or(SceneError::UnknownKey("animation"))?;
        self.pose_with(&[key], t)
    }

    fn pose_with(&mut self, playing: &[AnimationKey], t: f32) -> Result<(), SceneError> {
        if !t.is_finite() {
            return Err(SceneError::Invalid(format!("cannot pose the scene at time {t}")));
        }
        if self.animations.is_empty() {
            return Ok(());
        }
        let mut pose = self.rest.clone();
        let mut weights = self.rest_weights.clone();
        for c in playing.iter().filter_map(|&k| self.animations.get(k)).flat_map(|a| &a.channels) {
            if let Keyframes::Weights { targets, .. } = c.values {
                if !weights.contains_key(c.node) {
                    weights.insert(c.node, vec![0.0; targets]);
                }
                if let Some(w) = weights.get_mut(c.node) {
                    c.apply_weights(t, w);
                }
            } else if let Some(trs) = pose.get_mut(c.node) {
                c.apply(t, trs);
            }
        }
        self.weights = weights;
        for (node, trs) in &pose {
            if let Some(n) = self.nodes.get_mut(node) {
                n.local = trs.matrix();
            }
        }
        for root in self.roots.clone() {
            self.update_subtree(root);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use std::f32::consts::FRAC_PI_2;

    use super::*;

    fn channel(node: NodeKey, times: &[f32], interpolation: Interpolation, values: Keyframes) -> Channel {
        Channel { node, times: times.to_vec(), interpolation, values }
    }

    #[test]
    fn step_and_linear_hold_their_ends_and_run_between_keys() {
        let mut rest = Trs::IDENTITY;
        let node = NodeKey::default();
        let keys = Keyframes::Translation(vec![Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0), Vec3::new(2.0, 4.0, 0.0)]);
        let linear = channel(node, &[1.0, 2.0, 4.0], Interpolation::Linear, keys.clone());
        for (t, want) in [(0.0, Vec3::ZERO), (1.5, Vec3::new(1.0, 0.0, 0.0)), (3.0, Vec3::new(2.0, 2.0, 0.0))] {
            linear.apply(t, &mut rest);
            assert_eq!(rest.translation, want, "linear at {t}");
        }
        linear.apply(9.0, &mut rest);
        assert_eq!(rest.translation, Vec3::new(2.0, 4.0, 0.0));
        let step = channel(node, &[1.0, 2.0, 4.0], Interpolation::Step, keys);
        for (t, want) in [(1.99, Vec3::ZERO), (2.0, Vec3::new(2.0, 0.0, 0.0)), (3.9, Vec3::new(2.0, 0.0, 0.0))] {
            step.apply(t, &mut rest);
            assert_eq!(rest.translation, want, "step at {t}");
        }
    }

    #[test]
    fn linear_rotations_take_the_shorter_arc() {
        let node = NodeKey::default();
        // A quarter turn about y, keyed with the second quaternion on the far side of the sphere.
        let end = -Quat::from_rotation_y(FRAC_PI_2);
        let c = channel(node, &[0.0, 1.0], Interpolation::Linear, Keyframes::Rotation(vec![Quat::IDENTITY, end]));
        let mut pose = Trs::IDENTITY;
        c.apply(0.5, &mut pose);
        let x = pose.rotation * Vec3::X;
        let half = std::f32::consts::FRAC_PI_4;
        assert!((x - Vec3::new(half.cos(), 0.0, -half.sin())).length() < 1e-6, "{x}");
    }

    /// The glTF spline by hand: keys at 1 s and 3 s, values 1 and 5, out-tangent 2 at the first and
    /// in-tangent -1 at the second. At 2 s (s = 1/2, span 2): h00 = 1/2, h10 = 1/8, h01 = 1/2, h11 = -1/8,
    /// so 1/2 * 1 + 2 * 1/8 * 2 + 1/2 * 5 + 2 * (-1/8) * (-1) = 0.5 + 0.5 + 2.5 + 0.25 = 3.75. At 1.5 s
    /// (s = 1/4): h00 = 27/32, h10 = 9/64, h01 = 5/32, h11 = -3/64, so 27/32 + 2 * 9/64 * 2 + 5/32 * 5 +
    /// 2 * (-3/64) * (-1) = (54 + 36 + 50 + 6) / 64 = 146/64.
    #[test]
    fn cubic_splines_match_a_hand_evaluation() {
        let node = NodeKey::default();
        let x = |v: f32| Vec3::new(v, 0.0, 0.0);
        // In-tangent, value, out-tangent per key.
        let values = vec![x(7.0), x(1.0), x(2.0), x(-1.0), x(5.0), x(9.0)];
        let c = channel(node, &[1.0, 3.0], Interpolation::CubicSpline, Keyframes::Translation(values));
        let mut pose = Trs::IDENTITY;
        for (t, want) in [(0.0, 1.0), (1.0, 1.0), (1.5, 146.0 / 64.0), (2.0, 3.75), (3.0, 5.0), (4.0, 5.0)] {
            c.apply(t, &mut pose);
            assert!((pose.translation.x - want).abs() < 1e-6, "at {t}: {} against {want}", pose.translation.x);
        }
        // A spline of rotations is normalized: halfway between two quarter turns about z with zero
        // tangents lies the unnormalized mean, which normalizes to the eighth turn.
        let (a, b) = (Quat::IDENTITY, Quat::from_rotation_z(FRAC_PI_2));
        let zero = Quat::from_xyzw(0.0, 0.0, 0.0, 0.0);
        let c = channel(
            node,
            &[0.0, 1.0],
            Interpolation::CubicSpline,
            Keyframes::Rotation(vec![zero, a, zero, zero, b, zero]),
        );
        let c = Animation::new("spin", vec![c]).unwrap().channels[0].clone();
        c.apply(0.5, &mut pose);
        assert!(pose.rotation.angle_between(Quat::from_rotation_z(FRAC_PI_2 / 2.0)) < 1e-5);
        assert!((pose.rotation.length() - 1.0).abs() < 1e-6);
    }

    #[test]
    fn bad_channels_are_refused_by_name() {
        let node = NodeKey::default();
        let t = |times: &[f32], n: usize| {
            let c = channel(node, times, Interpolation::Linear, Keyframes::Scale(vec![Vec3::ONE; n]));
            Animation::new("walk", vec![c]).unwrap_err().to_string()
        };
        assert!(
            t(&[0.0, 1.0, 1.0], 3).contains("not increasing: key 2 at 1 s after 1 s"),
            "{}",
            t(&[0.0, 1.0, 1.0], 3)
        );
        assert!(t(&[0.0, 1.0], 3).contains("need 2 values, not 3"));
        assert!(t(&[-1.0], 1).contains("key time -1"));
        assert!(t(&[], 0).contains("no keys"));
        assert!(t(&[0.0, 1.0], 3).starts_with("animation 'walk', channel 0 (scale)"), "{}", t(&[0.0, 1.0], 3));
        let zero = Quat::from_xyzw(0.0, 0.0, 0.0, 0.0);
        let c = channel(node, &[0.0], Interpolation::Step, Keyframes::Rotation(vec![zero]));
        assert!(Animation::new("turn", vec![c]).unwrap_err().to_string().contains("rotation 0 is zero"));
    }

    #[test]
    fn posing_moves_animated_nodes_and_their_children_from_rest() {
        let mut s = Scene::new();
        let arm = s.add_node("arm", None, Mat4::from_translation(Vec3::new(1.0, 0.0, 0.0))).unwrap();
        let hand = s.add_node("hand", Some(arm), Mat4::from_translation(Vec3::new(0.0, 2.0, 0.0))).unwrap();
        let turn = Keyframes::Rotation(vec![Quat::IDENTITY, Quat::from_rotation_z(FRAC_PI_2)]);
        let c = channel(arm, &[0.0, 2.0], Interpolation::Linear, turn);
        s.add_animation(Animation::new("wave", vec![c]).unwrap()).unwrap();
        assert_eq!(s.rest_pose(arm).unwrap().translation, Vec3::new(1.0, 0.0, 0.0));
        s.pose(2.0).unwrap();
        let hand_at = s.node(hand).unwrap().world_transform().w_axis.truncate();
        assert!((hand_at - Vec3::new(-1.0, 0.0, 0.0)).length() < 1e-6, "{hand_at}");
        // The same time gives the same pose, whatever came before.
        s.pose(1.0).unwrap();
        let halfway = s.node(hand).unwrap().world_transform();
        s.pose(0.0).unwrap();
        s.pose(1.0).unwrap();
        assert_eq!(s.node(hand).unwrap().world_transform(), halfway);
        assert!(s.pose(f32::NAN).is_err());
        let shear =
            Mat4::from_cols_array(&[1.0, 0.0, 0.0, 0.0, 0.5, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]);
        let sheared = s.add_node("sheared", None, shear).unwrap();
        let c = channel(sheared, &[0.0], Interpolation::Step, Keyframes::Scale(vec![Vec3::ONE]));
        let e = s.add_animation(Animation::new("skew", vec![c]).unwrap()).unwrap_err();
        assert!(e.to_string().contains("node 'sheared' has a transform with shear"), "{e}");
    }
}
