//! A desk's DMX: one datagram of sACN or Art-Net (the first byte picks which), or a
//! `.dmx` recording played into scenes/dmx-rig.toml (GDTF modes and a personality).
//! No panic, no allocation past the budget; a packet taken is a universe atmo can use;
//! the states a recording drives are finite.
#![no_main]
use std::sync::OnceLock;

use atmo::shafts::dmx::{playback::Playback, recording::Reader, wire};
use libfuzzer_sys::fuzz_target;

mod common;

fn rig() -> &'static atmo::shafts::Scene {
    static RIG: OnceLock<atmo::shafts::Scene> = OnceLock::new();
    RIG.get_or_init(|| {
        atmo::shafts::edits::load(std::path::Path::new("../scenes/dmx-rig.toml"), &[])
            .expect("the rig scene loads")
    })
}

fuzz_target!(|data: &[u8]| {
    common::small_budget();
    let Some((&kind, rest)) = data.split_first() else {
        return;
    };
    let from = "127.0.0.1:6454".parse().expect("an address");
    match kind % 3 {
        0 | 1 => {
            let protocol = [wire::Protocol::Sacn, wire::Protocol::ArtNet][kind as usize % 3];
            if let wire::Packet::Dmx(d) = wire::parse(protocol, rest, from) {
                assert!((1..=atmo::shafts::dmx::MAX_UNIVERSE).contains(&d.universe));
                assert!(d.priority <= 200);
            }
        }
        _ => {
            let show = &rig().show;
            let Ok(reader) = Reader::new(rest, "fuzz.dmx") else {
                return;
            };
            let mut playback = Playback::new(show);
            for event in reader.take(10_000) {
                let Ok(event) = event else { break };
                playback.apply(show, &event);
                for (state, gobo) in playback.states(show, event.time_us + 1000) {
                    assert!(state.channels.iter().all(|c| c.is_finite()) && gobo.is_finite());
                }
            }
        }
    }
});
