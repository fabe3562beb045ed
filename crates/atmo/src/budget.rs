//! One memory budget for a run. Every allocation whose size depends on the input (maps,
//! frames, buffers, shadow maps, files read whole) is checked against it before it is
//! made, and refused with a message naming the input, what it would need and the
//! setting to lower, never an allocation failure that aborts the process.
//!
//! The budget is one number for the process (the CLI's `--memory-limit`), read where a
//! size is checked; library users set it once with [`set_limit`]. What a build already
//! keeps (a scene's gobos, profiles and meshes, read one after another) is counted in
//! the checks made while it reads the next ([`beside`]), so that many files each
//! within the budget cannot add up past it.

use std::cell::RefCell;
use std::sync::atomic::{AtomicU64, Ordering};

use crate::error::{Error, Result};

/// The budget when nothing sets another: 2 GiB.
pub const DEFAULT_LIMIT_BYTES: u64 = 2 << 30;

/// The smallest budget that [`set_limit`] takes, 64 MiB: below it the defaults fail.
pub const MIN_LIMIT_BYTES: u64 = 64 << 20;

static LIMIT: AtomicU64 = AtomicU64::new(DEFAULT_LIMIT_BYTES);

/// Sets the run's budget, bytes; refuses less than [`MIN_LIMIT_BYTES`].
pub fn set_limit(bytes: u64) -> Result<()> {
    check_limit(bytes)?;
    LIMIT.store(bytes, Ordering::Relaxed);
    Ok(())
}

/// Checks that `bytes` may be a budget: at least [`MIN_LIMIT_BYTES`].
pub fn check_limit(bytes: u64) -> Result<()> {
    if bytes < MIN_LIMIT_BYTES {
        return Err(Error::out_of_range(
            "memory_limit",
            format!("{} MiB", bytes >> 20),
            &format!("at least {} MiB", MIN_LIMIT_BYTES >> 20),
        ));
    }
    Ok(())
}

/// The run's budget, bytes.
pub fn limit() -> u64 {
    LIMIT.load(Ordering::Relaxed)
}

thread_local! {
    /// Bytes the thread's current build already holds, and what holds them, outermost
    /// first: see [`beside`].
    static HELD: RefCell<(u64, Vec<&'static str>)> = const { RefCell::new((0, Vec::new())) };
}

/// Runs `work` with `held_bytes` (what the caller keeps while it runs, named `held` in
/// messages) counted in every [`check`] it makes on this thread; nested calls add up.
pub fn beside<T>(held_bytes: u64, held: &'static str, work: impl FnOnce() -> T) -> T {
    /// Puts the outer count back however `work` ends, a panic included.
    struct Restore(u64);
    impl Drop for Restore {
        fn drop(&mut self) {
            HELD.with_borrow_mut(|(bytes, holders)| {
                *bytes = self.0;
                holders.pop();
            });
        }
    }
    let outer = HELD.with_borrow_mut(|(bytes, holders)| {
        let outer = *bytes;
        *bytes = outer.saturating_add(held_bytes);
        holders.push(held);
        outer
    });
    let _restore = Restore(outer);
    work()
}

/// Checks that `needed_bytes`, beside what the build holds ([`beside`]), fits the run's
/// budget, else an [`Error::OverBudget`] naming what needs it and the `setting` to
/// lower.
pub fn check(what: &str, needed_bytes: u64, setting: &str) -> Result<()> {
    let budget_bytes = limit();
    let (held, holder) = HELD.with_borrow(|(bytes, holders)| (*bytes, holders.join(" and ")));
    let total = needed_bytes.saturating_add(held);
    if total <= budget_bytes {
        Ok(())
    } else if held > 0 {
        Err(Error::OverBudget {
            what: format!("{what} beside {holder} ({} MiB)", held.div_ceil(1 << 20)),
            needed_bytes: total,
            budget_bytes,
            setting: format!("{setting}, or {holder}"),
        })
    } else {
        Err(Error::OverBudget {
            what: what.to_string(),
            needed_bytes: total,
            budget_bytes,
            setting: setting.to_string(),
        })
    }
}

/// Parses a size as a user writes it: a number with an optional unit K, M, G or T
/// (binary, `Ki`/`iB` spellings too); a bare number is MiB. `"2G"`, `"512M"`, `"4096"`.
pub fn parse_size(text: &str) -> std::result::Result<u64, String> {
    let t = text.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (number, unit) = t.split_at(split);
    let value: f64 = number
        .parse()
        .map_err(|_| format!("`{text}` is not a size like 2G, 512M or 4096 (MiB)"))?;
    let shift = match unit
        .trim()
        .trim_end_matches("iB")
        .trim_end_matches(['i', 'B'])
    {
        "K" | "k" => 10,
        "" | "M" | "m" => 20,
        "G" | "g" => 30,
        "T" | "t" => 40,
        other => {
            return Err(format!(
                "unknown unit `{other}` in `{text}`: use K, M, G or T"
            ))
        }
    };
    let bytes = value * (1u64 << shift) as f64;
    if bytes.is_finite() && bytes >= 1.0 && bytes < u64::MAX as f64 {
        Ok(bytes as u64)
    } else {
        Err(format!("`{text}` is not a size a machine has"))
    }
}

/// The process's peak resident memory since it started or since [`reset_peak_rss`],
/// bytes (Linux's `VmHWM`); `None` where the system does not say.
pub fn peak_rss_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb << 10)
}

/// Starts the peak of [`peak_rss_bytes`] again from the present (Linux 4.0 and later),
/// so that one bench case measures its own; whether it could.
pub fn reset_peak_rss() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_read_as_users_write_them() {
        assert_eq!(parse_size("2G"), Ok(2 << 30));
        assert_eq!(parse_size("2GiB"), Ok(2 << 30));
        assert_eq!(parse_size("512M"), Ok(512 << 20));
        assert_eq!(parse_size("4096"), Ok(4096 << 20));
        assert_eq!(parse_size("1.5G"), Ok(3 << 29));
        assert_eq!(parse_size("64k"), Ok(64 << 10));
        assert!(parse_size("-1G").is_err());
        assert!(parse_size("2X").is_err());
        assert!(parse_size("").is_err());
    }

    #[test]
    fn what_a_build_holds_counts_in_the_checks_it_makes() {
        let limit = limit();
        assert!(check("a", limit / 2, "x").is_ok());
        let refused = beside(limit / 2 + 1, "the maps", || check("a", limit / 2, "x"));
        let message = refused.unwrap_err().to_string();
        assert!(message.contains("a beside the maps"), "{message}");
        assert!(message.contains("lower x, or the maps"), "{message}");
        // Nested calls add up, and each puts the outer count back.
        beside(limit / 4, "m", || {
            assert!(check("b", limit / 2, "x").is_ok());
            assert!(beside(limit / 4 + 1, "m", || check("b", limit / 2, "x")).is_err());
            assert!(check("b", limit / 2, "x").is_ok());
        });
        assert!(check("a", limit, "x").is_ok());
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn the_peak_follows_what_is_touched() {
        let before = peak_rss_bytes().unwrap();
        let block = vec![1u8; 64 << 20];
        std::hint::black_box(&block);
        let after = peak_rss_bytes().unwrap();
        assert!(after >= before + (60 << 20), "{before} -> {after}");
        drop(block);
        if reset_peak_rss() {
            assert!(peak_rss_bytes().unwrap() < after);
        }
    }
}
