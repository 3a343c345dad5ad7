//! The declarative settings macros: [`named_enum!`](crate::named_enum) for a setting's choices,
//! [`technique_settings!`](crate::technique_settings) for a technique's table, and
//! [`setting_group!`](crate::setting_group) for keys read together as one of its fields.

/// Declares a settings enum with its text names, `FromStr` (errors list the names) and `Display`.
#[macro_export]
macro_rules! named_enum {
    ($(#[$m:meta])* pub enum $name:ident { $($(#[$vm:meta])* $variant:ident = $text:literal),+ $(,)? }) => {
        $(#[$m])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum $name { $($(#[$vm])* $variant),+ }

        impl $name {
            /// Every variant's name.
            pub const NAMES: &'static [&'static str] = &[$($text),+];
            /// The variant's name.
            #[must_use]
            pub fn as_str(self) -> &'static str {
                match self { $(Self::$variant => $text),+ }
            }
        }

        impl ::std::str::FromStr for $name {
            type Err = String;
            fn from_str(s: &str) -> Result<Self, String> {
                match s { $($text => Ok(Self::$variant),)+ _ => Err(format!("one of {}", Self::NAMES.join(", "))) }
            }
        }

        impl ::std::fmt::Display for $name {
            fn fmt(&self, f: &mut ::std::fmt::Formatter<'_>) -> ::std::fmt::Result {
                f.write_str(self.as_str())
            }
        }

        impl $crate::technique::settings::SettingValue for $name {
            fn from_setting(text: &str, _: &$crate::technique::settings::SettingKey) -> Option<Self> {
                text.parse().ok()
            }
            fn to_setting(&self) -> String {
                self.as_str().to_string()
            }
        }
    };
}

/// Declares a technique's settings once: each field with the key (or group of keys, such as a depth
/// map's) it reads, in the order the canonical settings string lists them. The struct, its
/// [`TechniqueSettings`](crate::technique::settings::TechniqueSettings) (keys, parsing with every value checked against its key's kind, printing) and,
/// when given, the light kinds it takes and a check across fields all come from this one table.
///
/// ```
/// use shadow_core::technique::settings::{SettingKey, TechniqueSettings};
///
/// shadow_core::technique_settings! {
///     /// A technique with one setting.
///     pub struct Example {
///         /// Height of the receiving plane.
///         pub plane_y: f32 = SettingKey::float("plane_y", "0", -1e6, 1e6, "height of the plane"),
///     }
/// }
///
/// let e = Example::parse("example", &[("plane_y".into(), "2.5".into())]).unwrap();
/// assert_eq!(e.plane_y, 2.5);
/// assert_eq!(e.settings_string(), "plane_y=2.5");
/// assert!(Example::parse("example", &[("plane_y".into(), "1e9".into())]).is_err());
/// ```
#[macro_export]
macro_rules! technique_settings {
    (
        $(#[$m:meta])*
        pub struct $name:ident {
            $( $(#[$fm:meta])* pub $field:ident : $ty:ty = $key:expr ),+ $(,)?
        }
        $( lights = $lights:expr; )?
        $( check = $check:expr; )?
    ) => {
        $(#[$m])*
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub struct $name { $( $(#[$fm])* pub $field: $ty ),+ }

        impl $crate::technique::settings::TechniqueSettings for $name {
            $( const LIGHTS: $crate::technique::LightKinds = $lights; )?

            fn keys() -> &'static [$crate::technique::settings::SettingKey] {
                static KEYS: ::std::sync::OnceLock<::std::vec::Vec<$crate::technique::settings::SettingKey>> =
                    ::std::sync::OnceLock::new();
                KEYS.get_or_init(|| {
                    let mut keys = ::std::vec::Vec::new();
                    $( keys.extend_from_slice($crate::technique::settings::KeySet::key_list(&$key)); )+
                    keys
                })
            }

            fn from_values(
                v: &$crate::technique::settings::Values<'_>,
            ) -> Result<Self, $crate::technique::settings::SettingsError> {
                let mut keys = Self::keys();
                let settings = Self {
                    $( $field: {
                        let (own, rest) = keys.split_at($crate::technique::settings::KeySet::key_list(&$key).len());
                        keys = rest;
                        <$ty as $crate::technique::settings::SettingField>::read(v, own)?
                    } ),+
                };
                let _ = keys;
                $( ($check)(&settings, v)?; )?
                Ok(settings)
            }

            fn to_values(&self) -> Vec<String> {
                let mut out = Vec::new();
                $( $crate::technique::settings::SettingField::write(&self.$field, &mut out); )+
                out
            }
        }
    };
}

/// Declares settings read together as one field of a [`technique_settings!`] table, such as the knobs
/// of one backend alone: the struct, its keys in order (`KEYS`, the field's keys in the table) and its
/// [`SettingField`](crate::technique::settings::SettingField) reading and printing.
///
/// ```
/// use shadow_core::technique::settings::{SettingKey, TechniqueSettings};
///
/// shadow_core::setting_group! {
///     /// What one backend alone reads.
///     pub struct GpuOptions {
///         /// Workgroup size.
///         pub group: u32 = SettingKey::int("group", "64", 1, 1024, "GPU workgroup size"),
///     }
/// }
///
/// shadow_core::technique_settings! {
///     /// A technique with a shared setting and a GPU one.
///     pub struct Example {
///         /// Height of the receiving plane.
///         pub plane_y: f32 = SettingKey::float("plane_y", "0", -1e6, 1e6, "height of the plane"),
///         /// The GPU's own knobs.
///         pub gpu: GpuOptions = GpuOptions::KEYS,
///     }
/// }
///
/// let e = Example::parse("example", &[("group".into(), "128".into())]).unwrap();
/// assert_eq!(e.gpu.group, 128);
/// assert_eq!(e.settings_string(), "plane_y=0,group=128");
/// ```
#[macro_export]
macro_rules! setting_group {
    (
        $(#[$m:meta])*
        pub struct $name:ident {
            $( $(#[$fm:meta])* pub $field:ident : $ty:ty = $key:expr ),+ $(,)?
        }
    ) => {
        $(#[$m])*
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub struct $name { $( $(#[$fm])* pub $field: $ty ),+ }

        impl $name {
            /// The group's keys, in the order of its fields.
            pub const KEYS: &'static [$crate::technique::settings::SettingKey] = &[$($key),+];
        }

        impl $crate::technique::settings::SettingField for $name {
            fn read(
                v: &$crate::technique::settings::Values<'_>,
                _: &[$crate::technique::settings::SettingKey],
            ) -> Result<Self, $crate::technique::settings::SettingsError> {
                Ok(Self { $( $field: v.read(&$key)? ),+ })
            }

            fn write(&self, out: &mut Vec<String>) {
                $( out.push($crate::technique::settings::SettingValue::to_setting(&self.$field)); )+
            }
        }
    };
}
