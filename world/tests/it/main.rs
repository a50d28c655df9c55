//! The world's tests against numbers computed by hand, one test binary with
//! one module per theme (`cargo test --release -p mrsim-world --test it
//! dynamics::` runs one).

mod ackermann;
mod behaviours;
mod dynamics;
mod obstacles;
mod people;
mod shapes;
mod unicycle;
