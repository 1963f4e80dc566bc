//! A firmware image as `cargo xtask dist` writes it: the ELF file's bytes (loaded unchanged,
//! segment by segment, into the emulated flash), their SHA-256 (printed, so a run names the
//! exact file), the stack's top (the vector table's first word: the initial MSP) and the
//! entry points of embassy's task polls (`TaskStorage<F>::poll`, one per task in the image),
//! which the runner watches to time the boot: reset → every task polled.

use std::path::{Path, PathBuf};

use sha2::{Digest, Sha256};

/// One image.
#[derive(Debug, Clone)]
pub struct Image {
    /// Where it was read from.
    pub path: PathBuf,
    /// The file's bytes.
    pub bytes: Vec<u8>,
    /// SHA-256 of the file, lowercase hex.
    pub sha256: String,
    /// The loadable segments: (load address, bytes).
    pub segments: Vec<(u32, Vec<u8>)>,
    /// The initial stack pointer (word 0 of the vector table at the lowest segment).
    pub stack_top: u32,
    /// Entry addresses of the task polls (Thumb bit cleared).
    pub task_polls: Vec<u32>,
}

/// Why an image cannot be used.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ImageError {
    /// The file could not be read.
    Read(String),
    /// Not a firmware ELF.
    Elf(String),
    /// No vector table at its first segment.
    NoVectorTable,
}

impl core::fmt::Display for ImageError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            ImageError::Read(e) => write!(f, "cannot read the image: {e}"),
            ImageError::Elf(e) => write!(f, "not a firmware ELF: {e}"),
            ImageError::NoVectorTable => write!(f, "no vector table in the first segment"),
        }
    }
}

impl std::error::Error for ImageError {}

/// Lowercase hex SHA-256 of `bytes`.
pub fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// What every task poll's symbol carries (`embassy_executor::raw::TaskStorage<F>::poll`),
/// in both manglings: legacy `…TaskStorage$LT$F$GT$4poll17h…E` and v0
/// `…11TaskStorage…E4poll…`.
fn is_task_poll(name: &str) -> bool {
    name.contains("TaskStorage") && name.contains("4poll")
}

impl Image {
    /// The image in `bytes` (read from `path`).
    ///
    /// # Errors
    /// When the bytes are not a 32-bit little-endian ELF with a vector table.
    pub fn from_bytes(path: &Path, bytes: Vec<u8>) -> Result<Self, ImageError> {
        let segments: Vec<(u32, Vec<u8>)> = fw_elf::load_segments(&bytes)
            .map_err(|e| ImageError::Elf(e.to_string()))?
            .into_iter()
            .map(|s| (s.address, s.data))
            .collect();
        let stack_top = segments
            .first()
            .and_then(|(_, d)| d.get(0..4))
            .and_then(|w| w.try_into().ok())
            .map(u32::from_le_bytes)
            .ok_or(ImageError::NoVectorTable)?;
        let mut task_polls: Vec<u32> = fw_elf::symbols(&bytes)
            .map_err(|e| ImageError::Elf(e.to_string()))?
            .into_iter()
            .filter(|s| is_task_poll(&s.name))
            .map(|s| s.address & !1)
            .collect();
        task_polls.sort_unstable();
        task_polls.dedup();
        Ok(Self {
            path: path.to_path_buf(),
            sha256: sha256_hex(&bytes),
            bytes,
            segments,
            stack_top,
            task_polls,
        })
    }

    /// The image in the file at `path`.
    ///
    /// # Errors
    /// When the file cannot be read or is no firmware ELF.
    pub fn load(path: &Path) -> Result<Self, ImageError> {
        let bytes = std::fs::read(path)
            .map_err(|e| ImageError::Read(format!("{}: {e}", path.display())))?;
        Self::from_bytes(path, bytes)
    }
}

/// The workspace's `dist/` (where `cargo xtask dist` writes the images).
pub fn dist_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../dist")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sha256_of_known_input() {
        // FIPS 180-2's "abc".
        assert_eq!(
            sha256_hex(b"abc"),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
    }

    #[test]
    fn task_polls_in_both_manglings() {
        assert!(is_task_poll(
            "_ZN16embassy_executor3raw20TaskStorage$LT$F$GT$4poll17h119b6b6c1c125153E"
        ));
        assert!(is_task_poll(
            "_RNvMs1_NtCs5APViPlMGpI_16embassy_executor3rawINtB5_11TaskStorageNCNvNvNtCsve3zSKosp0_9flight_fw8firmware21_____embassy_main_task36_____embassy_main_task_inner_function0E4pollB18_"
        ));
        assert!(!is_task_poll("_ZN4core6future4poll17h0E"));
    }

    #[test]
    fn garbage_is_refused_with_a_reason() {
        let err = Image::from_bytes(Path::new("x.elf"), b"not an elf".to_vec()).unwrap_err();
        assert!(matches!(err, ImageError::Elf(_)), "{err}");
        let err = Image::load(Path::new("/nonexistent/image.elf")).unwrap_err();
        assert!(err.to_string().contains("/nonexistent/image.elf"), "{err}");
    }
}
