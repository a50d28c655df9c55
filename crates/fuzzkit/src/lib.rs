//! What the fuzz targets of mrsim's decoders share: the largest single
//! allocation a call asks for, so a target can hold a decoder to memory in
//! proportion to its input (a length field of 2^60 must not become a
//! 2^60-byte buffer).
//!
//! It is a crate of its own because the measure is a global allocator,
//! which a program may have only one of: each crate with fuzz targets
//! (the live page, ROS 2's CDR, the maps, the Zenoh wire format) takes it
//! as a dev-dependency, so it is in their test binaries and nowhere else.
//! The allocator passes every call to the system's unchanged and notes the
//! size on the requesting thread; [`measure`] reads it.
#![warn(missing_docs)]

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

struct Noting;

thread_local! {
    static LARGEST: Cell<usize> = const { Cell::new(0) };
}

fn note(n: usize) {
    let _ = LARGEST.try_with(|c| c.set(c.get().max(n)));
}

// SAFETY: every call is passed on to the system allocator unchanged.
unsafe impl GlobalAlloc for Noting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        note(l.size());
        // SAFETY: the caller's layout, as GlobalAlloc::alloc requires.
        unsafe { System.alloc(l) }
    }
    unsafe fn alloc_zeroed(&self, l: Layout) -> *mut u8 {
        note(l.size());
        // SAFETY: as above.
        unsafe { System.alloc_zeroed(l) }
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, n: usize) -> *mut u8 {
        note(n);
        // SAFETY: a block of this allocator (the system's) and its layout.
        unsafe { System.realloc(p, l, n) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        // SAFETY: as above.
        unsafe { System.dealloc(p, l) }
    }
}

#[global_allocator]
static NOTING: Noting = Noting;

/// `f`'s result and the largest allocation it asked for, bytes.
pub fn measure<T>(f: impl FnOnce() -> T) -> (T, usize) {
    LARGEST.with(|c| c.set(0));
    let r = f();
    (r, LARGEST.with(Cell::get))
}
