//! The Zenoh wire format is what other hosts send: join requests,
//! commands and join replies, snapshots and statistics, each maybe sealed
//! with the run's key. Its decoders and the inboxes that call them are
//! fuzzed with random bytes and with mutations of valid messages: none may
//! panic, allocate more than the message's own size justifies (a count
//! read from the bytes is bounded before anything is allocated) or hang,
//! and each refusal is counted.
//!
//! The cases of each target are few in the normal test suite (under a
//! second); `PROPTEST_CASES=N` runs N of each (docs/failures.md,
//! "Fuzzing").

use super::inbox::{AgentInbox, WorldInbox, decode_reply, encode_reply};
use super::keys::Keys;
use super::seal::{self, RunKey, TAG_LEN};
use super::wire::{self, Wire, decode, decode_slice, encode_slice};
use crate::Namespace;
use mrsim_proto::{
    BodyState, CommandMsg, JoinReply, JoinRequest, RobotStats, SnapshotHeader, StatsHeader,
};
use proptest::prelude::*;

use mrsim_fuzzkit as largest;

/// What decoding `len` bytes may allocate at once: a fixed allowance plus
/// a few times the message (a decoded item is no bigger than twice its
/// encoding).
fn allowance(len: usize) -> usize {
    4096 + 4 * len
}

/// `bytes` decodes as a `T` exactly when it is `T::LEN` long, and a decoded
/// value encodes to `T::LEN` bytes that decode to the same encoding.
fn decodes_only_at_its_length<T: Wire>(bytes: &[u8]) -> Result<(), TestCaseError> {
    let (v, largest) = largest::measure(|| decode::<T>(bytes));
    prop_assert_eq!(v.is_some(), bytes.len() == T::LEN);
    prop_assert!(largest <= allowance(bytes.len()));
    if let Some(v) = v {
        let once = wire::encode(&v);
        prop_assert_eq!(once.len(), T::LEN);
        let again = decode::<T>(&once).map(|w| wire::encode(&w));
        prop_assert_eq!(again.as_ref(), Some(&once));
    }
    Ok(())
}

/// `bytes` decodes as a header and items exactly when it is a header and a
/// whole number of at most `max` items; nothing is allocated past that.
fn slice_is_bounded<H: Wire + Default, T: Wire>(
    bytes: &[u8],
    max: usize,
) -> Result<(), TestCaseError> {
    let mut header = H::default();
    let mut items: Vec<T> = Vec::new();
    let (ok, largest) = largest::measure(|| decode_slice(bytes, max, &mut header, &mut items));
    let whole = bytes.len() >= H::LEN
        && (bytes.len() - H::LEN).is_multiple_of(T::LEN)
        && (bytes.len() - H::LEN) / T::LEN <= max;
    prop_assert_eq!(ok, whole);
    prop_assert!(items.len() <= max);
    prop_assert!(
        largest <= allowance(bytes.len()),
        "{} bytes: {}",
        bytes.len(),
        largest
    );
    if ok {
        prop_assert_eq!(items.len(), (bytes.len() - H::LEN) / T::LEN);
    } else {
        prop_assert!(items.is_empty(), "nothing changed on a refusal");
    }
    Ok(())
}

/// One change to a message's bytes.
#[derive(Debug, Clone)]
enum Mutation {
    Flip(usize, u8),
    Insert(usize, u8),
    Remove(usize),
    Truncate(usize),
    Extend(Vec<u8>),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<usize>(), 1..=255u8).prop_map(|(i, b)| Mutation::Flip(i, b)),
        (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Mutation::Insert(i, b)),
        any::<usize>().prop_map(Mutation::Remove),
        any::<usize>().prop_map(Mutation::Truncate),
        prop::collection::vec(any::<u8>(), 1..80).prop_map(Mutation::Extend),
    ]
}

fn apply(b: &mut Vec<u8>, m: &Mutation) {
    let n = b.len();
    match m {
        Mutation::Flip(i, x) if n > 0 => b[i % n] ^= x,
        Mutation::Insert(i, x) => b.insert(i % (n + 1), *x),
        Mutation::Remove(i) if n > 0 => {
            b.remove(i % n);
        }
        Mutation::Truncate(i) => b.truncate(i % (n + 1)),
        Mutation::Extend(x) => b.extend_from_slice(x),
        _ => {}
    }
}

fn body(i: u32) -> BodyState {
    BodyState {
        id: i,
        kind: i % 2,
        position: [f64::from(i), -1.5],
        velocity: [0.25, f64::from(i) * 0.5],
        radius: 0.2,
        heading: 1.0,
        ..Default::default()
    }
}

/// A snapshot of `n` bodies as the world sends it.
fn snapshot(n: u32, tick: u64) -> Vec<u8> {
    let header = SnapshotHeader {
        tick,
        sim_time: tick as f64 * 0.1,
        body_count: n,
        ..Default::default()
    };
    let bodies: Vec<BodyState> = (0..n).map(body).collect();
    let mut out = Vec::new();
    encode_slice(&header, &bodies, &mut out);
    out
}

fn key() -> RunKey {
    RunKey::from_bytes([7; seal::KEY_LEN])
}

/// A valid message of each kind the world or an agent sends.
fn valid(which: usize) -> Vec<u8> {
    match which % 6 {
        0 => wire::encode(&CommandMsg {
            robot_id: 3,
            kind: 1,
            token: 99,
            tick: 12,
            value: [0.5, -0.5],
            ..Default::default()
        }),
        1 => wire::encode(&JoinRequest {
            protocol_version: mrsim_proto::PROTOCOL_VERSION,
            pid: 4242,
            nonce: 5,
            robot: mrsim_proto::FixedStr::new("r0"),
            ..Default::default()
        }),
        2 => encode_reply(
            &JoinReply {
                accepted: 1,
                nonce: 5,
                ..Default::default()
            },
            &key(),
        ),
        3 => snapshot(5, 7),
        4 => {
            let mut m = snapshot(3, 8);
            key().seal(&mut m);
            m
        }
        _ => {
            let robots: Vec<RobotStats> = (0..3)
                .map(|i| RobotStats {
                    robot_id: i,
                    ..Default::default()
                })
                .collect();
            let mut out = Vec::new();
            encode_slice(&StatsHeader::default(), &robots, &mut out);
            out
        }
    }
}

/// Every decoder of the wire format, and the inboxes that call them, on
/// one message.
fn decode_everything(bytes: &[u8], max: usize) -> Result<(), TestCaseError> {
    decodes_only_at_its_length::<CommandMsg>(bytes)?;
    decodes_only_at_its_length::<JoinRequest>(bytes)?;
    decodes_only_at_its_length::<JoinReply>(bytes)?;
    decodes_only_at_its_length::<SnapshotHeader>(bytes)?;
    decodes_only_at_its_length::<StatsHeader>(bytes)?;
    slice_is_bounded::<SnapshotHeader, BodyState>(bytes, max)?;
    slice_is_bounded::<StatsHeader, RobotStats>(bytes, max)?;
    if let Some(message) = seal::unchecked(bytes) {
        prop_assert_eq!(message.len() + TAG_LEN, bytes.len());
        slice_is_bounded::<SnapshotHeader, BodyState>(message, max)?;
    }
    let _ = seal::tick_of(bytes);
    let (r, largest) = largest::measure(|| decode_reply(bytes));
    prop_assert!(largest <= allowance(bytes.len()));
    if let Some((reply, k)) = r {
        prop_assert_eq!(k.is_some(), bytes.len() == JoinReply::LEN + seal::KEY_LEN);
        let _ = reply;
    }
    // The world's inbox: every message is a command or join kept, dropped
    // or refused and counted.
    let world = WorldInbox::new(4);
    world.command(bytes);
    world.join(bytes);
    {
        let s = super::inbox::lock(&world.state);
        prop_assert_eq!(
            s.commands.len() as u64
                + s.refused_commands
                + s.joins.len() as u64
                + s.refused_joins
                + s.dropped,
            2
        );
    }
    // An agent's inbox, before and after it has the run's key.
    for keyed in [false, true] {
        let agent = AgentInbox::default();
        if keyed {
            let mut s = super::inbox::lock(&agent.state);
            s.key = Some(key());
        }
        agent.reply(bytes);
        agent.snapshot(bytes);
        agent.stats(bytes);
        let mut s = super::inbox::lock(&agent.state);
        let mut header = SnapshotHeader::default();
        let mut bodies: Vec<BodyState> = Vec::new();
        let _ = s.take_snapshot(|m| decode_slice(m, max, &mut header, &mut bodies));
        prop_assert!(bodies.len() <= max);
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 1000, ..ProptestConfig::default() })]

    #[test]
    fn random_bytes_on_any_key_never_panic_and_decode_only_at_their_length(
        bytes in prop::collection::vec(any::<u8>(), 0..1200),
        max in 0..40usize,
    ) {
        decode_everything(&bytes, max)?;
    }

    #[test]
    fn mutated_messages_never_panic_and_are_refused_unless_whole(
        which in 0..6usize,
        muts in prop::collection::vec(mutation(), 1..4),
        max in 0..40usize,
    ) {
        let mut bytes = valid(which);
        for m in &muts {
            apply(&mut bytes, m);
        }
        decode_everything(&bytes, max)?;
    }

    #[test]
    fn a_sealed_snapshot_changed_anywhere_no_longer_opens(
        n in 0..20u32,
        at in any::<usize>(),
        flip in 1..=255u8,
    ) {
        let mut m = snapshot(n, 3);
        let plain = m.clone();
        key().seal(&mut m);
        prop_assert_eq!(key().open(&m), Some(&plain[..]));
        let i = at % m.len();
        m[i] ^= flip;
        prop_assert_eq!(key().open(&m), None);
    }

    #[test]
    fn any_liveliness_key_gives_a_pid_only_for_an_agent_token(
        tail in "[0-9a-z/]{0,12}",
        pid in any::<u32>(),
    ) {
        let keys = Keys::new(&Namespace::new("fuzz").expect("namespace"));
        prop_assert_eq!(keys.agent_pid(&keys.agent_token(pid)), Some(pid));
        let other = format!("{}{tail}", keys.agent_token(pid));
        if !tail.is_empty() {
            let got = keys.agent_pid(&other);
            prop_assert!(got.is_none() || tail.bytes().all(|b| b.is_ascii_digit()));
        }
        let _ = keys.agent_pid(&tail);
    }
}

#[test]
fn every_valid_message_decodes_as_its_kind() {
    assert!(decode::<CommandMsg>(&valid(0)).is_some());
    assert!(decode::<JoinRequest>(&valid(1)).is_some());
    assert!(matches!(decode_reply(&valid(2)), Some((_, Some(_)))));
    let (mut h, mut b) = (SnapshotHeader::default(), Vec::<BodyState>::new());
    assert!(decode_slice(&valid(3), 10, &mut h, &mut b) && b.len() == 5);
    assert_eq!(
        key().open(&valid(4)).map(<[u8]>::len),
        Some(valid(3).len() - 2 * BodyState::LEN)
    );
}
