//! mrsim scenario files.
#![warn(missing_docs)]

mod types;
pub use types::*;
