//! Spotlights: a point source with a beam, a soft edge and an optional gobo, the
//! "light map" the paper projects onto the sample planes (shafts 4.1). Together they give
//! `I_l`, the intensity the light sends toward a point, in shafts (2) and (5).
//!
//! Light space: the origin at the lamp, `z` along the beam axis, `y` toward the light's
//! `up` (made perpendicular to the axis), and `x = z x up` so that, seen from behind
//! the lamp looking along the beam, `x` points right (a left-handed triple, as a
//! screen's right, up and depth). A point `(x, y, z)` with
//! `z > 0` projects to `(u, v) = (x, y) / (z tan(field / 2))`, the square `[-1, 1]^2`
//! circumscribing the field cone; that square carries the gobo image (its top row at
//! `v = 1`) and the shadow map.

use std::sync::Arc;

use glam::{DVec3, Mat3, Vec3};

use super::photometry::Photometry;
use super::tables::IntensityMap;
use crate::fast::fast_atan;

/// How the intensity falls from full at the beam edge to zero at the field edge.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Falloff {
    /// Linear in the off-axis angle.
    Linear,
    /// Smoothstep (`3x^2 - 2x^3`) in the off-axis angle: no visible edge at either end.
    Smooth,
}

impl Falloff {
    /// The edge's profile at `x` in [0, 1], the fraction of the way from the field's
    /// edge (0) to the beam's (1).
    #[inline(always)]
    pub fn shape(self, x: f32) -> f32 {
        match self {
            Falloff::Linear => x,
            Falloff::Smooth => x * x * (3.0 - 2.0 * x),
        }
    }
}

/// How a gobo image is looked up.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sampling {
    /// The texel under the point: hard-edged patterns as they are in the image.
    Nearest,
    /// Bilinear between the four nearest texels.
    Bilinear,
}

/// A gobo: the pattern a spotlight projects, linear RGB transmittance in [0, 1].
#[derive(Debug, Clone, PartialEq)]
pub struct Gobo {
    /// Width in texels.
    width: usize,
    /// Height in texels.
    height: usize,
    /// Row-major texels, top row first, as the image's 8-bit sRGB values: 3 bytes a
    /// texel (a 4096^2 gobo holds 50 MB, where linear f32 took 200 MB); [`Gobo::texel`]
    /// is the linear transmittance. Private, with the size, so that [`Gobo::dark`]
    /// always describes them. Shared: the lights and wheel slots that project one file,
    /// and every pose of a head, hold one copy.
    srgb: Arc<[[u8; 3]]>,
    /// Lookup.
    pub sampling: Sampling,
    /// How far the gobo is turned in its holder, radians, counterclockwise seen from
    /// behind the lamp (a rotating gobo of a moving head).
    pub rotation: f32,
    /// Per block of [`Gobo::BLOCK`]^2 texels, row-major: whether every texel a lookup
    /// in the block reads (the block and one texel around it) is black, so that
    /// [`Gobo::sample_turned`] gives 0 there without reading four texels. A gobo is
    /// mostly metal: the stage's dots leave two thirds of the beam dark.
    dark: Arc<[bool]>,
}

impl Gobo {
    /// The side of [`Gobo::dark`]'s blocks, texels.
    const BLOCK: usize = 4;

    /// A gobo of `width x height` texels, row-major from the top, as 8-bit sRGB,
    /// unturned. Panics unless `srgb` holds `width * height` texels.
    pub fn new(width: usize, height: usize, srgb: Vec<[u8; 3]>, sampling: Sampling) -> Gobo {
        assert_eq!(srgb.len(), width * height, "a {width} x {height} gobo");
        let b = Self::BLOCK;
        let (bw, bh) = (width.div_ceil(b), height.div_ceil(b));
        // A block's texels and one around it, clipped to the image: a lookup clamps to
        // the edge, so a point beyond it reads the edge's texels, which are in its block.
        let dark = (0..bw * bh)
            .map(|k| {
                let (bx, by) = (k % bw, k / bw);
                let cols = (bx * b).saturating_sub(1)..((bx + 1) * b + 1).min(width);
                let rows = (by * b).saturating_sub(1)..((by + 1) * b + 1).min(height);
                rows.into_iter().all(|y| {
                    srgb[y * width + cols.start..y * width + cols.end]
                        .iter()
                        .all(|t| *t == [0; 3])
                })
            })
            .collect();
        Gobo {
            width,
            height,
            srgb: srgb.into(),
            sampling,
            rotation: 0.0,
            dark,
        }
    }

    /// Width and height in texels.
    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// The texels, row-major from the top, as the image's 8-bit sRGB values.
    pub fn srgb(&self) -> &[[u8; 3]] {
        &self.srgb
    }

    /// The same texels looked up with `sampling` (shared, not copied).
    pub fn with_sampling(&self, sampling: Sampling) -> Gobo {
        Gobo {
            sampling,
            ..self.clone()
        }
    }

    /// What the texels hold, bytes (3 a texel, and the dark-block flags).
    pub fn bytes(&self) -> u64 {
        (std::mem::size_of_val(&*self.srgb) + self.dark.len()) as u64
    }

    /// The linear transmittance of texel `k` (row-major).
    #[inline]
    pub fn texel(&self, k: usize) -> Vec3 {
        Self::linear(crate::image::srgb8_table(), self.srgb[k])
    }

    #[inline(always)]
    fn linear(table: &[f32; 256], [r, g, b]: [u8; 3]) -> Vec3 {
        Vec3::new(table[r as usize], table[g as usize], table[b as usize])
    }

    /// The transmittance at `(u, v)` in `[-1, 1]^2` (`v = 1` at the image's top),
    /// the image turned by [`Gobo::rotation`].
    #[inline]
    pub fn sample(&self, u: f32, v: f32) -> Vec3 {
        self.sample_turned(u, v, self.turn())
    }

    /// `(sin, cos)` of [`Gobo::rotation`], for [`Gobo::sample_turned`]: a caller that
    /// samples many points of one frame takes them once.
    pub fn turn(&self) -> (f32, f32) {
        self.rotation.sin_cos()
    }

    /// [`Gobo::sample`] with the rotation's `(sin, cos)` from [`Gobo::turn`]. Always
    /// inlined: the plane method's sub-sample loop calls it for every lit sub-sample
    /// of a gobo's beam (the show 122 -> 116 ms a frame).
    #[inline(always)]
    pub fn sample_turned(&self, u: f32, v: f32, (sin, cos): (f32, f32)) -> Vec3 {
        // The image's point that the turn brings to (u, v): turned back (unturned, the
        // same u and v to the bit).
        let (u, v) = (cos * u + sin * v, cos * v - sin * u);
        let x = (0.5 * (u + 1.0)) * self.width as f32;
        let y = (0.5 * (1.0 - v)) * self.height as f32;
        let (w, h) = (self.width as isize, self.height as isize);
        // Every texel either lookup reads is the texel under the point (clamped to the
        // image) or a neighbour of it: in that texel's block or the ring around it.
        let b = Self::BLOCK as isize;
        let (bx, by) = (
            (x as isize).clamp(0, w - 1) / b,
            (y as isize).clamp(0, h - 1) / b,
        );
        if self.dark[(by * self.width.div_ceil(Self::BLOCK) as isize + bx) as usize] {
            return Vec3::ZERO;
        }
        // The decoding table once a lookup, not once a channel (a per-sample hot path).
        let table = crate::image::srgb8_table();
        let at = |i: isize, j: isize| {
            Self::linear(
                table,
                self.srgb[(j.clamp(0, h - 1) * w + i.clamp(0, w - 1)) as usize],
            )
        };
        match self.sampling {
            Sampling::Nearest => at(x.floor() as isize, y.floor() as isize),
            Sampling::Bilinear => {
                let (fx, fy) = (x - 0.5, y - 0.5);
                let (i, j) = (fx.floor(), fy.floor());
                let (a, b) = (fx - i, fy - j);
                let (i, j) = (i as isize, j as isize);
                (at(i, j) * (1.0 - a) + at(i + 1, j) * a) * (1.0 - b)
                    + (at(i, j + 1) * (1.0 - a) + at(i + 1, j + 1) * a) * b
            }
        }
    }
}

/// What shapes a spotlight's intensity over its field: `I_l` is
/// [`Spotlight::intensity`] times the profile (in [0, 1]) times the gobo.
#[derive(Debug, Clone, PartialEq)]
pub enum Profile {
    /// Full inside the beam, zero outside the field, the falloff between.
    Beam {
        /// Half the beam angle (full intensity inside), radians, at most the field's.
        beam_half: f32,
        /// Edge between beam and field.
        falloff: Falloff,
    },
    /// A measured distribution from a photometric file, divided by its peak (which
    /// [`Spotlight::intensity`] carries). Zero past the field, which is where the
    /// file's light ends (or 85 degrees off the axis, the most a spotlight's square
    /// light map holds).
    Measured(Arc<Photometry>),
}

/// One spotlight, validated.
#[derive(Debug, Clone, PartialEq)]
pub struct Spotlight {
    /// Lamp position, m.
    pub position: Vec3,
    /// World to light space: rows are the light's `x`, `y` and `z` (beam axis).
    pub light_from_world: Mat3,
    /// Intensity per channel where the profile is 1 (colour times intensity, or times
    /// the measured peak): cd or W/sr.
    pub intensity: Vec3,
    /// Half the field angle (zero outside), radians, below pi/2.
    pub field_half: f32,
    /// The intensity's shape over the field.
    pub profile: Profile,
    /// Projected pattern, if any.
    pub gobo: Option<Gobo>,
    /// The profile tabulated for the plane method (built once with the light).
    pub intensity_map: IntensityMap,
    /// `tan(field / 2)`.
    tan_field: f32,
    /// `tan(beam / 2)` (0 for a measured profile: no region of constant intensity).
    tan_beam: f32,
    /// 1 / the measured peak, 1/cd (1 for a beam).
    inv_peak: f32,
}

impl Spotlight {
    /// A spotlight at `position` whose beam is the light-space `z` of
    /// `light_from_world` (see [`light_frame`]); `field_half` in radians in
    /// `(0, pi/2)`, and for a [`Profile::Beam`] `0 <= beam_half <= field_half`. For a
    /// measured profile `intensity` is the colour (times any dimmer) times the file's
    /// peak candela.
    pub fn new(
        position: Vec3,
        light_from_world: Mat3,
        intensity: Vec3,
        field_half: f32,
        profile: Profile,
        gobo: Option<Gobo>,
    ) -> Spotlight {
        let (tan_beam, inv_peak) = match &profile {
            Profile::Beam { beam_half, .. } => (beam_half.tan(), 1.0),
            Profile::Measured(p) => (0.0, 1.0 / p.peak()),
        };
        let mut light = Spotlight {
            position,
            light_from_world,
            intensity,
            field_half,
            profile,
            gobo,
            intensity_map: IntensityMap::empty(),
            tan_field: field_half.tan(),
            tan_beam,
            inv_peak,
        };
        light.intensity_map = IntensityMap::new(&light);
        light
    }

    /// `tan(field / 2)`: the half-width of the light's `(u, v)` square at `z = 1`.
    #[inline]
    pub fn tan_field(&self) -> f32 {
        self.tan_field
    }

    /// `tan(beam / 2)`: inside it a beam's profile is 1 (0 for a measured profile).
    #[inline]
    pub fn tan_beam(&self) -> f32 {
        self.tan_beam
    }

    /// The light-space position of the world point `p`.
    #[inline]
    pub fn to_light(&self, p: Vec3) -> Vec3 {
        self.light_from_world * (p - self.position)
    }

    /// Whether the segment between the world points `from` and `to` passes through the
    /// field cone, where [`Spotlight::intensity_toward`] may be non-zero. In light
    /// space the cone is `g = tan^2(field / 2) z^2 - x^2 - y^2 > 0` with `z > 0`; along
    /// the segment `g` is a quadratic in its parameter, so it is positive somewhere on
    /// the part with `z > 0` where its greatest value there is: at an end of that part
    /// or at the quadratic's vertex. A segment that only touches the cone's surface is
    /// given `false`.
    pub fn segment_meets_field(&self, from: Vec3, to: Vec3) -> bool {
        let a = self.to_light(from).as_dvec3();
        let d = self.to_light(to).as_dvec3() - a;
        // The part of [0, 1] in front of the lamp (z > 0).
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        if d.z == 0.0 {
            if a.z <= 0.0 {
                return false;
            }
        } else {
            let t = -a.z / d.z;
            if d.z > 0.0 {
                lo = lo.max(t);
            } else {
                hi = hi.min(t);
            }
        }
        if lo > hi {
            return false;
        }
        let t2 = (self.tan_field as f64).powi(2);
        let qa = t2 * d.z * d.z - d.x * d.x - d.y * d.y;
        let qb = 2.0 * (t2 * a.z * d.z - a.x * d.x - a.y * d.y);
        let qc = t2 * a.z * a.z - a.x * a.x - a.y * a.y;
        let g = |t: f64| (qa * t + qb) * t + qc;
        let vertex = if qa < 0.0 {
            (-qb / (2.0 * qa)).clamp(lo, hi)
        } else {
            lo
        };
        g(lo) > 0.0 || g(hi) > 0.0 || g(vertex) > 0.0
    }

    /// `I_l`: the intensity sent toward the light-space point `local` (any distance),
    /// per channel; zero outside the field cone.
    #[inline]
    pub fn intensity_toward(&self, local: Vec3) -> Vec3 {
        if local.z <= 0.0 {
            return Vec3::ZERO;
        }
        let scale = 1.0 / (local.z * self.tan_field);
        self.intensity_at(local.x * scale, local.y * scale)
    }

    /// `I_l` toward the light-space projection `(u, v)` (see the module doc).
    #[inline]
    pub fn intensity_at(&self, u: f32, v: f32) -> Vec3 {
        let profile = self.profile_at(u, v);
        match &self.gobo {
            Some(gobo) if profile > 0.0 => self.intensity * profile * gobo.sample(u, v),
            _ => self.intensity * profile,
        }
    }

    /// The profile at `(u, v)`, exactly (the plane method looks up
    /// [`Spotlight::intensity_map`] instead): for a beam 1 inside it, 0 outside the field,
    /// the falloff between; for a measured profile the file's candela over its peak at
    /// the direction's vertical angle and half-plane, 0 outside the field.
    #[inline(always)]
    pub fn profile_at(&self, u: f32, v: f32) -> f32 {
        let q = u * u + v * v;
        if q >= 1.0 {
            return 0.0;
        }
        let r2 = q * self.tan_field * self.tan_field;
        match &self.profile {
            Profile::Beam { beam_half, falloff } => {
                if r2 <= self.tan_beam * self.tan_beam {
                    return 1.0;
                }
                let x = (self.field_half - fast_atan(r2.sqrt())) / (self.field_half - beam_half);
                falloff.shape(x.clamp(0.0, 1.0))
            }
            Profile::Measured(photometry) => {
                let gamma = r2.sqrt().atan().to_degrees();
                let c = v.atan2(u).to_degrees();
                photometry.candela_at(gamma, c) * self.inv_peak
            }
        }
    }

    /// The interval `[t0, t1]` within `[t_min, t_max]` where the ray
    /// `origin + t dir` is inside the field cone, or `None`. The cone's forward half is
    /// convex (field below 180 degrees), so this is one interval. In double precision:
    /// the roots of a quadratic lose digits in single.
    pub fn cone_interval(
        &self,
        origin: Vec3,
        dir: Vec3,
        t_min: f32,
        t_max: f32,
    ) -> Option<(f32, f32)> {
        if t_min >= t_max {
            return None;
        }
        let m = self.light_from_world.as_dmat3();
        let o: DVec3 = m * (origin.as_dvec3() - self.position.as_dvec3());
        let d: DVec3 = m * dir.as_dvec3();
        let k = (self.tan_field as f64).powi(2);
        // Inside: z > 0 and x^2 + y^2 - k z^2 <= 0, a quadratic a t^2 + b t + c.
        let a = d.x * d.x + d.y * d.y - k * d.z * d.z;
        let b = 2.0 * (o.x * d.x + o.y * d.y - k * o.z * d.z);
        let c = o.x * o.x + o.y * o.y - k * o.z * o.z;
        let inside = |t: f64| {
            let p = o + t * d;
            p.z > 0.0 && p.x * p.x + p.y * p.y <= k * p.z * p.z
        };
        let (lo, hi) = (t_min as f64, t_max as f64);
        // The ends, where z = 0, and the quadratic's roots: at most five cuts.
        let mut cuts = [hi; 5];
        cuts[0] = lo;
        let mut count = 2;
        let mut cut = |t: f64| {
            if t > lo && t < hi {
                cuts[count] = t;
                count += 1;
            }
        };
        if d.z != 0.0 {
            cut(-o.z / d.z);
        }
        if a.abs() > 1e-12 * (b.abs() + c.abs()).max(1e-30) {
            let disc = b * b - 4.0 * a * c;
            if disc >= 0.0 {
                // The stable pair of roots.
                let q = -0.5 * (b + b.signum() * disc.sqrt());
                cut(q / a);
                if q != 0.0 {
                    cut(c / q);
                }
            }
        } else if b != 0.0 {
            cut(-c / b);
        }
        let cuts = &mut cuts[..count];
        cuts.sort_unstable_by(f64::total_cmp);
        let mut span: Option<(f64, f64)> = None;
        for w in cuts.windows(2) {
            if w[1] > w[0] && inside(0.5 * (w[0] + w[1])) {
                span = Some(span.map_or((w[0], w[1]), |(s, _)| (s, w[1])));
            }
        }
        span.map(|(s, e)| (s as f32, e as f32))
    }

    /// The world direction of light-space `(u, v)` on the `z = 1` plane, not normalised.
    #[inline]
    pub fn world_direction(&self, u: f32, v: f32) -> Vec3 {
        self.light_from_world.transpose() * Vec3::new(u * self.tan_field, v * self.tan_field, 1.0)
    }
}

/// The rows of the world-to-light rotation for a beam along `axis` with `up` as the
/// light's `y` (made perpendicular); `None` when they are parallel.
pub fn light_frame(axis: Vec3, up: Vec3) -> Option<Mat3> {
    let z = axis.try_normalize()?;
    // Seen from behind the lamp, x right and y up: (x, y, z) is a left-handed triple,
    // like a screen's (right, up, into the screen).
    let x = z.cross(up).try_normalize()?;
    let y = x.cross(z);
    Some(Mat3::from_cols(x, y, z).transpose())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn light(falloff: Falloff) -> Spotlight {
        Spotlight::new(
            Vec3::new(0.0, 5.0, 0.0),
            light_frame(Vec3::NEG_Y, Vec3::Z).unwrap(),
            Vec3::new(100.0, 90.0, 80.0),
            20f32.to_radians(),
            Profile::Beam {
                beam_half: 10f32.to_radians(),
                falloff,
            },
            None,
        )
    }

    #[test]
    fn the_profile_is_full_in_the_beam_and_zero_beyond_the_field() {
        for falloff in [Falloff::Linear, Falloff::Smooth] {
            let l = light(falloff);
            let at = |deg: f32| {
                let a = deg.to_radians();
                l.intensity_toward(Vec3::new(a.sin(), 0.0, a.cos())).x
            };
            assert_eq!(at(0.0), 100.0);
            assert_eq!(at(9.9), 100.0);
            assert!((at(15.0) - 50.0).abs() < 0.1, "{falloff:?} {}", at(15.0));
            assert!(at(19.0) < 15.0 && at(19.0) > 0.0);
            assert_eq!(at(20.1), 0.0);
            assert_eq!(l.intensity_toward(Vec3::new(0.0, 0.0, -1.0)), Vec3::ZERO);
        }
        // Past the middle of the edge (16.7 degrees) the smooth edge is the darker one.
        let outer = Vec3::new(0.3, 0.0, 1.0);
        let (linear, smooth) = (light(Falloff::Linear), light(Falloff::Smooth));
        assert!(smooth.intensity_toward(outer).x < linear.intensity_toward(outer).x - 5.0);
    }

    /// Segments meet the field cone as points along them say: 20,000 random
    /// segments about the lamp, each against 2,000 points along it (a segment whose
    /// points all miss may still cross the cone between them, so only a hit among the
    /// points must be found).
    #[test]
    fn a_segment_meets_the_field_where_its_points_do() {
        let l = light(Falloff::Smooth);
        let mut seed = 7u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 40) as f32 / (1u64 << 24) as f32 * 16.0 - 8.0
        };
        let (mut hits, mut misses) = (0, 0);
        for _ in 0..20_000 {
            let (from, to) = (
                Vec3::new(next(), next() * 0.5 + 4.0, next()),
                Vec3::new(next(), next() * 0.5 + 4.0, next()),
            );
            let sampled = (0..=2000).any(|k| {
                let p = from.lerp(to, k as f32 / 2000.0);
                l.intensity_toward(l.to_light(p)) != Vec3::ZERO
            });
            let met = l.segment_meets_field(from, to);
            if sampled {
                assert!(met, "{from} -> {to}");
                hits += 1;
            } else if !met {
                misses += 1;
            }
        }
        // Both kinds are there, and nearly every segment no point of which is lit is
        // also found to miss (the others graze the cone between two points).
        assert!(hits > 1000 && misses > 1000, "{hits} {misses}");
    }

    #[test]
    fn the_light_frame_looks_along_the_axis_with_x_to_the_right() {
        let m = light_frame(Vec3::Z, Vec3::Y).unwrap();
        assert!((m * Vec3::Z - Vec3::Z).length() < 1e-6);
        assert!((m * Vec3::Y - Vec3::Y).length() < 1e-6);
        // Looking along +z with y up, the viewer's right is world -x.
        assert!((m * Vec3::NEG_X - Vec3::X).length() < 1e-6);
        assert!(light_frame(Vec3::Y, Vec3::Y).is_none());
    }

    #[test]
    fn cone_intervals_agree_with_point_tests() {
        let l = light(Falloff::Linear);
        let tan_f = l.tan_field();
        let mut rays = 0;
        for k in 0..400 {
            let f = k as f32;
            let origin = Vec3::new(
                (f * 0.37).sin() * 6.0,
                (f * 0.11).cos() * 6.0,
                (f * 0.53).sin() * 6.0,
            );
            let dir = Vec3::new((f * 1.7).cos(), (f * 0.9).sin(), (f * 2.3).cos()).normalize();
            let interval = l.cone_interval(origin, dir, 0.0, 20.0);
            for s in 0..2000 {
                let t = (s as f32 + 0.5) * 0.01;
                let p = l.to_light(origin + t * dir);
                let inside = p.z > 0.0 && p.x.hypot(p.y) < tan_f * p.z;
                let margin = 1e-3;
                match interval {
                    Some((a, b)) if t > a + margin && t < b - margin => assert!(inside, "{k} {t}"),
                    Some((a, b)) if t < a - margin || t > b + margin => assert!(!inside, "{k} {t}"),
                    None => assert!(!inside, "{k} {t}"),
                    _ => {}
                }
            }
            rays += interval.is_some() as usize;
        }
        assert!(rays > 50, "{rays}");
    }

    #[test]
    fn gobo_sampling_orients_the_image_as_seen_from_behind_the_lamp() {
        // 2 x 2: top-left red, top-right green, bottom-left blue, bottom-right white.
        let gobo = |sampling| {
            Gobo::new(
                2,
                2,
                vec![[255, 0, 0], [0, 255, 0], [0, 0, 255], [255; 3]],
                sampling,
            )
        };
        let g = gobo(Sampling::Nearest);
        assert_eq!(g.sample(-0.5, 0.5), Vec3::X);
        assert_eq!(g.sample(0.5, 0.5), Vec3::Y);
        assert_eq!(g.sample(-0.5, -0.5), Vec3::Z);
        let b = gobo(Sampling::Bilinear);
        assert!((b.sample(0.0, 0.5) - Vec3::new(0.5, 0.5, 0.0)).length() < 1e-6);
        assert!((b.sample(0.0, 0.0) - Vec3::splat(0.5)).length() < 1e-6);
        // A quarter turn counterclockwise brings the top-right (green) to the top-left.
        let turned = Gobo {
            rotation: std::f32::consts::FRAC_PI_2,
            ..gobo(Sampling::Nearest)
        };
        assert_eq!(turned.sample(-0.5, 0.5), Vec3::Y);
        assert_eq!(turned.sample(0.5, 0.5), Vec3::ONE);
    }

    /// Skipping the dark blocks changes no lookup: sparse lit texels (on blocks' edges
    /// and corners too) in an image whose sides are not a whole number of blocks,
    /// looked up over and beyond the image, turned and not, both ways.
    #[test]
    fn dark_blocks_give_what_their_texels_give() {
        let (w, h) = (37, 23);
        let srgb = (0..w * h)
            .map(|k: usize| {
                let lit = (k * 2_654_435_761) % 97 < 2;
                if lit {
                    [(k % 251) as u8 | 1, 200, 0]
                } else {
                    [0; 3]
                }
            })
            .collect::<Vec<_>>();
        for sampling in [Sampling::Nearest, Sampling::Bilinear] {
            let gobo = Gobo::new(w, h, srgb.clone(), sampling);
            let dark = gobo.dark.iter().filter(|&&d| d).count();
            assert!(dark > gobo.dark.len() / 4, "{dark} of {}", gobo.dark.len());
            let plain = Gobo {
                dark: vec![false; gobo.dark.len()].into(),
                ..gobo.clone()
            };
            let mut lit = 0;
            for rotation in [0.0f32, 0.7, -2.0] {
                let turn = rotation.sin_cos();
                for j in 0..=300 {
                    for i in 0..=300 {
                        let (u, v) = (-1.3 + i as f32 * 0.0087, -1.3 + j as f32 * 0.0087);
                        let want = plain.sample_turned(u, v, turn);
                        assert_eq!(gobo.sample_turned(u, v, turn), want, "({u}, {v}) {turn:?}");
                        lit += (want != Vec3::ZERO) as usize;
                    }
                }
            }
            assert!(lit > 2_000, "{lit} lit lookups");
        }
    }
}
