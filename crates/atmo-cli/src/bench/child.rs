//! Cases run as processes of their own (this executable), measured from outside by
//! `wait4`: the child's own CPU time and peak memory, not the bench's.

use std::ffi::{OsStr, OsString};
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::Instant;

use anyhow::{bail, Context, Result};

/// What one process took.
#[derive(Debug, Clone, Copy, Default)]
pub struct Cost {
    /// Wall time, ms.
    pub wall_ms: f64,
    /// User and system time of all its threads, ms.
    pub cpu_ms: f64,
    /// Its peak resident memory, MiB.
    pub peak_mb: f64,
}

impl Cost {
    /// The cost of running `a` then `b`: times add, memory is the larger.
    pub fn then(self, b: Cost) -> Cost {
        Cost {
            wall_ms: self.wall_ms + b.wall_ms,
            cpu_ms: self.cpu_ms + b.cpu_ms,
            peak_mb: self.peak_mb.max(b.peak_mb),
        }
    }
}

/// How a child ended and what it took.
pub struct Run {
    pub cost: Cost,
    /// Its exit code (`None` if a signal ended it).
    pub code: Option<i32>,
    /// What it wrote to standard error.
    pub messages: String,
}

/// Runs this executable with `args` (standard output discarded) and waits for it.
pub fn run(args: &[OsString]) -> Result<Run> {
    let log = tempfile_in_temp("atmo-bench-child.log");
    let stderr = std::fs::File::create(&log).context("the bench's log file")?;
    let start = Instant::now();
    let child = Command::new(std::env::current_exe().context("the atmo executable")?)
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(stderr)
        .spawn()
        .context("starting atmo")?;
    let mut status = 0;
    // SAFETY: a plain libc call on a zeroed rusage; the pid is our own unwaited child.
    let usage = unsafe {
        let mut usage: libc::rusage = std::mem::zeroed();
        if libc::wait4(child.id() as libc::pid_t, &mut status, 0, &mut usage) < 0 {
            bail!("waiting for atmo: {}", std::io::Error::last_os_error());
        }
        usage
    };
    let wall_ms = start.elapsed().as_secs_f64() * 1e3;
    let messages = std::fs::read_to_string(&log).unwrap_or_default();
    let _ = std::fs::remove_file(&log);
    let seconds = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    Ok(Run {
        cost: Cost {
            wall_ms,
            cpu_ms: (seconds(usage.ru_utime) + seconds(usage.ru_stime)) * 1e3,
            // Linux reports ru_maxrss in KiB; to a tenth of a MiB, as every case's.
            peak_mb: (usage.ru_maxrss as f64 / 1024.0 * 10.0).round() / 10.0,
        },
        code: libc::WIFEXITED(status).then(|| libc::WEXITSTATUS(status)),
        messages,
    })
}

/// A path in the system's temporary folder, unique to this process.
pub fn tempfile_in_temp(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("{}-{name}", std::process::id()))
}

/// A command's arguments from strings and paths alike.
pub fn os(items: &[&dyn AsRef<OsStr>]) -> Vec<OsString> {
    items.iter().map(|a| a.as_ref().to_owned()).collect()
}
