//! Files in and out, safely. Every input is read through one bounded reader (a stated
//! limit per kind of file and the run's memory budget; an endless or huge file is a
//! clear error, never an aborted allocation). Every output is written atomically
//! through a temporary beside it, named `.atmo-PID-N.tmp` (folders too), that is removed
//! on error, by [`interrupt`] (the CLI calls it on SIGINT and SIGTERM), or by
//! the next write into the same folder once its process is gone (after SIGKILL or a
//! power cut). Writing goes through a symbolic link to its target and keeps the
//! target's permissions.

use std::collections::HashSet;
use std::fs::File;
use std::io::{BufWriter, Read, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

use crate::error::{Error, Result};

/// Largest parameter file (atmosphere, scene, probe directions), bytes: 64 MiB.
pub const TEXT_LIMIT_BYTES: u64 = 64 << 20;

/// Largest data file (OBJ mesh, particles, table), bytes: 1 GiB, and never more than
/// the run's memory budget ([`crate::budget`]).
pub const DATA_LIMIT_BYTES: u64 = 1 << 30;

/// Temporaries this process has open, removed by [`interrupt`].
static LIVE: Mutex<Live> = Mutex::new(Live {
    paths: Vec::new(),
    interrupted: false,
});

struct Live {
    paths: Vec<PathBuf>,
    interrupted: bool,
}

/// Folders already swept of stale temporaries by this process.
static SWEPT: Mutex<Option<HashSet<PathBuf>>> = Mutex::new(None);

/// Reads the whole file `path` (a `what`, for messages), refusing one longer than
/// `limit` bytes or than the run's memory budget; reads at most one byte past the
/// limit, so a file that never ends (a FIFO, `/dev/zero`) stops there.
pub fn read_bounded(path: &Path, what: &str, limit: u64) -> Result<Vec<u8>> {
    let budget = crate::budget::limit();
    let too_long = || {
        let why = if budget < limit {
            " (the memory budget; raise --memory-limit)"
        } else {
            ""
        };
        Error::Invalid(format!(
            "{}: the {what} is longer than the limit of {} MiB{why}",
            path.display(),
            limit.min(budget) >> 20
        ))
    };
    let limit = limit.min(budget);
    let file = File::open(path).map_err(Error::io_at(path))?;
    // A file that says its length is refused before anything is read.
    if file
        .metadata()
        .is_ok_and(|m| m.is_file() && m.len() > limit)
    {
        return Err(too_long());
    }
    let mut bytes = Vec::new();
    file.take(limit + 1)
        .read_to_end(&mut bytes)
        .map_err(Error::io_at(path))?;
    if bytes.len() as u64 > limit {
        return Err(too_long());
    }
    Ok(bytes)
}

/// Largest TOML file (scene, atmosphere, cloud scene), bytes: 16 MiB, far past what a
/// person writes (a three-minute show with a cue every tenth of a second is 150 kB).
pub const TOML_LIMIT_BYTES: u64 = 16 << 20;

/// Memory a TOML file takes parsed (its editable tree, then its typed values), bytes
/// per byte of text: 47 measured for a 5 MB scene of cues (235 MB over the program's
/// own), charged at 64.
pub const TOML_PARSED_BYTES_PER_BYTE: u64 = 64;

/// [`read_text`] for a TOML file (a `what`), whose parsing is charged to the run's
/// memory budget before it is parsed: a file too large for it is refused, naming it.
pub fn read_toml(path: &Path, what: &str) -> Result<String> {
    let text = read_text(path, what, TOML_LIMIT_BYTES)?;
    crate::budget::check(
        &format!(
            "the {what} {} ({} kB) parsed",
            path.display(),
            text.len() >> 10
        ),
        text.len() as u64 * TOML_PARSED_BYTES_PER_BYTE,
        "the file's size",
    )?;
    Ok(text)
}

/// [`read_bounded`] for UTF-8 text.
pub fn read_text(path: &Path, what: &str, limit: u64) -> Result<String> {
    String::from_utf8(read_bounded(path, what, limit)?)
        .map_err(|_| Error::Invalid(format!("{}: the {what} is not UTF-8 text", path.display())))
}

/// Checks, before any work, that the folder `path` would be written into exists, so a
/// long computation does not end in a failed write, and that `path` is not a device, a
/// FIFO or a socket ([`write_atomically`] refuses those too, and folders).
pub fn check_folder(path: &Path) -> Result<()> {
    if let Ok(m) = std::fs::metadata(resolve(path)) {
        if !m.is_file() && !m.is_dir() {
            return Err(not_a_file(path, &m));
        }
    }
    let folder = folder_of(path);
    if folder.is_dir() {
        Ok(())
    } else {
        Err(Error::Io {
            path: path.to_path_buf(),
            error: std::io::Error::new(
                std::io::ErrorKind::NotFound,
                format!("the folder {} does not exist", folder.display()),
            ),
        })
    }
}

/// Refuses an output that is one of the inputs (it would be overwritten before, or
/// while, it is read): `inputs` are (what names it, path) pairs, e.g. a flag.
pub fn check_distinct(output: &Path, inputs: &[(&str, &Path)]) -> Result<()> {
    let Ok(out) = output.canonicalize() else {
        return Ok(()); // not there yet: not an input
    };
    for (flag, input) in inputs {
        if input.canonicalize().is_ok_and(|i| i == out) {
            return Err(Error::Invalid(format!(
                "{}: the output is also an input ({flag}); write somewhere else",
                output.display()
            )));
        }
    }
    Ok(())
}

fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// The path a write to `path` lands on: a symbolic link's target (followed to the end),
/// so the link stays a link.
fn resolve(path: &Path) -> PathBuf {
    match std::fs::symlink_metadata(path) {
        Ok(m) if m.file_type().is_symlink() => path.canonicalize().unwrap_or(path.into()),
        _ => path.to_path_buf(),
    }
}

/// A fresh temporary name beside `path`, short (any file name the system allows can be
/// written) and recognisable; registered until [`release`]d. None is made once the run
/// is [`interrupt`]ed.
fn temporary_beside(path: &Path) -> Result<PathBuf> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let mut live = LIVE.lock().unwrap_or_else(|e| e.into_inner());
    if live.interrupted {
        return Err(Error::Invalid(format!(
            "{}: not written, the run was interrupted",
            path.display()
        )));
    }
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let tmp = path.with_file_name(format!(".atmo-{}-{n}.tmp", std::process::id()));
    live.paths.push(tmp.clone());
    Ok(tmp)
}

fn release(tmp: &Path) {
    LIVE.lock()
        .unwrap_or_else(|e| e.into_inner())
        .paths
        .retain(|t| t != tmp);
}

/// Stops the run's writing, for a signal handler: no temporary is made from now on, and
/// those open are removed (files and folders), twice 50 ms apart so that a write
/// between naming its temporary and creating it is caught. Afterwards the process
/// should exit.
pub fn interrupt() {
    let open = {
        let mut live = LIVE.lock().unwrap_or_else(|e| e.into_inner());
        live.interrupted = true;
        std::mem::take(&mut live.paths)
    };
    for sweep in 0..2 {
        if sweep > 0 {
            std::thread::sleep(std::time::Duration::from_millis(50));
        }
        for tmp in open.iter().rev() {
            remove_temporary(tmp);
        }
    }
}

/// Removes a temporary, a file or a folder with what it holds, if it is there.
fn remove_temporary(path: &Path) {
    let _ = std::fs::remove_file(path).or_else(|_| std::fs::remove_dir_all(path));
}

/// Whether the run was [`interrupt`]ed (its writes then fail; the signal, not their
/// error, is the news).
pub fn interrupted() -> bool {
    LIVE.lock().unwrap_or_else(|e| e.into_inner()).interrupted
}

/// Removes from `folder` the temporaries of atmo processes that are gone (killed
/// without a chance to clean up); once per folder and process.
pub fn remove_stale_temporaries(folder: &Path) {
    {
        let mut swept = SWEPT.lock().unwrap_or_else(|e| e.into_inner());
        if !swept
            .get_or_insert_with(HashSet::new)
            .insert(folder.to_path_buf())
        {
            return;
        }
    }
    let Ok(entries) = std::fs::read_dir(folder) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) = name.to_str().and_then(temporary_pid) else {
            continue;
        };
        if pid != std::process::id() && !process_alive(pid, &entry.path()) {
            remove_temporary(&entry.path());
        }
    }
}

/// The PID in a temporary's name `.atmo-PID-N.tmp`, or `None` for any other name.
fn temporary_pid(name: &str) -> Option<u32> {
    let rest = name.strip_prefix(".atmo-")?.strip_suffix(".tmp")?;
    let (pid, n) = rest.split_once('-')?;
    n.parse::<u64>().ok()?;
    pid.parse().ok()
}

/// Whether the process `pid` that made `temporary` may still be writing it: on Linux
/// whether it runs; elsewhere whether the file changed in the last day.
fn process_alive(pid: u32, temporary: &Path) -> bool {
    let proc = Path::new("/proc");
    if proc.join("self").exists() {
        return proc.join(pid.to_string()).exists();
    }
    std::fs::metadata(temporary)
        .and_then(|m| m.modified())
        .ok()
        .and_then(|t| t.elapsed().ok())
        .is_none_or(|age| age.as_secs() < 86_400)
}

/// Runs `write(temporary, target)` with a fresh temporary beside `path`'s target (a
/// link followed) that is removed if `write` fails; `what` names `path`'s kind.
fn through_temporary<T>(
    path: &Path,
    what: &str,
    write: impl FnOnce(&Path, &Path) -> Result<T>,
) -> Result<T> {
    if path.file_name().is_none() {
        return Err(Error::Invalid(format!(
            "{}: not a {what} name",
            path.display()
        )));
    }
    let target = resolve(path);
    remove_stale_temporaries(folder_of(&target));
    let tmp = temporary_beside(&target)?;
    let result = write(&tmp, &target);
    if result.is_err() {
        remove_temporary(&tmp);
    }
    // A file of a set written together stays registered until the set is renamed.
    if result.is_err() || !is_deferred(&tmp) {
        release(&tmp);
    }
    result
}

/// A file of a set ([`write_together`]) written to its temporary, to be renamed to
/// `target` (for `path`) with the others.
struct Deferred {
    tmp: PathBuf,
    target: PathBuf,
    path: PathBuf,
}

thread_local! {
    /// The files of the set this thread is writing, if it is writing one.
    static SET: std::cell::RefCell<Option<Vec<Deferred>>> = const { std::cell::RefCell::new(None) };
}

fn is_deferred(tmp: &Path) -> bool {
    SET.with(|s| {
        s.borrow()
            .as_ref()
            .is_some_and(|set| set.iter().any(|d| d.tmp == tmp))
    })
}

/// Renames the complete temporary `tmp` to `target`, or, inside [`write_together`],
/// leaves it for the set's renaming.
fn put_in_place(tmp: &Path, target: &Path, path: &Path) -> Result<()> {
    let deferred = SET.with(|s| match s.borrow_mut().as_mut() {
        Some(set) => {
            set.push(Deferred {
                tmp: tmp.to_path_buf(),
                target: target.to_path_buf(),
                path: path.to_path_buf(),
            });
            true
        }
        None => false,
    });
    if deferred {
        Ok(())
    } else {
        std::fs::rename(tmp, target).map_err(Error::io_at(path))
    }
}

/// Runs `write` with every file it writes ([`write_atomically`], and so
/// [`crate::image::Frame::write`]) held back as one set: each is written whole to its
/// temporary, and only once `write` succeeds are they all renamed into place, with an
/// interrupt ([`interrupt`]) held off until the last, so after an error or a signal
/// the old files stand, all of them, or the new ones do (cube faces, plots). A rename
/// that fails part way (a file system error, not a signal) is said, naming its file.
pub fn write_together<T>(write: impl FnOnce() -> Result<T>) -> Result<T> {
    SET.with(|s| {
        let mut set = s.borrow_mut();
        assert!(set.is_none(), "write_together is not nested");
        *set = Some(Vec::new());
    });
    let result = write();
    let set = SET.with(|s| s.borrow_mut().take()).unwrap_or_default();
    let renamed = result.and_then(|value| {
        let mut live = LIVE.lock().unwrap_or_else(|e| e.into_inner());
        if live.interrupted {
            return Err(Error::Invalid(
                "not written, the run was interrupted".to_string(),
            ));
        }
        let renamed = set
            .iter()
            .try_for_each(|d| std::fs::rename(&d.tmp, &d.target).map_err(Error::io_at(&d.path)));
        live.paths.retain(|p| !set.iter().any(|d| &d.tmp == p));
        renamed.map(|()| value)
    });
    for d in &set {
        // Those of a failed set (a renamed one is not there any more).
        remove_temporary(&d.tmp);
        release(&d.tmp);
    }
    renamed
}

/// The error for an output `path` that is there and not a regular file (`m`): the
/// rename would replace it, a device or a FIFO too (as root, `-o /dev/full` once
/// replaced the device with a file).
fn not_a_file(path: &Path, m: &std::fs::Metadata) -> Error {
    let kind = special_kind(m.file_type());
    Error::Invalid(format!(
        "{}: the output is {kind}, which atmo does not replace; name a regular file, new or old",
        path.display()
    ))
}

/// What a file that is not a regular file is, for messages.
#[cfg(unix)]
fn special_kind(t: std::fs::FileType) -> &'static str {
    use std::os::unix::fs::FileTypeExt as _;
    match () {
        _ if t.is_dir() => "a folder",
        _ if t.is_char_device() || t.is_block_device() => "a device",
        _ if t.is_fifo() => "a FIFO",
        _ if t.is_socket() => "a socket",
        _ => "not a regular file",
    }
}

#[cfg(not(unix))]
fn special_kind(t: std::fs::FileType) -> &'static str {
    if t.is_dir() {
        "a folder"
    } else {
        "not a regular file"
    }
}

/// Writes `path` through `fill` into a temporary file beside it, then renames it into
/// place; on any error the temporary file is removed and `path` is left untouched. A
/// symbolic link is written through, and an existing file keeps its permissions. A
/// `path` that is there and not a regular file (a device, a FIFO, a folder) is refused
/// before anything is written.
pub fn write_atomically(
    path: &Path,
    fill: impl FnOnce(&mut BufWriter<File>) -> Result<()>,
) -> Result<()> {
    through_temporary(path, "file", |tmp, target| {
        // What is there now: a regular file keeps its permissions, anything else is
        // refused before the temporary is made.
        let old = std::fs::metadata(target).ok();
        if let Some(m) = old.as_ref().filter(|m| !m.is_file()) {
            return Err(not_a_file(path, m));
        }
        let file = File::create(tmp).map_err(Error::io_at(tmp))?;
        let mut w = BufWriter::new(file);
        fill(&mut w)?;
        w.flush().map_err(Error::io_at(tmp))?;
        if let Some(old) = old {
            w.get_ref()
                .set_permissions(old.permissions())
                .map_err(Error::io_at(tmp))?;
        }
        w.get_ref().sync_all().map_err(Error::io_at(tmp))?;
        put_in_place(tmp, target, path)
    })
}

/// Writes the files of the folder `folder` through `fill`, given a temporary folder
/// beside it to write into; at the end the temporary becomes `folder` (or, where
/// `folder` exists, its files move into it, leaving the folder's other files alone).
/// On any error, or a signal, nothing of the new files is left.
pub fn write_folder_atomically<T>(
    folder: &Path,
    fill: impl FnOnce(&Path) -> Result<T>,
) -> Result<T> {
    through_temporary(folder, "folder", |tmp, target| {
        std::fs::create_dir(tmp).map_err(Error::io_at(tmp))?;
        let value = fill(tmp)?;
        if target.is_dir() {
            for entry in std::fs::read_dir(tmp).map_err(Error::io_at(tmp))? {
                let from = entry.map_err(Error::io_at(tmp))?.path();
                let to = target.join(from.file_name().expect("a folder's entry"));
                std::fs::rename(&from, &to).map_err(Error::io_at(&to))?;
            }
            std::fs::remove_dir(tmp).map_err(Error::io_at(tmp))?;
        } else {
            std::fs::rename(tmp, target).map_err(Error::io_at(folder))?;
        }
        Ok(value)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("atmo-files-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn names(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    fn put(w: &mut BufWriter<File>, bytes: &[u8]) -> Result<()> {
        w.write_all(bytes).map_err(Error::io_at(Path::new("test")))
    }

    #[test]
    fn outputs_that_are_not_regular_files_are_refused_and_left_alone() {
        let dir = scratch("not-files");
        let folder = dir.join("a-folder");
        std::fs::create_dir(&folder).unwrap();
        let e = write_atomically(&folder, |w| put(w, b"x")).unwrap_err();
        assert!(e.to_string().contains("is a folder"), "{e}");
        assert!(folder.is_dir());
        #[cfg(unix)]
        {
            use std::os::unix::fs::FileTypeExt as _;
            // A device (and a link to one, as /proc/self/fd links are): refused early
            // and at the write, never replaced.
            let link = dir.join("null-link");
            std::os::unix::fs::symlink("/dev/null", &link).unwrap();
            for path in [Path::new("/dev/null"), link.as_path()] {
                let early = check_folder(path).unwrap_err();
                assert!(early.to_string().contains("is a device"), "{early}");
                let e = write_atomically(path, |w| put(w, b"x")).unwrap_err();
                assert!(e.to_string().contains("is a device"), "{e}");
            }
            assert!(std::fs::metadata("/dev/null")
                .unwrap()
                .file_type()
                .is_char_device());
        }
        // A regular file, and a folder for a folder's output, pass the early check.
        check_folder(&folder).unwrap();
        check_folder(&dir.join("new.png")).unwrap();
        let expected = if cfg!(unix) { 2 } else { 1 }; // the folder, and the link
        assert_eq!(names(&dir).len(), expected, "a temporary was left");
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn files_written_together_all_appear_or_none() {
        let dir = scratch("together");
        let (a, b) = (dir.join("a.txt"), dir.join("b.txt"));
        std::fs::write(&a, "old a").unwrap();
        std::fs::write(&b, "old b").unwrap();
        // The second file fails after the first is complete: neither is replaced.
        let failed = write_together(|| {
            write_atomically(&a, |w| put(w, b"new a"))?;
            assert_eq!(
                std::fs::read_to_string(&a).unwrap(),
                "old a",
                "renamed early"
            );
            write_atomically(&b, |_| Err(Error::Invalid("disk full".into())))
        });
        assert!(failed.is_err());
        assert_eq!(std::fs::read_to_string(&a).unwrap(), "old a");
        assert_eq!(std::fs::read_to_string(&b).unwrap(), "old b");
        assert_eq!(names(&dir), ["a.txt", "b.txt"], "a temporary was left");
        // Both complete: both replaced, and a value comes back.
        let n = write_together(|| {
            write_atomically(&a, |w| put(w, b"new a"))?;
            write_atomically(&b, |w| put(w, b"new b"))?;
            Ok(2)
        });
        assert_eq!(n.unwrap(), 2);
        assert_eq!(std::fs::read_to_string(&a).unwrap(), "new a");
        assert_eq!(std::fs::read_to_string(&b).unwrap(), "new b");
        assert_eq!(names(&dir), ["a.txt", "b.txt"]);
        let live = LIVE.lock().unwrap().paths.clone();
        assert!(
            !live.iter().any(|p| p.starts_with(&dir)),
            "still registered"
        );
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn the_longest_file_names_can_be_written() {
        let dir = scratch("long");
        // 251 characters and ".exr": the most most file systems allow.
        let path = dir.join(format!("{}.exr", "a".repeat(251)));
        write_atomically(&path, |w| put(w, b"x")).unwrap();
        assert_eq!(names(&dir).len(), 1, "a temporary was left");
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn reads_stop_at_their_limit() {
        let dir = scratch("bounded");
        let path = dir.join("big.txt");
        std::fs::write(&path, vec![b'a'; 1000]).unwrap();
        assert_eq!(read_bounded(&path, "file", 1000).unwrap().len(), 1000);
        let e = read_text(&path, "scene file", 999).unwrap_err().to_string();
        assert!(e.contains("scene file is longer than the limit"), "{e}");
        std::fs::write(&path, [0xff, 0xfe]).unwrap();
        assert!(read_text(&path, "file", 10)
            .unwrap_err()
            .to_string()
            .contains("not UTF-8"));
        std::fs::remove_dir_all(dir).unwrap();
        // A file that never ends stops at the limit.
        #[cfg(target_os = "linux")]
        assert!(read_bounded(Path::new("/dev/zero"), "file", 1 << 20).is_err());
    }

    #[test]
    fn temporaries_of_gone_processes_are_swept_and_live_ones_kept() {
        let dir = scratch("stale");
        // PID 0 is never a user process; this process's own temporaries stay.
        let stale = dir.join(".atmo-0-7.tmp");
        std::fs::write(&stale, b"half").unwrap();
        std::fs::create_dir(dir.join(".atmo-0-8.tmp")).unwrap();
        let own = dir.join(format!(".atmo-{}-99.tmp", std::process::id()));
        std::fs::write(&own, b"mine").unwrap();
        std::fs::write(dir.join(".atmo-notes.tmp"), b"not ours").unwrap();
        write_atomically(&dir.join("out.txt"), |w| put(w, b"new")).unwrap();
        let own_name = own.file_name().unwrap().to_string_lossy().into_owned();
        let mut expected = vec![".atmo-notes.tmp".to_string(), own_name, "out.txt".into()];
        expected.sort();
        assert_eq!(names(&dir), expected);
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn a_failed_write_leaves_nothing_and_the_old_file_whole() {
        let dir = scratch("failed");
        let path = dir.join("out.txt");
        std::fs::write(&path, b"old").unwrap();
        let e = write_atomically(&path, |w| {
            put(w, b"half")?;
            Err(Error::Invalid("disk full".into()))
        });
        assert!(e.is_err());
        assert_eq!(std::fs::read(&path).unwrap(), b"old");
        assert_eq!(names(&dir), ["out.txt"]);
        assert_eq!(std::fs::read(&path).unwrap(), b"old");
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn links_are_written_through_and_permissions_kept() {
        use std::os::unix::fs::PermissionsExt;
        let dir = scratch("link");
        let real = dir.join("real.txt");
        std::fs::write(&real, b"old").unwrap();
        std::fs::set_permissions(&real, std::fs::Permissions::from_mode(0o640)).unwrap();
        let link = dir.join("link.txt");
        std::os::unix::fs::symlink(&real, &link).unwrap();
        write_atomically(&link, |w| put(w, b"new")).unwrap();
        assert!(std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink());
        assert_eq!(std::fs::read(&real).unwrap(), b"new");
        let mode = std::fs::metadata(&real).unwrap().permissions().mode();
        assert_eq!(mode & 0o777, 0o640);
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn folders_appear_whole_or_not_at_all() {
        let dir = scratch("folder");
        let frames = dir.join("frames");
        let e = write_folder_atomically(&frames, |tmp| {
            std::fs::write(tmp.join("frame-0000.png"), b"1").unwrap();
            Err::<(), _>(Error::Invalid("frame 1 failed".into()))
        });
        assert!(e.is_err());
        assert!(names(&dir).is_empty(), "{:?}", names(&dir));
        write_folder_atomically(&frames, |tmp| {
            std::fs::write(tmp.join("frame-0000.png"), b"1").map_err(Error::io_at(tmp))
        })
        .unwrap();
        assert_eq!(names(&frames), ["frame-0000.png"]);
        // Into an existing folder: the new files join what is there.
        std::fs::write(frames.join("notes.txt"), b"mine").unwrap();
        write_folder_atomically(&frames, |tmp| {
            std::fs::write(tmp.join("frame-0000.png"), b"2").map_err(Error::io_at(tmp))
        })
        .unwrap();
        assert_eq!(names(&frames), ["frame-0000.png", "notes.txt"]);
        assert_eq!(std::fs::read(frames.join("frame-0000.png")).unwrap(), b"2");
        assert_eq!(names(&dir), ["frames"]);
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn an_output_that_is_an_input_is_refused() {
        let dir = scratch("distinct");
        let a = dir.join("a.exr");
        std::fs::write(&a, b"x").unwrap();
        let same = dir.join(".").join("a.exr");
        let e = check_distinct(&same, &[("--particles", &a)]).unwrap_err();
        assert!(e.to_string().contains("--particles"), "{e}");
        check_distinct(&dir.join("b.exr"), &[("--particles", &a)]).unwrap();
        std::fs::remove_dir_all(dir).unwrap();
    }
}
