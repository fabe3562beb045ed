//! Standard output and standard error that never panic. Rust's `println!` and
//! `eprintln!` panic when the stream fails (a full disk behind `> file`, `/dev/full`),
//! which ends the run with exit 101 and leaves its temporaries. Here a failed standard
//! output ends the run cleanly: its temporaries removed, a message tried on standard
//! error, exit 1 (what atmo printed is its result, and it is lost). A failed standard
//! error loses the message, and the run goes on: its results are its files. A closed
//! pipe still ends the run by SIGPIPE, as other Unix tools (main.rs).

use std::fmt;
use std::io::Write as _;

/// Writes `args` on standard output, or ends the run if it cannot be written.
pub fn out(args: fmt::Arguments) {
    let mut stdout = std::io::stdout().lock();
    if let Err(e) = stdout.write_fmt(args).and_then(|()| stdout.flush()) {
        atmo::files::interrupt();
        err(format_args!(
            "atmo: standard output: {e}; what was printed is incomplete\n"
        ));
        std::process::exit(1);
    }
}

/// Writes `args` on standard error if it can.
pub fn err(args: fmt::Arguments) {
    let _ = std::io::stderr().lock().write_fmt(args);
}

/// `println!` on standard output through [`out`].
macro_rules! outln {
    ($($arg:tt)*) => {
        $crate::streams::out(format_args!("{}\n", format_args!($($arg)*)))
    };
}

/// `eprintln!` on standard error through [`err`].
macro_rules! note {
    ($($arg:tt)*) => {
        $crate::streams::err(format_args!("{}\n", format_args!($($arg)*)))
    };
}
