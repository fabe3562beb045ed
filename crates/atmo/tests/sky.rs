//! The shell method held to the reference integrator, and the physical invariants of
//! the sky it computes.

use atmo::atmosphere::geometry::horizon_dip;
use atmo::reference::sky::{ReferenceSettings, ReferenceSky};
use atmo::sky::{Order, SkyModel, SkySettings, SkylightMap};
use atmo::Atmosphere;
use rayon::prelude::*;

/// Relative error per channel; where the sky is darker than 1 % of the map's brightest
/// radiance (any channel), relative to that 1 %: the error that can show on a display.
/// It matters only in the earth's shadow at sunset, where the sky is ~1e-6 of its
/// brightest.
fn worst_error(
    map: &SkylightMap,
    points: &[(usize, usize)],
    want: &[Vec<f64>],
) -> (f64, (usize, usize)) {
    let brightest = map.radiance.iter().fold(0.0f64, |m, &v| m.max(v as f64));
    let mut worst = (0.0f64, (0, 0));
    for (&(i, j), w) in points.iter().zip(want) {
        for (got, want) in map.at(i, j).iter().zip(w) {
            let floor = 0.01 * brightest;
            let err = (*got as f64 - want).abs() / want.max(floor);
            if err > worst.0 {
                worst = (err, (i, j));
            }
        }
    }
    worst
}

fn grid_points(step: usize) -> Vec<(usize, usize)> {
    let rows: Vec<usize> = (0..64).step_by(step).chain([1, 2, 63]).collect();
    let cols: Vec<usize> = (0..64).step_by(step).chain([63]).collect();
    rows.iter()
        .flat_map(|&j| cols.iter().map(move |&i| (i, j)))
        .collect()
}

/// The worst error (as `worst_error`) of `model`'s skylight map against the converged
/// reference at `points`, for the sun at `sun_deg`, over the model's orders.
fn error_against_reference(
    model: &SkyModel,
    sun_deg: f64,
    points: &[(usize, usize)],
) -> (f64, (usize, usize)) {
    let e = sun_deg.to_radians();
    let map = model.skylight_map(e);
    let reference = ReferenceSky::new(
        model.atmosphere(),
        model.altitude_m(),
        e,
        ReferenceSettings::CONVERGED,
    );
    let last = model.orders();
    // The brute-force second order has no ground: compare it over a black one.
    assert!(last < 2 || model.atmosphere().ground_albedo == 0.0);
    let want: Vec<Vec<f64>> = points
        .par_iter()
        .map(|&(i, j)| reference.radiance(map.grid.azimuth(i), map.grid.elevation(j), 1, last))
        .collect();
    worst_error(&map, points, &want)
}

#[test]
fn single_scattering_within_one_percent_of_the_reference() {
    let a = Atmosphere::earth();
    let settings = SkySettings {
        order: Order::Through(1),
        ..SkySettings::default()
    };
    let points = grid_points(9);
    for altitude in [0.0, 4000.0, 13000.0] {
        let model = SkyModel::new(&a, &settings, altitude).unwrap();
        for sun in [0.0f64, 3.0, 10.0, 30.0, 60.0, 90.0] {
            let (err, at) = error_against_reference(&model, sun, &points);
            // One known exception: with the sun's centre exactly on the horizon seen from
            // the ground, the earth's shadow boundary passes through the viewpoint and
            // runs along the anti-solar horizon ray (measured 1.04 %, at 1e-4 of the
            // brightest sky); docs/sky.md.
            let bound = if sun == 0.0 && altitude == 0.0 && at == (63, 0) {
                0.015
            } else {
                0.01
            };
            assert!(
                err < bound,
                "altitude {altitude} m, sun {sun} deg: worst error {err:.4} at {at:?}"
            );
        }
    }
}

#[test]
fn second_order_within_two_percent_of_the_reference() {
    let mut a = Atmosphere::earth();
    a.ground_albedo = 0.0;
    let points = [(0, 1), (0, 32), (31, 10), (63, 1), (63, 40), (31, 63)];
    for altitude in [0.0, 13000.0] {
        let model = SkyModel::new(&a, &SkySettings::paper(), altitude).unwrap();
        for sun in [5.0f64, 45.0] {
            let (err, at) = error_against_reference(&model, sun, &points);
            assert!(
                err < 0.02,
                "altitude {altitude} m, sun {sun} deg: worst error {err:.4} at {at:?}"
            );
        }
    }
}

#[test]
fn doubling_the_reference_changes_little() {
    let a = Atmosphere::earth();
    let (altitude, sun) = (1000.0, 20f64.to_radians());
    let coarse = ReferenceSky::new(&a, altitude, sun, ReferenceSettings::CONVERGED);
    let mut fine_settings = ReferenceSettings::CONVERGED.doubled();
    // The nested sphere integral is checked at double resolution in `atmo bench sky`;
    // here the single-scattering counts, which dominate the sky.
    fine_settings.sphere_directions = ReferenceSettings::CONVERGED.sphere_directions;
    fine_settings.nested_segments = ReferenceSettings::CONVERGED.nested_segments;
    let fine = ReferenceSky::new(&a, altitude, sun, fine_settings);
    for (az, el) in [(0.0, 0.01), (1.5, 0.3), (3.1, 1.2)] {
        let (c, f) = (coarse.radiance(az, el, 1, 1), fine.radiance(az, el, 1, 1));
        for (c, f) in c.iter().zip(&f) {
            assert!(((c - f) / f).abs() < 1e-3, "{az} {el}: {c} vs {f}");
        }
    }
}

#[test]
fn radiance_is_positive_and_finite_everywhere() {
    let a = Atmosphere::earth();
    for altitude in [0.0, 13000.0] {
        let model = SkyModel::new(
            &a,
            &SkySettings {
                order: Order::Through(3),
                ..SkySettings::default()
            },
            altitude,
        )
        .unwrap();
        for sun in [-8.0f64, 0.0, 20.0, 90.0] {
            for map in [
                model.skylight_map(sun.to_radians()),
                model.ground_map(sun.to_radians()),
            ] {
                assert!(
                    map.radiance.iter().all(|v| v.is_finite() && *v >= 0.0),
                    "{altitude} {sun}"
                );
            }
        }
    }
}

#[test]
fn low_sun_reddens_the_horizon_toward_the_sun() {
    let a = Atmosphere::earth();
    let model = SkyModel::new(&a, &SkySettings::default(), 0.0).unwrap();
    let map = model.skylight_map(2f64.to_radians());
    let n = a.channels();
    let redness = |l: &[f32]| l[n - 1] / l[0];
    let (horizon, zenith) = (map.at(0, 0), map.at(0, 63));
    assert!(
        redness(horizon) > 5.0 * redness(zenith),
        "{horizon:?} {zenith:?}"
    );
    // At noon the zenith is blue: more short-wave than long-wave radiance.
    let noon = model.skylight_map(60f64.to_radians());
    assert!(noon.at(0, 63)[0] > 3.0 * noon.at(0, 63)[n - 1]);
}

#[test]
fn second_order_adds_bluer_light_and_third_order_less() {
    let a = Atmosphere::earth();
    let through = |n| {
        let settings = SkySettings {
            order: Order::Through(n),
            ..SkySettings::default()
        };
        SkyModel::new(&a, &settings, 0.0).unwrap()
    };
    let (second, third) = (through(2), through(3));
    let e = 30f64.to_radians();
    let o1 = second.skylight_map_parts(e, true, false);
    let o2 = second.skylight_map_parts(e, false, true);
    let mut o3 = third.skylight_map_parts(e, false, true);
    for (v, o2) in o3.radiance.iter_mut().zip(&o2.radiance) {
        *v -= o2;
    }
    let n = a.channels();
    let zenith = |m: &SkylightMap| m.at(0, 63).to_vec();
    let (z1, z2, z3) = (zenith(&o1), zenith(&o2), zenith(&o3));
    // The paper's Fig. 8: a bluer sky with the second order.
    assert!(z2[0] / z2[n - 1] > z1[0] / z1[n - 1], "{z1:?} {z2:?}");
    for c in 0..n {
        assert!(
            z2[c] > 0.02 * z1[c] && z2[c] < z1[c],
            "order 2 is a correction: {z1:?} {z2:?}"
        );
        assert!(
            z3[c] > 0.0 && z3[c] < z2[c],
            "order 3 is smaller than order 2: {z2:?} {z3:?}"
        );
    }
}

#[test]
fn light_comes_from_below_the_horizontal_at_13_km() {
    let a = Atmosphere::earth();
    let model = SkyModel::new(&a, &SkySettings::default(), 13000.0).unwrap();
    let map = model.skylight_map(30f64.to_radians());
    let dip = horizon_dip(a.bottom_radius_m, 13000.0);
    assert!((map.grid.elevation(0) + dip).abs() < 1e-12);
    // The grid row just below the horizontal carries sky light brighter than the zenith.
    let below = (0..64).find(|&j| map.grid.elevation(j + 1) > 0.0).unwrap();
    assert!(map.grid.elevation(below) < 0.0);
    let (b, z) = (map.at(32, below)[2], map.at(32, 63)[2]);
    assert!(b > z, "below the horizontal {b} vs zenith {z}");
}

#[test]
fn moving_the_sun_equals_a_fresh_model_and_threads_do_not_change_bytes() {
    let a = Atmosphere::earth();
    let model = SkyModel::new(&a, &SkySettings::default(), 2000.0).unwrap();
    let _ = model.skylight_map(0.1);
    let moved = model.skylight_map(0.7);
    let one_thread = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let fresh = one_thread.install(|| {
        SkyModel::new(&a, &SkySettings::default(), 2000.0)
            .unwrap()
            .skylight_map(0.7)
    });
    assert_eq!(moved.radiance, fresh.radiance);
}

#[test]
fn bad_settings_and_altitudes_are_refused() {
    let a = Atmosphere::earth();
    let err = |s: SkySettings, h: f64| {
        SkyModel::new(&a, &s, h)
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default()
    };
    assert!(err(SkySettings::default(), -1.0).contains("altitude"));
    assert!(err(SkySettings::default(), 60_000.0).contains("altitude"));
    assert!(err(SkySettings::default(), f64::NAN).contains("altitude"));
    for order in [0, 61] {
        assert!(err(
            SkySettings {
                order: Order::Through(order),
                ..SkySettings::default()
            },
            0.0
        )
        .contains("order"));
    }
    assert!(err(
        SkySettings {
            directions: 0,
            ..SkySettings::default()
        },
        0.0
    )
    .contains("directions"));
    let huge = SkySettings {
        directions: 4096,
        shells: 2000,
        scattering_directions: 4096,
        ..SkySettings::default()
    };
    assert!(err(huge, 0.0).contains("budget"));
}

/// A planet of a million kilometres is inside the documented radii, but its rays are
/// split into sub-samples every `max_interval_m`: the budget counts them (it left them
/// out and the maps grew past 2.5 GB), and a longer interval brings it back within.
#[test]
fn sub_samples_along_long_rays_enter_the_memory_budget() {
    let earth = include_str!("../presets/earth.toml");
    let huge = earth
        .lines()
        .map(|l| match l.split('=').next().map(str::trim) {
            Some("bottom_radius_m") => "bottom_radius_m = 1e9".to_string(),
            Some("top_radius_m") => "top_radius_m = 2e9".to_string(),
            _ => l.to_string(),
        })
        .collect::<Vec<_>>()
        .join("\n");
    let planet = Atmosphere::from_toml_str(&huge, "huge planet").unwrap();
    assert_eq!(planet.bottom_radius_m, 1e9);
    let refused = SkySettings::default()
        .validate(&planet)
        .unwrap_err()
        .to_string();
    assert!(
        refused.contains("budget") && refused.contains("max_interval_m"),
        "{refused}"
    );
    let coarse = SkySettings {
        max_interval_m: 1e7,
        ..SkySettings::default()
    };
    coarse.validate(&planet).unwrap();
    // The Earth at the defaults stays well inside.
    let earth = SkySettings::default().memory_bytes(&Atmosphere::earth());
    assert!(earth < atmo::budget::DEFAULT_LIMIT_BYTES / 2, "{earth}");
}

#[test]
fn pictures_are_symmetric_about_the_suns_vertical_plane() {
    use atmo::sky::SkyPicture;
    use atmo::view::{direction_of, Sun};
    let a = Atmosphere::earth();
    let model = SkyModel::new(&a, &SkySettings::default(), 3000.0).unwrap();
    let sun = Sun::from_degrees(12.0, 237.0).unwrap();
    let picture = SkyPicture::new(&model, sun);
    for (offset, elevation) in [
        (10.0f64, 5.0f64),
        (75.0, 30.0),
        (150.0, -1.0),
        (179.0, -20.0),
    ] {
        let left = direction_of((237.0 - offset).to_radians(), elevation.to_radians());
        let right = direction_of((237.0 + offset).to_radians(), elevation.to_radians());
        let (l, r) = (picture.radiance(left, true), picture.radiance(right, true));
        assert!(
            (l - r).abs().max_element() <= 1e-6 * l.max_element(),
            "{offset} {elevation}: {l} {r}"
        );
        assert!(l.min_element() > 0.0);
    }
    // And not symmetric about any other plane: toward the sun is brighter than away.
    let toward = picture.radiance(direction_of(237f64.to_radians(), 0.2), false);
    let away = picture.radiance(direction_of(57f64.to_radians(), 0.2), false);
    assert!(toward.x > 1.2 * away.x, "{toward} {away}");
    // A window's texels drawn row by row are the frame's levels, in either order
    // (the sun's disc and the horizon in view, a width that splits no row evenly).
    use atmo::image::{Display, Levels, TexelOrder, ToneMap};
    use atmo::sky::View;
    use atmo::view::{Camera, Fov};
    let camera = Camera::yaw_pitch(glam::Vec3::ZERO, 237.0, 5.0, Fov::Vertical(40.0), (97, 61));
    let view = View {
        camera: camera.unwrap(),
        sun_disc: true,
    };
    let levels = Levels::new(Display {
        exposure: 0.3,
        tone: ToneMap::Exponential,
    });
    let frame = picture.render(&view);
    for order in [TexelOrder::Rgba, TexelOrder::Bgra] {
        let mut want = Vec::new();
        frame.to_texels(&levels, order, &mut want);
        let mut texels = vec![[0u8; 4]; want.len()];
        picture.render_texels_into(&view, &levels, order, &mut texels);
        assert_eq!(texels, want, "{order:?}");
        assert!(want.iter().any(|t| t[0] != t[2]), "a sky of colours");
    }
}

#[test]
fn other_atmospheres_match_the_reference_too() {
    // The paper's model (phase, lambda^-4 power law) and Earth with ozone, which
    // changes the attenuation but not the scattering.
    let paper = Atmosphere::preset("paper").unwrap();
    let ozone = Atmosphere::earth().with_ozone(true).unwrap();
    let settings = SkySettings {
        order: Order::Through(1),
        ..SkySettings::default()
    };
    let points = grid_points(13);
    for a in [paper, ozone] {
        for (altitude, sun) in [(0.0, 10.0f64), (7000.0, 45.0), (13000.0, 3.0)] {
            let model = SkyModel::new(&a, &settings, altitude).unwrap();
            let (err, at) = error_against_reference(&model, sun, &points);
            assert!(
                err < 0.01,
                "{}: altitude {altitude}, sun {sun}: {err:.4} at {at:?}",
                a.name
            );
        }
    }
}

/// The reference for every order: single scattering (with the sunlit ground) by
/// quadrature, the higher orders by the path tracer. Returns the radiance and the path
/// tracer's standard error per channel.
fn every_order(
    reference: &ReferenceSky,
    azimuth: f64,
    elevation: f64,
    paths: usize,
) -> (Vec<f64>, Vec<f64>) {
    let single = reference.radiance(azimuth, elevation, 1, 1);
    let (multiple, error) = reference.multiple_scattering(azimuth, elevation, paths, 7);
    (
        single.iter().zip(&multiple).map(|(s, m)| s + m).collect(),
        error,
    )
}

/// Every order of both species over a dark and a bright ground, against the
/// independent reference: single scattering by quadrature, the higher orders by the
/// path tracer (4,000 paths a channel here, standard error about 1 % of the sky: the
/// test holds the mean signed error, the bias, within 0.5 % and every point within
/// 1 % plus four standard errors; `ATMO_SKY_PATHS` sets another count, for a
/// tighter measurement).
#[test]
fn every_order_agrees_with_the_path_tracer() {
    let paths: usize = std::env::var("ATMO_SKY_PATHS")
        .ok()
        .and_then(|p| p.parse().ok())
        .unwrap_or(4000);
    let settings = SkySettings {
        order: Order::All,
        multiple_mie: true,
        ..SkySettings::default()
    };
    let (mut signed, mut errors) = (Vec::new(), Vec::new());
    for (albedo, altitude, suns) in [(0.0, 0.0, [30.0f64, 2.0]), (0.3, 9000.0, [60.0, 8.0])] {
        let mut a = Atmosphere::earth();
        a.ground_albedo = albedo;
        let model = SkyModel::new(&a, &settings, altitude).unwrap();
        for sun in suns {
            let e = sun.to_radians();
            let map = model.skylight_map(e);
            let reference = ReferenceSky::new(&a, altitude, e, ReferenceSettings::CONVERGED);
            let points = [
                (0, 0),
                (0, 8),
                (21, 3),
                (63, 2),
                (63, 30),
                (40, 63),
                (10, 20),
                (32, 12),
            ];
            let want: Vec<(Vec<f64>, Vec<f64>)> = points
                .par_iter()
                .map(|&(i, j)| {
                    every_order(
                        &reference,
                        map.grid.azimuth(i),
                        map.grid.elevation(j),
                        paths,
                    )
                })
                .collect();
            for (&(i, j), (want, se)) in points.iter().zip(&want) {
                for ((got, w), se) in map.at(i, j).iter().zip(want).zip(se) {
                    let err = (*got as f64 - w) / w;
                    assert!(
                        err.abs() <= 0.01 + 4.0 * se / w,
                        "albedo {albedo}, {altitude} m, sun {sun} deg, ({i}, {j}): {got} vs {w} +- {se}"
                    );
                    signed.push(err);
                    errors.push(err.abs());
                }
            }
        }
    }
    let bias = signed.iter().sum::<f64>() / signed.len() as f64;
    errors.sort_by(f64::total_cmp);
    let (median, p95) = (errors[errors.len() / 2], errors[errors.len() * 95 / 100]);
    eprintln!("{paths} paths: bias {bias:.5}, median {median:.5}, 95th percentile {p95:.5}");
    assert!(bias.abs() <= 0.005, "bias {bias}");
}

/// A coarse model with every order of both species.
fn coarse_all_orders(a: &Atmosphere, order: Order, altitude: f64) -> SkyModel {
    let settings = SkySettings {
        shells: 20,
        directions: 24,
        scattering_directions: 32,
        sun_bins: 32,
        order,
        multiple_mie: true,
        ..SkySettings::default()
    };
    SkyModel::new(a, &settings, altitude).unwrap()
}

/// The largest difference between two maps, relative per channel, floored at 1 % of
/// the brightest.
fn largest_difference(a: &SkylightMap, b: &SkylightMap) -> f64 {
    let floor = 0.01 * a.radiance.iter().fold(0.0f32, |m, &v| m.max(v));
    a.radiance
        .iter()
        .zip(&b.radiance)
        .map(|(x, y)| ((x - y).abs() / x.max(floor)) as f64)
        .fold(0.0, f64::max)
}

#[test]
fn every_order_equals_twenty_orders() {
    let mut a = Atmosphere::earth();
    a.ground_albedo = 0.3;
    for altitude in [0.0, 8000.0] {
        let (all, twenty) = (
            coarse_all_orders(&a, Order::All, altitude),
            coarse_all_orders(&a, Order::Through(20), altitude),
        );
        assert!(
            all.orders() < 12,
            "the geometric tail ends early: {}",
            all.orders()
        );
        for sun in [-4.0f64, 1.0, 20.0, 80.0] {
            let e = sun.to_radians();
            for (x, y) in [
                (all.skylight_map(e), twenty.skylight_map(e)),
                (all.ground_map(e), twenty.ground_map(e)),
            ] {
                let d = largest_difference(&y, &x);
                assert!(d < 1e-3, "{altitude} m, sun {sun} deg: {d}");
            }
        }
    }
}

#[test]
fn a_brighter_ground_brightens_every_order_above_the_first() {
    let mut dark = Atmosphere::earth();
    dark.ground_albedo = 0.0;
    let mut bright = dark.clone();
    bright.ground_albedo = 0.5;
    let e = 25f64.to_radians();
    let (d, b) = (
        coarse_all_orders(&dark, Order::Through(4), 2000.0),
        coarse_all_orders(&bright, Order::Through(4), 2000.0),
    );
    // Single scattering in the sky does not see the ground.
    assert!(
        largest_difference(
            &d.skylight_map_parts(e, true, false),
            &b.skylight_map_parts(e, true, false)
        ) < 1e-6
    );
    // The higher orders do, everywhere: light reflected by the ground is scattered again.
    let (dm, bm) = (
        d.skylight_map_parts(e, false, true),
        b.skylight_map_parts(e, false, true),
    );
    for (x, y) in dm.radiance.iter().zip(&bm.radiance) {
        assert!(*y > 1.05 * x, "{x} vs {y}");
    }
    // And the ground itself is brighter than its sunlit part alone.
    let sunlit = b.ground_map(e);
    let lit_by_sky = coarse_all_orders(&bright, Order::Through(1), 2000.0).ground_map(e);
    for (all, sun) in sunlit.radiance.iter().zip(&lit_by_sky.radiance) {
        assert!(*all > *sun, "{all} vs {sun}");
    }
}

/// The sky's harmonics from its equirectangular map equal a direct integration of its
/// radiance over the sphere, and so does the irradiance on a horizontal surface; the
/// nine harmonics' own estimate of it is rough (the bright horizon band leaks into it),
/// which is why the lighting carries the integral.
#[test]
fn the_lighting_harmonics_equal_direct_integration() {
    use atmo::quadrature::fibonacci_sphere;
    use atmo::sky::lighting::{irradiance, irradiance_up, project_equirect, sh_basis};
    use atmo::sky::SkyPicture;
    use atmo::view::Sun;
    let a = Atmosphere::earth();
    let model = coarse_all_orders(&a, Order::Through(2), 1000.0);
    let sky = SkyPicture::new(&model, Sun::from_degrees(25.0, 135.0).unwrap());
    let map = sky.equirect(256, false);
    let sh = project_equirect(&map);
    let directions = fibonacci_sphere(200_000);
    let w = 4.0 * std::f64::consts::PI / directions.len() as f64;
    let (mut direct, mut up) = ([[0.0f64; 3]; 9], [0.0f64; 3]);
    for d in &directions {
        let l = sky.radiance(*d, false);
        let basis = sh_basis(d.as_vec3());
        for (s, b) in direct.iter_mut().zip(basis) {
            for (c, v) in s.iter_mut().zip(l.to_array()) {
                *c += w * b * v as f64;
            }
        }
        // World up is y.
        for (e, v) in up.iter_mut().zip(l.to_array()) {
            *e += w * d.y.max(0.0) * v as f64;
        }
    }
    for (k, (got, want)) in sh.iter().zip(&direct).enumerate() {
        for c in 0..3 {
            assert!(
                (got[c] - want[c]).abs() < 2e-3 * direct[0][c],
                "coefficient {k}: {got:?} vs {want:?}"
            );
        }
    }
    let (integrated, from_sh) = (irradiance_up(&map), irradiance(&sh, glam::Vec3::Y));
    for c in 0..3 {
        assert!(
            (integrated[c] - up[c]).abs() < 2e-3 * up[c],
            "{integrated:?} vs {up:?}"
        );
        // Nine harmonics overestimate it by 5 to 17 % here.
        assert!(
            (from_sh[c] - up[c]).abs() < 0.25 * up[c],
            "{from_sh:?} vs {up:?}"
        );
    }
}

/// The aerial perspective: order 1 against the reference's single scattering cut at the
/// same distance, the whole ray equal to the sky, and the invariants (transmittance in
/// (0, 1] and falling, in-scattered light >= 0 and growing with the distance).
#[test]
fn aerial_perspective_agrees_with_the_reference_and_the_sky() {
    let a = Atmosphere::earth();
    let single = SkyModel::new(
        &a,
        &SkySettings {
            order: Order::Through(1),
            ..SkySettings::default()
        },
        1500.0,
    )
    .unwrap();
    let distances = [300.0, 2000.0, 10_000.0, 40_000.0, 150_000.0];
    for (sun, azimuth, elevation) in [
        (30.0f64, 0.3f64, 0.05f64),
        (5.0, 2.8, -0.02),
        (60.0, 1.5, 0.4),
    ] {
        let e = sun.to_radians();
        let reference = ReferenceSky::new(&a, 1500.0, e, ReferenceSettings::CONVERGED);
        let got = single.aerial(e, azimuth, elevation, &distances).unwrap();
        for (d, light) in distances.iter().zip(&got) {
            let (t, s) = reference.aerial_single(azimuth, elevation, *d);
            for c in 0..a.channels() {
                let (dt, ds) = (
                    (light.transmittance[c] as f64 - t[c]).abs(),
                    (light.inscatter[c] as f64 - s[c]).abs() / s[c],
                );
                assert!(
                    dt < 1e-3 && ds < 0.01,
                    "sun {sun}, {d} m, channel {c}: T {} vs {}, S {} vs {}",
                    light.transmittance[c],
                    t[c],
                    light.inscatter[c],
                    s[c]
                );
            }
        }
    }
    // Every order, a bright ground: invariants, and the whole ray is the sky.
    let mut bright = a.clone();
    bright.ground_albedo = 0.3;
    let model = coarse_all_orders(&bright, Order::All, 800.0);
    let e = 12f64.to_radians();
    for (azimuth, elevation) in [(0.2, 0.3), (2.0, -0.4), (3.0, 0.01)] {
        let far = [1e3, 5e3, 2e4, 8e4, 3e5, 5e6];
        let lights = model.aerial(e, azimuth, elevation, &far).unwrap();
        for w in lights.windows(2) {
            for c in 0..bright.channels() {
                let (t0, t1) = (w[0].transmittance[c], w[1].transmittance[c]);
                assert!(t1 > 0.0 && t1 <= t0 && t0 <= 1.0, "{t0} {t1}");
                assert!(w[1].inscatter[c] >= w[0].inscatter[c] && w[0].inscatter[c] >= 0.0);
            }
        }
        let sky = model.radiance_along(e, &[(azimuth, elevation)]);
        let whole = &lights.last().unwrap().inscatter;
        for c in 0..bright.channels() {
            // Looking down, the sky adds the ground's own light; the haze alone is less.
            // Looking up, the same sum, its intervals split at the marks (1e-4 apart).
            if elevation > 0.0 {
                assert!(
                    (whole[c] - sky[0][c]).abs() <= 1e-3 * sky[0][c],
                    "{whole:?} {:?}",
                    sky[0]
                );
            } else {
                assert!(whole[c] < sky[0][c], "{whole:?} {:?}", sky[0]);
            }
        }
    }
}

#[test]
fn froxels_equal_the_aerial_perspective_of_their_directions() {
    use atmo::atmosphere::spectrum::SpectrumToRgb;
    use atmo::sky::aerial::quadratic_slices;
    use atmo::view::{Camera, Fov, Sun};
    let a = Atmosphere::earth();
    let model = coarse_all_orders(&a, Order::Through(2), 300.0);
    let slices = quadratic_slices(16, 60_000.0);
    let rays = model.aerial_rays(512, &slices).unwrap();
    let sun = Sun::from_degrees(20.0, 140.0).unwrap();
    let camera =
        Camera::yaw_pitch(glam::Vec3::ZERO, 100.0, -5.0, Fov::Vertical(60.0), (16, 12)).unwrap();
    let froxels = rays.froxels(&model, sun, &camera);
    assert_eq!(froxels.inscatter.len(), 16 * 16 * 12);
    let colour = SpectrumToRgb::for_atmosphere(&a);
    let basis = camera.pixel_basis();
    for (x, y) in [(0u32, 0u32), (8, 6), (15, 11), (3, 9)] {
        let d = basis.direction(x, y).unwrap().normalize();
        // World (x east, y up, z south) to elevation and azimuth from the sun.
        let elevation = (d.y as f64).asin();
        let toward = sun.toward();
        let (h, s) = (
            glam::Vec2::new(d.x, d.z),
            glam::Vec2::new(toward.x, toward.z),
        );
        let azimuth = (h.normalize().dot(s.normalize()) as f64)
            .clamp(-1.0, 1.0)
            .acos();
        let want = model
            .aerial(sun.elevation(), azimuth, elevation, &slices)
            .unwrap();
        for (k, light) in want.iter().enumerate() {
            let at = k * 16 * 12 + (y * 16 + x) as usize;
            let rgb = glam::Vec3::from(colour.rgb(&light.inscatter));
            let got = froxels.inscatter[at];
            assert!(
                // 3 %: where the ray meets the ground before the slice, a row 0.2 deg
                // off ends a few per cent nearer or farther (elsewhere under 1.4 %).
                (got - rgb).abs().max_element() <= 0.03 * rgb.max_element() + 1e-4,
                "({x}, {y}) slice {k}: {got} vs {rgb}"
            );
            let t = froxels.transmittance[at];
            assert!(
                t.min_element() > 0.0 && t.max_element() <= 1.0 + 1e-6,
                "{t}"
            );
        }
    }
}

/// The default sky (every order, ozone) at sunset: a blue zenith over an orange
/// horizon under the sun, where the paper's model (second order, no ozone) leaves the
/// zenith greyer. Ozone's Chappuis band takes the orange out of the light that reaches
/// the zenith along the long path at sunset.
#[test]
fn the_default_sunset_has_a_blue_zenith_over_an_orange_horizon() {
    use atmo::atmosphere::spectrum::SpectrumToRgb;
    let sun = 1f64.to_radians();
    let directions = [(0.0, 90f64.to_radians()), (0.0, 2f64.to_radians())];
    let colours = |atmosphere: &Atmosphere, settings: &SkySettings| {
        let model = SkyModel::new(atmosphere, settings, 0.0).unwrap();
        let to_rgb = SpectrumToRgb::for_atmosphere(atmosphere);
        let l = model.radiance_along(sun, &directions);
        (to_rgb.rgb(&l[0]), to_rgb.rgb(&l[1]))
    };
    let (zenith, horizon) = colours(&Atmosphere::earth(), &SkySettings::default());
    let paper = Atmosphere::earth().with_ozone(false).unwrap();
    let (paper_zenith, _) = colours(&paper, &SkySettings::paper());
    eprintln!("zenith {zenith:?} horizon {horizon:?} paper zenith {paper_zenith:?}");
    let blue = |c: [f32; 3]| c[2] / c[0];
    assert!(blue(zenith) > 1.5, "zenith {zenith:?}");
    assert!(
        horizon[0] > 1.3 * horizon[2] && horizon[0] > horizon[1],
        "horizon {horizon:?}"
    );
    assert!(
        blue(zenith) > 1.2 * blue(paper_zenith),
        "{zenith:?} {paper_zenith:?}"
    );
}

/// The default sky's colour against the same atmosphere at 48 wavelengths (360 to 830
/// nm, `earth-spectral`, its spectrum integrated against the CIE functions): within
/// du'v' 0.001 over the sky at suns 1 (the sunset), 2, 10 and 30 deg, from the ground
/// and from 7 km (an altitude the fit of the preset's weights did not see). A
/// piecewise-linear spectrum between the six wavelengths was 0.0035 off.
#[test]
fn the_default_colours_are_those_of_the_spectral_reference() {
    use atmo::atmosphere::spectrum::SpectrumToRgb;
    let settings = SkySettings {
        shells: 20,
        directions: 32,
        ..SkySettings::default()
    };
    let six = Atmosphere::earth();
    let many = Atmosphere::preset("earth-spectral").unwrap();
    assert!(six.colour.is_some() && many.wavelengths_nm.len() >= 40);
    let (c6, c48) = (
        SpectrumToRgb::for_atmosphere(&six),
        SpectrumToRgb::for_atmosphere(&many),
    );
    // u'v' of linear sRGB (through XYZ, D65).
    let uv = |rgb: [f32; 3]| {
        let [r, g, b] = rgb.map(|v| v as f64);
        let x = 0.4124564 * r + 0.3575761 * g + 0.1804375 * b;
        let y = 0.2126729 * r + 0.7151522 * g + 0.0721750 * b;
        let z = 0.0193339 * r + 0.1191920 * g + 0.9503041 * b;
        let d = x + 15.0 * y + 3.0 * z;
        (4.0 * x / d, 9.0 * y / d)
    };
    let mut directions = Vec::new();
    for e in [-5.0f64, 1.0, 3.0, 8.0, 15.0, 30.0, 60.0, 89.0] {
        for a in [0.0f64, 25.0, 60.0, 90.0, 130.0, 180.0] {
            directions.push((a.to_radians(), e.to_radians()));
        }
    }
    let mut worst = 0.0f64;
    for altitude in [0.0, 7000.0] {
        let m6 = SkyModel::new(&six, &settings, altitude).unwrap();
        let m48 = SkyModel::new(&many, &settings, altitude).unwrap();
        for sun in [1.0f64, 2.0, 10.0, 30.0] {
            let l6 = m6.radiance_along(sun.to_radians(), &directions);
            let l48 = m48.radiance_along(sun.to_radians(), &directions);
            for (a, b) in l6.iter().zip(&l48) {
                let ((u1, v1), (u2, v2)) = (uv(c6.rgb(a)), uv(c48.rgb(b)));
                let duv = ((u1 - u2).powi(2) + (v1 - v2).powi(2)).sqrt();
                assert!(duv < 1e-3, "{altitude} m, sun {sun}: du'v' {duv}");
                worst = worst.max(duv);
            }
        }
    }
    eprintln!("worst du'v' {worst:.5}");
    // Without the fitted weights, the piecewise-linear spectrum is several times off.
    let mut plain = six.clone();
    plain.colour = None;
    let m = SkyModel::new(&plain, &settings, 0.0).unwrap();
    let m48 = SkyModel::new(&many, &settings, 0.0).unwrap();
    let zenith = [(0.0, 89f64.to_radians())];
    let sun = 10f64.to_radians();
    let ((u1, v1), (u2, v2)) = (
        uv(SpectrumToRgb::for_atmosphere(&plain).rgb(&m.radiance_along(sun, &zenith)[0])),
        uv(c48.rgb(&m48.radiance_along(sun, &zenith)[0])),
    );
    assert!(((u1 - u2).powi(2) + (v1 - v2).powi(2)).sqrt() > 2e-3);
}
