//! The plane method against the ray marcher, and its parts against their definitions.

use super::*;
use crate::geometry::{Ray, Shape};

/// The example scenes: one beam with a sphere's shadow, five lights over a mesh, a
/// box and a gobo, and a measured (asymmetric) profile.
fn scenes() -> Vec<Scene> {
    let folder = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
    ["spotlight-sphere.toml", "stage.toml", "photometric.toml"]
        .iter()
        .map(|f| Scene::from_file(&folder.join(f)).unwrap())
        .collect()
}

/// Around the lamp's image in Fig. 6, where rays pass the lamp within a few slabs'
/// lengths, the planes agree with the converged ray marcher: one `g` at each plane
/// left the lamp's own pixels dark (0 against 243 cd/m^2) and its neighbours at a
/// fifth to a third of the light, 28 levels RMS within 5 pixels of it.
#[test]
fn the_light_where_rays_pass_the_lamp_matches_the_reference() {
    use crate::reference::shafts::RayMarcher;
    let scene = scenes().swap_remove(0);
    let method = SamplePlanes::new(&scene);
    let camera = &scene.camera;
    let (lx, ly) = camera.pixel_of(scene.spotlights[0].position).unwrap();
    let (mut diff, mut total, mut worst, mut near) = (0.0f64, 0.0f64, 0.0f32, 0);
    for y in ly as u32 - 15..=ly as u32 + 15 {
        for x in lx as u32 - 15..=lx as u32 + 15 {
            let ray = camera.ray(x as f32 + 0.5, y as f32 + 0.5);
            let ours = method.radiance(ray, interleaved_offset(x, y)).y;
            let reference = RayMarcher::CONVERGED.radiance(&scene, ray).y;
            diff += (ours - reference).abs() as f64;
            total += reference as f64;
            if reference > 1.0 {
                worst = worst.max((ours / reference - 1.0).abs());
                near += 1;
            }
        }
    }
    let mean = diff / total;
    eprintln!("{near} lit pixels: mean error {mean:.4}, worst {worst:.4}");
    assert!(near > 100, "{near}");
    assert!(mean < 0.01 && worst < 0.1, "mean {mean}, worst {worst}");
}

/// A camera ray meets an object, or a light's lit volume, only through a point of
/// the view plane inside its box, so leaving the others out changes nothing; and
/// bounded objects in front of the camera get boxes smaller than the picture (else
/// the test proves nothing).
#[test]
fn camera_rays_meet_objects_and_lit_volumes_only_inside_their_view_boxes() {
    let mut bounded = 0;
    for scene in scenes() {
        let camera = &scene.camera;
        let method = SamplePlanes::new(&scene);
        let boxes = method
            .objects
            .iter()
            .chain(method.lights.iter().map(|l| &l.view));
        let volumes: Vec<Shape> = method.lights.iter().map(|l| Shape::Box(l.bounds)).collect();
        let shapes = scene.objects.list.iter().map(|o| &o.shape).chain(&volumes);
        let (tw, th) = camera.pinhole("a test").unwrap();
        bounded += boxes
            .clone()
            .filter(|b| (b.x[1] - b.x[0]) * (b.y[1] - b.y[0]) < 2.0 * tw * th)
            .count();
        for (y, x) in (0..camera.height).flat_map(|y| (0..camera.width).map(move |x| (y, x))) {
            let ray = camera.ray(x as f32 + 0.5, y as f32 + 0.5);
            let at = view_point(camera, ray);
            let ray = Ray {
                origin: camera.position,
                dir: ray.normalize(),
            };
            for (shape, b) in shapes.clone().zip(boxes.clone()) {
                if shape.intersect(&ray, f32::INFINITY).is_some()
                    || matches!(shape, Shape::Box(a) if a.contains(camera.position))
                {
                    assert!(b.holds(at), "pixel ({x}, {y}) meets {:?}", shape.bounds());
                }
            }
        }
    }
    // Fig. 6's sphere; the stage's rectangle, box, mesh and sphere; lit volumes.
    assert!(bounded >= 6, "{bounded} boxes smaller than the picture");
}

/// The lit volume's extent found from the blocks' boxes is the walk over every
/// texel's ray end, to the bit: from cameras all round the scenes, with reaches
/// that leave every surface and that cut some off (blocks walked whole).
#[test]
fn the_extent_from_block_boxes_is_the_walk_over_every_ray_end() {
    let mut cut = 0;
    for scene in scenes() {
        for light in scene.lights() {
            let size = 128;
            let map = ShadowMap::new(light, &scene.objects, size);
            let blocks: Vec<usize> = map.end_boxes(light, 1e3).map(|(b, _)| b).collect();
            for k in 0..8 {
                let angle = k as f32 * std::f32::consts::FRAC_PI_4;
                let position = Vec3::new(9.0 * angle.cos(), 1.0 + k as f32, 9.0 * angle.sin());
                let camera = Camera::look_at(
                    position,
                    Vec3::new(0.0, 1.0, 0.0),
                    Vec3::Y,
                    crate::view::Fov::Vertical(50.0),
                    (64, 48),
                )
                .unwrap();
                for reach in [1e3, 6.0, 2.5] {
                    cut += map.end_boxes(light, reach).any(|(_, b)| b.is_none()) as usize;
                    let lamp = Extent::lamp(light.position, &camera);
                    let walk = blocks.iter().fold(lamp, |e, &b| {
                        map.block_ends(light, reach, b)
                            .fold(e, |e, p| e.grow(p, &camera, light.position))
                    });
                    let found = Extent::of(&map, light, &camera, reach);
                    assert_eq!(
                        (found.measures(), found.bounds),
                        (walk.measures(), walk.bounds),
                        "camera at {position}, reach {reach}"
                    );
                }
            }
        }
    }
    assert!(cut > 10, "{cut} cases cut a surface off");
}

#[test]
fn lookups_left_out_are_those_that_would_give_the_values_assumed() {
    let mut seen = [0usize; 4];
    for scene in scenes() {
        let method = SamplePlanes::new(&scene);
        let camera = &scene.camera;
        let m = scene.planes.sub_planes as usize;
        for y in (0..camera.height).step_by(11) {
            for x0 in (0..camera.width).step_by(LANES * 3) {
                let rays: Vec<Vec3> = (x0..(x0 + LANES as u32).min(camera.width))
                    .map(|x| camera.ray(x as f32 + 0.5, y as f32 + 0.5))
                    .collect();
                let offsets: Vec<f32> = (0..rays.len())
                    .map(|l| interleaved_offset(x0 + l as u32, y))
                    .collect();
                let mut ends = [0.0; LANES];
                for (end, ray) in ends.iter_mut().zip(&rays) {
                    *end = camera.far * ray.length();
                }
                for (light, planes) in scene.lights().zip(&method.lights) {
                    let lanes = Lanes::new(&method, light, planes, &rays, &offsets, &ends);
                    for (_, slice) in lanes.slices(m) {
                        let lookups =
                            Lookups::of_slice(light, &planes.shadow, &lanes, slice.clone());
                        seen[lookups as usize] += 1;
                        for (l, k) in
                            (0..lanes.count).flat_map(|l| slice.clone().map(move |k| (l, k)))
                        {
                            if k < lanes.k_first[l] as usize || k >= lanes.k_last[l] as usize {
                                continue;
                            }
                            let [u, v, z] = lanes.project(l, k);
                            let lit = planes.shadow.lit_at(u, v, z);
                            let profile = light.intensity_map.get(u, v);
                            let fine = match lookups {
                                Lookups::None => !lit,
                                Lookups::Core => lit && profile == 1.0,
                                Lookups::Profile => lit,
                                Lookups::Both => true,
                            };
                            assert!(fine, "{lookups:?}: lit {lit}, profile {profile}");
                        }
                    }
                }
            }
        }
    }
    // Every kind of slice came up, so each assertion above was put to the test.
    assert!(seen.iter().all(|&n| n > 20), "{seen:?}");
}
