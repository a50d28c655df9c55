//! The end-to-end tests of the `mrsim` binary and library, one test binary
//! with one module per theme (linked once, not once per theme). Run one
//! theme with its module path as the filter:
//!
//! ```sh
//! cargo test --release --test it golden::
//! ```
//!
//! Every module shares `common` (fresh folders, run ids, the `heavy` lock),
//! so its counters and its lock hold across all the themes.

mod common;

mod bench;
mod cars;
mod cores;
mod cores_real;
mod crowdnav;
mod cut;
mod designated_path;
mod dwa_shapes;
mod episodes;
mod faults;
mod golden;
mod interaction;
mod invalid;
mod lidar;
mod limits;
mod maps;
mod orca;
mod outputs;
mod own_planner;
mod ownership;
mod papers;
mod papers_band;
mod people;
mod report;
mod routes;
mod scale;
mod spine;
mod sweep;
mod timing;
mod top;
mod top_scale;
mod transport;
mod unicycle;
mod verdict;
mod zenoh;
mod zhu_loh;
