//! Pictures of the sky: a camera's pixels turned into directions, looked up in the
//! skylight map (bilinear, sky 4.2), with the ground below the horizon and the sun's
//! disc.
//!
//! The camera is in the world frame of [`crate::view`]; directions are turned into the
//! sky's own frame (x east, y north, z up) by [`sky_from_world`].

use glam::{DVec3, Vec2, Vec3, Vec3A};
use rayon::prelude::*;

use super::shells::sun_disc_radiance;
#[cfg(feature = "table")]
use super::table::SkylightTable;
use super::{DirectionGrid, SkyModel, SkylightMap};
use crate::atmosphere::geometry::horizon_dip;
use crate::atmosphere::optical_depth::transmittance_to_sun;
use crate::atmosphere::spectrum::SpectrumToRgb;
use crate::atmosphere::Atmosphere;
#[cfg(feature = "table")]
use crate::error::Result;
use crate::fast::fast_acos;
use crate::image::{Frame, Levels, TexelOrder};
use crate::view::{Camera, Sun};

/// The sky's own frame (x east, y north, z up, centred on the planet's axis through
/// the viewpoint) from the world frame (x east, y up, z south; [`crate::view`]): a
/// rotation, exact in floating point.
#[inline]
pub fn sky_from_world(v: Vec3) -> Vec3 {
    Vec3::new(v.x, -v.z, v.y)
}

/// What to draw: the camera (its orientation and lens; the viewpoint's altitude is the
/// model's or the table's) and whether the sun's disc is in the picture.
#[derive(Debug, Clone)]
pub struct View {
    /// The camera, world frame.
    pub camera: Camera,
    /// Whether to draw the sun's disc.
    pub sun_disc: bool,
}

/// The constants of the bilinear lookup (sky 4.2) in a [`DirectionGrid`], in f32 for
/// the per-pixel path.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridLookup {
    /// Points in azimuth.
    pub azimuths: usize,
    /// Grid columns per radian of azimuth.
    pub x_scale: f32,
    /// Lowest elevation, rad, and grid rows per radian of elevation.
    pub y_min: f32,
    pub y_scale: f32,
    /// Largest column and row indices, as f32.
    pub x_last: f32,
    pub y_last: f32,
}

impl GridLookup {
    /// The lookup constants of `grid`.
    pub fn new(grid: &DirectionGrid) -> Self {
        let (x_last, y_last) = ((grid.azimuths - 1) as f32, (grid.elevations - 1) as f32);
        GridLookup {
            azimuths: grid.azimuths,
            x_scale: x_last / std::f32::consts::PI,
            y_min: grid.elevation_min as f32,
            y_scale: y_last / (grid.elevation_max - grid.elevation_min) as f32,
            x_last,
            y_last,
        }
    }
}

/// Radiance over a grid of directions, linear sRGB, ready for bilinear lookups.
struct RgbGrid {
    /// Values in SIMD-aligned vectors, for the lookups' arithmetic.
    rgb: Vec<Vec3A>,
    lookup: GridLookup,
}

impl RgbGrid {
    fn new(grid: &DirectionGrid, rgb: Vec<Vec3>) -> Self {
        RgbGrid {
            // Radiance is never negative; clamping here keeps the per-pixel path lean.
            rgb: rgb
                .into_iter()
                .map(|v| Vec3A::from(v).max(Vec3A::ZERO))
                .collect(),
            lookup: GridLookup::new(grid),
        }
    }

    fn of_map(map: &SkylightMap, colour: &SpectrumToRgb) -> Self {
        let rgb = map.to_rgb(colour).into_iter().map(Vec3::from).collect();
        Self::new(&map.grid, rgb)
    }

    /// Bilinear interpolation at (azimuth from the sun in [0, pi], elevation), rad,
    /// clamped to the grid. (Inlined always: left to itself the compiler calls it
    /// once a pixel from the shading loop.)
    #[inline(always)]
    fn sample(&self, azimuth: f32, elevation: f32) -> Vec3A {
        let g = &self.lookup;
        let x = (azimuth * g.x_scale).clamp(0.0, g.x_last);
        let y = ((elevation - g.y_min) * g.y_scale).clamp(0.0, g.y_last);
        let (i, j) = (
            (x as usize).min(g.azimuths - 2),
            (y as usize).min(g.y_last as usize - 1),
        );
        let (fx, fy) = (x - i as f32, y - j as f32);
        let at = j * g.azimuths + i;
        let (r0, r1) = (
            &self.rgb[at..at + 2],
            &self.rgb[at + g.azimuths..at + g.azimuths + 2],
        );
        let lo = r0[0].lerp(r0[1], fx);
        let hi = r1[0].lerp(r1[1], fx);
        lo.lerp(hi, fy)
    }
}

/// The skylight map of one sun (and, from a model, the ground map), in linear sRGB,
/// ready to sample.
pub struct SkyPicture {
    sky: RgbGrid,
    /// Directions below `ground_below`: the ground map of a model; a table has none,
    /// and those pixels stay black.
    ground: Option<RgbGrid>,
    /// Elevation below which the ground map applies, rad.
    ground_below: f32,
    /// Horizontal unit vector toward the sun's azimuth.
    sun_horizontal: Vec2,
    sun_direction: Vec3,
    sun_rgb: Vec3A,
    sun_cos_radius: f32,
    /// Angular radius of the disc, rad.
    sun_radius: f32,
}

impl SkyPicture {
    /// Computes the maps of `model` for `sun`.
    pub fn new(model: &SkyModel, sun: Sun) -> Self {
        let colour = SpectrumToRgb::for_atmosphere(model.atmosphere());
        let sky = model.skylight_map(sun.elevation());
        let ground = model.ground_map(sun.elevation());
        Self::of_model_maps(
            model,
            sun,
            RgbGrid::of_map(&sky, &colour),
            RgbGrid::of_map(&ground, &colour),
        )
    }

    /// A picture of `model`'s sky for `sun` from its skylight and ground maps computed
    /// elsewhere (a GPU's shell pass), as linear sRGB `[elevation][azimuth]` on the
    /// model's grids.
    pub fn from_model_maps(model: &SkyModel, sun: Sun, sky: Vec<Vec3>, ground: Vec<Vec3>) -> Self {
        let (sky_grid, ground_grid) = model.grids();
        Self::of_model_maps(
            model,
            sun,
            RgbGrid::new(sky_grid, sky),
            RgbGrid::new(ground_grid, ground),
        )
    }

    fn of_model_maps(model: &SkyModel, sun: Sun, sky: RgbGrid, ground: RgbGrid) -> Self {
        let atmosphere = model.atmosphere();
        let colour = SpectrumToRgb::for_atmosphere(atmosphere);
        let mut sun_spectrum = vec![0.0; atmosphere.channels()];
        model.sun_radiance(sun.elevation(), &mut sun_spectrum);
        Self::with_maps(
            atmosphere,
            sun,
            sky,
            Some(ground),
            -horizon_dip(atmosphere.bottom_radius_m, model.altitude_m()),
            colour.rgb(&sun_spectrum),
        )
    }

    /// Draws the skylight map of `sun` seen from `altitude_m` from `table` (sky 4.2);
    /// an error outside the table's ranges. The table holds the sky above the horizon;
    /// below it, where an application draws its terrain, the picture is black.
    #[cfg(feature = "table")]
    pub fn from_table(table: &SkylightTable, sun: Sun, altitude_m: f64) -> Result<Self> {
        let map = table.map(sun.elevation(), altitude_m)?;
        Ok(Self::from_table_map(table, sun, altitude_m, map))
    }

    /// A picture of `map`, a skylight map of `table` for `sun` at `altitude_m`.
    #[cfg(feature = "table")]
    pub fn from_table_map(
        table: &SkylightTable,
        sun: Sun,
        altitude_m: f64,
        map: Vec<Vec3>,
    ) -> Self {
        let atmosphere = table.atmosphere();
        let grid = table.grid(altitude_m);
        let ground_below = grid.elevation_min;
        Self::with_maps(
            atmosphere,
            sun,
            RgbGrid::new(&grid, map),
            None,
            ground_below,
            sun_disc_rgb(atmosphere, altitude_m, sun.elevation()),
        )
    }

    fn with_maps(
        atmosphere: &Atmosphere,
        sun: Sun,
        sky: RgbGrid,
        ground: Option<RgbGrid>,
        ground_below: f64,
        sun_rgb: [f32; 3],
    ) -> Self {
        let (sin_a, cos_a) = sun.azimuth().sin_cos();
        SkyPicture {
            sky,
            ground,
            ground_below: ground_below as f32,
            sun_horizontal: Vec2::new(sin_a as f32, cos_a as f32),
            sun_direction: sky_from_world(sun.toward()),
            sun_rgb: Vec3A::from(sun_rgb),
            sun_cos_radius: atmosphere.sun_angular_radius.cos() as f32,
            sun_radius: atmosphere.sun_angular_radius as f32,
        }
    }

    /// Linear sRGB radiance seen along the world direction `d` (world frame).
    pub fn radiance(&self, d: DVec3, sun_disc: bool) -> Vec3 {
        let mut rays = Rays::default();
        rays.fill(1, |_| sky_from_world(d.normalize().as_vec3()));
        let mut out = [Vec3::ZERO];
        let edges = Edges {
            sun_disc,
            pixel: 0.0,
            sun_cos_outer: self.sun_cos_radius,
        };
        self.shade(&mut rays, edges, &mut out);
        out[0]
    }

    /// The radiance along `rays` into `out`. The trigonometry runs over whole arrays
    /// first, in loops the compiler vectorises, then the map lookups one ray at a time:
    /// a 1920 x 1080 frame takes a few milliseconds.
    fn shade(&self, rays: &mut Rays, edges: Edges, out: &mut [Vec3]) {
        let (sx, sy) = (self.sun_horizontal.x, self.sun_horizontal.y);
        let sun = self.sun_direction;
        // Equal-length slices, so the loop runs without bounds checks.
        let n = rays.x.len();
        let (xs, ys, zs) = (&rays.x[..n], &rays.y[..n], &rays.z[..n]);
        let elevations = &mut rays.elevation[..n];
        let azimuths = &mut rays.azimuth[..n];
        let suns = &mut rays.sun[..n];
        for k in 0..n {
            let (x, y, z) = (xs[k], ys[k], zs[k]);
            let horizontal = (x * x + y * y).sqrt();
            let length = (horizontal * horizontal + z * z).sqrt();
            elevations[k] = std::f32::consts::FRAC_PI_2 - fast_acos(z / length);
            // The azimuth from the sun's, folded into [0, pi] (the sky is symmetric);
            // straight up, any azimuth will do.
            let cos = (x * sx + y * sy) / horizontal.max(1e-30);
            azimuths[k] = fast_acos(if horizontal > 1e-6 * length { cos } else { 1.0 });
            suns[k] = (x * sun.x + y * sun.y + z * sun.z) / length;
        }
        for (k, o) in out.iter_mut().enumerate() {
            let (azimuth, elevation) = (azimuths[k], elevations[k]);
            // No ray (outside the fisheye's circle) has a NaN elevation: black.
            if elevation.is_nan() {
                *o = Vec3::ZERO;
                continue;
            }
            // The sky's share of the pixel: the horizon's edge is smooth over one pixel.
            let above = elevation - self.ground_below;
            let sky = if edges.pixel > 0.0 {
                (above / edges.pixel + 0.5).clamp(0.0, 1.0)
            } else {
                (above >= 0.0) as u8 as f32
            };
            let mut rgb = Vec3A::ZERO;
            if sky > 0.0 {
                rgb += sky * self.sky.sample(azimuth, elevation);
            }
            if let Some(ground) = self.ground.as_ref().filter(|_| sky < 1.0) {
                rgb += (1.0 - sky) * ground.sample(azimuth, elevation);
            }
            if edges.sun_disc && suns[k] >= edges.sun_cos_outer {
                rgb += if edges.pixel > 0.0 {
                    let d = Vec3::new(xs[k], ys[k], zs[k]);
                    self.sun_rgb * disc_cover(d, self.sun_direction, self.sun_radius, edges.pixel)
                } else {
                    self.sun_rgb
                };
            }
            *o = rgb.into();
        }
    }

    /// Renders `view`, rows in parallel.
    pub fn render(&self, view: &View) -> Frame {
        let mut frame = Frame::new(view.camera.width, view.camera.height);
        self.render_into(view, &mut frame);
        frame
    }

    /// Renders `view` into `frame` (of the view's size), rows in parallel.
    pub fn render_into(&self, view: &View, frame: &mut Frame) {
        let camera = view.camera.pixel_basis().rotated(sky_from_world);
        let pixel = camera.pixel_angle();
        self.shade_frame(frame, pixel, view.sun_disc, |x, y| {
            camera.direction(x, y).unwrap_or(Vec3::NAN)
        });
    }

    /// A `width x height` picture whose pixel (x, y) looks along the world direction
    /// `direction(x, y)` (any length), each pixel spanning `pixel` rad: environment
    /// maps and other lenses than a camera's.
    pub fn render_directions(
        &self,
        width: u32,
        height: u32,
        pixel: f32,
        sun_disc: bool,
        direction: impl Fn(u32, u32) -> Vec3 + Sync,
    ) -> Frame {
        let mut frame = Frame::new(width, height);
        self.shade_frame(&mut frame, pixel, sun_disc, |x, y| {
            sky_from_world(direction(x, y))
        });
        frame
    }

    /// Renders `view` as the 8-bit texels of `levels` in `order` (the view's size, row
    /// by row, alpha 255), rows in parallel: what a window shows, without a frame of
    /// radiances between the shading and the levels. Each row is shaded into memory of
    /// its own and turned into levels while it is still in the cache: at 1280 x 720
    /// the frame's 11 MB written and read again took longer than the levels' table.
    pub fn render_texels_into(
        &self,
        view: &View,
        levels: &Levels,
        order: TexelOrder,
        texels: &mut [[u8; 4]],
    ) {
        let camera = view.camera.pixel_basis().rotated(sky_from_world);
        let pixel = camera.pixel_angle();
        let width = view.camera.width as usize;
        self.shade_rows(
            texels,
            width,
            pixel,
            view.sun_disc,
            |x, y| camera.direction(x, y).unwrap_or(Vec3::NAN),
            |row, texels| levels.texels(row, order, texels),
        );
    }

    /// Shades every pixel of `frame`, rows in parallel, along the sky-frame direction
    /// `direction(x, y)` (NaN for none).
    fn shade_frame(
        &self,
        frame: &mut Frame,
        pixel: f32,
        sun_disc: bool,
        direction: impl Fn(u32, u32) -> Vec3 + Sync,
    ) {
        let width = frame.width as usize;
        self.shade_rows(
            &mut frame.pixels,
            width,
            pixel,
            sun_disc,
            direction,
            |row, out| out.copy_from_slice(row),
        );
    }

    /// Shades the rows of `out` (`width` long), in parallel, along the sky-frame
    /// direction `direction(x, y)` (NaN for none), each into a row of radiances that
    /// `put` writes into `out`'s row.
    fn shade_rows<T: Send>(
        &self,
        out: &mut [T],
        width: usize,
        pixel: f32,
        sun_disc: bool,
        direction: impl Fn(u32, u32) -> Vec3 + Sync,
        put: impl Fn(&[Vec3], &mut [T]) + Sync,
    ) {
        let edges = Edges {
            sun_disc,
            pixel,
            sun_cos_outer: (self.sun_radius + pixel).cos(),
        };
        out.par_chunks_mut(width).enumerate().for_each_init(
            || (Rays::default(), Vec::new()),
            |(rays, row), (y, out)| {
                rays.fill(out.len(), |x| direction(x as u32, y as u32));
                row.resize(out.len(), Vec3::ZERO);
                self.shade(rays, edges, row);
                put(row, out);
            },
        );
    }
}

/// How the sun's disc and the horizon end: over one pixel in a picture (anti-aliased:
/// the disc is a few pixels wide, and a hard edge flips whole pixels on the last bit of
/// a direction), in or out for single directions.
#[derive(Debug, Clone, Copy)]
struct Edges {
    /// Whether to draw the sun's disc.
    sun_disc: bool,
    /// The angle a pixel spans, rad; 0 for hard edges.
    pixel: f32,
    /// Directions whose cosine to the sun is below this miss the disc.
    sun_cos_outer: f32,
}

/// The part of a pixel looking along `d` (any length) that the sun's disc (unit
/// direction `sun`, angular radius `radius`) covers: linear over one pixel (`pixel`
/// rad) across the edge. The angle from the centre comes from the cross product,
/// which unlike the dot product keeps its precision near 0.
#[inline]
pub fn disc_cover(d: Vec3, sun: Vec3, radius: f32, pixel: f32) -> f32 {
    let angle = (d.cross(sun).length() / d.length()).min(1.0).asin();
    ((radius - angle) / pixel + 0.5).clamp(0.0, 1.0)
}

/// The linear sRGB radiance of the sun's disc at `sun_elevation` rad seen from
/// `altitude_m` (no limb darkening), through the atmosphere.
pub fn sun_disc_rgb(atmosphere: &Atmosphere, altitude_m: f64, sun_elevation: f64) -> [f32; 3] {
    let colour = SpectrumToRgb::for_atmosphere(atmosphere);
    let mut sun_spectrum = vec![0.0; atmosphere.channels()];
    let r = atmosphere.bottom_radius_m + altitude_m;
    transmittance_to_sun(atmosphere, r, sun_elevation.sin(), &mut sun_spectrum);
    sun_disc_radiance(atmosphere, &mut sun_spectrum);
    colour.rgb(&sun_spectrum)
}

/// Directions (not necessarily unit; NaN where a pixel has none) and their map
/// coordinates, as arrays so the per-ray arithmetic vectorises.
#[derive(Default)]
struct Rays {
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
    /// Elevation, rad.
    elevation: Vec<f32>,
    /// Azimuth from the sun's, in [0, pi].
    azimuth: Vec<f32>,
    /// Cosine of the angle to the sun.
    sun: Vec<f32>,
}

impl Rays {
    /// `n` rays, ray `k` along `direction(k)`.
    fn fill(&mut self, n: usize, direction: impl Fn(usize) -> Vec3) {
        for v in [
            &mut self.x,
            &mut self.y,
            &mut self.z,
            &mut self.elevation,
            &mut self.azimuth,
            &mut self.sun,
        ] {
            v.resize(n, 0.0);
        }
        let (xs, ys, zs) = (&mut self.x[..n], &mut self.y[..n], &mut self.z[..n]);
        for k in 0..n {
            let d = direction(k);
            (xs[k], ys[k], zs[k]) = (d.x, d.y, d.z);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sky_sees_the_world_camera_in_its_own_frame() {
        use crate::view::Fov;
        // Yaw 90 (east), pitch 10: in the sky's frame x east, y north, z up.
        let cam = Camera::yaw_pitch(Vec3::ZERO, 90.0, 10.0, Fov::Vertical(60.0), (101, 101));
        let basis = cam.unwrap().pixel_basis().rotated(sky_from_world);
        let d = basis.direction(50, 50).unwrap().normalize();
        let e = 10f32.to_radians();
        assert!(
            (d - Vec3::new(e.cos(), 0.0, e.sin())).length() < 1e-6,
            "{d}"
        );
        // Pixels to the right are clockwise (toward larger azimuth, here south: -y).
        let right = basis.direction(100, 50).unwrap();
        assert!(right.y < 0.0, "{right}");
        // The dome: zenith in the middle, north on top, east on the left.
        let dome = Camera::dome(Vec3::ZERO, (101, 101)).unwrap();
        let basis = dome.pixel_basis().rotated(sky_from_world);
        assert!((basis.direction(50, 50).unwrap().z - 1.0).abs() < 1e-6);
        assert!(basis.direction(50, 0).unwrap().y > 0.99);
        assert!(basis.direction(0, 50).unwrap().x > 0.99);
    }

    #[test]
    fn grid_lookup_is_exact_at_points_and_linear_between() {
        let grid = DirectionGrid::new(5, 4, -0.1, 1.5);
        let rgb = (0..20).map(|k| Vec3::splat(k as f32)).collect();
        let g = RgbGrid::new(&grid, rgb);
        let at = |i: usize, j: usize| g.sample(grid.azimuth(i) as f32, grid.elevation(j) as f32);
        assert!((at(2, 1).x - 7.0).abs() < 1e-5);
        assert!((at(4, 3).x - 19.0).abs() < 1e-5 && at(0, 0).x.abs() < 1e-5);
        let mid = g.sample(
            (0.5 * (grid.azimuth(2) + grid.azimuth(3))) as f32,
            grid.elevation(1) as f32,
        );
        assert!((mid.x - 7.5).abs() < 1e-5);
        // Below the grid: its lowest row.
        assert!((g.sample(0.0, -1.0).x).abs() < 1e-5);
    }

    #[test]
    fn the_sun_disc_edge_is_smooth_over_one_pixel() {
        let sun = Vec3::new(0.0, 0.6, 0.8);
        let (radius, pixel) = (0.005f32, 0.002f32);
        // Directions at `angle` from the sun's centre, away from it in a fixed plane.
        let at = |angle: f32| {
            let side = sun.cross(Vec3::X).normalize();
            let d = sun * angle.cos() + side * angle.sin();
            disc_cover(3.0 * d, sun, radius, pixel)
        };
        assert_eq!(at(0.0), 1.0);
        assert_eq!(at(radius - pixel), 1.0);
        assert!((at(radius) - 0.5).abs() < 0.02, "{}", at(radius));
        assert_eq!(at(radius + pixel), 0.0);
        // Monotone across the edge.
        let steps: Vec<f32> = (0..20)
            .map(|k| at(radius - pixel + 0.0002 * k as f32))
            .collect();
        assert!(steps.windows(2).all(|w| w[1] <= w[0]), "{steps:?}");
    }
}
