// Shared by every target: a small memory budget, so that a reader that allocates past
// it without asking is caught by libFuzzer's -malloc_limit_mb (run.sh sets 512 MB).

/// Sets the run's budget to 256 MiB (once; cheap after).
pub fn small_budget() {
    atmo::budget::set_limit(256 << 20).expect("256 MiB is a valid budget");
}
