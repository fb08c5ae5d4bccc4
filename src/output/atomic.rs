//! Output files appear whole or not at all, and only where the user meant them.
//!
//! - Every output is staged in a temporary file beside its target and renamed into place at the end;
//!   several outputs of one run are staged together ([`Outputs`]) and renamed only once all were written,
//!   so a failed run leaves none of its outputs behind and every file that existed before untouched.
//! - Only regular files are written. A directory, FIFO, socket or device given as an output is refused
//!   (replacing `/dev/null` or a named pipe with a regular file is never what was meant).
//! - A symbolic link to a regular file is written *through*: its target is replaced atomically and the link
//!   stays. That is what the shell's `>` and `cp` do, so a link pointing an output elsewhere (a results
//!   directory, another disk) keeps working; replacing the link by a file would silently cut that tie. A link
//!   to nothing (dangling) or to a special file is refused.
//! - No two outputs of a run, and no output and an input, may be the same file: names are compared after
//!   resolving `..`, symbolic links and the current directory ([`check_outputs`]).
//!
//! Renaming is atomic per file; a run's renames follow one another. They happen after everything was written,
//! inside directories where a file was just created, so the only way to see some outputs renamed and not
//! others is for a rename itself to fail (a file system fault), which is reported.

use std::fs::{File, OpenOptions};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use anyhow::{Context as _, Result, bail, ensure};

/// Outputs staged together: each written to a temporary file beside its target by [`Outputs::stage`],
/// all renamed into place by [`Outputs::commit`]. Dropped without a commit (an error on the way), it removes
/// every temporary file and leaves the targets as they were.
#[derive(Default)]
pub struct Outputs {
    staged: Vec<Staged>,
}

struct Staged {
    /// As the user named it, for messages.
    shown: PathBuf,
    /// The regular file that will be replaced or created (symbolic links resolved).
    target: PathBuf,
    temp: PathBuf,
}

impl Outputs {
    pub fn new() -> Self {
        Self::default()
    }

    /// Writes an output to its temporary file with `write` (buffered), flushed and synced to disk. Refuses
    /// a `path` that is not a regular file (see the module documentation) or that names the same file as
    /// an output staged before.
    pub fn stage(&mut self, path: &Path, write: impl FnOnce(&mut BufWriter<File>) -> Result<()>) -> Result<()> {
        let target = resolve(path)?;
        if let Some(other) = self.staged.iter().find(|s| s.target == target) {
            bail!(
                "{} and {} are the same file ({}); each output needs its own",
                other.shown.display(),
                path.display(),
                target.display()
            );
        }
        let (file, temp) = create_temp(&target).with_context(|| format!("cannot write {}", path.display()))?;
        // Registered before writing, so that Drop removes it whatever happens next.
        self.staged.push(Staged { shown: path.to_owned(), target, temp });
        let result = (|| -> Result<()> {
            let mut writer = BufWriter::new(file);
            write(&mut writer)?;
            let file = writer.into_inner().map_err(|e| e.into_error())?;
            file.sync_all()?;
            Ok(())
        })();
        result.with_context(|| format!("writing {}", path.display()))
    }

    /// [`Outputs::stage`] for content already in memory.
    pub fn stage_bytes(&mut self, path: &Path, bytes: &[u8]) -> Result<()> {
        self.stage(path, |w| Ok(w.write_all(bytes)?))
    }

    /// Renames every staged output into place, in the order staged.
    pub fn commit(mut self) -> Result<()> {
        while let Some(staged) = self.staged.first() {
            // On failure Drop removes this temporary file and those not renamed yet.
            std::fs::rename(&staged.temp, &staged.target)
                .with_context(|| format!("cannot rename {} to {}", staged.temp.display(), staged.shown.display()))?;
            self.staged.remove(0);
        }
        Ok(())
    }
}

impl Drop for Outputs {
    fn drop(&mut self) {
        for staged in &self.staged {
            let _ = std::fs::remove_file(&staged.temp);
        }
    }
}

/// Calls `write` on a buffered temporary file beside `path`, then renames it to `path`. On any error the
/// temporary file is removed and `path` is left as it was.
pub fn write_file(path: &Path, write: impl FnOnce(&mut BufWriter<File>) -> Result<()>) -> Result<()> {
    let mut outputs = Outputs::new();
    outputs.stage(path, write)?;
    outputs.commit()
}

/// Like [`write_file`] for content that is already in memory.
pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<()> {
    write_file(path, |w| Ok(w.write_all(bytes)?))
}

/// The regular file that writing the output `path` replaces or creates: `path` itself with `..`, links and
/// the current directory resolved, or for a symbolic link the file it points to. Refuses directories,
/// FIFOs, sockets, devices, dangling links and a missing directory.
pub fn resolve(path: &Path) -> Result<PathBuf> {
    let shown = path.display();
    match std::fs::symlink_metadata(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            let name = path.file_name().with_context(|| format!("{shown} does not name a file"))?;
            let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
            let resolved = match dir.canonicalize() {
                Ok(d) if d.is_dir() => d,
                Ok(_) => bail!("cannot write {shown}: {} is not a directory", dir.display()),
                Err(_) => bail!("cannot write {shown}: directory {} does not exist", dir.display()),
            };
            Ok(resolved.join(name))
        }
        Err(e) => Err(e).with_context(|| format!("cannot write {shown}")),
        Ok(meta) => {
            let link = meta.file_type().is_symlink();
            let to = || std::fs::read_link(path).map(|t| t.display().to_string()).unwrap_or_default();
            // Where a link leads, followed to the end (`/dev/stdout` leads to a pipe or a terminal).
            let kind = match std::fs::metadata(path) {
                Ok(m) => m.file_type(),
                Err(e) if link && e.kind() == std::io::ErrorKind::NotFound => {
                    bail!("{shown} is a symbolic link to {}, which does not exist; name a file to write", to())
                }
                Err(e) => return Err(e).with_context(|| format!("cannot write {shown}")),
            };
            if let Some(what) = special_kind(kind) {
                let through = if link { format!(" (a symbolic link to {})", to()) } else { String::new() };
                bail!("{shown}{through} is {what}; sensorlight writes only regular files, name one");
            }
            path.canonicalize().with_context(|| format!("cannot write {shown}"))
        }
    }
}

/// What a file that is not a regular file is, in words.
fn special_kind(kind: std::fs::FileType) -> Option<&'static str> {
    if kind.is_file() {
        return None;
    }
    if kind.is_dir() {
        return Some("a directory");
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt as _;
        if kind.is_fifo() {
            return Some("a named pipe (FIFO)");
        } else if kind.is_socket() {
            return Some("a socket");
        } else if kind.is_char_device() || kind.is_block_device() {
            return Some("a device");
        }
    }
    Some("not a regular file")
}

/// Fails early, before any long computation, if `path` cannot be written: its directory is missing or not
/// writable, or it is not a regular file (see [`resolve`]). Leaves nothing behind.
pub fn check_writable(path: &Path) -> Result<()> {
    check_outputs(&[("output", path)], &[])
}

/// [`check_writable`] for each of a run's outputs, given as (what it is, e.g. `--stats-json`; path), and
/// that no two of them, nor an output and one of `inputs`, are the same file. Leaves nothing behind.
pub fn check_outputs(outputs: &[(&str, &Path)], inputs: &[&Path]) -> Result<()> {
    let mut seen: Vec<(&str, &Path, PathBuf)> = Vec::new();
    for &(what, path) in outputs {
        let target = resolve(path)?;
        if let Some((other, other_path, _)) = seen.iter().find(|(_, _, t)| *t == target) {
            bail!(
                "{what} {} and {other} {} are the same file ({}); each output needs its own",
                path.display(),
                other_path.display(),
                target.display()
            );
        }
        for input in inputs {
            let same = input.canonicalize().is_ok_and(|i| i == target);
            ensure!(
                !same,
                "{what} {} would overwrite the input {}; name another file",
                path.display(),
                input.display()
            );
        }
        let (_, temp) = create_temp(&target).with_context(|| format!("cannot write {}", path.display()))?;
        std::fs::remove_file(&temp).with_context(|| format!("cannot remove {}", temp.display()))?;
        seen.push((what, path, target));
    }
    Ok(())
}

/// Checks that `path` names a file of type `extension` (any case), e.g. before deriving a PNG name beside it.
pub fn check_extension(path: &Path, extension: &str) -> Result<()> {
    let ok = path.extension().is_some_and(|e| e.eq_ignore_ascii_case(extension));
    anyhow::ensure!(ok, "{}: expected a .{extension} file name", path.display());
    Ok(())
}

/// Creates a new, empty temporary file beside `target` (never following a link or reusing a file there).
fn create_temp(target: &Path) -> std::io::Result<(File, PathBuf)> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let name = target.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    loop {
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let temp = target.with_file_name(format!(".{name}.{}.{n}.tmp", std::process::id()));
        match OpenOptions::new().write(true).create_new(true).open(&temp) {
            Ok(file) => return Ok((file, temp)),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(e),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("sensorlight-atomic-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn listing(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> =
            std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        names.sort();
        names
    }

    #[test]
    fn failed_write_leaves_nothing_behind() {
        let dir = scratch("failed");
        let target = dir.join("out.bin");
        let err = write_file(&target, |w| {
            w.write_all(b"partial")?;
            anyhow::bail!("disk on fire")
        });
        assert!(err.is_err());
        assert!(listing(&dir).is_empty(), "temporary file left behind");
        check_writable(&target).unwrap();
        assert!(listing(&dir).is_empty(), "the check left a file behind");
        assert!(check_writable(&dir).unwrap_err().to_string().contains("is a directory"));
        assert!(check_writable(&dir.join("missing/out.bin")).unwrap_err().to_string().contains("does not exist"));
        write_bytes(&target, b"whole").unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"whole");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// The second of two outputs fails: the first, already written to its temporary file, must not appear,
    /// and a file that existed before keeps its content.
    #[test]
    fn a_failed_output_takes_the_others_with_it() {
        let dir = scratch("batch");
        let (exr, png) = (dir.join("out.exr"), dir.join("out.png"));
        std::fs::write(&png, b"old preview").unwrap();
        let mut outputs = Outputs::new();
        outputs.stage_bytes(&exr, b"image").unwrap();
        let err = outputs.stage(&png, |w| {
            w.write_all(b"half")?;
            Err(std::io::Error::from_raw_os_error(28).into())
        });
        assert!(err.unwrap_err().to_string().contains("out.png"));
        drop(outputs);
        assert_eq!(listing(&dir), ["out.png"], "only the file that was there before");
        assert_eq!(std::fs::read(&png).unwrap(), b"old preview");

        let mut outputs = Outputs::new();
        outputs.stage_bytes(&exr, b"image").unwrap();
        outputs.stage_bytes(&png, b"preview").unwrap();
        let visible: Vec<String> = listing(&dir).into_iter().filter(|n| !n.starts_with('.')).collect();
        assert_eq!(visible, ["out.png"], "nothing renamed before the commit");
        outputs.commit().unwrap();
        assert_eq!(listing(&dir), ["out.exr", "out.png"]);
        assert_eq!(std::fs::read(&png).unwrap(), b"preview");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    #[cfg(unix)]
    fn outputs_never_alias_each_other_or_an_input() {
        let dir = scratch("alias");
        std::fs::create_dir(dir.join("sub")).unwrap();
        std::fs::write(dir.join("out.png"), b"preview").unwrap();
        std::os::unix::fs::symlink(dir.join("out.png"), dir.join("link.json")).unwrap();
        let exr = dir.join("out.exr");
        let png = dir.join("out.png");
        let cases = [
            (dir.join("out.exr"), "-o"),            // the very same name
            (dir.join("sub/../out.exr"), "-o"),     // through ..
            (dir.join("link.json"), "PNG preview"), // a link to the preview
        ];
        for (json, clash) in cases {
            let outputs = [("-o", exr.as_path()), ("PNG preview", png.as_path()), ("--stats-json", json.as_path())];
            let message = check_outputs(&outputs, &[]).unwrap_err().to_string();
            assert!(message.contains("same file") && message.contains(clash), "{json:?}: {message}");
        }
        std::fs::write(dir.join("scene.toml"), "x").unwrap();
        let input = dir.join("scene.toml");
        let message = check_outputs(&[("--json", &dir.join("sub/../scene.toml"))], &[&input]).unwrap_err();
        assert!(message.to_string().contains("would overwrite the input"), "{message}");
        // Staging catches the same clash, should a caller skip the check.
        let mut outputs = Outputs::new();
        outputs.stage_bytes(&png, b"a").unwrap();
        assert!(outputs.stage_bytes(&dir.join("link.json"), b"b").unwrap_err().to_string().contains("same file"));
        drop(outputs);
        assert_eq!(listing(&dir), ["link.json", "out.png", "scene.toml", "sub"]);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    #[cfg(unix)]
    fn special_files_are_refused_and_links_written_through() {
        let dir = scratch("special");
        let fifo = dir.join("pipe.json");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status().is_ok_and(|s| s.success());
        assert!(made, "mkfifo failed");
        let message = write_bytes(&fifo, b"x").unwrap_err().to_string();
        assert!(message.contains("named pipe"), "{message}");
        use std::os::unix::fs::FileTypeExt as _;
        assert!(std::fs::symlink_metadata(&fifo).unwrap().file_type().is_fifo(), "the FIFO is still there");
        for device in ["/dev/null", "/dev/full"] {
            let message = check_writable(Path::new(device)).unwrap_err().to_string();
            assert!(message.contains("is a device"), "{message}");
        }
        // A link to /dev/null is refused too, naming where it leads.
        std::os::unix::fs::symlink("/dev/null", dir.join("null.exr")).unwrap();
        let message = check_writable(&dir.join("null.exr")).unwrap_err().to_string();
        assert!(message.contains("symbolic link to /dev/null") && message.contains("device"), "{message}");
        // A dangling link.
        std::os::unix::fs::symlink(dir.join("nowhere/x"), dir.join("dangling.exr")).unwrap();
        let message = check_writable(&dir.join("dangling.exr")).unwrap_err().to_string();
        assert!(message.contains("does not exist"), "{message}");
        // A link to a regular file: the file is replaced, the link stays a link.
        std::fs::create_dir(dir.join("results")).unwrap();
        std::fs::write(dir.join("results/real.exr"), b"old").unwrap();
        std::os::unix::fs::symlink(dir.join("results/real.exr"), dir.join("out.exr")).unwrap();
        write_bytes(&dir.join("out.exr"), b"new").unwrap();
        assert!(std::fs::symlink_metadata(dir.join("out.exr")).unwrap().file_type().is_symlink());
        assert_eq!(std::fs::read(dir.join("results/real.exr")).unwrap(), b"new");
        assert_eq!(listing(&dir.join("results")), ["real.exr"], "no temporary left beside the target");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn extension_is_checked_in_any_case() {
        assert!(check_extension(Path::new("a/out.EXR"), "exr").is_ok());
        assert!(check_extension(Path::new("out.png"), "exr").is_err());
        assert!(check_extension(Path::new("out"), "exr").is_err());
    }
}
