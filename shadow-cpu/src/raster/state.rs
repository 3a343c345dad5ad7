//! Fixed-function state of a draw, shaped after Vulkan's pipeline state (DESIGN 4).

pub use shadow_core::technique::settings::DepthBias;

/// Which faces are discarded before rasterization.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CullMode {
    /// Keep both.
    None,
    /// Discard back faces.
    Back,
    /// Discard front faces.
    Front,
}

/// Which winding is the front face, seen in NDC (y up).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrontFace {
    /// Counter-clockwise (the default everywhere here).
    Ccw,
    /// Clockwise.
    Cw,
}

/// A comparison of a new value against a stored one.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CompareFn {
    /// Never passes.
    Never,
    /// new < stored.
    Less,
    /// new <= stored.
    LessEqual,
    /// new == stored.
    Equal,
    /// new > stored.
    Greater,
    /// new >= stored.
    GreaterEqual,
    /// new != stored.
    NotEqual,
    /// Always passes.
    Always,
}

impl CompareFn {
    /// Does `new` pass against `stored`?
    #[inline(always)]
    pub fn test<T: PartialOrd>(self, new: T, stored: T) -> bool {
        match self {
            Self::Never => false,
            Self::Less => new < stored,
            Self::LessEqual => new <= stored,
            Self::Equal => new == stored,
            Self::Greater => new > stored,
            Self::GreaterEqual => new >= stored,
            Self::NotEqual => new != stored,
            Self::Always => true,
        }
    }
}

/// What a stencil test outcome does to the stored value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StencilOp {
    /// Leave it.
    Keep,
    /// Set 0.
    Zero,
    /// Set the reference value.
    Replace,
    /// Add 1, saturating at 255.
    IncrementClamp,
    /// Subtract 1, saturating at 0.
    DecrementClamp,
    /// Flip every bit.
    Invert,
    /// Add 1 modulo 256.
    IncrementWrap,
    /// Subtract 1 modulo 256.
    DecrementWrap,
}

impl StencilOp {
    /// The new stored value, before the write mask.
    #[inline(always)]
    pub fn apply(self, stored: u8, reference: u8) -> u8 {
        match self {
            Self::Keep => stored,
            Self::Zero => 0,
            Self::Replace => reference,
            Self::IncrementClamp => stored.saturating_add(1),
            Self::DecrementClamp => stored.saturating_sub(1),
            Self::Invert => !stored,
            Self::IncrementWrap => stored.wrapping_add(1),
            Self::DecrementWrap => stored.wrapping_sub(1),
        }
    }
}

/// Stencil state for one facing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StencilFace {
    /// Test of `reference & read_mask` against `stored & read_mask`.
    pub compare: CompareFn,
    /// Op when the stencil test fails.
    pub fail: StencilOp,
    /// Op when the stencil test passes and the depth test fails.
    pub depth_fail: StencilOp,
    /// Op when both pass.
    pub pass: StencilOp,
}

impl StencilFace {
    /// Always passes, changes nothing.
    pub const KEEP: Self =
        Self { compare: CompareFn::Always, fail: StencilOp::Keep, depth_fail: StencilOp::Keep, pass: StencilOp::Keep };
}

/// Two-sided stencil state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StencilState {
    /// For front-facing primitives.
    pub front: StencilFace,
    /// For back-facing primitives.
    pub back: StencilFace,
    /// Bits read by the test.
    pub read_mask: u8,
    /// Bits an op may change.
    pub write_mask: u8,
    /// The reference value.
    pub reference: u8,
}

/// Depth test state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DepthState {
    /// Test of the fragment's depth against the stored depth.
    pub compare: CompareFn,
    /// Write the depth of fragments that pass.
    pub write: bool,
    /// Depth bias (Vulkan float formula).
    pub bias: DepthBias,
    /// Clamp depth to [0, 1] instead of clipping at the near and far planes.
    pub clamp: bool,
}

impl DepthState {
    /// Less, with writes: the usual opaque pass.
    pub const LESS_WRITE: Self = Self { compare: CompareFn::Less, write: true, bias: DepthBias::NONE, clamp: false };
    /// Less, without writes: volume and decal passes.
    pub const LESS_READ: Self = Self { compare: CompareFn::Less, write: false, bias: DepthBias::NONE, clamp: false };
}

/// Everything fixed-function about a draw.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RasterState {
    /// Face culling.
    pub cull: CullMode,
    /// Which winding is front.
    pub front_face: FrontFace,
    /// Depth test, or none (every fragment passes, nothing is written).
    pub depth: Option<DepthState>,
    /// Stencil test, or none.
    pub stencil: Option<StencilState>,
    /// Run depth and stencil tests before the fragment closure (the closure then cannot discard what the
    /// tests already wrote, and only runs for fragments that passed).
    pub early_tests: bool,
}

impl Default for RasterState {
    fn default() -> Self {
        Self {
            cull: CullMode::None,
            front_face: FrontFace::Ccw,
            depth: Some(DepthState::LESS_WRITE),
            stencil: None,
            early_tests: true,
        }
    }
}

/// What a draw did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RasterCounters {
    /// Triangles that reached setup (after clipping; one per clipped sub-triangle).
    pub triangles: u64,
    /// Fragments rasterized, before any test (under a computation mask: the masked-in ones only).
    pub fragments: u64,
    /// Fragments that passed the depth and stencil tests.
    pub passed: u64,
    /// Fragments whose stencil op was anything but Keep.
    pub stencil_updates: u64,
}

impl std::ops::AddAssign for RasterCounters {
    fn add_assign(&mut self, o: Self) {
        self.triangles += o.triangles;
        self.fragments += o.fragments;
        self.passed += o.passed;
        self.stencil_updates += o.stencil_updates;
    }
}
