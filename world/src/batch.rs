//! A buffer the tick loop fills and hands to a thread in batches, whose
//! storage the thread sends back for reuse: the recorder's ticks
//! ([`crate::record`]) and the commands' timings ([`crate::timings`]).
//! Handing over every tick cost the loop a futex wake each time.

use crossbeam::channel::{Receiver, Sender};
use std::time::{Duration, Instant};

/// What a [`Batcher`] fills.
pub trait Batch: Default {
    /// Nothing in it.
    fn is_empty(&self) -> bool;
    /// Empties it, keeping its storage.
    fn clear(&mut self);
}

impl<T> Batch for Vec<T> {
    fn is_empty(&self) -> bool {
        Vec::is_empty(self)
    }
    fn clear(&mut self) {
        Vec::clear(self)
    }
}

/// The loop's side: the batch being filled, the channel to the thread
/// (messages of type `M`, a batch wrapped by `wrap`) and the emptied
/// batches coming back.
pub struct Batcher<T: Batch, M> {
    tx: Option<Sender<M>>,
    recycled: Receiver<T>,
    pending: T,
    oldest: Option<Instant>,
    wrap: fn(T) -> M,
}

impl<T: Batch, M> Batcher<T, M> {
    /// Sends batches on `tx`, each as `wrap(batch)`; `recycled` brings the
    /// thread's emptied batches back.
    pub fn new(tx: Sender<M>, recycled: Receiver<T>, pending: T, wrap: fn(T) -> M) -> Self {
        Self {
            tx: Some(tx),
            recycled,
            pending,
            oldest: None,
            wrap,
        }
    }

    /// The batch being filled; its age counts from the first call since it
    /// was last sent.
    pub fn pending(&mut self) -> &mut T {
        self.oldest.get_or_insert_with(Instant::now);
        &mut self.pending
    }

    /// Sends the batch if it has waited `age` or more.
    pub fn send_if_older(&mut self, age: Duration) {
        if self.oldest.is_some_and(|t| t.elapsed() >= age) {
            self.send();
        }
    }

    /// Sends the batch now (nothing if it is empty).
    pub fn send(&mut self) {
        self.oldest = None;
        if self.pending.is_empty() {
            return;
        }
        let mut next = self.recycled.try_recv().unwrap_or_default();
        next.clear();
        let batch = std::mem::replace(&mut self.pending, next);
        if let Some(tx) = &self.tx {
            let _ = tx.send((self.wrap)(batch));
        }
    }

    /// The channel to the thread, for other messages; `None` once closed.
    pub fn sender(&self) -> Option<&Sender<M>> {
        self.tx.as_ref()
    }

    /// Sends what is pending and closes the channel: the thread ends once
    /// it has taken everything in.
    pub fn close(&mut self) {
        self.send();
        self.tx.take();
    }
}
