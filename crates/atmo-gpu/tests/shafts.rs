//! Light shafts on the GPU against the CPU plane method, on the example scenes at a
//! small size: every object kind, a gobo, measured profiles, a haze box, supersampling,
//! both GPU methods.

mod common;

use std::path::Path;

use atmo::shafts::{SamplePlanes, Scene};
use atmo_gpu::shafts::{GpuShafts, ShaftsMethod};
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
