//! Flashable file formats from load segments: raw binary (USB DFU), Intel HEX (probe-rs,
//! nRF tools) and UF2 (drag-and-drop bootloaders such as the nice!nano's).

use fw_elf::Segment;

/// Flat image from the lowest to the highest loaded address, gaps filled with 0xFF (the
/// erased state of flash). Returns the start address and the bytes.
pub fn to_bin(segments: &[Segment]) -> (u32, Vec<u8>) {
    let Some(start) = segments.iter().map(|s| s.address).min() else {
        return (0, Vec::new());
    };
    let end = segments
        .iter()
        .map(|s| s.address as usize + s.data.len())
        .max()
        .unwrap_or(start as usize);
    let mut image = vec![0xFF; end - start as usize];
    for s in segments {
        let at = (s.address - start) as usize;
        if let Some(dst) = image.get_mut(at..at + s.data.len()) {
            dst.copy_from_slice(&s.data);
        }
    }
    (start, image)
}

fn hex_record(kind: u8, address: u16, data: &[u8]) -> String {
    let mut bytes = vec![data.len() as u8, (address >> 8) as u8, address as u8, kind];
    bytes.extend_from_slice(data);
    let sum = bytes.iter().fold(0u8, |a, b| a.wrapping_add(*b));
    bytes.push(sum.wrapping_neg());
    let mut line = String::from(":");
    for b in bytes {
        line.push_str(&format!("{b:02X}"));
    }
    line.push('\n');
    line
}

/// Intel HEX with 16-byte data records and extended linear address records.
pub fn to_ihex(segments: &[Segment]) -> String {
    let mut out = String::new();
    let mut upper: Option<u16> = None;
    for s in segments {
        for (i, chunk) in s.data.chunks(16).enumerate() {
            let address = s.address + (i * 16) as u32;
            // A record must not cross a 64 KiB boundary: split it if it would.
            let room = (0x1_0000 - (address & 0xFFFF)) as usize;
            let (first, rest) = chunk.split_at(room.min(chunk.len()));
            for (address, part) in [(address, first), (address + first.len() as u32, rest)] {
                if part.is_empty() {
                    continue;
                }
                let hi = (address >> 16) as u16;
                if upper != Some(hi) {
                    out.push_str(&hex_record(0x04, 0, &hi.to_be_bytes()));
                    upper = Some(hi);
                }
                out.push_str(&hex_record(0x00, address as u16, part));
            }
        }
    }
    out.push_str(&hex_record(0x01, 0, &[]));
    out
}

/// UF2 family ID of the nRF52840 (Microsoft's uf2 families.json).
pub const UF2_FAMILY_NRF52840: u32 = 0xADA5_2840;

/// UF2: 512-byte blocks carrying 256 bytes each, covering every 256-byte page that holds
/// loaded data (pages that only lie in gaps between segments are left out).
pub fn to_uf2(segments: &[Segment], family: u32) -> Vec<u8> {
    const PAYLOAD: u32 = 256;
    let (start, image) = to_bin(segments);
    let base = start & !(PAYLOAD - 1);
    let mut padded = vec![0xFF; (start - base) as usize];
    padded.extend_from_slice(&image);
    let covered = |addr: u32| {
        segments
            .iter()
            .any(|s| addr < s.address + s.data.len() as u32 && s.address < addr + PAYLOAD)
    };
    let pages: Vec<(u32, &[u8])> = padded
        .chunks(PAYLOAD as usize)
        .enumerate()
        .map(|(i, c)| (base + i as u32 * PAYLOAD, c))
        .filter(|(addr, _)| covered(*addr))
        .collect();
    let total = pages.len() as u32;
    let mut out = Vec::with_capacity(pages.len() * 512);
    for (n, (addr, chunk)) in pages.into_iter().enumerate() {
        let words = [
            0x0A32_4655,
            0x9E5D_5157,
            0x0000_2000, // flag: familyID present
            addr,
            PAYLOAD,
            n as u32,
            total,
            family,
        ];
        let block_start = out.len();
        for w in words {
            out.extend_from_slice(&w.to_le_bytes());
        }
        out.extend_from_slice(chunk);
        // Unused payload bytes are erased flash; then zero padding up to the end magic.
        out.resize(block_start + 32 + PAYLOAD as usize, 0xFF);
        out.resize(block_start + 508, 0);
        out.extend_from_slice(&0x0AB1_6F30u32.to_le_bytes());
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seg(address: u32, data: &[u8]) -> Segment {
        Segment {
            address,
            data: data.to_vec(),
        }
    }

    #[test]
    fn bin_fills_gaps_with_erased_flash() {
        let (start, image) = to_bin(&[seg(0x100, &[1, 2]), seg(0x104, &[3])]);
        assert_eq!(start, 0x100);
        assert_eq!(image, vec![1, 2, 0xFF, 0xFF, 3]);
    }

    #[test]
    fn ihex_records_and_checksums() {
        // Worked by hand: 02 0000 04 0800 → sum 0x0E → checksum 0xF2.
        let hex = to_ihex(&[seg(0x0800_0000, &[0xDE, 0xAD])]);
        assert_eq!(hex, ":020000040800F2\n:02000000DEAD73\n:00000001FF\n");
    }

    #[test]
    fn ihex_splits_at_64k_boundaries() {
        let hex = to_ihex(&[seg(0x0000_FFF8, &[0u8; 16])]);
        let lines: Vec<&str> = hex.lines().collect();
        assert_eq!(lines[0], ":020000040000FA");
        assert!(lines[1].starts_with(":08FFF800"));
        assert_eq!(lines[2], ":020000040001F9");
        assert!(lines[3].starts_with(":08000000"));
    }

    #[test]
    fn uf2_blocks_are_well_formed() {
        let data: Vec<u8> = (0..300u32).map(|i| i as u8).collect();
        let uf2 = to_uf2(&[seg(0x26010, &data)], UF2_FAMILY_NRF52840);
        assert_eq!(uf2.len(), 2 * 512, "0x26000..0x26200 → two 256-byte pages");
        let word = |b: &[u8], i: usize| u32::from_le_bytes(b[i * 4..i * 4 + 4].try_into().unwrap());
        let (b0, b1) = uf2.split_at(512);
        assert_eq!(word(b0, 0), 0x0A32_4655);
        assert_eq!(word(b0, 3), 0x26000);
        assert_eq!(word(b1, 3), 0x26100);
        assert_eq!(word(b1, 5), 1);
        assert_eq!(word(b1, 6), 2);
        assert_eq!(word(b0, 7), UF2_FAMILY_NRF52840);
        assert_eq!(
            &b0[32..48],
            &[0xFF; 16],
            "bytes before the image are erased flash"
        );
        assert_eq!(b0[48], 0);
        assert_eq!(b1[32], 0xF0, "0x26100 holds data byte 0xF0");
        assert_eq!(word(b0, 127), 0x0AB1_6F30);
    }
}
