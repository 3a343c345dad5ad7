//! shadow-core: everything the shadow backends share.
//!
//! The scene graph ([`scene`]), model loading ([`assets`]), procedural meshes ([`procedural`]) and the
//! built-in test scenes of the papers ([`scenes`]); the per-frame geometry kernels that both backends call
//! ([`geometry`]: adjacency, silhouettes, shadow-volume extrusion); fitted light views ([`light`]); the
//! backend-neutral technique traits and settings ([`technique`]); images, metrics and counters.
//!
//! Nothing here needs a GPU. The conventions both backends follow (DESIGN section 4) are written down
//! where they are implemented: light-space lookups in [`light`], the metrics in [`metrics`].

pub mod affine;
pub mod assets;
pub mod bounds;
pub mod deform;
pub mod frame;
pub mod geometry;
pub mod hash;
pub mod image;
pub mod inspect;
pub mod light;
pub mod lookup;
pub mod material;
pub mod mesh;
pub mod metrics;
pub mod procedural;
pub mod scene;
pub mod scenes;
pub mod script;
pub mod stats;
pub mod technique;
pub mod text;

pub use bounds::Aabb;
pub use frame::{FrameInputs, Instance};
pub use glam;
pub use image::Image;
pub use light::LightView;
pub use mesh::{Mesh, MeshError};
pub use scene::{
    Camera, CameraKey, Light, LightKey, LightKind, LightShadow, Material, MaterialKey, MeshKey, Node, NodeKey, Scene,
    TextureKey,
};
pub mod shading;
