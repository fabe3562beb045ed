//! `atmo dmx`: a desk's DMX recorded without a window (`record`), and what a recording
//! holds (`info`). docs/previz.md says how to connect a desk.

use std::collections::BTreeSet;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use anyhow::Result;
use atmo::shafts::dmx::receiver::{Listener, Settings};
use atmo::shafts::dmx::recording::{self, Reader, Writer};
use atmo::shafts::dmx::wire::Protocol;
use clap::{Args, Subcommand, ValueEnum};

#[derive(Args)]
pub struct DmxArgs {
    #[command(subcommand)]
    command: DmxCommand,
}

#[derive(Subcommand)]
enum DmxCommand {
    /// Listen to a desk and write what it sends, time-stamped, to a .dmx file that
    /// `atmo shafts SCENE --dmx-file` renders offline.
    Record(RecordArgs),
    /// Frames, length and universes of a .dmx recording, and each universe's levels
    /// at its end.
    Info(InfoArgs),
}

/// The protocols a desk sends DMX by.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ProtocolArg {
    /// ANSI E1.31 (streaming ACN), UDP port 5568, multicast or unicast.
    Sacn,
    /// Art-Net (ArtDmx; ArtPoll is answered), UDP port 6454.
    Artnet,
}

impl From<ProtocolArg> for Protocol {
    fn from(p: ProtocolArg) -> Protocol {
        match p {
            ProtocolArg::Sacn => Protocol::Sacn,
            ProtocolArg::Artnet => Protocol::ArtNet,
        }
    }
}

/// Where to listen: the flags `atmo dmx record` and `atmo view stage --dmx` share.
#[derive(Args, Clone)]
pub struct ListenArgs {
    /// Universes to take (repeatable; atmo's numbers: sACN's, Art-Net's port-address
    /// plus one). Default: those the scene patches.
    #[arg(long = "universe", value_name = "N")]
    pub universes: Vec<u32>,
    /// Address (and port) to listen at: 0.0.0.0 (every interface, the default), an
    /// interface's address, or ADDR:PORT (default port: 5568 for sACN, 6454 for
    /// Art-Net).
    #[arg(long, value_name = "ADDR[:PORT]")]
    pub bind: Option<String>,
}

impl ListenArgs {
    /// The listener's settings for `protocol`, with the `patched` universes where
    /// none are given.
    pub fn settings(&self, protocol: Protocol, patched: &BTreeSet<u16>) -> Result<Settings> {
        let universes: BTreeSet<u16> = if self.universes.is_empty() {
            patched.clone()
        } else {
            self.universes
                .iter()
                .map(|&u| {
                    atmo::error::check_range("--universe", u as f64, 1.0, 63999.0)?;
                    Ok(u as u16)
                })
                .collect::<atmo::Result<_>>()?
        };
        if universes.is_empty() {
            return Err(atmo::Error::Invalid(
                "no universe to listen to: give --universe N (or a scene that patches \
                 fixtures)"
                    .into(),
            )
            .into());
        }
        let mut settings = Settings::new(protocol, universes);
        if let Some(bind) = &self.bind {
            let port = settings.bind.port();
            settings.bind = bind
                .parse::<SocketAddr>()
                .or_else(|_| {
                    bind.parse::<std::net::IpAddr>()
                        .map(|ip| SocketAddr::new(ip, port))
                })
                .map_err(|_| {
                    atmo::Error::Invalid(format!(
                        "--bind {bind:?}: allowed an IP address or ADDR:PORT, as 0.0.0.0, \
                         192.168.1.20 or 127.0.0.1:5568"
                    ))
                })?;
        }
        Ok(settings)
    }
}

#[derive(Args)]
pub struct RecordArgs {
    /// The protocol to listen for.
    #[arg(long, value_enum)]
    protocol: ProtocolArg,
    #[command(flatten)]
    listen: ListenArgs,
    /// A scene whose patched universes to listen to (instead of --universe).
    #[arg(long)]
    scene: Option<PathBuf>,
    /// The recording to write (.dmx), in place when the recording ends.
    #[arg(short, long, value_name = "FILE.dmx")]
    output: PathBuf,
    /// Stop after this many seconds.
    #[arg(long, default_value_t = 3600.0)]
    seconds: f64,
    /// Stop once this many seconds pass without a frame, after the first.
    #[arg(long, value_name = "SECONDS")]
    idle: Option<f64>,
}

#[derive(Args)]
pub struct InfoArgs {
    /// A .dmx recording.
    recording: PathBuf,
    /// Also list every frame: its time, universe and levels up to the last non-zero.
    #[arg(long)]
    frames: bool,
}

pub fn run(args: DmxArgs) -> Result<()> {
    match args.command {
        DmxCommand::Record(args) => record(args),
        DmxCommand::Info(args) => info(args),
    }
}

/// The universes a scene file's fixtures are patched in.
pub fn patched_universes(scene: &atmo::shafts::Scene) -> BTreeSet<u16> {
    scene
        .show
        .fixtures
        .iter()
        .filter_map(|f| f.patch.as_ref().map(|p| p.universe))
        .collect()
}

fn record(args: RecordArgs) -> Result<()> {
    atmo::error::check_range("--seconds", args.seconds, 0.01, 1e6)?;
    if let Some(idle) = args.idle {
        atmo::error::check_range("--idle", idle, 0.01, 1e6)?;
    }
    atmo::files::check_folder(&args.output)?;
    let patched = match &args.scene {
        Some(path) => patched_universes(&atmo::shafts::edits::load(path, &[])?),
        None => BTreeSet::new(),
    };
    let settings = args.listen.settings(args.protocol.into(), &patched)?;
    let universes = settings.universes.clone();
    let start = Instant::now();
    let mut listener = Listener::bind(settings, start)?;
    note!(
        "atmo: listening at {} for universe(s) {}; recording to {} for up to {} s{}",
        listener.local_addr(),
        universes
            .iter()
            .map(u16::to_string)
            .collect::<Vec<_>>()
            .join(", "),
        args.output.display(),
        args.seconds,
        args.idle.map_or(String::new(), |s| format!(
            " or until {s} s pass without a frame"
        ))
    );
    if let Some(why) = &listener.stats().multicast_failed {
        note!("atmo: multicast not joined ({why}); unicast sACN still arrives");
    }
    let (end, idle) = (
        Duration::from_secs_f64(args.seconds),
        args.idle.map(Duration::from_secs_f64),
    );
    let mut frames = Vec::new();
    let mut count = 0u64;
    let mut last_frame: Option<Instant> = None;
    atmo::files::write_atomically(&args.output, |out| {
        let mut writer = Writer::new(out).map_err(atmo::Error::io_at(&args.output))?;
        loop {
            let now = Instant::now();
            if now - start >= end || idle.zip(last_frame).is_some_and(|(i, t)| now - t >= i) {
                break;
            }
            listener.receive(Duration::from_millis(50), &mut frames)?;
            for f in frames.drain(..) {
                writer.write(&f).map_err(atmo::Error::io_at(&args.output))?;
                count += 1;
                last_frame = Some(Instant::now());
            }
        }
        writer.finish().map_err(atmo::Error::io_at(&args.output))?;
        Ok(())
    })?;
    let stats = listener.stats();
    note!(
        "{}: {count} frames from {} datagrams ({} ignored{})",
        args.output.display(),
        stats.datagrams,
        stats.ignored,
        stats
            .last_ignored
            .as_ref()
            .map_or(String::new(), |w| format!("; the last: {w}"))
    );
    Ok(())
}

fn info(args: InfoArgs) -> Result<()> {
    let origin = args.recording.display().to_string();
    let bytes = atmo::files::read_bounded(
        &args.recording,
        "DMX recording",
        atmo::files::DATA_LIMIT_BYTES,
    )?;
    let mut last = std::collections::BTreeMap::new();
    let (mut frames, mut end_us) = (0u64, 0u64);
    for event in Reader::new(&bytes, &origin)? {
        let event = event?;
        if args.frames {
            outln!(
                "frame {frames}: {:.6} s, universe {}: {}",
                event.time_us as f64 * 1e-6,
                event.universe,
                used(&event.levels)
            );
        }
        frames += 1;
        end_us = event.time_us;
        last.insert(event.universe, event.levels);
    }
    outln!(
        "{origin}: {frames} frames over {:.3} s, {} bytes (format {:?})",
        end_us as f64 * 1e-6,
        bytes.len(),
        std::str::from_utf8(&recording::MAGIC[..8]).unwrap_or("")
    );
    for (universe, levels) in &last {
        outln!("universe {universe} at the end: {}", used(levels));
    }
    Ok(())
}

/// A universe's levels up to its last non-zero channel, as `channels 1-N: L1 L2 ...`.
fn used(levels: &atmo::shafts::dmx::Levels) -> String {
    let n = levels.iter().rposition(|&l| l != 0).map_or(0, |k| k + 1);
    let list: Vec<String> = levels[..n].iter().map(u8::to_string).collect();
    format!("channels 1-{n}: {}", list.join(" "))
}
