//! No code: this crate exists for its `Cargo.toml`, which names the features
//! that the workspace's test build turns on, so that `cargo run --release`
//! and the Python build after `cargo test --release --workspace` reuse its
//! compiled dependencies instead of building them again with other features.
