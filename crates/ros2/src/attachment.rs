//! The attachment rmw_zenoh puts on every sample: 33 bytes, the sequence
//! number (i64, little-endian, from 1 per publisher), the source timestamp
//! (i64 LE, ns since the Unix epoch), then the publisher's 16-byte GID as
//! Zenoh's serializer writes a sequence (a LEB128 length, `0x10`, then the
//! bytes).
//!
//! From rmw_zenoh (<https://github.com/ros2/rmw_zenoh>),
//! `rmw_zenoh_cpp/src/detail/attachment_helpers.cpp`
//! (`AttachmentData::serialize_to_zbytes`: `zenoh::ext::Serializer`,
//! `serialize(sequence_number_)`, `serialize(source_timestamp_)`,
//! `serialize(source_gid_)`, the GID a `std::array<uint8_t, 16>`), in the
//! form it has had since rmw_zenoh_cpp 0.6.0 ("Change serialization format
//! in attachment_helpers.cpp", #601) and in ROS 2 Jazzy's and Kilted's
//! releases. A sample without a well-formed attachment is still taken
//! (its payload is what counts), and counted.

/// The attachment's length.
pub const LEN: usize = 33;

/// One sample's attachment.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Attachment {
    /// The publisher's sequence number (from 1).
    pub sequence_number: i64,
    /// When it was published, ns since the Unix epoch.
    pub source_timestamp: i64,
    /// The publisher's GID.
    pub gid: [u8; 16],
}

/// Why an attachment did not decode.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum AttachmentError {
    /// Not 33 bytes.
    #[error("attachment of {0} bytes, not 33")]
    Length(usize),
    /// The GID's length byte is not 16.
    #[error("attachment GID length {0}, not 16")]
    GidLength(u8),
}

impl Attachment {
    /// The 33 bytes.
    pub fn encode(&self) -> [u8; LEN] {
        let mut out = [0u8; LEN];
        out[..8].copy_from_slice(&self.sequence_number.to_le_bytes());
        out[8..16].copy_from_slice(&self.source_timestamp.to_le_bytes());
        out[16] = 16;
        out[17..].copy_from_slice(&self.gid);
        out
    }

    /// Reads 33 bytes.
    pub fn decode(bytes: &[u8]) -> Result<Self, AttachmentError> {
        let b: &[u8; LEN] = bytes
            .try_into()
            .map_err(|_| AttachmentError::Length(bytes.len()))?;
        if b[16] != 16 {
            return Err(AttachmentError::GidLength(b[16]));
        }
        let mut i = [0u8; 8];
        i.copy_from_slice(&b[..8]);
        let sequence_number = i64::from_le_bytes(i);
        i.copy_from_slice(&b[8..16]);
        let source_timestamp = i64::from_le_bytes(i);
        let mut gid = [0u8; 16];
        gid.copy_from_slice(&b[17..]);
        Ok(Self {
            sequence_number,
            source_timestamp,
            gid,
        })
    }
}

/// A publisher's GID, as rmw_zenoh computes it: the XXH3-128 hash (seed
/// 0, the default secret) of the publisher's liveliness token, its low 64
/// bits then its high 64 bits, each little-endian (`memcpy` of
/// `XXH128_hash_t::low64` and `::high64` on a little-endian host).
///
/// From rmw_zenoh (<https://github.com/ros2/rmw_zenoh>),
/// `rmw_zenoh_cpp/src/detail/liveliness_utils.cpp`, `Entity::Entity` (at
/// commit 3411fdec149fe0c932f24d4d79ef908eb81d7482: "we hash the complete
/// std::string that comprises the liveliness keyexpression into a GID"),
/// with `simplified_xxhash3.cpp` (xxHash's XXH3_128bits, extracted); the
/// attachment carries it (`rmw_publisher_data.cpp` at commit
/// 3e19ec730c529035a648aec80c0ae0a056943b8c: `entity_->copy_gid()`). The
/// hash came in with "Add the GID hash" (#298, commit
/// 97aed4819677b9825b20bb44a01707f42843e06a); some releases in between
/// put a random GID in the attachment instead (`generate_random_gid`),
/// which no subscriber can check, so the hash is the form to match.
pub fn gid_of(token: &str) -> [u8; 16] {
    twox_hash::XxHash3_128::oneshot(token.as_bytes()).to_le_bytes()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_attachment_is_two_int64s_a_length_byte_and_the_gid() {
        let a = Attachment {
            sequence_number: 1,
            source_timestamp: 0x0102030405060708,
            gid: [0xab; 16],
        };
        let b = a.encode();
        assert_eq!(b.len(), 33);
        assert_eq!(&b[..8], &[1, 0, 0, 0, 0, 0, 0, 0]);
        assert_eq!(&b[8..16], &[8, 7, 6, 5, 4, 3, 2, 1]);
        assert_eq!(b[16], 0x10);
        assert_eq!(Attachment::decode(&b), Ok(a));
    }

    #[test]
    fn a_malformed_attachment_is_an_error() {
        assert_eq!(Attachment::decode(&[0; 5]), Err(AttachmentError::Length(5)));
        assert_eq!(
            Attachment::decode(&[0; 33]),
            Err(AttachmentError::GidLength(0))
        );
    }

    #[test]
    fn gids_of_different_tokens_differ() {
        assert_ne!(gid_of("@ros2_lv/0/a/0/1/MP"), gid_of("@ros2_lv/0/a/0/2/MP"));
    }

    #[test]
    fn a_gid_is_xxh3_128_of_the_token_low_half_first() {
        // XXH3-128 of the empty input (seed 0) is
        // 0x99aa06d3014798d86001c324468d497f (xxHash's own test vector):
        // low64 0x6001c324468d497f first, then high64, each little-endian.
        let g = gid_of("");
        assert_eq!(&g[..8], &0x6001c324468d497fu64.to_le_bytes());
        assert_eq!(&g[8..], &0x99aa06d3014798d8u64.to_le_bytes());
    }
}
