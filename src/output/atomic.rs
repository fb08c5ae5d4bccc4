//! Output files appear whole or not at all: written to a temporary file beside the target, renamed on success.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use anyhow::{Context as _, Result};

/// Calls `write` on a buffered temporary file next to `path`, then renames it to `path`. On any error the
/// temporary file is removed and `path` is left as it was.
pub fn write_file(path: &Path, write: impl FnOnce(&mut BufWriter<File>) -> Result<()>) -> Result<()> {
    let temp = temp_path(path);
    let result = (|| {
        let file = File::create(&temp).with_context(|| format!("cannot create {}", temp.display()))?;
        let mut writer = BufWriter::new(file);
        write(&mut writer)?;
        let file = writer.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
        std::fs::rename(&temp, path).with_context(|| format!("cannot rename {} to {}", temp.display(), path.display()))
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&temp);
    }
    result.with_context(|| format!("writing {}", path.display()))
}

/// Fails early, before any long computation, if `path` cannot be written: its directory is missing or not
/// writable, or `path` is a directory. Leaves nothing behind.
pub fn check_writable(path: &Path) -> Result<()> {
    anyhow::ensure!(!path.is_dir(), "{} is a directory; name a file to write", path.display());
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    anyhow::ensure!(dir.is_dir(), "cannot write {}: directory {} does not exist", path.display(), dir.display());
    let temp = temp_path(path);
    File::create(&temp).with_context(|| format!("cannot write {} in {}", path.display(), dir.display()))?;
    std::fs::remove_file(&temp).with_context(|| format!("cannot remove {}", temp.display()))
}

/// Checks that `path` names a file of type `extension` (any case), e.g. before deriving a PNG name beside it.
pub fn check_extension(path: &Path, extension: &str) -> Result<()> {
    let ok = path.extension().is_some_and(|e| e.eq_ignore_ascii_case(extension));
    anyhow::ensure!(ok, "{}: expected a .{extension} file name", path.display());
    Ok(())
}

/// Like [`write_file`] for content that is already in memory.
pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<()> {
    write_file(path, |w| Ok(w.write_all(bytes)?))
}

fn temp_path(path: &Path) -> PathBuf {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    path.with_file_name(format!(".{name}.{}.tmp", std::process::id()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failed_write_leaves_nothing_behind() {
        let dir = std::env::temp_dir().join(format!("sensorlight-atomic-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let target = dir.join("out.bin");
        let err = write_file(&target, |w| {
            w.write_all(b"partial")?;
            anyhow::bail!("disk on fire")
        });
        assert!(err.is_err());
        assert!(std::fs::read_dir(&dir).unwrap().next().is_none(), "temporary file left behind");
        check_writable(&target).unwrap();
        assert!(std::fs::read_dir(&dir).unwrap().next().is_none(), "the check left a file behind");
        assert!(check_writable(&dir).unwrap_err().to_string().contains("is a directory"));
        assert!(check_writable(&dir.join("missing/out.bin")).unwrap_err().to_string().contains("does not exist"));
        write_bytes(&target, b"whole").unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"whole");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn extension_is_checked_in_any_case() {
        assert!(check_extension(Path::new("a/out.EXR"), "exr").is_ok());
        assert!(check_extension(Path::new("out.png"), "exr").is_err());
        assert!(check_extension(Path::new("out"), "exr").is_err());
    }
}
