//! The scene file as `flatray serve` reads and writes it: only a regular
//! file is read (a pipe or a device could block forever, and the scene's
//! lock with it), a read-only one is never replaced, and each save keeps
//! the file's previous texts as a few generations of backups.
//!
//! The path given here is the scene file's own, any symbolic link in it
//! resolved when the server started: a link found there later was put in
//! the file's place, and is neither read nor replaced.

use std::path::{Path, PathBuf};

/// How many earlier texts a save keeps: `NAME.bak` (the newest), then
/// `NAME.bak.1` to `NAME.bak.4`.
pub(crate) const BACKUPS: usize = 5;

/// The scene file's text, read only when it is a regular file within the
/// input budget; `Ok(None)` when there is no file there (it was removed or
/// is being replaced).
pub(crate) fn read_text(path: &Path) -> Result<Option<String>, String> {
    refuse_link(path)?;
    match flatray_io::read_within(path, flatray_io::MAX_INPUT_BYTES) {
        Ok(bytes) => String::from_utf8(bytes)
            .map(Some)
            .map_err(|_| format!("{}: the scene file is not UTF-8 text", path.display())),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(e) => Err(format!(
            "{}: cannot read the scene file: {e}",
            path.display()
        )),
    }
}

/// Refuses to replace a file that is read-only or is not a regular file.
pub(crate) fn check_writable(path: &Path) -> Result<(), String> {
    refuse_link(path)?;
    let Ok(metadata) = std::fs::metadata(path) else {
        return Ok(());
    };
    if !metadata.is_file() {
        return Err(format!(
            "{}: it is not a regular file; flatray will not replace it",
            path.display()
        ));
    }
    if metadata.permissions().readonly() {
        return Err(format!(
            "{}: the file is read-only; flatray will not replace it (make it writable, or save the scene from the page's export link)",
            path.display()
        ));
    }
    Ok(())
}

fn refuse_link(path: &Path) -> Result<(), String> {
    if std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink()) {
        return Err(format!(
            "{}: the scene file was replaced by a symbolic link; flatray reads and saves only the file it started with (restart it to follow the link)",
            path.display()
        ));
    }
    Ok(())
}

/// `scene.ron` -> `scene.ron.bak` (`generation` 0), `scene.ron.bak.N`.
pub(crate) fn backup_path(path: &Path, generation: usize) -> PathBuf {
    let mut name = path
        .file_name()
        .map(|n| n.to_os_string())
        .unwrap_or_default();
    name.push(".bak");
    if generation > 0 {
        name.push(format!(".{generation}"));
    }
    path.with_file_name(name)
}

/// Keeps `previous` (the text the file holds before a save) as the newest
/// backup, each older one moved a generation down and the oldest of
/// [`BACKUPS`] dropped. Nothing moves when the newest backup already holds
/// that text. Returns the newest backup's path.
pub(crate) fn keep_backup(path: &Path, previous: &str) -> Result<PathBuf, String> {
    let newest = backup_path(path, 0);
    if read_text(&newest).ok().flatten().as_deref() == Some(previous) {
        return Ok(newest);
    }
    for generation in (1..BACKUPS).rev() {
        let from = backup_path(path, generation - 1);
        if std::fs::symlink_metadata(&from).is_ok_and(|m| m.is_file()) {
            std::fs::rename(&from, backup_path(path, generation))
                .map_err(|e| format!("{}: cannot keep it as a backup: {e}", from.display()))?;
        }
    }
    flatray_io::write_text(&newest, previous).map_err(|e| e.to_string())?;
    Ok(newest)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn backups_keep_five_generations_newest_first() {
        let dir = std::env::temp_dir().join(format!("flatray-backups-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let scene = dir.join("s.ron");
        for k in 0..7 {
            keep_backup(&scene, &format!("text {k}")).unwrap();
            // The same text twice makes no new generation.
            keep_backup(&scene, &format!("text {k}")).unwrap();
        }
        for generation in 0..BACKUPS {
            assert_eq!(
                std::fs::read_to_string(backup_path(&scene, generation)).unwrap(),
                format!("text {}", 6 - generation)
            );
        }
        assert!(!backup_path(&scene, BACKUPS).exists());
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn pipes_and_read_only_files_are_refused() {
        let dir = std::env::temp_dir().join(format!("flatray-disk-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("s.ron");
        std::fs::write(&file, "Scene()").unwrap();
        assert_eq!(read_text(&file).unwrap().as_deref(), Some("Scene()"));
        assert_eq!(check_writable(&file), Ok(()));
        let mut permissions = std::fs::metadata(&file).unwrap().permissions();
        permissions.set_readonly(true);
        std::fs::set_permissions(&file, permissions).unwrap();
        assert!(check_writable(&file).unwrap_err().contains("read-only"));
        assert_eq!(read_text(&dir.join("missing.ron")), Ok(None));
        assert!(check_writable(&dir).is_err(), "a folder");
        assert!(read_text(&dir).is_err(), "a folder");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
