//! Memory held by a run, measured from outside: the largest resident size of any child
//! this test binary ran (so it holds this one test; `getrusage` has no per-child peak).

mod common;

use common::{atmo, probe_file, scratch, COARSE_SHELLS};

/// The largest peak resident size of the children run so far, bytes.
#[cfg(target_os = "linux")]
fn children_peak_bytes() -> u64 {
    // SAFETY: getrusage writes into the struct it is given.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    assert_eq!(
        unsafe { libc::getrusage(libc::RUSAGE_CHILDREN, &mut usage) },
        0
    );
    usage.ru_maxrss as u64 * 1024
}

/// `--probe` streams its directions in blocks: 50,000 of them held about 5 kB each
/// at once (a 2 M line file passed 5 GB), now a block's worth.
#[cfg(target_os = "linux")]
#[test]
fn probe_directions_stream_in_bounded_memory() {
    let dir = scratch("probe-memory");
    let file = probe_file(&dir, 50_000);
    let o = atmo(
        &[
            &["sky", "--probe", file.to_str().unwrap()][..],
            &COARSE_SHELLS,
        ]
        .concat(),
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(o.stdout.iter().filter(|&&b| b == b'\n').count(), 50_001);
    // Holding every direction's maps took 150 MB; one block of them is a tenth of it.
    let peak = children_peak_bytes();
    assert!(peak < 80 << 20, "peak {} MB", peak >> 20);
    std::fs::remove_dir_all(dir).unwrap();
}
