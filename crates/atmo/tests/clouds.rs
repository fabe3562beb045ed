//! The cloud light pass: the intensity buffer against the exact transmittance, the
//! prefix-sum fill against the paper's shadow polygons, order and thread independence,
//! and bad input.

use atmo::clouds::buffer::{IntensityBuffer, Splat};
use atmo::clouds::generator::{Cumulus, SplitMix64};
use atmo::clouds::particles::Particle;
use atmo::reference::clouds::{shadow_polygons, transmittance};
use glam::Vec3;

fn cloud(particles: usize) -> Vec<Particle> {
    Cumulus {
        particles,
        width: 400.0,
        ..Cumulus::default()
    }
    .generate()
}

fn sun(elevation_deg: f32, azimuth_deg: f32) -> Vec3 {
    let (e, a) = (elevation_deg.to_radians(), azimuth_deg.to_radians());
    Vec3::new(e.cos() * a.sin(), e.sin(), e.cos() * a.cos())
}

/// Mean and max of |Gamma - exact| / exact over all voxel centres with exact > 1e-3.
fn errors_at_centres(buffer: &IntensityBuffer, particles: &[Particle], to_sun: Vec3) -> (f64, f64) {
    let n = buffer.resolution;
    let (mut sum, mut max, mut count) = (0.0f64, 0.0f64, 0usize);
    for ix in (0..n).step_by(3) {
        for iz in (0..n).step_by(3) {
            for iy in 0..n {
                let exact = transmittance(particles, to_sun, buffer.voxel_centre(ix, iy, iz));
                if exact > 1e-3 {
                    let e = (buffer.at(ix, iy, iz) as f64 - exact).abs() / exact;
                    sum += e;
                    max = max.max(e);
                    count += 1;
                }
            }
        }
    }
    assert!(count > 1000, "{count}");
    (sum / count as f64, max)
}

#[test]
fn split_particles_give_the_exact_transmittance_at_voxel_centres() {
    let particles = cloud(3000);
    let to_sun = sun(35.0, 40.0);
    let pieces = IntensityBuffer::new(&particles, to_sun, 48, 0.0, Splat::Pieces).unwrap();
    let (mean, max) = errors_at_centres(&pieces, &particles, to_sun);
    // What is left is the footprints' cut 3.5 s from each axis (0.2 % of a column).
    assert!(mean < 3e-3 && max < 3e-2, "pieces: mean {mean} max {max}");
    // The paper's one factor per particle shadows a voxel by the whole of a particle it
    // sits in: further off, but not wildly.
    let whole = IntensityBuffer::new(&particles, to_sun, 48, 0.0, Splat::Whole).unwrap();
    let (mean_whole, _) = errors_at_centres(&whole, &particles, to_sun);
    assert!(
        mean_whole > 10.0 * mean && mean_whole < 0.5,
        "whole: {mean_whole}"
    );
    // The cloud casts a real shadow: Gamma ranges from about 1 to nearly 0.
    let (lo, hi) = pieces.log_gamma.iter().fold((1.0f32, 0.0f32), |(l, h), g| {
        (l.min(g.exp()), h.max(g.exp()))
    });
    assert!(lo < 0.05 && hi > 0.99, "{lo} {hi}");
}

#[test]
fn the_prefix_sum_fill_equals_the_papers_shadow_polygons() {
    let particles = cloud(80);
    for (to_sun, forward) in [(sun(60.0, 10.0), 0.0), (sun(20.0, 200.0), 0.5)] {
        let buffer = IntensityBuffer::new(&particles, to_sun, 20, forward, Splat::Whole).unwrap();
        let slow = shadow_polygons(&buffer, &particles, forward);
        let worst = buffer
            .log_gamma
            .iter()
            .zip(&slow)
            .map(|(a, b)| ((a.exp() - b).abs() / b.max(1e-6)) as f64)
            .fold(0.0, f64::max);
        assert!(worst < 2e-5, "{worst}");
        assert!(slow.iter().any(|g| *g < 0.5), "the test has shadow in it");
    }
}

#[test]
fn particle_order_and_thread_count_do_not_change_the_buffer() {
    let particles = cloud(2000);
    let to_sun = sun(30.0, 70.0);
    let build = |p: &[Particle]| IntensityBuffer::new(p, to_sun, 40, 0.6, Splat::Pieces).unwrap();
    let reference = build(&particles);
    // Shuffled (Fisher-Yates with a fixed seed): the same within rounding.
    let mut shuffled = particles.clone();
    let mut rng = SplitMix64::new(7);
    for i in (1..shuffled.len()).rev() {
        shuffled.swap(i, (rng.next_u64() % (i as u64 + 1)) as usize);
    }
    let other = build(&shuffled);
    let worst = reference
        .log_gamma
        .iter()
        .zip(&other.log_gamma)
        .map(|(a, b)| (a.exp() - b.exp()).abs() / b.exp().max(1e-6))
        .fold(0.0f32, f32::max);
    assert!(worst < 1e-4, "{worst}");
    // Thread count: bit for bit.
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| build(&particles));
    assert_eq!(one.log_gamma, reference.log_gamma);
}

/// 2,000 points in the cloud: near particle centres (chosen by `seed`), jittered
/// within their radius.
fn points_in(particles: &[Particle], seed: u64) -> Vec<Vec3> {
    let mut rng = SplitMix64::new(seed);
    (0..2000)
        .map(|_| {
            let p = particles[(rng.next_u64() % particles.len() as u64) as usize];
            p.position
                + Vec3::new(
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                ) * p.radius
        })
        .collect()
}

#[test]
fn trilinear_lookups_between_centres_stay_close_to_the_exact_transmittance() {
    let particles = cloud(3000);
    let to_sun = sun(35.0, 40.0);
    let buffer = IntensityBuffer::new(&particles, to_sun, 96, 0.0, Splat::Pieces).unwrap();
    let (mut sum, mut count) = (0.0f64, 0);
    for point in points_in(&particles, 3) {
        let exact = transmittance(&particles, to_sun, point);
        if exact > 1e-2 {
            sum += (buffer.sample(point) as f64 - exact).abs() / exact;
            count += 1;
        }
    }
    let mean = sum / count as f64;
    assert!(count > 200 && mean < 0.05, "{count} points, mean {mean}");
    // Outside the grid on the sun's side: full sunlight.
    let far_up = particles[0].position + to_sun.normalize() * 5000.0;
    assert_eq!(buffer.sample(far_up), 1.0);
}

/// The buffer's slope along the light (`IntensityBuffer::extinction`, what the drawing
/// takes the blobs beside a blob from) against the particles' extinction at the same
/// points: the mean over a voxel along the light, so converging as the voxels shrink
/// (measured 38, 8.4 and 4.0 % in the mean where the cloud is at 32^3, 96^3 and
/// 192^3); nothing outside the cloud.
#[test]
fn the_buffers_slope_along_the_light_is_the_clouds_extinction() {
    let particles = cloud(3000);
    let to_sun = sun(35.0, 40.0);
    let extinction = |x: Vec3| particles.iter().map(|p| p.extinction_at(x)).sum::<f32>();
    let mean_error = |resolution: usize| {
        let buffer =
            IntensityBuffer::new(&particles, to_sun, resolution, 0.0, Splat::Pieces).unwrap();
        let (mut sum, mut count) = (0.0f64, 0);
        for point in points_in(&particles, 5) {
            let exact = extinction(point) as f64;
            if exact > 1e-3 {
                sum += (buffer.extinction(point) as f64 - exact).abs() / exact;
                count += 1;
            }
        }
        assert!(count > 200, "{count} points");
        let far_up = particles[0].position + to_sun.normalize() * 5000.0;
        assert_eq!(buffer.extinction(far_up), 0.0);
        sum / count as f64
    };
    let errors = [32, 96, 192].map(mean_error);
    eprintln!("the buffer's extinction: mean error {errors:?} at 32^3, 96^3 and 192^3");
    assert!(
        errors[2] < 0.06 && errors[1] < errors[0] && errors[2] < errors[1],
        "{errors:?}"
    );
}

#[test]
fn bad_buffers_are_refused() {
    let particles = cloud(50);
    let up = Vec3::Y;
    let message = |r: atmo::Result<IntensityBuffer>| r.expect_err("refused").to_string();
    assert!(
        message(IntensityBuffer::new(&[], up, 32, 0.5, Splat::Pieces)).contains("no particles")
    );
    assert!(message(IntensityBuffer::new(
        &particles,
        up,
        1024,
        0.5,
        Splat::Pieces
    ))
    .contains("budget"));
    assert!(message(IntensityBuffer::new(
        &particles,
        Vec3::ZERO,
        32,
        0.5,
        Splat::Pieces
    ))
    .contains("sun direction"));
    assert!(
        message(IntensityBuffer::new(&particles, up, 32, 1.5, Splat::Pieces)).contains("forward")
    );
}

#[test]
fn the_harris_baseline_follows_its_recursion() {
    use atmo::clouds::harris::light_per_particle;
    // Four particles on a vertical line under an overhead sun, and one to the side whose
    // axis passes 3 m from theirs; sun-side first: y decreasing.
    let particle = |x: f32, y: f32| Particle {
        position: Vec3::new(x, y, 0.0),
        radius: 10.0,
        density: 0.08,
        albedo: 0.9,
    };
    let particles = vec![
        particle(0.0, 40.0),
        particle(0.0, 20.0),
        particle(3.0, 10.0),
        particle(0.0, 0.0),
        particle(0.0, -20.0),
    ];
    let forward = 0.5;
    let got = light_per_particle(&particles, Vec3::Y, 2048, forward).unwrap();
    // Direct evaluation of clouds (3)-(4) along each particle's centre line.
    let mut want = vec![0.0f64; particles.len()];
    for k in 0..particles.len() {
        let mut light = 1.0f64;
        for j in 0..k {
            let b = {
                let d = particles[k].position - particles[j].position;
                (d.x * d.x + d.z * d.z).sqrt() as f64
            };
            let tau = particles[j].column(b, f64::NEG_INFINITY, f64::INFINITY);
            light =
                particles[j].albedo as f64 * tau * forward as f64 * want[j] + (-tau).exp() * light;
        }
        want[k] = light;
    }
    for (k, (g, w)) in got.iter().zip(&want).enumerate() {
        assert!((*g as f64 - w).abs() < 0.01 * w, "particle {k}: {g} vs {w}");
    }
    assert!(want[4] < 0.6 * want[0], "{want:?}");
}

#[test]
fn particle_files_round_trip_and_bad_ones_name_the_line() {
    use atmo::clouds::files;
    let dir = std::env::temp_dir().join(format!("atmo-particles-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let particles = cloud(300);
    for name in ["cloud.csv", "cloud.atmo-particles"] {
        let path = dir.join(name);
        files::write(&path, &particles).unwrap();
        assert_eq!(files::read(&path, 0.5).unwrap(), particles, "{name}");
    }
    let good = "# a test\nx,y,z,radius,density\n0,0,0,1,0.1\n\n1,2,3,2,0.2\n";
    let read = files::parse_csv(good, "t.csv", 0.7).unwrap();
    assert_eq!(read.len(), 2);
    assert_eq!(read[1].albedo, 0.7);
    let bad = [
        (
            "x,y,z,radius,density\n0,0,0,1,0.1\n0,0,0,-1,0.1\n",
            "t.csv:3: radius",
        ),
        ("x,y,z,radius,density\n0,0,0,1,NaN\n", "t.csv:2: density"),
        ("x,y,z,radius,density\n0,0,0,1,-0.5\n", "t.csv:2: density"),
        ("x,y,z,radius,density\n0,0,zero,1,0.1\n", "t.csv:2: `zero`"),
        ("x,y,z,radius,density\n0,0,0,1\n", "t.csv:2: 4 values"),
        ("x,y,z,radius\n0,0,0,1\n", "t.csv:1: the header"),
        ("x,y,z,radius,density\n", "no particles"),
        ("", "no header"),
    ];
    for (text, wanted) in bad {
        let message = files::parse_csv(text, "t.csv", 1.0)
            .unwrap_err()
            .to_string();
        assert!(message.contains(wanted), "{text:?}: {message}");
    }
    let binary = std::fs::read(dir.join("cloud.atmo-particles")).unwrap();
    for (bytes, wanted) in [
        (binary[..binary.len() - 3].to_vec(), "bytes of particles"),
        (
            b"ATMOPARX0000000000000".to_vec(),
            "not an atmo particle file",
        ),
        (
            [&binary[..8], &2u32.to_le_bytes(), &binary[12..]].concat(),
            "version 2",
        ),
    ] {
        let message = files::parse_binary(&bytes, "b").unwrap_err().to_string();
        assert!(message.contains(wanted), "{message}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// 65 x 65 pixels at the origin looking down -z, 11.4 deg across.
fn axis_camera() -> atmo::view::Camera {
    use atmo::view::{Camera, Lens};
    Camera {
        position: Vec3::ZERO,
        forward: Vec3::NEG_Z,
        right: Vec3::X,
        up: Vec3::Y,
        lens: Lens::Pinhole {
            tan_half_width: 0.1,
            tan_half_height: 0.1,
        },
        width: 65,
        height: 65,
        supersampling: 1,
        far: f32::INFINITY,
    }
}

#[test]
fn billboards_composite_as_clouds_five_each_blob_taking_its_absorbed_share() {
    use atmo::atmosphere::PhaseFunction;
    use atmo::clouds::render::{render, AerialHaze, CloudLight};
    use atmo::image::Frame;
    // Two particles on the camera's axis, the pixel at the image centre looking through
    // both; only ambient light, so each source is a (1 - e^-tau) ambient (clouds (6)'s
    // a tau ambient for a blob that also absorbs what it scatters), tau the faded column.
    let particle = |z: f32, density: f32| Particle {
        position: Vec3::new(0.0, 0.0, z),
        radius: 6.0,
        density,
        albedo: 0.8,
    };
    let particles = vec![particle(-200.0, 0.05), particle(-100.0, 0.02)];
    let camera = axis_camera();
    // The same sky from everywhere: what a droplet scatters of it is the same
    // whichever way it is seen.
    let sky = Vec3::new(1.0, 0.5, 0.25);
    let light = CloudLight {
        to_sun: Vec3::Y,
        sun: Vec3::ZERO,
        ambient: atmo::clouds::SkyLight::uniform(sky),
        phase: PhaseFunction::CloudMie,
        haze: AerialHaze::CLEAR,
        scattering: atmo::clouds::Scattering::SINGLE,
    };
    let buffer = IntensityBuffer::new(&particles, Vec3::Y, 16, 0.5, Splat::Pieces).unwrap();
    let mut background = Frame::new(65, 65);
    background
        .pixels
        .iter_mut()
        .for_each(|p| *p = Vec3::splat(2.0));
    let frame = render(&particles, &buffer, &camera, &light, Some(&background)).unwrap();
    let tau = |p: &Particle| p.faded_column(0.0);
    let (near, far) = (tau(&particles[1]), tau(&particles[0]));
    // The faded column on the axis is the Gaussian's within a few per cent.
    let gaussian = particles[1].column(0.0, f64::NEG_INFINITY, f64::INFINITY) as f32;
    assert!((near / gaussian - 1.0).abs() < 0.02, "{near} {gaussian}");
    let a = 0.8;
    let absorbed = |tau: f32| 1.0 - (-tau).exp();
    let want = sky * (a * absorbed(near))
        + (-near).exp() * (sky * (a * absorbed(far)) + (-far).exp() * Vec3::splat(2.0));
    let got = frame.pixels[32 * 65 + 32];
    assert!(
        (got - want).abs().max_element() < 1e-4 * want.max_element(),
        "{got:?} vs {want:?}"
    );
    // Far from the particles: the background alone.
    assert_eq!(frame.pixels[0], Vec3::splat(2.0));
}

/// The paper's own billboards, the frame's baseline: two blobs on the axis each send
/// `a tau p Gamma` (clouds (6)), `Gamma` read at the centre, composited by (5) over
/// the background; the sky and every order of the light given are not theirs.
#[test]
fn the_papers_billboards_send_a_tau_p_gamma_each() {
    use atmo::atmosphere::PhaseFunction;
    use atmo::clouds::render::{paper_billboards, render, AerialHaze, CloudLight};
    use atmo::clouds::{Scattering, SkyLight};
    use atmo::image::Frame;
    let particle = |z: f32, density: f32| Particle {
        position: Vec3::new(0.0, 0.0, z),
        radius: 6.0,
        density,
        albedo: 0.8,
    };
    let particles = vec![particle(-200.0, 0.3), particle(-100.0, 0.02)];
    let camera = axis_camera();
    let light = CloudLight {
        to_sun: Vec3::Y,
        sun: Vec3::ONE,
        ambient: SkyLight::uniform(Vec3::ONE),
        phase: PhaseFunction::CloudMie,
        haze: AerialHaze::CLEAR,
        scattering: Scattering::MULTIPLE,
    };
    let buffer = IntensityBuffer::new(&particles, Vec3::Y, 16, 0.0, Splat::Pieces).unwrap();
    let mut background = Frame::new(65, 65);
    background.pixels.fill(Vec3::splat(2.0));
    let paper = paper_billboards(&particles, &buffer, &camera, &light, Some(&background)).unwrap();
    // The sun straight above, the ray along the axis: the phase at 90 degrees.
    let p = PhaseFunction::CloudMie.eval_f32(0.0);
    let source = |k: usize| {
        let q = &particles[k];
        0.8 * q.faded_column(0.0) * p * buffer.sample(q.position)
    };
    let through = |k: usize| (-particles[k].faded_column(0.0)).exp();
    let want = source(1) + through(1) * (source(0) + through(0) * 2.0);
    let got = paper.pixels[32 * 65 + 32];
    assert!(
        (got - Vec3::splat(want)).abs().max_element() < 1e-4 * want,
        "{got} vs {want}"
    );
    assert_eq!(paper.pixels[0], Vec3::splat(2.0));
    // The far blob is thick (a column of 1.5): the paper's thin blob sends more than
    // the drawing's, which absorbs its own light.
    let single = CloudLight {
        ambient: SkyLight::NONE,
        scattering: Scattering::SINGLE,
        ..light
    };
    let drawn = render(&particles, &buffer, &camera, &single, Some(&background)).unwrap();
    let behind = 2.0 * through(0) * through(1);
    let (thin, absorbing) = (got.x - behind, drawn.pixels[32 * 65 + 32].x - behind);
    assert!(thin > 1.4 * absorbing, "{thin} vs {absorbing}");
}

/// The billboards are drawn eight pixels of a row at a time: a blob on the axis comes out
/// the same on both sides of it (its pixels fall in other lanes on each side), and a
/// blob cut by the frame's right edge lights nothing at the left of the rows below (the
/// last eight of a row run past its end, into the next row's first pixels).
#[test]
fn billboards_drawn_eight_pixels_at_a_time_keep_each_pixel_its_own() {
    use atmo::atmosphere::PhaseFunction;
    use atmo::clouds::render::{render, AerialHaze, CloudLight};
    let camera = axis_camera();
    // The sun straight above: the light is symmetric about the vertical plane x = 0,
    // to the buffer's rounding (the rim's faint pixels differ by up to 15 % of
    // themselves, a millionth of the brightest, with the pixels drawn one at a time).
    let light = CloudLight {
        to_sun: Vec3::Y,
        sun: Vec3::ONE,
        ambient: atmo::clouds::SkyLight::NONE,
        phase: PhaseFunction::CloudMie,
        haze: AerialHaze::CLEAR,
        scattering: atmo::clouds::Scattering::MULTIPLE,
    };
    let draw = |x: f32| {
        let particles = [Particle {
            position: Vec3::new(x, 0.0, -100.0),
            radius: 6.0,
            density: 0.05,
            albedo: 0.9,
        }];
        let buffer = IntensityBuffer::new(&particles, Vec3::Y, 32, 0.0, Splat::Pieces).unwrap();
        render(&particles, &buffer, &camera, &light, None).unwrap()
    };
    let centred = draw(0.0);
    let lit = centred.pixels.iter().filter(|p| p.x > 0.0).count();
    assert!(lit > 300, "{lit} pixels lit");
    let brightest = centred.pixels.iter().map(|p| p.x).fold(0.0, f32::max);
    for y in 0..65 {
        for x in 0..65 {
            let (a, b) = (centred.pixels[y * 65 + x], centred.pixels[y * 65 + 64 - x]);
            assert!(
                (a - b).abs().max_element() <= 1e-2 * a.max(b).max_element() + 1e-6 * brightest,
                "({x}, {y}): {a:?} vs {b:?}"
            );
        }
    }
    // Centred on column 62 (of 65), 19 pixels across its reach.
    let cut = draw(100.0 * 0.1 * 30.0 / 32.5);
    for y in 0..65 {
        let row = &cut.pixels[y * 65..(y + 1) * 65];
        assert!(
            row[..16].iter().all(|p| *p == Vec3::ZERO),
            "row {y}: {:?}",
            &row[..8]
        );
    }
    assert!(cut.pixels[32 * 65 + 64].x > 0.1 * brightest);
}

/// Each billboard is drawn row by row over the row's chord of its silhouette (an
/// ellipse on the screen), not over a square around it: a blob seen near the corner of
/// a wide view, where perspective stretches it most, still lights every pixel whose ray
/// passes within its reach, and none whose ray passes clear of it.
#[test]
fn a_billboard_lights_every_pixel_within_its_reach_and_no_other() {
    use atmo::atmosphere::PhaseFunction;
    use atmo::clouds::render::{render, AerialHaze, CloudLight};
    use atmo::view::{Camera, Lens};
    // 113 deg across, 90 deg high.
    let camera = Camera {
        lens: Lens::Pinhole {
            tan_half_width: 1.5,
            tan_half_height: 1.0,
        },
        width: 96,
        height: 64,
        ..axis_camera()
    };
    let light = CloudLight {
        to_sun: Vec3::Y,
        sun: Vec3::ZERO,
        ambient: atmo::clouds::SkyLight::uniform(Vec3::ONE),
        phase: PhaseFunction::CloudMie,
        haze: AerialHaze::CLEAR,
        scattering: atmo::clouds::Scattering::SINGLE,
    };
    // Near the corner and the top, large; and small ones, a few pixels across, placed
    // off the pixels' centres every way.
    let mut centres = vec![
        60.0 * Vec3::new(1.3, -0.85, -1.0),
        60.0 * Vec3::new(-0.4, 0.9, -1.0),
    ];
    for k in 0..12 {
        let (x, y) = (k as f32 * 0.137 - 0.8, 0.5 - k as f32 * 0.083);
        centres.push(200.0 * Vec3::new(x, y, -1.0));
    }
    let mut small = 0;
    for centre in centres {
        let particles = [Particle {
            position: centre,
            radius: 12.0,
            density: 0.05,
            albedo: 0.9,
        }];
        let buffer = IntensityBuffer::new(&particles, Vec3::Y, 16, 0.0, Splat::Pieces).unwrap();
        let frame = render(&particles, &buffer, &camera, &light, None).unwrap();
        let reach = particles[0].reach();
        let mut inside = 0;
        for y in 0..64 {
            for x in 0..96 {
                let ray = camera.ray(x as f32 + 0.5, y as f32 + 0.5).normalize();
                let d = particles[0].position;
                // The ray's distance from the centre, within or clear of the reach by 2 %.
                let b = (d.length_squared() - d.dot(ray).powi(2)).max(0.0).sqrt();
                let lit = frame.pixels[y * 96 + x].x > 0.0;
                if b < 0.98 * reach {
                    inside += 1;
                    assert!(lit, "({x}, {y}) within the reach of {centre} and dark");
                } else if b > 1.02 * reach {
                    assert!(!lit, "({x}, {y}) clear of {centre} and lit");
                }
            }
        }
        assert!(inside > 4, "{inside} pixels within the reach");
        small += (inside < 40) as usize;
    }
    assert_eq!(small, 12, "the far blobs are a few pixels across");
}

/// The depths given to the drawing are one per particle where it reads them: down the
/// vertical where the sky's light is dimmed inside the cloud (a brighter sky above than
/// below), out of the cloud where the transfer table draws every order; the same picture
/// as `render` makes with its own; where neither, they are not read.
#[test]
fn depths_given_to_the_drawing_are_one_per_particle_where_they_are_read() {
    use atmo::atmosphere::PhaseFunction;
    use atmo::clouds::render::{
        dims_the_sky, needs_depths, render, render_with_depths, AerialHaze, CloudLight, Scattering,
    };
    use atmo::clouds::{CloudDepths, Octaves, SkyLight};
    let particles = cloud(60);
    let buffer = IntensityBuffer::new(&particles, Vec3::Y, 16, 0.0, Splat::Pieces).unwrap();
    let centre = particles.iter().map(|p| p.position).sum::<Vec3>() / 60.0;
    let camera = atmo::view::Camera::look_at(
        centre + Vec3::new(0.0, 200.0, -1500.0),
        centre,
        Vec3::Y,
        atmo::view::Fov::Vertical(30.0),
        (32, 18),
    )
    .unwrap();
    let mut sh = [[0.0; 3]; 9];
    sh[0] = [1.0; 3];
    sh[1] = [0.8; 3];
    let light = CloudLight {
        to_sun: Vec3::Y,
        sun: Vec3::ONE,
        ambient: SkyLight::from_harmonics(&sh),
        phase: PhaseFunction::CloudMie,
        haze: AerialHaze::CLEAR,
        scattering: Scattering::MULTIPLE,
    };
    assert!(dims_the_sky(&light));
    let depths = CloudDepths::of(&particles).unwrap();
    let given =
        render_with_depths(&particles, &depths, &buffer, None, &camera, &light, None).unwrap();
    let own = render(&particles, &buffer, &camera, &light, None).unwrap();
    assert!(
        own.pixels.iter().any(|p| p.x > 0.0),
        "the cloud in the picture"
    );
    assert!(given.pixels == own.pixels);
    let shortened = |vertical: usize, out: usize, thickness: usize| CloudDepths {
        vertical: depths.vertical[..vertical].to_vec(),
        out: depths.out[..out].to_vec(),
        thickness: depths.thickness[..thickness].to_vec(),
    };
    let short = |vertical: usize, out: usize| shortened(vertical, out, out);
    for (shorter, counted) in [
        (short(59, 60), "59 vertical depths given for 60 particles"),
        (
            short(60, 59),
            "59 depths out of the cloud given for 60 particles",
        ),
        (
            shortened(60, 60, 59),
            "59 thicknesses given for 60 particles",
        ),
    ] {
        let message =
            render_with_depths(&particles, &shorter, &buffer, None, &camera, &light, None)
                .unwrap_err()
                .to_string();
        assert!(message.contains(counted), "{message}");
    }
    // A sky alike all round is not dimmed: the table alone reads the depths out.
    let flat = CloudLight {
        ambient: SkyLight::uniform(Vec3::ONE),
        ..light
    };
    assert!(!dims_the_sky(&flat) && needs_depths(&flat));
    render_with_depths(
        &particles,
        &short(0, 60),
        &buffer,
        None,
        &camera,
        &flat,
        None,
    )
    .unwrap();
    let octaves = CloudLight {
        scattering: Scattering::Octaves(Octaves::MULTIPLE),
        ..flat
    };
    assert!(!needs_depths(&octaves));
    render_with_depths(
        &particles,
        &CloudDepths::default(),
        &buffer,
        None,
        &camera,
        &octaves,
        None,
    )
    .unwrap();
    // A transfer solve is needed to draw with one, and named when missing.
    let solved = CloudLight {
        scattering: Scattering::SOLVE,
        ..octaves
    };
    let message = render_with_depths(
        &particles,
        &CloudDepths::default(),
        &buffer,
        None,
        &camera,
        &solved,
        None,
    )
    .unwrap_err()
    .to_string();
    assert!(message.contains("transfer solve"), "{message}");
}
