//! What a ROS 2 node on another host sends mrsim is a `cmd_vel`
//! (`geometry_msgs/msg/Twist` in CDR) with rmw_zenoh's 33-byte attachment.
//! Their decoders (and the CDR reader under them, strings included, whose
//! length comes from the bytes) are fuzzed with random bytes and with
//! mutations of valid payloads: none may panic, allocate more than the
//! payload itself or hang.
//!
//! The cases of each target are few in the normal test suite (under a
//! second); `PROPTEST_CASES=N` runs N of each (docs/failures.md,
//! "Fuzzing").

use crate::attachment::{self, Attachment};
use crate::cdr::{Reader, Writer};
use crate::msgs::{Twist, Vector3};
use proptest::prelude::*;

use mrsim_fuzzkit as largest;

/// What decoding `len` bytes may allocate at once.
fn allowance(len: usize) -> usize {
    1024 + 2 * len
}

fn twist(v: [f64; 6]) -> Twist {
    Twist {
        linear: Vector3 {
            x: v[0],
            y: v[1],
            z: v[2],
        },
        angular: Vector3 {
            x: v[3],
            y: v[4],
            z: v[5],
        },
    }
}

/// Reads `bytes` as every message mrsim takes from a ROS 2 node, and as a
/// few strings and numbers through the CDR reader.
fn decode_everything(bytes: &[u8]) -> Result<(), TestCaseError> {
    let (_, largest) = largest::measure(|| {
        let _ = Twist::decode(bytes);
        let _ = Attachment::decode(bytes);
        if let Ok(mut r) = Reader::new(bytes) {
            for _ in 0..4 {
                if r.string().is_err() {
                    break;
                }
            }
            let _ = r.u8();
            let _ = r.f64();
            let _ = r.end();
        }
    });
    prop_assert!(
        largest <= allowance(bytes.len()),
        "{} bytes asked for {largest} at once",
        bytes.len()
    );
    prop_assert_eq!(
        Attachment::decode(bytes).is_ok(),
        bytes.len() == attachment::LEN && bytes[16] == 16
    );
    Ok(())
}

/// One change to a payload.
#[derive(Debug, Clone)]
enum Mutation {
    Flip(usize, u8),
    Insert(usize, u8),
    Truncate(usize),
    Extend(Vec<u8>),
    Word(usize, u32),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<usize>(), 1..=255u8).prop_map(|(i, b)| Mutation::Flip(i, b)),
        (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Mutation::Insert(i, b)),
        any::<usize>().prop_map(Mutation::Truncate),
        prop::collection::vec(any::<u8>(), 1..24).prop_map(Mutation::Extend),
        (
            any::<usize>(),
            prop_oneof![Just(u32::MAX), Just(0x7fff_ffff), Just(0), any::<u32>()]
        )
            .prop_map(|(i, w)| Mutation::Word(i, w)),
    ]
}

fn apply(b: &mut Vec<u8>, m: &Mutation) {
    let n = b.len();
    match m {
        Mutation::Flip(i, x) if n > 0 => b[i % n] ^= x,
        Mutation::Insert(i, x) => b.insert(i % (n + 1), *x),
        Mutation::Truncate(i) => b.truncate(i % (n + 1)),
        Mutation::Extend(x) => b.extend_from_slice(x),
        Mutation::Word(i, w) if n >= 4 => {
            let at = i % (n - 3);
            b[at..at + 4].copy_from_slice(&w.to_le_bytes());
        }
        _ => {}
    }
}

/// A valid payload of each kind: a Twist, an attachment, a CDR string.
fn valid(which: usize, v: [f64; 6]) -> Vec<u8> {
    match which % 3 {
        0 => twist(v).encode(),
        1 => Attachment {
            sequence_number: 3,
            source_timestamp: 4,
            gid: [9; 16],
        }
        .encode()
        .to_vec(),
        _ => {
            let mut w = Writer::new();
            w.string("/r0/cmd_vel");
            w.string("");
            w.finish()
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 1000, ..ProptestConfig::default() })]

    #[test]
    fn random_bytes_as_cmd_vel_never_panic_nor_allocate_past_their_size(
        head in prop::sample::select(HEADS),
        rest in prop::collection::vec(any::<u8>(), 0..120),
    ) {
        decode_everything(&[head, &rest[..]].concat())?;
    }

    #[test]
    fn mutated_cmd_vel_payloads_never_panic_and_a_twist_round_trips(
        which in 0..3usize,
        v in prop::array::uniform6(-1e3..1e3f64),
        muts in prop::collection::vec(mutation(), 0..4),
    ) {
        let t = twist(v);
        prop_assert_eq!(Twist::decode(&t.encode()).ok(), Some(t));
        let mut bytes = valid(which, v);
        for m in &muts {
            apply(&mut bytes, m);
        }
        decode_everything(&bytes)?;
    }
}

/// CDR's two encapsulations, another, and nothing.
const HEADS: &[&[u8]] = &[&[0, 1, 0, 0], &[0, 0, 0, 0], &[0, 2, 0, 0], &[]];

#[test]
fn a_cdr_string_claiming_more_bytes_than_the_payload_holds_is_refused_without_allocating() {
    // A length word of 4 GiB before three bytes: refused as short, nothing
    // allocated for the claim.
    let mut bytes = vec![0, 1, 0, 0];
    bytes.extend_from_slice(&u32::MAX.to_le_bytes());
    bytes.extend_from_slice(b"ab\0");
    let (r, largest) = largest::measure(|| Reader::new(&bytes).and_then(|mut r| r.string()));
    assert!(r.is_err());
    assert!(largest <= allowance(bytes.len()), "{largest}");
}
