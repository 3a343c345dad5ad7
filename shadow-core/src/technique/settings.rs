//! Technique settings: `name:key=value,...` parsing, typed settings structs, and their canonical strings.
//!
//! Every settings struct lists its keys with defaults and help ([`TechniqueSettings::keys`]); unknown
//! keys and unparsable values are errors that name the technique, the key and what was expected.

use std::collections::BTreeMap;
use std::fmt;

#[macro_use]
mod macros;

/// Largest shadow-map side any technique accepts: 16384^2 f32 texels is 1 GiB, refused before allocating
/// anything bigger.
pub const MAX_MAP_RESOLUTION: u32 = 16384;

/// Why a technique specification was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SettingsError {
    /// Not of the form `name[:key=value,...]`.
    #[error("bad technique specification '{spec}': {why}")]
    Syntax {
        /// The whole specification.
        spec: String,
        /// What is wrong.
        why: String,
    },
    /// A key the technique does not have.
    #[error("technique '{technique}' has no setting '{key}' (settings: {valid})")]
    UnknownKey {
        /// Technique name.
        technique: String,
        /// The unknown key.
        key: String,
        /// The keys it does have.
        valid: String,
    },
    /// A value that does not parse or is out of range.
    #[error("technique '{technique}': bad value '{value}' for '{key}': expected {expected}")]
    BadValue {
        /// Technique name.
        technique: String,
        /// The key.
        key: String,
        /// The value given.
        value: String,
        /// What would have been accepted.
        expected: String,
    },
}

/// A technique name with the settings given for it (not yet checked against the technique).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct TechniqueSpec {
    /// Registry name.
    pub name: String,
    /// Settings in the order given.
    pub values: Vec<(String, String)>,
}

impl TechniqueSpec {
    /// A specification with no settings.
    #[must_use]
    pub fn named(name: &str) -> Self {
        Self { name: name.into(), values: Vec::new() }
    }

    /// Parses `name[:key=value,...]`. Values never contain commas.
    ///
    /// # Errors
    /// [`SettingsError::Syntax`] for an empty name, a pair without `=`, an empty key or a repeated key.
    pub fn parse(spec: &str) -> Result<Self, SettingsError> {
        let bad = |why: &str| SettingsError::Syntax { spec: spec.into(), why: why.into() };
        let (name, rest) = match spec.split_once(':') {
            Some((n, r)) => (n.trim(), Some(r)),
            None => (spec.trim(), None),
        };
        if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_') {
            return Err(bad("the name must be non-empty letters, digits and '-'"));
        }
        let values = key_values(rest.unwrap_or("")).map_err(|why| bad(&why))?;
        Ok(Self { name: name.into(), values })
    }
}

/// Parses `key=value,key=value,...`: the one syntax of technique settings and of the CLI's `--camera` and
/// `--light`. A piece without `=` continues the value before it, so vectors keep their commas
/// (`pos=1,2,3`); empty pieces are skipped. The error says what is wrong, without the text.
///
/// # Errors
/// A first piece without `=`, an empty key, or a key given twice.
///
/// # Examples
/// ```
/// use shadow_core::technique::key_values;
/// let kv = key_values("eye=0,1,2,fov=30").unwrap();
/// assert_eq!(kv, vec![("eye".into(), "0,1,2".into()), ("fov".into(), "30".into())]);
/// assert!(key_values("fov=30,fov=40").unwrap_err().contains("twice"));
/// ```
pub fn key_values(text: &str) -> Result<Vec<(String, String)>, String> {
    let mut values: Vec<(String, String)> = Vec::new();
    for piece in text.split(',').map(str::trim).filter(|p| !p.is_empty()) {
        let Some((k, v)) = piece.split_once('=') else {
            match values.last_mut() {
                Some((_, v)) => {
                    v.push(',');
                    v.push_str(piece);
                    continue;
                }
                None => return Err(format!("'{piece}' is not key=value")),
            }
        };
        let (k, v) = (k.trim(), v.trim());
        if k.is_empty() {
            return Err(format!("'{piece}' has an empty key"));
        }
        if values.iter().any(|(seen, _)| seen == k) {
            return Err(format!("'{k}' is given twice"));
        }
        values.push((k.into(), v.into()));
    }
    Ok(values)
}

impl fmt::Display for TechniqueSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.name)?;
        for (i, (k, v)) in self.values.iter().enumerate() {
            write!(f, "{}{k}={v}", if i == 0 { ':' } else { ',' })?;
        }
        Ok(())
    }
}

/// What values a setting takes: the one description that parsing, validation, `shadowlab techniques` and a
/// viewer's controls all read.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SettingKind {
    /// A whole number in `lo..=hi`.
    Int {
        /// Smallest.
        lo: u32,
        /// Largest.
        hi: u32,
    },
    /// A number in `lo..=hi`.
    Float {
        /// Smallest.
        lo: f32,
        /// Largest.
        hi: f32,
    },
    /// One of these names.
    Choice(&'static [&'static str]),
}

/// One setting: key, default, the values it takes, and help text.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SettingKey {
    /// The key.
    pub key: &'static str,
    /// Its default, as text.
    pub default: &'static str,
    /// What it does.
    pub help: &'static str,
    /// The values it takes.
    pub kind: SettingKind,
    /// A word taken besides the kind's values (`auto`, or `0` for "off" below an integer range); the field
    /// type says what it means.
    pub word: Option<&'static str>,
}

impl SettingKey {
    /// A whole number in `lo..=hi`.
    #[must_use]
    pub const fn int(key: &'static str, default: &'static str, lo: u32, hi: u32, help: &'static str) -> Self {
        Self { key, default, help, kind: SettingKind::Int { lo, hi }, word: None }
    }

    /// A number in `lo..=hi`.
    #[must_use]
    pub const fn float(key: &'static str, default: &'static str, lo: f32, hi: f32, help: &'static str) -> Self {
        Self { key, default, help, kind: SettingKind::Float { lo, hi }, word: None }
    }

    /// One of `names` (a `named_enum!`'s `NAMES`).
    #[must_use]
    pub const fn choice(
        key: &'static str,
        default: &'static str,
        names: &'static [&'static str],
        help: &'static str,
    ) -> Self {
        Self { key, default, help, kind: SettingKind::Choice(names), word: None }
    }

    /// The same setting, also taking `word`.
    #[must_use]
    pub const fn or(self, word: &'static str) -> Self {
        Self { word: Some(word), ..self }
    }

    /// The same setting with another default.
    #[must_use]
    pub const fn with_default(self, default: &'static str) -> Self {
        Self { default, ..self }
    }

    /// What the setting takes, for error messages: "a number from 16 to 16384", "auto, or 0 to 64",
    /// "one of none, constant, slope".
    #[must_use]
    pub fn expected(&self) -> String {
        let range = match self.kind {
            SettingKind::Int { lo, hi } => format!("{lo} to {hi}"),
            SettingKind::Float { lo, hi } => format!("{lo} to {hi}"),
            SettingKind::Choice(names) => return format!("one of {}", names.join(", ")),
        };
        match self.word {
            Some(word) => format!("{word}, or {range}"),
            None => format!("a number from {range}"),
        }
    }
}

/// A field type a setting reads into and prints from.
pub trait SettingValue: Sized {
    /// The value of `text` for `key`, or `None` when `key` does not take it.
    fn from_setting(text: &str, key: &SettingKey) -> Option<Self>;
    /// The text the value prints as (and reads back from).
    fn to_setting(&self) -> String;
}

impl SettingValue for u32 {
    fn from_setting(text: &str, key: &SettingKey) -> Option<Self> {
        let v: u32 = text.parse().ok()?;
        match key.kind {
            _ if key.word == Some(text) => Some(v),
            SettingKind::Int { lo, hi } => (lo..=hi).contains(&v).then_some(v),
            _ => None,
        }
    }
    fn to_setting(&self) -> String {
        self.to_string()
    }
}

impl SettingValue for f32 {
    fn from_setting(text: &str, key: &SettingKey) -> Option<Self> {
        let v: f32 = text.parse().ok()?;
        match key.kind {
            SettingKind::Float { lo, hi } => (v >= lo && v <= hi).then_some(v),
            _ => None,
        }
    }
    fn to_setting(&self) -> String {
        self.to_string()
    }
}

/// A whole number, or the key's word for none (`auto`).
impl SettingValue for Option<u32> {
    fn from_setting(text: &str, key: &SettingKey) -> Option<Self> {
        if key.word == Some(text) { Some(None) } else { u32::from_setting(text, key).map(Some) }
    }
    fn to_setting(&self) -> String {
        self.map_or_else(|| "auto".to_string(), |n| n.to_string())
    }
}

/// The keys a settings field reads: one, or a group (a depth map's five).
pub trait KeySet {
    /// The keys, in order.
    fn key_list(&self) -> &[SettingKey];
}

impl KeySet for SettingKey {
    fn key_list(&self) -> &[SettingKey] {
        std::slice::from_ref(self)
    }
}

impl<const N: usize> KeySet for [SettingKey; N] {
    fn key_list(&self) -> &[SettingKey] {
        self
    }
}

impl KeySet for &[SettingKey] {
    fn key_list(&self) -> &[SettingKey] {
        self
    }
}

/// A settings field: a value of one key, or a group of keys read together.
pub trait SettingField: Sized {
    /// Reads the field from its keys.
    ///
    /// # Errors
    /// A value its key does not take.
    fn read(v: &Values<'_>, keys: &[SettingKey]) -> Result<Self, SettingsError>;
    /// Appends the values of its keys, in order.
    fn write(&self, out: &mut Vec<String>);
}

impl<T: SettingValue> SettingField for T {
    fn read(v: &Values<'_>, keys: &[SettingKey]) -> Result<Self, SettingsError> {
        v.read(&keys[0])
    }
    fn write(&self, out: &mut Vec<String>) {
        out.push(self.to_setting());
    }
}

/// The values given for a technique, with the defaults of its keys behind them.
pub struct Values<'a> {
    technique: &'a str,
    given: BTreeMap<&'a str, &'a str>,
    keys: &'static [SettingKey],
}

impl Values<'_> {
    /// The value of `key` (given or default), read as its kind says.
    ///
    /// # Errors
    /// [`SettingsError::BadValue`] when the key does not take it.
    pub fn read<T: SettingValue>(&self, key: &SettingKey) -> Result<T, SettingsError> {
        T::from_setting(self.text(key.key), key).ok_or_else(|| self.bad(key.key, &key.expected()))
    }

    /// The value of the key named `key`.
    ///
    /// # Errors
    /// [`SettingsError::BadValue`] when the key does not take it.
    ///
    /// # Panics
    /// When `key` is not one of the technique's keys: that is a bug in the settings struct.
    pub fn get<T: SettingValue>(&self, key: &str) -> Result<T, SettingsError> {
        match self.keys.iter().find(|k| k.key == key) {
            Some(k) => self.read(k),
            None => panic!("settings struct reads undeclared key '{key}'"),
        }
    }

    /// The text of `key`, given or default.
    ///
    /// # Panics
    /// When `key` is not one of the technique's keys: that is a bug in the settings struct.
    #[must_use]
    pub fn text(&self, key: &str) -> &str {
        match self.given.get(key) {
            Some(v) => v,
            None => match self.keys.iter().find(|k| k.key == key) {
                Some(k) => k.default,
                None => panic!("settings struct reads undeclared key '{key}'"),
            },
        }
    }

    /// A [`SettingsError::BadValue`] for `key` with its current text.
    #[must_use]
    pub fn bad(&self, key: &str, expected: &str) -> SettingsError {
        SettingsError::BadValue {
            technique: self.technique.into(),
            key: key.into(),
            value: self.text(key).into(),
            expected: expected.into(),
        }
    }
}

/// A typed settings struct of a technique.
pub trait TechniqueSettings: Sized + Clone + Send + Sync + 'static {
    /// The kinds of light the technique takes; others are refused before its build.
    const LIGHTS: super::LightKinds = super::LightKinds::ALL;

    /// Every key, with its default and help.
    fn keys() -> &'static [SettingKey];
    /// Reads the struct from given-or-default values.
    ///
    /// # Errors
    /// A value that does not parse or is out of range.
    fn from_values(values: &Values<'_>) -> Result<Self, SettingsError>;
    /// Every key with its current value, in [`TechniqueSettings::keys`] order.
    fn to_values(&self) -> Vec<String>;

    /// The settings of a spec for the technique named `technique`, unknown keys refused.
    ///
    /// # Errors
    /// [`SettingsError::UnknownKey`] or [`SettingsError::BadValue`].
    fn parse(technique: &str, given: &[(String, String)]) -> Result<Self, SettingsError> {
        let keys = Self::keys();
        for (k, _) in given {
            if !keys.iter().any(|s| s.key == k) {
                let valid = if keys.is_empty() {
                    "none".to_string()
                } else {
                    keys.iter().map(|s| s.key).collect::<Vec<_>>().join(", ")
                };
                return Err(SettingsError::UnknownKey { technique: technique.into(), key: k.clone(), valid });
            }
        }
        let values = Values { technique, given: given.iter().map(|(k, v)| (k.as_str(), v.as_str())).collect(), keys };
        Self::from_values(&values)
    }

    /// The defaults.
    ///
    /// # Panics
    /// When the declared defaults do not parse: a bug in the settings struct, caught by its tests.
    #[must_use]
    fn defaults() -> Self {
        match Self::parse("defaults", &[]) {
            Ok(s) => s,
            Err(e) => panic!("declared defaults do not parse: {e}"),
        }
    }

    /// Canonical `key=value,...` with every key, for reports.
    #[must_use]
    fn settings_string(&self) -> String {
        Self::keys().iter().zip(self.to_values()).map(|(k, v)| format!("{}={v}", k.key)).collect::<Vec<_>>().join(",")
    }
}

named_enum! {
    /// A setting that is on or off (each field's docs say what "on" does).
    pub enum OnOff {
        /// Off.
        Off = "off",
        /// On.
        On = "on",
    }
}

impl OnOff {
    /// Whether it is on.
    #[must_use]
    pub fn is_on(self) -> bool {
        self == Self::On
    }
}

named_enum! {
    /// How a shadow map's depth is offset when the map is rendered (Vulkan's float depth bias, DESIGN 4).
    pub enum BiasMode {
        /// No bias.
        None = "none",
        /// The constant term only: `bias_constant * 2^(e - 23)`, e the exponent of the primitive's largest |z|.
        Constant = "constant",
        /// Constant plus `bias_slope * max(|dz/dx|, |dz/dy|)` in texels.
        Slope = "slope",
        /// No bias in the map; each receiver is moved `bias_world` towards the light before the lookup (a
        /// constant offset in scene units, the classic constant bias of Weiskopf-Ertl Fig. 3).
        World = "world",
    }
}

named_enum! {
    /// How a shadow-map lookup filters depth comparisons.
    pub enum Filter {
        /// One comparison against the nearest texel.
        None = "none",
        /// Bilinear percentage-closer filtering: the 2x2 comparisons around the sample, bilinearly
        /// weighted (what hardware comparison samplers do).
        Bilinear = "bilinear",
        /// A 3x3 box of bilinear comparisons, one texel apart.
        Pcf3x3 = "pcf3x3",
        /// A 4x4 grid of comparisons, each jittered inside its cell by a per-pixel hash.
        Pcf4x4Jitter = "pcf4x4-jitter",
        /// 16 Poisson-disk comparisons, rotated per pixel.
        Poisson16 = "poisson16",
    }
}

/// The bias of a shadow-map render: Vulkan's depth-bias parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DepthBias {
    /// The constant factor, in units of the depth format's resolution at the primitive's depth.
    pub constant: f32,
    /// The slope factor, times the primitive's largest depth slope per texel.
    pub slope: f32,
    /// Largest bias applied (0 for no clamp).
    pub clamp: f32,
}

impl DepthBias {
    /// No bias at all.
    pub const NONE: Self = Self { constant: 0.0, slope: 0.0, clamp: 0.0 };

    /// The bias for a mode and its two factors.
    #[must_use]
    pub fn from_mode(mode: BiasMode, constant: f32, slope: f32) -> Self {
        match mode {
            BiasMode::None | BiasMode::World => Self::NONE,
            BiasMode::Constant => Self { constant, slope: 0.0, clamp: 0.0 },
            BiasMode::Slope => Self { constant, slope, clamp: 0.0 },
        }
    }

    /// Vulkan's offset for a float depth buffer: `slope * max_slope + constant * 2^(e - 23)`, where `e` is
    /// the exponent of `max_abs_z`, then clamped when `clamp` is not 0.
    #[must_use]
    pub fn offset(&self, max_slope: f32, max_abs_z: f32) -> f32 {
        if self.constant == 0.0 && self.slope == 0.0 {
            return 0.0;
        }
        let r = if max_abs_z > 0.0 {
            // 2^(e - 23) with e = floor(log2 |z|): the spacing of f32 values at that magnitude.
            let e = ((max_abs_z.to_bits() >> 23) & 0xff) as i32 - 127;
            2f32.powi(e - 23)
        } else {
            2f32.powi(-149)
        };
        let o = self.slope * max_slope + self.constant * r;
        if self.clamp > 0.0 {
            o.min(self.clamp)
        } else if self.clamp < 0.0 {
            o.max(self.clamp)
        } else {
            o
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_specs() {
        let s = TechniqueSpec::parse("shadow-map:res=1024,filter=pcf3x3").unwrap();
        assert_eq!(s.name, "shadow-map");
        assert_eq!(s.values, vec![("res".into(), "1024".into()), ("filter".into(), "pcf3x3".into())]);
        assert_eq!(s.to_string(), "shadow-map:res=1024,filter=pcf3x3");
        assert_eq!(TechniqueSpec::parse("ray-traced").unwrap().values, vec![]);
        assert!(TechniqueSpec::parse("").is_err());
        assert!(TechniqueSpec::parse("a:b").is_err());
        assert!(TechniqueSpec::parse("a:=1").is_err());
        assert!(TechniqueSpec::parse("a:b=1,b=2").is_err());
        assert!(TechniqueSpec::parse("a b").is_err());
    }

    #[test]
    fn vulkan_float_bias() {
        let b = DepthBias::from_mode(BiasMode::Slope, 1.0, 2.0);
        // z = 0.75 has exponent -1, so r = 2^-24.
        assert_eq!(b.offset(0.0, 0.75), 2f32.powi(-24));
        assert_eq!(b.offset(0.5, 0.75), 1.0 + 2f32.powi(-24));
        assert_eq!(DepthBias::from_mode(BiasMode::None, 5.0, 5.0).offset(1.0, 1.0), 0.0);
    }
}
