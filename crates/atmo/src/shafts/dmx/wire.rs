//! The two ways desks send DMX over Ethernet, read from one UDP datagram each:
//! sACN (ANSI E1.31, port 5568) and Art-Net (ArtDmx and ArtPoll, port 6454).
//!
//! Both are parsed here, as fixed layouts of a few fields: the `sacn` crate's packet
//! layer panicked on a data packet whose framing layer claims fewer bytes than its own
//! header (found by the `dmx` fuzz target in 4,542 runs), and `artnet_protocol` takes
//! every byte after an ArtDmx header as levels whatever its Length field says (a
//! 600-byte datagram gave 582 "channels"). Anything that is not a well-formed packet of
//! a universe atmo can use is [`Packet::Ignored`] with the reason, never a panic (the
//! `dmx` fuzz target holds it to that).

use std::net::Ipv4Addr;

use super::{Levels, MAX_UNIVERSE, UNIVERSE_SIZE};

/// The UDP ports desks send to.
pub const SACN_PORT: u16 = 5568;
pub const ARTNET_PORT: u16 = 6454;

/// Which protocol a datagram came by.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Protocol {
    Sacn,
    ArtNet,
}

/// Who sent a universe: sACN's component identifier, or an Art-Net sender's address.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Source {
    Cid([u8; 16]),
    Address(std::net::SocketAddr),
}

/// One universe's levels from a source.
#[derive(Debug, Clone, PartialEq)]
pub struct Dmx {
    /// atmo's universe number: sACN's, or Art-Net's 15-bit port-address plus one (desks
    /// show Art-Net's universe 0:0:0 as universe 1).
    pub universe: u16,
    pub source: Source,
    /// sACN's priority (0-200; Art-Net has none: 100, sACN's default).
    pub priority: u8,
    /// The sender's sequence number (Art-Net: 0 when it keeps none).
    pub sequence: u8,
    /// The source says it stops sending this universe (sACN's Stream_Terminated).
    pub terminated: bool,
    /// The levels (channels the packet does not carry are 0).
    pub levels: Box<Levels>,
}

/// What a datagram is.
#[derive(Debug, Clone, PartialEq)]
pub enum Packet {
    Dmx(Dmx),
    /// An ArtPoll: a desk looking for nodes, to be answered ([`poll_reply`]).
    ArtPoll,
    /// Not for atmo, or malformed: why.
    Ignored(String),
}

/// sACN's priority when a packet does not say (and Art-Net's).
pub const DEFAULT_PRIORITY: u8 = 100;

/// Reads one datagram of `protocol` from `from`.
pub fn parse(protocol: Protocol, bytes: &[u8], from: std::net::SocketAddr) -> Packet {
    match protocol {
        Protocol::Sacn => parse_sacn(bytes),
        Protocol::ArtNet => parse_artnet(bytes, from),
    }
}

/// E1.31's fixed layout of a data packet: the root layer's preamble and packet
/// identifier, its vector, and the offsets of the fields read (ANSI E1.31-2018, 6).
const ACN_ID: &[u8; 12] = b"ASC-E1.17\0\0\0";
const VECTOR_ROOT_DATA: u32 = 0x0000_0004;
const VECTOR_ROOT_EXTENDED: u32 = 0x0000_0008;
const VECTOR_FRAMING_DATA: u32 = 0x0000_0002;
const VECTOR_DMP_SET_PROPERTY: u8 = 0x02;
/// Where the root, framing and DMP layers' flags-and-length fields are, and where the
/// property values (the start code, then the levels) begin.
const ROOT_AT: usize = 16;
const FRAMING_AT: usize = 38;
const DMP_AT: usize = 115;
const VALUES_AT: usize = 125;

fn parse_sacn(bytes: &[u8]) -> Packet {
    let ignore = |why: &str| Packet::Ignored(format!("sACN: {why}"));
    if bytes.len() < VALUES_AT || bytes[..4] != [0, 0x10, 0, 0] || &bytes[4..16] != ACN_ID {
        return ignore("not an E1.31 packet (no ACN preamble and identifier)");
    }
    let u16_at = |k: usize| u16::from_be_bytes([bytes[k], bytes[k + 1]]);
    let u32_at =
        |k: usize| u32::from_be_bytes([bytes[k], bytes[k + 1], bytes[k + 2], bytes[k + 3]]);
    // Each layer's length (the low 12 bits) runs from its own field to the packet's
    // end, which the datagram must hold.
    for (at, name) in [(ROOT_AT, "root"), (FRAMING_AT, "framing"), (DMP_AT, "DMP")] {
        let length = (u16_at(at) & 0x0fff) as usize;
        if at + length > bytes.len() || at + length < VALUES_AT {
            return ignore(&format!(
                "the {name} layer's length {length} does not fit the {}-byte datagram",
                bytes.len()
            ));
        }
    }
    match u32_at(ROOT_AT + 2) {
        VECTOR_ROOT_DATA => {}
        VECTOR_ROOT_EXTENDED => return ignore("a synchronisation or discovery packet"),
        v => return ignore(&format!("root vector {v:#x}, not data")),
    }
    if u32_at(FRAMING_AT + 2) != VECTOR_FRAMING_DATA {
        return ignore("framing vector not data");
    }
    let (priority, sequence, options) = (bytes[108], bytes[111], bytes[112]);
    let universe = u16_at(113);
    if !(1..=MAX_UNIVERSE).contains(&universe) {
        return ignore(&format!("universe {universe}: allowed 1 to {MAX_UNIVERSE}"));
    }
    if bytes[DMP_AT + 2] != VECTOR_DMP_SET_PROPERTY
        || bytes[DMP_AT + 3] != 0xa1
        || u16_at(DMP_AT + 4) != 0
        || u16_at(DMP_AT + 6) != 1
    {
        return ignore("DMP layer not a set-property of consecutive channels");
    }
    let count = u16_at(DMP_AT + 8) as usize;
    let Some(values) = bytes
        .get(VALUES_AT..VALUES_AT + count)
        .filter(|_| (1..=UNIVERSE_SIZE + 1).contains(&count))
    else {
        return ignore(&format!(
            "{count} property values (1 to 513, within the datagram)"
        ));
    };
    if options & 0x80 != 0 {
        return ignore("preview data (for visualisers told to take it)");
    }
    let terminated = options & 0x40 != 0;
    if values[0] != 0 && !terminated {
        return ignore(&format!(
            "start code {:#04x}, not DMX levels (0)",
            values[0]
        ));
    }
    let mut levels = Box::new([0u8; UNIVERSE_SIZE]);
    levels[..count - 1].copy_from_slice(&values[1..]);
    let mut cid = [0u8; 16];
    cid.copy_from_slice(&bytes[22..38]);
    Packet::Dmx(Dmx {
        universe,
        source: Source::Cid(cid),
        priority: priority.min(200),
        sequence,
        terminated,
        levels,
    })
}

/// Art-Net's packet identifier, the opcodes atmo reads and the smallest protocol
/// version it takes.
const ARTNET_ID: &[u8; 8] = b"Art-Net\0";
const OP_POLL: u16 = 0x2000;
const OP_POLL_REPLY: u16 = 0x2100;
const OP_DMX: u16 = 0x5000;
const ARTNET_VERSION: u16 = 14;

fn parse_artnet(bytes: &[u8], from: std::net::SocketAddr) -> Packet {
    if bytes.len() < 12 || &bytes[..8] != ARTNET_ID {
        return Packet::Ignored("not an Art-Net packet".into());
    }
    let opcode = u16::from_le_bytes([bytes[8], bytes[9]]);
    let version = u16::from_be_bytes([bytes[10], bytes[11]]);
    if version < ARTNET_VERSION {
        return Packet::Ignored(format!("Art-Net protocol version {version}, below 14"));
    }
    match opcode {
        OP_POLL => Packet::ArtPoll,
        OP_DMX => {
            // Sequence, Physical, SubUni, Net, Length (big-endian), then the levels.
            let Some(header) = bytes.get(12..18) else {
                return Packet::Ignored("ArtDmx shorter than its 18-byte header".into());
            };
            let port_address = u16::from_le_bytes([header[2], header[3] & 0x7f]);
            let length = u16::from_be_bytes([header[4], header[5]]) as usize;
            if !(2..=UNIVERSE_SIZE).contains(&length) || !length.is_multiple_of(2) {
                return Packet::Ignored(format!(
                    "ArtDmx Length {length}: allowed an even number from 2 to 512"
                ));
            }
            let Some(slots) = bytes.get(18..18 + length) else {
                return Packet::Ignored(format!(
                    "ArtDmx Length {length} but {} bytes of levels",
                    bytes.len() - 18
                ));
            };
            let universe = port_address + 1;
            let mut levels = Box::new([0u8; UNIVERSE_SIZE]);
            levels[..length].copy_from_slice(slots);
            Packet::Dmx(Dmx {
                universe,
                source: Source::Address(from),
                priority: DEFAULT_PRIORITY,
                sequence: header[0],
                terminated: false,
                levels,
            })
        }
        other => Packet::Ignored(format!(
            "Art-Net opcode {other:#06x}, not ArtDmx or ArtPoll"
        )),
    }
}

/// The ArtPollReply that tells a desk atmo is here (at `address`, the address it is
/// reached at), listening to `universes` (atmo's numbers; the first four are
/// reported as output ports, as one node reports them), named `name`.
pub fn poll_reply(address: Ipv4Addr, universes: &[u16], name: &str) -> Vec<u8> {
    let mut p = Vec::with_capacity(239);
    p.extend_from_slice(ARTNET_ID);
    p.extend_from_slice(&OP_POLL_REPLY.to_le_bytes());
    p.extend_from_slice(&address.octets());
    p.extend_from_slice(&ARTNET_PORT.to_le_bytes());
    // Firmware version, then NetSwitch and SubSwitch of the first universe's
    // port-address (bits 14-8 and 7-4), OEM (0xffff: none), UBEA version, status 1,
    // ESTA manufacturer (0x7ff0: ESTA's prototype code).
    let ports: Vec<u16> = universes
        .iter()
        .take(4)
        .map(|u| u.saturating_sub(1) & 0x7fff)
        .collect();
    let first = ports.first().copied().unwrap_or(0);
    p.extend_from_slice(&[0, 1, (first >> 8) as u8 & 0x7f, (first >> 4) as u8 & 0x0f]);
    p.extend_from_slice(&[0xff, 0xff, 0, 0]);
    p.extend_from_slice(&0x7ff0u16.to_le_bytes());
    let text = |n: usize, s: &str| {
        let mut field = vec![0u8; n];
        let s = s.as_bytes();
        field[..s.len().min(n - 1)].copy_from_slice(&s[..s.len().min(n - 1)]);
        field
    };
    p.extend(text(18, name));
    p.extend(text(64, &format!("{name}: previz of light in haze")));
    p.extend(text(64, "#0001 [0000] atmo listening"));
    p.extend_from_slice(&(ports.len() as u16).to_be_bytes());
    // Port types (0x80: output of DMX512), good input, good output (0x80: data
    // transmitted), swin, swout (each port's low nibble).
    let per_port = |f: &dyn Fn(u16) -> u8| -> [u8; 4] {
        std::array::from_fn(|k| ports.get(k).map_or(0, |&a| f(a)))
    };
    p.extend_from_slice(&per_port(&|_| 0x80));
    p.extend_from_slice(&[0; 4]);
    p.extend_from_slice(&per_port(&|_| 0x80));
    p.extend_from_slice(&[0; 4]);
    p.extend_from_slice(&per_port(&|a| (a & 0x0f) as u8));
    // SwVideo, SwMacro, SwRemote, spare x3, Style (0x06: a visualiser), MAC, BindIp,
    // BindIndex, Status2 (0x08: 15-bit port-addresses), filler.
    p.extend_from_slice(&[0, 0, 0, 0, 0, 0, 0x06]);
    p.extend_from_slice(&[0; 6]);
    p.extend_from_slice(&address.octets());
    p.extend_from_slice(&[1, 0x08]);
    p.resize(239, 0);
    p
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    fn from() -> std::net::SocketAddr {
        "127.0.0.1:6454".parse().unwrap()
    }

    /// An ArtDmx datagram for port-address `port` carrying `levels`.
    pub(crate) fn art_dmx(port: u16, sequence: u8, levels: &[u8]) -> Vec<u8> {
        let mut p = ARTNET_ID.to_vec();
        p.extend_from_slice(&OP_DMX.to_le_bytes());
        p.extend_from_slice(&14u16.to_be_bytes());
        p.extend_from_slice(&[sequence, 0]);
        p.extend_from_slice(&port.to_le_bytes());
        p.extend_from_slice(&(levels.len() as u16).to_be_bytes());
        p.extend_from_slice(levels);
        p
    }

    /// An sACN data packet from the source `cid` (each byte of it), start code 0 unless
    /// `start` says otherwise, carrying `values`.
    pub(crate) struct Sacn<'a> {
        pub cid: u8,
        pub universe: u16,
        pub priority: u8,
        pub sequence: u8,
        pub values: &'a [u8],
        pub start: u8,
        pub preview: bool,
        pub terminated: bool,
    }

    impl Sacn<'_> {
        /// The datagram, as E1.31-2018 lays it out.
        pub(crate) fn bytes(&self) -> Vec<u8> {
            let count = self.values.len() + 1;
            let total = VALUES_AT + count;
            let flags_length = |at: usize| (0x7000 | (total - at) as u16).to_be_bytes();
            let mut p = vec![0, 0x10, 0, 0];
            p.extend_from_slice(ACN_ID);
            p.extend_from_slice(&flags_length(ROOT_AT));
            p.extend_from_slice(&VECTOR_ROOT_DATA.to_be_bytes());
            p.extend_from_slice(&[self.cid; 16]);
            p.extend_from_slice(&flags_length(FRAMING_AT));
            p.extend_from_slice(&VECTOR_FRAMING_DATA.to_be_bytes());
            let mut name = [0u8; 64];
            name[..4].copy_from_slice(b"desk");
            p.extend_from_slice(&name);
            let options = (self.preview as u8) << 7 | (self.terminated as u8) << 6;
            p.extend_from_slice(&[self.priority, 0, 0, self.sequence, options]);
            p.extend_from_slice(&self.universe.to_be_bytes());
            p.extend_from_slice(&flags_length(DMP_AT));
            p.extend_from_slice(&[VECTOR_DMP_SET_PROPERTY, 0xa1, 0, 0, 0, 1]);
            p.extend_from_slice(&(count as u16).to_be_bytes());
            p.push(self.start);
            p.extend_from_slice(self.values);
            p
        }
    }

    #[test]
    fn art_dmx_gives_its_levels_and_honours_its_length() {
        let Packet::Dmx(d) = parse(Protocol::ArtNet, &art_dmx(0x0102, 7, &[9, 8, 7, 6]), from())
        else {
            panic!("not read as DMX")
        };
        assert_eq!((d.universe, d.sequence), (0x0103, 7));
        assert_eq!(&d.levels[..5], &[9, 8, 7, 6, 0]);
        // Bytes past the Length field are not levels; a Length past the datagram, an
        // odd one and one over 512 are refused.
        let mut long = art_dmx(0, 1, &[1, 2]);
        long.extend_from_slice(&[5; 600]);
        let Packet::Dmx(d) = parse(Protocol::ArtNet, &long, from()) else {
            panic!("not read")
        };
        assert_eq!(&d.levels[..3], &[1, 2, 0]);
        let mut short = art_dmx(0, 1, &[1, 2, 3, 4]);
        short.truncate(20);
        for bad in [short, art_dmx(0, 1, &[1, 2, 3]), art_dmx(0, 1, &[0; 514])] {
            assert!(matches!(
                parse(Protocol::ArtNet, &bad, from()),
                Packet::Ignored(_)
            ));
        }
    }

    #[test]
    fn a_poll_is_answered_with_a_reply_of_the_listened_universes() {
        let mut poll = ARTNET_ID.to_vec();
        poll.extend_from_slice(&OP_POLL.to_le_bytes());
        poll.extend_from_slice(&[0, 14, 0, 0]);
        assert_eq!(parse(Protocol::ArtNet, &poll, from()), Packet::ArtPoll);
        let reply = poll_reply(Ipv4Addr::LOCALHOST, &[1, 0x213], "atmo");
        assert_eq!(reply.len(), 239);
        assert_eq!(&reply[..8], ARTNET_ID);
        assert_eq!(u16::from_le_bytes([reply[8], reply[9]]), OP_POLL_REPLY);
        assert_eq!(&reply[10..14], &[127, 0, 0, 1]);
        // Two output ports: 0:0:0 and 0x212's low nibble 2 (its net and subnet are
        // the first port's in one reply: 0).
        assert_eq!(u16::from_be_bytes([reply[172], reply[173]]), 2);
        assert_eq!(&reply[174..176], &[0x80, 0x80]);
        assert_eq!(&reply[190..192], &[0, 2]);
        assert_eq!(&reply[26..31], b"atmo\0");
    }

    #[test]
    fn sacn_data_gives_its_universe_priority_and_levels() {
        let packet = |universe: u16, start: u8, preview: bool| {
            Sacn {
                cid: 3,
                universe,
                priority: 150,
                sequence: 42,
                values: &[10, 20, 30],
                start,
                preview,
                terminated: false,
            }
            .bytes()
        };
        let Packet::Dmx(d) = parse(Protocol::Sacn, &packet(7, 0, false), from()) else {
            panic!("not read")
        };
        assert_eq!((d.universe, d.priority, d.sequence), (7, 150, 42));
        assert_eq!(d.source, Source::Cid([3; 16]));
        assert_eq!(&d.levels[..4], &[10, 20, 30, 0]);
        for bad in [
            packet(7, 0xdd, false),
            packet(7, 0, true),
            packet(64000, 0, false),
        ] {
            assert!(matches!(
                parse(Protocol::Sacn, &bad, from()),
                Packet::Ignored(_)
            ));
        }
        let mut cut = packet(7, 0, false);
        cut.truncate(100);
        assert!(matches!(
            parse(Protocol::Sacn, &cut, from()),
            Packet::Ignored(_)
        ));
        // A framing layer that claims fewer bytes than its own header (what made the
        // sacn crate panic), one that claims more than the datagram, and the fuzz
        // target's input that found it.
        for claim in [0x7000u16, 0x7fff] {
            let mut lying = packet(7, 0, false);
            lying[FRAMING_AT..FRAMING_AT + 2].copy_from_slice(&claim.to_be_bytes());
            assert!(matches!(
                parse(Protocol::Sacn, &lying, from()),
                Packet::Ignored(_)
            ));
        }
        let found = include_bytes!(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../fuzz/corpus/dmx/sacn-framing-shorter-than-its-header"
        ));
        assert!(matches!(
            parse(Protocol::Sacn, &found[1..], from()),
            Packet::Ignored(_)
        ));
    }
}
