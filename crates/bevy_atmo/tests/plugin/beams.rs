//! The plugin's beams held to `atmo shafts`' CPU picture (the sample planes, every
//! pixel): the paper's Fig. 6 light and haze, in an empty scene, and with a floor and a
//! sphere (black, so that the picture is the haze's light alone) shadowing the beam,
//! with MSAA 4x.

use crate::common::{app, settled, EXPOSURE, HEIGHT, WIDTH};
use atmo::atmosphere::PhaseFunction;
use atmo::geometry::{Aabb, Shape};
use atmo::image::{Display, Frame, ToneMap};
use atmo::shafts::haze::Haze;
use atmo::shafts::objects::{Object, Objects};
use atmo::shafts::scene::IntensityUnit;
use atmo::shafts::spotlight::{light_frame, Falloff, Profile, Spotlight};
use atmo::shafts::{PlaneSettings, SamplePlanes, Scene};
use atmo::view::{Camera as AtmoCamera, Fov};
use bevy::camera::ClearColorConfig;
use bevy::prelude::*;
use bevy_atmo::prelude::*;

/// The paper's Fig. 6: the camera, the lamp and where it aims, m.
const EYE: Vec3 = Vec3::new(0.0, 1.4, 6.5);
const LOOK_AT: Vec3 = Vec3::new(0.0, 1.1, 0.0);
const LAMP: Vec3 = Vec3::new(-4.2, 3.0, -1.2);
const AIM: Vec3 = Vec3::new(0.6, 0.0, 0.2);
/// On its axis, cd; its beam and field, half-angles in degrees.
const CANDELA: f32 = 1500.0;
const BEAM_HALF_DEG: f32 = 12.0;
const FIELD_HALF_DEG: f32 = 17.0;
/// The sphere's centre and radius, m.
const SPHERE: Vec3 = Vec3::new(-1.5, 1.6, -0.6);
const RADIUS: f32 = 0.5;

/// Fig. 6's display.
const DISPLAY: Display = Display {
    exposure: 0.6,
    tone: ToneMap::Exponential,
};

fn haze() -> AtmoHaze {
    AtmoHaze {
        bounds: Some((Vec3::new(-8.0, 0.0, -8.0), Vec3::new(8.0, 6.0, 8.0))),
        ..AtmoHaze::default()
    }
}

/// Fig. 6's lamp as atmo's spotlight, shaped by `beam`'s profile and gobo where it has
/// them (the plugin's reading of the same `SpotLight` and `AtmoBeam`).
fn lamp(beam: &AtmoBeam) -> Spotlight {
    let frame = light_frame((AIM - LAMP).normalize(), Vec3::Y).unwrap();
    let (intensity, field_half, profile) = match &beam.profile {
        Some(measured) => (
            Vec3::splat(measured.peak()),
            measured.reach().min(85.0).to_radians(),
            Profile::Measured(measured.clone()),
        ),
        None => (
            Vec3::splat(CANDELA),
            FIELD_HALF_DEG.to_radians(),
            Profile::Beam {
                beam_half: BEAM_HALF_DEG.to_radians(),
                falloff: Falloff::Smooth,
            },
        ),
    };
    Spotlight::new(
        LAMP,
        frame,
        intensity,
        field_half,
        profile,
        beam.gobo.clone(),
    )
}

/// atmo's picture of `light` in the haze, with `objects` (black) in it.
fn reference(light: Spotlight, objects: Vec<Shape>) -> Frame {
    reference_of(light, objects, (WIDTH, HEIGHT))
}

/// [`reference`] of `size` pixels.
fn reference_of(light: Spotlight, objects: Vec<Shape>, size: (u32, u32)) -> Frame {
    let h = haze();
    let (min, max) = h.bounds.unwrap();
    let scene = Scene {
        // The plugin's far plane: the haze box's farthest corner.
        camera: AtmoCamera::look_at(EYE, LOOK_AT, Vec3::Y, Fov::Vertical(45.0), size)
            .unwrap()
            .with_far(Vec3::new(-8.0, 6.0, -8.0).distance(EYE))
            .unwrap(),
        haze: Haze {
            extinction: h.extinction,
            albedo: h.albedo,
            phase: PhaseFunction::PaperHaze { exponent: 16.0 },
            bounds: Some(Aabb { min, max }),
        },
        spotlights: vec![light],
        objects: Objects {
            list: objects
                .into_iter()
                .map(|shape| Object {
                    shape,
                    albedo: Vec3::ZERO,
                    casts_shadow: true,
                })
                .collect(),
        },
        planes: PlaneSettings {
            adaptive: false,
            ..PlaneSettings::default()
        },
        display: DISPLAY,
        unit: IntensityUnit::Candela,
        files: Vec::new(),
        files_bytes: 0,
        show: Default::default(),
    };
    SamplePlanes::new(&scene).render()
}

/// The plugin's picture of the same light with `beam` and haze (black behind), with
/// `msaa` and what `furnish` adds, as radiance.
fn drawn(beam: AtmoBeam, msaa: Msaa, furnish: impl FnOnce(&mut World)) -> Option<Frame> {
    let mut app = app((
        haze(),
        msaa,
        Camera {
            clear_color: ClearColorConfig::Custom(Color::BLACK),
            ..default()
        },
        Transform::from_translation(EYE).looking_at(LOOK_AT, Vec3::Y),
    ))?;
    let world = app.world_mut();
    world.spawn((
        beam,
        SpotLight {
            intensity: CANDELA * 4.0 * std::f32::consts::PI,
            inner_angle: BEAM_HALF_DEG.to_radians(),
            outer_angle: FIELD_HALF_DEG.to_radians(),
            shadow_maps_enabled: false,
            ..default()
        },
        Transform::from_translation(LAMP).looking_at(AIM, Vec3::Y),
    ));
    furnish(world);
    let shot = settled(&mut app);
    let mut frame = Frame::new(WIDTH, HEIGHT);
    for (p, s) in frame.pixels.iter_mut().zip(&shot) {
        *p = Vec3::new(s[0], s[1], s[2]) / EXPOSURE.exposure();
    }
    Some(frame)
}

/// Asserts `got` within 1 level RMS of `want` (the bound), and not dark.
fn check(got: &Frame, want: &Frame, what: &str) {
    if let Ok(dir) = std::env::var("ATMO_TEST_PICTURES") {
        let dir = std::path::Path::new(&dir);
        let name = what.replace(' ', "-");
        got.write(
            &dir.join(format!("bevy-{name}.png")),
            DISPLAY.exposure,
            DISPLAY.tone,
        )
        .unwrap();
        want.write(
            &dir.join(format!("atmo-{name}.png")),
            DISPLAY.exposure,
            DISPLAY.tone,
        )
        .unwrap();
    }
    let e = got.level_errors(want, DISPLAY).unwrap();
    eprintln!(
        "{what}: plugin vs atmo shafts RMS {:.3}, max {:.3} levels",
        e.rms, e.max
    );
    let brightest = want.pixels.iter().map(|p| p.y).fold(0.0, f32::max);
    assert!(
        brightest * DISPLAY.exposure > 0.5,
        "{what}: the beam is dark"
    );
    assert!(e.rms <= 1.0, "{what}: RMS {:.3} levels (bound 1)", e.rms);
}

#[test]
fn a_beam_in_an_empty_scene_is_atmo_shafts() {
    let Some(frame) = drawn(AtmoBeam::default(), Msaa::Off, |_| {}) else {
        return;
    };
    check(
        &frame,
        &reference(lamp(&AtmoBeam::default()), Vec::new()),
        "empty scene",
    );
}

/// `small` shown bilinearly over `width` x `height` pixels, as `ShaftsPass` shows a
/// picture of fewer pixels.
fn shown(small: &Frame, width: u32, height: u32) -> Frame {
    let mut big = Frame::new(width, height);
    let (sw, sh) = (small.width as i64, small.height as i64);
    let texel =
        |x: i64, y: i64| small.pixels[(y.clamp(0, sh - 1) * sw + x.clamp(0, sw - 1)) as usize];
    for (i, p) in big.pixels.iter_mut().enumerate() {
        let (x, y) = ((i as u32 % width) as f32, (i as u32 / width) as f32);
        let at = (
            (x + 0.5) * sw as f32 / width as f32 - 0.5,
            (y + 0.5) * sh as f32 / height as f32 - 0.5,
        );
        let (bx, by) = (at.0.floor(), at.1.floor());
        let (fx, fy) = (at.0 - bx, at.1 - by);
        let (bx, by) = (bx as i64, by as i64);
        let top = texel(bx, by).lerp(texel(bx + 1, by), fx);
        let bottom = texel(bx, by + 1).lerp(texel(bx + 1, by + 1), fx);
        *p = top.lerp(bottom, fy);
    }
    big
}

#[test]
fn a_beam_drawn_at_half_resolution_is_the_half_picture_shown_larger() {
    // A quarter of the pixels, shown bilinearly: atmo's picture of half the size, shown
    // the same way. Against the whole picture it blurs what is sharp (the lamp, the
    // beam's cut by the haze box's floor): said, not bounded.
    let Some(frame) = drawn(AtmoBeam::default(), Msaa::Off, |world| {
        let mut hazes = world.query::<&mut AtmoHaze>();
        for mut haze in hazes.iter_mut(world) {
            haze.resolution_scale = 0.5;
        }
    }) else {
        return;
    };
    let half = reference_of(
        lamp(&AtmoBeam::default()),
        Vec::new(),
        (WIDTH / 2, HEIGHT / 2),
    );
    check(&frame, &shown(&half, WIDTH, HEIGHT), "half resolution");
    let whole = reference(lamp(&AtmoBeam::default()), Vec::new());
    let e = frame.level_errors(&whole, DISPLAY).unwrap();
    eprintln!(
        "half resolution against every pixel: RMS {:.3}, max {:.3} levels",
        e.rms, e.max
    );
}

#[test]
fn a_measured_profile_and_a_gobo_shape_the_beam_as_in_atmo_shafts() {
    // The repository's IES spot and its gobo of spokes, from their files.
    let files = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
    let beam = AtmoBeam::default()
        .with_photometry(&files.join("photometry/spot.ies"))
        .unwrap()
        .with_gobo(&files.join("gobos/spokes.png"))
        .unwrap();
    let want = reference(lamp(&beam), Vec::new());
    let Some(frame) = drawn(beam, Msaa::Off, |_| {}) else {
        return;
    };
    check(&frame, &want, "measured with a gobo");
    // The gobo is in the picture: the plain beam of the same file differs.
    let plain = AtmoBeam::default()
        .with_photometry(&files.join("photometry/spot.ies"))
        .unwrap();
    let apart = reference(lamp(&plain), Vec::new())
        .level_errors(&want, DISPLAY)
        .unwrap();
    assert!(
        apart.rms > 2.0,
        "the gobo changes {:.2} levels RMS",
        apart.rms
    );
}

#[test]
fn a_floor_and_a_sphere_end_and_shadow_the_beam_with_msaa_4x() {
    let black = StandardMaterial {
        base_color: Color::BLACK,
        unlit: true,
        ..default()
    };
    let Some(frame) = drawn(AtmoBeam::default(), Msaa::Sample4, |world| {
        let mut meshes = world.resource_mut::<Assets<Mesh>>();
        let floor = meshes.add(Plane3d::default().mesh().size(16.0, 16.0));
        let sphere = meshes.add(Sphere::new(RADIUS).mesh().ico(5).unwrap());
        let material = world.resource_mut::<Assets<StandardMaterial>>().add(black);
        world.spawn((Mesh3d(floor), MeshMaterial3d(material.clone())));
        world.spawn((
            Mesh3d(sphere),
            MeshMaterial3d(material),
            Transform::from_translation(SPHERE),
        ));
    }) else {
        return;
    };
    let floor = Shape::Plane {
        point: Vec3::ZERO,
        normal: Vec3::Y,
    };
    let sphere = Shape::Sphere {
        center: SPHERE,
        radius: RADIUS,
    };
    let light = || lamp(&AtmoBeam::default());
    let want = reference(light(), vec![floor.clone(), sphere]);
    check(&frame, &want, "floor and sphere");
    // The sphere's shadow is in the picture: without it the beam is brighter.
    let unshadowed = reference(light(), vec![floor]);
    let sum = |f: &Frame| f.pixels.iter().map(|p| p.y).sum::<f32>();
    assert!(
        sum(&unshadowed) > 1.02 * sum(&want),
        "the sphere casts no shadow: {} vs {}",
        sum(&unshadowed),
        sum(&want)
    );
}
