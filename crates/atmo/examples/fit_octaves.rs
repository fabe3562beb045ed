//! The octaves of every order (`atmo::clouds::Octaves`) against the volumetric path
//! tracer over 36 views: three cumulus clouds (200 and 2,000 particles of density
//! 0.006, 9,382 of the generator's 0.04), each seen from above, level and below, the
//! sun 25 deg high from the front, the side and behind and 60 deg high. Prints each
//! view's mean of the octaves over the path tracer's (on the cloud's pixels) and its
//! 8 x 8 blocks within 15 %; with `--search`, a grid search over the octaves' numbers,
//! best worst view first: how `Octaves::MULTIPLE` was chosen (docs/clouds.md, "Every
//! order: octaves"). With `--floor`, the same scores for a second path-traced picture
//! (another seed) in place of the octaves: how far a perfect model would score with
//! the path tracer's noise. With `--oracle`, the scores of the path tracer's own first
//! two orders (another seed) plus the octaves' higher octave and slab's light, each
//! weighted, the best weights first: what a second order computed exactly would leave.
//! With `--transfer`, a transfer table for the orders past the first (four features of
//! a point: its optical depths toward the sun, out of the cloud and toward the eye, and
//! the angle to the sun) fitted by least squares to the path tracer over the views,
//! then over two clouds and scored on the third's views: the lead past the octaves
//! (docs/clouds.md, "Every order: octaves"), measured through the exact density and
//! through the billboards. About a minute and a half.
//!
//! `cargo run --release -p atmo --example fit_octaves -- [--paths N] [--search]
//! [--floor] [--oracle] [--transfer] [--octaves COUNT,A,B,C,K,D,E]` (the fields of
//! `Octaves` in order). The path-traced pictures (48 x 28, N paths a pixel, default 32: a few
//! minutes on two cores for each kind) are kept in the system's temporary folder and
//! reused.

use std::path::Path;

use atmo::atmosphere::PhaseFunction;
use atmo::clouds::octaves::Emission;
use atmo::clouds::particles::{emission_nodes, Particle};
use atmo::clouds::{render, Cumulus, Haze, IntensityBuffer, Lighting, Octaves, SkyLight, Splat};
use atmo::reference::clouds::{Agreement, PathSettings, ReferenceCloud, ReferenceLight};
use atmo::view::{Camera, Fov, Sun};
use faer::linalg::solvers::Solve;
use glam::{DVec3, Vec3};
use rayon::prelude::*;

/// atmo's errors and the file system's.
type Result<T> = std::result::Result<T, Box<dyn std::error::Error>>;

/// The pictures' size, pixels.
const SIZE: (u32, u32) = (48, 28);

/// One view: its cloud's particles, camera and light, the path tracer's picture and
/// which pixels the cloud covers.
struct View {
    name: String,
    particles: Vec<atmo::clouds::Particle>,
    camera: Camera,
    to_sun: Vec3,
    buffer: IntensityBuffer,
    traced: Vec<f64>,
    covered: Vec<bool>,
}

impl View {
    /// The path tracer's picture of this view with `orders` and `seed` at `paths` a
    /// pixel, from the temporary folder when an earlier run made it.
    fn path_traced(&self, paths: usize, orders: usize, seed: u64) -> Result<Vec<f64>> {
        let kind = match (orders, seed) {
            (usize::MAX, 3) => String::new(),
            (usize::MAX, _) => format!("-seed{seed}"),
            _ => format!("-orders{orders}-seed{seed}"),
        };
        let file = std::env::temp_dir()
            .join("atmo-fit-octaves")
            .join(format!("{}{kind}-{paths}.txt", self.name));
        traced(&file, || {
            eprintln!("{}{kind}: path tracing {paths} paths a pixel", self.name);
            let settings = PathSettings {
                paths,
                orders,
                seed,
            };
            self.reference()
                .path_traced_picture(&self.camera, &settings)
                .iter()
                .map(|p| p.0)
                .collect()
        })
    }

    /// The single-scattering quadrature's picture of this view (kept as the path
    /// tracer's are).
    fn single(&self) -> Result<Vec<f64>> {
        let file = std::env::temp_dir()
            .join("atmo-fit-octaves")
            .join(format!("{}-single.txt", self.name));
        traced(&file, || {
            self.reference()
                .single_scattering_picture(&self.camera)
                .iter()
                .map(|p| p.0)
                .collect()
        })
    }

    /// The references' cloud, lit as the billboards' is.
    fn reference(&self) -> ReferenceCloud<'_> {
        ReferenceCloud::new(
            &self.particles,
            ReferenceLight {
                to_sun: self.to_sun.as_dvec3(),
                phase: PhaseFunction::CloudMie,
                sky: 0.0,
            },
        )
    }

    /// The cloud drawn by the billboards with `octaves`, the red channel (the sun is
    /// white).
    fn rendered(&self, octaves: Octaves) -> Result<Vec<f64>> {
        let light = Lighting {
            to_sun: self.to_sun,
            sun: Vec3::ONE,
            ambient: SkyLight::NONE,
            phase: PhaseFunction::CloudMie,
            haze: Haze::CLEAR,
            scattering: octaves,
        };
        let frame = render(&self.particles, &self.buffer, &self.camera, &light, None)?;
        Ok(frame.pixels.iter().map(|p| p.x as f64).collect())
    }

    /// How `picture` agrees with this view's path-traced picture.
    fn agreement(&self, picture: &[f64]) -> Agreement {
        Agreement::of(picture, &self.traced, &self.covered, SIZE.0 as usize)
    }
}

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let value = |flag: &str| {
        args.iter()
            .position(|a| a == flag)
            .and_then(|i| args.get(i + 1))
    };
    let paths: usize = value("--paths").map_or(32, |v| v.parse().expect("--paths N"));
    let octaves = value("--octaves").map_or(Octaves::MULTIPLE, |v| {
        let f: Vec<f32> = v.split(',').map(|x| x.parse().expect("a number")).collect();
        assert_eq!(f.len(), 7, "--octaves COUNT,A,B,C,K,D,E");
        Octaves {
            count: f[0] as u32,
            attenuation: f[1],
            contribution: f[2],
            eccentricity: f[3],
            depth_scale: f[4],
            diffuse: f[5],
            extrapolation: f[6],
        }
    });
    octaves.validate()?;
    let views = views(paths)?;
    for (view, score) in views.iter().zip(scores(&views, &octaves)?) {
        println!(
            "{:<22} octaves / path tracer {:.3}   blocks within 15 %: {} of {} by their means, {} by their medians",
            view.name, score.mean_ratio, score.blocks_within_15, score.blocks, score.medians_within_15
        );
    }
    println!("{octaves:?}: {}", summary(&scores(&views, &octaves)?));
    if args.iter().any(|a| a == "--floor") {
        let scores = views
            .iter()
            .map(|v| Ok(v.agreement(&v.path_traced(paths, usize::MAX, 5)?)))
            .collect::<Result<Vec<_>>>()?;
        println!(
            "the path tracer (seed 5) for the octaves: {}",
            summary(&scores)
        );
    }
    if args.iter().any(|a| a == "--oracle") {
        oracle(&views, &octaves, paths)?;
    }
    if args.iter().any(|a| a == "--transfer") {
        transfer(&views)?;
    }
    if args.iter().any(|a| a == "--search") {
        // Every candidate's worst view, views within 10 % and blocks within 15 %.
        let mut found = Vec::new();
        for count in [1, 2, 3] {
            for contribution in [0.8, 0.9, 1.0] {
                for eccentricity in [0.2, 0.3, 0.4] {
                    for depth_scale in [0.3] {
                        for diffuse in [0.0, 1.0, 1.5, 2.0] {
                            for extrapolation in [2.5, 5.0, 10.0] {
                                let o = Octaves {
                                    count,
                                    attenuation: 0.25,
                                    contribution,
                                    eccentricity,
                                    depth_scale,
                                    diffuse,
                                    extrapolation,
                                };
                                let scores = scores(&views, &o)?;
                                found.push((
                                    worst(&scores),
                                    within(&scores),
                                    blocks(&scores, |s| s.blocks_within_15),
                                    o,
                                ));
                            }
                        }
                    }
                }
            }
        }
        // Of those whose worst view is within 8 % of the best worst view, the most views
        // within 10 %, then the most blocks within 15 %.
        let best = found.iter().map(|f| f.0).fold(f64::INFINITY, f64::min);
        found.retain(|f| f.0 <= 1.08 * best);
        found.sort_by(|a, b| b.1.cmp(&a.1).then(b.2.total_cmp(&a.2)));
        println!("best worst view {best:.3}; within 8 % of it, best first:");
        for (_, _, _, o) in found.iter().take(10) {
            println!("{o:?}: {}", summary(&scores(&views, o)?));
        }
    }
    Ok(())
}

/// Prints the best of the path tracer's first two orders (another seed) plus `x` times
/// the octaves' first higher octave (at `octaves`' own attenuation, or its square) and
/// `y` times the slab's light, each as the billboards draw it with `octaves`' other
/// numbers, over a grid of `x` and `y`: what computing the second order exactly
/// would leave to the model.
fn oracle(views: &[View], octaves: &Octaves, paths: usize) -> Result<()> {
    let mut parts = Vec::new();
    for view in views {
        // Each part drawn alone: the billboards with it less those without it.
        let single = view.rendered(Octaves::SINGLE)?;
        let part = |o: Octaves| -> Result<Vec<f64>> {
            Ok(view
                .rendered(o)?
                .iter()
                .zip(&single)
                .map(|(a, b)| a - b)
                .collect())
        };
        let octave = |attenuation: f32| {
            part(Octaves {
                count: 2,
                attenuation,
                contribution: 1.0,
                diffuse: 0.0,
                ..*octaves
            })
        };
        let slab = part(Octaves {
            count: 1,
            diffuse: 1.0,
            ..*octaves
        })?;
        let a = octaves.attenuation;
        let two = view.path_traced(paths, 2, 11)?;
        parts.push((two, [octave(a)?, octave(a * a)?], slab));
    }
    let mut found = Vec::new();
    for (i, attenuation) in [octaves.attenuation, octaves.attenuation.powi(2)]
        .into_iter()
        .enumerate()
    {
        for x in [0.0, 0.25, 0.5, 0.75, 1.0] {
            for y in [0.0, 0.5, 1.0, 1.5, 2.0, 3.0] {
                let scores: Vec<Agreement> = views
                    .iter()
                    .zip(&parts)
                    .map(|(view, (two, octave, slab))| {
                        let picture: Vec<f64> = (0..two.len())
                            .map(|k| two[k] + x * octave[i][k] + y * slab[k])
                            .collect();
                        view.agreement(&picture)
                    })
                    .collect();
                found.push((
                    blocks(&scores, |s| s.blocks_within_15),
                    format!(
                        "two orders + {x} octave (a {attenuation}) + {y} slab: {}",
                        summary(&scores)
                    ),
                ));
            }
        }
    }
    found.sort_by(|a, b| b.0.total_cmp(&a.0));
    for (_, line) in found.iter().take(8) {
        println!("{line}");
    }
    Ok(())
}

/// The transfer table's axes: the optical depth toward the sun, the least optical
/// depth out of the cloud along the six axes (how deep the point lies), the cosine
/// between the sun's and the view's directions, and the optical depth toward the eye.
const TRANSFER_AXES: [&[f64]; 4] = [
    &[0.0, 0.5, 1.5, 4.0, 10.0, 30.0],
    &[0.0, 0.5, 1.5, 4.0, 10.0],
    &[-1.0, -0.5, 0.0, 0.5, 0.8, 1.0],
    &[0.0, 1.0, 3.0, 8.0],
];

/// A transfer table for the orders past the first, fitted to the path tracer: each
/// pixel is a single scattering plus the table's light, `F(features)` times what each
/// piece of the pixel's ray scatters toward the eye, `F` multilinear over
/// [`TRANSFER_AXES`] and its 720 values fitted by least squares (a little ridge) to the
/// path tracer's light less that single scattering: over every view, then over the
/// views of two clouds and scored on the third's. Two ways: through the particles'
/// exact density (64 steps a ray, the quadrature's single scattering), and through the
/// billboards as `render` composites them (each blob's features at its emission nodes,
/// the billboards' own single scattering; drawn here one pixel at a time in double
/// precision, as a fit needs each pixel's weight of every value of the table).
fn transfer(views: &[View]) -> Result<()> {
    let exact: Vec<Transfer> = views
        .iter()
        .map(|v| {
            Ok(Transfer {
                single: v.single()?,
                rows: transfer_rows(v),
            })
        })
        .collect::<Result<_>>()?;
    fit_transfer(views, &exact, "through the exact density")?;
    let mut billboards = Vec::new();
    for cloud in views.chunk_by(|a, b| a.particles == b.particles) {
        let deepest = deepest(&cloud[0].particles)?;
        for view in cloud {
            billboards.push(billboard_rows(view, &deepest));
        }
    }
    fit_transfer(views, &billboards, "through the billboards")
}

/// One view's pictures for a transfer table: single scattering, and each pixel's weight
/// of every value of the table (merged, sparse).
struct Transfer {
    single: Vec<f64>,
    rows: Vec<Vec<(usize, f64)>>,
}

/// Fits the table to `pictures` (one per view) and prints its scores.
fn fit_transfer(views: &[View], pictures: &[Transfer], how: &str) -> Result<()> {
    let n: usize = TRANSFER_AXES.iter().map(|a| a.len()).product();
    for held_out in [None, Some("c2000"), Some("c200")] {
        let trained = |v: &View| held_out.is_none_or(|c| !v.name.starts_with(&format!("{c}-")));
        let (mut ata, mut atb) = (faer::Mat::<f64>::zeros(n, n), faer::Mat::<f64>::zeros(n, 1));
        for (view, picture) in views.iter().zip(pictures).filter(|(v, _)| trained(v)) {
            for (k, row) in picture
                .rows
                .iter()
                .enumerate()
                .filter(|(k, _)| view.covered[*k])
            {
                let target = view.traced[k] - picture.single[k];
                for &(i, wi) in row {
                    atb[(i, 0)] += wi * target;
                    for &(j, wj) in row {
                        ata[(i, j)] += wi * wj;
                    }
                }
            }
        }
        let ridge = 1e-6 * (0..n).map(|i| ata[(i, i)]).sum::<f64>() / n as f64;
        (0..n).for_each(|i| ata[(i, i)] += ridge);
        let table = ata
            .llt(faer::Side::Lower)
            .map_err(|e| format!("{e:?}"))?
            .solve(&atb);
        let score = |fitted: bool| {
            let scores: Vec<Agreement> = views
                .iter()
                .zip(pictures)
                .filter(|(v, _)| trained(v) == fitted)
                .map(|(view, picture)| {
                    let drawn: Vec<f64> = picture
                        .rows
                        .iter()
                        .zip(&picture.single)
                        .map(|(row, s)| {
                            s + row.iter().map(|&(i, w)| w * table[(i, 0)]).sum::<f64>()
                        })
                        .collect();
                    view.agreement(&drawn)
                })
                .collect();
            summary(&scores)
        };
        match held_out {
            None => println!(
                "transfer table {how}, fitted to every view: {}",
                score(true)
            ),
            Some(c) => println!(
                "transfer table {how}, fitted without {c}: on the others {}; on {c} {}",
                score(true),
                score(false)
            ),
        }
    }
    Ok(())
}

/// Adds `weight` times the table's multilinear weights at `features` to `row`.
fn add_to_row(row: &mut std::collections::BTreeMap<usize, f64>, features: [f64; 4], weight: f64) {
    let hats = features
        .into_iter()
        .zip(TRANSFER_AXES)
        .map(|(v, e)| hat(e, v));
    let hats: Vec<[(usize, f64); 2]> = hats.collect();
    for corner in 0..16usize {
        let (mut index, mut w) = (0, weight);
        for (axis, (hat, edges)) in hats.iter().zip(TRANSFER_AXES).enumerate() {
            let (i, f) = hat[(corner >> axis) & 1];
            index = index * edges.len() + i;
            w *= f;
        }
        if w > 0.0 {
            *row.entry(index).or_default() += w;
        }
    }
}

/// The six axes along which the depth out of the cloud is taken.
const AXES_OUT: [Vec3; 6] = [
    Vec3::X,
    Vec3::NEG_X,
    Vec3::Y,
    Vec3::NEG_Y,
    Vec3::Z,
    Vec3::NEG_Z,
];

/// Each particle's least optical depth out of the cloud along [`AXES_OUT`], at its
/// centre, from intensity buffers lit along them at 64^3.
fn deepest(particles: &[Particle]) -> Result<Vec<f32>> {
    let mut deepest = vec![f32::INFINITY; particles.len()];
    for axis in AXES_OUT {
        let buffer = IntensityBuffer::new(particles, axis, 64, 0.0, Splat::Pieces)?;
        for (d, p) in deepest.iter_mut().zip(particles) {
            *d = d.min(-buffer.sample_log_grid(buffer.grid_coordinates(p.position)));
        }
    }
    Ok(deepest)
}

/// [`Transfer`] through the billboards: front to back as `render` draws them, each
/// blob's single scattering by `Octaves::SINGLE` at its emission nodes and its weight
/// of the table, `albedo (1 - e^-tau)` times what gets through in front, at the nodes'
/// mean depth toward the sun, its particle's least depth out of the cloud (`deepest`,
/// one per particle), the pixel's angle to the sun and the depth in front of it and
/// half its own.
fn billboard_rows(view: &View, deepest: &[f32]) -> Transfer {
    let particles = &view.particles;
    let camera = &view.camera;
    let depth = |k: usize| camera.depth(particles[k].position);
    let mut order: Vec<usize> = (0..particles.len())
        .filter(|&k| depth(k) > particles[k].reach())
        .collect();
    order.sort_by(|&a, &b| depth(a).total_cmp(&depth(b)));
    let (single, rows) = pixel_rays(camera)
        .into_par_iter()
        .map(|ray| {
            let cos = view.to_sun.dot(ray);
            let phase = PhaseFunction::CloudMie.eval_f32(cos);
            let (mut through, mut single) = (1.0f64, 0.0f64);
            let mut row = std::collections::BTreeMap::new();
            for &i in &order {
                let p = &particles[i];
                let d = p.position - camera.position;
                let t = d.dot(ray);
                let tau = p.faded_column((d.length_squared() - t * t).max(0.0));
                if tau <= 0.0 {
                    continue;
                }
                let [(u0, l0), (u1, l1)] = emission_nodes(tau);
                let at = |l: f32| {
                    let point = camera.position + ray * (t + l * p.sigma());
                    view.buffer
                        .sample_log_grid(view.buffer.grid_coordinates(point))
                };
                let log_gamma = [at(l0), at(l1)];
                let emission = Emission {
                    tau,
                    u: [u0, u1],
                    log_gamma,
                    slab: 0.0,
                };
                let lit = through * p.albedo as f64;
                single += lit * Octaves::SINGLE.light(phase, &emission).single as f64;
                let tau = tau as f64;
                let features = [
                    -0.5 * (log_gamma[0] + log_gamma[1]) as f64,
                    deepest[i] as f64,
                    cos as f64,
                    -through.ln() + 0.5 * tau,
                ];
                add_to_row(&mut row, features, lit * -(-tau).exp_m1());
                through *= (-tau).exp();
                if through < 1e-3 {
                    break;
                }
            }
            (single, row.into_iter().collect())
        })
        .unzip();
    Transfer { single, rows }
}

/// The unit ray through each pixel centre of `camera`, row by row (the references'
/// order).
fn pixel_rays(camera: &Camera) -> Vec<Vec3> {
    (0..camera.width * camera.height)
        .map(|k| {
            let (x, y) = (k % camera.width, k / camera.width);
            camera.ray(x as f32 + 0.5, y as f32 + 0.5).normalize()
        })
        .collect()
}

/// [`Transfer::rows`] through the particles' exact density, 64 steps a ray.
fn transfer_rows(view: &View) -> Vec<Vec<(usize, f64)>> {
    let reference = view.reference();
    let volume = &reference.volume;
    let to_sun = view.to_sun.as_dvec3();
    let depth = |p: DVec3, toward: DVec3| -volume.transmittance(p, toward).max(1e-300).ln();
    let origin = view.camera.position.as_dvec3();
    pixel_rays(&view.camera)
        .into_par_iter()
        .map(|ray| {
            let dir = ray.as_dvec3().normalize();
            let ray = volume.ray(origin, dir);
            let mut row = std::collections::BTreeMap::new();
            let Some((a, b)) = ray.span() else {
                return Vec::new();
            };
            let h = (b - a) / 64.0;
            let mut eye = ray.depth(0.0, a);
            for i in 0..64 {
                let t = a + (i as f64 + 0.5) * h;
                let piece = ray.depth(t - 0.5 * h, t + 0.5 * h);
                let (sigma, scattering) = ray.extinction(t);
                if sigma > 0.0 && eye < 10.0 {
                    // What the step scatters toward the eye, per unit F.
                    let weight = scattering / sigma * (-eye).exp() * -(-piece).exp_m1();
                    let p = origin + dir * t;
                    let deepest = AXES_OUT
                        .iter()
                        .map(|&d| depth(p, d.as_dvec3()))
                        .fold(f64::INFINITY, f64::min);
                    let features = [
                        depth(p, to_sun),
                        deepest,
                        to_sun.dot(dir),
                        eye + 0.5 * piece,
                    ];
                    add_to_row(&mut row, features, weight);
                }
                eye += piece;
            }
            row.into_iter().collect()
        })
        .collect()
}

/// The two nodes of `edges` around `v` and their linear weights (the end node alone
/// outside).
fn hat(edges: &[f64], v: f64) -> [(usize, f64); 2] {
    let last = edges.len() - 1;
    match edges.iter().position(|&e| v <= e) {
        Some(0) => [(0, 1.0), (0, 0.0)],
        Some(i) => {
            let f = (v - edges[i - 1]) / (edges[i] - edges[i - 1]);
            [(i - 1, 1.0 - f), (i, f)]
        }
        None => [(last, 1.0), (last, 0.0)],
    }
}

/// The 36 views, each with its path-traced picture (from the temporary folder when an
/// earlier run made it).
fn views(paths: usize) -> Result<Vec<View>> {
    let clouds = [
        ("c200", 200, 0.006),
        ("c2000", 2000, 0.006),
        ("c9382", 9382, 0.04),
    ];
    // Eye height (None: level with the cloud's middle) and horizontal distance, m.
    let eyes = [
        ("above", Some(2400.0), 2640.0),
        ("level", None, 2640.0),
        ("below", Some(300.0), 1800.0),
    ];
    let suns = [
        ("front", 25.0, 200.0),
        ("side", 25.0, 290.0),
        ("behind", 25.0, 20.0),
        ("high", 60.0, 250.0),
    ];
    let folder = std::env::temp_dir().join("atmo-fit-octaves");
    std::fs::create_dir_all(&folder)?;
    let mut views = Vec::new();
    for (cloud, count, density) in clouds {
        let particles = Cumulus {
            particles: count,
            density,
            ..Cumulus::default()
        }
        .generate();
        let centre = particles.iter().map(|p| p.position).sum::<Vec3>() / count as f32;
        for (eye, height, distance) in eyes {
            // The camera south-west of the cloud, looking at its middle.
            let a = 200f32.to_radians();
            let position = Vec3::new(
                centre.x + a.sin() * distance,
                height.unwrap_or(centre.y),
                centre.z - a.cos() * distance,
            );
            let camera = Camera::look_at(position, centre, Vec3::Y, Fov::Vertical(30.0), SIZE)?;
            for (sun, elevation, azimuth) in suns {
                let to_sun = Sun::from_degrees(elevation, azimuth)?.toward();
                let buffer = IntensityBuffer::new(&particles, to_sun, 128, 0.0, Splat::Pieces)?;
                views.push(View {
                    name: format!("{cloud}-{eye}-{sun}"),
                    particles: particles.clone(),
                    camera: camera.clone(),
                    to_sun,
                    buffer,
                    traced: Vec::new(),
                    covered: Vec::new(),
                });
                let view = views.last_mut().expect("just pushed");
                view.covered = view.reference().covered(&view.camera);
                view.traced = view.path_traced(paths, usize::MAX, 3)?;
            }
        }
    }
    Ok(views)
}

/// The path tracer's picture kept in `file`, or made by `make` and kept there.
fn traced(file: &Path, make: impl FnOnce() -> Vec<f64>) -> Result<Vec<f64>> {
    if let Ok(text) = std::fs::read_to_string(file) {
        let values: Vec<f64> = text
            .split_whitespace()
            .filter_map(|v| v.parse().ok())
            .collect();
        if values.len() == (SIZE.0 * SIZE.1) as usize {
            return Ok(values);
        }
    }
    let values = make();
    let text: Vec<String> = values.iter().map(|v| format!("{v:e}")).collect();
    std::fs::write(file, text.join(" "))?;
    Ok(values)
}

/// The octaves' score on each view.
fn scores(views: &[View], octaves: &Octaves) -> Result<Vec<Agreement>> {
    views
        .iter()
        .map(|view| Ok(view.agreement(&view.rendered(*octaves)?)))
        .collect()
}

/// The worst view's distance from the path tracer, as a ratio (1.3: 30 % off either way).
fn worst(scores: &[Agreement]) -> f64 {
    scores
        .iter()
        .map(|s| s.mean_ratio.ln().abs())
        .fold(0.0, f64::max)
        .exp()
}

/// How many views are within 10 % of the path tracer in the mean.
fn within(scores: &[Agreement]) -> usize {
    scores
        .iter()
        .filter(|s| (s.mean_ratio - 1.0).abs() < 0.1)
        .count()
}

/// The share of all views' 8 x 8 blocks within 15 % of the path tracer, by the blocks'
/// means (`Agreement::blocks_within_15`) or medians (`Agreement::medians_within_15`).
fn blocks(scores: &[Agreement], within: fn(&Agreement) -> usize) -> f64 {
    let (good, all) = scores
        .iter()
        .fold((0, 0), |(g, a), s| (g + within(s), a + s.blocks));
    good as f64 / all as f64
}

/// The worst view, the typical one (the geometric mean of the ratios' distance from 1),
/// the views within 10 % and the blocks within 15 %.
fn summary(scores: &[Agreement]) -> String {
    let typical =
        (scores.iter().map(|s| s.mean_ratio.ln().abs()).sum::<f64>() / scores.len() as f64).exp();
    format!(
        "worst view {:.3}, typical {typical:.3}, {} of {} views within 10 %, blocks within 15 % {:.0} % by their means, {:.0} % by their medians",
        worst(scores),
        within(scores),
        scores.len(),
        100.0 * blocks(scores, |s| s.blocks_within_15),
        100.0 * blocks(scores, |s| s.medians_within_15)
    )
}
