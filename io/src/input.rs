//! Reading an input file under a budget: only regular files (never a
//! device, a pipe or a folder, which may never end), and never more bytes
//! than the budget, checked before they are held.

use std::io::Read;
use std::path::Path;

/// At most this many bytes in a scene file, a floor image or a plan to
/// import: far beyond any plan (a scene of 100,000 walls is about 5 MB).
pub const MAX_INPUT_BYTES: u64 = 256 << 20;

/// The bytes of the regular file at `path`, refused when it is not a
/// regular file (before it is opened: opening a pipe would wait for a
/// writer) or holds more than `limit` bytes.
pub fn read_within(path: &Path, limit: u64) -> std::io::Result<Vec<u8>> {
    let metadata = std::fs::metadata(path)?;
    if !metadata.is_file() {
        let what = if metadata.is_dir() {
            "a folder"
        } else {
            "not a regular file (a device or a pipe)"
        };
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("it is {what}; flatray reads only files"),
        ));
    }
    let too_large = || {
        std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("it is larger than the {} MiB flatray reads", limit >> 20),
        )
    };
    if metadata.len() > limit {
        return Err(too_large());
    }
    let mut bytes = Vec::with_capacity(metadata.len() as usize);
    // The file may grow after the size was read: take one byte past the
    // budget, to tell.
    std::fs::File::open(path)?
        .take(limit + 1)
        .read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(too_large());
    }
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn folders_devices_and_large_files_are_refused() {
        let dir = std::env::temp_dir().join(format!("flatray-input-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("f.txt");
        std::fs::write(&file, b"0123456789").unwrap();
        assert_eq!(read_within(&file, 10).unwrap(), b"0123456789");
        assert!(
            read_within(&file, 9)
                .unwrap_err()
                .to_string()
                .contains("larger")
        );
        assert!(
            read_within(&dir, 10)
                .unwrap_err()
                .to_string()
                .contains("folder")
        );
        #[cfg(unix)]
        assert!(
            read_within(Path::new("/dev/zero"), 10)
                .unwrap_err()
                .to_string()
                .contains("not a regular file")
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
