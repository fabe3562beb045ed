//! Every order of the clouds' light against the volumetric path tracer over 108 views:
//! nine cumulus clouds (200 and 2,000 particles of density 0.006, 9,382 of the
//! generator's 0.04, 500 of 0.04, 1,000 of 0.002, 4,000 of 0.015, 20,000 of 0.04, 300
//! of 0.003 and 8,000 of 0.004: optical depth about 3 to 55 through the middle, blobs
//! large and small), each seen from above, level and below, the sun 25 deg high from
//! the front, the side and behind and 60 deg high. Fits the two models of the orders
//! past the first: prints each view's mean of the octaves (`atmo::clouds::Octaves`)
//! and of the library's transfer table over the path tracer's (on the cloud's pixels)
//! and their 8 x 8 blocks within 15 %, then their scores over all the views.
//!
//! Every view is also scored for the transfer solve (`atmo::clouds::DiffuseLight`,
//! `Scattering::SOLVE`), and both the table and the solve by the thinnest and the
//! thickest fifth of the cloud's pixels (`atmo::reference::clouds::fifths`); `--dump
//! FOLDER` writes the table's and the solve's pictures and the covered pixels there as
//! text.
//!
//! `--clouds c200,c2000,c9382` keeps the views of the clouds named: those three are the
//! 36 views the octaves were fitted to; `c60134`, the bench's 60,134-particle cloud of
//! the paper (twelve views more), is scored only when named, a cloud no fit has seen.
//! With `--search`, a grid search over the
//! octaves' numbers, best worst view first: how `Octaves::MULTIPLE` was chosen
//! (docs/clouds.md, "Every order: octaves"). With `--floor`, the same scores for a
//! second path-traced picture (another seed) in place of the octaves: how far a perfect
//! model would score with the path tracer's noise. With `--oracle`, the scores of the
//! path tracer's own first two orders (another seed) plus the octaves' higher octave
//! and slab's light, each weighted, the best weights first: what a second order
//! computed exactly would leave. With `--transfer`, the transfer table
//! (`atmo::clouds::TransferTable`) fitted to the path tracer over the views, then over
//! all clouds but one and scored on that one's views (`--smooth S` weighs the penalty on
//! neighbouring values' differences, default 1e-4); `--write` writes the table fitted
//! to every view into the library (`src/clouds/transfer_fitted.rs`). About twelve minutes.
//!
//! `cargo run --release -p atmo-fit-clouds -- [--paths N] [--clouds A,B]
//! [--search] [--floor] [--oracle] [--transfer [--smooth S] [--write]] [--octaves
//! COUNT,A,B,C,K,D,E]` (the fields of `Octaves` in order). The path-traced pictures
//! (48 x 28, N paths a pixel, default 32; 128 paths take about 75 minutes on two cores
//! for the 108 views) are kept in the system's temporary folder and reused.
//!
//! A tool of atmo's own, not a user's example: it makes the data the library ships
//! (`Octaves::MULTIPLE`, `transfer_fitted.rs`) and the figures in docs/clouds.md.

use std::path::Path;

use atmo::atmosphere::PhaseFunction;
use atmo::clouds::transfer::{self, CloudDepths, TransferTable};
use atmo::clouds::{
    render_with_depths, solve_for, AerialHaze, CloudLight, Cumulus, IntensityBuffer, Octaves,
    Scattering, SkyLight, Splat,
};
use atmo::reference::clouds::{fifths, Agreement, PathSettings, ReferenceCloud, ReferenceLight};
use atmo::view::{Camera, Fov, Sun};
use faer::linalg::solvers::Solve;
use glam::Vec3;
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
    depths: CloudDepths,
    traced: Vec<f64>,
    covered: Vec<bool>,
    /// The cloud's optical depth along each pixel.
    depths_on_pixels: Vec<f64>,
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
            .join("atmo-fit-clouds")
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
    fn rendered(&self, scattering: Scattering) -> atmo::error::Result<Vec<f64>> {
        let light = CloudLight {
            to_sun: self.to_sun,
            sun: Vec3::ONE,
            ambient: SkyLight::NONE,
            phase: PhaseFunction::CloudMie,
            haze: AerialHaze::CLEAR,
            scattering,
        };
        let diffuse = solve_for(&self.particles, &self.buffer, &light, None)?;
        let frame = render_with_depths(
            &self.particles,
            &self.depths,
            &self.buffer,
            diffuse.as_ref(),
            &self.camera,
            &light,
            None,
        )?;
        Ok(frame.pixels.iter().map(|p| p.x as f64).collect())
    }

    /// How `picture` agrees with this view's path-traced picture.
    fn agreement(&self, picture: &[f64]) -> Agreement {
        Agreement::of(picture, &self.traced, &self.covered, SIZE.0 as usize)
    }
}

/// The flags `main` reads.
const FLAGS: [&str; 11] = [
    "--paths",
    "--clouds",
    "--octaves",
    "--smooth",
    "--dump",
    "--orders",
    "--search",
    "--floor",
    "--oracle",
    "--transfer",
    "--write",
];

/// Those of [`FLAGS`] followed by a value.
const VALUED: [&str; 5] = ["--paths", "--clouds", "--octaves", "--smooth", "--dump"];

/// What `--help` prints (the module doc has the rest).
const USAGE: &str = "usage: cargo run --release -p atmo-fit-clouds -- [--paths N] [--clouds A,B] \
[--search] [--floor] [--oracle] [--orders] [--dump FOLDER] [--transfer [--smooth S] [--write]] \
[--octaves COUNT,A,B,C,K,D,E]
(path-traced pictures of every view are made first and kept in the temporary folder: \
minutes to an hour the first time; see the module doc of tools/fit-clouds/src/main.rs)";

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    // An argument it does not read would otherwise start an hour of path tracing.
    let mut k = 0;
    while let Some(arg) = args.get(k) {
        if arg == "--help" || arg == "-h" {
            println!("{USAGE}");
            return Ok(());
        }
        if !FLAGS.contains(&arg.as_str()) || (VALUED.contains(&arg.as_str()) && k + 1 == args.len())
        {
            eprintln!("fit-clouds: {arg}: not an argument it takes, or without its value\n{USAGE}");
            std::process::exit(2);
        }
        k += if VALUED.contains(&arg.as_str()) { 2 } else { 1 };
    }
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
    let chosen = value("--clouds");
    let views = views(paths, |cloud, only_named| match chosen {
        Some(c) => c.split(',').any(|c| c == cloud),
        None => !only_named,
    })?;
    if args.iter().any(|a| a == "--orders") {
        for v in &views {
            let mean = |p: &[f64]| -> f64 {
                p.iter()
                    .zip(&v.covered)
                    .filter(|(_, c)| **c)
                    .map(|(x, _)| x)
                    .sum::<f64>()
            };
            let all = mean(&v.traced);
            let one = mean(&v.path_traced(paths, 1, 11)?);
            let two = mean(&v.path_traced(paths, 2, 11)?);
            let single = mean(&v.rendered(Scattering::SINGLE)?);
            println!(
                "{}: of the path tracer's light, order 1 {:.3}, order 2 {:.3}, the rest {:.3}; the billboards' single scattering {:.3}",
                v.name,
                one / all,
                (two - one) / all,
                (all - two) / all,
                single / all
            );
        }
        return Ok(());
    }
    let octave_scores = scores(&views, &octaves)?;
    // The table's and the solve's pictures of every view, written to `--dump`'s folder
    // (with the covered pixels) when it is given.
    let dump = |name: &str, values: Vec<String>| -> Result<()> {
        if let Some(folder) = value("--dump") {
            std::fs::write(
                Path::new(folder).join(format!("{name}.txt")),
                values.join(" "),
            )?;
        }
        Ok(())
    };
    let mut pictures = Vec::new();
    for v in &views {
        let of = |s: Scattering| v.rendered(s);
        let (table, solve) = (of(Scattering::MULTIPLE)?, of(Scattering::SOLVE)?);
        let text = |p: &[f64]| p.iter().map(|x| format!("{x:e}")).collect();
        dump(&format!("{}-table", v.name), text(&table))?;
        dump(&format!("{}-solve", v.name), text(&solve))?;
        let covered = v.covered.iter().map(|c| u8::from(*c).to_string()).collect();
        dump(&format!("{}-covered", v.name), covered)?;
        pictures.push([table, solve]);
    }
    let agreements = |model: usize| -> Vec<Agreement> {
        views
            .iter()
            .zip(&pictures)
            .map(|(v, p)| v.agreement(&p[model]))
            .collect()
    };
    let (table, solve) = (agreements(0), agreements(1));
    for (model, name) in ["table", "solve"].into_iter().enumerate() {
        let f: Vec<[f64; 2]> = views
            .iter()
            .zip(&pictures)
            .map(|(v, p)| fifths(&p[model], &v.traced, &v.covered, &v.depths_on_pixels))
            .collect();
        for (view, [thin, thick]) in views.iter().zip(&f) {
            println!(
                "{:<22} {name}: thin fifth {thin:.3}, thick fifth {thick:.3}",
                view.name
            );
        }
        let within = |i: usize| f.iter().filter(|v| (v[i] - 1.0).abs() < 0.1).count();
        println!(
            "{name}: thin fifth within 10 % in {} of {} views, thick fifth in {}",
            within(0),
            f.len(),
            within(1)
        );
    }
    for (((view, octaves), table), solve) in
        views.iter().zip(&octave_scores).zip(&table).zip(&solve)
    {
        println!(
            "{:<22} over the path tracer: octaves {:.3}, table {:.3}, solve {:.3}   blocks within 15 % by their means / medians: octaves {} / {}, table {} / {}, solve {} / {} of {}",
            view.name,
            octaves.mean_ratio,
            table.mean_ratio,
            solve.mean_ratio,
            octaves.blocks_within_15,
            octaves.medians_within_15,
            table.blocks_within_15,
            table.medians_within_15,
            solve.blocks_within_15,
            solve.medians_within_15,
            table.blocks
        );
    }
    println!("{octaves:?}: {}", summary(&octave_scores));
    println!("the library's transfer table: {}", summary(&table));
    println!("the transfer solve: {}", summary(&solve));
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
        let smooth = value("--smooth").map_or(1e-4, |v| v.parse().expect("--smooth S"));
        let table = transfer(&views, smooth)?;
        if args.iter().any(|a| a == "--write") {
            let file = Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("../../crates/atmo/src/clouds/transfer_fitted.rs");
            let how = format!(
                "cargo run --release -p atmo-fit-clouds -- --paths {paths} --transfer --smooth {smooth} --write"
            );
            write_table(&table, &file, &how)?;
            println!(
                "written to {}; the library's table above is the one compiled in until this example is built again",
                file.display()
            );
        }
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
        let single = view.rendered(Scattering::SINGLE)?;
        let part = |o: Octaves| -> Result<Vec<f64>> {
            Ok(view
                .rendered(Scattering::Octaves(o))?
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

/// The transfer table ([`TransferTable`]) fitted by least squares to the path tracer's
/// light less the billboards' single scattering, over the covered pixels of `views`:
/// over all, and over all but one cloud scored on that cloud's views. The pictures are
/// the renderer's own: it is linear in the table's values, so the design's column for
/// a value is the picture drawn with that value 1 and the rest 0, less single
/// scattering. The fit is the least squares with every value at least 0 (light is not
/// negative; clamping an unconstrained fit's negative values at 0 took the blocks within
/// 15 % from 76 % to 26 %) and a small penalty on the differences of neighbouring values
/// along each axis (`smooth` times the design's mean diagonal), which fills the values
/// no pixel sees from their neighbours. Returns the table fitted to every view.
fn transfer(views: &[View], smooth: f64) -> Result<TransferTable> {
    let n = transfer::VALUES;
    // Each basis table is leaked once: the renderer takes a table that lives as long
    // as the program.
    let basis: Vec<&'static TransferTable> = (0..n)
        .map(|i| {
            let mut values = [0.0; transfer::VALUES];
            values[i] = 1.0;
            &*Box::leak(Box::new(TransferTable { values }))
        })
        .collect();
    // Per cloud, the normal equations of its views' covered pixels.
    let mut normal: Vec<(String, faer::Mat<f64>, faer::Mat<f64>)> = Vec::new();
    for view in views {
        let single = view.rendered(Scattering::SINGLE)?;
        let covered: Vec<usize> = (0..single.len()).filter(|&k| view.covered[k]).collect();
        let mut design = faer::Mat::<f64>::zeros(covered.len(), n);
        let columns: Vec<Vec<f64>> = basis
            .par_iter()
            .map(|table| view.rendered(Scattering::Transfer(table)))
            .collect::<atmo::error::Result<_>>()?;
        for (j, column) in columns.iter().enumerate() {
            for (r, &k) in covered.iter().enumerate() {
                design[(r, j)] = column[k] - single[k];
            }
        }
        let target = faer::Mat::<f64>::from_fn(covered.len(), 1, |r, _| {
            view.traced[covered[r]] - single[covered[r]]
        });
        let cloud = view.name.split('-').next().unwrap_or_default().to_string();
        let ata = design.transpose() * &design;
        let atb = design.transpose() * &target;
        match normal.iter_mut().find(|(c, ..)| *c == cloud) {
            Some((_, a, b)) => {
                *a += &ata;
                *b += &atb;
            }
            None => normal.push((cloud, ata, atb)),
        }
    }
    let fit = |held_out: Option<&str>| -> Result<TransferTable> {
        let (mut ata, mut atb) = (faer::Mat::<f64>::zeros(n, n), faer::Mat::<f64>::zeros(n, 1));
        for (cloud, a, b) in &normal {
            if held_out != Some(cloud.as_str()) {
                ata += a;
                atb += b;
            }
        }
        let scale = (0..n).map(|i| ata[(i, i)]).sum::<f64>() / n as f64;
        for (i, j) in neighbours() {
            let w = smooth * scale;
            ata[(i, i)] += w;
            ata[(j, j)] += w;
            ata[(i, j)] -= w;
            ata[(j, i)] -= w;
        }
        (0..n).for_each(|i| ata[(i, i)] += 1e-6 * scale);
        let solved = non_negative(&ata, &atb);
        let mut values = [0.0; transfer::VALUES];
        for (v, x) in values.iter_mut().zip(solved) {
            *v = x as f32;
        }
        Ok(TransferTable { values })
    };
    let score = |table: TransferTable, on: &dyn Fn(&View) -> bool| -> Result<String> {
        let table: &'static TransferTable = Box::leak(Box::new(table));
        let scores = views
            .iter()
            .filter(|v| on(v))
            .map(|v| Ok(v.agreement(&v.rendered(Scattering::Transfer(table))?)))
            .collect::<Result<Vec<_>>>()?;
        Ok(summary(&scores))
    };
    let all = fit(None)?;
    println!(
        "transfer table (smooth {smooth}) fitted to every view: {}",
        score(all.clone(), &|_| true)?
    );
    for (cloud, ..) in &normal {
        let table = fit(Some(cloud))?;
        let of = |v: &View| v.name.starts_with(&format!("{cloud}-"));
        println!(
            "  fitted without {cloud}: on {cloud} {}",
            score(table, &of)?
        );
    }
    Ok(all)
}

/// The least squares with every value at least 0: `x >= 0` minimising
/// `x' A x / 2 - b' x` for the normal equations `A`, `b`, by coordinate descent
/// (each value in turn set to its best at least 0 given the others, the gradient kept
/// up to date), from the unconstrained solution clamped at 0, until a sweep moves the
/// objective by less than a millionth.
fn non_negative(a: &faer::Mat<f64>, b: &faer::Mat<f64>) -> Vec<f64> {
    let n = a.nrows();
    let mut x: Vec<f64> = match a.llt(faer::Side::Lower) {
        Ok(llt) => {
            let solved = llt.solve(b);
            (0..n).map(|i| solved[(i, 0)].max(0.0)).collect()
        }
        Err(_) => vec![0.0; n],
    };
    // g = A x - b.
    let mut g: Vec<f64> = (0..n)
        .map(|i| (0..n).map(|j| a[(i, j)] * x[j]).sum::<f64>() - b[(i, 0)])
        .collect();
    let objective = |x: &[f64], g: &[f64]| {
        // x' A x / 2 - b' x = x' (g + b) / 2 - b' x = (x' g - b' x) / 2.
        (0..n).map(|i| x[i] * g[i] - x[i] * b[(i, 0)]).sum::<f64>() / 2.0
    };
    let mut last = objective(&x, &g);
    for _ in 0..5000 {
        for i in 0..n {
            let step = ((x[i] - g[i] / a[(i, i)]).max(0.0)) - x[i];
            if step != 0.0 {
                x[i] += step;
                for (j, gj) in g.iter_mut().enumerate() {
                    *gj += a[(j, i)] * step;
                }
            }
        }
        let now = objective(&x, &g);
        if (last - now).abs() <= 1e-6 * now.abs() {
            break;
        }
        last = now;
    }
    x
}

/// The pairs of the table's values next to each other along one axis.
fn neighbours() -> Vec<(usize, usize)> {
    let sizes = [
        transfer::THICKNESS.len(),
        transfer::SUN.len(),
        transfer::OUT.len(),
        transfer::COSINE.len(),
        transfer::EYE.len(),
    ];
    let mut pairs = Vec::new();
    for i in 0..transfer::VALUES {
        let mut stride = 1;
        let mut rest = i;
        for axis in (0..sizes.len()).rev() {
            if rest % sizes[axis] + 1 < sizes[axis] {
                pairs.push((i, i + stride));
            }
            rest /= sizes[axis];
            stride *= sizes[axis];
        }
    }
    pairs
}

/// Writes `table` as the Rust source the library includes (`transfer_fitted.rs`).
fn write_table(table: &TransferTable, file: &Path, how: &str) -> Result<()> {
    let mut text = format!(
        "//! The transfer table fitted to the path tracer ([`super::transfer`]), written by\n\
         //! `{how}`:\n\
         //! `[thickness][sun][out][cosine][eye]`, 1/sr per unit sun irradiance.\n\n\
         /// The fitted values.\n\
         #[rustfmt::skip]\n\
         pub(super) const VALUES: [f32; super::transfer::VALUES] = [\n"
    );
    for row in table
        .values
        .chunks(transfer::EYE.len() * transfer::COSINE.len())
    {
        let row: Vec<String> = row.iter().map(|v| format!("{v:e}")).collect();
        text += &format!("    {},\n", row.join(", "));
    }
    text += "];\n";
    let temporary = file.with_extension("rs.tmp");
    std::fs::write(&temporary, text)?;
    std::fs::rename(&temporary, file)?;
    Ok(())
}

/// The paper's cloud, the bench's, scored only when named: no fit has seen it.
const UNSEEN: &str = "c60134";

/// The views of the clouds `chosen(name, only_named)` keeps (twelve a cloud), each with its
/// path-traced picture (from the temporary folder when an earlier run made it).
fn views(paths: usize, chosen: impl Fn(&str, bool) -> bool) -> Result<Vec<View>> {
    let clouds = [
        ("c200", 200, 0.006),
        ("c2000", 2000, 0.006),
        ("c9382", 9382, 0.04),
        ("c500", 500, 0.04),
        ("c1000", 1000, 0.002),
        ("c4000", 4000, 0.015),
        ("c20000", 20000, 0.04),
        ("c300", 300, 0.003),
        ("c8000", 8000, 0.004),
        (UNSEEN, 60134, 0.04),
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
    let folder = std::env::temp_dir().join("atmo-fit-clouds");
    std::fs::create_dir_all(&folder)?;
    let mut views = Vec::new();
    for (cloud, count, density) in clouds.into_iter().filter(|c| chosen(c.0, c.0 == UNSEEN)) {
        let particles = Cumulus {
            particles: count,
            density,
            ..Cumulus::default()
        }
        .generate();
        let centre = particles.iter().map(|p| p.position).sum::<Vec3>() / count as f32;
        let depths = CloudDepths::of(&particles)?;
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
                    depths: depths.clone(),
                    traced: Vec::new(),
                    covered: Vec::new(),
                    depths_on_pixels: Vec::new(),
                });
                let view = views.last_mut().expect("just pushed");
                view.covered = view.reference().covered(&view.camera);
                view.depths_on_pixels = view.reference().depths(&view.camera);
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
        .map(|view| Ok(view.agreement(&view.rendered(Scattering::Octaves(*octaves))?)))
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
