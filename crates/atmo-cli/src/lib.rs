//! `atmo`: render light scattered in the air from the command line.
//!
//! Exit codes: 0 on success, 2 for bad input (a message names the field and the
//! allowed range; no output file is left behind), 1 for anything else.
//!
//! A library with the binary `atmo` over it ([`main`]), so that the command line's
//! reading ([`parse_from`], [`parse_clouds_scene`]) and an animation folder's
//! ([`Manifest::parse`], [`frame_from_bytes`]) are fuzzed as they run
//! (docs/fuzzing.md).

// First: its macros (`outln!`, `note!`) are for every module after it.
#[macro_use]
mod streams;
mod args;
mod backend;
mod bench;
mod commands;
mod output;

pub use output::{frame_from_bytes, Manifest};

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use commands::{assemble, clouds, compare, dmx, inspect, precompute, shafts, sky, sun, view};

/// The command line, read.
#[derive(Parser)]
#[command(
    name = "atmo",
    version,
    about = "Light scattered in the air: the sky with multiple scattering, shafts of light from spotlights in haze, clouds"
)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Memory the run may use for everything whose size depends on the input (maps,
    /// frames, buffers, shadow maps, files): 2G, 512M, 4096 (MiB). Larger requests are
    /// refused before they are made, naming the setting to lower.
    #[arg(long, global = true, value_name = "SIZE", default_value = "2G", value_parser = memory_limit)]
    memory_limit: u64,
}

/// `--memory-limit`: a size of at least [`atmo::budget::MIN_LIMIT_BYTES`].
fn memory_limit(text: &str) -> Result<u64, String> {
    let bytes = atmo::budget::parse_size(text)?;
    atmo::budget::check_limit(bytes).map_err(|e| e.to_string())?;
    Ok(bytes)
}

#[derive(Subcommand)]
enum Command {
    /// Render the sky with multiple scattering (sampling shells and scattering maps).
    Sky(sky::SkyArgs),
    /// Render spotlights in haze: beams, volumetric shadows, gobos (sample planes, or
    /// --reference ray marching).
    Shafts(shafts::ShaftsArgs),
    /// How far two .exr renders are apart: RMS and max in 8-bit levels, and a
    /// difference image.
    Compare(compare::CompareArgs),
    /// Render a particle cloud lit by the sun through a 3-D intensity buffer; still, or
    /// animated with the sun or the wind moving.
    Clouds(clouds::CloudsArgs),
    /// The animated PNG of an animation drawn in chunks (`--frames A..B` on a render
    /// farm), after checking every frame is there and of one animation.
    Assemble(assemble::AssembleArgs),
    /// Precompute tables for real-time drawing: `atmo precompute sky -o earth.atmo-sky`.
    Precompute(precompute::PrecomputeArgs),
    /// What a skylight table holds (parameters, size, terms, error), and with --plots
    /// the pictures that explain it.
    Inspect(inspect::InspectArgs),
    /// An interactive window: `atmo view sky` (every flag of `atmo sky`, and
    /// --frames/--screenshot/--script to run without a person).
    View(view::ViewArgs),
    /// Where the sun is at a place and a time (NREL's SPA) and the sunlight reaching
    /// that point through the atmosphere, as JSON.
    Sun(sun::SunArgs),
    /// Time each method against its baseline in the same run and print the ratios.
    Bench(bench::BenchArgs),
    /// A lighting desk's DMX (sACN, Art-Net): `atmo dmx record` writes what it sends
    /// for `atmo shafts --dmx-file`; `atmo dmx info` says what a recording holds.
    Dmx(dmx::DmxArgs),
}

/// The `atmo` program: reads the command line, runs the command, exits with its code.
pub fn main() {
    // Silences Mesa's device-select layer ("XDG_RUNTIME_DIR is invalid") on headless
    // machines; set before any thread starts, so no other code reads the environment.
    if std::env::var_os("NODEVICE_SELECT").is_none() {
        std::env::set_var("NODEVICE_SELECT", "1");
    }
    // An interrupted run leaves no temporary behind (SIGINT, SIGTERM, SIGHUP); one
    // killed outright leaves them for the next write into the folder to remove.
    let _ = ctrlc::set_handler(|| {
        atmo::files::interrupt();
        note!("atmo: interrupted; nothing was left half-written");
        std::process::exit(130);
    });
    // `atmo ... | head`: a closed pipe ends the run quietly, as it does other Unix
    // tools (Rust ignores SIGPIPE, and printing then panics).
    #[cfg(unix)]
    // SAFETY: called before any other thread starts; SIG_DFL is a valid disposition.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = match parse_from(std::env::args_os().collect()) {
        Ok(cli) => cli,
        Err(Refused::Clap(e)) => e.exit(),
        Err(Refused::Input(message)) => {
            note!("atmo: {message}");
            std::process::exit(2);
        }
    };
    atmo::budget::set_limit(cli.memory_limit).expect("checked by clap");
    let result = match cli.command {
        Command::Sky(args) => sky::run(args).map_err(|e| with_flag(e, sky::FLAGS)),
        Command::Shafts(args) => shafts::run(args),
        Command::Compare(args) => compare::run(args),
        Command::Clouds(args) => clouds::run(args).map_err(|e| with_flag(e, clouds::FLAGS)),
        Command::Assemble(args) => assemble::run(args),
        Command::Precompute(args) => precompute::run(args),
        Command::Inspect(args) => inspect::run(args),
        Command::View(args) => {
            let flags = args.flags();
            view::run(args).map_err(|e| with_flag(e, flags))
        }
        Command::Sun(args) => sun::run(args).map_err(|e| with_flag(e, sky::FLAGS)),
        Command::Bench(args) => bench::run(args),
        Command::Dmx(args) => dmx::run(args),
    };
    if let Err(error) = result {
        if atmo::files::interrupted() {
            // A write refused because of the signal: the handler is exiting.
            loop {
                std::thread::park();
            }
        }
        note!("atmo: {error:#}");
        // Errors of the library are about what the user asked for; others are ours.
        let code = if error.downcast_ref::<atmo::Error>().is_some() {
            2
        } else {
            1
        };
        std::process::exit(code);
    }
}

/// Why a command line was refused: clap's own answer (a usage error, or `--help` and
/// `--version`, which it prints), or atmo's message about a value (exit code 2).
#[derive(Debug)]
pub enum Refused {
    Clap(clap::Error),
    Input(String),
}

/// `argv` with the flags of `atmo clouds --scene FILE` put in just after `clouds`, so
/// the command line's own flags override them.
fn with_scene(
    command: &clap::Command,
    mut argv: Vec<std::ffi::OsString>,
) -> Result<Vec<std::ffi::OsString>, Refused> {
    let Some(at) = argv.iter().position(|a| a == "clouds") else {
        return Ok(argv);
    };
    let scene = argv[at..].iter().enumerate().find_map(|(k, a)| {
        let a = a.to_str()?;
        match a.strip_prefix("--scene") {
            Some("") => argv.get(at + k + 1).map(std::path::PathBuf::from),
            Some(rest) => rest.strip_prefix('=').map(std::path::PathBuf::from),
            None => None,
        }
    });
    let Some(scene) = scene else {
        return Ok(argv);
    };
    let extra = clouds::scene_arguments(&scene, &clouds_flags(command))
        .map_err(|e| Refused::Input(e.to_string()))?;
    argv.splice(at + 1..at + 1, extra.into_iter().map(Into::into));
    Ok(argv)
}

/// The long names of `atmo clouds`' flags: the keys a cloud scene file may set.
fn clouds_flags(command: &clap::Command) -> Vec<&str> {
    command
        .find_subcommand("clouds")
        .expect("clouds is a subcommand")
        .get_arguments()
        .filter_map(|a| a.get_long())
        .collect()
}

/// The command as atmo reads it, where every option's value may start with a hyphen
/// (`--exposure -1`, `--sun-elevation -inf`): such values are numbers to refuse by
/// range, not unknown flags. A later value of a flag replaces an earlier one: a cloud
/// scene's flags go first (`atmo clouds --scene` and `atmo view clouds --scene`).
fn command() -> clap::Command {
    fn hyphen_values(command: clap::Command) -> clap::Command {
        command
            .mut_args(|a| {
                if a.get_action().takes_values() && !a.is_positional() {
                    a.allow_hyphen_values(true)
                } else {
                    a
                }
            })
            .mut_subcommands(hyphen_values)
    }
    hyphen_values(Cli::command())
        .mut_subcommand("clouds", |c| c.args_override_self(true))
        .mut_subcommand("view", |v| {
            v.mut_subcommand("clouds", |c| c.args_override_self(true))
        })
}

/// The command line `argv` (the program's name first) read, a cloud scene's flags
/// included (`--scene`). A negative value for a flag that counts something is refused
/// naming the flag.
pub fn parse_from(argv: Vec<std::ffi::OsString>) -> Result<Cli, Refused> {
    let command = command();
    let argv = with_scene(&command, argv)?;
    matched(command, argv)
}

/// `atmo clouds` with the flags of the cloud scene file `text` (as `--scene` reads
/// one from the current folder), then `argv`: the scene's reading without a file.
pub fn parse_clouds_scene(text: &str, argv: &[&str]) -> Result<Cli, Refused> {
    let command = command();
    let extra = clouds::scene_arguments_of(
        text,
        "scene",
        std::path::Path::new("."),
        &clouds_flags(&command),
    )
    .map_err(|e| Refused::Input(e.to_string()))?;
    let argv = ["atmo", "clouds"]
        .into_iter()
        .map(String::from)
        .chain(extra)
        .chain(argv.iter().map(|a| a.to_string()))
        .map(Into::into)
        .collect();
    matched(command, argv)
}

/// `argv` matched against `command`.
fn matched(command: clap::Command, argv: Vec<std::ffi::OsString>) -> Result<Cli, Refused> {
    let refuse = |error: clap::Error| -> Refused {
        use clap::error::{ContextKind, ContextValue};
        if let (Some(ContextValue::String(arg)), Some(ContextValue::String(value))) = (
            error.get(ContextKind::InvalidArg),
            error.get(ContextKind::InvalidValue),
        ) {
            if value.parse::<f64>().is_ok_and(|v| v < 0.0) {
                let flag = arg.split_whitespace().next().unwrap_or(arg);
                return Refused::Input(format!(
                    "{flag} = {value} is out of range: allowed whole numbers >= 0"
                ));
            }
        }
        Refused::Clap(error)
    };
    let matches = command.try_get_matches_from(argv).map_err(refuse)?;
    Cli::from_arg_matches(&matches).map_err(refuse)
}

/// The library names what was wrong as its own field (`sun.elevation_deg`); where a
/// command's flag sets that field, the message names the flag first, so that the user
/// sees what to change: `--sun-elevation: sun.elevation_deg = 95 is out of range ...`.
fn with_flag(error: anyhow::Error, flags: &[(&str, &str)]) -> anyhow::Error {
    // A field out of range, or the setting a memory budget's message says to lower.
    let field = match error.downcast_ref::<atmo::Error>() {
        Some(atmo::Error::OutOfRange { field, .. }) => field.clone(),
        Some(atmo::Error::OverBudget { setting, .. }) => setting.clone(),
        _ => return error,
    };
    match flags.iter().find(|(f, _)| *f == field) {
        Some((_, flag)) => error.context(flag.to_string()),
        None => error,
    }
}
