//! Recorded DMX (`.dmx`): the frames a desk sent, time-stamped, to render offline
//! (`atmo shafts SCENE --dmx-file show.dmx --animate`) exactly as the window drew them.
//!
//! The file is `ATMO-DMX` and a version byte (1), then one record a frame: the time
//! since the previous record (microseconds), the universe, and what changed from that
//! universe's previous levels (all 0 before its first record) as runs: how many, then
//! each run's distance from the end of the one before (from channel 1 for the first),
//! its length and its bytes. Every number is an unsigned LEB128 varint. A desk
//! resending a still look at 44 Hz writes a few bytes a frame; a pan sweep, a run of
//! two bytes a head.

use std::io::Write;

use super::playback::Event;
use super::{Levels, MAX_UNIVERSE, UNIVERSE_SIZE};
use crate::error::{Error, Result};

/// The file's first bytes: its name and format version.
pub const MAGIC: &[u8; 9] = b"ATMO-DMX\x01";

/// Channels whose levels did not change, between two that did, that still go in one
/// run (a run's head costs two bytes).
const GAP: usize = 3;

/// The latest time a record may have, us (a million seconds, as a scene's times).
pub const MAX_TIME_US: u64 = 1_000_000_000_000;

/// Writes frames as records.
pub struct Writer<W: Write> {
    out: W,
    last_us: u64,
    previous: std::collections::BTreeMap<u16, Box<Levels>>,
}

impl<W: Write> Writer<W> {
    /// A writer that starts with the file's magic.
    pub fn new(mut out: W) -> std::io::Result<Writer<W>> {
        out.write_all(MAGIC)?;
        Ok(Writer {
            out,
            last_us: 0,
            previous: Default::default(),
        })
    }

    /// Writes one frame (frames in time order: an earlier one is stamped at the last
    /// one's time).
    pub fn write(&mut self, event: &Event) -> std::io::Result<()> {
        let time = event.time_us.clamp(self.last_us, MAX_TIME_US);
        let before = self
            .previous
            .entry(event.universe)
            .or_insert_with(|| Box::new([0; UNIVERSE_SIZE]));
        let mut runs: Vec<(usize, usize)> = Vec::new();
        for k in (0..UNIVERSE_SIZE).filter(|&k| before[k] != event.levels[k]) {
            match runs.last_mut() {
                Some((_, end)) if k <= *end + GAP => *end = k + 1,
                _ => runs.push((k, k + 1)),
            }
        }
        let mut record = Vec::with_capacity(16 + 2 * runs.len());
        varint(&mut record, time - self.last_us);
        varint(&mut record, event.universe as u64);
        varint(&mut record, runs.len() as u64);
        let mut at = 0;
        for &(start, end) in &runs {
            varint(&mut record, (start - at) as u64);
            varint(&mut record, (end - start) as u64);
            record.extend_from_slice(&event.levels[start..end]);
            at = end;
        }
        self.out.write_all(&record)?;
        **before = *event.levels;
        self.last_us = time;
        Ok(())
    }

    /// The output, flushed.
    pub fn finish(mut self) -> std::io::Result<W> {
        self.out.flush()?;
        Ok(self.out)
    }
}

fn varint(out: &mut Vec<u8>, mut x: u64) {
    loop {
        let byte = (x & 0x7f) as u8;
        x >>= 7;
        if x == 0 {
            out.push(byte);
            return;
        }
        out.push(byte | 0x80);
    }
}

/// A recording's bytes, read back as frames.
pub struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
    time_us: u64,
    levels: std::collections::BTreeMap<u16, Box<Levels>>,
    /// Where messages say the bytes came from.
    origin: String,
    failed: bool,
}

impl<'a> Reader<'a> {
    /// A reader of `bytes` (a whole `.dmx` file; `origin` names it in messages):
    /// refused unless they start with [`MAGIC`].
    pub fn new(bytes: &'a [u8], origin: &str) -> Result<Reader<'a>> {
        if !bytes.starts_with(MAGIC) {
            return Err(Error::Invalid(format!(
                "{origin}: not a DMX recording of atmo (it does not start with \"ATMO-DMX\" \
                 and version 1)"
            )));
        }
        Ok(Reader {
            bytes,
            at: MAGIC.len(),
            time_us: 0,
            levels: Default::default(),
            origin: origin.to_string(),
            failed: false,
        })
    }

    fn fail(&mut self, why: &str) -> Error {
        self.failed = true;
        Error::Invalid(format!(
            "{}: the record at byte {} {why}",
            self.origin, self.at
        ))
    }

    fn number(&mut self, at: &mut usize, most: u64, what: &str) -> Result<u64> {
        let mut x = 0u64;
        for shift in (0..64).step_by(7) {
            let Some(&byte) = self.bytes.get(*at) else {
                return Err(self.fail(&format!("is cut off in its {what}")));
            };
            *at += 1;
            x |= ((byte & 0x7f) as u64) << shift;
            if byte & 0x80 == 0 {
                return if x <= most {
                    Ok(x)
                } else {
                    Err(self.fail(&format!("has {what} {x}: allowed at most {most}")))
                };
            }
        }
        Err(self.fail(&format!("has a {what} longer than ten bytes")))
    }

    fn record(&mut self) -> Result<Event> {
        let mut at = self.at;
        let dt = self.number(&mut at, MAX_TIME_US, "time step")?;
        let time_us = self.time_us + dt;
        if time_us > MAX_TIME_US {
            return Err(self.fail(&format!(
                "is at {time_us} us: allowed at most {MAX_TIME_US}"
            )));
        }
        let universe = self.number(&mut at, MAX_UNIVERSE as u64, "universe")? as u16;
        if universe == 0 {
            return Err(self.fail("has universe 0: allowed 1 to 63999"));
        }
        let runs = self.number(&mut at, UNIVERSE_SIZE as u64, "run count")?;
        let mut levels = self
            .levels
            .get(&universe)
            .cloned()
            .unwrap_or_else(|| Box::new([0; UNIVERSE_SIZE]));
        let mut channel = 0usize;
        for _ in 0..runs {
            let left = (UNIVERSE_SIZE - channel) as u64;
            channel += self.number(&mut at, left, "run's distance")? as usize;
            let length = self.number(&mut at, (UNIVERSE_SIZE - channel) as u64, "run's length")?;
            let Some(bytes) = self.bytes.get(at..at + length as usize) else {
                return Err(self.fail("is cut off in a run's levels"));
            };
            levels[channel..channel + length as usize].copy_from_slice(bytes);
            (at, channel) = (at + length as usize, channel + length as usize);
        }
        self.levels.insert(universe, levels.clone());
        (self.at, self.time_us) = (at, time_us);
        Ok(Event {
            time_us,
            universe,
            levels,
        })
    }
}

impl Iterator for Reader<'_> {
    type Item = Result<Event>;

    /// The next frame; after an error, nothing.
    fn next(&mut self) -> Option<Result<Event>> {
        (!self.failed && self.at < self.bytes.len()).then(|| self.record())
    }
}

/// The time of a recording's last frame, us, and how many frames it holds; an error
/// where any record is malformed.
pub fn extent(bytes: &[u8], origin: &str) -> Result<(u64, usize)> {
    let mut last = 0;
    let mut count = 0;
    for event in Reader::new(bytes, origin)? {
        last = event?.time_us;
        count += 1;
    }
    Ok((last, count))
}

/// A recording played into a show at any times, in any order (a render farm's chunks
/// start anywhere): forward from where it is, or again from the start for an earlier
/// time.
pub struct Player<'a> {
    bytes: &'a [u8],
    origin: String,
    frames: std::iter::Peekable<Reader<'a>>,
    playback: super::playback::Playback,
    /// The time last posed, us.
    posed_us: u64,
}

impl<'a> Player<'a> {
    /// A player of the recording `bytes` (`origin` names it) for `show`'s fixtures.
    pub fn new(
        bytes: &'a [u8],
        origin: &str,
        show: &crate::shafts::show::Show,
    ) -> Result<Player<'a>> {
        Ok(Player {
            bytes,
            origin: origin.to_string(),
            frames: Reader::new(bytes, origin)?.peekable(),
            playback: super::playback::Playback::new(show),
            posed_us: 0,
        })
    }

    /// Poses `scene`'s heads at `time_us` as the recording has them.
    pub fn pose(&mut self, scene: &mut crate::shafts::Scene, time_us: u64) -> Result<()> {
        if time_us < self.posed_us {
            *self = Player::new(self.bytes, &self.origin, &scene.show)?;
        }
        self.posed_us = time_us;
        self.playback.play_to(scene, &mut self.frames, time_us)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn event(time_us: u64, universe: u16, set: &[(usize, u8)]) -> Event {
        let mut levels = Box::new([0u8; UNIVERSE_SIZE]);
        for &(k, v) in set {
            levels[k] = v;
        }
        Event {
            time_us,
            universe,
            levels,
        }
    }

    #[test]
    fn frames_read_back_as_written_and_a_still_look_costs_a_few_bytes() {
        let frames = [
            event(0, 1, &[(0, 255), (1, 128), (511, 7)]),
            event(22_727, 2, &[(100, 1)]),
            event(45_454, 1, &[(0, 255), (1, 128), (511, 7)]),
            event(68_181, 1, &[(0, 200), (3, 9), (511, 7)]),
            // An earlier stamp is written at the last one's time.
            event(60_000, 2, &[]),
        ];
        let mut w = Writer::new(Vec::new()).unwrap();
        let mut sizes = Vec::new();
        for f in &frames {
            let before = w.out.len();
            w.write(f).unwrap();
            sizes.push(w.out.len() - before);
        }
        let bytes = w.finish().unwrap();
        // The third frame repeats the first: its time step, universe and no runs.
        assert_eq!(sizes[2], 3 + 1 + 1);
        let back: Vec<Event> = Reader::new(&bytes, "test")
            .unwrap()
            .map(|e| e.unwrap())
            .collect();
        let mut expected = frames.to_vec();
        expected[4].time_us = 68_181;
        assert_eq!(back, expected);
        assert_eq!(extent(&bytes, "test").unwrap(), (68_181, 5));
    }

    #[test]
    fn malformed_records_are_refused_with_where_they_are() {
        let mut w = Writer::new(Vec::new()).unwrap();
        w.write(&event(5, 3, &[(10, 1), (11, 2)])).unwrap();
        let good = w.finish().unwrap();
        // Cut anywhere inside the record: an error, never a panic or a short frame.
        for cut in MAGIC.len() + 1..good.len() {
            let mut r = Reader::new(&good[..cut], "cut.dmx").unwrap();
            let e = r.next().unwrap().unwrap_err().to_string();
            assert!(e.contains("cut.dmx: the record at byte 9"), "{e}");
            assert!(r.next().is_none());
        }
        let mut bad = MAGIC.to_vec();
        // Universe 0, a universe past 63999, a run past channel 512.
        for record in [
            &[0u8, 0, 0][..],
            &[0, 0x80, 0xf4, 0x03, 0],
            &[0, 1, 1, 0x80, 0x04, 1, 0],
        ] {
            bad.truncate(MAGIC.len());
            bad.extend_from_slice(record);
            let e = Reader::new(&bad, "bad.dmx")
                .unwrap()
                .next()
                .unwrap()
                .unwrap_err();
            assert!(e.to_string().contains("allowed"), "{e}");
        }
        assert!(Reader::new(b"ATMO-DMX\x02", "v2").is_err());
    }
}
