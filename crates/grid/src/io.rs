use crate::{GridError, Result};
use std::io::Write;
use std::path::{Path, PathBuf};

/// The folder a file at `path` goes in (`.` for a bare file name).
fn folder_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// Writes `bytes` to `path` atomically: into a new temporary file in the same folder, created
/// exclusively under an unpredictable name (so a file or link planted there is never written
/// through), flushed to disk, then renamed over `path`. A reader never sees a half-written
/// file, an existing file is only replaced once the new one is complete, and a symbolic link
/// at `path` is replaced rather than followed. A temporary file that a killed process left in
/// the folder (`.envfield-*.tmp`, untouched for ten minutes) is removed first.
///
/// The file at `path` must not be an input of this run ([`protect_input`]).
///
/// # Errors
/// [`GridError::Io`] naming the path; [`GridError::Invalid`] for a path that names a folder
/// or an input.
pub fn write_atomic(path: impl AsRef<Path>, bytes: &[u8]) -> Result<()> {
    let path = path.as_ref();
    check_file_path(path)?;
    remove_stale_temporaries(&folder_of(path));
    let result = (|| {
        let mut builder = tempfile::Builder::new();
        builder.prefix(TEMP_PREFIX).suffix(TEMP_SUFFIX);
        // The mode a plain `File::create` gives (0666 less the umask), not tempfile's 0600.
        #[cfg(unix)]
        builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
        let mut tmp = builder.tempfile_in(folder_of(path))?;
        tmp.write_all(bytes)?;
        tmp.as_file().sync_all()?;
        tmp.persist(path).map_err(|e| e.error)?;
        Ok(())
    })();
    result.map_err(|e: std::io::Error| GridError::io(path, e))
}

/// The names of [`write_atomic`]'s temporary files: `.envfield-<random>.tmp`.
const TEMP_PREFIX: &str = ".envfield-";
const TEMP_SUFFIX: &str = ".tmp";

/// How long a temporary file goes untouched before it counts as left by a killed write (a
/// write in progress touches its file every few milliseconds).
const STALE_AFTER: std::time::Duration = std::time::Duration::from_secs(600);

/// Removes the temporary files of [`write_atomic`] in `dir` that nobody has touched for
/// [`STALE_AFTER`]: what an interrupted run left (a kill runs no destructor). Best effort: a
/// folder that cannot be listed, or a file that cannot be removed, is left as it is.
fn remove_stale_temporaries(dir: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let name = name.to_string_lossy();
        if !(name.starts_with(TEMP_PREFIX) && name.ends_with(TEMP_SUFFIX)) {
            continue;
        }
        // Only plain files (never a link or folder planted under the pattern).
        let Ok(meta) = entry.path().symlink_metadata() else {
            continue;
        };
        let stale = meta
            .modified()
            .ok()
            .and_then(|m| m.elapsed().ok())
            .is_some_and(|age| age >= STALE_AFTER);
        if meta.file_type().is_file() && stale {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

/// The files this process read its input from and must never write over
/// ([`protect_input`]), by identity (device and inode on Unix, the canonical path elsewhere).
static INPUTS: std::sync::Mutex<Vec<(FileId, PathBuf)>> = std::sync::Mutex::new(Vec::new());

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg(unix)]
struct FileId(u64, u64);
#[derive(Clone, PartialEq, Eq, Debug)]
#[cfg(not(unix))]
struct FileId(PathBuf);

/// The identity of the file at `path` itself (a link is not followed): `None` for no file.
fn file_id(path: &Path, follow: bool) -> Option<FileId> {
    let meta = if follow {
        std::fs::metadata(path)
    } else {
        std::fs::symlink_metadata(path)
    }
    .ok()?;
    if !meta.is_file() {
        return None;
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        Some(FileId(meta.dev(), meta.ino()))
    }
    #[cfg(not(unix))]
    {
        path.canonicalize().ok().map(FileId)
    }
}

/// Marks the file at `path` as an input of this process: from now on [`write_atomic`] and
/// [`check_writable`] refuse to write over it, under any name (a second path to the same
/// file, a hard link); a symbolic link to it may still be replaced, which leaves it as it was.
/// An example calls it on every file a user gave it to read, so that no output flag, no
/// `--out` folder and no file name written into one can replace what the user saved.
/// A path that names no file is ignored.
pub fn protect_input(path: impl AsRef<Path>) {
    let path = path.as_ref();
    if let Some(id) = file_id(path, true) {
        let mut inputs = INPUTS
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        if !inputs.iter().any(|(i, _)| *i == id) {
            inputs.push((id, path.to_path_buf()));
        }
    }
}

/// Refuses `path` when the file there is a protected input ([`protect_input`]).
fn check_not_input(path: &Path) -> Result<()> {
    let Some(id) = file_id(path, false) else {
        return Ok(());
    };
    let inputs = INPUTS
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    match inputs.iter().find(|(i, _)| *i == id) {
        Some((_, input)) => Err(GridError::Invalid(format!(
            "{} is an input of this run ({}): not written over (choose another file or folder)",
            path.display(),
            if input == path {
                "the file read".to_string()
            } else {
                format!("the file read as {}", input.display())
            }
        ))),
        None => Ok(()),
    }
}

/// That `path` names a file (not a folder) in a folder that exists, and not an input of this
/// run ([`protect_input`]).
fn check_file_path(path: &Path) -> Result<()> {
    check_not_input(path)?;
    let text = path.as_os_str().to_string_lossy();
    if path.file_name().is_none() || path.is_dir() || text.ends_with('/') {
        return Err(GridError::Invalid(format!(
            "{} is a folder, not a file path",
            path.display()
        )));
    }
    let dir = folder_of(path);
    if !dir.is_dir() {
        return Err(GridError::io(
            path,
            std::io::Error::new(
                std::io::ErrorKind::NotFound,
                format!("folder {} does not exist", dir.display()),
            ),
        ));
    }
    Ok(())
}

/// Checks, before any work, that a file could be written at `path`: it names a file (not a
/// folder) that is not an input of this run ([`protect_input`]), its folder exists, and a
/// file can be created there. Call it on output paths
/// before a long computation, so a typo fails at once rather than after the work.
///
/// # Errors
/// [`GridError::Invalid`] for a folder or a path without a file name; [`GridError::Io`]
/// naming the path when its folder is missing or cannot be written.
pub fn check_writable(path: impl AsRef<Path>) -> Result<()> {
    let path = path.as_ref();
    check_file_path(path)?;
    tempfile::Builder::new()
        .prefix(".envfield-")
        .tempfile_in(folder_of(path))
        .map(drop)
        .map_err(|e| GridError::io(path, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A protected input is never written over, under its own name or another path to it (a
    /// hard link); a symbolic link to it is replaced, leaving it as it was.
    #[test]
    fn an_input_is_never_written_over() {
        let d = dir("inputs");
        let input = d.join("scene.obj");
        std::fs::write(&input, b"the user's scene").unwrap();
        protect_input(&input);
        let e = write_atomic(&input, b"re-export").unwrap_err().to_string();
        assert!(e.contains("an input of this run"), "{e}");
        assert!(check_writable(&input).is_err());
        let other = d.join("./scene.obj");
        assert!(write_atomic(&other, b"x").is_err());
        let hard = d.join("hard.obj");
        std::fs::hard_link(&input, &hard).unwrap();
        assert!(write_atomic(&hard, b"x")
            .unwrap_err()
            .to_string()
            .contains("scene.obj"));
        #[cfg(unix)]
        {
            let link = d.join("link.obj");
            std::os::unix::fs::symlink(&input, &link).unwrap();
            write_atomic(&link, b"new").unwrap();
            assert_eq!(std::fs::read(&link).unwrap(), b"new");
        }
        assert_eq!(std::fs::read(&input).unwrap(), b"the user's scene");
        write_atomic(d.join("other.obj"), b"fine").unwrap();
    }

    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("envfield-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    /// What a killed write left (a temporary file untouched for an hour) goes at the next
    /// write to the folder; a fresh one (a write in progress elsewhere), other files, and a
    /// folder under the pattern stay.
    #[test]
    fn a_killed_writes_temporary_file_is_removed_by_the_next_write() {
        let dir = dir("stale");
        let stale = dir.join(".envfield-abc123.tmp");
        let fresh = dir.join(".envfield-def456.tmp");
        let other = dir.join("notes.tmp");
        let folder = dir.join(".envfield-folder.tmp");
        for p in [&stale, &fresh, &other] {
            std::fs::write(p, b"half").unwrap();
        }
        std::fs::create_dir_all(&folder).unwrap();
        let hour_ago = std::time::SystemTime::now() - std::time::Duration::from_secs(3600);
        for p in [&stale, &other] {
            let f = std::fs::File::options().write(true).open(p).unwrap();
            f.set_modified(hour_ago).unwrap();
        }
        write_atomic(dir.join("out.bin"), b"done").unwrap();
        assert!(!stale.exists());
        assert!(fresh.exists() && other.exists() && folder.is_dir());
        assert_eq!(std::fs::read(dir.join("out.bin")).unwrap(), b"done");
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn replaces_and_leaves_no_temporary_file() {
        let dir = dir("atomic");
        let p = dir.join("x.txt");
        write_atomic(&p, b"one").unwrap();
        write_atomic(&p, b"two").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"two");
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
        #[cfg(unix)]
        {
            // Readable by others as a plain File::create would leave it (umask aside).
            use std::os::unix::fs::PermissionsExt;
            let plain = dir.join("plain.txt");
            std::fs::write(&plain, b"").unwrap();
            let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
            assert_eq!(mode(&p), mode(&plain));
            std::fs::remove_file(&plain).unwrap();
        }
        assert!(write_atomic(dir.join("missing/x.txt"), b"").is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn a_planted_link_is_never_written_through() {
        let dir = dir("atomic-link");
        let victim = dir.join("victim.txt");
        std::fs::write(&victim, b"keep me").unwrap();
        // The old writer's temporary name, planted as a link to the victim.
        let out = dir.join("f.npy");
        let planted = dir.join(format!(".f.npy.{}.tmp", std::process::id()));
        std::os::unix::fs::symlink(&victim, &planted).unwrap();
        // And a link at the output path itself: it is replaced, not followed.
        let linked_out = dir.join("g.npy");
        std::os::unix::fs::symlink(&victim, &linked_out).unwrap();
        write_atomic(&out, b"new").unwrap();
        write_atomic(&linked_out, b"new").unwrap();
        assert_eq!(std::fs::read(&victim).unwrap(), b"keep me");
        assert_eq!(std::fs::read(&out).unwrap(), b"new");
        assert!(!std::fs::symlink_metadata(&linked_out)
            .unwrap()
            .file_type()
            .is_symlink());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn output_paths_are_checked_before_the_work() {
        let dir = dir("writable");
        assert!(check_writable(dir.join("ok.json")).is_ok());
        let err = check_writable(dir.join("missing/p.json"))
            .unwrap_err()
            .to_string();
        assert!(err.contains("missing"), "{err}");
        let err = check_writable(&dir).unwrap_err().to_string();
        assert!(err.contains("folder"), "{err}");
        assert_eq!(
            std::fs::read_dir(&dir).unwrap().count(),
            0,
            "no file left behind"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
