//! Tau Labs firmware packages (`.tlfw`), as the Tau Labs GCS uploads them through its
//! bootloader: the raw firmware (`.bin` from the bank base) followed by the 100-byte firmware
//! descriptor that the bootloader keeps in the last 100 bytes of the firmware bank.
//!
//! The descriptor is `struct fw_version_info` from Tau Labs' make/templates/
//! firmwareinfotemplate.c, filled as make/scripts/version-info.py fills it: magic "TlFw",
//! commit hash prefix, build time, board type and revision (the board's board-info.mk),
//! a 26-byte tag, the SHA-1 of the firmware, the SHA-1 of the UAVO definitions (zero: we have
//! no UAVOs) and 20 bytes of padding. The GCS compares board type and revision with the
//! board's bootloader before it uploads; the CRC the bootloader checks is computed by the GCS
//! over the firmware during upload, it is not in the file.

/// Size of the descriptor at the end of the firmware bank (FW_DESC_SIZE).
pub const DESCRIPTOR_LEN: usize = 100;
/// Board type of every Sparky2-family board in Tau Labs' board-info blob.
pub const BOARD_TYPE_SPARKY2: u8 = 0x92;
/// Sparky2 v2.0 (flight/targets/sparky2/board-info/board-info.mk).
pub const REVISION_SPARKY2: u8 = 0x01;
/// BrushedSparky rev 0x22 (nIRQ on PB7).
pub const REVISION_BRUSHEDSPARKY: u8 = 0x22;

/// What the descriptor says.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Descriptor {
    /// Board type the image is for.
    pub board_type: u8,
    /// Board revision the image is for.
    pub board_revision: u8,
    /// SHA-1 of the firmware part.
    pub sha1: [u8; 20],
    /// Version tag (zero-padded).
    pub tag: String,
}

fn put(out: &mut Vec<u8>, bytes: &[u8], len: usize) {
    let n = bytes.len().min(len);
    out.extend_from_slice(bytes.get(..n).unwrap_or_default());
    out.resize(out.len() + len - n, 0);
}

/// The `.tlfw` file for `firmware` (the `.bin` from the firmware bank base).
pub fn package(firmware: &[u8], board_type: u8, board_revision: u8, tag: &str) -> Vec<u8> {
    let mut out = firmware.to_vec();
    out.extend_from_slice(b"TlFw");
    // No git commit or build time baked in: the package is reproducible from the ELF.
    out.extend_from_slice(&0u32.to_le_bytes());
    out.extend_from_slice(&0u32.to_le_bytes());
    out.push(board_type);
    out.push(board_revision);
    put(&mut out, tag.as_bytes(), 26);
    out.extend_from_slice(&sha1(firmware));
    put(&mut out, &[], 40);
    out
}

/// Splits a `.tlfw` into firmware and descriptor, checking the magic and the SHA-1.
pub fn parse(file: &[u8]) -> Result<(&[u8], Descriptor), String> {
    let split = file
        .len()
        .checked_sub(DESCRIPTOR_LEN)
        .ok_or("shorter than a firmware descriptor")?;
    let (firmware, d) = file.split_at(split);
    if d.get(0..4) != Some(b"TlFw") {
        return Err("descriptor magic is not \"TlFw\"".into());
    }
    let field = |r: std::ops::Range<usize>| d.get(r).unwrap_or_default();
    let mut sha = [0u8; 20];
    sha.copy_from_slice(field(40..60));
    if sha != sha1(firmware) {
        return Err("descriptor SHA-1 does not match the firmware".into());
    }
    let tag = field(14..40);
    let end = tag.iter().position(|&b| b == 0).unwrap_or(tag.len());
    Ok((
        firmware,
        Descriptor {
            board_type: field(12..13).first().copied().unwrap_or(0),
            board_revision: field(13..14).first().copied().unwrap_or(0),
            sha1: sha,
            tag: String::from_utf8_lossy(tag.get(..end).unwrap_or_default()).into_owned(),
        },
    ))
}

/// SHA-1 (FIPS 180-4), as version-info.py's hashlib computes it over the firmware.
pub fn sha1(data: &[u8]) -> [u8; 20] {
    let mut h: [u32; 5] = [
        0x6745_2301,
        0xEFCD_AB89,
        0x98BA_DCFE,
        0x1032_5476,
        0xC3D2_E1F0,
    ];
    let mut msg = data.to_vec();
    msg.push(0x80);
    while msg.len() % 64 != 56 {
        msg.push(0);
    }
    msg.extend_from_slice(&((data.len() as u64) * 8).to_be_bytes());
    for block in msg.chunks_exact(64) {
        let mut w: Vec<u32> = block
            .chunks_exact(4)
            .map(|c| u32::from_be_bytes(c.try_into().unwrap_or([0; 4])))
            .collect();
        for i in 16..80 {
            let at = |j: usize| w.get(i - j).copied().unwrap_or(0);
            let next = (at(3) ^ at(8) ^ at(14) ^ at(16)).rotate_left(1);
            w.push(next);
        }
        let [mut a, mut b, mut c, mut d, mut e] = h;
        for (i, wi) in w.iter().enumerate() {
            let (f, k) = match i {
                0..=19 => ((b & c) | (!b & d), 0x5A82_7999),
                20..=39 => (b ^ c ^ d, 0x6ED9_EBA1),
                40..=59 => ((b & c) | (b & d) | (c & d), 0x8F1B_BCDC),
                _ => (b ^ c ^ d, 0xCA62_C1D6),
            };
            let t = a
                .rotate_left(5)
                .wrapping_add(f)
                .wrapping_add(e)
                .wrapping_add(k)
                .wrapping_add(*wi);
            (e, d, c, b, a) = (d, c, b.rotate_left(30), a, t);
        }
        for (x, y) in h.iter_mut().zip([a, b, c, d, e]) {
            *x = x.wrapping_add(y);
        }
    }
    let mut out = [0u8; 20];
    for (chunk, x) in out.chunks_exact_mut(4).zip(h) {
        chunk.copy_from_slice(&x.to_be_bytes());
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hex(b: &[u8]) -> String {
        b.iter().map(|x| format!("{x:02x}")).collect()
    }

    #[test]
    fn sha1_known_answers() {
        assert_eq!(
            hex(&sha1(b"abc")),
            "a9993e364706816aba3e25717850c26c9cd0d89d"
        );
        assert_eq!(hex(&sha1(b"")), "da39a3ee5e6b4b0d3255bfef95601890afd80709");
        let long = b"abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq";
        assert_eq!(hex(&sha1(long)), "84983e441c3bd26ebaae4aa1f95129e5e54670f1");
    }

    #[test]
    fn package_layout_matches_fw_version_info() {
        let fw = [1u8, 2, 3, 4, 5];
        let p = package(&fw, BOARD_TYPE_SPARKY2, REVISION_SPARKY2, "taulink");
        assert_eq!(p.len(), fw.len() + DESCRIPTOR_LEN);
        let d = &p[fw.len()..];
        assert_eq!(&d[0..4], b"TlFw");
        assert_eq!(d[12], 0x92);
        assert_eq!(d[13], 0x01);
        assert_eq!(&d[14..21], b"taulink");
        assert_eq!(d[21], 0);
        assert_eq!(&d[40..60], &sha1(&fw));
        let (firmware, desc) = parse(&p).unwrap();
        assert_eq!(firmware, &fw);
        assert_eq!(desc.board_revision, 0x01);
        assert_eq!(desc.tag, "taulink");
    }

    #[test]
    fn parse_rejects_a_wrong_sha1_or_magic() {
        let mut p = package(&[9u8; 64], BOARD_TYPE_SPARKY2, REVISION_BRUSHEDSPARKY, "x");
        p[0] ^= 1;
        assert!(parse(&p).is_err());
        let mut q = package(&[9u8; 64], BOARD_TYPE_SPARKY2, REVISION_BRUSHEDSPARKY, "x");
        q[64] = b'O';
        assert!(parse(&q).is_err());
        assert!(parse(&[0u8; 10]).is_err());
    }
}
