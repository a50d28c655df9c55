//! The live page's server reads two things others write: the requests of
//! whoever reaches its port (method and URL, the `after=` of `/frame`), and
//! the world's setup message (JSON, over Zenoh from another host). Both are
//! fuzzed with random input and mutations of valid input: none may panic,
//! allocate far past the input's size or hang; a setup it cannot read
//! leaves the page waiting.
//!
//! The cases of each target are few in the normal test suite (under a
//! second); `PROPTEST_CASES=N` runs N of each (docs/failures.md,
//! "Fuzzing").

use super::{Feed, Pump, route};
use proptest::prelude::*;

use mrsim_fuzzkit as largest;

/// What reading `len` bytes may allocate at once: the page's setup is a
/// few times the scenario it comes from.
fn allowance(len: usize) -> usize {
    (64 << 10) + 64 * len
}

const SCENARIO: &str = "name = \"fuzz\"\n[world]\ndt = 0.1\n[[robot]]\nname = \"r0\"\nstart = [0, 0]\n\
goal = [1, 0]\n[[robot]]\nname = \"r1\"\nstart = [0, 1]\ngoal = [1, 1]\n\
[[wall]]\nsegment = [[-1, -1], [2, -1]]\n";

/// The world's setup message for a small scenario.
fn setup() -> Vec<u8> {
    let s = mrsim_scenario::parse(SCENARIO, "fuzz.toml")
        .expect("scenario")
        .scenario;
    serde_json::json!({"run_id": "fuzz", "scenario": s})
        .to_string()
        .into_bytes()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 1000, ..ProptestConfig::default() })]

    #[test]
    fn any_request_gets_an_answer_and_never_panics(
        get in any::<bool>(),
        path in prop::sample::select(&["/", "/setup", "/frame", "/frame?", "", "//", "/x"][..]),
        query in "[a-z=&0-9%?-]{0,40}",
        published in any::<bool>(),
    ) {
        let feed = Feed::new();
        if published {
            feed.publish("{\"tick\":1}".into());
            feed.set_setup("{}".into());
        }
        let url = format!("{path}?{query}");
        let (status, _, body) = route(get, &url, &feed);
        prop_assert!([200, 204, 404, 503].contains(&status));
        prop_assert!(body.len() <= (64 << 10) + super::PAGE.len());
        if !get {
            prop_assert_eq!(status, 404);
        }
    }

    #[test]
    fn a_mutated_or_random_setup_never_panics_and_an_unreadable_one_leaves_the_page_waiting(
        random in any::<bool>(),
        bytes in prop::collection::vec(any::<u8>(), 0..200),
        at in any::<usize>(),
        cut in any::<usize>(),
    ) {
        let mut msg = if random { bytes.clone() } else { setup() };
        if !random {
            let n = msg.len();
            // Bytes put in somewhere, and the message maybe cut short.
            let i = at % (n + 1);
            msg.splice(i..i, bytes.iter().copied().take(8));
            if cut % 3 == 0 {
                msg.truncate(cut % (msg.len() + 1));
            }
        }
        let feed = Feed::new();
        let mut pump = Pump::new(feed.clone());
        let (_, largest) = largest::measure(|| pump.take_setup(&msg));
        prop_assert!(largest <= allowance(msg.len()), "{} bytes: {largest}", msg.len());
        let (status, _, _) = route(true, "/setup", &feed);
        prop_assert_eq!(status == 200, pump.scenario.is_some());
    }
}

#[test]
fn the_valid_setup_is_read() {
    let feed = Feed::new();
    let mut pump = Pump::new(feed.clone());
    pump.take_setup(&setup());
    assert!(pump.scenario.is_some());
    assert_eq!(route(true, "/setup", &feed).0, 200);
    assert_eq!(route(true, "/frame?after=x", &feed).0, 204);
}
