//! The bytes on the wire: every message is its fields in order, little
//! endian, with no padding, and is decoded only if its length is exactly
//! right. Whatever arrives from the network is checked here first: a
//! message of the wrong length (garbage, another program on the key, a
//! truncated frame) is refused, never read past its end.

use mrsim_proto::{
    BodyState, CommandMsg, FixedStr, JoinReply, JoinRequest, RobotStats, SnapshotHeader,
    StatsHeader,
};

/// A message type with a fixed-size encoding.
pub trait Wire: Sized {
    /// Bytes of one encoded value.
    const LEN: usize;
    /// Appends the encoding to `out`.
    fn put(&self, out: &mut Vec<u8>);
    /// Decodes one value from the first [`LEN`](Self::LEN) bytes of `r`.
    fn get(r: &mut Reader<'_>) -> Self;
}

/// Reads fields from a slice whose length was checked beforehand.
pub struct Reader<'a> {
    bytes: &'a [u8],
}

impl Reader<'_> {
    fn take<const N: usize>(&mut self) -> [u8; N] {
        let mut a = [0; N];
        let (head, tail) = self.bytes.split_at(N.min(self.bytes.len()));
        a[..head.len()].copy_from_slice(head);
        self.bytes = tail;
        a
    }
    fn u32(&mut self) -> u32 {
        u32::from_le_bytes(self.take())
    }
    fn u64(&mut self) -> u64 {
        u64::from_le_bytes(self.take())
    }
    fn f64(&mut self) -> f64 {
        f64::from_le_bytes(self.take())
    }
    fn str<const N: usize>(&mut self) -> FixedStr<N> {
        let len = (self.u32() as usize).min(N);
        let bytes: [u8; N] = self.take();
        // Invalid UTF-8 reads as the empty string, as on shared memory.
        FixedStr::new(std::str::from_utf8(&bytes[..len]).unwrap_or(""))
    }
}

fn put_str<const N: usize>(s: &FixedStr<N>, out: &mut Vec<u8>) {
    let b = s.as_str().as_bytes();
    out.extend_from_slice(&(b.len() as u32).to_le_bytes());
    let start = out.len();
    out.resize(start + N, 0);
    out[start..start + b.len()].copy_from_slice(b);
}

fn put_u32(v: u32, out: &mut Vec<u8>) {
    out.extend_from_slice(&v.to_le_bytes());
}
fn put_u64(v: u64, out: &mut Vec<u8>) {
    out.extend_from_slice(&v.to_le_bytes());
}
fn put_f64(v: f64, out: &mut Vec<u8>) {
    out.extend_from_slice(&v.to_le_bytes());
}

/// Decodes one `T` from exactly `bytes`; `None` if the length is wrong.
pub fn decode<T: Wire>(bytes: &[u8]) -> Option<T> {
    (bytes.len() == T::LEN).then(|| T::get(&mut Reader { bytes }))
}

/// Encodes `header` then `items` into `out` (cleared first).
pub fn encode_slice<H: Wire, T: Wire>(header: &H, items: &[T], out: &mut Vec<u8>) {
    out.clear();
    out.reserve(H::LEN + items.len() * T::LEN);
    header.put(out);
    for t in items {
        t.put(out);
    }
}

/// Encodes one value into a fresh buffer.
pub fn encode<T: Wire>(v: &T) -> Vec<u8> {
    let mut out = Vec::with_capacity(T::LEN);
    v.put(&mut out);
    out
}

/// Decodes a header and the items after it into `items`; false (and
/// nothing changed) if the bytes are not a header followed by a whole
/// number of items, or hold more than `max` items.
pub fn decode_slice<H: Wire, T: Wire>(
    bytes: &[u8],
    max: usize,
    header: &mut H,
    items: &mut Vec<T>,
) -> bool {
    let Some(rest) = bytes.len().checked_sub(H::LEN) else {
        return false;
    };
    if rest % T::LEN != 0 || rest / T::LEN > max {
        return false;
    }
    let mut r = Reader { bytes };
    *header = H::get(&mut r);
    items.clear();
    items.extend((0..rest / T::LEN).map(|_| T::get(&mut r)));
    true
}

impl Wire for BodyState {
    const LEN: usize = 4 * 4 + 8 * 8;
    fn put(&self, o: &mut Vec<u8>) {
        put_u32(self.id, o);
        put_u32(self.kind, o);
        put_u32(self.flags, o);
        put_u32(self._pad, o);
        for v in self.position.iter().chain(&self.velocity) {
            put_f64(*v, o);
        }
        put_f64(self.radius, o);
        put_f64(self.heading, o);
        put_f64(self.angular_velocity, o);
        put_f64(self.steering, o);
    }
    fn get(r: &mut Reader<'_>) -> Self {
        Self {
            id: r.u32(),
            kind: r.u32(),
            flags: r.u32(),
            _pad: r.u32(),
            position: [r.f64(), r.f64()],
            velocity: [r.f64(), r.f64()],
            radius: r.f64(),
            heading: r.f64(),
            angular_velocity: r.f64(),
            steering: r.f64(),
        }
    }
}

impl Wire for SnapshotHeader {
    const LEN: usize = 4 * 8 + 2 * 4;
    fn put(&self, o: &mut Vec<u8>) {
        put_u64(self.tick, o);
        put_f64(self.sim_time, o);
        put_u64(self.published_ns, o);
        put_u64(self.deadline_ns, o);
        put_u32(self.finished, o);
        put_u32(self.body_count, o);
    }
    fn get(r: &mut Reader<'_>) -> Self {
        Self {
            tick: r.u64(),
            sim_time: r.f64(),
            published_ns: r.u64(),
            deadline_ns: r.u64(),
            finished: r.u32(),
            body_count: r.u32(),
        }
    }
}

impl Wire for CommandMsg {
    const LEN: usize = 2 * 4 + 2 * 8 + 2 * 8 + 3 * 8 + 8 + 4;
    fn put(&self, o: &mut Vec<u8>) {
        put_u32(self.robot_id, o);
        put_u32(self.kind, o);
        put_u64(self.token, o);
        put_u64(self.tick, o);
        put_f64(self.value[0], o);
        put_f64(self.value[1], o);
        put_u64(self.compute_ns, o);
        put_u64(self.woke_ns, o);
        put_u64(self.sent_ns, o);
        put_u64(self.cpu_ns, o);
        put_u32(self.overruns, o);
    }
    fn get(r: &mut Reader<'_>) -> Self {
        Self {
            robot_id: r.u32(),
            kind: r.u32(),
            token: r.u64(),
            tick: r.u64(),
            value: [r.f64(), r.f64()],
            compute_ns: r.u64(),
            woke_ns: r.u64(),
            sent_ns: r.u64(),
            cpu_ns: r.u64(),
            overruns: r.u32(),
            _pad: 0,
        }
    }
}

impl Wire for JoinRequest {
    const LEN: usize = 2 * 4 + 8 + 4 + mrsim_proto::MAX_NAME_LEN;
    fn put(&self, o: &mut Vec<u8>) {
        put_u32(self.protocol_version, o);
        put_u32(self.pid, o);
        put_u64(self.nonce, o);
        put_str(&self.robot, o);
    }
    fn get(r: &mut Reader<'_>) -> Self {
        Self {
            protocol_version: r.u32(),
            pid: r.u32(),
            nonce: r.u64(),
            robot: r.str(),
            // Not sent: the world's inbox over Zenoh is shared by every
            // agent and sized from the robots, not per process.
            group: 0,
        }
    }
}

impl Wire for JoinReply {
    const LEN: usize = 8 + 2 * 4 + 8 + 2 * 4 + 4 + mrsim_proto::MAX_REASON_LEN;
    fn put(&self, o: &mut Vec<u8>) {
        put_u64(self.nonce, o);
        put_u32(self.accepted, o);
        put_u32(self.robot_id, o);
        put_u64(self.token, o);
        put_u32(self.protocol_version, o);
        put_u32(self.world_pid, o);
        put_str(&self.reason, o);
    }
    fn get(r: &mut Reader<'_>) -> Self {
        Self {
            nonce: r.u64(),
            accepted: r.u32(),
            robot_id: r.u32(),
            token: r.u64(),
            protocol_version: r.u32(),
            world_pid: r.u32(),
            reason: r.str(),
        }
    }
}

impl Wire for RobotStats {
    const LEN: usize = 4 * 4 + 2 * 8 + 4 * 8;
    fn put(&self, o: &mut Vec<u8>) {
        put_u32(self.robot_id, o);
        put_u32(self.state, o);
        put_u32(self.reached_goal, o);
        put_u32(self.agent_pid, o);
        put_f64(self.latency_p50_us, o);
        put_f64(self.latency_p99_us, o);
        put_u64(self.commands, o);
        put_u64(self.deadline_misses, o);
        put_u64(self.collisions, o);
        put_u64(self.commands_rejected, o);
    }
    fn get(r: &mut Reader<'_>) -> Self {
        Self {
            robot_id: r.u32(),
            state: r.u32(),
            reached_goal: r.u32(),
            agent_pid: r.u32(),
            latency_p50_us: r.f64(),
            latency_p99_us: r.f64(),
            commands: r.u64(),
            deadline_misses: r.u64(),
            collisions: r.u64(),
            commands_rejected: r.u64(),
        }
    }
}

impl Wire for StatsHeader {
    const LEN: usize = 7 * 8 + 4 * 4;
    fn put(&self, o: &mut Vec<u8>) {
        put_u64(self.tick, o);
        put_u64(self.max_ticks, o);
        put_f64(self.sim_time, o);
        put_f64(self.realtime_factor, o);
        put_u64(self.published_ns, o);
        put_u64(self.collisions_total, o);
        put_u64(self.agents_lost, o);
        put_u32(self.phase, o);
        put_u32(self.realtime, o);
        put_u32(self.robot_count, o);
        put_u32(self.world_pid, o);
    }
    fn get(r: &mut Reader<'_>) -> Self {
        Self {
            tick: r.u64(),
            max_ticks: r.u64(),
            sim_time: r.f64(),
            realtime_factor: r.f64(),
            published_ns: r.u64(),
            collisions_total: r.u64(),
            agents_lost: r.u64(),
            phase: r.u32(),
            realtime: r.u32(),
            robot_count: r.u32(),
            world_pid: r.u32(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn round_trip<T: Wire + PartialEq + std::fmt::Debug>(v: T) {
        let bytes = encode(&v);
        assert_eq!(bytes.len(), T::LEN);
        assert_eq!(decode::<T>(&bytes), Some(v));
    }

    #[test]
    fn every_message_survives_encoding() {
        round_trip(CommandMsg {
            robot_id: 3,
            kind: 1,
            token: u64::MAX - 5,
            tick: 77,
            value: [1.5, -0.25],
            compute_ns: 9,
            woke_ns: 10,
            sent_ns: 11,
            cpu_ns: 12,
            overruns: 13,
            _pad: 0,
        });
        round_trip(JoinRequest {
            protocol_version: 6,
            pid: 1234,
            nonce: 99,
            robot: FixedStr::new("r17"),
            group: 0,
        });
        round_trip(JoinReply {
            nonce: 1,
            accepted: 0,
            robot_id: u32::MAX,
            token: 0,
            protocol_version: 6,
            world_pid: 5,
            reason: FixedStr::new("no robot named `x`"),
        });
        round_trip(SnapshotHeader {
            tick: 8,
            published_ns: 3,
            body_count: 9,
            ..Default::default()
        });
        round_trip(BodyState {
            id: 2,
            radius: 0.5,
            heading: 0.25,
            angular_velocity: -0.5,
            steering: 0.125,
            ..Default::default()
        });
        round_trip(StatsHeader {
            tick: 4,
            robot_count: 2,
            sim_time: 0.4,
            ..Default::default()
        });
        round_trip(RobotStats {
            robot_id: 1,
            latency_p99_us: 3.5,
            ..Default::default()
        });
    }

    #[test]
    fn a_snapshot_decodes_to_its_bodies() {
        let h = SnapshotHeader {
            tick: 5,
            body_count: 2,
            ..Default::default()
        };
        let bodies = [
            BodyState {
                id: 0,
                position: [1.0, 2.0],
                radius: 0.3,
                ..Default::default()
            },
            BodyState {
                id: 1,
                kind: 1,
                velocity: [-1.0, 0.5],
                ..Default::default()
            },
        ];
        let mut buf = Vec::new();
        encode_slice(&h, &bodies, &mut buf);
        let (mut h2, mut b2) = (SnapshotHeader::default(), Vec::new());
        assert!(decode_slice(&buf, 10, &mut h2, &mut b2));
        assert_eq!((h2, b2.as_slice()), (h, &bodies[..]));
    }

    #[test]
    fn garbage_of_the_wrong_length_is_refused() {
        assert_eq!(decode::<CommandMsg>(&[0u8; 7]), None);
        assert_eq!(decode::<CommandMsg>(&[0u8; CommandMsg::LEN + 1]), None);
        assert_eq!(decode::<JoinRequest>(&[]), None);
        let (mut h, mut b) = (SnapshotHeader::default(), vec![BodyState::default()]);
        assert!(!decode_slice(&[1u8; 3], 10, &mut h, &mut b));
        let too_long = vec![0u8; SnapshotHeader::LEN + BodyState::LEN * 11];
        assert!(!decode_slice(&too_long, 10, &mut h, &mut b));
        let ragged = vec![0u8; SnapshotHeader::LEN + BodyState::LEN + 1];
        assert!(!decode_slice(&ragged, 10, &mut h, &mut b));
        assert_eq!(b.len(), 1, "a refused snapshot leaves the old one");
    }

    #[test]
    fn a_name_with_invalid_utf8_reads_as_empty() {
        let mut bytes = encode(&JoinRequest {
            robot: FixedStr::new("ab"),
            ..Default::default()
        });
        bytes[16 + 4] = 0xff;
        let req = decode::<JoinRequest>(&bytes).unwrap();
        assert_eq!(req.robot.as_str(), "");
    }
}
