//! `cargo xtask verify`: checks each built image against its boot contract (`layout`), so a
//! file that its bootloader would refuse, or that would start and then lose its interrupts,
//! never reaches a pilot. Every check reads the files `dist` wrote; nothing is trusted from
//! the linker scripts.

use crate::formats;
use crate::layout::Layout;
use crate::tlfw;
use fw_elf::{self as elf, Segment};

/// VTOR, the Vector Table Offset Register (Armv7-M SCB).
pub const VTOR: u32 = 0xE000_ED08;
/// How many instructions of the reset handler are searched for the VTOR write.
const RESET_SEARCH: usize = 24;

/// The files of one variant, as `dist` wrote them.
pub struct Files<'a> {
    /// The ELF.
    pub elf: &'a [u8],
    /// The `.bin` (flat image from the lowest load address).
    pub bin: Option<&'a [u8]>,
    /// The `.uf2`, if the variant has one.
    pub uf2: Option<&'a [u8]>,
    /// The `.tlfw` and the board type and revision it must name.
    pub tlfw: Option<(&'a [u8], u8, u8)>,
}

fn bytes_at(segments: &[Segment], address: u32, len: u32) -> Option<&[u8]> {
    segments.iter().find_map(|s| {
        let off = address.checked_sub(s.address)? as usize;
        s.data.get(off..off + len as usize)
    })
}

fn word_at(segments: &[Segment], address: u32) -> Option<u32> {
    let b = bytes_at(segments, address, 4)?;
    Some(u32::from_le_bytes(b.try_into().ok()?))
}

fn half_at(segments: &[Segment], address: u32) -> Option<u16> {
    let b = bytes_at(segments, address, 2)?;
    Some(u16::from_le_bytes(b.try_into().ok()?))
}

fn overlaps(a: &std::ops::Range<u32>, start: u32, end: u32) -> bool {
    start < a.end && a.start < end
}

/// Follows the reset handler's straight-line code from `entry` and reports whether it stores
/// `table` into VTOR before the first branch: PC-relative literal loads, MOVW/MOVT and
/// immediate-offset STRs are tracked; any other instruction forgets what it may write.
pub fn writes_vtor(segments: &[Segment], entry: u32, table: u32) -> bool {
    let mut regs: [Option<u32>; 16] = [None; 16];
    let mut pc = entry & !1;
    let literal = |pc: u32, offset: i64| -> Option<u32> {
        let base = i64::from((pc + 4) & !3);
        word_at(segments, u32::try_from(base + offset).ok()?)
    };
    for _ in 0..RESET_SEARCH {
        let Some(hw) = half_at(segments, pc) else {
            return false;
        };
        let wide = matches!(hw >> 11, 0x1D..=0x1F);
        let hw2 = if wide {
            match half_at(segments, pc + 2) {
                Some(h) => h,
                None => return false,
            }
        } else {
            0
        };
        let set = |regs: &mut [Option<u32>; 16], r: u16, v: Option<u32>| {
            if let Some(slot) = regs.get_mut(usize::from(r)) {
                *slot = v;
            }
        };
        let get = |regs: &[Option<u32>; 16], r: u16| regs.get(usize::from(r)).copied().flatten();
        if !wide {
            match hw {
                // LDR Rt, [PC, #imm8*4]
                _ if hw & 0xF800 == 0x4800 => {
                    let v = literal(pc, i64::from(hw & 0xFF) * 4);
                    set(&mut regs, (hw >> 8) & 7, v);
                }
                // STR Rt, [Rn, #imm5*4]
                _ if hw & 0xF800 == 0x6000 => {
                    let (rt, rn, imm) = (hw & 7, (hw >> 3) & 7, u32::from((hw >> 6) & 0x1F) * 4);
                    let addr = get(&regs, rn).map(|a| a.wrapping_add(imm));
                    if addr == Some(VTOR) && get(&regs, rt) == Some(table) {
                        return true;
                    }
                }
                // B, B<cond>, BX/BLX, CBZ/CBNZ, POP {.., pc}: end of the straight line.
                _ if hw & 0xF000 == 0xD000
                    || hw & 0xF800 == 0xE000
                    || hw & 0xFF00 == 0x4700
                    || hw & 0xF500 == 0xB100
                    || hw & 0xFF00 == 0xBD00 =>
                {
                    return false;
                }
                _ => regs = [None; 16],
            }
            pc += 2;
            continue;
        }
        match (hw, hw2) {
            // LDR.W Rt, [PC, #±imm12]
            _ if hw & 0xFF7F == 0xF85F => {
                let imm = i64::from(hw2 & 0xFFF);
                let v = literal(pc, if hw & 0x80 != 0 { imm } else { -imm });
                set(&mut regs, hw2 >> 12, v);
            }
            // MOVW / MOVT
            _ if hw & 0xFBF0 == 0xF240 || hw & 0xFBF0 == 0xF2C0 => {
                let imm = u32::from(hw & 0xF) << 12
                    | u32::from((hw >> 10) & 1) << 11
                    | u32::from((hw2 >> 12) & 7) << 8
                    | u32::from(hw2 & 0xFF);
                let rd = (hw2 >> 8) & 0xF;
                let v = if hw & 0xFBF0 == 0xF240 {
                    Some(imm)
                } else {
                    get(&regs, rd).map(|low| (low & 0xFFFF) | imm << 16)
                };
                set(&mut regs, rd, v);
            }
            // STR.W Rt, [Rn, #imm12]
            _ if hw & 0xFFF0 == 0xF8C0 => {
                let addr = get(&regs, hw & 0xF).map(|a| a.wrapping_add(u32::from(hw2 & 0xFFF)));
                if addr == Some(VTOR) && get(&regs, hw2 >> 12) == Some(table) {
                    return true;
                }
            }
            // MSR, hints, barriers: no general register written.
            _ if hw & 0xFF80 == 0xF380 => {}
            // BL: a call; r0-r3, r12 and lr do not survive it.
            _ if hw & 0xF800 == 0xF000 && hw2 & 0xD000 == 0xD000 => {
                for r in [0, 1, 2, 3, 12, 14] {
                    set(&mut regs, r, None);
                }
            }
            // B.W and conditional B.W: end of the straight line.
            _ if hw & 0xF800 == 0xF000 && hw2 & 0x8000 == 0x8000 => return false,
            _ => regs = [None; 16],
        }
        pc += 4;
    }
    false
}

/// Checks one variant; returns every broken rule (empty: the image keeps its contract).
pub fn check(layout: &Layout, files: &Files) -> Vec<String> {
    let mut problems = Vec::new();
    let segments = match elf::load_segments(files.elf) {
        Ok(s) if !s.is_empty() => s,
        Ok(_) => return vec!["ELF has no loadable content".into()],
        Err(e) => return vec![format!("ELF: {e}")],
    };
    for s in &segments {
        let (start, end) = (s.address, s.address + s.data.len() as u32);
        if start < layout.accepted.start || end > layout.accepted.end {
            problems.push(format!(
                "loads 0x{start:08X}..0x{end:08X}, outside what the {} accepts \
                 (0x{:08X}..0x{:08X})",
                layout.starter, layout.accepted.start, layout.accepted.end
            ));
        }
        for (range, what) in layout.reserved_flash {
            if overlaps(range, start, end) {
                problems.push(format!("loads 0x{start:08X}..0x{end:08X} over the {what}"));
            }
        }
    }

    // The vector table the starter reads: initial SP and reset vector at the origin.
    let (Some(sp), Some(reset)) = (
        word_at(&segments, layout.origin),
        word_at(&segments, layout.origin + 4),
    ) else {
        problems.push(format!("no vector table at 0x{:08X}", layout.origin));
        return problems;
    };
    if !sp.is_multiple_of(8) || sp <= layout.ram.start || sp > layout.ram.end {
        problems.push(format!(
            "initial SP 0x{sp:08X} is not an 8-byte aligned stack top in RAM 0x{:08X}..0x{:08X}",
            layout.ram.start, layout.ram.end
        ));
    }
    if let Some((mask, value)) = layout.sp_mask
        && sp & mask != value
    {
        problems.push(format!(
            "initial SP 0x{sp:08X} fails the {}'s check (SP & 0x{mask:08X}) == 0x{value:08X}: \
             it would never start the image",
            layout.starter
        ));
    }
    for i in 1..16u32 {
        let v = word_at(&segments, layout.origin + 4 * i).unwrap_or(0);
        if (i == 1 || v != 0) && (v & 1 == 0 || bytes_at(&segments, v & !1, 2).is_none()) {
            problems.push(format!(
                "vector {i} (0x{v:08X}) is not Thumb code in the image"
            ));
        }
    }
    if !writes_vtor(&segments, reset, layout.origin) {
        problems.push(format!(
            "the reset handler (0x{reset:08X}) does not write 0x{:08X} to VTOR before its \
             first branch: interrupts would go to the {}'s vector table",
            layout.origin, layout.starter
        ));
    }

    // Statics and stack: only the RAM the layout gives the image (the MBR's forward words).
    match elf::alloc_sections(files.elf) {
        Ok(sections) => {
            for s in sections
                .iter()
                .filter(|s| (0x2000_0000..0x4000_0000).contains(&s.address))
            {
                if s.address < layout.ram.start || s.address + s.size > layout.ram.end {
                    problems.push(format!(
                        "{} at 0x{:08X}..0x{:08X} is outside RAM 0x{:08X}..0x{:08X}",
                        s.name,
                        s.address,
                        s.address + s.size,
                        layout.ram.start,
                        layout.ram.end
                    ));
                }
            }
        }
        Err(e) => problems.push(format!("ELF sections: {e}")),
    }

    let (start, image) = formats::to_bin(&segments);
    if let Some(bin) = files.bin
        && (bin != image.as_slice() || start != layout.origin)
    {
        problems.push(format!(
            ".bin is not the image from 0x{:08X} (image starts at 0x{start:08X})",
            layout.origin
        ));
    }
    if let Some(family) = layout.uf2_family {
        match files.uf2 {
            Some(uf2) => problems.extend(check_uf2(layout, family, &segments, uf2)),
            None => problems.push("no .uf2 written".into()),
        }
    }
    if let Some((file, board_type, revision)) = files.tlfw {
        match tlfw::parse(file) {
            Err(e) => problems.push(format!(".tlfw: {e}")),
            Ok((firmware, d)) => {
                if firmware != image.as_slice() || start != layout.origin {
                    problems.push(".tlfw firmware is not the image from the bank base".into());
                }
                if (d.board_type, d.board_revision) != (board_type, revision) {
                    problems.push(format!(
                        ".tlfw names board 0x{:02X} rev 0x{:02X}, not 0x{board_type:02X} rev \
                         0x{revision:02X}",
                        d.board_type, d.board_revision
                    ));
                }
            }
        }
    }
    problems
}

fn check_uf2(layout: &Layout, family: u32, segments: &[Segment], uf2: &[u8]) -> Vec<String> {
    let mut problems = Vec::new();
    if uf2.is_empty() || !uf2.len().is_multiple_of(512) {
        return vec![format!(
            ".uf2 is {} bytes, not whole 512-byte blocks",
            uf2.len()
        )];
    }
    let total = (uf2.len() / 512) as u32;
    let mut covered = 0u32;
    for (n, block) in uf2.chunks_exact(512).enumerate() {
        let word = |i: usize| {
            block
                .get(i * 4..i * 4 + 4)
                .and_then(|b| b.try_into().ok())
                .map(u32::from_le_bytes)
                .unwrap_or(0)
        };
        let (flags, addr, len) = (word(2), word(3), word(4));
        if word(0) != 0x0A32_4655 || word(1) != 0x9E5D_5157 || word(127) != 0x0AB1_6F30 {
            problems.push(format!(".uf2 block {n}: bad magic"));
            continue;
        }
        if flags & 0x2000 == 0 || word(7) != family {
            problems.push(format!(
                ".uf2 block {n}: family 0x{:08X}, the bootloader wants 0x{family:08X}",
                word(7)
            ));
        }
        if word(5) != n as u32 || word(6) != total || len != 256 {
            problems.push(format!(".uf2 block {n}: numbering or payload size wrong"));
        }
        if addr < layout.accepted.start || addr + len > layout.accepted.end {
            problems.push(format!(
                ".uf2 block {n} at 0x{addr:08X}: the bootloader refuses blocks outside \
                 0x{:08X}..0x{:08X}",
                layout.accepted.start, layout.accepted.end
            ));
        }
        // Payload bytes that the ELF loads must be exactly those.
        let payload = block.get(32..32 + len as usize).unwrap_or_default();
        for (i, b) in payload.iter().enumerate() {
            if let Some(want) = bytes_at(segments, addr + i as u32, 1) {
                covered += 1;
                if want.first() != Some(b) {
                    problems.push(format!(".uf2 block {n}: content differs from the ELF"));
                    break;
                }
            }
        }
    }
    let loaded: u32 = segments.iter().map(|s| s.data.len() as u32).sum();
    if covered != loaded {
        problems.push(format!(
            ".uf2 carries {covered} of the {loaded} loaded bytes"
        ));
    }
    problems
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::{F405_TAULABS, NRF_UF2};

    fn seg(address: u32, data: Vec<u8>) -> Segment {
        Segment { address, data }
    }

    /// A vector table at `origin` (SP, reset → origin + 0x100, 14 more vectors → a `b .`),
    /// and at origin + 0x100 `code`, then literal words.
    fn image(origin: u32, sp: u32, code: &[u16], literals: &[u32]) -> Vec<u8> {
        let mut v = Vec::new();
        v.extend_from_slice(&sp.to_le_bytes());
        v.extend_from_slice(&(origin + 0x101).to_le_bytes());
        for _ in 2..16 {
            v.extend_from_slice(&(origin + 0x181).to_le_bytes());
        }
        v.resize(0x100, 0);
        for hw in code {
            v.extend_from_slice(&hw.to_le_bytes());
        }
        v.resize(0x120, 0);
        for w in literals {
            v.extend_from_slice(&w.to_le_bytes());
        }
        v.resize(0x180, 0);
        v.extend_from_slice(&[0xFE, 0xE7]);
        v
    }

    /// cortex-m-rt's set-vtor prologue: ldr r0,=VTOR; ldr r1,=table; str r1,[r0]; bl ...
    fn set_vtor_prologue() -> Vec<u16> {
        // ldr r0,[pc,#0x1C] at +0x100 → 0x120; ldr r1,[pc,#0x1C] at +0x102 → 0x124
        vec![0x4807, 0x4908, 0x6001, 0xF000, 0xF800]
    }

    /// A minimal ELF around one segment, with one `.data` section at `data_at`.
    fn elf_with(segment: &Segment, data_at: u32) -> Vec<u8> {
        let mut e = vec![0u8; 0x200];
        e[..6].copy_from_slice(&[0x7F, b'E', b'L', b'F', 1, 1]);
        e[0x1C..0x20].copy_from_slice(&0x40u32.to_le_bytes());
        e[0x2A..0x2C].copy_from_slice(&32u16.to_le_bytes());
        e[0x2C..0x2E].copy_from_slice(&1u16.to_le_bytes());
        let off = 0x200u32;
        e[0x40..0x44].copy_from_slice(&1u32.to_le_bytes());
        e[0x44..0x48].copy_from_slice(&off.to_le_bytes());
        e[0x4C..0x50].copy_from_slice(&segment.address.to_le_bytes());
        e[0x50..0x54].copy_from_slice(&(segment.data.len() as u32).to_le_bytes());
        // sections at 0x100: null, .shstrtab (index 1), .data (index 2)
        e[0x20..0x24].copy_from_slice(&0x100u32.to_le_bytes());
        e[0x2E..0x30].copy_from_slice(&40u16.to_le_bytes());
        e[0x30..0x32].copy_from_slice(&3u16.to_le_bytes());
        e[0x32..0x34].copy_from_slice(&1u16.to_le_bytes());
        e[0x180..0x18C].copy_from_slice(b"\0.shstrtab\0\0");
        e[0x18C..0x192].copy_from_slice(b".data\0");
        let sh1 = 0x100 + 40;
        e[sh1 + 4..sh1 + 8].copy_from_slice(&3u32.to_le_bytes());
        e[sh1 + 16..sh1 + 20].copy_from_slice(&0x180u32.to_le_bytes());
        e[sh1 + 20..sh1 + 24].copy_from_slice(&0x20u32.to_le_bytes());
        let sh2 = 0x100 + 80;
        e[sh2..sh2 + 4].copy_from_slice(&0xCu32.to_le_bytes());
        e[sh2 + 4..sh2 + 8].copy_from_slice(&1u32.to_le_bytes());
        e[sh2 + 8..sh2 + 12].copy_from_slice(&3u32.to_le_bytes());
        e[sh2 + 12..sh2 + 16].copy_from_slice(&data_at.to_le_bytes());
        e[sh2 + 20..sh2 + 24].copy_from_slice(&16u32.to_le_bytes());
        e.extend_from_slice(&segment.data);
        e
    }

    fn uf2_good() -> (Segment, Vec<u8>) {
        let s = seg(
            0x26000,
            image(0x26000, 0x2004_0000, &set_vtor_prologue(), &[VTOR, 0x26000]),
        );
        let uf2 = formats::to_uf2(std::slice::from_ref(&s), formats::UF2_FAMILY_NRF52840);
        (s, uf2)
    }

    fn check_uf2_image(s: &Segment, data_at: u32, uf2: &[u8]) -> Vec<String> {
        let elf = elf_with(s, data_at);
        let (_, bin) = formats::to_bin(std::slice::from_ref(s));
        let files = Files {
            elf: &elf,
            bin: Some(&bin),
            uf2: Some(uf2),
            tlfw: None,
        };
        check(&NRF_UF2, &files)
    }

    #[test]
    fn a_good_uf2_image_passes() {
        let (s, uf2) = uf2_good();
        assert_eq!(check_uf2_image(&s, 0x2000_0008, &uf2), Vec::<String>::new());
    }

    #[test]
    fn no_vtor_write_fails() {
        // The reset handler goes straight to `bl`: what today's images did.
        let s = seg(0x26000, image(0x26000, 0x2004_0000, &[0xF000, 0xF800], &[]));
        let uf2 = formats::to_uf2(std::slice::from_ref(&s), formats::UF2_FAMILY_NRF52840);
        let p = check_uf2_image(&s, 0x2000_0008, &uf2);
        assert!(p.iter().any(|m| m.contains("VTOR")), "{p:?}");
    }

    #[test]
    fn vtor_write_of_another_table_fails() {
        let s = seg(
            0x26000,
            image(0x26000, 0x2004_0000, &set_vtor_prologue(), &[VTOR, 0x0]),
        );
        assert!(!writes_vtor(std::slice::from_ref(&s), 0x26101, 0x26000));
    }

    #[test]
    fn movw_movt_vtor_write_is_found() {
        // movw r0,#0xED08; movt r0,#0xE000; movw r1,#0x6000; movt r1,#0x2; str r1,[r0]
        let code = [
            0xF64E, 0x5008, 0xF2CE, 0x0000, 0xF246, 0x0100, 0xF2C0, 0x0102, 0x6001,
        ];
        let s = seg(0x26000, image(0x26000, 0x2004_0000, &code, &[]));
        assert!(writes_vtor(std::slice::from_ref(&s), 0x26101, 0x26000));
    }

    #[test]
    fn data_on_the_mbr_forward_word_fails() {
        let (s, uf2) = uf2_good();
        let p = check_uf2_image(&s, 0x2000_0000, &uf2);
        assert!(p.iter().any(|m| m.contains(".data at 0x20000000")), "{p:?}");
    }

    #[test]
    fn uf2_blocks_past_the_bootloader_limit_fail() {
        // Today's layout let code run to 0xEC000; the bootloader stops at 0xEA000.
        let mut data = image(0x26000, 0x2004_0000, &set_vtor_prologue(), &[VTOR, 0x26000]);
        data.resize(0xEA100 - 0x26000, 0xAA);
        let s = seg(0x26000, data);
        let uf2 = formats::to_uf2(std::slice::from_ref(&s), formats::UF2_FAMILY_NRF52840);
        let p = check_uf2_image(&s, 0x2000_0008, &uf2);
        assert!(p.iter().any(|m| m.contains("refuses blocks")), "{p:?}");
        assert!(p.iter().any(|m| m.contains("outside what")), "{p:?}");
    }

    #[test]
    fn wrong_uf2_family_fails() {
        let (s, _) = uf2_good();
        let uf2 = formats::to_uf2(std::slice::from_ref(&s), 0x1B57_745F);
        let p = check_uf2_image(&s, 0x2000_0008, &uf2);
        assert!(p.iter().any(|m| m.contains("family")), "{p:?}");
    }

    #[test]
    fn taulabs_stack_at_the_end_of_sram_fails_the_bootloader_mask() {
        let prologue = set_vtor_prologue();
        let bad = seg(
            0x0802_0000,
            image(0x0802_0000, 0x2002_0000, &prologue, &[VTOR, 0x0802_0000]),
        );
        let good = seg(
            0x0802_0000,
            image(0x0802_0000, 0x2001_FFF0, &prologue, &[VTOR, 0x0802_0000]),
        );
        for (s, want_fail) in [(bad, true), (good, false)] {
            let elf = elf_with(&s, 0x2000_0000);
            let (_, bin) = formats::to_bin(std::slice::from_ref(&s));
            let pkg = tlfw::package(&bin, 0x92, 0x01, "t");
            let files = Files {
                elf: &elf,
                bin: Some(&bin),
                uf2: None,
                tlfw: Some((&pkg, 0x92, 0x01)),
            };
            let p = check(&F405_TAULABS, &files);
            assert_eq!(
                p.iter().any(|m| m.contains("0x2FFE0000")),
                want_fail,
                "{p:?}"
            );
            assert_eq!(p.is_empty(), !want_fail, "{p:?}");
        }
    }

    #[test]
    fn tlfw_for_the_wrong_board_fails() {
        let s = seg(
            0x0802_0000,
            image(
                0x0802_0000,
                0x2001_FFF0,
                &set_vtor_prologue(),
                &[VTOR, 0x0802_0000],
            ),
        );
        let elf = elf_with(&s, 0x2000_0000);
        let (_, bin) = formats::to_bin(std::slice::from_ref(&s));
        let pkg = tlfw::package(&bin, 0x92, 0x22, "t");
        let files = Files {
            elf: &elf,
            bin: Some(&bin),
            uf2: None,
            tlfw: Some((&pkg, 0x92, 0x01)),
        };
        let p = check(&F405_TAULABS, &files);
        assert!(p.iter().any(|m| m.contains("rev 0x22")), "{p:?}");
    }

    #[test]
    fn code_on_the_settings_sectors_fails() {
        let mut data = image(
            0x0800_0000,
            0x2002_0000,
            &set_vtor_prologue(),
            &[VTOR, 0x0800_0000],
        );
        data.resize(0x8010, 0);
        let s = seg(0x0800_0000, data);
        let elf = elf_with(&s, 0x2000_0000);
        let files = Files {
            elf: &elf,
            bin: None,
            uf2: None,
            tlfw: None,
        };
        let p = check(&crate::layout::F405_DIRECT, &files);
        assert!(p.iter().any(|m| m.contains("settings")), "{p:?}");
    }
}
