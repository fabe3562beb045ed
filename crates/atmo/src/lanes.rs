//! Values a loop takes several at a time, in the three shapes atmo's hot loops have:
//!
//! - **Spectra, four wavelengths to a [`Lane`]** (`glam::Vec4`): the sky's per-sample
//!   loops over a spectrum whose length is known only at run time.
//! - **Pixels, eight to a [`Lanes`]** (`wide::f32x8`): the clouds' drawing and light
//!   passes, whose `exp`s go eight at a time ([`exp_lanes`]).
//! - **Pixels, sixteen to plain arrays** (`[f32; 16]`, [`LANES_OF_RAYS`]): the sample
//!   planes' sub-sample loops, written over arrays that the compiler vectorises.
//!
//! They are three because their data differ (a spectrum's channels; a row's pixels with
//! gathers from a 3-D buffer; neighbouring rays with per-lane table lookups); the
//! widths were each measured on their loop (docs/decisions.md). This module is the one
//! place their types and helpers live.

/// Spectra in the per-sample loops are packed four wavelengths to a SIMD lane, the last
/// lane padded with zeros: with a channel count known only at run time the compiler
/// emits scalar code otherwise (measured: the order-2 skylight map 7.0 -> 5.0 ms).
pub type Lane = glam::Vec4;

/// Lanes that hold `channels` wavelengths.
pub fn lanes(channels: usize) -> usize {
    channels.div_ceil(4)
}

/// Packs `values` (one a channel) into `out` lanes, padding with zeros.
pub fn pack(values: &[f32], out: &mut [Lane]) {
    for (lane, chunk) in out.iter_mut().zip(values.chunks(4)) {
        let mut v = [0.0; 4];
        v[..chunk.len()].copy_from_slice(chunk);
        *lane = Lane::from_array(v);
    }
}

/// Adds packed `lanes` to `out` (one value a channel).
pub fn unpack_add(lanes: &[Lane], out: &mut [f32]) {
    for (chunk, lane) in out.chunks_mut(4).zip(lanes) {
        for (o, v) in chunk.iter_mut().zip(lane.to_array()) {
            *o += v;
        }
    }
}

/// Neighbouring pixels that go through the sample planes' sub-samples together
/// ([`crate::shafts::planes`]): the width of its array loops.
pub const LANES_OF_RAYS: usize = 16;

/// Eight values of the clouds' per-pixel quantities, one per pixel of a billboard's
/// row: the hot loop of [`crate::clouds::render`](mod@crate::clouds::render) takes a
/// row eight pixels at a time, its `exp`s vectorised (glibc's `expf` was a sixth of the
/// frame, one at a time).
pub type Lanes = wide::f32x8;

/// How many pixels [`Lanes`] hold.
pub const LANES: usize = 8;

/// `e^x` for `x <= 0` in lanes, within 3e-7 of it; 0 below -87.3 (where `e^x` leaves the
/// normal numbers). Every `exp` of the drawing is of such an argument (optical depths
/// and `ln Gamma`, all negated). Written here rather than taking wide's `exp`, which
/// handles infinities, NaNs, overflow and subnormals in some twenty more operations and
/// is not inlined: it was a fifth of the frame, and this took the bench's frame from
/// 274 to 226 ms. Cephes' `expf`: `x = n ln 2 + r`, `|r| <= ln 2 / 2`, `e^r` by its
/// Taylor polynomial to `r^6` (error under `r^7 / 7! = 1.2e-7` of it), times `2^n`
/// built in the exponent's bits.
#[inline(always)]
pub fn exp_lanes(x: Lanes) -> Lanes {
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
pub fn first(v: Lanes) -> f32 {
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
