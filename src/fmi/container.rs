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

/// Why serialized state bytes were refused.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum StateBytesError {
    /// Fewer bytes than the smallest container.
    TooShort(usize),
    /// The bytes do not start with [`MAGIC`].
    NotAState,
    /// Another format version.
    Version(u32),
    /// The length differs from the header's.
    Length {
        /// Bytes given.
        actual: usize,
        /// Bytes the header gives.
        expected: usize,
    },
    /// The header's lengths overflow.
    ImpossibleLengths(usize),
    /// The checksum does not match.
    Checksum,
    /// The GUID is not UTF-8.
    GuidNotText,
    /// The state belongs to another FMU.
    Foreign {
        /// The state's GUID.
        theirs: String,
        /// This FMU's GUID.
        ours: String,
    },
}

impl std::fmt::Display for StateBytesError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StateBytesError::TooShort(n) => write!(
                f,
                "{n} bytes are too few for a serialized state (at least {MIN_LEN}); it was truncated"
            ),
            StateBytesError::NotAState => write!(
                f,
                "the bytes are not a serialized state of origami-fmu (they do not start with \
                 \"OFMUSTAT\")"
            ),
            StateBytesError::Version(v) => write!(
                f,
                "the state has format version {v}; this library reads version {FORMAT_VERSION}"
            ),
            StateBytesError::Length { actual, expected } => write!(
                f,
                "the state has {actual} bytes but its header says {expected}; it was truncated or extended"
            ),
            StateBytesError::ImpossibleLengths(n) => write!(
                f,
                "the state has {n} bytes but its header gives impossible lengths; it was truncated \
                 or corrupted"
            ),
            StateBytesError::Checksum => write!(
                f,
                "the state's checksum does not match its bytes: they were changed after \
                 fmi2SerializeFMUstate wrote them"
            ),
            StateBytesError::GuidNotText => write!(f, "the state's GUID is not text"),
            StateBytesError::Foreign { theirs, ours } => write!(
                f,
                "the state belongs to the FMU with GUID {theirs}, not to this one ({ours}): another \
                 scene or library version"
            ),
        }
    }
}

impl std::error::Error for StateBytesError {}

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
fn header(
    bytes: &[u8],
) -> Result<(std::ops::Range<usize>, std::ops::Range<usize>), StateBytesError> {
    let n = bytes.len();
    if n < MIN_LEN {
        return Err(StateBytesError::TooShort(n));
    }
    if &bytes[..8] != MAGIC {
        return Err(StateBytesError::NotAState);
    }
    let word =
        |at: usize| u32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
    let version = word(8);
    if version != FORMAT_VERSION {
        return Err(StateBytesError::Version(version));
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
        Some(e) => Err(StateBytesError::Length {
            actual: n,
            expected: e,
        }),
        None => Err(StateBytesError::ImpossibleLengths(n)),
    }
}

/// The GUID a container names (its header checked, not its checksum).
pub fn guid(bytes: &[u8]) -> Result<&str, StateBytesError> {
    let (g, _) = header(bytes)?;
    std::str::from_utf8(&bytes[g]).map_err(|_| StateBytesError::GuidNotText)
}

/// The payload of a container written by [`seal`] for GUID `guid`; any
/// other bytes are refused with the reason.
pub fn open<'a>(guid: &str, bytes: &'a [u8]) -> Result<&'a [u8], StateBytesError> {
    let (g, payload) = header(bytes)?;
    let body = bytes.len() - CHECKSUM;
    let [a, b] = hash128(&[&bytes[..body]]);
    let mut sum = [0u8; CHECKSUM];
    sum[..8].copy_from_slice(&a.to_le_bytes());
    sum[8..].copy_from_slice(&b.to_le_bytes());
    if bytes[body..] != sum {
        return Err(StateBytesError::Checksum);
    }
    let theirs = String::from_utf8_lossy(&bytes[g]);
    if theirs != guid {
        return Err(foreign(&theirs, guid));
    }
    Ok(&bytes[payload])
}

/// The refusal of a state of the FMU with GUID `theirs` by one with `ours`.
pub fn foreign(theirs: &str, ours: &str) -> StateBytesError {
    StateBytesError::Foreign {
        theirs: theirs.into(),
        ours: ours.into(),
    }
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
        assert!(
            open("{h}", &c)
                .unwrap_err()
                .to_string()
                .contains("GUID {g}")
        );
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
        assert!(
            open("{g}", &v2)
                .unwrap_err()
                .to_string()
                .contains("version 2")
        );
        let mut long = c.clone();
        long.push(0);
        assert!(
            open("{g}", &long)
                .unwrap_err()
                .to_string()
                .contains("extended")
        );
        // Lengths that overflow are refused, not wrapped.
        let mut huge = c.clone();
        huge[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(open("{g}", &huge).is_err());
        let mut huge = c;
        huge[19..27].copy_from_slice(&u64::MAX.to_le_bytes());
        assert!(open("{g}", &huge).is_err());
    }
}
