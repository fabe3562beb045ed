//! The light of a cloud against references that share nothing with the billboards but
//! the particles: the single-scattering integral by quadrature, and every order by the
//! volumetric path tracer (atmo::reference::clouds). Sun 25 deg high from the front
//! (behind the camera), the side and behind the cloud.

use atmo::atmosphere::PhaseFunction;
use atmo::clouds::buffer::{IntensityBuffer, Splat};
use atmo::clouds::render::{render, AerialHaze, CloudLight};
use atmo::clouds::{CloudShadow, Cumulus, Octaves, Particle, Scattering, SkyLight};
use atmo::image::Frame;
use atmo::reference::clouds::{fifths, Agreement, PathSettings, ReferenceCloud, ReferenceLight};
use atmo::view::{Camera, Fov, Sun};
use glam::{DVec3, Vec3};

/// A 200-particle cumulus of optical depth 8 to 11 through its middle.
fn cloud() -> Vec<Particle> {
    Cumulus {
        particles: 200,
        density: 0.006,
        ..Cumulus::default()
    }
    .generate()
}

/// The particles' mean position, m.
fn centre(particles: &[Particle]) -> Vec3 {
    particles.iter().map(|p| p.position).sum::<Vec3>() / particles.len() as f32
}

/// The camera 2.2 cloud widths away at 2.4 km, 26 deg, `w` x `h`.
fn camera(particles: &[Particle], w: u32, h: u32) -> Camera {
    camera_at(particles, 2400.0, w, h)
}

/// The same at `height` m (the cloud's middle is at about 1.2 km).
fn camera_at(particles: &[Particle], height: f32, w: u32, h: u32) -> Camera {
    let centre = centre(particles);
    let a = 200f32.to_radians();
    let eye = Vec3::new(
        centre.x + a.sin() * 2640.0,
        height,
        centre.z - a.cos() * 2640.0,
    );
    Camera::look_at(eye, centre, Vec3::Y, Fov::Vertical(26.0), (w, h)).unwrap()
}

/// The three suns: from the front (the camera's side), the side and behind the cloud.
const SUNS: [(&str, f64); 3] = [("front", 200.0), ("side", 290.0), ("behind", 20.0)];

/// Each sun: its name, the vector toward it and the reference cloud it lights.
fn lit(particles: &[Particle]) -> impl Iterator<Item = (&'static str, Vec3, ReferenceCloud<'_>)> {
    SUNS.into_iter().map(move |(name, azimuth)| {
        let to_sun = Sun::from_degrees(25.0, azimuth).unwrap().toward();
        (name, to_sun, reference(particles, to_sun))
    })
}

fn reference(particles: &[Particle], to_sun: Vec3) -> ReferenceCloud<'_> {
    ReferenceCloud::new(
        particles,
        ReferenceLight {
            to_sun: to_sun.as_dvec3(),
            phase: PhaseFunction::CloudMie,
            sky: 0.0,
        },
    )
}

/// The billboards' picture with `scattering`, the buffer holding the sun's
/// transmittance, unit sunlight, no ambient light.
fn fast(particles: &[Particle], camera: &Camera, to_sun: Vec3, scattering: Scattering) -> Vec<f64> {
    let buffer = IntensityBuffer::new(particles, to_sun, 128, 0.0, Splat::Pieces).unwrap();
    let light = CloudLight {
        to_sun,
        sun: Vec3::ONE,
        ambient: SkyLight::NONE,
        phase: PhaseFunction::CloudMie,
        haze: AerialHaze::CLEAR,
        scattering,
    };
    let frame = render(particles, &buffer, camera, &light, None).unwrap();
    frame.pixels.iter().map(|p| p.x as f64).collect()
}

#[test]
fn the_path_tracer_and_the_quadrature_agree_on_single_scattering() {
    let particles = cloud();
    let mut worst = 0.0f64;
    for (name, _, cloud) in lit(&particles) {
        let centre = centre(&particles).as_dvec3();
        for (k, offset) in [(0.0, 0.0), (250.0, 100.0), (-200.0, -150.0)]
            .into_iter()
            .enumerate()
        {
            let origin = centre + DVec3::new(offset.0, offset.1, -3000.0);
            let (quad, through) = cloud.single_scattering(origin, DVec3::Z);
            assert!(
                quad > 0.0 && through > 0.0 && through < 0.5,
                "{quad} {through}"
            );
            let settings = PathSettings {
                paths: 20_000,
                orders: 1,
                seed: 1,
            };
            let (mean, error) = cloud.path_traced(origin, DVec3::Z, &settings, k as u64 + 7);
            assert!(
                (mean - quad).abs() < 4.0 * error + 0.01 * quad,
                "sun {name}, ray {k}: path tracer {mean} +- {error}, quadrature {quad}"
            );
            worst = worst.max((mean / quad - 1.0).abs());
        }
    }
    eprintln!("single scattering, path tracer vs quadrature: worst {worst:.4}");
}

#[test]
fn the_quadrature_and_the_free_flights_are_converged_and_exact() {
    let particles = cloud();
    let to_sun = Sun::from_degrees(25.0, 290.0).unwrap().toward();
    let cloud = reference(&particles, to_sun);
    let centre = centre(&particles).as_dvec3();
    let origin = centre + DVec3::new(100.0, 50.0, -3000.0);
    // Doubling the steps changes the integral by less than 0.1 %.
    let coarse = cloud.single_scattering(origin, DVec3::Z).0;
    let fine = cloud.single_scattering_with(origin, DVec3::Z, 8.0).0;
    assert!((coarse / fine - 1.0).abs() < 1e-3, "{coarse} {fine}");
    // A free flight lands where the exact optical depth reaches its target.
    let ray = cloud.volume.ray(origin, DVec3::Z);
    let total = ray.depth(0.0, f64::INFINITY);
    for target in [0.01, 1.0, 0.9 * total] {
        let t = ray.free_flight(target).unwrap();
        assert!(
            (ray.depth(0.0, t) - target).abs() < 1e-6 * target.max(1.0),
            "{target}"
        );
    }
    assert!(ray.free_flight(1.01 * total).is_none());
}

/// The mean radiance over the cloud's pixels (`covered`: optical depth over 0.1),
/// `fast`'s over `reference`'s.
fn mean_ratio(camera: &Camera, covered: &[bool], fast: &[f64], reference: &[f64]) -> f64 {
    Agreement::of(fast, reference, covered, camera.width as usize).mean_ratio
}

#[test]
fn single_scattering_pictures_match_the_quadrature() {
    // The bounds: within 3 % in the mean, 5 % RMS of the mean. Measured: 1.006,
    // 0.995 and 0.993 of the quadrature, RMS 2.6, 3.4 and 3.3 % (front, side, behind);
    // before the blobs beside and the third emission node, 0.942, 0.946 and 0.985
    // (docs/clouds.md, "Drawing"); the paper's own billboards were 16 % dark from the
    // front on this cloud at density 0.04.
    let particles = cloud();
    let camera = camera(&particles, 64, 36);
    for (name, to_sun, cloud) in lit(&particles) {
        let reference: Vec<f64> = cloud
            .single_scattering_picture(&camera)
            .iter()
            .map(|p| p.0)
            .collect();
        assert!(reference.iter().all(|v| *v >= 0.0 && v.is_finite()));
        let fast = fast(&particles, &camera, to_sun, Scattering::SINGLE);
        let agreement = Agreement::of(&fast, &reference, &cloud.covered(&camera), 64);
        let (ratio, rms) = (agreement.mean_ratio, agreement.rms_of_mean);
        eprintln!("{name}: single scattering, billboards / quadrature {ratio:.4}, rms {rms:.4}");
        assert!(
            (ratio - 1.0).abs() < 0.03 && rms < 0.05,
            "{name}: {ratio} {rms}"
        );
    }
}

/// The mean of every order over the cloud's pixels against the path tracer's (24
/// paths a pixel), by the transfer table and by the octaves; the path tracer's against
/// single scattering's.
fn every_order(particles: &[Particle], camera: &Camera, to_sun: Vec3) -> ([f64; 2], f64) {
    let cloud = reference(particles, to_sun);
    let settings = PathSettings {
        paths: 24,
        orders: usize::MAX,
        seed: 3,
    };
    let traced: Vec<f64> = cloud
        .path_traced_picture(camera, &settings)
        .iter()
        .map(|p| p.0)
        .collect();
    let single = fast(particles, camera, to_sun, Scattering::SINGLE);
    let covered = cloud.covered(camera);
    let every = [Scattering::MULTIPLE, Scattering::Octaves(Octaves::MULTIPLE)].map(|s| {
        mean_ratio(
            camera,
            &covered,
            &fast(particles, camera, to_sun, s),
            &traced,
        )
    });
    (every, mean_ratio(camera, &covered, &traced, &single))
}

#[test]
fn every_order_matches_the_path_tracer() {
    // Measured at 48 x 28: the transfer table 1.010 (front), 1.020 (side), 1.004
    // (behind) of the path tracer in the mean, held within 5 % (the issue asks 10 %;
    // 1.067, 1.080 and 0.998 before the table's slices by thickness); the octaves 1.12,
    // 1.14 and 0.84; every order is 3 to 5.3 times single scattering here. Both are
    // fitted to many views of several clouds (docs/clouds.md), this one's among them.
    let particles = cloud();
    let camera = camera(&particles, 48, 28);
    for (name, to_sun, _) in lit(&particles) {
        let ([table, octaves], gain) = every_order(&particles, &camera, to_sun);
        eprintln!("{name}: every order, billboards / path tracer {table:.3} (octaves {octaves:.3}); path tracer / single {gain:.2}");
        assert!(gain > 2.5, "{name}: higher orders add light: {gain}");
        assert!((table - 1.0).abs() < 0.05, "{name}: {table}");
        assert!((octaves - 1.0).abs() < 0.2, "{name}: octaves {octaves}");
    }
}

#[test]
fn every_order_holds_from_below_a_thick_cloud_against_the_sun() {
    // A 500-particle cumulus of the generator's density (optical depth about 55
    // through its centre along the sun) seen from 300 m, 1.8 km off, the sun 25 deg
    // high behind it: the worst view of the octaves fitted to the thin clouds alone
    // (1.61 of the path tracer here, the octaves' light carried through the cloud
    // with too much of the droplets' forward lobe; 1.18 with three octaves refitted to
    // thick clouds too). Measured at 32 x 18: the octaves 1.11, the transfer table 0.978
    // (held within 5 %; 0.970 before the slices by thickness).
    let particles = Cumulus {
        particles: 500,
        density: 0.04,
        ..Cumulus::default()
    }
    .generate();
    let centre = centre(&particles);
    let a = 200f32.to_radians();
    let eye = Vec3::new(
        centre.x + a.sin() * 1800.0,
        300.0,
        centre.z - a.cos() * 1800.0,
    );
    let camera = Camera::look_at(eye, centre, Vec3::Y, Fov::Vertical(30.0), (32, 18)).unwrap();
    let to_sun = Sun::from_degrees(25.0, 20.0).unwrap().toward();
    let ([table, octaves], gain) = every_order(&particles, &camera, to_sun);
    eprintln!("thick, from below, sun behind: every order, billboards / path tracer {table:.3} (octaves {octaves:.3}); path tracer / single {gain:.2}");
    assert!((table - 1.0).abs() < 0.05, "{table}");
    assert!((octaves - 1.0).abs() < 0.2, "octaves {octaves}");
}

#[test]
fn the_shadow_on_the_ground_matches_the_path_tracer() {
    // Measured with 2000 paths at 21 points 150 m apart across the shadow: the cloud
    // scatters 1 to 3 % of the sun's irradiance onto its shadow (0.3-2 % around it),
    // more with the sun in front of the camera than behind the cloud. Where the
    // cloud's optical depth is over 3, the mean irradiance of the map with
    // SCATTERED_DOWN is 0.98 (sun in front) and 1.43 (behind) of the path tracer's; the
    // geometric shadow alone 0.33 and 0.39.
    let particles = cloud();
    let c = centre(&particles);
    for (name, to_sun, cloud) in lit(&particles).step_by(2) {
        let shadow = CloudShadow::new(&particles, to_sun, 256).unwrap();
        // Where the sun's ray through the cloud's centre meets the ground, and points
        // across the shadow from there, where the cloud's optical depth is over 3.
        let hit = c - c.y / to_sun.y * to_sun;
        let across = Vec3::new(-to_sun.z, 0.0, to_sun.x).normalize();
        let points: Vec<Vec3> = (0..21)
            .map(|k| hit + across * ((k as f32 - 10.0) * 150.0))
            .filter(|p| shadow.depth_at(*p) > 3.0)
            .collect();
        assert!(
            points.len() >= 4,
            "{name}: the shadow is crossed: {}",
            points.len()
        );
        let (mut traced, mut mapped, mut geometric) = (0.0, 0.0, 0.0);
        for (k, p) in points.iter().enumerate() {
            let r = cloud.ground_irradiance(p.as_dvec3(), 1500, k as u64 + 11);
            traced += r.total();
            mapped += (to_sun.y * shadow.sunlight(*p)) as f64;
            geometric += (to_sun.y * (-shadow.depth_at(*p)).exp()) as f64;
        }
        eprintln!(
            "{name}: in the shadow, map / path tracer {:.2}, geometric / path tracer {:.2}",
            mapped / traced,
            geometric / traced
        );
        assert!(
            (mapped / traced - 1.0).abs() < 0.5,
            "{name}: {mapped} vs {traced}"
        );
        assert!(
            geometric < 0.6 * traced,
            "{name}: the cloud lights its shadow"
        );
    }
}

#[test]
fn the_sky_light_matches_the_path_tracer_in_the_mean() {
    // A sky of radiance 1 over the upper hemisphere and none below, its light alone
    // (the path tracer with and without the sky, the same paths), against the
    // billboards lit by its harmonics and dimmed inside the cloud by the profile down
    // the vertical (atmo::clouds::SkyDimming), against the sphere's mean (0.5)
    // scattered as if from everywhere, atmo's term before, and against the sky's light
    // through the transfer solve: seen from above (2.4 km), level (1.2 km) and below
    // (300 m), in the mean and by thirds of the rows.
    let particles = cloud();
    let to_sun = Sun::from_degrees(25.0, 200.0).unwrap().toward();
    let buffer = IntensityBuffer::new(&particles, to_sun, 128, 0.0, Splat::Pieces).unwrap();
    let above = {
        let mut map = Frame::new(64, 32);
        map.pixels[..64 * 16].fill(Vec3::ONE);
        SkyLight::from_map(&map)
    };
    let cloud = reference(&particles, to_sun);
    for height in [2400.0, 1200.0, 300.0] {
        let camera = camera_at(&particles, height, 48, 28);
        let traced = |sky: f64| {
            let light = ReferenceLight {
                to_sun: to_sun.as_dvec3(),
                phase: PhaseFunction::CloudMie,
                sky,
            };
            let settings = PathSettings {
                paths: 32,
                orders: usize::MAX,
                seed: 3,
            };
            ReferenceCloud::new(&particles, light).path_traced_picture(&camera, &settings)
        };
        let (lit, dark) = (traced(1.0), traced(0.0));
        let sky: Vec<f64> = lit.iter().zip(&dark).map(|(a, b)| a.0 - b.0).collect();
        let billboards_by = |ambient: SkyLight, scattering: Scattering| -> Vec<f64> {
            let light = CloudLight {
                to_sun,
                sun: Vec3::ZERO,
                ambient,
                phase: PhaseFunction::CloudMie,
                haze: AerialHaze::CLEAR,
                scattering,
            };
            let frame = render(&particles, &buffer, &camera, &light, None).unwrap();
            frame.pixels.iter().map(|p| p.x as f64).collect()
        };
        let covered = cloud.covered(&camera);
        // billboards / path tracer over the covered pixels of rows `rows`.
        let ratio = |fast: &[f64], rows: std::ops::Range<usize>| {
            let k = rows.flat_map(|y| (0..48).map(move |x| y * 48 + x));
            let (f, t) = k
                .filter(|&k| covered[k])
                .fold((0.0, 0.0), |(f, t), k| (f + fast[k], t + sky[k]));
            f / t
        };
        let billboards = |ambient: SkyLight| billboards_by(ambient, Scattering::MULTIPLE);
        let (harmonics, isotropic, solved) = (
            billboards(above),
            billboards(SkyLight::uniform(Vec3::splat(0.5))),
            billboards_by(above, Scattering::SOLVE),
        );
        let thirds = |fast: &[f64]| [0..9, 9..19, 19..28].map(|rows| ratio(fast, rows));
        for (name, fast) in [
            ("harmonics", &harmonics),
            ("isotropic", &isotropic),
            ("solved", &solved),
        ] {
            eprintln!(
                "sky light alone from {height} m, {name}: billboards / path tracer {:.3}; top, middle, bottom thirds {:.3?}",
                ratio(fast, 0..28),
                thirds(fast),
            );
        }
        // Measured: 1.06 (thirds 1.15, 0.97, 1.35) from above, 1.09 (1.13, 1.10, 0.96)
        // level, 1.08 (1.16, 1.11, 0.87) from below; through the solve 0.96 (0.99,
        // 0.93, 1.08), 1.01 (0.98, 1.01, 1.10) and 1.04 (0.97, 1.06, 1.03), where the
        // solve read the sky's harmonics it was 1.05 (1.02, 1.01, 1.36) from above, the
        // base lit by their ringing from below the horizon; not dimmed
        // inside the cloud, 0.97 (0.83, 0.92, 1.48), 1.10 (0.86, 1.16, 1.23) and 1.18
        // (1.01, 1.26, 1.03); the isotropic term from above 1.09 (0.86, 1.03, 1.78).
        // From above, the rows at the bottom are the cloud's lower flanks, where the
        // droplets' forward lobe looks at the dark below. Each way: the mean within
        // `mean` of the path tracer's, every third within `low` to `high`.
        for (name, fast, mean, low, high) in [
            ("the dimming profile", &harmonics, 0.12, 0.8, 1.4),
            ("through the solve", &solved, 0.05, 0.9, 1.15),
        ] {
            let whole = ratio(fast, 0..28);
            assert!(
                (whole - 1.0).abs() < mean,
                "from {height} m, {name}, the mean: {whole}"
            );
            for third in thirds(fast) {
                assert!(
                    third > low && third < high,
                    "from {height} m, {name}, a third: {third}"
                );
            }
        }
        if height == 2400.0 {
            let (base, base_before) = (ratio(&harmonics, 19..28), ratio(&isotropic, 19..28));
            assert!(
                base < base_before - 0.3,
                "the base: {base} against {base_before}"
            );
        }
    }
}

/// The transfer table on a cloud no fit has seen (another seed, a particle count and a
/// density none of the fit's nine clouds has) from three sides: above with the sun
/// from the front, level with it from the side, below with it behind the cloud.
/// Measured at 40 x 24, 24 paths a pixel: the table 0.998, 0.996 and 1.065 of the path
/// tracer in the mean (the octaves 1.062, 1.042 and 1.270), every order 3.9, 8.0 and
/// 1.6 times single scattering.
#[test]
fn every_order_holds_on_a_cloud_no_fit_has_seen() {
    let particles = Cumulus {
        particles: 1200,
        density: 0.01,
        seed: 11,
        ..Cumulus::default()
    }
    .generate();
    let middle = centre(&particles).y;
    // Each view: its bound on the table's mean (about twice the measured error, and
    // the 10 % from below against the sun).
    for (name, height, azimuth, bound) in [
        ("above, front", 2400.0, 200.0, 0.03),
        ("level, side", middle, 290.0, 0.03),
        ("below, behind", 300.0, 20.0, 0.10),
    ] {
        let camera = camera_at(&particles, height, 40, 24);
        let to_sun = Sun::from_degrees(25.0, azimuth).unwrap().toward();
        let ([table, octaves], gain) = every_order(&particles, &camera, to_sun);
        eprintln!("unseen cloud, {name}: every order, billboards / path tracer {table:.3} (octaves {octaves:.3}); path tracer / single {gain:.2}");
        assert!(gain > 1.3, "{name}: higher orders add light: {gain}");
        assert!((table - 1.0).abs() < bound, "{name}: {table}");
        assert!(
            (table - 1.0).abs() < (octaves - 1.0).abs(),
            "{name}: the table {table} nearer than the octaves {octaves}"
        );
    }
}

/// The transfer solve (atmo::clouds::DiffuseLight), which no fit has touched but its
/// flux limiter's streaming limit (chosen over the 36 views of three clouds, this one's
/// among them), against the path tracer on the 200-particle cloud from above: its
/// mean within 5 % and the mean of the thickest fifth of the cloud's pixels (its core)
/// within 10 %. Measured at 48 x 28, 24 paths a pixel: front 0.953, side 0.968, behind
/// 0.965 in the mean; the core 0.942, 0.931, 0.941 (the fringe, the thinnest fifth,
/// 1.11, 1.15 and 1.04: docs/clouds.md, "Every order: the transfer solve").
#[test]
fn the_transfer_solve_matches_the_path_tracer_on_a_small_cloud() {
    let particles = cloud();
    let camera = camera(&particles, 48, 28);
    let settings = PathSettings {
        paths: 24,
        orders: usize::MAX,
        seed: 3,
    };
    for ((name, to_sun, cloud), (mean_bound, core_bound)) in lit(&particles).zip([(0.05, 0.10); 3])
    {
        let traced: Vec<f64> = cloud
            .path_traced_picture(&camera, &settings)
            .iter()
            .map(|p| p.0)
            .collect();
        let covered = cloud.covered(&camera);
        let solved = fast(&particles, &camera, to_sun, Scattering::SOLVE);
        let single = fast(&particles, &camera, to_sun, Scattering::SINGLE);
        let mean = mean_ratio(&camera, &covered, &solved, &traced);
        let [fringe, core] = fifths(&solved, &traced, &covered, &cloud.depths(&camera));
        let gain = mean_ratio(&camera, &covered, &solved, &single);
        eprintln!("{name}: the solve / path tracer {mean:.3}, core {core:.3}, fringe {fringe:.3}; solve / single {gain:.2}");
        assert!(
            gain > 2.0,
            "{name}: the solve adds the higher orders: {gain}"
        );
        assert!((mean - 1.0).abs() < mean_bound, "{name}: {mean}");
        assert!((core - 1.0).abs() < core_bound, "{name}: core {core}");
    }
}
