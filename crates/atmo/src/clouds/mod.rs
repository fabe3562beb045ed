//! Clouds lit by a moving sun, after Shimada, Shinya, Shiraishi and Harada, "Fast
//! rendering of dynamic clouds using GPU shaders" (cited as `clouds (n)`): a cloud is a
//! set of Gaussian particles ([`particles`], made by [`generator`]); the light reaching
//! every part of it is kept in a 3-D intensity buffer oriented to the sun ([`buffer`]),
//! filled in any particle order by the multiplicative form (7).
//!
//! [`harris`] is the baseline light pass the buffer is measured against; [`render`](mod@render)
//! draws the billboards, lit by the sun through the buffer, by every order of it
//! ([`octaves`]) and by the sky ([`sky_light`]); [`shadow`] is the cloud's shadow on the
//! ground; [`files`] reads and writes particles.

pub mod buffer;
pub mod files;
pub mod generator;
pub mod harris;
pub mod octaves;
pub mod particles;
pub mod render;
pub mod shadow;
pub mod sky_light;
pub mod transfer;
mod transfer_fitted;

pub use buffer::{IntensityBuffer, Splat};
pub use generator::Cumulus;
pub use octaves::Octaves;
pub use particles::Particle;
pub use render::{
    dims_the_sky, needs_depths, render, render_with_depths, AerialHaze, CloudLight, Scattering,
};
pub use shadow::CloudShadow;
pub use sky_light::{vertical_depths, SkyDimming, SkyLight};
pub use transfer::{CloudDepths, TransferTable};

/// Eight values of the drawing's per-pixel quantities, one per pixel of a billboard's
/// row: the hot loop of [`render`](mod@render) takes a row eight pixels at a time, its
/// `exp`s vectorised (glibc's `expf` was a sixth of the frame, one at a time).
pub(crate) type Lanes = wide::f32x8;

/// How many pixels [`Lanes`] hold.
pub(crate) const LANES: usize = 8;

/// `e^x` for `x <= 0` in lanes, within 3e-7 of it; 0 below -87.3 (where `e^x` leaves the
/// normal numbers). Every `exp` of the drawing is of such an argument (optical depths
/// and `ln Gamma`, all negated). Written here rather than taking wide's `exp`, which
/// handles infinities, NaNs, overflow and subnormals in some twenty more operations and
/// is not inlined: it was a fifth of the frame, and this took the bench's frame from
/// 274 to 226 ms. Cephes' `expf`: `x = n ln 2 + r`, `|r| <= ln 2 / 2`, `e^r` by its
/// Taylor polynomial to `r^6` (error under `r^7 / 7! = 1.2e-7` of it), times `2^n`
/// built in the exponent's bits.
#[inline(always)]
pub(crate) fn exp_lanes(x: Lanes) -> Lanes {
    const LOWEST: f32 = -87.3;
    // Rounded to the nearest whole number by adding and taking away 1.5 * 2^23.
    const ROUND: f32 = 12_582_912.0;
    let splat = Lanes::splat;
    let x = x.fast_max(splat(LOWEST));
    let n = (x * splat(std::f32::consts::LOG2_E) + splat(ROUND)) - splat(ROUND);
    // ln 2 in two parts, the first exact in a few bits, so `n ln 2` loses nothing.
    let r = x - n * splat(0.693_359_4) - n * splat(-2.121_944_4e-4);
    let p = splat(1.0 / 720.0);
    let p = splat(1.0 / 120.0) + r * p;
    let p = splat(1.0 / 24.0) + r * p;
    let p = splat(1.0 / 6.0) + r * p;
    let p = splat(0.5) + r * p;
    let p = Lanes::ONE + r + r * r * p;
    let two_n: Lanes = bytemuck::cast((n.trunc_int() + wide::i32x8::splat(127)) << 23u32);
    x.simd_gt(splat(LOWEST)).select(p * two_n, Lanes::ZERO)
}

/// Lane `0` of `v`: what a one-value call of a lanes function returns.
#[inline]
pub(crate) fn first(v: Lanes) -> f32 {
    v.to_array()[0]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Within 3e-7 of `e^x` (double precision) over [-87.3, 0], 0 below; exact at 0.
    #[test]
    fn exp_lanes_is_exp_for_arguments_up_to_zero() {
        let mut worst = 0.0f64;
        for k in 0..=200_000u32 {
            let x = -87.29 * k as f32 / 200_000.0;
            let got = first(exp_lanes(Lanes::splat(x))) as f64;
            let want = (x as f64).exp();
            worst = worst.max((got - want).abs() / want);
        }
        assert!(worst < 3e-7, "{worst}");
        assert_eq!(first(exp_lanes(Lanes::ZERO)), 1.0);
        assert_eq!(first(exp_lanes(Lanes::splat(-90.0))), 0.0);
        assert_eq!(first(exp_lanes(Lanes::splat(f32::NEG_INFINITY))), 0.0);
    }
}
