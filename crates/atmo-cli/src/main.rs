//! The `atmo` program: everything is in the library, so that its command line is
//! fuzzed as it runs.

fn main() {
    atmo_cli::main()
}
