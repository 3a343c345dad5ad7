//! The moments each map keeps and what a filtered texel of them says about the receiver (twins: the
//! functions of the same names in query.wgsl and build.wgsl). Depths are normalized linear depths in
//! [0, 1] along the light's axis.

/// The smallest variance a filtered texel of normalized depth is given. Averaging a mip level's worth of
/// f32 squares leaves errors near 1e-7 in `E[d^2] - E[d]^2`; 1e-6 keeps those from reading as
/// depth spread, and costs a receiver about 1e-3 of the depth range (2 cm over a 20 m light) before
/// Chebyshev's bound darkens it.
pub const MIN_VARIANCE: f32 = 1e-6;

/// Which moments a texel keeps.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MomentKind {
    /// `(d, d^2)` (Donnelly-Lauritzen 2006).
    Variance,
    /// `(e^(c+ x), e^(2 c+ x), -e^(-c- x), e^(-2 c- x))` with `x = 2d - 1` (Lauritzen-McCool 2008): two
    /// variance maps of warped depth, whose warps push a blocker and a receiver apart so the bound bleeds
    /// less.
    ExponentialVariance {
        /// `c+`.
        positive: f32,
        /// `c-`.
        negative: f32,
    },
    /// `(x, x^2, x^3, x^4)` with `x = 2d - 1` and the Hamburger bound (Peters-Klein 2015), moment bias
    /// `bias`.
    Hamburger {
        /// The moment bias alpha.
        bias: f32,
    },
}

/// Chebyshev's one-tailed bound on the fraction of a distribution of mean `mean` and mean square
/// `mean_sq` at or beyond `t`: 1 when `t` is not beyond the mean, else `s^2 / (s^2 + (t - mean)^2)`
/// with the variance `s^2` at least `min_variance`.
#[must_use]
pub fn chebyshev(mean: f32, mean_sq: f32, t: f32, min_variance: f32) -> f32 {
    if t <= mean {
        return 1.0;
    }
    let variance = (mean_sq - mean * mean).max(min_variance);
    let d = t - mean;
    variance / (variance + d * d)
}

/// `(v - lo) / (hi - lo)` clamped to [0, 1].
#[must_use]
pub fn linstep(lo: f32, hi: f32, v: f32) -> f32 {
    ((v - lo) / (hi - lo)).clamp(0.0, 1.0)
}

/// The moments the Hamburger bias mixes in (Peters-Klein 2015): those of atoms at -1, 0 and 1 weighing
/// 0.315, 0.37 and 0.315, three points, so the mixed Hankel matrix stays positive definite however
/// narrow the filtered distribution (a two-point mixture would leave it singular for a single depth).
const HAMBURGER_BIAS_MOMENTS: [f32; 4] = [0.0, 0.63, 0.0, 0.63];

/// The Hamburger 4MSM shadow intensity (Peters-Klein 2015, algorithm 2): the fraction of the
/// distribution with moments `b` (of depths in [-1, 1]) nearer the light than `z`, as the canonical
/// representation through `z` bounds it, after mixing `b` with `HAMBURGER_BIAS_MOMENTS` by `alpha`.
#[must_use]
pub fn hamburger_shadow(b: [f32; 4], z: f32, alpha: f32) -> f32 {
    let b: [f32; 4] = std::array::from_fn(|k| (1.0 - alpha) * b[k] + alpha * HAMBURGER_BIAS_MOMENTS[k]);
    // B = L D L^T of the Hankel matrix [[1, b1, b2], [b1, b2, b3], [b2, b3, b4]]; solve B c = (1, z, z^2).
    let d22 = (b[1] - b[0] * b[0]).max(1e-20);
    let l32 = (b[2] - b[0] * b[1]) / d22;
    let d33 = (b[3] - b[1] * b[1] - l32 * l32 * d22).max(1e-20);
    let w2 = z - b[0];
    let w3 = z * z - b[1] - l32 * w2;
    let c3 = w3 / d33;
    let c2 = w2 / d22 - l32 * c3;
    let c1 = 1.0 - b[0] * c2 - b[1] * c3;
    // The other two support points: the roots z2 <= z3 of c3 x^2 + c2 x + c1. Where c3 rounds to 0 (a
    // receiver just behind a narrow distribution can make z^2 - b2 - l32 w2 cancel exactly) one root is
    // at infinity; a c3 kept 1e-7 of the others away puts it at 1e7 instead, where the formulas below
    // take their limits rather than inf / inf.
    let least = 1e-7 * (c1.abs() + c2.abs());
    let c3 = if c3 >= 0.0 { c3.max(least) } else { c3.min(-least) };
    let p = c2 / c3;
    let q = c1 / c3;
    let r = (0.25 * p * p - q).max(0.0).sqrt();
    let (z2, z3) = (-0.5 * p - r, -0.5 * p + r);
    if z <= z2 {
        0.0
    } else if z <= z3 {
        ((z * z3 - b[0] * (z + z3) + b[1]) / ((z3 - z2) * (z - z2))).clamp(0.0, 1.0)
    } else {
        (1.0 - (z2 * z3 - b[0] * (z2 + z3) + b[1]) / ((z - z2) * (z - z3))).clamp(0.0, 1.0)
    }
}

impl MomentKind {
    /// The moments of one depth `d`.
    #[must_use]
    pub fn encode(self, d: f32) -> [f32; 4] {
        match self {
            Self::Variance => [d, d * d, 0.0, 0.0],
            Self::ExponentialVariance { positive, negative } => {
                let (p, n) = self.warp(d, positive, negative);
                [p, p * p, n, n * n]
            }
            Self::Hamburger { .. } => {
                // Centred on 0, where f32 keeps the most digits of the moments' differences.
                let x = 2.0 * d - 1.0;
                let x2 = x * x;
                [x, x2, x2 * x, x2 * x2]
            }
        }
    }

    /// The two warps of `d`: `e^(c+ x)` and `-e^(-c- x)`, `x = 2d - 1`.
    fn warp(self, d: f32, positive: f32, negative: f32) -> (f32, f32) {
        let x = 2.0 * d - 1.0;
        ((positive * x).exp(), -(-negative * x).exp())
    }

    /// Visibility of a receiver at depth `t` from the moments `m` averaged over its filter region.
    #[must_use]
    pub fn visibility(self, m: [f32; 4], t: f32) -> f32 {
        match self {
            Self::Variance => chebyshev(m[0], m[1], t, MIN_VARIANCE),
            Self::ExponentialVariance { positive, negative } => {
                let (p, n) = self.warp(t, positive, negative);
                // The minimum variance carried through each warp by its slope, d(warp)/dd.
                let (sp, sn) = (2.0 * positive * p, 2.0 * negative * n);
                chebyshev(m[0], m[1], p, MIN_VARIANCE * sp * sp).min(chebyshev(m[2], m[3], n, MIN_VARIANCE * sn * sn))
            }
            Self::Hamburger { bias } => 1.0 - hamburger_shadow(m, 2.0 * t - 1.0, bias),
        }
    }

    /// The GPU's description: a kind code (0 variance, 1 exponential, 2 Hamburger) and its two parameters.
    #[must_use]
    pub fn code(self) -> (f32, f32, f32) {
        match self {
            Self::Variance => (0.0, 0.0, 0.0),
            Self::ExponentialVariance { positive, negative } => (1.0, positive, negative),
            Self::Hamburger { bias } => (2.0, bias, 0.0),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const KINDS: [MomentKind; 3] = [
        MomentKind::Variance,
        MomentKind::ExponentialVariance { positive: 40.0, negative: 5.0 },
        MomentKind::Hamburger { bias: 3e-5 },
    ];

    /// The moments of depths `d` with weights `w`.
    fn mix(kind: MomentKind, parts: &[(f32, f32)]) -> [f32; 4] {
        let mut m = [0.0; 4];
        for &(d, w) in parts {
            for (a, e) in m.iter_mut().zip(kind.encode(d)) {
                *a += w * e;
            }
        }
        m
    }

    #[test]
    fn one_depth_shadows_what_lies_behind_it_and_nothing_before() {
        for kind in KINDS {
            let m = mix(kind, &[(0.4, 1.0)]);
            assert_eq!(kind.visibility(m, 0.3), 1.0, "{kind:?} in front");
            assert!(kind.visibility(m, 0.4) > 0.95, "{kind:?} on the surface: {}", kind.visibility(m, 0.4));
            assert!(kind.visibility(m, 0.6) < 0.01, "{kind:?} behind: {}", kind.visibility(m, 0.6));
        }
    }

    #[test]
    fn half_covered_regions_are_half_lit_within_each_bound() {
        // A blocker at 0.3 over half the region, the receiver's own plane at 0.7 over the other half.
        for kind in KINDS {
            let m = mix(kind, &[(0.3, 0.5), (0.7, 0.5)]);
            let v = kind.visibility(m, 0.7);
            // Chebyshev's is an upper bound (light bleeds in); 4MSM's reconstruction is near exact.
            assert!((0.49..0.75).contains(&v), "{kind:?}: {v}");
        }
        let msm = MomentKind::Hamburger { bias: 3e-5 };
        assert!((msm.visibility(mix(msm, &[(0.3, 0.5), (0.7, 0.5)]), 0.7) - 0.5).abs() < 0.05);
    }

    #[test]
    fn the_exponential_warp_bleeds_less_than_variance_behind_two_blockers() {
        // The classic bleeding case: blockers at 0.2 and 0.5 in a region, a receiver at 0.55 right
        // behind the second. Truth: fully shadowed.
        let (vsm, evsm) = (KINDS[0], KINDS[1]);
        let parts = [(0.2, 0.5), (0.5, 0.5)];
        let v = vsm.visibility(mix(vsm, &parts), 0.55);
        let e = evsm.visibility(mix(evsm, &parts), 0.55);
        assert!(v > 0.3, "variance bleeds: {v}");
        assert!(e < 0.1 * v, "exponential: {e} against {v}");
        assert!(linstep(0.2, 1.0, 0.1) == 0.0 && (linstep(0.2, 1.0, 0.6) - 0.5).abs() < 1e-6);
    }

    #[test]
    fn a_region_of_the_receivers_own_plane_is_lit() {
        // A plane tilted to the light: the region's depths spread evenly around the receiver's. The
        // variance bounds read the mean as lit; the Hamburger reconstruction, smoothed by its moment
        // bias, leaves the plane darkened by about a tenth (the plane's nearer half shows through: the
        // price of a bound sharp enough to stop bleeding).
        let parts: Vec<_> = (0..9).map(|i| (0.46 + 0.01 * i as f32, 1.0 / 9.0)).collect();
        for (kind, least) in KINDS.into_iter().zip([0.99, 0.9, 0.85]) {
            let v = kind.visibility(mix(kind, &parts), 0.5);
            assert!(v > least, "{kind:?}: {v}");
        }
    }
}
