//! Light shafts on the GPU against the CPU plane method, on the example scenes at a
//! small size: every object kind, a gobo, measured profiles, a haze box, supersampling,
//! both GPU methods.

mod common;

use std::path::Path;

use atmo::shafts::{SamplePlanes, Scene};
use atmo_gpu::display::{cleared_pass, picture_texture};
use atmo_gpu::shafts::{GpuShafts, ShaftsMethod, ShaftsPass, ShaftsPipelines};
use common::{assert_close, drawn_over, gpu, mean_level};

/// The example scene `name`, drawn at 1/5 of its size.
fn scene(name: &str, supersampling: u32) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes")
        .join(name);
    let mut scene = Scene::from_file(&path).unwrap();
    scene.camera.width /= 5;
    scene.camera.height /= 5;
    scene.camera.supersampling = supersampling;
    // The GPU draws every pixel; the CPU does the same here (the paper's method).
    scene.planes.adaptive = false;
    scene
}

fn check(scene: &Scene, what: &str) {
    let Some(gpu) = gpu() else { return };
    let cpu = SamplePlanes::new(scene).render();
    let shafts = GpuShafts::new(&gpu, scene).unwrap();
    let exposure = scene.display.exposure;
    for method in [ShaftsMethod::Planes, ShaftsMethod::Compute] {
        let out = shafts.render(&gpu, method).unwrap().frame;
        assert!(
            mean_level(&out, exposure) > 10.0,
            "{what} {method:?}: the picture is dark"
        );
        assert!(out.pixels.iter().all(|p| p.min_element() >= 0.0));
        assert_close(&out, &cpu, exposure, &format!("{what} {method:?}"));
    }
}

#[test]
fn the_stage_matches_the_cpu_planes() {
    // Plane, rectangle, box, mesh and sphere; a gobo; a haze box; five lights.
    check(&scene("stage.toml", 1), "stage");
}

#[test]
fn measured_profiles_match_the_cpu_planes() {
    // IES and EULUMDAT lights; the oval wash's light map has rows over C.
    check(&scene("photometric.toml", 1), "photometric");
}

#[test]
fn the_sphere_in_a_beam_matches_with_supersampling() {
    check(&scene("spotlight-sphere.toml", 2), "spotlight-sphere 2x2");
}

#[test]
fn a_camera_without_a_far_plane_matches_the_cpu_planes() {
    // An infinite far plane (as `Camera::look_at` makes it): both devices end the rays
    // that meet nothing where the haze sends no more light (`Scene::far_m`), in its box
    // and in haze filling all space.
    let mut scene = scene("spotlight-sphere.toml", 1);
    scene.camera.far = f32::INFINITY;
    check(&scene, "no far plane, haze everywhere");
    scene.haze.bounds = Some(atmo::geometry::Aabb {
        min: glam::Vec3::new(-8.0, 0.0, -3.0),
        max: glam::Vec3::new(8.0, 6.0, 3.0),
    });
    check(&scene, "no far plane, a haze box");
}

#[test]
fn an_image_wider_than_the_device_allows_is_refused_before_allocation() {
    let Some(gpu) = gpu() else { return };
    let mut scene = scene("spotlight-sphere.toml", 1);
    scene.camera.width = gpu.limits().max_texture_dimension_2d + 1;
    scene.camera.height = 2;
    let err = GpuShafts::new(&gpu, &scene).err().unwrap().to_string();
    assert!(
        err.contains("max_texture_dimension_2d") && err.contains("camera.width"),
        "{err}"
    );
}

#[test]
fn a_show_played_on_one_set_of_passes_matches_the_cpu_frame_by_frame() {
    // The animation's path: the passes compiled once, each frame's lights uploaded.
    let Some(gpu) = gpu() else { return };
    let mut show = scene("show.toml", 1);
    let mut pipelines = None;
    for time in [0.0, 4.5] {
        show.at_time(time);
        let shafts = match pipelines.take() {
            None => GpuShafts::new(&gpu, &show).unwrap(),
            Some(p) => GpuShafts::with_pipelines(&gpu, &show, p).unwrap(),
        };
        let out = shafts.render(&gpu, ShaftsMethod::Planes).unwrap().frame;
        let cpu = SamplePlanes::new(&show).render();
        assert!(
            mean_level(&out, show.display.exposure) > 10.0,
            "{time} s: dark"
        );
        assert_close(
            &out,
            &cpu,
            show.display.exposure,
            &format!("show at {time} s"),
        );
        pipelines = Some(shafts.pipelines());
    }
}

#[test]
fn the_shafts_draw_into_a_callers_target_as_they_read_back() {
    // Recorded into the caller's encoder and drawn into its own target (larger than
    // the picture, the picture at (8, 4), exposure 0.5) with no read-back of ours.
    let Some(gpu) = gpu() else { return };
    let scene = scene("spotlight-sphere.toml", 1);
    let shafts = GpuShafts::new(&gpu, &scene).unwrap();
    let read_back = shafts.render(&gpu, ShaftsMethod::Planes).unwrap().frame;
    let (w, h) = (scene.camera.width + 16, scene.camera.height + 8);
    let target = picture_texture(&gpu, w, h).unwrap();
    let mut pass = ShaftsPass::new(&gpu, target.format()).unwrap();
    pass.exposure = 0.5;
    pass.corner = [8, 4];
    let view = target.create_view(&Default::default());
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    shafts
        .prepare(&gpu, &mut encoder, &mut pass, ShaftsMethod::Planes)
        .unwrap();
    {
        let cleared = wgpu::Color {
            r: 0.25,
            g: 0.0,
            b: 0.0,
            a: 1.0,
        };
        let mut render = cleared_pass(&mut encoder, &view, "the caller's pass", cleared);
        pass.draw(&mut render);
    }
    gpu.queue.submit([encoder.finish()]);
    let bytes = gpu
        .read_texture("the caller's target", &target, w, h)
        .unwrap();
    let texels: &[[f32; 4]] = bytemuck::cast_slice(&bytes);
    let at = |x: u32, y: u32| texels[(y * w + x) as usize];
    for (i, p) in read_back.pixels.iter().enumerate() {
        let (x, y) = (i as u32 % scene.camera.width, i as u32 / scene.camera.width);
        let t = at(x + 8, y + 4);
        assert_eq!(
            [t[0], t[1], t[2], t[3]],
            [0.5 * p.x, 0.5 * p.y, 0.5 * p.z, 1.0],
            "({x}, {y})"
        );
    }
    assert!(
        mean_level(&read_back, scene.display.exposure) > 10.0,
        "dark"
    );
    assert_eq!(
        at(2, 1),
        [0.25, 0.0, 0.0, 1.0],
        "outside the picture: the caller's"
    );
    assert_eq!(at(w - 1, h - 1), [0.25, 0.0, 0.0, 1.0]);
}

/// `scene` drawn by [`GpuShafts::haze_over`] and [`ShaftsPass::over`] over a target
/// holding `behind` everywhere, read back as RGBA.
fn haze_over(gpu: &atmo_gpu::Gpu, scene: &Scene, behind: f64) -> Vec<[f32; 4]> {
    let size = (scene.camera.width, scene.camera.height);
    let shafts = GpuShafts::haze_over(gpu, scene, ShaftsPipelines::new(gpu).unwrap()).unwrap();
    drawn_over(gpu, size, behind, |encoder, format| {
        let mut pass = ShaftsPass::over(gpu, format, 1).unwrap();
        shafts
            .prepare(gpu, encoder, &mut pass, ShaftsMethod::Planes)
            .unwrap();
        pass
    })
}

#[test]
fn the_haze_alone_over_a_scene_is_its_light_and_its_transmittance() {
    // Over black: the haze's light alone, the CPU's picture of the scene with every
    // surface black (still casting its shadows and ending the rays). Over white, less
    // that light: the haze's transmittance from the eye to each pixel's surface.
    let Some(gpu) = gpu() else { return };
    let scene = scene("spotlight-sphere.toml", 1);
    let mut dark = scene.clone();
    for object in &mut dark.objects.list {
        object.albedo = glam::Vec3::ZERO;
    }
    let want = SamplePlanes::new(&dark).render();
    let over_black = haze_over(&gpu, &scene, 0.0);
    let mut light = atmo::image::Frame::new(scene.camera.width, scene.camera.height);
    for (p, t) in light.pixels.iter_mut().zip(&over_black) {
        *p = glam::Vec3::new(t[0], t[1], t[2]);
    }
    assert!(mean_level(&light, scene.display.exposure) > 10.0, "dark");
    assert_close(&light, &want, scene.display.exposure, "the haze alone");
    let over_white = haze_over(&gpu, &scene, 1.0);
    let camera = &scene.camera;
    let mut worst = 0.0f32;
    for (i, (white, black)) in over_white.iter().zip(&over_black).enumerate() {
        let (x, y) = (i as u32 % camera.width, i as u32 / camera.width);
        let dir = camera.ray(x as f32 + 0.5, y as f32 + 0.5).normalize();
        let ray = atmo::geometry::Ray {
            origin: camera.position,
            dir,
        };
        let far = camera.far * camera.ray(x as f32 + 0.5, y as f32 + 0.5).length();
        let end = scene.objects.hit(&ray, far).map_or(far, |hit| hit.t);
        let want = (-scene.haze.extinction
            * scene
                .haze
                .length_inside(camera.position, camera.position + end * dir))
        .exp();
        worst = worst.max((white[1] - black[1] - want).abs());
        assert_eq!(white[3], 1.0, "the target's alpha is kept");
    }
    eprintln!("the haze's transmittance: worst difference {worst:.2e}");
    assert!(worst < 1e-3, "transmittance off by {worst}");
}
