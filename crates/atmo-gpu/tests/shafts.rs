//! Light shafts on the GPU against the CPU plane method, on the example scenes at a
//! small size: every object kind, a gobo, measured profiles, a haze box, supersampling,
//! both GPU methods.

mod common;

use std::path::Path;

use atmo::shafts::{SamplePlanes, Scene};
use atmo_gpu::display::{cleared_pass, picture_texture};
use atmo_gpu::shafts::{GpuShafts, ShaftsMethod, ShaftsPass};
use common::{assert_close, gpu, mean_level};

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
