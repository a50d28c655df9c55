//! The ROS 2 messages mrsim exchanges, as plain structs with their CDR
//! encoders (and a decoder for what comes in: `geometry_msgs/msg/Twist`).
//! Field order and types follow the message definitions of ROS 2 Jazzy
//! (`common_interfaces`, `geometry2`, `rcl_interfaces`).

use crate::cdr::{CdrError, Reader, Writer};

/// `builtin_interfaces/msg/Time`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Time {
    /// Whole seconds.
    pub sec: i32,
    /// Nanoseconds, < 1e9.
    pub nanosec: u32,
}

impl Time {
    /// The time `seconds` (>= 0; a negative or non-finite time is 0).
    pub fn from_secs(seconds: f64) -> Self {
        if !seconds.is_finite() || seconds <= 0.0 {
            return Self::default();
        }
        let ns = (seconds * 1e9).round() as u128;
        Self {
            sec: i32::try_from(ns / 1_000_000_000).unwrap_or(i32::MAX),
            nanosec: (ns % 1_000_000_000) as u32,
        }
    }

    /// The time in seconds.
    pub fn as_secs(&self) -> f64 {
        f64::from(self.sec) + f64::from(self.nanosec) * 1e-9
    }

    fn write(&self, w: &mut Writer) {
        w.i32(self.sec);
        w.u32(self.nanosec);
    }
}

/// `std_msgs/msg/Header`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Header {
    /// When.
    pub stamp: Time,
    /// In which frame.
    pub frame_id: String,
}

impl Header {
    fn write(&self, w: &mut Writer) {
        self.stamp.write(w);
        w.string(&self.frame_id);
    }
}

/// `geometry_msgs/msg/Vector3`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Vector3 {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
}

impl Vector3 {
    fn write(&self, w: &mut Writer) {
        w.f64(self.x);
        w.f64(self.y);
        w.f64(self.z);
    }

    fn read(r: &mut Reader<'_>) -> Result<Self, CdrError> {
        Ok(Self {
            x: r.f64()?,
            y: r.f64()?,
            z: r.f64()?,
        })
    }
}

/// `geometry_msgs/msg/Quaternion` (x, y, z, w).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Quaternion {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
    /// w.
    pub w: f64,
}

impl Quaternion {
    /// The rotation by `yaw` radians about +z.
    pub fn from_yaw(yaw: f64) -> Self {
        let h = 0.5 * yaw;
        Self {
            x: 0.0,
            y: 0.0,
            z: h.sin(),
            w: h.cos(),
        }
    }

    fn write(&self, w: &mut Writer) {
        w.f64(self.x);
        w.f64(self.y);
        w.f64(self.z);
        w.f64(self.w);
    }
}

/// `geometry_msgs/msg/Twist`: what `cmd_vel` carries.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Twist {
    /// Linear velocity, m/s (x forward for a unicycle).
    pub linear: Vector3,
    /// Angular velocity, rad/s (z the turn rate).
    pub angular: Vector3,
}

impl Twist {
    /// The CDR payload.
    pub fn encode(&self) -> Vec<u8> {
        let mut w = Writer::new();
        self.write(&mut w);
        w.finish()
    }

    fn write(&self, w: &mut Writer) {
        self.linear.write(w);
        self.angular.write(w);
    }

    /// Decodes a CDR payload; a payload of another type (too short, or
    /// with more than padding after the last field) is an error.
    pub fn decode(payload: &[u8]) -> Result<Self, CdrError> {
        let mut r = Reader::new(payload)?;
        let t = Self {
            linear: Vector3::read(&mut r)?,
            angular: Vector3::read(&mut r)?,
        };
        r.end()?;
        Ok(t)
    }
}

/// `nav_msgs/msg/Odometry`, with zero covariances (mrsim's odometry is
/// the simulated truth).
#[derive(Debug, Clone, PartialEq)]
pub struct Odometry {
    /// Stamp and the odometry frame (`<robot>/odom`).
    pub header: Header,
    /// The body frame (`<robot>/base_link`).
    pub child_frame_id: String,
    /// Position in the odometry frame.
    pub position: Vector3,
    /// Orientation in the odometry frame.
    pub orientation: Quaternion,
    /// Linear velocity in the body frame.
    pub linear: Vector3,
    /// Angular velocity in the body frame.
    pub angular: Vector3,
}

impl Odometry {
    /// The CDR payload.
    pub fn encode(&self) -> Vec<u8> {
        let mut w = Writer::new();
        self.header.write(&mut w);
        w.string(&self.child_frame_id);
        self.position.write(&mut w);
        self.orientation.write(&mut w);
        for _ in 0..36 {
            w.f64(0.0);
        }
        self.linear.write(&mut w);
        self.angular.write(&mut w);
        for _ in 0..36 {
            w.f64(0.0);
        }
        w.finish()
    }
}

/// `sensor_msgs/msg/LaserScan` (no intensities).
#[derive(Debug, Clone, PartialEq)]
pub struct LaserScan {
    /// Stamp and the scanner's frame.
    pub header: Header,
    /// First beam's angle, rad.
    pub angle_min: f32,
    /// Last beam's angle, rad.
    pub angle_max: f32,
    /// Between beams, rad.
    pub angle_increment: f32,
    /// Between measurements, s (0: all at once).
    pub time_increment: f32,
    /// Between scans, s.
    pub scan_time: f32,
    /// Shortest valid range, m.
    pub range_min: f32,
    /// Longest valid range, m.
    pub range_max: f32,
    /// One per beam (`+inf`: no return).
    pub ranges: Vec<f32>,
}

impl LaserScan {
    /// The CDR payload.
    pub fn encode(&self) -> Vec<u8> {
        let mut w = Writer::new();
        self.header.write(&mut w);
        for v in [
            self.angle_min,
            self.angle_max,
            self.angle_increment,
            self.time_increment,
            self.scan_time,
            self.range_min,
            self.range_max,
        ] {
            w.f32(v);
        }
        w.count(self.ranges.len());
        for r in &self.ranges {
            w.f32(*r);
        }
        w.count(0);
        w.finish()
    }
}

/// `geometry_msgs/msg/TransformStamped`.
#[derive(Debug, Clone, PartialEq)]
pub struct TransformStamped {
    /// Stamp and the parent frame.
    pub header: Header,
    /// The child frame.
    pub child_frame_id: String,
    /// The child's origin in the parent frame.
    pub translation: Vector3,
    /// The child's orientation in the parent frame.
    pub rotation: Quaternion,
}

/// `tf2_msgs/msg/TFMessage`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TfMessage {
    /// The transforms.
    pub transforms: Vec<TransformStamped>,
}

impl TfMessage {
    /// The CDR payload.
    pub fn encode(&self) -> Vec<u8> {
        let mut w = Writer::new();
        w.count(self.transforms.len());
        for t in &self.transforms {
            t.header.write(&mut w);
            w.string(&t.child_frame_id);
            t.translation.write(&mut w);
            t.rotation.write(&mut w);
        }
        w.finish()
    }
}

/// `rosgraph_msgs/msg/Clock`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Clock {
    /// The simulated time.
    pub clock: Time,
}

impl Clock {
    /// The CDR payload.
    pub fn encode(&self) -> Vec<u8> {
        let mut w = Writer::new();
        self.clock.write(&mut w);
        w.finish()
    }
}

/// `nav_msgs/msg/OccupancyGrid`.
#[derive(Debug, Clone, PartialEq)]
pub struct OccupancyGrid {
    /// Stamp and the map frame.
    pub header: Header,
    /// `info.map_load_time`.
    pub map_load_time: Time,
    /// Metres a cell.
    pub resolution: f32,
    /// Cells across.
    pub width: u32,
    /// Cells up.
    pub height: u32,
    /// The lower-left cell's corner in the map frame.
    pub origin_position: Vector3,
    /// The grid's orientation in the map frame.
    pub origin_orientation: Quaternion,
    /// Row-major from the lower-left cell: -1 unknown, 0 free .. 100
    /// occupied.
    pub data: Vec<i8>,
}

impl OccupancyGrid {
    /// The CDR payload.
    pub fn encode(&self) -> Vec<u8> {
        let mut w = Writer::new();
        self.header.write(&mut w);
        self.map_load_time.write(&mut w);
        w.f32(self.resolution);
        w.u32(self.width);
        w.u32(self.height);
        self.origin_position.write(&mut w);
        self.origin_orientation.write(&mut w);
        w.count(self.data.len());
        for v in &self.data {
            w.u8(*v as u8);
        }
        w.finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_twist_is_six_float64s_after_the_header_and_decodes_back() {
        let t = Twist {
            linear: Vector3 {
                x: 0.5,
                y: -0.25,
                z: 0.0,
            },
            angular: Vector3 {
                x: 0.0,
                y: 0.0,
                z: 1.25,
            },
        };
        let b = t.encode();
        assert_eq!(b.len(), 4 + 48);
        assert_eq!(&b[4..12], &0.5f64.to_le_bytes());
        assert_eq!(&b[44..52], &1.25f64.to_le_bytes());
        assert_eq!(Twist::decode(&b).unwrap(), t);
    }

    #[test]
    fn a_payload_of_another_type_is_not_a_twist() {
        // A Clock is 8 bytes: far too short.
        let clock = Clock {
            clock: Time::from_secs(1.0),
        };
        assert!(Twist::decode(&clock.encode()).is_err());
        // An Odometry is far longer: trailing bytes.
        let odom = Odometry {
            header: Header::default(),
            child_frame_id: "b".into(),
            position: Vector3::default(),
            orientation: Quaternion::from_yaw(0.0),
            linear: Vector3::default(),
            angular: Vector3::default(),
        };
        assert!(Twist::decode(&odom.encode()).is_err());
    }

    #[test]
    fn a_clock_is_seconds_and_nanoseconds() {
        let b = Clock {
            clock: Time::from_secs(2.05),
        }
        .encode();
        assert_eq!(&b[4..8], &2i32.to_le_bytes());
        assert_eq!(&b[8..12], &50_000_000u32.to_le_bytes());
        assert_eq!(Time::from_secs(f64::NAN), Time::default());
    }

    #[test]
    fn odometry_has_two_covariance_blocks_of_36() {
        let o = Odometry {
            header: Header {
                stamp: Time::default(),
                frame_id: "a0/odom".into(),
            },
            child_frame_id: "a0/base_link".into(),
            position: Vector3::default(),
            orientation: Quaternion::from_yaw(0.0),
            linear: Vector3::default(),
            angular: Vector3::default(),
        };
        let b = o.encode();
        // header: 8 (stamp) + 4 + 8 ("a0/odom\0") = 20; child: 4 + 13 = 17
        // -> 37, padded to 40; pose 7 + 36, twist 6 + 36 float64s.
        assert_eq!(b.len(), 4 + 40 + (7 + 36 + 6 + 36) * 8);
    }

    #[test]
    fn a_yaw_quaternion_is_a_unit_rotation_about_z() {
        let q = Quaternion::from_yaw(std::f64::consts::FRAC_PI_2);
        assert!((q.z * q.z + q.w * q.w - 1.0).abs() < 1e-12);
        assert!((q.z - q.w).abs() < 1e-12);
    }
}
