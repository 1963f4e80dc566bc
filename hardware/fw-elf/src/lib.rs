//! Just enough ELF32 (little-endian, ARM) reading to get the loadable image, the
//! text/data/bss sizes and the symbol table out of a firmware ELF, so no binutils are needed
//! (xtask's flashable files and checks, the processor-in-the-loop runner's loader).

use std::fmt;

/// A contiguous piece of flash content at its load (physical) address.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Segment {
    /// Load address in flash.
    pub address: u32,
    /// Bytes as they must appear in flash.
    pub data: Vec<u8>,
}

/// Sizes as Berkeley `size` counts them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Sizes {
    /// Allocated, read-only sections with contents (code, rodata, vector table).
    pub text: u32,
    /// Allocated, writable sections with contents (initialised statics, copied from flash).
    pub data: u32,
    /// Allocated sections without contents (zeroed and uninitialised statics).
    pub bss: u32,
}

/// What is wrong with a file that should be a firmware ELF.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ElfError {
    /// Not a 32-bit little-endian ELF.
    NotElf32Le,
    /// A header points outside the file.
    Truncated,
}

impl fmt::Display for ElfError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ElfError::NotElf32Le => write!(f, "not a 32-bit little-endian ELF file"),
            ElfError::Truncated => write!(f, "ELF header points outside the file"),
        }
    }
}

impl std::error::Error for ElfError {}

const PT_LOAD: u32 = 1;
const SHT_NOBITS: u32 = 8;
const SHF_WRITE: u32 = 1;
const SHF_ALLOC: u32 = 2;

fn u16_at(b: &[u8], at: usize) -> Result<u16, ElfError> {
    let s = b.get(at..at + 2).ok_or(ElfError::Truncated)?;
    Ok(u16::from_le_bytes(
        s.try_into().map_err(|_| ElfError::Truncated)?,
    ))
}

fn u32_at(b: &[u8], at: usize) -> Result<u32, ElfError> {
    let s = b.get(at..at + 4).ok_or(ElfError::Truncated)?;
    Ok(u32::from_le_bytes(
        s.try_into().map_err(|_| ElfError::Truncated)?,
    ))
}

fn check_header(elf: &[u8]) -> Result<(), ElfError> {
    match elf.get(0..6) {
        Some([0x7F, b'E', b'L', b'F', 1, 1]) => Ok(()),
        _ => Err(ElfError::NotElf32Le),
    }
}

/// The loadable segments with file contents, by load address (LMA), sorted.
pub fn load_segments(elf: &[u8]) -> Result<Vec<Segment>, ElfError> {
    check_header(elf)?;
    let phoff = u32_at(elf, 0x1C)? as usize;
    let phentsize = u16_at(elf, 0x2A)? as usize;
    let phnum = u16_at(elf, 0x2C)? as usize;
    let mut segments = Vec::new();
    for i in 0..phnum {
        let ph = phoff + i * phentsize;
        let (kind, offset, paddr, filesz) = (
            u32_at(elf, ph)?,
            u32_at(elf, ph + 4)? as usize,
            u32_at(elf, ph + 12)?,
            u32_at(elf, ph + 16)? as usize,
        );
        if kind != PT_LOAD || filesz == 0 {
            continue;
        }
        let data = elf
            .get(offset..offset + filesz)
            .ok_or(ElfError::Truncated)?;
        segments.push(Segment {
            address: paddr,
            data: data.to_vec(),
        });
    }
    segments.sort_by_key(|s| s.address);
    Ok(segments)
}

/// Which of Berkeley `size`'s three counts an allocated section adds to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Class {
    /// Read-only with contents: code, rodata, the vector table (in flash).
    Text,
    /// Writable with contents: initialised statics (in RAM, copied from flash).
    Data,
    /// Without contents: zeroed and uninitialised statics (in RAM).
    Bss,
}

/// One allocated section: where it lives at run time and how big it is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Section {
    /// Section name (`.data`, `.bss`, ...).
    pub name: String,
    /// Run-time (virtual) address.
    pub address: u32,
    /// Size in bytes.
    pub size: u32,
    /// What it counts as.
    pub class: Class,
}

/// The allocated sections (those that take memory at run time), in header order; empty
/// ones are left out.
pub fn alloc_sections(elf: &[u8]) -> Result<Vec<Section>, ElfError> {
    check_header(elf)?;
    let shoff = u32_at(elf, 0x20)? as usize;
    let shentsize = u16_at(elf, 0x2E)? as usize;
    let shnum = u16_at(elf, 0x30)? as usize;
    let shstrndx = u16_at(elf, 0x32)? as usize;
    let names = u32_at(elf, shoff + shstrndx * shentsize + 16)? as usize;
    let mut out = Vec::new();
    for i in 0..shnum {
        let sh = shoff + i * shentsize;
        let (name, kind, flags, address, size) = (
            u32_at(elf, sh)? as usize,
            u32_at(elf, sh + 4)?,
            u32_at(elf, sh + 8)?,
            u32_at(elf, sh + 12)?,
            u32_at(elf, sh + 20)?,
        );
        if flags & SHF_ALLOC == 0 || size == 0 {
            continue;
        }
        let class = if kind == SHT_NOBITS {
            Class::Bss
        } else if flags & SHF_WRITE != 0 {
            Class::Data
        } else {
            Class::Text
        };
        out.push(Section {
            name: string_at(elf, names + name)?,
            address,
            size,
            class,
        });
    }
    Ok(out)
}

/// The NUL-terminated string at `at`.
fn string_at(elf: &[u8], at: usize) -> Result<String, ElfError> {
    let tail = elf.get(at..).ok_or(ElfError::Truncated)?;
    let end = tail
        .iter()
        .position(|&b| b == 0)
        .ok_or(ElfError::Truncated)?;
    Ok(String::from_utf8_lossy(tail.get(..end).unwrap_or_default()).into_owned())
}

/// text/data/bss from the section headers.
pub fn sizes(elf: &[u8]) -> Result<Sizes, ElfError> {
    let mut sizes = Sizes::default();
    for s in alloc_sections(elf)? {
        match s.class {
            Class::Text => sizes.text += s.size,
            Class::Data => sizes.data += s.size,
            Class::Bss => sizes.bss += s.size,
        }
    }
    Ok(sizes)
}

/// One symbol of the symbol table with an address (functions, objects).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Symbol {
    /// The (mangled) name.
    pub name: String,
    /// Its value: the address (Thumb functions have bit 0 set, as the table stores them).
    pub address: u32,
    /// Its size in bytes (0 when the table does not say).
    pub size: u32,
}

const SHT_SYMTAB: u32 = 2;
const SYM_SIZE: usize = 16;

/// Every named symbol of the `.symtab` sections, in table order.
pub fn symbols(elf: &[u8]) -> Result<Vec<Symbol>, ElfError> {
    check_header(elf)?;
    let shoff = u32_at(elf, 0x20)? as usize;
    let shentsize = u16_at(elf, 0x2E)? as usize;
    let shnum = u16_at(elf, 0x30)? as usize;
    let section = |i: usize| shoff + i * shentsize;
    let mut out = Vec::new();
    for i in 0..shnum {
        let sh = section(i);
        if u32_at(elf, sh + 4)? != SHT_SYMTAB {
            continue;
        }
        let (offset, size, link) = (
            u32_at(elf, sh + 16)? as usize,
            u32_at(elf, sh + 20)? as usize,
            u32_at(elf, sh + 24)? as usize,
        );
        let strings = u32_at(elf, section(link) + 16)? as usize;
        for entry in (offset..offset + size).step_by(SYM_SIZE) {
            let name = u32_at(elf, entry)? as usize;
            if name == 0 {
                continue;
            }
            out.push(Symbol {
                name: string_at(elf, strings + name)?,
                address: u32_at(elf, entry + 4)?,
                size: u32_at(elf, entry + 8)?,
            });
        }
    }
    Ok(out)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A minimal ELF32 with one PT_LOAD segment and three sections (text, data, bss).
    pub fn tiny_elf() -> Vec<u8> {
        let mut e = vec![0u8; 0x200];
        e[..6].copy_from_slice(&[0x7F, b'E', b'L', b'F', 1, 1]);
        // program headers at 0x40, one entry of 32 bytes
        e[0x1C..0x20].copy_from_slice(&0x40u32.to_le_bytes());
        e[0x2A..0x2C].copy_from_slice(&32u16.to_le_bytes());
        e[0x2C..0x2E].copy_from_slice(&1u16.to_le_bytes());
        let ph = 0x40;
        e[ph..ph + 4].copy_from_slice(&PT_LOAD.to_le_bytes());
        e[ph + 4..ph + 8].copy_from_slice(&0x100u32.to_le_bytes()); // offset
        e[ph + 8..ph + 12].copy_from_slice(&0x2000_0000u32.to_le_bytes()); // vaddr
        e[ph + 12..ph + 16].copy_from_slice(&0x0800_0000u32.to_le_bytes()); // paddr
        e[ph + 16..ph + 20].copy_from_slice(&4u32.to_le_bytes()); // filesz
        e[0x100..0x104].copy_from_slice(&[1, 2, 3, 4]);
        // section headers at 0x140, 40 bytes each: null, text, data, bss
        e[0x20..0x24].copy_from_slice(&0x140u32.to_le_bytes());
        e[0x2E..0x30].copy_from_slice(&40u16.to_le_bytes());
        e[0x30..0x32].copy_from_slice(&4u16.to_le_bytes());
        for (i, (kind, flags, size)) in [
            (1u32, SHF_ALLOC, 100u32),
            (1, SHF_ALLOC | SHF_WRITE, 8),
            (SHT_NOBITS, SHF_ALLOC | SHF_WRITE, 50),
        ]
        .into_iter()
        .enumerate()
        {
            let sh = 0x140 + (i + 1) * 40;
            e[sh + 4..sh + 8].copy_from_slice(&kind.to_le_bytes());
            e[sh + 8..sh + 12].copy_from_slice(&flags.to_le_bytes());
            e[sh + 20..sh + 24].copy_from_slice(&size.to_le_bytes());
        }
        e
    }

    #[test]
    fn reads_segments_at_load_address() {
        let segs = load_segments(&tiny_elf()).unwrap();
        assert_eq!(
            segs,
            vec![Segment {
                address: 0x0800_0000,
                data: vec![1, 2, 3, 4]
            }]
        );
    }

    #[test]
    fn counts_sizes_like_berkeley_size() {
        assert_eq!(
            sizes(&tiny_elf()).unwrap(),
            Sizes {
                text: 100,
                data: 8,
                bss: 50
            }
        );
    }

    #[test]
    fn an_elf_without_a_symbol_table_has_no_symbols() {
        assert_eq!(symbols(&tiny_elf()).unwrap(), vec![]);
    }

    #[test]
    fn rejects_non_elf_and_truncated() {
        assert_eq!(load_segments(b"hello"), Err(ElfError::NotElf32Le));
        let mut short = tiny_elf();
        short.truncate(0x41);
        assert_eq!(load_segments(&short), Err(ElfError::Truncated));
    }
}
