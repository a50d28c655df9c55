//! A 2-D laser scanner's scan: what a planner gets in
//! [`crate::Observation::scan`] (computed by `mrsim-lidar`, with rapier's ray
//! casts, for the agent's observation and the world's scan.csv alike; the
//! planners stay free of rapier).
//!
//! The scan has the meanings of ROS `sensor_msgs/LaserScan` (REP 117): beam
//! `k` points at `angle_min + k * angle_increment` radians in the robot's
//! frame (counter-clockwise from its heading); `ranges[k]` is the distance
//! from the robot's centre to the first surface along it, or `+inf` when
//! nothing lies within `range_max`. With a 360 degree field of view the
//! beams are spread over [-pi, pi) (`angle_increment` = 2 pi / beams, no
//! beam twice); a narrower one spans [-fov/2, fov/2] end to end. A beam
//! starting inside a disc reads 0; noise (Gaussian, standard deviation
//! `noise`) moves hits only, clamped to [0, range_max].

/// One laser scan (ROS LaserScan's fields that a 2-D simulation fills).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct LaserScan {
    /// Angle of the first beam, rad, in the robot's frame.
    pub angle_min: f64,
    /// Angle between consecutive beams, rad.
    pub angle_increment: f64,
    /// Longest range measured; beyond it a beam reads `+inf`.
    pub range_max: f64,
    /// One range per beam, in scenario units (`+inf`: no return).
    pub ranges: Vec<f64>,
}

/// A scanner's configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LidarConfig {
    /// Beams per scan, >= 1.
    pub beams: u32,
    /// Field of view, rad in (0, 2 pi].
    pub fov: f64,
    /// Longest range, > 0.
    pub range: f64,
    /// Standard deviation of the range noise (0 = none).
    pub noise: f64,
}

impl LidarConfig {
    /// `angle_min` and `angle_increment` of this configuration's scans.
    pub fn angles(&self) -> (f64, f64) {
        let n = self.beams.max(1) as f64;
        let full = self.fov >= std::f64::consts::TAU - 1e-12;
        if full {
            (-std::f64::consts::PI, std::f64::consts::TAU / n)
        } else if self.beams <= 1 {
            (0.0, 0.0)
        } else {
            (-self.fov / 2.0, self.fov / (n - 1.0))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::{FRAC_PI_2, PI};

    #[test]
    fn a_full_circle_spreads_the_beams_over_minus_pi_to_pi_without_repeating_one() {
        let cfg = LidarConfig {
            beams: 4,
            fov: 2.0 * PI,
            range: 1.0,
            noise: 0.0,
        };
        let (a0, inc) = cfg.angles();
        assert_eq!(a0, -PI);
        assert!((inc - FRAC_PI_2).abs() < 1e-15);
    }

    #[test]
    fn a_narrow_field_of_view_spans_its_ends() {
        let cfg = LidarConfig {
            beams: 5,
            fov: PI,
            range: 1.0,
            noise: 0.0,
        };
        let (a0, inc) = cfg.angles();
        assert!((a0 + FRAC_PI_2).abs() < 1e-15);
        assert!((a0 + 4.0 * inc - FRAC_PI_2).abs() < 1e-15);
    }
}
