//! ROS 2 over rmw_zenoh, for mrsim's ROS 2 agent (`mrsim ros2`): what a
//! ROS 2 node using `rmw_zenoh_cpp` puts on a Zenoh network, written
//! without a ROS install and over the Zenoh library mrsim already uses.
//!
//! - [`cdr`]: little-endian CDR with its encapsulation header;
//! - [`msgs`]: the messages (Twist in; Odometry, LaserScan, TFMessage,
//!   Clock, OccupancyGrid out);
//! - [`names`]: key expressions, type names and RIHS01 hashes, liveliness
//!   tokens, QoS;
//! - [`attachment`]: the 33-byte attachment of every sample;
//! - [`node`]: a node on a Zenoh session (tokens, publishers with
//!   attachments, subscribers that see other types under the same name).

#![warn(missing_docs)]

pub mod attachment;
pub mod cdr;
#[cfg(test)]
mod fuzz;
pub mod msgs;
pub mod names;
pub mod node;
