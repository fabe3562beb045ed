//! Listening to a desk: a UDP socket for sACN or Art-Net, each universe merged from its
//! sources as E1.31 says, stamped frames out.
//!
//! Per universe the sources heard in the last [`SOURCE_TIMEOUT`] are merged: the
//! highest priority wins, and sources of equal priority are merged highest-takes-
//! precedence, channel by channel (as OLA and most nodes do). A packet out of sequence
//! (a sequence number 1-19 behind the source's last, E1.31 6.7.2; Art-Net's 0 turns
//! the check off) is dropped; a source that says it terminates leaves at once. When
//! every source of a universe has gone, its last levels hold (the look stays up, as
//! fixtures hold their last DMX). An ArtPoll is answered with an ArtPollReply, so desks
//! list atmo among their nodes. Every changed universe becomes an [`Event`] stamped
//! from the listener's start.

use std::collections::{BTreeMap, BTreeSet, VecDeque};
use std::net::{Ipv4Addr, SocketAddr, UdpSocket};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use super::playback::Event;
use super::wire::{self, Dmx, Packet, Protocol, Source};
use super::{Levels, UNIVERSE_SIZE};
use crate::error::{Error, Result};

/// How long a source is heard after its last packet (E1.31's network data loss).
pub const SOURCE_TIMEOUT: Duration = Duration::from_millis(2500);

/// The most sources merged into one universe; a packet from one more is dropped.
pub const MAX_SOURCES: usize = 16;

/// What to listen to.
#[derive(Debug, Clone)]
pub struct Settings {
    pub protocol: Protocol,
    /// The address and port to bind (sACN: multicast groups of the universes are
    /// joined on this address's interface, or on every one for 0.0.0.0).
    pub bind: SocketAddr,
    /// The universes to take (atmo's numbers); others are ignored.
    pub universes: BTreeSet<u16>,
}

impl Settings {
    /// Listening to `universes` by `protocol` on every interface at its port.
    pub fn new(protocol: Protocol, universes: BTreeSet<u16>) -> Settings {
        let port = match protocol {
            Protocol::Sacn => wire::SACN_PORT,
            Protocol::ArtNet => wire::ARTNET_PORT,
        };
        Settings {
            protocol,
            bind: SocketAddr::from((Ipv4Addr::UNSPECIFIED, port)),
            universes,
        }
    }
}

/// What the listener has seen, for the window's panel and the tests.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Stats {
    /// Datagrams received.
    pub datagrams: u64,
    /// DMX packets of a listened universe taken.
    pub taken: u64,
    /// Dropped: not DMX of atmo's (with the last reason), of an unlistened universe,
    /// out of sequence, from one source too many.
    pub ignored: u64,
    pub last_ignored: Option<String>,
    pub other_universe: u64,
    pub out_of_sequence: u64,
    pub too_many_sources: u64,
    /// ArtPolls answered.
    pub polls: u64,
    /// Frames (changed universes) made.
    pub frames: u64,
    /// Multicast groups that could not be joined (sACN; unicast still arrives).
    pub multicast_failed: Option<String>,
}

/// One source's stream of a universe.
#[derive(Debug)]
struct Stream {
    priority: u8,
    sequence: u8,
    seen: Instant,
    levels: Box<Levels>,
}

/// A universe: its sources and the levels they merge to.
#[derive(Debug)]
struct Universe {
    streams: BTreeMap<Source, Stream>,
    levels: Box<Levels>,
}

impl Universe {
    /// The merge of the streams heard since `since`, if any is (others are forgotten).
    fn merged(&mut self, since: Instant) -> Option<Box<Levels>> {
        self.streams.retain(|_, s| s.seen >= since);
        let top = self.streams.values().map(|s| s.priority).max()?;
        let mut out = Box::new([0u8; UNIVERSE_SIZE]);
        for s in self.streams.values().filter(|s| s.priority == top) {
            for (o, &l) in out.iter_mut().zip(s.levels.iter()) {
                *o = (*o).max(l);
            }
        }
        Some(out)
    }
}

/// A bound socket and the universes it merges.
pub struct Listener {
    socket: UdpSocket,
    settings: Settings,
    universes: BTreeMap<u16, Universe>,
    start: Instant,
    stats: Stats,
    buffer: Vec<u8>,
    /// The socket's read timeout as last set (set again only when a wait differs).
    timeout: Option<Duration>,
}

impl Listener {
    /// Binds the socket (and, for sACN, joins the universes' multicast groups);
    /// frames are stamped from `start`.
    pub fn bind(settings: Settings, start: Instant) -> Result<Listener> {
        let socket = UdpSocket::bind(settings.bind).map_err(|e| {
            Error::Invalid(format!(
                "--bind {}: cannot listen there ({e}){}",
                settings.bind,
                if e.kind() == std::io::ErrorKind::AddrInUse {
                    "; another program (a desk's own visualiser, olad) may hold the port"
                } else {
                    ""
                }
            ))
        })?;
        let mut stats = Stats::default();
        if settings.protocol == Protocol::Sacn {
            let interface = match settings.bind.ip() {
                std::net::IpAddr::V4(ip) => ip,
                std::net::IpAddr::V6(_) => Ipv4Addr::UNSPECIFIED,
            };
            for &u in &settings.universes {
                let group = Ipv4Addr::new(239, 255, (u >> 8) as u8, u as u8);
                if let Err(e) = socket.join_multicast_v4(&group, &interface) {
                    stats.multicast_failed = Some(format!("{group}: {e}"));
                }
            }
        }
        Ok(Listener {
            socket,
            settings,
            universes: BTreeMap::new(),
            start,
            stats,
            buffer: vec![0; 2048],
            timeout: None,
        })
    }

    /// The address the socket is bound to.
    pub fn local_addr(&self) -> SocketAddr {
        self.socket.local_addr().unwrap_or(self.settings.bind)
    }

    /// What it has seen so far.
    pub fn stats(&self) -> &Stats {
        &self.stats
    }

    fn now_us(&self) -> u64 {
        self.start.elapsed().as_micros() as u64
    }

    /// Waits up to `wait` for a datagram and takes it, then forgets sources that timed
    /// out; the frames this made go to `out`.
    pub fn receive(&mut self, wait: Duration, out: &mut Vec<Event>) -> Result<()> {
        let wait = Some(wait.max(Duration::from_millis(1)));
        if self.timeout != wait {
            self.socket
                .set_read_timeout(wait)
                .map_err(|e| Error::Invalid(format!("the DMX socket: {e}")))?;
            self.timeout = wait;
        }
        match self.socket.recv_from(&mut self.buffer) {
            Ok((n, from)) => {
                self.stats.datagrams += 1;
                let packet = wire::parse(self.settings.protocol, &self.buffer[..n], from);
                self.take(packet, from, out);
            }
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock
                        | std::io::ErrorKind::TimedOut
                        | std::io::ErrorKind::Interrupted
                        | std::io::ErrorKind::ConnectionRefused
                ) => {}
            Err(e) => return Err(Error::Invalid(format!("the DMX socket: {e}"))),
        }
        let since = Instant::now().checked_sub(SOURCE_TIMEOUT);
        let timed_out: Vec<u16> = self
            .universes
            .iter()
            .filter(|(_, u)| u.streams.values().any(|s| Some(s.seen) < since))
            .map(|(&k, _)| k)
            .collect();
        for universe in timed_out {
            self.remerge(universe, out);
        }
        Ok(())
    }

    fn ignore(&mut self, why: String) {
        self.stats.ignored += 1;
        self.stats.last_ignored = Some(why);
    }

    fn take(&mut self, packet: Packet, from: SocketAddr, out: &mut Vec<Event>) {
        match packet {
            Packet::Ignored(why) => self.ignore(why),
            Packet::ArtPoll => {
                self.stats.polls += 1;
                let universes: Vec<u16> = self.settings.universes.iter().copied().collect();
                let reply = wire::poll_reply(reply_address(from), &universes, "atmo");
                let mut to = vec![SocketAddr::new(from.ip(), wire::ARTNET_PORT)];
                if from.port() != wire::ARTNET_PORT {
                    to.push(from);
                }
                for addr in to {
                    let _ = self.socket.send_to(&reply, addr);
                }
            }
            Packet::Dmx(d) => self.take_dmx(d, out),
        }
    }

    fn take_dmx(&mut self, d: Dmx, out: &mut Vec<Event>) {
        if !self.settings.universes.contains(&d.universe) {
            self.stats.other_universe += 1;
            return self.ignore(format!("universe {} is not listened to", d.universe));
        }
        let universe = self
            .universes
            .entry(d.universe)
            .or_insert_with(|| Universe {
                streams: BTreeMap::new(),
                levels: Box::new([0; UNIVERSE_SIZE]),
            });
        if let Some(s) = universe.streams.get(&d.source) {
            let behind = d.sequence.wrapping_sub(s.sequence) as i8;
            let checked = !(self.settings.protocol == Protocol::ArtNet
                && (d.sequence == 0 || s.sequence == 0));
            if checked && behind <= 0 && behind > -20 {
                let why = format!(
                    "universe {}: sequence {} after {}",
                    d.universe, d.sequence, s.sequence
                );
                self.stats.out_of_sequence += 1;
                return self.ignore(why);
            }
        } else if universe.streams.len() >= MAX_SOURCES && !d.terminated {
            self.stats.too_many_sources += 1;
            return self.ignore(format!(
                "universe {}: a source past the {MAX_SOURCES} merged",
                d.universe
            ));
        }
        self.stats.taken += 1;
        if d.terminated {
            universe.streams.remove(&d.source);
        } else {
            universe.streams.insert(
                d.source,
                Stream {
                    priority: d.priority,
                    sequence: d.sequence,
                    seen: Instant::now(),
                    levels: d.levels,
                },
            );
        }
        self.remerge(d.universe, out);
    }

    /// Merges the universe's streams again; a frame out if its levels changed.
    fn remerge(&mut self, universe: u16, out: &mut Vec<Event>) {
        let now_us = self.now_us();
        let Some(u) = self.universes.get_mut(&universe) else {
            return;
        };
        let since = Instant::now()
            .checked_sub(SOURCE_TIMEOUT)
            .unwrap_or(self.start);
        if let Some(levels) = u.merged(since) {
            if levels != u.levels {
                u.levels = levels.clone();
                self.stats.frames += 1;
                out.push(Event {
                    time_us: now_us,
                    universe,
                    levels,
                });
            }
        }
    }
}

/// The address a poller at `to` reaches this host at (the interface that routes to
/// it), for the ArtPollReply.
fn reply_address(to: SocketAddr) -> Ipv4Addr {
    UdpSocket::bind((Ipv4Addr::UNSPECIFIED, 0))
        .and_then(|s| s.connect(to).and_then(|_| s.local_addr()))
        .ok()
        .and_then(|a| match a.ip() {
            std::net::IpAddr::V4(ip) if !ip.is_unspecified() => Some(ip),
            _ => None,
        })
        .unwrap_or(Ipv4Addr::LOCALHOST)
}

/// The most frames kept for the window between two pictures: past it the oldest are
/// dropped (the recording still gets them), so a flood cannot grow memory.
pub const MAX_PENDING: usize = 16_384;

/// What the listening thread hands over.
#[derive(Default)]
struct Inbox {
    frames: VecDeque<Event>,
    dropped: u64,
    stats: Stats,
    error: Option<String>,
}

/// A [`Listener`] on its own thread, for the window: frames wait in an inbox until
/// [`Receiver::take`], and each is also written to the recording, if one is made.
pub struct Receiver {
    inbox: Arc<Mutex<Inbox>>,
    stop: Arc<AtomicBool>,
    thread: Option<std::thread::JoinHandle<Result<()>>>,
    local: SocketAddr,
}

/// How long the thread waits for a datagram before it looks at the stop flag.
const POLL: Duration = Duration::from_millis(20);

impl Receiver {
    /// Starts listening (binding now, so a bad address is an error here), stamping
    /// frames from `start`; with `record`, every frame also goes to that file,
    /// written in place when [`Receiver::stop`] is called.
    pub fn start(
        settings: Settings,
        start: Instant,
        record: Option<std::path::PathBuf>,
    ) -> Result<Receiver> {
        let mut listener = Listener::bind(settings, start)?;
        let local = listener.local_addr();
        let inbox = Arc::new(Mutex::new(Inbox::default()));
        let stop = Arc::new(AtomicBool::new(false));
        let (inbox2, stop2) = (inbox.clone(), stop.clone());
        let thread = std::thread::Builder::new()
            .name("atmo-dmx".into())
            .spawn(move || {
                let mut run = |keep: &mut dyn FnMut(&Event) -> Result<()>| {
                    pass_on(&mut listener, &stop2, &inbox2, keep)
                };
                let result = match &record {
                    None => run(&mut |_| Ok(())),
                    Some(path) => crate::files::write_atomically(path, |out| {
                        let mut writer =
                            super::recording::Writer::new(out).map_err(Error::io_at(path))?;
                        run(&mut |e| writer.write(e).map_err(Error::io_at(path)))?;
                        writer.finish().map_err(Error::io_at(path))?;
                        Ok(())
                    }),
                };
                if let Err(e) = &result {
                    inbox2.lock().unwrap_or_else(|e| e.into_inner()).error = Some(e.to_string());
                }
                result
            })
            .map_err(|e| Error::Invalid(format!("cannot start the DMX thread: {e}")))?;
        Ok(Receiver {
            inbox,
            stop,
            thread: Some(thread),
            local,
        })
    }

    /// The address it listens at.
    pub fn local_addr(&self) -> SocketAddr {
        self.local
    }

    /// The frames that arrived since the last call, in order, and how many were
    /// dropped since because the inbox was full.
    pub fn take(&self) -> (Vec<Event>, u64) {
        let mut inbox = self.inbox.lock().unwrap_or_else(|e| e.into_inner());
        let dropped = std::mem::take(&mut inbox.dropped);
        (inbox.frames.drain(..).collect(), dropped)
    }

    /// The listener's counts, and its error if it stopped on one.
    pub fn stats(&self) -> (Stats, Option<String>) {
        let inbox = self.inbox.lock().unwrap_or_else(|e| e.into_inner());
        (inbox.stats.clone(), inbox.error.clone())
    }

    /// Stops listening and writes the recording in place.
    pub fn stop(mut self) -> Result<()> {
        self.halt()
    }

    fn halt(&mut self) -> Result<()> {
        self.stop.store(true, Ordering::Relaxed);
        match self.thread.take().map(|t| t.join()) {
            None => Ok(()),
            Some(Ok(result)) => result,
            Some(Err(_)) => Err(Error::Invalid("the DMX thread panicked".into())),
        }
    }
}

/// The listening thread's loop until `stop`: each frame given to `keep` (the
/// recording), then into the inbox, with the listener's counts.
fn pass_on(
    listener: &mut Listener,
    stop: &AtomicBool,
    inbox: &Mutex<Inbox>,
    keep: &mut dyn FnMut(&Event) -> Result<()>,
) -> Result<()> {
    let mut frames = Vec::new();
    while !stop.load(Ordering::Relaxed) {
        listener.receive(POLL, &mut frames)?;
        frames.iter().try_for_each(&mut *keep)?;
        let mut inbox = inbox.lock().unwrap_or_else(|e| e.into_inner());
        for f in frames.drain(..) {
            if inbox.frames.len() == MAX_PENDING {
                inbox.frames.pop_front();
                inbox.dropped += 1;
            }
            inbox.frames.push_back(f);
        }
        inbox.stats = listener.stats().clone();
    }
    Ok(())
}

impl Drop for Receiver {
    fn drop(&mut self) {
        let _ = self.halt();
    }
}
