//! The bytes of a serialized FMU state: a versioned, checksummed container
//! around a payload (the JSON of the saved state), bound to the GUID of
//! the FMU that wrote it.
//!
//! ```text
//! offset      size  content (integers little-endian)
//! 0           8     magic "OFMUSTAT"
//! 8           4     format version (FORMAT_VERSION)
//! 12          4     GUID length g
//! 16          g     GUID (ASCII, as in modelDescription.xml)
//! 16+g        8     payload length p
//! 24+g        p     payload
//! 24+g+p      16    checksum: hash128 of every byte before it
//! ```
//!
//! [`open`] checks, in this order, the length against the header, the
//! magic number, the version, the checksum and the GUID, so that a
//! truncated, extended or corrupted state, or one of another scene, is
//! refused before its payload is parsed. The checksum detects corruption
//! (every single-byte change, see `hash128`), not
//! malice: a forged payload with a recomputed checksum passes here and is
//! refused by the checks of every value it holds
//! ([`crate::model::Model::check_state`]). The payload is opaque to this
//! file, so the saved state's struct may gain or lose a field without a
//! change here.

use super::resources::hash128;

/// First bytes of every serialized state.
pub const MAGIC: &[u8; 8] = b"OFMUSTAT";

/// The container's format version; a state of another version is refused.
pub const FORMAT_VERSION: u32 = 1;

/// Bytes of the checksum at the end.
const CHECKSUM: usize = 16;

/// Bytes before the GUID (magic, version, GUID length).
const HEAD: usize = 16;

/// Bytes of a container with an empty GUID and payload.
pub const MIN_LEN: usize = HEAD + 8 + CHECKSUM;

/// The container of `payload` for the FMU with GUID `guid`.
pub fn seal(guid: &str, payload: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(MIN_LEN + guid.len() + payload.len());
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    out.extend_from_slice(&(guid.len() as u32).to_le_bytes());
    out.extend_from_slice(guid.as_bytes());
    out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    out.extend_from_slice(payload);
    let [a, b] = hash128(&[&out]);
    out.extend_from_slice(&a.to_le_bytes());
    out.extend_from_slice(&b.to_le_bytes());
    out
}

/// The header: GUID and payload ranges, with the length, magic number
/// and version checked (not the checksum).
fn header(bytes: &[u8]) -> Result<(std::ops::Range<usize>, std::ops::Range<usize>), String> {
    let n = bytes.len();
    if n < MIN_LEN {
        return Err(format!(
            "{n} bytes are too few for a serialized state (at least {MIN_LEN}); it was truncated"
        ));
    }
    if &bytes[..8] != MAGIC {
        return Err(
            "the bytes are not a serialized state of origami-fmu (they do not start with \
             \"OFMUSTAT\")"
                .into(),
        );
    }
    let word =
        |at: usize| u32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
    let version = word(8);
    if version != FORMAT_VERSION {
        return Err(format!(
            "the state has format version {version}; this library reads version {FORMAT_VERSION}"
        ));
    }
    let g = word(12) as usize;
    let at = HEAD.saturating_add(g);
    let p = match bytes.get(at..at.saturating_add(8)) {
        Some(b) => {
            let mut w = [0u8; 8];
            w.copy_from_slice(b);
            u64::from_le_bytes(w)
        }
        None => u64::MAX,
    };
    let expected = usize::try_from(p)
        .ok()
        .and_then(|p| MIN_LEN.checked_add(g)?.checked_add(p));
    match expected {
        Some(e) if e == n => Ok((HEAD..at, at + 8..n - CHECKSUM)),
        Some(e) => Err(format!(
            "the state has {n} bytes but its header says {e}; it was truncated or extended"
        )),
        None => Err(format!(
            "the state has {n} bytes but its header gives impossible lengths; it was truncated \
             or corrupted"
        )),
    }
}

/// The GUID a container names (its header checked, not its checksum).
pub fn guid(bytes: &[u8]) -> Result<&str, String> {
    let (g, _) = header(bytes)?;
    std::str::from_utf8(&bytes[g]).map_err(|_| "the state's GUID is not text".into())
}

/// The payload of a container written by [`seal`] for GUID `guid`; any
/// other bytes are refused with the reason.
pub fn open<'a>(guid: &str, bytes: &'a [u8]) -> Result<&'a [u8], String> {
    let (g, payload) = header(bytes)?;
    let body = bytes.len() - CHECKSUM;
    let [a, b] = hash128(&[&bytes[..body]]);
    let mut sum = [0u8; CHECKSUM];
    sum[..8].copy_from_slice(&a.to_le_bytes());
    sum[8..].copy_from_slice(&b.to_le_bytes());
    if bytes[body..] != sum {
        return Err(
            "the state's checksum does not match its bytes: they were changed after \
             fmi2SerializeFMUstate wrote them"
                .into(),
        );
    }
    let theirs = String::from_utf8_lossy(&bytes[g]);
    if theirs != guid {
        return Err(foreign(&theirs, guid));
    }
    Ok(&bytes[payload])
}

/// The refusal of a state of the FMU with GUID `theirs` by one with `ours`.
pub fn foreign(theirs: &str, ours: &str) -> String {
    format!(
        "the state belongs to the FMU with GUID {theirs}, not to this one ({ours}): another \
         scene or library version"
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_refusals() {
        let c = seal("{g}", b"payload");
        assert_eq!(c.len(), MIN_LEN + 3 + 7);
        assert_eq!(open("{g}", &c), Ok(&b"payload"[..]));
        assert_eq!(guid(&c), Ok("{g}"));
        assert!(open("{h}", &c).unwrap_err().contains("GUID {g}"));
        for n in 0..c.len() {
            assert!(open("{g}", &c[..n]).is_err(), "{n}");
        }
        for bit in 0..8 * c.len() {
            let mut d = c.clone();
            d[bit / 8] ^= 1 << (bit % 8);
            assert!(open("{g}", &d).is_err(), "bit {bit}");
        }
        let mut v2 = c.clone();
        v2[8] = 2;
        assert!(open("{g}", &v2).unwrap_err().contains("version 2"));
        let mut long = c.clone();
        long.push(0);
        assert!(open("{g}", &long).unwrap_err().contains("extended"));
        // Lengths that overflow are refused, not wrapped.
        let mut huge = c.clone();
        huge[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(open("{g}", &huge).is_err());
        let mut huge = c;
        huge[19..27].copy_from_slice(&u64::MAX.to_le_bytes());
        assert!(open("{g}", &huge).is_err());
    }
}
