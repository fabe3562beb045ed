//! The sky from the skylight table on the GPU against the CPU draw of the same table.

mod common;

use std::sync::OnceLock;

use atmo::atmosphere::spectrum::SpectrumToRgb;
use atmo::sky::table::{SkylightTable, TableSettings};
use atmo::sky::{Order, SkyModel, SkySettings};
use atmo::sky::{SkyPicture, View};
use atmo::view::{Camera, Fov, Sun};
use atmo::Atmosphere;
use atmo_gpu::sky::{
    AerialTextures, DepthTarget, GpuAerial, GpuSkyModel, GpuSkyTable, SkyPass, SkyTarget,
};
use common::{assert_close, gpu, mean_level};
use glam::Vec3;

/// A coarse table (16 x 16 directions, 12 suns, 4 altitudes) that builds in a second.
fn table() -> &'static SkylightTable {
    static TABLE: OnceLock<SkylightTable> = OnceLock::new();
    TABLE.get_or_init(|| {
        let settings = TableSettings {
            sky: SkySettings {
                directions: 16,
                shells: 24,
                scattering_directions: 32,
                ..SkySettings::default()
            },
            sun_steps: 12,
            altitude_steps: 4,
            ..TableSettings::default()
        };
        SkylightTable::precompute(&Atmosphere::earth(), &settings, &|_, _| {}).unwrap()
    })
}

#[test]
fn the_skylight_map_equals_the_cpu_sum_of_the_same_terms() {
    let Some(gpu) = gpu() else { return };
    let table = table();
    let sky = GpuSkyTable::new(&gpu, table).unwrap();
    for (sun_deg, altitude) in [(30.0f64, 0.0), (2.0, 5000.0), (-3.0, 12000.0)] {
        let cpu = table.map(sun_deg.to_radians(), altitude).unwrap();
        let (gpu_map, _) = sky.map(&gpu, sun_deg.to_radians(), altitude).unwrap();
        assert_eq!(cpu.len(), gpu_map.len());
        let brightest = cpu.iter().map(|v| v.max_element()).fold(0.0, f32::max);
        assert!(brightest > 0.0);
        for (d, (a, b)) in gpu_map.iter().zip(&cpu).enumerate() {
            // The same f32 sums in the same order; the GPU may fuse multiply-adds.
            assert!(
                (*a - *b).abs().max_element() <= 1e-5 * brightest,
                "sun {sun_deg} deg, altitude {altitude} m, direction {d}: {a} vs {b}"
            );
        }
    }
}

#[test]
fn perspective_and_fisheye_frames_match_the_cpu_picture() {
    let Some(gpu) = gpu() else { return };
    let table = table();
    let sky = GpuSkyTable::new(&gpu, table).unwrap();
    let mut pass = SkyPass::new(&gpu, SkyTarget::HEADLESS).unwrap();
    let sun = Sun::from_degrees(8.0, 120.0).unwrap();
    for camera in [
        Camera::yaw_pitch(Vec3::ZERO, 100.0, 10.0, Fov::Vertical(70.0), (96, 64)).unwrap(),
        Camera::dome(Vec3::ZERO, (96, 64)).unwrap(),
    ] {
        let name = format!("{:?}", camera.lens);
        let view = View {
            camera,
            sun_disc: true,
        };
        let altitude = 3000.0;
        let cpu = SkyPicture::from_table(table, sun, altitude)
            .unwrap()
            .render(&view);
        let out = sky
            .render(&gpu, &mut pass, sun, altitude, &view)
            .unwrap()
            .frame;
        assert!(mean_level(&out, 10.0) > 20.0, "{name}: the sky is dark");
        assert_close(&out, &cpu, 10.0, &name);
    }
}

#[test]
fn a_sun_outside_the_table_is_refused_before_any_gpu_work() {
    let Some(gpu) = gpu() else { return };
    let sky = GpuSkyTable::new(&gpu, table()).unwrap();
    let err = sky.map(&gpu, 80f64.to_radians(), 50_000.0).unwrap_err();
    assert!(
        err.to_string().contains("altitude") || err.to_string().contains("sun"),
        "{err}"
    );
}

/// The table's sky recorded into a caller's encoder and render pass: a target larger
/// than the view with the view in a viewport at (8, 4), a depth buffer cleared to
/// `depth`, exposure 0.5. Returns the view's pixels, and the colour of one pixel outside.
fn draw_embedded(
    gpu: &atmo_gpu::Gpu,
    reversed_z: bool,
    depth: f32,
    view: &View,
) -> (Vec<Vec3>, Vec3) {
    let sky = GpuSkyTable::new(gpu, table()).unwrap();
    let target = SkyTarget {
        format: wgpu::TextureFormat::Rgba32Float,
        depth: Some(DepthTarget {
            format: wgpu::TextureFormat::Depth32Float,
            reversed_z,
        }),
        samples: 1,
    };
    let mut pass = SkyPass::new(gpu, target).unwrap();
    pass.exposure = 0.5;
    pass.corner = [8, 4];
    let (w, h) = (view.camera.width + 16, view.camera.height + 8);
    let texture = |format, usage| gpu.texture_2d("the target", (w, h), format, usage);
    let attachment = wgpu::TextureUsages::RENDER_ATTACHMENT;
    let colour = texture(target.format, attachment | wgpu::TextureUsages::COPY_SRC);
    let depth_texture = texture(wgpu::TextureFormat::Depth32Float, attachment);
    let (colour_view, depth_view) = (
        colour.create_view(&Default::default()),
        depth_texture.create_view(&Default::default()),
    );
    let sun = Sun::from_degrees(8.0, 120.0).unwrap();
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    sky.prepare(gpu, &mut encoder, &mut pass, sun, 3000.0, view)
        .unwrap();
    {
        let mut render = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: None,
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &colour_view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color {
                        r: 0.25,
                        g: 0.0,
                        b: 0.0,
                        a: 1.0,
                    }),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &depth_view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(depth),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            ..Default::default()
        });
        let (cw, ch) = (view.camera.width as f32, view.camera.height as f32);
        render.set_viewport(8.0, 4.0, cw, ch, 0.0, 1.0);
        pass.draw(&mut render);
    }
    gpu.queue.submit([encoder.finish()]);
    let bytes = gpu.read_texture("embedded sky", &colour, w, h).unwrap();
    let texels: &[[f32; 4]] = bytemuck::cast_slice(&bytes);
    let at = |x: u32, y: u32| Vec3::from_slice(&texels[(y * w + x) as usize][..3]);
    let inside = (0..view.camera.height)
        .flat_map(|y| (0..view.camera.width).map(move |x| (x + 8, y + 4)))
        .map(|(x, y)| at(x, y))
        .collect();
    (inside, at(2, 1))
}

#[test]
fn the_sky_draws_into_a_callers_target_only_where_the_depth_is_at_the_far_plane() {
    let Some(gpu) = gpu() else { return };
    let camera = Camera::yaw_pitch(Vec3::ZERO, 100.0, 10.0, Fov::Vertical(70.0), (48, 32)).unwrap();
    let view = View {
        camera,
        sun_disc: true,
    };
    let sun = Sun::from_degrees(8.0, 120.0).unwrap();
    let cpu = SkyPicture::from_table(table(), sun, 3000.0)
        .unwrap()
        .render(&view);
    let cleared = Vec3::new(0.25, 0.0, 0.0);
    for reversed_z in [false, true] {
        let far = if reversed_z { 0.0 } else { 1.0 };
        let (sky, outside) = draw_embedded(&gpu, reversed_z, far, &view);
        // Outside the viewport the caller's clear colour stays.
        assert_eq!(outside, cleared, "reversed z {reversed_z}");
        let mut frame = atmo::image::Frame::new(48, 32);
        for (p, s) in frame.pixels.iter_mut().zip(&sky) {
            *p = *s * 2.0;
        }
        assert_close(
            &frame,
            &cpu,
            10.0,
            &format!("embedded, reversed z {reversed_z}"),
        );
        // Where the caller drew something nearer than the far plane, no sky.
        let (covered, _) = draw_embedded(&gpu, reversed_z, 0.5, &view);
        assert!(
            covered.iter().all(|&p| p == cleared),
            "reversed z {reversed_z}: sky drawn over geometry"
        );
    }
}

/// A model with coarse settings (a fraction of a second to build); `all` for every
/// order of both species, else orders 1 to `order` of the molecules.
fn model(atmosphere: &Atmosphere, order: u32, altitude: f64) -> SkyModel {
    let all = order == 0;
    let settings = SkySettings {
        directions: 24,
        shells: 24,
        scattering_directions: 32,
        sun_bins: 32,
        order: if all {
            Order::All
        } else {
            Order::Through(order)
        },
        multiple_mie: all,
        ..SkySettings::default()
    };
    SkyModel::new(atmosphere, &settings, altitude).unwrap()
}

#[test]
fn the_shell_method_maps_equal_the_cpu_maps() {
    let Some(gpu) = gpu() else { return };
    let earth = Atmosphere::earth();
    let paper = Atmosphere::preset("paper").unwrap();
    let mut bright = Atmosphere::earth();
    bright.ground_albedo = 0.3;
    // Order 0: all orders, aerosols too.
    for (atmosphere, order, altitude, sun_deg) in [
        (&earth, 2, 0.0, 30.0f64),
        (&earth, 2, 9000.0, -2.0),
        (&earth, 3, 2000.0, 4.0),
        (&bright, 0, 3000.0, 8.0),
        (&bright, 0, 0.0, -3.0),
        (&paper, 1, 500.0, 60.0),
    ] {
        let model = model(atmosphere, order, altitude);
        let colour = SpectrumToRgb::for_atmosphere(atmosphere);
        let sky = GpuSkyModel::new(&gpu, &model).unwrap();
        let sun = sun_deg.to_radians();
        let [sky_map, ground_map] = sky.maps(&gpu, sun).unwrap();
        for (what, gpu_map, cpu_map) in [
            ("sky", sky_map, model.skylight_map(sun).to_rgb(&colour)),
            ("ground", ground_map, model.ground_map(sun).to_rgb(&colour)),
        ] {
            assert_eq!(gpu_map.len(), cpu_map.len());
            let brightest = cpu_map
                .iter()
                .map(|v| v[0].max(v[1]).max(v[2]))
                .fold(0.0, f32::max);
            // From the ground itself the ground map is black (the rays end at once).
            assert!(
                brightest > 0.0 || (what, altitude) == ("ground", 0.0),
                "{what}: black"
            );
            for (d, (a, b)) in gpu_map.iter().zip(&cpu_map).enumerate() {
                // f32 where the CPU keeps some f64 (radii, distances): a few 1e-4 of the
                // brightest value at most.
                let b = glam::Vec3::from(*b);
                assert!(
                    (*a - b).abs().max_element() <= 3e-4 * brightest,
                    "{} order {order} at {altitude} m, sun {sun_deg} deg, {what} {d}: {a} vs {b}",
                    atmosphere.name
                );
            }
        }
    }
}

#[test]
fn the_shell_method_picture_matches_the_cpu_picture() {
    let Some(gpu) = gpu() else { return };
    let earth = Atmosphere::earth();
    let model = model(&earth, 2, 3000.0);
    let sky = GpuSkyModel::new(&gpu, &model).unwrap();
    let mut pass = SkyPass::new(&gpu, SkyTarget::HEADLESS).unwrap();
    let sun = Sun::from_degrees(6.0, 200.0).unwrap();
    for camera in [
        // Looking down past the horizon: the ground map, the horizon's edge, the sun.
        Camera::yaw_pitch(Vec3::ZERO, 200.0, -2.0, Fov::Vertical(60.0), (96, 64)).unwrap(),
        Camera::dome(Vec3::ZERO, (96, 64)).unwrap(),
    ] {
        let name = format!("{:?}", camera.lens);
        let view = View {
            camera,
            sun_disc: true,
        };
        let cpu = SkyPicture::new(&model, sun).render(&view);
        let out = sky.render(&gpu, &mut pass, sun, &view).unwrap().frame;
        assert!(mean_level(&out, 0.15) > 20.0, "{name}: dark");
        assert_close(&out, &cpu, 0.15, &format!("shells {name}"));
    }
}

#[test]
fn molecules_with_another_phase_in_the_higher_orders_are_refused_with_a_way_out() {
    let Some(gpu) = gpu() else { return };
    let mut atmosphere = Atmosphere::earth();
    atmosphere.rayleigh.phase = atmo::atmosphere::PhaseFunction::HenyeyGreenstein { g: 0.2 };
    let err = GpuSkyModel::new(&gpu, model(&atmosphere, 2, 0.0))
        .err()
        .unwrap()
        .to_string();
    assert!(
        err.contains("Rayleigh's") && err.contains("on the CPU"),
        "{err}"
    );
    // Single scattering needs no table: drawn.
    assert!(GpuSkyModel::new(&gpu, model(&atmosphere, 1, 0.0)).is_ok());
}

#[test]
fn the_aerial_froxels_equal_the_cpu_froxels() {
    let Some(gpu) = gpu() else { return };
    let mut bright = Atmosphere::earth();
    bright.ground_albedo = 0.3;
    // Every order of both species (order 0 here), and single scattering.
    for order in [0, 1] {
        let model = model(&bright, order, 1200.0);
        let slices = atmo::sky::aerial::quadratic_slices(12, 80_000.0);
        let rays = model.aerial_rays(256, &slices).unwrap();
        let sun = Sun::from_degrees(15.0, 120.0).unwrap();
        let camera =
            Camera::yaw_pitch(Vec3::ZERO, 90.0, -3.0, Fov::Vertical(50.0), (20, 14)).unwrap();
        let cpu = rays.froxels(&model, sun, &camera);
        let sky = GpuSkyModel::new(&gpu, &model).unwrap();
        let aerial = GpuAerial::new(&gpu, &sky, rays).unwrap();
        let out = aerial.froxels(&gpu, &sky, sun, &camera).unwrap();
        assert_eq!(out.inscatter.len(), cpu.inscatter.len());
        let brightest = cpu
            .inscatter
            .iter()
            .fold(0.0f32, |m, v| m.max(v.max_element()));
        assert!(brightest > 0.0);
        for (k, (a, b)) in out.inscatter.iter().zip(&cpu.inscatter).enumerate() {
            // f32 where the CPU keeps radii and distances in f64.
            assert!(
                (*a - *b).abs().max_element() <= 1e-3 * brightest,
                "order {order}, {k}: {a} vs {b}"
            );
        }
        for (a, b) in out.transmittance.iter().zip(&cpu.transmittance) {
            assert!((*a - *b).abs().max_element() <= 1e-4, "{a} vs {b}");
        }
        // Textures of another size than the camera's grid are refused, not written.
        let small = AerialTextures::new(&gpu, (camera.width, camera.height, 3)).unwrap();
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let refused = aerial.prepare(&gpu, &mut encoder, &sky, sun, &camera, &small);
        assert!(refused.unwrap_err().to_string().contains("aerial textures"));
    }
}
