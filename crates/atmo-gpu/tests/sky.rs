//! The sky from the skylight table on the GPU against the CPU draw of the same table.

mod common;

use std::sync::OnceLock;

use atmo::sky::frame::{Projection, SkyPicture, View};
use atmo::sky::table::{SkylightTable, TableSettings};
use atmo::sky::{SkySettings, Sun};
use atmo::Atmosphere;
use atmo_gpu::sky::GpuSkyTable;
use common::{assert_close, gpu, mean_level};

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
    let sun = Sun::from_degrees(8.0, 120.0).unwrap();
    for projection in [
        Projection::perspective_degrees(100.0, 10.0, 70.0).unwrap(),
        Projection::Fisheye,
    ] {
        let view = View {
            width: 96,
            height: 64,
            projection,
            sun_disc: true,
        };
        let altitude = 3000.0;
        let cpu = SkyPicture::from_table(table, sun, altitude)
            .unwrap()
            .render(&view);
        let out = sky.render(&gpu, sun, altitude, &view).unwrap().frame;
        assert!(
            mean_level(&out, 10.0) > 20.0,
            "{projection:?}: the sky is dark"
        );
        assert_close(&out, &cpu, 10.0, &format!("{projection:?}"));
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
