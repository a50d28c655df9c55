//! The tick doorbell: one futex word in shared memory that wakes every
//! agent process of a run with one system call.
//!
//! Why not an iceoryx2 event: on Linux an iceoryx2 event is a Unix datagram
//! socket per listener, so waking N agents is N `sendto` calls by the world
//! and one `recvfrom` per agent to drain it: at hundreds of agents those
//! system calls are most of the world's CPU time (BENCHMARKS.md has the
//! profiles). A futex wakes them all at once (`FUTEX_WAKE`, every waiter),
//! and an agent's wait is one `FUTEX_WAIT`.
//!
//! The word counts rings. The world publishes the snapshot (iceoryx2,
//! zero-copy) and then rings: it bumps the count (release) and wakes every
//! waiter. An agent remembers the count it last saw and sleeps only while
//! the word still holds it; the kernel compares and sleeps atomically, so a
//! ring between the agent's look and its sleep is never lost. A count that
//! moved means "look for a new snapshot": the snapshot itself always comes
//! through iceoryx2, so a spurious or merged ring costs one empty receive.
//!
//! The same page counts the agents' answers, so that the world is woken
//! once per tick, by the last answer it waits for, rather than by every
//! command (an iceoryx2 notify per command would cost a `sendto` by each
//! agent and up to one wake-up of the world per command). Before publishing tick t
//! the world sets the `answers` word to t's tag (its low 16 bits) with a
//! count of zero, and the count it waits for. An agent that has published
//! its command for tick t adds one to the count if the tag is still t's
//! (an answer to an older tick is not counted), and the answer that brings
//! the count to the expected one, or past it, wakes the world
//! (`FUTEX_WAKE`). The world, like an agent, remembers the word as it last
//! saw it and sleeps only while it still holds that; the command is
//! published before it is counted, so a count the world has seen comes
//! with its command already in.
//!
//! The file lives in /dev/shm under the run's prefix (so
//! [`crate::Namespace::remove_leftovers`] removes it, and
//! [`crate::Namespace::make_private`] keeps it private). The world creates
//! it before any iceoryx2 service of the run, so an agent that found the
//! services finds the doorbell; the world removes it when it ends.
//!
//! The doorbell also names its world (process id and start time). A world
//! that was killed leaves its doorbell, services and nodes behind until the
//! next world of the run id clears them. An agent started before that next
//! world would find the dead world's services, join nothing, and later
//! have its files removed under it. So an agent opens the doorbell first,
//! and goes on only when the world named there is running
//! ([`Doorbell::open`]). A world clears the run's leftovers before it
//! creates its doorbell, so everything of the run found after a live
//! world's doorbell is that world's.

use crate::{Namespace, TransportError};
use std::fs::OpenOptions;
use std::os::fd::AsRawFd;
use std::os::unix::fs::OpenOptionsExt;
use std::path::PathBuf;
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};
use std::time::Duration;

/// Size of the mapping: one page.
const LEN: usize = 4096;
/// Written first by the world; an agent refuses a file without it (a
/// doorbell being created, or some other file under the name).
const MAGIC: u32 = 0x6d72_6462; // "mrdb"

/// The words of the doorbell, each group on its own cache line.
#[repr(C, align(64))]
struct Words {
    magic: AtomicU32,
    /// The world's process id, written before `magic`.
    world_pid: AtomicU32,
    /// The world's start time (/proc/PID/stat's `starttime`, clock ticks
    /// since boot; 0 if unknown): a process id reused after the world died
    /// is not taken for it.
    world_start: AtomicU64,
    _pad: [u8; 48],
    ring: AtomicU32,
    _pad2: [u8; 60],
    /// Tick tag (high 16 bits) and answers counted (low 16 bits).
    answers: AtomicU32,
    /// The count of answers that wakes the world.
    expected: AtomicU32,
}

/// The tag of `tick` in the `answers` word.
fn tag(tick: u64) -> u32 {
    ((tick & 0xffff) as u32) << 16
}

/// The most answers one tick can count.
const MAX_COUNT: u32 = 0xffff;

/// `FUTEX_WAIT` on `word` while it holds `seen`, for at most `timeout`.
/// Returns normally when woken, when the word no longer held `seen`, on
/// time-out and on a signal: the caller looks at the word and its flags.
fn futex_wait(word: &AtomicU32, seen: u32, timeout: Duration) -> Result<(), TransportError> {
    let ts = libc::timespec {
        tv_sec: timeout.as_secs().min(i32::MAX as u64) as libc::time_t,
        tv_nsec: timeout.subsec_nanos() as libc::c_long,
    };
    // SAFETY: a futex wait on an aligned u32 of a live shared mapping,
    // with a valid relative timeout.
    let r = unsafe {
        libc::syscall(
            libc::SYS_futex,
            word.as_ptr(),
            libc::FUTEX_WAIT,
            seen,
            &ts as *const libc::timespec,
            std::ptr::null::<u32>(),
            0u32,
        )
    };
    if r < 0 {
        match std::io::Error::last_os_error().raw_os_error() {
            // Changed before we slept, timed out, or a signal.
            Some(libc::EAGAIN | libc::ETIMEDOUT | libc::EINTR) => {}
            _ => {
                return Err(TransportError::Wait(format!(
                    "futex wait: {}",
                    std::io::Error::last_os_error()
                )));
            }
        }
    }
    Ok(())
}

/// `FUTEX_WAKE` of up to `waiters` sleeping on `word`.
fn futex_wake(word: &AtomicU32, waiters: i32, what: &'static str) -> Result<(), TransportError> {
    // SAFETY: a futex wake on an aligned u32 of a live shared mapping.
    let r = unsafe {
        libc::syscall(
            libc::SYS_futex,
            word.as_ptr(),
            libc::FUTEX_WAKE,
            waiters,
            std::ptr::null::<libc::timespec>(),
            std::ptr::null::<u32>(),
            0u32,
        )
    };
    if r < 0 {
        return Err(TransportError::Send {
            what,
            detail: format!("futex wake: {}", std::io::Error::last_os_error()),
        });
    }
    Ok(())
}

/// One side's mapping of a run's doorbell.
pub struct Doorbell {
    words: *const Words,
    /// Set on the world's doorbell: the file it removes when dropped.
    owned: Option<PathBuf>,
    /// The ring count this side last saw (agents).
    seen: u32,
    /// The answers word as the world last saw it.
    answers_seen: u32,
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
            answers_seen: 0,
        };
        let w = bell.words();
        let pid = std::process::id();
        w.world_pid.store(pid, Ordering::Relaxed);
        w.world_start.store(
            mrsim_sys::process::start_time(pid).unwrap_or(0),
            Ordering::Relaxed,
        );
        w.magic.store(MAGIC, Ordering::Release);
        Ok(bell)
    }

    /// An agent's side: opens the doorbell the run's world created. Fails
    /// if there is none, or if the world that created it is no longer
    /// running (it was killed and left it behind).
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
            answers_seen: 0,
        };
        if bell.words().magic.load(Ordering::Acquire) != MAGIC {
            return Err(err(
                &path.display().to_string(),
                "no doorbell mark (not created yet, or not a doorbell)",
            ));
        }
        let (pid, start) = bell.world();
        if pid == 0 {
            return Err(err(
                &path.display().to_string(),
                "it names no world (made by a world of an older mrsim, protocol < 6)",
            ));
        }
        let started = mrsim_sys::process::start_time(pid);
        if !mrsim_sys::process::pid_alive(pid)
            || (start != 0 && started.is_some_and(|s| s != start))
        {
            return Err(err(
                &path.display().to_string(),
                format!(
                    "left by a world (pid {pid}) that is no longer running; \
                     no world of this run id is up"
                ),
            ));
        }
        bell.seen = bell.words().ring.load(Ordering::Acquire);
        Ok(bell)
    }

    /// The process id and start time of the world that created the
    /// doorbell.
    pub fn world(&self) -> (u32, u64) {
        let w = self.words();
        (
            w.world_pid.load(Ordering::Relaxed),
            w.world_start.load(Ordering::Relaxed),
        )
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
        futex_wake(ring, i32::MAX, "tick doorbell")
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
        futex_wait(ring, self.seen, timeout)?;
        let now = ring.load(Ordering::Acquire);
        let rang = now.wrapping_sub(self.seen);
        self.seen = now;
        Ok(rang)
    }

    /// The world's side, before it publishes tick `tick`: the answers to
    /// it start counting from zero, and the `count`-th wakes the world.
    pub fn expect(&mut self, tick: u64, count: usize) {
        let w = self.words();
        w.expected
            .store((count as u32).min(MAX_COUNT), Ordering::Relaxed);
        w.answers.store(tag(tick), Ordering::Release);
        self.answers_seen = tag(tick);
    }

    /// An agent's side, once its command for tick `tick` is published:
    /// counts it if the world still waits for answers to that tick, and
    /// wakes the world if it was the last (or later).
    pub fn answered(&self, tick: u64) -> Result<(), TransportError> {
        let w = self.words();
        let mut now = w.answers.load(Ordering::Relaxed);
        loop {
            if now & !MAX_COUNT != tag(tick) || now & MAX_COUNT == MAX_COUNT {
                // An answer to an older tick, or (past 65535) not counted.
                return Ok(());
            }
            match w
                .answers
                .compare_exchange_weak(now, now + 1, Ordering::AcqRel, Ordering::Relaxed)
            {
                Ok(_) => break,
                Err(changed) => now = changed,
            }
        }
        if (now + 1) & MAX_COUNT >= w.expected.load(Ordering::Relaxed) {
            futex_wake(&w.answers, 1, "answer count")?;
        }
        Ok(())
    }

    /// The world's side: returns at once if answers were counted since the
    /// last call (or since [`Doorbell::expect`]), else sleeps until the
    /// answer it waits for wakes it, `timeout` passes, or a signal arrives.
    /// True if answers were counted.
    pub fn wait_answers(&mut self, timeout: Duration) -> Result<bool, TransportError> {
        let answers = &self.words().answers;
        let now = answers.load(Ordering::Acquire);
        if now == self.answers_seen && !timeout.is_zero() {
            futex_wait(answers, now, timeout)?;
        }
        let now = answers.load(Ordering::Acquire);
        let counted = now != self.answers_seen;
        self.answers_seen = now;
        Ok(counted)
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
    use crate::test_support::{thread_id, wait_until_asleep};
    use std::time::Instant;

    /// Far longer than any wait here takes when it works: a wait that
    /// gets near it slept through what should have woken it.
    const GUARD: Duration = Duration::from_secs(60);

    fn ns(tag: &str) -> Namespace {
        Namespace::new(&format!("doorbell-{tag}-{}", std::process::id())).expect("namespace")
    }

    /// A world's doorbell and an agent's side of it.
    fn pair(tag: &str) -> (Doorbell, Doorbell) {
        let ns = ns(tag);
        let world = Doorbell::create(&ns).expect("create");
        let agent = Doorbell::open(&ns).expect("open");
        (world, agent)
    }

    #[test]
    fn a_ring_wakes_a_waiting_agent_and_is_seen_once() {
        let (world, mut agent) = pair("wake");
        let (tid_tx, tid_rx) = std::sync::mpsc::channel();
        let waiter = std::thread::spawn(move || {
            let _ = tid_tx.send(thread_id());
            let t = Instant::now();
            let rang = agent.wait(GUARD).expect("wait");
            let slept = t.elapsed();
            // Seen once: the next wait times out.
            let again = agent.wait(Duration::from_millis(20)).expect("wait");
            (rang, slept, again)
        });
        // Rung only once the agent sleeps in its wait, not after a pause
        // that is usually long enough: whatever the threads' speed, it is
        // the ring that must wake it.
        wait_until_asleep(tid_rx.recv().expect("waiter's id"));
        world.ring().expect("ring");
        let (rang, slept, again) = waiter.join().expect("waiter");
        assert_eq!(rang, 1);
        // Woken by the ring, not by the guard's timeout.
        assert!(slept < GUARD / 2, "{slept:?}");
        assert_eq!(again, 0);
    }

    #[test]
    fn a_ring_before_the_wait_is_not_lost() {
        let (world, mut agent) = pair("early");
        world.ring().expect("ring");
        world.ring().expect("ring");
        let t = Instant::now();
        // Both rings are counted, and the wait did not sleep: it returns
        // at once, so only a wait that slept through the rings (until the
        // guard's timeout) gets near the bound.
        assert_eq!(agent.wait(GUARD).expect("wait"), 2);
        assert!(t.elapsed() < GUARD / 2);
    }

    #[test]
    fn a_wait_without_a_ring_times_out() {
        let (_world, mut agent) = pair("quiet");
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
    fn a_doorbell_names_the_world_that_made_it() {
        let (world, agent) = pair("names");
        let me = std::process::id();
        assert_eq!(
            agent.world(),
            (me, mrsim_sys::process::start_time(me).expect("start"))
        );
        assert_eq!(world.world(), agent.world());
    }

    #[test]
    fn a_doorbell_left_by_a_world_that_ended_is_refused() {
        let ns = ns("dead");
        let world = Doorbell::create(&ns).expect("create");
        // A process that has ended (and was reaped) stands for a killed
        // world.
        let mut child = std::process::Command::new("true")
            .spawn()
            .expect("spawn true");
        let dead = child.id();
        child.wait().expect("wait true");
        world.words().world_pid.store(dead, Ordering::Relaxed);
        let e = Doorbell::open(&ns).err().expect("refused");
        assert!(e.to_string().contains("no longer running"), "{e}");
        // Its process id taken by another process (one that started at
        // another time) is no world either.
        world
            .words()
            .world_pid
            .store(std::process::id(), Ordering::Relaxed);
        world.words().world_start.fetch_add(1, Ordering::Relaxed);
        let e = Doorbell::open(&ns).err().expect("refused");
        assert!(e.to_string().contains("no longer running"), "{e}");
    }

    #[test]
    fn a_file_that_is_not_a_doorbell_is_refused() {
        let ns = ns("alien");
        std::fs::write(path(&ns), b"not a doorbell").expect("write");
        let e = Doorbell::open(&ns).err().expect("refused");
        assert!(e.to_string().contains("expected 4096"), "{e}");
        let _ = std::fs::remove_file(path(&ns));
    }

    #[test]
    fn the_last_expected_answer_wakes_the_world() {
        let (mut world, agent) = pair("answers");
        world.expect(41, 3);
        agent.answered(41).expect("answer");
        agent.answered(41).expect("answer");
        // Counted since the world last looked: it does not sleep.
        assert!(world.wait_answers(Duration::from_secs(60)).expect("wait"));
        // Nothing new: a short wait times out.
        assert!(!world.wait_answers(Duration::from_millis(5)).expect("wait"));
        let (tid_tx, tid_rx) = std::sync::mpsc::channel();
        let waiter = std::thread::spawn(move || {
            let _ = tid_tx.send(thread_id());
            let t = Instant::now();
            let counted = world.wait_answers(GUARD).expect("wait");
            (counted, t.elapsed())
        });
        // The third answer comes only once the world sleeps on the count,
        // not after a pause that is usually long enough: whatever the
        // threads' speed, it is the answer that must wake it.
        wait_until_asleep(tid_rx.recv().expect("waiter's id"));
        agent.answered(41).expect("answer");
        let (counted, slept) = waiter.join().expect("waiter");
        assert!(counted);
        // Woken by the third answer, not by the guard's timeout.
        assert!(slept < GUARD / 2, "{slept:?}");
    }

    #[test]
    fn an_answer_to_an_older_tick_is_not_counted() {
        let (mut world, agent) = pair("late");
        world.expect(7, 1);
        agent.answered(6).expect("answer");
        assert!(!world.wait_answers(Duration::ZERO).expect("look"));
        agent.answered(7).expect("answer");
        assert!(world.wait_answers(Duration::ZERO).expect("look"));
        // The next tick starts from zero again.
        world.expect(8, 1);
        assert!(!world.wait_answers(Duration::ZERO).expect("look"));
    }
}
