//! Snapshots that only the run's world can have written.
//!
//! Zenoh does not tell a subscriber who published a sample: any session
//! that reaches the world's endpoint could publish on the run's snapshot
//! key. So the world makes a random key when it starts ([`RunKey`]), hands
//! it to each agent in its accepted join reply (as it hands each agent the
//! token its commands must carry), and appends to every snapshot an
//! HMAC-SHA256 tag of the snapshot's bytes under that key. An agent keeps
//! only the snapshots whose tag checks, and only those of a tick no older
//! than the newest it has kept (a recorded snapshot sent again is refused);
//! the rest are counted, never planned on, and never displace the newest
//! genuine snapshot.
//!
//! The key travels as the command tokens do, in the join reply: a peer that
//! can read the run's join replies can learn both. What keeps such a peer
//! off the network is Zenoh's own authentication (user/password, TLS).

use crate::TransportError;
use ring::hmac;
use ring::rand::{SecureRandom, SystemRandom};

/// Bytes of the run's key as it travels in a join reply.
pub const KEY_LEN: usize = 32;
/// Bytes of the tag after a snapshot.
pub const TAG_LEN: usize = 32;

/// The key a run's world signs its snapshots with.
#[derive(Clone)]
pub struct RunKey {
    bytes: [u8; KEY_LEN],
    key: hmac::Key,
}

impl std::fmt::Debug for RunKey {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        // A key is never printed.
        f.write_str("RunKey(..)")
    }
}

impl RunKey {
    /// A fresh key from the operating system's random source.
    pub fn generate() -> Result<Self, TransportError> {
        let mut bytes = [0u8; KEY_LEN];
        SystemRandom::new()
            .fill(&mut bytes)
            .map_err(|_| TransportError::Setup {
                what: "the run's snapshot key".to_string(),
                detail: "the operating system's random source failed".to_string(),
            })?;
        Ok(Self::from_bytes(bytes))
    }

    /// The key of these bytes (as received in a join reply).
    pub fn from_bytes(bytes: [u8; KEY_LEN]) -> Self {
        Self {
            bytes,
            key: hmac::Key::new(hmac::HMAC_SHA256, &bytes),
        }
    }

    /// The key's bytes, to send in a join reply.
    pub fn bytes(&self) -> &[u8; KEY_LEN] {
        &self.bytes
    }

    /// Appends the tag of `message` (the whole of it) to it.
    pub fn seal(&self, message: &mut Vec<u8>) {
        let tag = hmac::sign(&self.key, message);
        message.extend_from_slice(tag.as_ref());
    }

    /// The message inside `sealed` if its tag is this key's, else `None`.
    pub fn open<'a>(&self, sealed: &'a [u8]) -> Option<&'a [u8]> {
        let (message, tag) = split(sealed)?;
        hmac::verify(&self.key, message, tag).ok()?;
        Some(message)
    }
}

/// The message inside `sealed` without checking its tag (for observers,
/// which watch but never act on a snapshot); `None` if too short to hold
/// one.
pub fn unchecked(sealed: &[u8]) -> Option<&[u8]> {
    split(sealed).map(|(message, _)| message)
}

fn split(sealed: &[u8]) -> Option<(&[u8], &[u8])> {
    let at = sealed.len().checked_sub(TAG_LEN)?;
    Some(sealed.split_at(at))
}

/// The tick of a snapshot's bytes (its first field), if it has one.
pub fn tick_of(message: &[u8]) -> Option<u64> {
    let first: [u8; 8] = message.get(..8)?.try_into().ok()?;
    Some(u64::from_le_bytes(first))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sealed_message_opens_with_its_key_only() {
        let k = RunKey::generate().expect("key");
        let mut m = b"a snapshot".to_vec();
        k.seal(&mut m);
        assert_eq!(m.len(), 10 + TAG_LEN);
        assert_eq!(k.open(&m), Some(&b"a snapshot"[..]));
        assert_eq!(
            RunKey::from_bytes(*k.bytes()).open(&m),
            Some(&b"a snapshot"[..])
        );
        let other = RunKey::generate().expect("key");
        assert_eq!(other.open(&m), None, "another key");
        let mut changed = m.clone();
        changed[0] ^= 1;
        assert_eq!(k.open(&changed), None, "a changed byte");
        assert_eq!(k.open(&m[..m.len() - 1]), None, "a cut tag");
        assert_eq!(k.open(&[]), None);
        assert_eq!(unchecked(&m), Some(&b"a snapshot"[..]));
    }

    #[test]
    fn two_worlds_never_share_a_key() {
        let a = RunKey::generate().expect("key");
        let b = RunKey::generate().expect("key");
        assert_ne!(a.bytes(), b.bytes());
    }
}
