//! The command line itself (every subcommand's flags and their value parsers: sizes,
//! `--chunk K/N`, `--frames A..B`, `X,Y,Z`, fractions), the arguments separated by NUL
//! bytes: no panic, no allocation past the budget; `parse_from` answers every input
//! with a command or a refusal. Lines naming `--scene` are left to `cloud_scene` (they
//! read a file).
#![no_main]
use std::ffi::OsStr;
use std::os::unix::ffi::OsStrExt as _;

use libfuzzer_sys::fuzz_target;

mod common;

fuzz_target!(|data: &[u8]| {
    common::small_budget();
    let args: Vec<&[u8]> = data.split(|&b| b == 0).collect();
    if args.len() > 64 || args.iter().any(|a| a.starts_with(b"--scene")) {
        return;
    }
    let argv = std::iter::once(OsStr::new("atmo"))
        .chain(args.iter().map(|a| OsStr::from_bytes(a)))
        .map(Into::into)
        .collect();
    let _ = atmo_cli::parse_from(argv);
});
