//! Little-endian plain CDR (XCDR1), as ROS 2 puts it on the wire: a 4-byte
//! encapsulation header `00 01 00 00` (CDR_LE, no options), then the fields
//! in declaration order, each primitive aligned to its own size counted
//! from the end of the header; a string is a `u32` length that counts its
//! terminating NUL, the bytes, the NUL; a sequence is a `u32` count and its
//! elements; a fixed array its elements only. (OMG, "Common Object Request
//! Broker Architecture (CORBA), Part 2: Interoperability", version 3.3,
//! 9.3 "CDR Transfer Syntax"; the encapsulation identifiers of OMG DDS-XTypes
//! 1.3, 7.6.3.1.2.)

/// The encapsulation header of little-endian plain CDR.
pub const HEADER_LE: [u8; 4] = [0x00, 0x01, 0x00, 0x00];

/// Why a CDR payload did not decode.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum CdrError {
    /// The payload is shorter than its header or its fields.
    #[error("CDR payload too short: {needed} bytes needed at offset {at}, {len} in all")]
    Short {
        /// Offset (after the header) of the field that did not fit.
        at: usize,
        /// Bytes it needed.
        needed: usize,
        /// The payload's length after the header.
        len: usize,
    },
    /// The encapsulation is not plain CDR (big- or little-endian).
    #[error("CDR encapsulation {0:02x?} is not plain CDR (00 00 or 00 01)")]
    Encapsulation([u8; 2]),
    /// Bytes left over after the message's last field (beyond alignment
    /// padding): the payload is of a larger type.
    #[error("{0} bytes after the message's last field: not this message type")]
    Trailing(usize),
    /// A string is not NUL-terminated UTF-8.
    #[error("a CDR string is not NUL-terminated UTF-8")]
    BadString,
}

/// Writes one message: the header, then fields appended in order.
#[derive(Debug, Clone)]
pub struct Writer {
    buf: Vec<u8>,
}

impl Default for Writer {
    fn default() -> Self {
        Self::new()
    }
}

impl Writer {
    /// A message with its little-endian header written.
    pub fn new() -> Self {
        let mut buf = Vec::with_capacity(256);
        buf.extend_from_slice(&HEADER_LE);
        Self { buf }
    }

    fn align(&mut self, n: usize) {
        let off = self.buf.len() - HEADER_LE.len();
        let pad = (n - off % n) % n;
        self.buf.resize(self.buf.len() + pad, 0);
    }

    /// A `uint8` or `int8`.
    pub fn u8(&mut self, v: u8) {
        self.buf.push(v);
    }

    /// A `uint32`.
    pub fn u32(&mut self, v: u32) {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// An `int32`.
    pub fn i32(&mut self, v: i32) {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// A `float32`.
    pub fn f32(&mut self, v: f32) {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// A `float64`.
    pub fn f64(&mut self, v: f64) {
        self.align(8);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// A `string`.
    pub fn string(&mut self, s: &str) {
        // A ROS string is far shorter than 4 GiB; a longer one is cut.
        let len = u32::try_from(s.len() + 1).unwrap_or(u32::MAX);
        self.u32(len);
        self.buf
            .extend_from_slice(&s.as_bytes()[..(len as usize).saturating_sub(1)]);
        self.buf.push(0);
    }

    /// A sequence's element count.
    pub fn count(&mut self, n: usize) {
        self.u32(u32::try_from(n).unwrap_or(u32::MAX));
    }

    /// The message's bytes, header included.
    pub fn finish(self) -> Vec<u8> {
        self.buf
    }
}

/// Reads one message's fields in order.
#[derive(Debug, Clone)]
pub struct Reader<'a> {
    body: &'a [u8],
    at: usize,
    big_endian: bool,
}

impl<'a> Reader<'a> {
    /// Reads the header of `payload`; plain CDR of either byte order.
    pub fn new(payload: &'a [u8]) -> Result<Self, CdrError> {
        let (head, body) = payload.split_at_checked(4).ok_or(CdrError::Short {
            at: 0,
            needed: 4,
            len: payload.len(),
        })?;
        let big_endian = match [head[0], head[1]] {
            [0, 1] => false,
            [0, 0] => true,
            other => return Err(CdrError::Encapsulation(other)),
        };
        Ok(Self {
            body,
            at: 0,
            big_endian,
        })
    }

    fn take<const N: usize>(&mut self) -> Result<[u8; N], CdrError> {
        let pad = (N - self.at % N) % N;
        let start = self.at + pad;
        let bytes = self.body.get(start..start + N).ok_or(CdrError::Short {
            at: start,
            needed: N,
            len: self.body.len(),
        })?;
        self.at = start + N;
        let mut out = [0u8; N];
        out.copy_from_slice(bytes);
        if self.big_endian {
            out.reverse();
        }
        Ok(out)
    }

    /// A `uint8`.
    pub fn u8(&mut self) -> Result<u8, CdrError> {
        self.take::<1>().map(|b| b[0])
    }

    /// A `uint32`.
    pub fn u32(&mut self) -> Result<u32, CdrError> {
        self.take::<4>().map(u32::from_le_bytes)
    }

    /// An `int32`.
    pub fn i32(&mut self) -> Result<i32, CdrError> {
        self.take::<4>().map(i32::from_le_bytes)
    }

    /// A `float32`.
    pub fn f32(&mut self) -> Result<f32, CdrError> {
        self.take::<4>().map(f32::from_le_bytes)
    }

    /// A `float64`.
    pub fn f64(&mut self) -> Result<f64, CdrError> {
        self.take::<8>().map(f64::from_le_bytes)
    }

    /// A `string`.
    pub fn string(&mut self) -> Result<String, CdrError> {
        let len = self.u32()? as usize;
        let bytes = self
            .body
            .get(self.at..self.at.saturating_add(len))
            .ok_or(CdrError::Short {
                at: self.at,
                needed: len,
                len: self.body.len(),
            })?;
        self.at += len;
        match bytes.split_last() {
            Some((0, text)) => std::str::from_utf8(text)
                .map(str::to_string)
                .map_err(|_| CdrError::BadString),
            _ => Err(CdrError::BadString),
        }
    }

    /// Ends the message: anything but up to 7 bytes of padding after the
    /// last field means the payload was of another type.
    pub fn end(self) -> Result<(), CdrError> {
        let left = self.body.len() - self.at.min(self.body.len());
        if left >= 8 {
            return Err(CdrError::Trailing(left));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_float64_after_a_uint32_is_padded_to_eight_bytes_from_the_header() {
        let mut w = Writer::new();
        w.u32(7);
        w.f64(1.5);
        let b = w.finish();
        assert_eq!(&b[..4], &HEADER_LE);
        assert_eq!(b.len(), 4 + 4 + 4 + 8);
        assert_eq!(&b[8..12], &[0, 0, 0, 0]);
        let mut r = Reader::new(&b).unwrap();
        assert_eq!(r.u32().unwrap(), 7);
        assert_eq!(r.f64().unwrap(), 1.5);
        r.end().unwrap();
    }

    #[test]
    fn a_string_counts_its_terminating_nul() {
        let mut w = Writer::new();
        w.string("odom");
        let b = w.finish();
        assert_eq!(&b[4..], &[5, 0, 0, 0, b'o', b'd', b'o', b'm', 0]);
        assert_eq!(Reader::new(&b).unwrap().string().unwrap(), "odom");
    }

    #[test]
    fn a_short_payload_is_an_error_not_a_panic() {
        let mut r = Reader::new(&[0, 1, 0, 0, 1, 2]).unwrap();
        assert!(matches!(r.f64(), Err(CdrError::Short { .. })));
        assert!(matches!(Reader::new(&[0, 1]), Err(CdrError::Short { .. })));
        assert!(matches!(
            Reader::new(&[0, 7, 0, 0]),
            Err(CdrError::Encapsulation(_))
        ));
    }

    #[test]
    fn big_endian_cdr_reads_too() {
        let mut b = vec![0, 0, 0, 0];
        b.extend_from_slice(&2.5f64.to_be_bytes());
        assert_eq!(Reader::new(&b).unwrap().f64().unwrap(), 2.5);
    }
}
