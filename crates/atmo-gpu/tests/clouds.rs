//! Clouds on the GPU against the CPU: the intensity buffer of both splats, and the
//! drawn cloud, with and without a background.

mod common;

use atmo::atmosphere::PhaseFunction;
use atmo::clouds::buffer::{IntensityBuffer, Splat};
use atmo::clouds::generator::Cumulus;
use atmo::clouds::particles::Particle;
use atmo::clouds::render::{render, Haze, Lighting};
use atmo::clouds::Octaves;
use atmo::image::Frame;
use atmo::view::{Camera, Fov};
use atmo_gpu::clouds::GpuClouds;
use common::{assert_close, gpu, mean_level};
use glam::Vec3;

fn cloud() -> Vec<Particle> {
    Cumulus {
        particles: 1500,
        width: 400.0,
        ..Cumulus::default()
    }
    .generate()
}

fn to_sun() -> Vec3 {
    let (e, a) = (35f32.to_radians(), 40f32.to_radians());
    Vec3::new(e.cos() * a.sin(), e.sin(), e.cos() * a.cos())
}

#[test]
fn the_light_pass_matches_the_cpu_buffer_for_both_splats() {
    let Some(gpu) = gpu() else { return };
    let particles = cloud();
    let mut clouds = GpuClouds::new(&gpu, &particles, 40).unwrap();
    for splat in [Splat::Whole, Splat::Pieces] {
        let forward = 0.3;
        let cpu = IntensityBuffer::new(&particles, to_sun(), 40, forward, splat).unwrap();
        clouds.light(&gpu, to_sun(), forward, splat).unwrap();
        let out = clouds.log_gamma(&gpu).unwrap();
        assert_eq!(out.len(), cpu.log_gamma.len());
        let darkest = cpu.log_gamma.iter().copied().fold(0.0, f32::min);
        assert!(
            darkest < -2.0,
            "{splat:?}: the cloud casts no shadow ({darkest})"
        );
        // Fixed point (2^-16 a step) and f32 exp/log on the GPU against the CPU's f64
        // column sums: Gamma within 0.05 % where it matters.
        let worst = out
            .iter()
            .zip(&cpu.log_gamma)
            .map(|(a, b)| (a - b).abs() * b.exp())
            .fold(0.0f32, f32::max);
        assert!(worst < 5e-4, "{splat:?}: worst |Gamma| difference {worst}");
    }
}

#[test]
fn the_drawn_cloud_matches_the_cpu_picture() {
    let Some(gpu) = gpu() else { return };
    let particles = cloud();
    let camera = Camera::look_at(
        Vec3::new(0.0, 1700.0, -600.0),
        Vec3::new(0.0, 1650.0, 0.0),
        Vec3::Y,
        Fov::Vertical(2.0 * 0.45f32.atan().to_degrees()),
        (120, 80),
    )
    .unwrap();
    let mut background = Frame::new(120, 80);
    for (i, p) in background.pixels.iter_mut().enumerate() {
        *p = Vec3::new(0.2, 0.3, 0.5) * (1.0 + (i % 120) as f32 / 120.0);
    }
    let mut clouds = GpuClouds::new(&gpu, &particles, 48).unwrap();
    clouds.light(&gpu, to_sun(), 0.0, Splat::Pieces).unwrap();
    let buffer = IntensityBuffer::new(&particles, to_sun(), 48, 0.0, Splat::Pieces).unwrap();
    for (phase, back, scattering) in [
        (PhaseFunction::CloudMie, None, Octaves::MULTIPLE),
        (
            PhaseFunction::HenyeyGreenstein { g: 0.6 },
            Some(&background),
            Octaves::SINGLE,
        ),
    ] {
        let light = Lighting {
            to_sun: to_sun(),
            sun: Vec3::ONE,
            ambient: Vec3::new(0.03, 0.04, 0.06),
            phase,
            // Air in front of the cloud: the GPU hazes it as the CPU does.
            haze: Haze {
                transmittance: Vec3::new(0.8, 0.85, 0.9),
                inscatter: Vec3::new(0.01, 0.02, 0.04),
            },
            scattering,
        };
        let cpu = render(&particles, &buffer, &camera, &light, back).unwrap();
        let out = clouds.render(&gpu, &camera, &light, back).unwrap().frame;
        assert!(
            mean_level(&out, 4.0) > 15.0,
            "{phase:?}: the picture is dark"
        );
        assert_close(&out, &cpu, 4.0, &format!("{phase:?}"));
    }
}

#[test]
fn drawing_before_the_light_pass_and_oversized_buffers_are_refused() {
    let Some(gpu) = gpu() else { return };
    let particles = cloud();
    let clouds = GpuClouds::new(&gpu, &particles, 8).unwrap();
    let camera = Camera::look_at(
        Vec3::Z * -2000.0,
        Vec3::ZERO,
        Vec3::Y,
        Fov::Vertical(53.0),
        (8, 8),
    )
    .unwrap();
    let light = Lighting {
        to_sun: to_sun(),
        sun: Vec3::ONE,
        ambient: Vec3::ZERO,
        phase: PhaseFunction::CloudMie,
        haze: Haze::CLEAR,
        scattering: Octaves::SINGLE,
    };
    let err = clouds.render(&gpu, &camera, &light, None).err().unwrap();
    assert!(err.to_string().contains("light pass"), "{err}");
    let err = GpuClouds::new(&gpu, &particles, 1024).err().unwrap();
    assert!(err.to_string().contains("resolution"), "{err}");
}
