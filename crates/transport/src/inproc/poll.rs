//! How an in-process side waits for its next message: poll briefly, then
//! block.

use crossbeam::channel::Receiver;
use std::time::Duration;

/// How a side waits for its next message: poll for up to `spin`, then
/// block; poll only while the previous wait was shorter than `spin`.
#[derive(Debug, Default)]
pub(super) struct Poll {
    spin: Duration,
    /// The previous wait, from the call to the message.
    last: std::cell::Cell<Duration>,
}

impl Poll {
    pub(super) fn new(spin: Duration) -> Self {
        Self {
            spin,
            last: std::cell::Cell::new(Duration::ZERO),
        }
    }

    /// True if the next wait starts by polling.
    pub(super) fn polls(&self) -> bool {
        !self.spin.is_zero() && self.last.get() < self.spin
    }

    /// Receives from `rx` within `timeout`. The poll yields the CPU between
    /// tries, so a thread whose turn it is (the world stepping, a worker
    /// planning) sharing the core is delayed by no more than a context
    /// switch per try.
    pub(super) fn recv<T>(
        &self,
        rx: &Receiver<T>,
        timeout: Duration,
    ) -> Result<T, crossbeam::channel::RecvTimeoutError> {
        use crossbeam::channel::{RecvTimeoutError, TryRecvError};
        let start = std::time::Instant::now();
        let got = if self.polls() {
            let spin = self.spin.min(timeout);
            loop {
                match rx.try_recv() {
                    Ok(m) => break Ok(m),
                    Err(TryRecvError::Disconnected) => break Err(RecvTimeoutError::Disconnected),
                    Err(TryRecvError::Empty) => {}
                }
                let spent = start.elapsed();
                if spent >= spin {
                    break rx.recv_timeout(timeout.saturating_sub(spent));
                }
                std::thread::yield_now();
            }
        } else {
            rx.recv_timeout(timeout)
        };
        if got.is_ok() {
            self.last.set(start.elapsed());
        }
        got
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crossbeam::channel::{RecvTimeoutError, unbounded};

    #[test]
    fn a_polling_side_gets_a_message_sent_while_it_polls() {
        let (tx, rx) = unbounded();
        let poll = Poll::new(Duration::from_secs(5));
        let sender = std::thread::spawn(move || {
            std::thread::sleep(Duration::from_millis(2));
            tx.send(7u32)
        });
        assert_eq!(poll.recv(&rx, Duration::from_secs(10)), Ok(7));
        assert!(sender.join().is_ok_and(|r| r.is_ok()));
    }

    #[test]
    fn a_polling_side_sees_the_sender_gone_and_an_empty_channel_time_out() {
        let (tx, rx) = unbounded::<u32>();
        let poll = Poll::new(Duration::from_millis(1));
        assert_eq!(
            poll.recv(&rx, Duration::from_millis(5)),
            Err(RecvTimeoutError::Timeout)
        );
        drop(tx);
        assert_eq!(
            poll.recv(&rx, Duration::from_millis(5)),
            Err(RecvTimeoutError::Disconnected)
        );
    }

    #[test]
    fn a_side_polls_only_while_its_waits_are_shorter_than_the_spin() {
        let (tx, rx) = unbounded();
        let mut poll = Poll::new(Duration::from_millis(20));
        assert!(poll.polls());
        // A wait longer than the spin: the next one blocks at once. The
        // message is sent only once this thread has polled through the
        // whole spin and sleeps in its blocking receive (not after a pause
        // that is usually long enough), so the wait is longer than the
        // spin however fast or slow the threads run.
        let me = crate::test_support::thread_id();
        let (started_tx, started_rx) = std::sync::mpsc::channel::<()>();
        let sender = std::thread::spawn(move || {
            let _ = started_rx.recv();
            crate::test_support::wait_until_asleep(me);
            let _ = tx.send(1u32);
            tx
        });
        let _ = started_tx.send(());
        assert_eq!(poll.recv(&rx, Duration::from_secs(60)), Ok(1));
        assert!(!poll.polls());
        // A message already waiting is a short wait: polling resumes.
        // Measured against a spin no receive of a waiting message comes
        // near (and a last wait as long), so that no pause of this thread
        // can make it look long.
        let hour = Duration::from_secs(3600);
        poll.spin = hour;
        poll.last.set(hour);
        assert!(!poll.polls());
        let tx = sender.join().expect("sender");
        let _ = tx.send(2);
        assert_eq!(poll.recv(&rx, Duration::from_secs(60)), Ok(2));
        assert!(poll.polls());
        // Zero spin never polls.
        assert!(!Poll::new(Duration::ZERO).polls());
    }
}
