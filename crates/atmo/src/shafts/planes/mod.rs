//! The paper's method (shafts 4.2-4.3): sample planes parallel to the screen through
//! the lit volume of each light; on each, `g = F h` from the tables (5)-(6); between
//! them, sub-sample planes that average `H I_l` over the plane's interval (7)-(9).
//!
//! The GPU draws every plane over the whole screen and lets blending add them up. The
//! CPU version keeps that arithmetic exactly, pixel by pixel (sixteen neighbouring
//! pixels at a time, in vector loops), and skips only what cannot contribute:
//! sub-samples where `I_l = 0` (outside the light's field cone, found per ray by
//! [`Spotlight::cone_interval`]), beyond the surface the ray meets (the GPU's depth
//! test), outside the haze, and planes whose whole interval is such; and the lookups
//! whose answer is known beforehand: a min-max chain over each shadow map tells a plane's
//! slice of sixteen rays wholly lit or wholly dark, and the beam's core has profile 1
//! (see `SamplePlanes::scattered`). The result is the same sum, to the bit; the work
//! follows the lit part of each ray. With [`PlaneSettings::adaptive`] (the default) the
//! CPU goes further than the paper: the scattered light is computed where the picture
//! changes and interpolated between ([`super::adaptive`]).
//!
//! One departure from the paper, on the CPU and the GPU alike: a slab between two
//! planes that passes near the lamp, where `1 / s^2` and the phase change within it
//! faster than one `g` at its plane can follow, is summed at points spaced evenly in
//! the scattering angle instead (`SamplePlanes::near_slabs`); the lamp's own pixels
//! came out dark without it.
//!
//! For light `l`, with planes at camera depths `z_i = z_near + (i + 1/2) dz`
//! (`i < n`) and sub-planes at `z_ij = z_near + (i + (j + 1/2)/m) dz` (`j < m`), a
//! camera ray `r` (unit length along the view axis, `|r| = 1 / cos` of its angle off
//! the axis) receives
//!
//! ```text
//! I_s = sum_i J_i F(alpha_i) h(s_i, t_i) dz |r|,   J_i = 1/m sum_j H(z_ij) I_l(z_ij)
//! ```
//!
//! `dz |r|` is shafts' `Delta t`, the length of ray between two planes.

use std::borrow::Cow;
use std::sync::atomic::{AtomicU8, Ordering};

use glam::Vec3;
use rayon::prelude::*;

use super::shadow_map::{ShadowMap, Stretch};
use super::spotlight::{Gobo, Spotlight};
use super::surface::{first_hit_among, shadow_ray, surface_radiance, SurfacePoint};
use super::tables::{AttenuationTable, PhaseTable};
use super::{adaptive, PlaneSettings, Scene};
use crate::fast::interleaved_offset;
use crate::geometry::Aabb;
use crate::image::Frame;
use crate::view::Camera;

mod extent;
mod lanes;
mod maps;
mod view_box;

use extent::Extent;
pub use lanes::LANES;
use lanes::*;
pub use maps::ShadowMaps;
use view_box::*;

/// Nearest camera depth a plane is put at, m.
const NEAR_PLANE: f32 = 1e-3;

/// One light's shadow map and the depths its planes span.
#[derive(Debug, Clone)]
pub struct LightPlanes<'a> {
    /// `H` for this light: built here, or borrowed when the light and the objects have
    /// not moved since it was built.
    pub shadow: Cow<'a, ShadowMap>,
    /// Camera depth where the first plane interval starts, m.
    pub z_near: f32,
    /// Camera depth where the last plane interval ends, m.
    pub z_far: f32,
    /// A box around the lit volume (the lamp and its shadow map's ray ends): rays that
    /// miss it skip the light.
    pub bounds: Aabb,
    /// Where that box shows on the camera's view plane: rays elsewhere miss it.
    view: ViewBox,
    /// Whether the lamp is in the haze: then its in-haze distance to any point in the
    /// (convex) haze is the whole distance.
    lamp_in_haze: bool,
    /// The eye in the light's space: where every camera ray starts.
    eye: Vec3,
}

impl LightPlanes<'_> {
    /// The spacing of the light's sub-sample planes, m of camera depth.
    fn sub_spacing(&self, settings: &PlaneSettings) -> f32 {
        (self.z_far - self.z_near) / (settings.planes * settings.sub_planes) as f32
    }
}

/// The tolerance of [`PlaneSettings::adaptive`] for a picture shown at `exposure`:
/// corners' contrast 0.25, 1 % at the centre, of values plus a radiance of 0.01 after
/// the exposure (level 25 of 255 in sRGB). Chosen with `atmo bench shafts` on the
/// Fig. 6 scene and the stage (docs/shafts.md): halving the 1 % changed the error
/// against the converged reference by 0.01 levels RMS at most and cost some 15 %
/// more time (single runs on a shared host).
fn adaptive_tolerance(exposure: f32) -> adaptive::Tolerance {
    adaptive::Tolerance {
        contrast: 0.25,
        relative: 0.01,
        floor: 0.01 / exposure,
    }
}

/// Whether [`PlaneSettings::adaptive`] refines and interpolates the light of `light`:
/// not of a lamp with a gobo, whose dots and lines are finer than a cell (its light is
/// computed at every pixel).
fn refined(light: &Spotlight) -> bool {
    light.gobo.is_none()
}

/// How near a lamp's image (pixels, in x and in y) [`PlaneSettings::adaptive`]
/// computes every pixel.
const LAMP_REACH: f32 = 2.5;

/// Everything the plane method prepares once a frame: shadow maps, the lit volumes'
/// depth ranges, and the `F` and `h` tables.
#[derive(Debug, Clone)]
pub struct SamplePlanes<'a> {
    scene: &'a Scene,
    /// Per light, in scene order.
    pub lights: Vec<LightPlanes<'a>>,
    phase: PhaseTable,
    attenuation: AttenuationTable,
    /// Per object, where it shows on the camera's view plane.
    objects: Vec<ViewBox>,
    /// Where rays that meet nothing end, camera depth, m ([`Scene::far_m`]).
    far: f32,
}

impl<'a> SamplePlanes<'a> {
    /// Builds the shadow maps, finds where each light's lit volume lies in camera depth
    /// (the lamp and the ends of its shadow map's rays), and tabulates `F` and `h`.
    pub fn new(scene: &'a Scene) -> SamplePlanes<'a> {
        SamplePlanes::prepare(
            scene,
            shadow_maps(scene).into_iter().map(Cow::Owned).collect(),
        )
    }

    /// As [`SamplePlanes::new`] with the shadow maps of an earlier frame (from
    /// [`shadow_maps`]), for when only the camera moved: an interactive viewer rebuilds
    /// a light's map only when that light or an object changes.
    pub fn with_shadow_maps(scene: &'a Scene, maps: &'a [ShadowMap]) -> SamplePlanes<'a> {
        assert_eq!(maps.len(), scene.light_count(), "one shadow map a light");
        SamplePlanes::prepare(scene, maps.iter().map(Cow::Borrowed).collect())
    }

    fn prepare(scene: &'a Scene, maps: Vec<Cow<'a, ShadowMap>>) -> SamplePlanes<'a> {
        let camera = &scene.camera;
        let far = scene.far_m();
        let mut s_max = 0.0f32;
        let mut t_max = 0.0f32;
        let lights = scene
            .lights()
            .zip(maps)
            .map(|(light, shadow)| {
                // Farther than this from the lamp is beyond the far plane anyway.
                let reach = far * 2.0 + (light.position - camera.position).length();
                let extent = Extent::of(&shadow, light, camera, reach);
                let (mut lo, mut hi) = (extent.near, extent.far);
                s_max = s_max.max(extent.from_lamp.sqrt());
                t_max = t_max.max(extent.from_eye.sqrt());
                if let Some(b) = &scene.haze.bounds {
                    let (bl, bh) = b
                        .corners()
                        .map(|c| camera.depth(c))
                        .into_iter()
                        .fold((f32::INFINITY, f32::NEG_INFINITY), |(l, h), z| {
                            (l.min(z), h.max(z))
                        });
                    lo = lo.max(bl);
                    hi = hi.min(bh);
                }
                LightPlanes {
                    shadow,
                    z_near: lo.max(NEAR_PLANE),
                    z_far: hi.min(far),
                    bounds: extent.bounds,
                    view: ViewBox::of(Some(extent.bounds), camera),
                    lamp_in_haze: scene.haze.bounds.is_none_or(|b| b.contains(light.position)),
                    eye: light.to_light(camera.position),
                }
            })
            .collect();
        // The longest camera ray per unit depth: to the image's corners (a scene's camera
        // is a pinhole; see `Scene::camera`).
        let corner = camera
            .pinhole("the sample planes")
            .map_or(f32::INFINITY, |(tw, th)| {
                (1.0 + tw.powi(2) + th.powi(2)).sqrt()
            });
        let t_max = t_max.min(far * corner);
        SamplePlanes {
            scene,
            lights,
            phase: PhaseTable::new(&scene.haze),
            attenuation: AttenuationTable::new(&scene.haze, s_max, t_max),
            objects: scene
                .objects
                .list
                .iter()
                .map(|o| ViewBox::of(o.shape.bounds(), camera))
                .collect(),
            far,
        }
    }

    /// The picture: surfaces lit through shadow maps plus the scattered light. Surfaces
    /// pixel by pixel; the scattered light at every pixel or, with
    /// [`PlaneSettings::adaptive`], where [`adaptive::refine`]
    /// asks for it, [`LANES`] pixels at a time (see `SamplePlanes::scattered`); both
    /// over both cores.
    pub fn render(&self) -> Frame {
        self.render_counted().0
    }

    /// [`SamplePlanes::render`], and how many pixels' scattered light was computed and
    /// how many interpolated (summed over the rays of a pixel).
    pub fn render_counted(&self) -> (Frame, adaptive::Counts) {
        let camera = &self.scene.camera;
        let (width, height) = (camera.width, camera.height);
        let n = (width * height) as usize;
        let mut frame = Frame::new(width, height);
        let subpixels = camera.subpixel_offsets();
        let weight = 1.0 / subpixels.len() as f32;
        let mut counts = adaptive::Counts::default();
        for &(dx, dy) in &subpixels {
            let ray = |p: u32| camera.ray((p % width) as f32 + dx, (p / width) as f32 + dy);
            let pass = if self.scene.planes.adaptive {
                self.add_adaptive(&ray, &mut frame.pixels)
            } else {
                self.add_every_pixel(&ray, &mut frame.pixels);
                adaptive::Counts {
                    computed: n,
                    interpolated: 0,
                }
            };
            counts.computed += pass.computed;
            counts.interpolated += pass.interpolated;
        }
        if subpixels.len() > 1 {
            for pixel in frame.pixels.iter_mut() {
                *pixel *= weight;
            }
        }
        (frame, counts)
    }

    /// Adds the light along the rays `ray(p)` of every pixel `p` to `pixels`, all of
    /// it computed: rows in parallel.
    fn add_every_pixel(&self, ray: &(impl Fn(u32) -> Vec3 + Sync), pixels: &mut [Vec3]) {
        let width = self.scene.camera.width;
        pixels
            .par_chunks_mut(width as usize)
            .enumerate()
            .for_each(|(y, row)| self.add_row(ray, y as u32 * width, row, |_, _| {}, &|_| true));
    }

    /// Adds to `row`, the pixels from `first` on, the light of the surfaces their rays
    /// `ray(p)` meet and the light scattered toward them from the lights `pick` takes,
    /// [`LANES`] pixels at a time; gives each ray's end (m) to `end(x, m)`.
    fn add_row(
        &self,
        ray: &impl Fn(u32) -> Vec3,
        first: u32,
        row: &mut [Vec3],
        mut end: impl FnMut(usize, f32),
        pick: &impl Fn(&Spotlight) -> bool,
    ) {
        let width = self.scene.camera.width;
        for (k, out) in row.chunks_mut(LANES).enumerate() {
            let start = first + (k * LANES) as u32;
            let (rays, offsets) = lanes_of(start..start + out.len() as u32, ray, width);
            let mut ends = [0.0f32; LANES];
            for l in 0..out.len() {
                let surface;
                (surface, ends[l]) = self.surface(rays[l]);
                out[l] += surface;
                end(k * LANES + l, ends[l]);
            }
            let count = out.len();
            self.scattered_rays(&rays[..count], &offsets[..count], &ends, out, pick);
        }
    }

    /// Adds the light along the rays `ray(p)` of every pixel `p` to `pixels`: the
    /// surfaces and the light of lamps with a gobo computed at every pixel (a gobo's
    /// dots and lines are finer than a cell and may fall between all of its samples: on
    /// the stage its beam interpolated was up to 26 levels off), the other lamps'
    /// scattered light by [`adaptive::refine`] (its counts; every pixel computed if
    /// every lamp has a gobo).
    fn add_adaptive(
        &self,
        ray: &(impl Fn(u32) -> Vec3 + Sync),
        pixels: &mut [Vec3],
    ) -> adaptive::Counts {
        let width = self.scene.camera.width;
        let patterned = |light: &Spotlight| !refined(light);
        // The surfaces' and the patterned lamps' light added, and where each ray ends, m.
        let mut ends = vec![0.0f32; pixels.len()];
        pixels
            .par_chunks_mut(width as usize)
            .zip(ends.par_chunks_mut(width as usize))
            .enumerate()
            .for_each(|(y, (row, ends))| {
                self.add_row(ray, y as u32 * width, row, |x, m| ends[x] = m, &patterned)
            });
        if !self.scene.lights().any(refined) {
            return adaptive::Counts {
                computed: pixels.len(),
                interpolated: 0,
            };
        }
        let compute = |list: &[u32], out: &mut [Vec3]| {
            list.par_chunks(LANES)
                .zip(out.par_chunks_mut(LANES))
                .with_min_len(16)
                .for_each(|(list, out)| {
                    let (rays, offsets) = lanes_of(list.iter().copied(), ray, width);
                    let mut lane_ends = [0.0f32; LANES];
                    for (end, &p) in lane_ends.iter_mut().zip(list) {
                        *end = ends[p as usize];
                    }
                    let count = list.len();
                    out.fill(Vec3::ZERO);
                    let (rays, offsets) = (&rays[..count], &offsets[..count]);
                    self.scattered_rays(rays, offsets, &lane_ends, out, &refined);
                });
        };
        self.scattered_adaptive(ray, &ends, compute, pixels)
    }

    /// Adds the scattered light of the lamps without a gobo at every pixel to `out` by
    /// [`adaptive::refine`] (and gives its counts), computing with `compute`. The guard
    /// lets a pixel take its corners' interpolation only where its ray ends (on a
    /// surface or at the far plane, `ends`, m) where interpolating the corners' ends
    /// puts it, within the tolerance or one sub-sample spacing (an object's silhouette
    /// cuts the haze in front of it short, and a thin one, a truss or a stand, passes
    /// between corners), and not near a lamp's image: within [`LAMP_REACH`] pixels,
    /// where `1/s^2` peaks inside one pixel, and as far again as the beam is narrower
    /// than a cell (a beam seen across opens by `tan(field / 2)` a pixel of distance
    /// from its apex). Nor does a pixel whose ray (`ray`, to its end) passes outside
    /// every lamp's field cone take light from corners whose rays pass inside one: it
    /// is black, as computing it gives (interpolation put up to 1.3e-6 of the range on
    /// 1,337 such pixels of the Fig. 6 scene).
    fn scattered_adaptive(
        &self,
        ray: &(impl Fn(u32) -> Vec3 + Sync),
        ends: &[f32],
        compute: impl Fn(&[u32], &mut [Vec3]),
        out: &mut [Vec3],
    ) -> adaptive::Counts {
        let scene = self.scene;
        let spacing = self
            .lights
            .iter()
            .map(|planes| planes.sub_spacing(&scene.planes))
            .fold(f32::INFINITY, f32::min);
        let tolerance = adaptive_tolerance(scene.display.exposure);
        let camera = &scene.camera;
        let lamps: Vec<(f32, f32, f32)> = scene
            .lights()
            .filter(|light| refined(light))
            .filter_map(|light| {
                let (x, y) = camera.pixel_of(light.position)?;
                Some((
                    x,
                    y,
                    LAMP_REACH + adaptive::COARSEST as f32 / light.tan_field(),
                ))
            })
            .collect();
        let width = camera.width;
        // Whether each pixel's ray meets a refined lamp's field cone, found once: a
        // cell's corners are asked about for every pixel in it. 0: not yet known.
        let known: Vec<AtomicU8> = (0..ends.len()).map(|_| AtomicU8::new(0)).collect();
        let lit = |p: u32| match known[p as usize].load(Ordering::Relaxed) {
            0 => {
                let end = camera.position + ray(p).normalize() * ends[p as usize];
                let meets = scene
                    .lights()
                    .filter(|light| refined(light))
                    .any(|light| light.segment_meets_field(camera.position, end));
                known[p as usize].store(1 + meets as u8, Ordering::Relaxed);
                meets
            }
            state => state == 2,
        };
        let guard = |p: u32, corners: [u32; 4], weights: [f32; 4]| {
            let (x, y) = ((p % width) as f32 + 0.5, (p / width) as f32 + 0.5);
            if lamps
                .iter()
                .any(|(lx, ly, reach)| (x - lx).abs().max((y - ly).abs()) <= *reach)
            {
                return false;
            }
            // The corners first: their answers are shared by the cell's pixels, and a
            // cell with no corner in a cone has only black to interpolate.
            if corners.iter().any(|&c| lit(c)) && !lit(p) {
                return false;
            }
            let end = ends[p as usize];
            let estimate: f32 = corners
                .iter()
                .zip(weights)
                .map(|(&c, w)| w * ends[c as usize])
                .sum();
            (end - estimate).abs() <= tolerance.relative * end + spacing
        };
        adaptive::refine(
            (camera.width, camera.height),
            tolerance,
            compute,
            guard,
            out,
        )
    }

    /// The radiance along one camera ray (unit length along the view axis), its
    /// sub-sample planes shifted by `offset` in [0, 1) of their spacing (1/2: the
    /// paper's, centred in their slices).
    pub fn radiance(&self, ray: Vec3, offset: f32) -> Vec3 {
        let (surface, end) = self.surface(ray);
        let mut out = [Vec3::ZERO];
        self.scattered_rays(&[ray], &[offset], &[end; LANES], &mut out, &|_| true);
        surface + out[0]
    }

    /// The light a camera ray (unit length along the view axis) gets from the surface it
    /// meets, and how far it goes before it meets it (the far plane if none), m. Only
    /// the objects whose [`ViewBox`] holds the ray are tried.
    fn surface(&self, ray: Vec3) -> (Vec3, f32) {
        let scene = self.scene;
        let length = ray.length();
        let far = self.far * length;
        let at = view_point(&scene.camera, ray);
        let objects = (scene.objects.list.iter().zip(&self.objects))
            .filter(|(_, b)| b.holds(at))
            .map(|(o, _)| o);
        match first_hit_among(scene, objects, ray / length, far) {
            Some(point) => (
                surface_radiance(scene, &point, |k, light| self.visibility(k, light, &point)),
                point.distance,
            ),
            None => (Vec3::ZERO, far),
        }
    }

    /// Adds the light scattered toward the eye along `rays` (at most [`LANES`]; with
    /// their sub-sample `offsets` and `ends`, m) to `out`, light by light: those `pick`
    /// takes whose lit volume some ray may meet ([`LightPlanes::view`]).
    fn scattered_rays(
        &self,
        rays: &[Vec3],
        offsets: &[f32],
        ends: &[f32; LANES],
        out: &mut [Vec3],
        pick: &impl Fn(&Spotlight) -> bool,
    ) {
        let mut at = [(0.0f32, 0.0f32); LANES];
        for (at, ray) in at.iter_mut().zip(rays) {
            *at = view_point(&self.scene.camera, *ray);
        }
        let at = &at[..rays.len()];
        for (light, planes) in self.scene.lights().zip(&self.lights) {
            if !pick(light) || !at.iter().any(|&p| planes.view.holds(p)) {
                continue;
            }
            let lanes = Lanes::new(self, light, planes, rays, offsets, ends);
            let scattered = self.scattered(light, planes, &lanes);
            for (out, s) in out.iter_mut().zip(scattered) {
                *out += s;
            }
            if lanes.near_lamp {
                for (l, out) in out.iter_mut().enumerate() {
                    *out += light.intensity * self.near_slabs(light, planes, &lanes, l);
                }
            }
        }
    }

    /// How much of `light` the surface point sees: its shadow map, filtered against
    /// the point's plane ([`ShadowMap::visibility`]), and where the filter's texels
    /// disagree (a shadow's edge runs between them) a shadow ray. The map places an
    /// edge only to within a texel, which on a floor seen at a glancing angle is a
    /// whole pixel of error; the pixels where it is in doubt are few (the edge's), so
    /// the exact answer there costs little (shafts 4.1 uses the map alone).
    fn visibility(&self, k: usize, light: &Spotlight, point: &SurfacePoint) -> f32 {
        let filtered = self.lights[k].shadow.visibility(
            light.to_light(point.position),
            light.light_from_world * point.normal,
        );
        if filtered > 0.0 && filtered < 1.0 {
            shadow_ray(self.scene, light, point)
        } else {
            filtered
        }
    }

    /// `I_s` of shafts (7) for one light along the rays of `lanes`.
    ///
    /// All sub-samples of a ray form one progression in camera depth,
    /// `z_k = z_near + (k + offset) sub` with `sub = dz / m`: sub-plane `k mod m` of plane
    /// `k / m`. Sample `k` of every ray lies in the same plane's slice, so the lanes go
    /// through `k` together, each counting only its own lit stretch: first the
    /// light-space projections of the `LANES` samples (straight arithmetic, which the
    /// compiler vectorises), then their shadow-map and light-map lookups into `J_i`
    /// (shafts (9), times `m`, without the light's colour), and where a plane's slice
    /// ends, `g` of shafts (6) for the lanes the same way.
    ///
    /// Before a slice, the lanes ask the shadow map's min-max chain about their
    /// stretches of it ([`Lookups::of_slice`]): where those are wholly lit the shadow
    /// lookups are left out, wholly dark all of them, and inside the beam's core (where
    /// the profile is 1) the light map's too. What is left out would have given
    /// exactly those values, so the sum is the same to the bit.
    fn scattered(&self, light: &Spotlight, planes: &LightPlanes, lanes: &Lanes) -> [Vec3; LANES] {
        let mut sum = [Vec3::ZERO; LANES];
        let m = self.scene.planes.sub_planes as usize;
        let shadow = &planes.shadow;
        // J_i per lane: the profile alone (in `x`), or with the gobo's colour.
        let mut j_sums = [Vec3::ZERO; LANES];
        let turn = light.gobo.as_ref().map_or((0.0, 1.0), Gobo::turn);
        for (plane, slice) in lanes.slices(m) {
            let lookups = Lookups::of_slice(light, shadow, lanes, slice.clone());
            if lookups == Lookups::None {
                continue;
            }
            for k in slice {
                let (mut u, mut v, mut z, mut active) = (
                    [0.0f32; LANES],
                    [0.0f32; LANES],
                    [0.0f32; LANES],
                    [0.0f32; LANES],
                );
                for l in 0..LANES {
                    [u[l], v[l], z[l]] = lanes.project(l, k);
                    active[l] = ((k as u32 >= lanes.k_first[l]) & ((k as u32) < lanes.k_last[l]))
                        as u8 as f32;
                }
                if let Some(gobo) = &light.gobo {
                    // The gobo first: over most of a pattern's beam it is dark and costs
                    // one lookup ([`Gobo::sample_turned`]); the maps where it is not.
                    for l in 0..lanes.count {
                        if active[l] == 0.0 {
                            continue;
                        }
                        let through = gobo.sample_turned(u[l], v[l], turn);
                        if through != Vec3::ZERO {
                            j_sums[l] +=
                                lookups.weight(light, shadow, [u[l], v[l], z[l]]) * through;
                        }
                    }
                    continue;
                }
                let mut weights = active;
                if !matches!(lookups, Lookups::None | Lookups::Core) {
                    for l in 0..lanes.count {
                        weights[l] *= lookups.weight(light, shadow, [u[l], v[l], z[l]]);
                    }
                }
                for l in 0..lanes.count {
                    j_sums[l].x += weights[l];
                }
            }
            self.add_plane(light, planes, lanes, plane, &mut j_sums, &mut sum);
        }
        for (s, length) in sum.iter_mut().zip(&lanes.length).take(lanes.count) {
            *s = light.intensity * *s * (lanes.dz * length / m as f32);
        }
        sum
    }

    /// `I_s` of shafts (7) without the light's colour from the slabs of lane `l`'s ray
    /// that pass near the lamp ([`near_lamp`]), where `1 / s^2` and the phase change
    /// within a slab too fast for one `g` at its plane: in each, points spaced evenly
    /// in the scattering angle, at most [`ANGLE_STEP`] apart (equiangular sampling;
    /// Kulla and Fajardo 2012), since along a line `dt / s^2 = d(alpha) / b`, `b` the
    /// line's distance from the lamp, so each point stands for an equal share of the
    /// geometric term and the peak where the ray passes the lamp is resolved however
    /// narrow. At each, `H I_l` and `g` of shafts (6) as at a sub-sample and a plane.
    /// Out of line: it runs for few rays, and inlined it slowed the sub-sample loop.
    #[inline(never)]
    fn near_slabs(&self, light: &Spotlight, planes: &LightPlanes, lanes: &Lanes, l: usize) -> Vec3 {
        let [za, zb] = lanes.z_lit[l];
        if za >= zb {
            return Vec3::ZERO;
        }
        let (len, dz) = (lanes.length[l], lanes.dz);
        let step = Vec3::new(lanes.step[0][l], lanes.step[1][l], lanes.step[2][l]);
        let slab = dz * len;
        // The ray's nearest approach to the lamp (the light space's origin): its camera
        // depth, the point, and its distance `b`; no slab's centre comes nearer (2 %
        // spared for rounding: each slab below is tested as `add_plane` tests it).
        let d_near = -planes.eye.dot(step) / (len * len);
        let foot = planes.eye + d_near * step;
        if !near_lamp(0.98 * foot.length_squared(), slab) {
            return Vec3::ZERO;
        }
        let b = foot.length().max(1e-6);
        let along = step / len;
        let n = self.scene.planes.planes as usize;
        let plane_of = |z: f32| ((z - planes.z_near) / dz).clamp(0.0, (n - 1) as f32) as usize;
        let mut total = Vec3::ZERO;
        for plane in plane_of(za)..=plane_of(zb) {
            let z0 = planes.z_near + plane as f32 * dz;
            let centre = slab_centre(
                planes.eye,
                planes.z_near + (plane as f32 + 0.5) * dz,
                step.into(),
            );
            if !near_lamp(centre.length_squared(), slab) {
                continue;
            }
            // The scattering angle at the slab's ends: atan2(b, -tau), tau the distance
            // along the ray from its nearest approach.
            let angle = |z: f32| b.atan2(-(z - d_near) * len);
            let (a0, a1) = (angle(z0), angle(z0 + dz));
            let count = ((a1 - a0) / ANGLE_STEP)
                .ceil()
                .clamp(1.0, MAX_ANGLE_SAMPLES) as u32;
            let d_angle = (a1 - a0) / count as f32;
            let mut slab_sum = Vec3::ZERO;
            for j in 0..count {
                let (sin, cos) = (a0 + (j as f32 + 0.5) * d_angle).sin_cos();
                let tau = -b * cos / sin;
                let depth = d_near + tau / len;
                if depth < za || depth >= zb {
                    continue;
                }
                let local = foot + tau * along;
                let weight = self.lit_profile(light, planes, local);
                if weight == Vec3::ZERO {
                    continue;
                }
                let s_haze = if planes.lamp_in_haze {
                    b / sin
                } else {
                    let eye = self.scene.camera.position;
                    self.scene
                        .haze
                        .length_inside(light.position, eye + depth * lanes.ray[l])
                };
                let t_haze = (depth * len - lanes.entry[l]).max(0.0);
                let g = self.phase.get(cos) * self.attenuation.get(s_haze, t_haze);
                slab_sum += weight * g;
            }
            total += slab_sum * (d_angle / b);
        }
        total
    }

    /// `H I_l` (with the gobo's colour; otherwise in every channel) at a light-space
    /// point, as a sub-sample takes it.
    fn lit_profile(&self, light: &Spotlight, planes: &LightPlanes, local: Vec3) -> Vec3 {
        let z = local.z.max(1e-6);
        let scale = 1.0 / (light.tan_field() * z);
        let (u, v) = (local.x * scale, local.y * scale);
        let weight = Lookups::Both.weight(light, &planes.shadow, [u, v, z]);
        match &light.gobo {
            Some(gobo) if weight > 0.0 => weight * gobo.sample_turned(u, v, gobo.turn()),
            _ => Vec3::splat(weight),
        }
    }

    /// Adds `J_i g_i` of plane `plane` to each lane's `sum` and clears `j_sums`: `g` of
    /// shafts (6) from the plane's light-space position, positions first, then lookups.
    fn add_plane(
        &self,
        light: &Spotlight,
        planes: &LightPlanes,
        lanes: &Lanes,
        plane: usize,
        j_sums: &mut [Vec3; LANES],
        sum: &mut [Vec3; LANES],
    ) {
        let haze = &self.scene.haze;
        let eye = self.scene.camera.position;
        let origin = planes.eye;
        let [sx, sy, sz] = &lanes.step;
        let depth = planes.z_near + (plane as f32 + 0.5) * lanes.dz;
        let (mut cos_alpha, mut s_haze, mut t_haze, mut inv_s2) = (
            [0.0f32; LANES],
            [0.0f32; LANES],
            [0.0f32; LANES],
            [0.0f32; LANES],
        );
        let mut near = [false; LANES];
        for l in 0..LANES {
            let local = slab_centre(origin, depth, [sx[l], sy[l], sz[l]]);
            let s2 = local.length_squared();
            near[l] = near_lamp(s2, lanes.dz * lanes.length[l]);
            let inv_s = s2.sqrt().recip();
            let dot = local.x * sx[l] + local.y * sy[l] + local.z * sz[l];
            cos_alpha[l] = -dot * inv_s * lanes.inv_length[l];
            s_haze[l] = s2 * inv_s;
            t_haze[l] = (depth * lanes.length[l] - lanes.entry[l]).max(0.0);
            inv_s2[l] = inv_s * inv_s;
        }
        let gobo = light.gobo.is_some();
        for l in 0..lanes.count {
            let js = std::mem::take(&mut j_sums[l]);
            if js == Vec3::ZERO || near[l] {
                continue;
            }
            if !planes.lamp_in_haze {
                s_haze[l] = haze.length_inside(light.position, eye + depth * lanes.ray[l]);
            }
            let g = self.phase.get(cos_alpha[l])
                * self.attenuation.get(s_haze[l], t_haze[l])
                * inv_s2[l];
            sum[l] += if gobo { js } else { Vec3::splat(js.x) } * g;
        }
    }
}

/// A slab passes near the lamp, and is summed at points evenly spaced in the scattering
/// angle, when its length along the ray is more than this times its centre's distance
/// from the lamp: there one `g` at the plane errs by 2 % and more (the midpoint rule
/// on `1 / s^2` where the ray passes the lamp: `(length / s)^2 / 12`), and by far more
/// where it passes closer (the lamp's own pixels came out dark). Fig. 6 against the
/// converged reference: RMS 0.082 levels, max 9.3 at 0.25; 0.072, max 4.8 at 0.5; at 1
/// the ring 10 to 15 pixels from the lamp's image stays 0.66 levels RMS (0.09 at 0.5).
pub const NEAR_LAMP: f32 = 0.5;

/// Largest spacing of a near slab's points in the scattering angle, radians, and most
/// points a slab takes.
pub const ANGLE_STEP: f32 = 0.05;
/// (See [`ANGLE_STEP`].)
pub const MAX_ANGLE_SAMPLES: f32 = 64.0;

/// Whether a slab `slab` m long whose centre is `sqrt(s2)` m from the lamp passes near
/// it ([`NEAR_LAMP`]).
#[inline(always)]
fn near_lamp(s2: f32, slab: f32) -> bool {
    s2 * (NEAR_LAMP * NEAR_LAMP) < slab * slab
}

/// The light-space point at camera depth `depth` on the ray from `origin` (the eye in
/// the light's space) with light-space step `step` per metre of depth.
#[inline(always)]
fn slab_centre(origin: Vec3, depth: f32, [sx, sy, sz]: [f32; 3]) -> Vec3 {
    Vec3::new(
        origin.x + depth * sx,
        origin.y + depth * sy,
        origin.z + depth * sz,
    )
}

/// The shadow map of each light of `scene`, in scene order.
pub fn shadow_maps(scene: &Scene) -> Vec<ShadowMap> {
    let size = scene.planes.shadow_map as usize;
    scene
        .lights()
        .map(|light| ShadowMap::new(light, &scene.objects, size))
        .collect()
}

/// The scene by the plane method.
pub fn render(scene: &Scene) -> Frame {
    SamplePlanes::new(scene).render()
}

/// `ceil(x)` for `x >= 0`, else 0, as an index: without the library call `f32::ceil`
/// is on x86-64's baseline instruction set.
#[inline(always)]
fn ceil_nonnegative(x: f32) -> usize {
    if x > 0.0 {
        let t = x as i32;
        (t + (x > t as f32) as i32) as usize
    } else {
        0
    }
}

#[cfg(test)]
mod tests;
