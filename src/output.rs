//! Writing a file the user named: whole or not at all, and only ever into
//! what the name points at.
//!
//! A plain file is written beside itself and moved over the old one once
//! complete, so that a failed or interrupted write leaves the older file as
//! it was and no half file. A name that is a link is followed, so the link
//! stays and the file it points at is replaced. A name that is not a plain
//! file (`/dev/null`, `/dev/stdout`, a named pipe) is written straight into:
//! moving a file over it would replace the device itself, which for root
//! turns `/dev/null` into a file that keeps all that is thrown away. A new
//! file keeps the permissions of the one it replaces.
//!
//! Every file the program writes where the user said goes through here:
//! the tree's JSON, sessions, meshes, pictures, the benchmark's CSV. (The
//! explorer's frame log, written line by line while it runs, is not a
//! file made whole.)

use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Writes what `write` produces to `path`, whole or not at all (see the
/// module's notes).
pub fn write_whole(
    path: &Path,
    write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> std::io::Result<()> {
    if is_not_a_place(path) {
        // A device, a pipe or an open file: there is nothing to keep and
        // nothing to replace; the data goes straight in, after what is
        // there (`>>` stays `>>`).
        let mut out = BufWriter::new(std::fs::OpenOptions::new().append(true).open(path)?);
        write(&mut out)?;
        return out.flush();
    }
    let target = followed(path)?;
    let partial = partial_beside(&target);
    let written = std::fs::File::create(&partial).and_then(|file| {
        // The new file keeps the old one's permissions.
        if let Ok(old) = std::fs::metadata(&target) {
            file.set_permissions(old.permissions())?;
        }
        let mut out = BufWriter::new(file);
        write(&mut out)?;
        out.into_inner().map_err(|e| e.into_error())?.sync_all()
    });
    let moved = written.and_then(|_| std::fs::rename(&partial, &target));
    if moved.is_err() {
        let _ = std::fs::remove_file(&partial);
    }
    moved
}

/// Saves `img` to `path` in the format its extension names (PNG, JPEG,
/// ...), whole or not at all as [`write_whole`] writes.
pub fn save_image(path: &Path, img: &image::RgbaImage) -> image::ImageResult<()> {
    let format = image::ImageFormat::from_path(path)?;
    let mut encoded = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut encoded), format)?;
    write_whole(path, |out| out.write_all(&encoded))?;
    Ok(())
}

/// Whether `path` names something that is not a place for a file: a
/// device or a pipe (`/dev/null`, a named pipe), or one of the system's
/// names of a file already open (`/dev/stdout`, `/dev/fd/N`,
/// `/proc/self/fd/N`), perhaps a pipe that has no path at all.
fn is_not_a_place(path: &Path) -> bool {
    let special = std::fs::metadata(path).is_ok_and(|meta| !meta.is_file() && !meta.is_dir());
    let open_file = ["/dev/stdout", "/dev/stderr"]
        .iter()
        .any(|name| path.as_os_str() == *name)
        || path.starts_with("/dev/fd")
        || path.starts_with("/proc");
    special || open_file
}

/// The path that `path` names once its links are followed, even to a file
/// not made yet (a link is kept, and the file it names is what changes).
fn followed(path: &Path) -> std::io::Result<PathBuf> {
    let mut target = path.to_path_buf();
    // As many links in a row as Linux follows before it gives up.
    for _ in 0..40 {
        match std::fs::symlink_metadata(&target) {
            Ok(meta) if meta.file_type().is_symlink() => {
                let next = std::fs::read_link(&target)?;
                target = match target.parent() {
                    // A relative link is read from the link's folder; an
                    // absolute one replaces the path.
                    Some(folder) => folder.join(next),
                    None => next,
                };
            }
            _ => return Ok(target),
        }
    }
    Err(std::io::Error::other("too many levels of links"))
}

/// The name the new file has while it is written: beside the target, in
/// the same folder (so the move is a rename), and this process's own.
fn partial_beside(target: &Path) -> PathBuf {
    let mut name = target.as_os_str().to_owned();
    name.push(format!(".partial-{}", std::process::id()));
    PathBuf::from(name)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    fn write_text(path: &Path, text: &str) -> std::io::Result<()> {
        write_whole(path, |w| w.write_all(text.as_bytes()))
    }

    /// A plain file is replaced whole, keeping its permissions; a failed
    /// write leaves the old one and no partial file; a missing folder is an
    /// error.
    #[test]
    fn a_plain_file_is_replaced_whole_or_kept() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.json");
        std::fs::write(&path, "old").unwrap();
        #[cfg(unix)]
        let mode = |p: &Path| {
            use std::os::unix::fs::PermissionsExt;
            std::fs::metadata(p).unwrap().permissions().mode() & 0o777
        };
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o640)).unwrap();
        }
        write_text(&path, "new").unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "new");
        #[cfg(unix)]
        assert_eq!(mode(&path), 0o640, "the old file's permissions are kept");

        let failed = write_whole(&path, |w| {
            w.write_all(b"half")?;
            Err(std::io::Error::other("the writer gave up"))
        });
        assert!(failed.is_err());
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "new");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);

        assert!(write_text(&dir.path().join("no_such_dir").join("x"), "x").is_err());
    }

    /// Writing through a link changes the file it names and keeps the link.
    #[cfg(unix)]
    #[test]
    fn a_link_is_followed_and_kept() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("real.json");
        let link = dir.path().join("link.json");
        std::fs::write(&file, "old").unwrap();
        std::os::unix::fs::symlink(&file, &link).unwrap();
        write_text(&link, "new").unwrap();
        assert!(
            std::fs::symlink_metadata(&link)
                .unwrap()
                .file_type()
                .is_symlink()
        );
        assert_eq!(std::fs::read_to_string(&file).unwrap(), "new");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);

        // A link to a file not made yet, relative, through a second link.
        let later = dir.path().join("later.json");
        let relative = dir.path().join("relative.json");
        let chained = dir.path().join("chained.json");
        std::os::unix::fs::symlink("later.json", &relative).unwrap();
        std::os::unix::fs::symlink(&relative, &chained).unwrap();
        write_text(&chained, "made").unwrap();
        let is_link = |p: &Path| {
            std::fs::symlink_metadata(p)
                .unwrap()
                .file_type()
                .is_symlink()
        };
        assert!(is_link(&chained) && is_link(&relative));
        assert_eq!(std::fs::read_to_string(&later).unwrap(), "made");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 5);

        // A loop of links is an error, not a hang.
        let a = dir.path().join("a");
        let b = dir.path().join("b");
        std::os::unix::fs::symlink(&b, &a).unwrap();
        std::os::unix::fs::symlink(&a, &b).unwrap();
        assert!(write_text(&a, "x").is_err());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 7);
    }

    /// A named pipe is written into and stays a pipe: moving a file over it
    /// would replace it (as it would replace `/dev/null` for root).
    #[cfg(unix)]
    #[test]
    fn a_named_pipe_is_written_into_not_replaced() {
        use std::os::unix::fs::FileTypeExt;
        let dir = tempfile::tempdir().unwrap();
        let pipe = dir.path().join("pipe");
        let made = std::process::Command::new("mkfifo").arg(&pipe).status();
        if !made.is_ok_and(|s| s.success()) {
            eprintln!("skipped: mkfifo is not available here");
            return;
        }
        // The read end is opened first, without waiting for a writer, so
        // that the write below finds a reader; and should the pipe be
        // replaced, the read end sees no data instead of waiting forever.
        let mut reader = {
            use std::os::unix::fs::OpenOptionsExt;
            std::fs::OpenOptions::new()
                .read(true)
                .custom_flags(libc::O_NONBLOCK)
                .open(&pipe)
                .unwrap()
        };
        write_text(&pipe, "through the pipe").unwrap();
        let mut read = String::new();
        std::io::Read::read_to_string(&mut reader, &mut read).unwrap();
        assert_eq!(read, "through the pipe");
        assert!(std::fs::metadata(&pipe).unwrap().file_type().is_fifo());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }
}
