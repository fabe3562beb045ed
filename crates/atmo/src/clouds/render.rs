//! Drawing a cloud (clouds 2.2): each particle a camera-facing Gaussian billboard,
//! composited with `E_k = S_k + T_k E_{k-1}` (5). The paper draws back to front; the
//! same sum taken front to back, `E += T_acc S_k`, `T_acc *= T_k`, lets a pixel stop
//! once almost nothing gets through it (a thousandth), which in a thick cloud is after
//! a few layers of the many behind. Unlike Harris's per-particle `I_k`, the sunlight
//! is looked up in the 3-D intensity buffer per pixel (trilinear), the quality gain of
//! clouds 3.3: detail finer than a particle. Where clouds (6) takes
//! `S_k = a_k tau_k p I_k / 4 pi` for a thin particle, each pixel here follows its own
//! ray through the blob and integrates the light the blob sends along it, what it
//! absorbs of its own light included ([`Emission`]), for every octave of
//! [`Octaves`] (docs/clouds.md, "Drawing"), or single scattering and the orders past
//! the first from a [`TransferTable`] ([`Scattering`]). A billboard's row is drawn
//! eight pixels at a time in SIMD lanes (the `wide` crate): the pixel's arithmetic, not
//! memory, was the frame's cost, and on two cores this draws the bench's frame 2.35
//! times faster than a pixel at a time.
//!
//! The blobs beside. Composited by their centres, a blob's light is dimmed by the whole
//! of every blob before it and by nothing of those after, where overlapping blobs
//! really share the depth: a blob's light comes from its emission nodes, and the
//! depth in front of node `j` at `l_j` standard deviations `s` from the blob's middle
//! is the blobs' before less their parts behind the node, plus the parts in front of
//! it of those after. Where the blobs' centres are spread evenly along the ray about
//! the node (a mean field), those differ by `sigma_o l_j s`, `sigma_o` the other
//! blobs' extinction at the node (the buffer's slope of `ln Gamma` along the light,
//! [`IntensityBuffer::extinction`], less the blob's own): the node's light is dimmed
//! by that much more, or less. On the 200-particle cloud of `tests/clouds_light.rs`
//! the picture's single scattering went from 0.942, 0.946 and 0.985 of the quadrature
//! (sun from the front, the side and behind) to 1.006, 0.995 and 0.993, with the third
//! emission node. In a scratch harness that knew every blob of a pixel (unfaded, in
//! double precision), the mean field gave 1.013, 1.002 and 1.005 and the blobs' exact
//! parts in front of each node 0.990, 0.982 and 0.994: the mean field is as good as
//! knowing them. It needs nothing of the pixel, so the GPU's blended billboards draw
//! it too.
//!
//! Thin columns. Eight pixels whose columns through a blob are all under
//! 0.1 (the outer rings of the footprints, where a blob absorbs little)
//! take the midpoint rule: one node, where the ray passes nearest the centre, for the
//! three. On the bench's frame (the solve's light) that drew a fifth fewer instructions
//! and moved the picture by 0.06 level RMS (a pixel's median 0.09 %, at most 3 %); the
//! 200-particle cloud's single scattering stayed within 1 % of the quadrature. Not
//! with a transfer table, whose lookups by the nodes' depths it would move; the GPU
//! draws three nodes everywhere.

use glam::Vec3;
use rayon::prelude::*;

use super::buffer::IntensityBuffer;
use super::diffusion::{DiffuseLight, Diffusion, Seen};
use super::octaves::{Emission, OctaveTerms, Octaves};
use super::particles::{tabulated_emission_nodes_lanes, weighted_lanes, Particle, EMISSION_NODES};
use super::sky_light::SkyLight;
use super::transfer::{Cells, CloudDepths, Slices, TransferTable};
use crate::atmosphere::phase::PhaseFunction;
use crate::error::{Error, Result};
use crate::image::Frame;
use crate::lanes::{exp_lanes, Lanes, LANES};
use crate::view::Camera;

/// How the cloud is lit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CloudLight {
    /// Unit vector toward the sun.
    pub to_sun: Vec3,
    /// Sunlight arriving at the cloud, RGB (irradiance in any units: pixels come out in
    /// the same per steradian).
    pub sun: Vec3,
    /// The sky's radiance around the cloud (the paper has none), which the droplets
    /// scatter toward the eye by their phase function and every order of
    /// `scattering`'s octaves ([`SkyLight::scattered`], [`Scattering::octaves`]);
    /// [`SkyLight::NONE`] for none.
    pub ambient: SkyLight,
    /// The droplets' phase function (clouds (6)'s `p`), e.g.
    /// [`PhaseFunction::CloudMie`].
    pub phase: PhaseFunction,
    /// Single scattering, or every order.
    pub scattering: Scattering,
    /// The air between the eye and the cloud.
    pub haze: AerialHaze,
}

/// How the sun's light scattered more than once is drawn.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Scattering {
    /// By octaves of single scattering ([`Octaves`]; [`Octaves::SINGLE`] for single
    /// scattering alone).
    Octaves(Octaves),
    /// Single scattering and a transfer table for the orders past the first
    /// ([`TransferTable`]).
    Transfer(&'static TransferTable),
    /// Single scattering and the orders past the first by solving their transfer
    /// through the cloud ([`DiffuseLight`]).
    Solve(Diffusion),
}

impl Scattering {
    /// Single scattering: the paper's model.
    pub const SINGLE: Scattering = Scattering::Octaves(Octaves::SINGLE);
    /// Every order, by the table fitted to the path tracer.
    pub const MULTIPLE: Scattering = Scattering::Transfer(&TransferTable::FITTED);
    /// Every order, by the transfer solve on its default grid: the nearest the path
    /// tracer, and what `atmo clouds` draws by default.
    pub const SOLVE: Scattering = Scattering::Solve(Diffusion::DEFAULT);

    /// The octaves the sky's light follows (its tilt, [`SkyLight::scattered`], and its
    /// dimming inside the cloud): these octaves, or with a table [`Octaves::MULTIPLE`].
    pub fn octaves(&self) -> Octaves {
        match self {
            Scattering::Octaves(octaves) => *octaves,
            Scattering::Transfer(_) | Scattering::Solve(_) => Octaves::MULTIPLE,
        }
    }

    /// The octaves each blob's own light is drawn by: these octaves, or with a table
    /// single scattering (the table adds the rest).
    pub fn blob_octaves(&self) -> Octaves {
        match self {
            Scattering::Octaves(octaves) => *octaves,
            Scattering::Transfer(_) | Scattering::Solve(_) => Octaves::SINGLE,
        }
    }

    /// The table, if the orders past the first are drawn by one.
    pub fn table(&self) -> Option<&'static TransferTable> {
        match self {
            Scattering::Transfer(table) => Some(table),
            _ => None,
        }
    }

    /// The transfer solve's settings, if the orders past the first are solved.
    pub fn diffusion(&self) -> Option<Diffusion> {
        match self {
            Scattering::Solve(diffusion) => Some(*diffusion),
            _ => None,
        }
    }

    /// Refuses octaves or a solve outside their ranges, naming the field.
    pub fn validate(&self) -> Result<()> {
        self.octaves().validate()?;
        self.diffusion().map_or(Ok(()), |d| d.validate())
    }
}

/// The atmosphere between the eye and the cloud (its aerial perspective,
/// [`crate::sky::aerial`]), one value for the whole cloud at its distance: the cloud's
/// light reaches the eye times `transmittance`, and the air in front of it adds
/// `inscatter` where the cloud hides what is behind (RGB).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AerialHaze {
    pub transmittance: Vec3,
    pub inscatter: Vec3,
}

impl AerialHaze {
    /// No air between the eye and the cloud.
    pub const CLEAR: AerialHaze = AerialHaze {
        transmittance: Vec3::ONE,
        inscatter: Vec3::ZERO,
    };
}

/// Rows drawn together by one thread.
const BAND: usize = 8;

/// Columns of a block whose opacity is tracked, to skip particles hidden behind it.
const BLOCK: usize = 16;

/// Draws `particles` lit through `buffer` over `background` (same size as the camera's
/// image, or black); an error for a fisheye camera.
pub fn render(
    particles: &[Particle],
    buffer: &IntensityBuffer,
    camera: &Camera,
    light: &CloudLight,
    background: Option<&Frame>,
) -> Result<Frame> {
    let depths = if needs_depths(light) {
        CloudDepths::of(particles)?
    } else {
        CloudDepths::default()
    };
    let diffuse = solve_for(particles, buffer, light, None)?;
    render_with_depths(
        particles,
        &depths,
        buffer,
        diffuse.as_ref(),
        camera,
        light,
        background,
    )
}

/// The transfer solve `light` draws with, if it draws with one ([`Scattering::Solve`]),
/// for `particles` lit through `buffer`; `previous` starts it (the module doc of
/// [`super::diffusion`]).
pub fn solve_for(
    particles: &[Particle],
    buffer: &IntensityBuffer,
    light: &CloudLight,
    previous: Option<&DiffuseLight>,
) -> Result<Option<DiffuseLight>> {
    light
        .scattering
        .diffusion()
        .map(|settings| {
            DiffuseLight::solve(
                particles,
                buffer,
                light.to_sun,
                light.phase,
                &light.ambient,
                &settings,
                previous,
            )
        })
        .transpose()
}

/// Whether `light` dims the sky's light inside the cloud, and so needs the particles'
/// depths down the vertical ([`CloudDepths::vertical`]).
pub fn dims_the_sky(light: &CloudLight) -> bool {
    light.scattering.diffusion().is_none()
        && !light.ambient.dimming(&light.scattering.octaves()).is_flat()
}

/// Whether drawing with `light` reads the particles' [`CloudDepths`]: where the sky's
/// light is dimmed inside the cloud ([`dims_the_sky`]) or a transfer table draws the
/// orders past the first (its `tau_out`).
pub fn needs_depths(light: &CloudLight) -> bool {
    dims_the_sky(light) || light.scattering.table().is_some()
}

/// [`render`] with the particles' depths given ([`CloudDepths::of`]), for a caller that
/// draws the same particles again under another sun or from another camera: they
/// depend on the particles alone, and making them costs tens of milliseconds for
/// 60,134 particles. Not read (and may be empty) unless [`needs_depths`]. Likewise the
/// transfer solve ([`solve_for`]), which depends on the particles and the sun: needed
/// with [`Scattering::Solve`], not read otherwise.
pub fn render_with_depths(
    particles: &[Particle],
    depths: &CloudDepths,
    buffer: &IntensityBuffer,
    diffuse: Option<&DiffuseLight>,
    camera: &Camera,
    light: &CloudLight,
    background: Option<&Frame>,
) -> Result<Frame> {
    let blob = Pixel::Blob;
    drawn(
        particles, depths, buffer, diffuse, camera, light, background, blob,
    )
}

/// The paper's own billboards, the baseline `atmo bench clouds` times the frame
/// against: each blob's pixel sends `S = a tau p Gamma / 4 pi` (clouds (6), the blob
/// thin) with `Gamma` read from the buffer once, where the pixel's ray passes nearest
/// the blob's centre (on its billboard; the per-fragment read of clouds 4.3), and lets
/// through `e^-tau`. The sun's single scattering alone (`light`'s sun, phase and haze;
/// no sky, the paper's model). The drawing is [`render`]'s (its order, footprints and
/// finished pixels, eight pixels at a time): only the pixel differs, so the two times
/// compare what a pixel costs.
pub fn paper_billboards(
    particles: &[Particle],
    buffer: &IntensityBuffer,
    camera: &Camera,
    light: &CloudLight,
    background: Option<&Frame>,
) -> Result<Frame> {
    let light = CloudLight {
        ambient: SkyLight::NONE,
        scattering: Scattering::SINGLE,
        ..*light
    };
    let none = CloudDepths::default();
    drawn(
        particles,
        &none,
        buffer,
        None,
        camera,
        &light,
        background,
        Pixel::Paper,
    )
}

/// What a blob's pixel computes.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Pixel {
    /// The light the blob sends along the pixel's ray, integrated over its depth at its
    /// emission nodes ([`render`]).
    Blob,
    /// The paper's thin blob lit by one read ([`paper_billboards`]).
    Paper,
}

/// [`render_with_depths`] with the pixel `pixel`.
#[allow(clippy::too_many_arguments)]
fn drawn(
    particles: &[Particle],
    depths: &CloudDepths,
    buffer: &IntensityBuffer,
    diffuse: Option<&DiffuseLight>,
    camera: &Camera,
    light: &CloudLight,
    background: Option<&Frame>,
    pixel: Pixel,
) -> Result<Frame> {
    let (w, h) = (camera.width as usize, camera.height as usize);
    let (_, tan_half_height) = camera.pinhole("the clouds' billboards")?;
    let focal = 0.5 * h as f32 / tan_half_height;
    // Front to back: nearest first (see the module doc).
    let depth: Vec<f32> = particles.iter().map(|p| camera.depth(p.position)).collect();
    let mut order: Vec<usize> = (0..particles.len())
        .filter(|&k| depth[k] > particles[k].reach())
        .collect();
    order.sort_by(|&a, &b| depth[a].total_cmp(&depth[b]).then(a.cmp(&b)));
    // Each particle's footprint on the screen: centre and radius in pixels, the radius
    // of its reach seen at its distance, widened off the axis where the perspective
    // stretches it (by 1 / cos^2 of the angle from the axis).
    let footprint: Vec<(f32, f32, f32)> = order
        .iter()
        .map(|&k| {
            let d = particles[k].position - camera.position;
            let z = depth[k];
            let (tx, ty) = (d.dot(camera.right) / z, d.dot(camera.up) / z);
            let r = particles[k].reach();
            let stretch = 1.0 + tx * tx + ty * ty;
            let (sx, sy) = (tx * focal + 0.5 * w as f32, -ty * focal + 0.5 * h as f32);
            (sx, sy, r / (z * z - r * r).sqrt() * focal * stretch)
        })
        .collect();
    // Each pixel's ray (its component along the view axis 1) is affine in the pixel
    // centre: `r = r0 + x rx + y ry`; so is its step in the buffer's grid.
    let r0 = camera.ray(0.5, 0.5);
    let (rx, ry) = (camera.ray(1.5, 0.5) - r0, camera.ray(0.5, 1.5) - r0);
    // Pixel `k`'s unit ray; its cosine to the sun and the phase function for it, the
    // same for every blob it crosses (one lane-load past the last pixel is read and not
    // used).
    let ray = |k: usize| (r0 + (k % w) as f32 * rx + (k / w) as f32 * ry).normalize();
    let mut cosines = Vec::with_capacity(w * h + LANES);
    cosines.par_extend((0..w * h).into_par_iter().map(|k| light.to_sun.dot(ray(k))));
    cosines.extend([0.0f32; LANES]);
    let phases: Vec<f32> = cosines
        .par_iter()
        .map(|&c| light.phase.eval_f32(c))
        .collect();
    // The sky's light the droplets scatter along a ray, taken where a blob was drawn,
    // and how much of it reaches each particle inside the cloud from above and below.
    let octaves_of_sky = light.scattering.octaves();
    let sky = light.ambient.scattered(light.phase, &octaves_of_sky);
    let dimming = light.ambient.dimming(&octaves_of_sky);
    let given = |what: &str, count: usize| {
        if count == particles.len() {
            Ok(())
        } else {
            Err(Error::Invalid(format!(
                "{count} {what} given for {} particles",
                particles.len()
            )))
        }
    };
    let top_shares: Vec<f32> = if !dims_the_sky(light) {
        vec![0.0; particles.len()]
    } else {
        given("vertical depths", depths.vertical.len())?;
        depths
            .vertical
            .iter()
            .map(|&d| dimming.top_share(d))
            .collect()
    };
    let table = match light.scattering.table() {
        Some(table) => {
            given("depths out of the cloud", depths.out.len())?;
            given("thicknesses", depths.thickness.len())?;
            Some(Tabled {
                cells: table.cells(),
                out: &depths.out,
                slices: depths.thickness.iter().map(|&t| Slices::of(t)).collect(),
            })
        }
        None => None,
    };
    let solved = match light.scattering {
        Scattering::Solve(_) => Some(diffuse.ok_or_else(|| {
            Error::Invalid("the clouds were drawn by a transfer solve without one".into())
        })?),
        _ => None,
    };
    // Where each pixel is finished: at [`OPAQUE`], or, behind a pixel of the background
    // brighter than its median (the sun's disc), as much lower as it is brighter, so
    // that what still shows through stays under 0.1 % of the background's median (a
    // cloud finished at `OPAQUE` in front of the sun let a thousandth of the disc
    // through, a white dot in a thick cloud the GPU, drawing every blob, hides).
    let mut finished = vec![OPAQUE; w * h + LANES];
    if let Some(b) = background {
        // The median of every seventh pixel's: the background's, to a pixel or so.
        let mut brightness: Vec<f32> = b
            .pixels
            .iter()
            .step_by(7)
            .map(|p| p.max_element())
            .collect();
        let middle = brightness.len() / 2;
        let median = *brightness.select_nth_unstable_by(middle, f32::total_cmp).1;
        for (f, p) in finished.iter_mut().zip(&b.pixels) {
            let bright = p.max_element();
            if bright > median {
                *f = OPAQUE * (median / bright);
            }
        }
    }
    let blobs = Blobs {
        particles,
        order: &order,
        footprint: &footprint,
        width: w,
        eye: camera.position,
        rays: [r0, rx, ry],
        grid: [
            buffer.grid_coordinates(camera.position),
            buffer.grid_step(r0),
            buffer.grid_step(rx),
            buffer.grid_step(ry),
        ],
        buffer,
        octaves: light.scattering.blob_octaves().terms(),
        cosines: &cosines,
        phases: &phases,
        top_shares: &top_shares,
        finished: &finished,
        table,
        solved: solved.map(|s| s.seen_from(camera.position)),
        pixel,
    };
    let table = blobs.table.is_some();
    let every_order = table || blobs.solved.is_some();
    let solved_sky = blobs.solved.as_ref().is_some_and(Seen::has_sky);
    let mut frame = Frame::new(camera.width, camera.height);
    frame
        .pixels
        .par_chunks_mut(BAND * w)
        .enumerate()
        .for_each(|(band, pixels)| {
            let mut sums = Sums::new(pixels.len() / w, w, table, solved_sky);
            blobs.draw(band, &mut sums);
            // The sunlight by every order (the higher octaves by the cloud's depth on
            // the ray), the sky's light dimmed inside the cloud, the haze in front of the
            // cloud, then what shows through it.
            let haze = light.haze;
            for (j, e) in pixels.iter_mut().enumerate() {
                let t = sums.through[j];
                let share = if every_order {
                    1.0
                } else {
                    octaves_of_sky.higher_share(t)
                };
                *e = light.sun * (sums.single[j] + share * sums.higher[j]);
                if solved_sky {
                    *e += Vec3::new(sums.sky[0][j], sums.sky[1][j], sums.sky[2][j]);
                } else if sums.skylit[j] > 0.0 {
                    // The blobs' mean share of the light from above, weighted as
                    // their sky light is.
                    let inside = sums.skylit[j] * dimming.at(sums.skytop[j] / sums.skylit[j]);
                    *e += inside * sky.along(ray(band * BAND * w + j));
                }
                *e = haze.transmittance * *e + (1.0 - t) * haze.inscatter;
            }
            if let Some(background) = background {
                let behind = &background.pixels[band * BAND * w..band * BAND * w + pixels.len()];
                for ((e, t), b) in pixels.iter_mut().zip(&sums.through).zip(behind) {
                    *e += *t * *b;
                }
            }
        });
    Ok(frame)
}

/// What drawing the blobs of a frame reads, made once for the frame
/// ([`render_with_depths`]).
struct Blobs<'a> {
    particles: &'a [Particle],
    /// The particles drawn, nearest first, and their footprints on the screen: centre
    /// and radius, pixels.
    order: &'a [usize],
    footprint: &'a [(f32, f32, f32)],
    /// The frame's width, pixels.
    width: usize,
    /// The camera's position.
    eye: Vec3,
    /// Pixel `(x, y)`'s ray is `r0 + x rx + y ry` (its component along the view axis 1).
    rays: [Vec3; 3],
    /// The eye in the buffer's grid, and the rays' steps in it (`g0`, `gx`, `gy`).
    grid: [Vec3; 4],
    buffer: &'a IntensityBuffer,
    octaves: OctaveTerms,
    /// Per pixel (and a lane-load past the last): the cosine of its ray to the sun, and
    /// the phase function of that.
    cosines: &'a [f32],
    phases: &'a [f32],
    /// Per particle: its share of the sky's light from above.
    top_shares: &'a [f32],
    /// Per pixel (and a lane-load past the last) the transmittance below which it is
    /// finished.
    finished: &'a [f32],
    /// With a table, what its lookups read.
    table: Option<Tabled<'a>>,
    /// With a transfer solve, its light seen from the eye.
    solved: Option<Seen>,
    /// What a blob's pixel computes.
    pixel: Pixel,
}

/// The transfer table laid out for drawing, and per particle its depth out of the
/// cloud and its slices of the table by its thickness ([`CloudDepths`]).
struct Tabled<'a> {
    cells: Cells,
    out: &'a [f32],
    slices: Vec<Slices>,
}

/// A band's sums per pixel (and a lane-load past the last): what still gets through
/// from behind; the single-scattered and the higher octaves' light per unit sunlight
/// (the higher kept apart until the pixel's depth is known); the share of the sky's
/// light the blobs scatter (albedo times what each takes out of the pixel's ray), to
/// be times the ray's sky light, and the same times each blob's share of that light
/// from above; with a table, the optical depth in front, `-ln through` (kept as a sum).
struct Sums {
    /// The band's rows.
    rows: usize,
    through: Vec<f32>,
    single: Vec<f32>,
    higher: Vec<f32>,
    skylit: Vec<f32>,
    skytop: Vec<f32>,
    in_front: Vec<f32>,
    /// With a transfer solve that carries the sky's light, that light (RGB).
    sky: [Vec<f32>; 3],
}

impl Sums {
    /// Nothing drawn yet over `rows` rows of `width` pixels, `in_front` kept if `table`,
    /// `sky` if `solved_sky`.
    fn new(rows: usize, width: usize, table: bool, solved_sky: bool) -> Sums {
        let padded = rows * width + LANES;
        let zeros = || vec![0.0f32; padded];
        Sums {
            rows,
            through: vec![1.0; padded],
            single: zeros(),
            higher: zeros(),
            skylit: zeros(),
            skytop: zeros(),
            in_front: if table { zeros() } else { Vec::new() },
            sky: std::array::from_fn(|_| if solved_sky { zeros() } else { Vec::new() }),
        }
    }
}

impl Blobs<'_> {
    /// Draws the blobs over band `band` (rows `BAND band` on) into `sums`, nearest
    /// first, eight pixels of a row at a time.
    fn draw(&self, band: usize, sums: &mut Sums) {
        let w = self.width;
        let [r0, rx, ry] = self.rays;
        let [g_eye, g0, gx, gy] = self.grid;
        let Sums {
            rows: rows_in_band,
            through,
            single,
            higher,
            skylit,
            skytop,
            in_front,
            sky,
        } = sums;
        let (y0, y1) = (band * BAND, (band * BAND + *rows_in_band) as f32);
        let solved_sky = self.solved.as_ref().is_some_and(Seen::has_sky);
        // The table reads the nodes' depths.
        let table = self.table.is_some();
        // The buffer's slope of `ln Gamma` per voxel along the light to the extinction
        // over a standard deviation of the blob, in lanes below: times `-s / voxel`.
        let per_voxel = -1.0 / self.buffer.voxel.y;
        // Blocks of BLOCK columns across the band: whether one of their pixels still
        // lets light through, kept up to date lazily (`dirty` after a particle).
        let blocks = w.div_ceil(BLOCK);
        let (mut open, mut dirty) = (vec![true; blocks], vec![false; blocks]);
        for (&k, &(sx, sy, sr)) in self.order.iter().zip(self.footprint) {
            if sy + sr < y0 as f32 || sy - sr > y1 || sx + sr < 0.0 || sx - sr > w as f32 {
                continue;
            }
            // Behind pixels that are all finished: nothing to draw.
            let b0 = (sx - sr).max(0.0) as usize / BLOCK;
            let b1 = ((sx + sr).max(0.0) as usize / BLOCK).min(blocks - 1);
            let mut any_open = false;
            for b in b0..=b1 {
                if dirty[b] {
                    let cols = b * BLOCK..((b + 1) * BLOCK).min(w);
                    open[b] = (0..*rows_in_band).any(|r| {
                        let row = r * w + cols.start..r * w + cols.end;
                        let band_row = band * BAND * w + row.start..band * BAND * w + row.end;
                        through[row]
                            .iter()
                            .zip(&self.finished[band_row])
                            .any(|(t, f)| t >= f)
                    });
                    dirty[b] = false;
                }
                any_open |= open[b];
            }
            if !any_open {
                continue;
            }
            dirty[b0..=b1].iter_mut().for_each(|d| *d = true);
            let p = &self.particles[k];
            let s = p.sigma();
            let to_depth_per_sigma = Lanes::splat(per_voxel * s);
            let albedo = Lanes::splat(p.albedo);
            let top = Lanes::splat(self.top_shares[k]);
            // The solve's light about the blob (to first order where it is narrow).
            let near = self.solved.as_ref().map(|seen| seen.near(p.position, s));
            // The centre from the eye; its dot with a pixel's ray, affine in the pixel.
            let d = p.position - self.eye;
            let (d2, d0, dx, dy) = (d.length_squared(), d.dot(r0), d.dot(rx), d.dot(ry));
            let rows =
                ((sy - sr).floor().max(y0 as f32) as usize)..((sy + sr).ceil().min(y1) as usize);
            // The reach widened by 1 %: the pixels' rays, affine in the pixel in
            // single precision, stray by up to 0.3 % of it across the frame.
            let cut = d2 as f64 - (1.01 * p.reach() as f64).powi(2);
            for y in rows {
                let yf = y as f32;
                // What is affine in the pixel, at the row's start; per lane below.
                let (r_y, t_y, g_y) = (r0 + yf * ry, d0 + yf * dy, g0 + yf * gy);
                let Some(cols) = row_span(
                    r_y,
                    rx,
                    t_y,
                    dx,
                    cut,
                    (sx - sr - 0.5, (sx + sr - 0.5).min(w as f32 - 1.0)),
                ) else {
                    continue;
                };
                for x in cols.clone().step_by(LANES) {
                    let i = (y - band * BAND) * w + x;
                    let xf = Lanes::splat(x as f32) + LANE_OFFSETS;
                    let t_through = Lanes::from(&through[i..i + LANES]);
                    let finished = Lanes::from(&self.finished[band * BAND * w + i..][..LANES]);
                    let mut live =
                        xf.simd_lt(Lanes::splat(cols.end as f32)) & t_through.simd_ge(finished);
                    if live.none() {
                        continue;
                    }
                    // The pixels' rays, their nearest approach to the centre (at `t`
                    // times the ray) and the column through the blob there.
                    let r = lanes3(r_y, rx, xf);
                    let rr = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
                    let t = (Lanes::splat(t_y) + xf * dx) / rr;
                    let tau =
                        p.faded_column_lanes((Lanes::splat(d2) - t * t * rr).fast_max(Lanes::ZERO));
                    live &= tau.simd_gt(Lanes::ZERO);
                    if live.none() {
                        continue;
                    }
                    // The sunlight at the blob's emission nodes along the ray (see
                    // `emission_nodes`), from which the octaves integrate what the
                    // blob sends toward the eye, with the cloud's extinction there
                    // (the slope of `ln Gamma` along the light) and its whole depth
                    // along the sun's ray through the nearest; the phase for this ray.
                    let g_ray = lanes3(g_y, gx, xf);
                    let phase = Lanes::from(&self.phases[band * BAND * w + i..][..LANES]);
                    if self.pixel == Pixel::Paper {
                        // clouds (6): `a tau p Gamma`, Gamma read where the ray passes
                        // nearest the centre.
                        let at = std::array::from_fn(|c| Lanes::splat(g_eye[c]) + g_ray[c] * t);
                        let gamma = exp_lanes(self.buffer.sample_log_lanes(at));
                        let old = Lanes::from(&single[i..i + LANES]);
                        let new = old + t_through * albedo * tau * phase * gamma;
                        single[i..i + LANES].copy_from_slice(live.select(new, old).as_array());
                        let kept = live.select(t_through * exp_lanes(-tau), t_through);
                        through[i..i + LANES].copy_from_slice(kept.as_array());
                        continue;
                    }
                    let along_scale = Lanes::splat(s) / rr.sqrt();
                    // The grid's point `l` standard deviations along the ray from where
                    // it passes nearest the centre, and the buffer read there (with the
                    // cloud's depth along the light where the octaves need it: at the
                    // first node).
                    let at = |l: Lanes| -> [Lanes; 3] {
                        std::array::from_fn(|c| {
                            Lanes::splat(g_eye[c]) + g_ray[c] * (t + l * along_scale)
                        })
                    };
                    let slab = self.octaves.needs_slab();
                    // A thin column by the midpoint rule: one node where the ray passes
                    // nearest the centre, for eight pixels whose columns are all under
                    // THIN_COLUMN (the fringes of the blobs' footprints). Not with a
                    // table, whose lookups by the nodes' depths it would move.
                    let thin = !table && (tau.simd_lt(Lanes::splat(THIN_COLUMN)) | !live).all();
                    let (nodes, reads) = if thin {
                        let middle = [tau * Lanes::splat(0.5), Lanes::ZERO, Lanes::splat(PHI_0)];
                        let read = if slab {
                            self.buffer.sample_lanes::<true>(at(Lanes::ZERO))
                        } else {
                            self.buffer.sample_lanes::<false>(at(Lanes::ZERO))
                        };
                        ([middle; EMISSION_NODES], [read; EMISSION_NODES])
                    } else {
                        let nodes = if table {
                            tabulated_emission_nodes_lanes::<true>(tau)
                        } else {
                            tabulated_emission_nodes_lanes::<false>(tau)
                        };
                        let reads: [_; EMISSION_NODES] = std::array::from_fn(|j| {
                            if j == 0 && slab {
                                self.buffer.sample_lanes::<true>(at(nodes[j][1]))
                            } else {
                                self.buffer.sample_lanes::<false>(at(nodes[j][1]))
                            }
                        });
                        (nodes, reads)
                    };
                    // The blobs beside (the module doc): the others' extinction at
                    // each node times its distance from the blob's middle.
                    let beside = std::array::from_fn(|j| {
                        let [_, l, phi] = nodes[j];
                        let others =
                            (reads[j][1] * to_depth_per_sigma - tau * phi).fast_max(Lanes::ZERO);
                        others * l
                    });
                    let emission = Emission {
                        tau,
                        log_gamma: reads.map(|r| r[0]),
                        beside,
                        slab: reads[0][2],
                    };
                    let blob = self.octaves.light(phase, &emission);
                    let lit = t_through * albedo;
                    let add = |sums: &mut [f32], v: Lanes| {
                        let old = Lanes::from(&sums[i..i + LANES]);
                        let new = live.select(old + lit * v, old);
                        sums[i..i + LANES].copy_from_slice(new.as_array());
                    };
                    add(single, blob.single);
                    let absorbed = Lanes::ONE - blob.transmitted;
                    match (&self.table, &near) {
                        (None, Some(near)) => {
                            // The solve's light toward the eye at the emission nodes'
                            // mean place (the grid's cells are wider than the blob's
                            // depth between its nodes: reading it at each node cost
                            // a third of the frame).
                            let at = t + weighted_lanes(|j| nodes[j][1]) * along_scale;
                            let point =
                                std::array::from_fn(|c| Lanes::splat(self.eye[c]) + r[c] * at);
                            if solved_sky {
                                // The sky's light through the same solve, every order.
                                let [sun, rgb @ ..] = near.lanes::<4>(&point);
                                add(higher, sun * absorbed);
                                for (sums, v) in sky.iter_mut().zip(rgb) {
                                    add(sums, v * absorbed);
                                }
                            } else {
                                let [sun] = near.lanes::<1>(&point);
                                add(higher, sun * absorbed);
                            }
                        }
                        (None, None) => add(higher, blob.higher),
                        (Some(Tabled { cells, out, slices }), _) => {
                            // The table's light at the emission nodes' mean depths
                            // toward the sun and toward the eye (the cloud's in front
                            // and theirs into the blob), the least of those and the
                            // particle's depth out, and the ray's angle.
                            let front = Lanes::from(&in_front[i..i + LANES]);
                            let eye = front + weighted_lanes(|j| nodes[j][0]);
                            let sun = -weighted_lanes(|j| emission.log_gamma[j]);
                            let f = cells.at(
                                slices[k],
                                sun,
                                eye.fast_min(sun).fast_min(Lanes::splat(out[k])),
                                Lanes::from(&self.cosines[band * BAND * w + i..][..LANES]),
                                eye,
                            );
                            add(higher, f * absorbed);
                            let sum = live.select(front + tau, front);
                            in_front[i..i + LANES].copy_from_slice(sum.as_array());
                        }
                    }
                    if near.is_none() {
                        // The sky's light dimmed inside the cloud, where no solve
                        // carries it.
                        add(skylit, absorbed);
                        add(skytop, absorbed * top);
                    }
                    let kept = live.select(t_through * blob.transmitted, t_through);
                    through[i..i + LANES].copy_from_slice(kept.as_array());
                }
            }
        }
    }
}

/// The pixels of a row whose rays pass within a blob's reach, of those whose centres
/// are within `bounds` (its footprint's, continuous): the rays `r_y + x rx` (pixel
/// `x`'s centre at `x`) with `(d . r)^2 > cut |r|^2`, `d` the centre from the eye,
/// `d . r = t_y + x dx` and `cut = |d|^2 - reach^2 > 0`. A quadratic in `x`: the row's
/// chord of the blob's silhouette, an ellipse on the screen where the blob is within
/// 90 degrees of the view's axis (in double precision: its terms are squares of
/// kilometres that nearly cancel). The chord is the drawing's own test up to its
/// rounding (the blob's column fades to 0 at the reach); `None` where the row misses
/// it. Drawing the chord rather than the footprint's square takes the bench's frame
/// from 358, 387 and 363 ms to 337, 353 and 344 (alternated, a host about 1.6 times
/// slower than quiet): 6 %.
#[inline]
fn row_span(
    r_y: Vec3,
    rx: Vec3,
    t_y: f32,
    dx: f32,
    cut: f64,
    bounds: (f32, f32),
) -> Option<std::ops::Range<usize>> {
    let (r_y, rx, t_y, dx) = (r_y.as_dvec3(), rx.as_dvec3(), t_y as f64, dx as f64);
    // a x^2 + 2 b x + c > 0, bounded along the row where a < 0.
    let a = dx * dx - cut * rx.length_squared();
    let b = t_y * dx - cut * r_y.dot(rx);
    let c = t_y * t_y - cut * r_y.length_squared();
    let (mut lo, mut hi) = (bounds.0 as f64, bounds.1 as f64);
    if a < 0.0 {
        let disc = b * b - a * c;
        if disc < 0.0 {
            return None;
        }
        let root = disc.sqrt();
        lo = lo.max((-b + root) / a);
        hi = hi.min((-b - root) / a);
    }
    let (start, end) = (lo.ceil().max(0.0), hi.floor() + 1.0);
    (start < end).then_some(start as usize..end as usize)
}

/// The lanes' offsets from the first pixel of eight along a row.
const LANE_OFFSETS: Lanes = Lanes::new([0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]);

/// `a + x b`, componentwise, for eight `x`.
#[inline(always)]
fn lanes3(a: Vec3, b: Vec3, x: Lanes) -> [Lanes; 3] {
    std::array::from_fn(|c| Lanes::splat(a[c]) + x * b[c])
}

/// Columns under this are drawn by the midpoint rule (the module doc, "Thin columns").
const THIN_COLUMN: f32 = 0.1;

/// The standard normal density at 0, `1 / sqrt(2 pi)`.
const PHI_0: f32 = 0.398_942_3;

/// A pixel that lets less than this through from behind is finished: the particles
/// still to come would change it by less than 0.1 %.
pub const OPAQUE: f32 = 1e-3;
