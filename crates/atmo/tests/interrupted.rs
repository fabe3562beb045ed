//! A write interrupted by a signal leaves nothing: the CLI's handler calls
//! `atmo::files::interrupt`. Its own test binary, because it removes every
//! temporary of the process.

use std::io::Write;

#[test]
fn a_signal_mid_write_removes_the_temporary_and_keeps_the_old_file() {
    let dir = std::env::temp_dir().join(format!("atmo-interrupted-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("out.txt");
    std::fs::write(&path, b"old").unwrap();
    let count = || std::fs::read_dir(&dir).unwrap().count();
    let result = atmo::files::write_atomically(&path, |w| {
        w.write_all(b"half").unwrap();
        assert_eq!(count(), 2, "the temporary is beside the file");
        atmo::files::interrupt();
        assert_eq!(count(), 1);
        Ok(())
    });
    assert!(result.is_err(), "the rename of a removed temporary fails");
    assert_eq!(std::fs::read(&path).unwrap(), b"old");
    assert_eq!(count(), 1);
    // And nothing more is written.
    assert!(atmo::files::interrupted());
    let later = atmo::files::write_atomically(&dir.join("later.txt"), |_| Ok(()));
    assert!(later.unwrap_err().to_string().contains("interrupted"));
    assert_eq!(count(), 1);
    std::fs::remove_dir_all(dir).unwrap();
}
