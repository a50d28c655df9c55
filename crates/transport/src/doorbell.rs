//! The tick doorbell: one futex word in shared memory that wakes every
//! agent process of a run with one system call.
//!
//! Why not an iceoryx2 event: on Linux an iceoryx2 event is a Unix datagram
//! socket per listener, so waking N agents is N `sendto` calls by the world
//! and one `recvfrom` per agent to drain it. Profiled at 256 agents on two
//! cores (`perf record -a -g`, BENCHMARKS.md, "Fourth round"), the world's
//! 256 `sendto`s a tick were 58 % of its CPU time and 9 % of all CPU
//! samples; the agents' `recvfrom` another 5 %. A futex wakes them all at
//! once (`FUTEX_WAKE`, every waiter), and an agent's wait is one
//! `FUTEX_WAIT`.
//!
//! The word counts rings. The world publishes the snapshot (iceoryx2,
//! zero-copy) and then rings: it bumps the count (release) and wakes every
//! waiter. An agent remembers the count it last saw and sleeps only while
//! the word still holds it; the kernel compares and sleeps atomically, so a
//! ring between the agent's look and its sleep is never lost. A count that
//! moved means "look for a new snapshot": the snapshot itself always comes
//! through iceoryx2, so a spurious or merged ring costs one empty receive.
//!
//! The file lives in /dev/shm under the run's prefix (so
//! [`crate::Namespace::remove_leftovers`] removes it, and
//! [`crate::Namespace::make_private`] keeps it private). The world creates
//! it before any iceoryx2 service of the run, so an agent that found the
//! services finds the doorbell; the world removes it when it ends.

use crate::{Namespace, TransportError};
use std::fs::OpenOptions;
use std::os::fd::AsRawFd;
use std::os::unix::fs::OpenOptionsExt;
use std::path::PathBuf;
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::Duration;

/// Size of the mapping: one page.
const LEN: usize = 4096;
/// Written first by the world; an agent refuses a file without it (a
/// doorbell being created, or some other file under the name).
const MAGIC: u32 = 0x6d72_6462; // "mrdb"

/// The words of the doorbell, each on its own cache line.
#[repr(C, align(64))]
struct Words {
    magic: AtomicU32,
    _pad: [u8; 60],
    ring: AtomicU32,
}

/// One side's mapping of a run's doorbell.
pub struct Doorbell {
    words: *const Words,
    /// Set on the world's doorbell: the file it removes when dropped.
    owned: Option<PathBuf>,
    /// The ring count this side last saw (agents).
    seen: u32,
}

// SAFETY: the mapping is only accessed through atomics, and is unmapped
// only in `drop`, which takes the doorbell by value.
unsafe impl Send for Doorbell {}

/// The doorbell file of run `ns`.
pub fn path(ns: &Namespace) -> PathBuf {
    PathBuf::from(format!("/dev/shm/{}doorbell", ns.prefix()))
}

fn err(what: &str, e: impl std::fmt::Display) -> TransportError {
    TransportError::Setup {
        what: format!("tick doorbell ({what})"),
        detail: e.to_string(),
    }
}

/// Maps `LEN` bytes of `file` shared, read-write.
fn map(file: &std::fs::File) -> Result<*const Words, TransportError> {
    // SAFETY: a fresh shared mapping of an open file of at least LEN bytes;
    // the result is checked before use.
    let p = unsafe {
        libc::mmap(
            std::ptr::null_mut(),
            LEN,
            libc::PROT_READ | libc::PROT_WRITE,
            libc::MAP_SHARED,
            file.as_raw_fd(),
            0,
        )
    };
    if p == libc::MAP_FAILED {
        return Err(err("mmap", std::io::Error::last_os_error()));
    }
    Ok(p as *const Words)
}

impl Doorbell {
    /// The world's side: creates the run's doorbell, replacing one a
    /// crashed world of the same run left behind.
    pub fn create(ns: &Namespace) -> Result<Self, TransportError> {
        let path = path(ns);
        let _ = std::fs::remove_file(&path);
        let file = OpenOptions::new()
            .read(true)
            .write(true)
            .create_new(true)
            .mode(0o600)
            .open(&path)
            .map_err(|e| err(&format!("creating {}", path.display()), e))?;
        file.set_len(LEN as u64)
            .map_err(|e| err(&format!("sizing {}", path.display()), e))?;
        let words = map(&file)?;
        let bell = Self {
            words,
            owned: Some(path),
            seen: 0,
        };
        bell.words().magic.store(MAGIC, Ordering::Release);
        Ok(bell)
    }

    /// An agent's side: opens the doorbell the run's world created.
    pub fn open(ns: &Namespace) -> Result<Self, TransportError> {
        let path = path(ns);
        let file = OpenOptions::new()
            .read(true)
            .write(true)
            .open(&path)
            .map_err(|e| err(&format!("opening {}", path.display()), e))?;
        let len = file
            .metadata()
            .map_err(|e| err(&format!("reading {}", path.display()), e))?
            .len();
        if len < LEN as u64 {
            return Err(err(
                &path.display().to_string(),
                format!("{len} bytes, expected {LEN} (not created yet, or not a doorbell)"),
            ));
        }
        let words = map(&file)?;
        let mut bell = Self {
            words,
            owned: None,
            seen: 0,
        };
        if bell.words().magic.load(Ordering::Acquire) != MAGIC {
            return Err(err(
                &path.display().to_string(),
                "no doorbell mark (not created yet, or not a doorbell)",
            ));
        }
        bell.seen = bell.words().ring.load(Ordering::Acquire);
        Ok(bell)
    }

    fn words(&self) -> &Words {
        // SAFETY: `words` is a live mapping of LEN >= size_of::<Words>()
        // bytes until drop; every field is an atomic.
        unsafe { &*self.words }
    }

    /// The world's side: wakes everyone waiting (call after publishing).
    pub fn ring(&self) -> Result<(), TransportError> {
        let ring = &self.words().ring;
        ring.fetch_add(1, Ordering::Release);
        // SAFETY: a futex wake on an aligned u32 of a live shared mapping.
        let r = unsafe {
            libc::syscall(
                libc::SYS_futex,
                ring.as_ptr(),
                libc::FUTEX_WAKE,
                i32::MAX,
                std::ptr::null::<libc::timespec>(),
                std::ptr::null::<u32>(),
                0u32,
            )
        };
        if r < 0 {
            return Err(TransportError::Send {
                what: "tick doorbell",
                detail: format!("futex wake: {}", std::io::Error::last_os_error()),
            });
        }
        Ok(())
    }

    /// An agent's side: returns at once if the doorbell rang since the last
    /// call, else sleeps until it rings, `timeout` passes, or a signal
    /// arrives. Returns how many times it rang since the last call (each
    /// ring follows one snapshot).
    pub fn wait(&mut self, timeout: Duration) -> Result<u32, TransportError> {
        let ring = &self.words().ring;
        let now = ring.load(Ordering::Acquire);
        if now != self.seen || timeout.is_zero() {
            let rang = now.wrapping_sub(self.seen);
            self.seen = now;
            return Ok(rang);
        }
        let ts = libc::timespec {
            tv_sec: timeout.as_secs().min(i32::MAX as u64) as libc::time_t,
            tv_nsec: timeout.subsec_nanos() as libc::c_long,
        };
        // SAFETY: a futex wait on an aligned u32 of a live shared mapping,
        // with a valid relative timeout.
        let r = unsafe {
            libc::syscall(
                libc::SYS_futex,
                ring.as_ptr(),
                libc::FUTEX_WAIT,
                self.seen,
                &ts as *const libc::timespec,
                std::ptr::null::<u32>(),
                0u32,
            )
        };
        if r < 0 {
            match std::io::Error::last_os_error().raw_os_error() {
                // Rang before we slept, timed out, or a signal: the caller
                // looks at the count below and at its own flags.
                Some(libc::EAGAIN | libc::ETIMEDOUT | libc::EINTR) => {}
                _ => {
                    return Err(TransportError::Wait(format!(
                        "futex wait: {}",
                        std::io::Error::last_os_error()
                    )));
                }
            }
        }
        let now = ring.load(Ordering::Acquire);
        let rang = now.wrapping_sub(self.seen);
        self.seen = now;
        Ok(rang)
    }
}

impl Drop for Doorbell {
    fn drop(&mut self) {
        // SAFETY: the mapping made in `create`/`open`, unmapped once.
        unsafe {
            libc::munmap(self.words as *mut libc::c_void, LEN);
        }
        if let Some(path) = &self.owned {
            let _ = std::fs::remove_file(path);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Instant;

    fn ns(tag: &str) -> Namespace {
        Namespace::new(&format!("doorbell-{tag}-{}", std::process::id())).expect("namespace")
    }

    #[test]
    fn a_ring_wakes_a_waiting_agent_and_is_seen_once() {
        let ns = ns("wake");
        let world = Doorbell::create(&ns).expect("create");
        let mut agent = Doorbell::open(&ns).expect("open");
        let waiter = std::thread::spawn(move || {
            let rang = agent.wait(Duration::from_secs(10)).expect("wait");
            // Seen once: the next wait times out.
            let again = agent.wait(Duration::from_millis(20)).expect("wait");
            (rang, again)
        });
        std::thread::sleep(Duration::from_millis(50));
        world.ring().expect("ring");
        let (rang, again) = waiter.join().expect("waiter");
        assert_eq!(rang, 1);
        assert_eq!(again, 0);
    }

    #[test]
    fn a_ring_before_the_wait_is_not_lost() {
        let ns = ns("early");
        let world = Doorbell::create(&ns).expect("create");
        let mut agent = Doorbell::open(&ns).expect("open");
        world.ring().expect("ring");
        world.ring().expect("ring");
        let t = Instant::now();
        // Both rings are counted, and the wait did not sleep.
        assert_eq!(agent.wait(Duration::from_secs(10)).expect("wait"), 2);
        assert!(t.elapsed() < Duration::from_secs(5));
    }

    #[test]
    fn a_wait_without_a_ring_times_out() {
        let ns = ns("quiet");
        let _world = Doorbell::create(&ns).expect("create");
        let mut agent = Doorbell::open(&ns).expect("open");
        assert_eq!(agent.wait(Duration::from_millis(5)).expect("wait"), 0);
    }

    #[test]
    fn the_world_removes_its_doorbell_and_an_agent_cannot_open_a_missing_one() {
        let ns = ns("gone");
        let world = Doorbell::create(&ns).expect("create");
        assert!(path(&ns).exists());
        drop(world);
        assert!(!path(&ns).exists());
        let e = Doorbell::open(&ns).err().expect("no doorbell");
        assert!(e.to_string().contains("doorbell"), "{e}");
    }

    #[test]
    fn a_file_that_is_not_a_doorbell_is_refused() {
        let ns = ns("alien");
        std::fs::write(path(&ns), b"not a doorbell").expect("write");
        let e = Doorbell::open(&ns).err().expect("refused");
        assert!(e.to_string().contains("expected 4096"), "{e}");
        let _ = std::fs::remove_file(path(&ns));
    }
}
