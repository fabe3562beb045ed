use std::io::Write;

use super::*;

/// A zip of `files` (name, bytes), stored.
pub(crate) fn zip(files: &[(&str, &[u8])]) -> Vec<u8> {
    let mut out = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let options =
        zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Stored);
    for (name, bytes) in files {
        out.start_file(*name, options).unwrap();
        out.write_all(bytes).unwrap();
    }
    out.finish().unwrap().into_inner()
}

/// A description with one fixture in a group raised 1 m, and a truss from a symbol.
fn description(fixture_matrix: &str, address: &str, geometry: &str) -> String {
    format!(
        r#"<?xml version="1.0" encoding="UTF-8"?>
<GeneralSceneDescription verMajor="1" verMinor="5">
  <Scene>
    <AUXData>
      <Symdef uuid="S1" name="truss piece">
        <ChildList><Geometry3D fileName="{geometry}"/></ChildList>
      </Symdef>
    </AUXData>
    <Layers>
      <Layer uuid="L1" name="rig">
        <ChildList>
          <GroupObject uuid="G1" name="raised">
            <Matrix>{{1,0,0}}{{0,1,0}}{{0,0,1}}{{0,0,1000}}</Matrix>
            <ChildList>
              <Fixture uuid="F1" name="Spot">
                <Matrix>{fixture_matrix}</Matrix>
                <GDTFSpec>Maker@Spot.gdtf</GDTFSpec>
                <GDTFMode>Standard</GDTFMode>
                <FixtureID>7</FixtureID>
                <Addresses><Address break="0">{address}</Address></Addresses>
              </Fixture>
              <Truss uuid="T1" name="bar">
                <Matrix>{{1,0,0}}{{0,1,0}}{{0,0,1}}{{2000,0,5000}}</Matrix>
                <Geometries><Symbol uuid="Y1" symdef="S1"/></Geometries>
              </Truss>
            </ChildList>
          </GroupObject>
        </ChildList>
      </Layer>
    </Layers>
  </Scene>
</GeneralSceneDescription>"#
    )
}

fn rig(description: &str, extra: &[(&str, &[u8])]) -> Result<Rig> {
    let triangle = three_ds::tests::file(
        &[[0.0, 0.0, 0.0], [1000.0, 0.0, 0.0], [0.0, 500.0, 0.0]],
        &[[0, 1, 2]],
    );
    let mut files: Vec<(&str, &[u8])> = vec![
        ("GeneralSceneDescription.xml", description.as_bytes()),
        ("bar.3ds", &triangle),
        ("Maker@Spot.gdtf", b"not read here"),
    ];
    files.extend_from_slice(extra);
    read(&zip(&files), "test.mvr")
}

/// Positions compose through the group, MVR's z-up millimetres become atmo's y-up
/// metres, the patch's absolute address splits into universe and channel, and a
/// truss's symbol places its 3DS triangle.
#[test]
fn a_rig_places_its_fixtures_and_truss_in_atmos_frame() {
    // Hung upside down (local z down) at x = 1 m, y = 2 m, z = 3 m above the group.
    let hung = "{1,0,0}{0,-1,0}{0,0,-1}{1000,2000,3000}";
    let rig = rig(&description(hung, "513", "bar.3ds"), &[]).unwrap();
    let f = &rig.fixtures[0];
    assert_eq!(
        (f.name.as_str(), f.fixture_id.as_str(), f.mode.as_str()),
        ("Spot", "7", "Standard")
    );
    assert_eq!(f.patch, Some((2, 1)));
    assert!(
        (f.origin - Vec3::new(1.0, 4.0, -2.0)).length() < 1e-6,
        "{}",
        f.origin
    );
    // Local -z is MVR's +z, atmo's +y: the beam points up at rest; tilt toward local
    // +y, MVR's -y, atmo's +z.
    assert!((f.axis - Vec3::Y).length() < 1e-6 && (f.front - Vec3::Z).length() < 1e-6);
    assert_eq!(rig.gdtf.len(), 1);
    // The triangle, 1 m along x and 0.5 m along MVR's y, from (2, 0, 6) m.
    assert_eq!(rig.triangles.len(), 1);
    let t = rig.triangles[0];
    assert!((t[0] - Vec3::new(2.0, 6.0, 0.0)).length() < 1e-6, "{t:?}");
    assert!((t[1] - Vec3::new(3.0, 6.0, 0.0)).length() < 1e-6);
    assert!((t[2] - Vec3::new(2.0, 6.0, -0.5)).length() < 1e-6);
    assert_eq!(address("2.17"), Ok(Some((2, 17))));
    assert_eq!(address("0"), Ok(None));
    assert!(address("1.513").is_err() && address("x").is_err());
}

/// Hostile archives are refused with what is wrong: a name with a folder, a DTD
/// (entity expansion), nesting past the limit, a symbol without its definition, a
/// matrix that is not one, a file that is not a zip.
#[test]
fn hostile_rigs_are_refused_naming_why() {
    let plain = "{1,0,0}{0,1,0}{0,0,1}{0,0,0}";
    let refuse = |text: &str, extra: &[(&str, &[u8])]| rig(text, extra).unwrap_err().to_string();
    assert!(
        refuse(&description(plain, "1", "../../etc/passwd.3ds"), &[])
            .contains("at the archive's root")
    );
    let bomb = format!(
        "<?xml version=\"1.0\"?><!DOCTYPE l [<!ENTITY a \"aaaaaaaaaa\"><!ENTITY b \"&a;&a;&a;&a;\">]>{}",
        description(plain, "1", "bar.3ds").trim_start_matches("<?xml version=\"1.0\" encoding=\"UTF-8\"?>")
    );
    assert!(refuse(&bomb, &[]).contains("GeneralSceneDescription.xml"));
    let deep = description(plain, "1", "bar.3ds").replace(
        "<GroupObject uuid=\"G1\" name=\"raised\">",
        &format!(
            "{}<GroupObject uuid=\"G1\" name=\"raised\">",
            "<GroupObject uuid=\"G\"><ChildList>".repeat(80)
        ),
    );
    let deep = deep.replace(
        "</GroupObject>",
        &format!("</GroupObject>{}", "</ChildList></GroupObject>".repeat(80)),
    );
    let e = refuse(&deep, &[]);
    assert!(e.contains("deeper than 64"), "{e}");
    let orphan = description(plain, "1", "bar.3ds").replace("symdef=\"S1\"", "symdef=\"S9\"");
    assert!(refuse(&orphan, &[]).contains("Symdef \"S9\""));
    assert!(refuse(&description("{1,0,0}{0,1,0}", "1", "bar.3ds"), &[]).contains("Matrix"));
    assert!(refuse(&description(plain, "99999999", "bar.3ds"), &[]).contains("allowed universes"));
    assert!(read(b"not a zip", "x.mvr")
        .unwrap_err()
        .to_string()
        .contains("not a readable zip"));
    // A glTF model is skipped, said so, not refused.
    let gltf = rig(&description(plain, "1", "model.glb"), &[]).unwrap();
    assert!(gltf.skipped[0].contains("only 3DS"), "{:?}", gltf.skipped);
}

/// The Capture demo show (a real MVR from a previz tool, tests/capture_demo_show.mvr of
/// python-mvr, MIT): its 76 fixtures with their patch, its truss and set from 3DS.
#[test]
fn a_real_rig_from_a_previz_tool_opens() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../scenes/mvr/capture_demo_show.mvr"
    );
    let rig = read(&std::fs::read(path).unwrap(), "capture_demo_show.mvr").unwrap();
    assert_eq!(rig.fixtures.len(), 76);
    assert_eq!(rig.gdtf.len(), 5);
    let first = rig.fixtures.iter().find(|f| f.fixture_id == "11").unwrap();
    assert_eq!(first.patch, Some((2, 1)));
    assert!(
        rig.triangles.len() > 10_000,
        "{} triangles",
        rig.triangles.len()
    );
    // A stage of tens of metres, its truss above the floor.
    let (lo, hi) = rig.triangles.iter().flatten().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    let size = hi - lo;
    assert!(
        size.max_element() > 5.0 && size.max_element() < 200.0,
        "{lo} .. {hi}"
    );
    assert!(
        rig.fixtures.iter().all(|f| f.origin.y > lo.y),
        "fixtures above the floor"
    );
}

/// The real rig in a scene: the MVR alone as the scene (its placeholder fixture types
/// drawn dark, the camera in front), refused without `replace` or `keep_dark` naming
/// each type, and lit through scenes/mvr-capture.toml's replacements with the MVR's
/// patch.
#[test]
fn a_real_rig_becomes_a_scene() {
    use crate::shafts::Scene;
    let scenes = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes"));
    let alone = Scene::from_file(&scenes.join("mvr/capture_demo_show.mvr")).unwrap();
    assert_eq!(alone.show.fixtures.len(), 0);
    let dark = alone
        .objects
        .list
        .iter()
        .filter(|o| !o.casts_shadow)
        .count();
    assert_eq!(dark, 76, "every fixture a dark body");
    let text = Scene::read_text(&scenes.join("mvr-capture.toml")).unwrap();
    let refused = Scene::from_text_at(
        &text.replace(
            "  { spec = \"ADB@ALC4@r3012.gdtf\", gdtf = \"fixtures/atmo-spot.gdtf\", mode = \"Standard\" },\n",
            "",
        ),
        &scenes.join("mvr-capture.toml"),
    )
    .unwrap_err()
    .to_string();
    assert!(
        refused.contains("\"ADB@ALC4@r3012.gdtf\" (8 fixtures)"),
        "{refused}"
    );
    assert!(refused.contains("keep_dark = true"));
    let lit = Scene::from_text_at(&text, &scenes.join("mvr-capture.toml")).unwrap();
    assert_eq!(lit.show.fixtures.len(), 76);
    assert_eq!(lit.light_count(), 76);
    assert!(lit.show.fixtures.iter().all(|f| f.patch.is_some()));
    let spot = lit
        .show
        .fixtures
        .iter()
        .find(|f| f.name == "Alpha Spot QWO 800 11")
        .unwrap();
    assert_eq!(
        spot.patch.as_ref().map(|p| (p.universe, p.address)),
        Some((2, 1))
    );
}
