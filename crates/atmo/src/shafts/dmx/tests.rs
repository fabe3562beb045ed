use super::playback::{Event, Playback, STROBE_OPEN};
use super::*;
use crate::shafts::show::{Fixture, Show};

fn names(list: &[&str]) -> Vec<String> {
    list.iter().map(|s| s.to_string()).collect()
}

const RANGES: [[f32; 2]; 3] = [[-270.0, 270.0], [-135.0, 135.0], [10.0, 40.0]];

fn personality(list: &[&str], slots: usize) -> Patch {
    let mode = Mode::personality(&names(list), RANGES, slots, "fixture[0].dmx").unwrap();
    Patch::new(1, 101, mode, "fixture[0].dmx").unwrap()
}

/// Levels with `values` from the patch's address on.
fn levels(address: u16, values: &[u8]) -> Box<Levels> {
    let mut l = Box::new([0u8; UNIVERSE_SIZE]);
    let at = address as usize - 1;
    l[at..at + values.len()].copy_from_slice(values);
    l
}

#[test]
fn coarse_and_fine_span_the_range_and_bands_pick_slots() {
    let p = personality(
        &["pan", "pan_fine", "tilt", "gobo", "prism", "iris", "dimmer"],
        2,
    );
    assert_eq!(p.mode.footprint(), 7);
    let read = |v: &[u8]| p.read(&levels(101, v));
    // 16 bits: 0 is one end, 65535 the other, 0x8000 a 540/65535 step past the middle.
    assert_eq!(read(&[0, 0]).pan_deg, Some(-270.0));
    assert_eq!(read(&[255, 255]).pan_deg, Some(270.0));
    let mid = read(&[128, 0]).pan_deg.unwrap();
    assert!((mid - 540.0 * 0.5 / 65535.0).abs() < 1e-3, "{mid}");
    assert_eq!(read(&[0, 0, 255]).tilt_deg, Some(135.0));
    // Gobo: three bands from 0, 85 and 170 (open, two gobos); prism out below 128;
    // iris 0 open.
    let gobo = |v: u8| read(&[0, 0, 0, v]).gobo.unwrap();
    assert_eq!(
        [gobo(0), gobo(84), gobo(85), gobo(169), gobo(170), gobo(255)],
        [0, 0, 1, 1, 2, 2]
    );
    assert_eq!(read(&[0, 0, 0, 0, 127]).prism_in, Some(false));
    assert_eq!(read(&[0, 0, 0, 0, 128]).prism_in, Some(true));
    assert_eq!(read(&[0; 7]).iris, Some(1.0));
    assert!((read(&[0, 0, 0, 0, 0, 255]).iris.unwrap() - 0.05).abs() < 1e-6);
    assert_eq!(read(&[0, 0, 0, 0, 0, 0, 51]).dimmer, Some(0.2));
    // A channel a fixture lacks says nothing.
    assert_eq!(read(&[0; 7]).zoom_deg, None);
    // Every reading only looks at its own channels: the rest of the universe is noise.
    let mut noisy = levels(101, &[10, 20, 30, 40, 50, 60, 70]);
    noisy[..100].fill(255);
    noisy[107..].fill(255);
    assert_eq!(
        p.read(&noisy),
        p.read(&levels(101, &[10, 20, 30, 40, 50, 60, 70]))
    );
}

#[test]
fn personalities_and_patches_are_refused_with_the_field_and_range() {
    let refuse = |list: &[&str]| {
        Mode::personality(&names(list), RANGES, 0, "fixture[2].dmx")
            .unwrap_err()
            .to_string()
    };
    assert!(refuse(&["pan", "tilt_fine"])
        .contains("fixture[2].dmx.channels[1] = \"tilt_fine\" must follow \"tilt\""));
    assert!(refuse(&["pan", "focus"]).contains("allowed pan, tilt"));
    assert!(refuse(&["pan", "pan"]).contains("named twice"));
    let mode = Mode::personality(&names(&["pan", "tilt", "dimmer"]), RANGES, 0, "f").unwrap();
    let e = Patch::new(1, 511, mode.clone(), "fixture[2].dmx")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("fixture[2].dmx.address = 511") && e.contains("[1, 510]"),
        "{e}"
    );
    assert!(Patch::new(1, 510, mode.clone(), "f").is_ok());
    assert!(Patch::new(0, 1, mode, "f")
        .unwrap_err()
        .to_string()
        .contains("f.universe = 0"));
}

#[test]
fn the_shutter_closes_strobes_and_speeds_turn_both_ways() {
    let p = personality(&["shutter", "gobo_spin", "prism_index"], 0);
    let read = |v: &[u8]| p.read(&levels(101, v));
    assert_eq!(read(&[0, 0, 0]).strobe_hz, Some(0.0));
    assert_eq!(read(&[16, 0, 0]).strobe_hz, None);
    assert_eq!(read(&[128, 0, 0]).strobe_hz, Some(1.0));
    assert_eq!(read(&[255, 0, 0]).strobe_hz, Some(25.0));
    assert_eq!(read(&[16, 0, 0]).gobo_turn, Some(Turn::Spin(0.0)));
    assert_eq!(read(&[16, 127, 0]).gobo_turn, Some(Turn::Spin(360.0)));
    assert_eq!(read(&[16, 128, 0]).gobo_turn, Some(Turn::Spin(0.0)));
    assert_eq!(read(&[16, 255, 0]).gobo_turn, Some(Turn::Spin(-360.0)));
    assert_eq!(read(&[16, 0, 255]).prism_turn, Some(Turn::Index(360.0)));
}

/// GDTF's mode masters: a function counts only while its master channel is in range,
/// and its span ends at the next function that counts.
#[test]
fn a_mode_master_switches_what_a_channel_does() {
    let function = |attribute, dmx_from, physical, mode_master| Function {
        attribute: Some(attribute),
        dmx_from,
        physical,
        sets: Vec::new(),
        closed: false,
        mode_master,
    };
    let mode = Mode {
        name: "m".into(),
        channels: vec![
            Channel {
                name: "control".into(),
                offsets: vec![1],
                functions: vec![function(Attribute::Dimmer, 0, [0.0, 0.0], None)],
            },
            Channel {
                name: "gobo turn".into(),
                offsets: vec![2],
                functions: vec![
                    function(Attribute::GoboIndex, 0, [0.0, 360.0], Some((0, [0, 127]))),
                    function(
                        Attribute::GoboSpin,
                        0,
                        [-100.0, 100.0],
                        Some((0, [128, 255])),
                    ),
                ],
            },
        ],
        colours: Vec::new(),
    };
    let p = Patch::new(1, 1, mode, "m").unwrap();
    assert_eq!(
        p.read(&levels(1, &[0, 255])).gobo_turn,
        Some(Turn::Index(360.0))
    );
    assert_eq!(
        p.read(&levels(1, &[200, 255])).gobo_turn,
        Some(Turn::Spin(100.0))
    );
    assert_eq!(
        p.read(&levels(1, &[200, 0])).gobo_turn,
        Some(Turn::Spin(-100.0))
    );
}

#[cfg(feature = "gdtf")]
#[test]
fn gdtf_dmx_values_mirror_or_shift_into_the_channel() {
    use super::gdtf_mode::{colour_xyy, dmx_value};
    assert_eq!(dmx_value("255/1", 2), Ok(65535));
    assert_eq!(dmx_value("128/1", 2), Ok(32896));
    assert_eq!(dmx_value("128/1s", 2), Ok(32768));
    assert_eq!(dmx_value("32768/2", 1), Ok(128));
    assert_eq!(dmx_value("7/1", 1), Ok(7));
    for bad in ["256/1", "1", "x/1", "1/5", "1/0"] {
        assert!(dmx_value(bad, 1).is_err(), "{bad}");
    }
    let white = colour_xyy("0.3127,0.3290,100").unwrap();
    assert!(
        (white - glam::Vec3::ONE).abs().max_element() < 0.01,
        "{white}"
    );
    let red = colour_xyy("0.64,0.33,21.26").unwrap();
    assert!(red.x > 0.95 && red.y < 0.02 && red.z < 0.02, "{red}");
}

/// The test fixture's GDTF mode: 16-bit pan and tilt over its physical ranges, the gobo
/// wheel's open slot and two gobos, the prism out on its wheel's open slot.
#[cfg(feature = "gdtf")]
#[test]
fn a_gdtf_mode_drives_its_fixture_as_the_file_says() {
    let bytes = crate::shafts::gdtf::example_fixture();
    let sampling = crate::shafts::spotlight::Sampling::Bilinear;
    let file = crate::shafts::gdtf::read(&bytes, "atmo-spot.gdtf", "Standard", sampling).unwrap();
    let patch = Patch::new(3, 20, file.dmx, "f").unwrap();
    assert_eq!(patch.mode.footprint(), 8);
    // Offsets 1,2 pan; 3,4 tilt; 5 zoom; 6 gobo; 7 dimmer; 8 prism.
    let read = |v: &[u8]| patch.read(&levels(20, v));
    let r = read(&[255, 255, 0, 0, 255, 0, 255, 0]);
    assert_eq!(
        (r.pan_deg, r.tilt_deg, r.zoom_deg),
        (Some(270.0), Some(-135.0), Some(36.0))
    );
    assert_eq!(
        (r.dimmer, r.gobo, r.prism_in),
        (Some(1.0), Some(0), Some(false))
    );
    let r = read(&[64, 0, 192, 0, 0, 200, 0, 255]);
    assert!((r.pan_deg.unwrap() - (-270.0 + 540.0 * 16384.0 / 65535.0)).abs() < 1e-3);
    assert!((r.tilt_deg.unwrap() - (-135.0 + 270.0 * 49152.0 / 65535.0)).abs() < 1e-3);
    assert_eq!(
        (r.zoom_deg, r.gobo, r.prism_in),
        (Some(8.0), Some(2), Some(true))
    );
}

/// The show's test head, patched, its lamp's white a warm one.
fn head(patch: Patch) -> Fixture {
    Fixture {
        white: glam::Vec3::new(1.0, 0.9, 0.8),
        patch: Some(patch),
        ..crate::shafts::show::tests::head()
    }
}

fn frame(time_us: u64, values: &[u8]) -> Event {
    Event {
        time_us,
        universe: 1,
        levels: levels(101, values),
    }
}

/// A show played from frames: each head holds what the last frame said, a spinning
/// gobo turns by its speed times the time since, the strobe flashes at its rate; the
/// same frames through a recording give the same states, bit for bit.
#[test]
fn frames_drive_the_heads_and_a_recording_plays_them_back_the_same() {
    let patch = personality(&["pan", "dimmer", "red", "cyan", "gobo_spin", "shutter"], 0);
    let show = Show::new(
        vec![Fixture {
            body: true,
            ..head(patch)
        }],
        Vec::new(),
    );
    let frames = [
        frame(100_000, &[0, 255, 255, 0, 127, 16]),
        frame(600_000, &[255, 128, 128, 255, 255, 255]),
        frame(900_000, &[128, 255, 255, 0, 128, 0]),
    ];
    let mut live = Playback::new(&show);
    // Before any frame: the scene's start.
    assert_eq!(live.states(&show, 50_000)[0].0, show.fixtures[0].start);
    let mut seen = Vec::new();
    let times = [50_000, 100_000, 350_000, 600_000, 610_000, 700_000, 950_000];
    let mut next = 0;
    for &t in &times {
        while next < frames.len() && frames[next].time_us <= t {
            assert!(live.apply(&show, &frames[next]));
            next += 1;
        }
        seen.push(live.states(&show, t));
    }
    let (s, gobo) = seen[2][0];
    assert_eq!(s.channels[0], -270.0);
    // Additive red full, others 1 (no channel), through the lamp's white.
    assert_eq!(&s.channels[5..8], &[1.0, 0.9, 0.8]);
    // 360 deg/s for 0.25 s from the start's 10 deg.
    assert!((gobo - 100.0).abs() < 1e-3, "{gobo}");
    // The second frame: strobing at 25 Hz (a flash the first fifth of each 40 ms),
    // full cyan taking the red out, reversed spin.
    let (s, gobo) = seen[3][0];
    assert_eq!(s.channels[5..8], [0.0, 0.9, 0.8]);
    assert!((gobo - 190.0).abs() < 1e-3, "{gobo}");
    assert!(((0.6 * 25.0f64).fract() < STROBE_OPEN) == (s.channels[4] > 0.0));
    assert_eq!(
        seen[4][0].0.channels[4], 0.0,
        "610 ms is in the dark part of a period"
    );
    assert!((seen[5][0].1 - (190.0 - 36.0)).abs() < 1e-3);
    // The shutter closed: dark.
    assert_eq!(seen[6][0].0.channels[4], 0.0);
    // Posed in a scene: one spotlight, dark with the shutter closed, and the head's
    // body panned with it (the head's centre 0.14 m behind the lamp, along the beam).
    let mut scene = crate::shafts::Scene::builder(
        glam::Vec3::new(0.0, 1.0, 8.0),
        glam::Vec3::ZERO,
        40.0,
        (8, 8),
    )
    .haze(0.1, 0.9)
    .build()
    .unwrap();
    scene.show = show.clone();
    live.pose(&mut scene, 950_000);
    assert_eq!(scene.show.lights()[0].intensity, glam::Vec3::ZERO);
    assert_eq!(scene.objects.list.len(), 1, "the body");
    let body = scene.objects.list[0].shape.bounds().unwrap();
    let beam = scene.show.lights()[0].light_from_world.row(2);
    let head_centre = show.fixtures[0].position - 0.14 * beam;
    assert!(body.min.cmple(head_centre).all() && body.max.cmpge(head_centre).all());
    assert!(!scene.objects.list[0].casts_shadow);

    let mut w = recording::Writer::new(Vec::new()).unwrap();
    frames.iter().for_each(|f| w.write(f).unwrap());
    let bytes = w.finish().unwrap();
    let mut played = Playback::new(&show);
    let mut reader = recording::Reader::new(&bytes, "show.dmx")
        .unwrap()
        .peekable();
    for (&t, expected) in times.iter().zip(&seen) {
        played.play_to(&mut scene, &mut reader, t).unwrap();
        assert_eq!(&played.states(&scene.show, t), expected, "at {t} us");
    }
}

#[cfg(feature = "dmx")]
mod live {
    use std::collections::BTreeSet;
    use std::net::UdpSocket;
    use std::time::{Duration, Instant};

    use super::super::receiver::{Listener, Settings};
    use super::super::wire::Protocol;
    use super::*;

    fn listener(protocol: Protocol, universes: &[u16]) -> Listener {
        let mut settings =
            Settings::new(protocol, universes.iter().copied().collect::<BTreeSet<_>>());
        settings.bind = "127.0.0.1:0".parse().unwrap();
        Listener::bind(settings, Instant::now()).unwrap()
    }

    /// Receives until `count` frames came or a second passed.
    fn frames(l: &mut Listener, count: usize) -> Vec<Event> {
        let mut out = Vec::new();
        let until = Instant::now() + Duration::from_secs(1);
        while out.len() < count && Instant::now() < until {
            l.receive(Duration::from_millis(20), &mut out).unwrap();
        }
        out
    }

    use super::super::wire::tests::{art_dmx, Sacn};

    fn sacn(
        cid: u8,
        universe: u16,
        priority: u8,
        sequence: u8,
        values: &[u8],
        end: bool,
    ) -> Vec<u8> {
        Sacn {
            cid,
            universe,
            priority,
            sequence,
            values,
            start: 0,
            preview: false,
            terminated: end,
        }
        .bytes()
    }

    #[test]
    fn art_net_frames_arrive_in_order_and_a_poll_is_answered() {
        let mut l = listener(Protocol::ArtNet, &[1, 3]);
        let to = l.local_addr();
        let desk = UdpSocket::bind("127.0.0.1:0").unwrap();
        desk.set_read_timeout(Some(Duration::from_secs(1))).unwrap();
        desk.send_to(&art_dmx(0, 1, &[10, 20]), to).unwrap();
        // Out of sequence (behind by one): dropped. Universe 2 (port 1): not listened.
        desk.send_to(&art_dmx(0, 0xff, &[99, 99]), to).unwrap();
        desk.send_to(&art_dmx(1, 2, &[5, 5]), to).unwrap();
        desk.send_to(&art_dmx(2, 2, &[7, 8]), to).unwrap();
        // The same levels again make no frame.
        desk.send_to(&art_dmx(2, 3, &[7, 8]), to).unwrap();
        let got = frames(&mut l, 2);
        assert_eq!(got.len(), 2);
        assert_eq!(
            (got[0].universe, &got[0].levels[..3]),
            (1, &[10, 20, 0][..])
        );
        assert_eq!((got[1].universe, &got[1].levels[..2]), (3, &[7, 8][..]));
        assert!(got[0].time_us <= got[1].time_us);
        for _ in 0..5 {
            l.receive(Duration::from_millis(5), &mut Vec::new())
                .unwrap();
        }
        let stats = l.stats().clone();
        assert_eq!(
            (stats.out_of_sequence, stats.other_universe, stats.taken),
            (1, 1, 3)
        );
        let mut poll = b"Art-Net\0".to_vec();
        poll.extend_from_slice(&[0x00, 0x20, 0, 14, 0, 0]);
        desk.send_to(&poll, to).unwrap();
        l.receive(Duration::from_millis(500), &mut Vec::new())
            .unwrap();
        let mut reply = [0u8; 600];
        let (n, from) = desk.recv_from(&mut reply).unwrap();
        assert_eq!((n, from), (239, to));
        assert_eq!(&reply[8..10], &[0x00, 0x21]);
        assert_eq!(&reply[174..176], &[0x80, 0x80], "two output ports");
    }

    #[test]
    fn sacn_sources_merge_by_priority_then_highest_level() {
        let mut l = listener(Protocol::Sacn, &[7]);
        let to = l.local_addr();
        let desk = UdpSocket::bind("127.0.0.1:0").unwrap();
        let send = |p: Vec<u8>| {
            desk.send_to(&p, to).unwrap();
        };
        send(sacn(1, 7, 100, 1, &[10, 200], false));
        let a = frames(&mut l, 1);
        // An equal priority merges highest-takes-precedence, channel by channel.
        send(sacn(2, 7, 100, 1, &[50, 0], false));
        let b = frames(&mut l, 1);
        // A higher priority takes the universe alone; when it terminates, the two
        // equal ones merge again.
        send(sacn(3, 7, 150, 1, &[1, 1], false));
        let c = frames(&mut l, 1);
        send(sacn(3, 7, 150, 2, &[], true));
        let d = frames(&mut l, 1);
        let first = |f: &[Event]| f[0].levels[..2].to_vec();
        assert_eq!(first(&a), [10, 200]);
        assert_eq!(first(&b), [50, 200]);
        assert_eq!(first(&c), [1, 1]);
        assert_eq!(first(&d), [50, 200]);
    }

    /// Hostile datagrams (random bytes, cut and lying packets, a flood) are counted
    /// and dropped; the listener keeps taking good frames.
    #[test]
    fn hostile_datagrams_never_stop_the_listener() {
        for protocol in [Protocol::Sacn, Protocol::ArtNet] {
            let mut l = listener(protocol, &[1]);
            let to = l.local_addr();
            let desk = UdpSocket::bind("127.0.0.1:0").unwrap();
            let good = match protocol {
                Protocol::Sacn => sacn(9, 1, 100, 1, &[42], false),
                Protocol::ArtNet => art_dmx(0, 0, &[42, 0]),
            };
            let mut seed = 12345u64;
            let mut sent = 0;
            for k in 0..2000usize {
                seed = seed
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let mut p = good.clone();
                match k % 4 {
                    0 => p.truncate((seed >> 33) as usize % p.len()),
                    1 => {
                        let i = (seed >> 33) as usize % p.len();
                        p[i] ^= (seed >> 20) as u8 | 1;
                    }
                    2 => {
                        p = (0..(seed >> 40) as usize % 1400)
                            .map(|i| (seed >> (i % 50)) as u8)
                            .collect()
                    }
                    _ => p.extend(std::iter::repeat_n(0xee, (seed >> 35) as usize % 1000)),
                }
                if desk.send_to(&p, to).is_ok() {
                    sent += 1;
                }
                if k % 64 == 0 {
                    l.receive(Duration::from_millis(1), &mut Vec::new())
                        .unwrap();
                }
            }
            let mut out = Vec::new();
            let until = Instant::now() + Duration::from_secs(2);
            while l.stats().datagrams < sent && Instant::now() < until {
                l.receive(Duration::from_millis(5), &mut out).unwrap();
            }
            assert!(l.stats().ignored > 100, "{protocol:?}: {:?}", l.stats());
            // A good frame after the flood still arrives (new levels: a frame).
            let fresh = match protocol {
                Protocol::Sacn => sacn(10, 1, 100, 1, &[43], false),
                Protocol::ArtNet => art_dmx(0, 0, &[43, 0]),
            };
            desk.send_to(&fresh, to).unwrap();
            let got = frames(&mut l, 1);
            assert!(
                got.iter().chain(&out).any(|e| e.levels[0] == 43),
                "{protocol:?}: the frame after the flood did not arrive"
            );
        }
    }
}
