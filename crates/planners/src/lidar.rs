//! A 2-D laser scanner: what a planner gets in [`crate::Observation::scan`]
//! and what the world writes to scan.csv, computed by the same function
//! ([`scan`]) on both sides so they agree to the bit.
//!
//! The scan has the meanings of ROS `sensor_msgs/LaserScan` (REP 117): beam
//! `k` points at `angle_min + k * angle_increment` radians in the robot's
//! frame (counter-clockwise from its heading); `ranges[k]` is the distance
//! from the robot's centre to the first surface along it, or `+inf` when
//! nothing lies within `range_max`. With a 360 degree field of view the
//! beams are spread over [-pi, pi) (`angle_increment` = 2 pi / beams, no
//! beam twice); a narrower one spans [-fov/2, fov/2] end to end.
//!
//! Rays are cast exactly against discs (other robots, obstacles) and
//! segments (walls, the arena, the map's traced outlines): a ray
//! p + t d meets the disc |x - c| = r at the smaller root of
//! t² + 2 t d.(p - c) + |p - c|² - r² = 0, and a segment a + s (b - a),
//! s in [0, 1], where the two lines' cross products say so. A ray starting
//! inside a disc reads 0. Noise, when asked for, is added to each hit's
//! range (Gaussian, standard deviation `noise`) and clamped to
//! [0, range_max]; misses stay `+inf`.
//!
//! ARCHITECTURE.md says why the scan is computed by the agent and not the
//! world, and BENCHMARKS.md what it costs.

use crate::{Segment, Vec2};

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

/// Distance along the unit ray `p + t d` to the disc of centre `c` and
/// radius `r` (0 if `p` is inside), if it meets it.
pub fn ray_disc(p: Vec2, d: Vec2, c: Vec2, r: f64) -> Option<f64> {
    let m = p - c;
    let b = m.dot(&d);
    let cc = m.norm_squared() - r * r;
    if cc <= 0.0 {
        return Some(0.0);
    }
    if b > 0.0 {
        return None;
    }
    let disc = b * b - cc;
    if disc < 0.0 {
        return None;
    }
    Some((-b - disc.sqrt()).max(0.0))
}

/// Distance along the unit ray `p + t d` to segment `s`, if it meets it.
pub fn ray_segment(p: Vec2, d: Vec2, s: &Segment) -> Option<f64> {
    let e = s.b - s.a;
    let cross = |u: Vec2, v: Vec2| u.x * v.y - u.y * v.x;
    let denom = cross(d, e);
    let ap = s.a - p;
    if denom.abs() <= f64::EPSILON * e.norm() {
        // Parallel: a hit only if collinear, at the nearer end ahead.
        if cross(ap, d).abs() > 1e-12 * (1.0 + ap.norm()) {
            return None;
        }
        let (ta, tb) = (ap.dot(&d), (s.b - p).dot(&d));
        return match (ta >= 0.0, tb >= 0.0) {
            (true, true) => Some(ta.min(tb)),
            (false, false) => None,
            _ => Some(0.0),
        };
    }
    let t = cross(ap, e) / denom;
    let u = cross(ap, d) / denom;
    (t >= 0.0 && (0.0..=1.0).contains(&u)).then_some(t)
}

/// Fills `out` with the scan of a robot at `origin` heading `heading`
/// (rad) among `discs` (centre, radius; the robot itself left out) and
/// `walls`. `gaussian` draws the noise (called once per hit beam, in beam
/// order, only when `config.noise > 0`).
pub fn scan(
    out: &mut LaserScan,
    config: &LidarConfig,
    origin: Vec2,
    heading: f64,
    discs: impl IntoIterator<Item = (Vec2, f64)>,
    walls: &[Segment],
    gaussian: &mut dyn FnMut() -> f64,
) {
    let (angle_min, inc) = config.angles();
    let range = config.range;
    out.angle_min = angle_min;
    out.angle_increment = inc;
    out.range_max = range;
    out.ranges.clear();
    let beams = config.beams.max(1) as usize;
    out.ranges.resize(beams, f64::INFINITY);
    let ranges = &mut out.ranges;
    let full = config.fov >= std::f64::consts::TAU - 1e-12;
    // Each surface is tested only on the beams within the angle it
    // subtends from the origin (one beam more either side for rounding;
    // the exact ray test decides), so the cost is the beams that can hit
    // it rather than every beam.
    let mut each = |start: f64, width: f64, hit: &mut dyn FnMut(Vec2) -> Option<f64>| {
        let mut test = |k: usize, ranges: &mut Vec<f64>| {
            let a = heading + angle_min + inc * k as f64;
            if let Some(t) = hit(Vec2::new(a.cos(), a.sin())) {
                ranges[k] = ranges[k].min(t);
            }
        };
        if width >= std::f64::consts::PI || inc <= 0.0 {
            (0..beams).for_each(|k| test(k, ranges));
        } else if full {
            let o = (start - heading - angle_min).rem_euclid(std::f64::consts::TAU) / inc;
            let k0 = o.floor() as i64 - 1;
            let count = ((width / inc).ceil() as usize + 3).min(beams);
            for j in 0..count {
                test((k0 + j as i64).rem_euclid(beams as i64) as usize, ranges);
            }
        } else {
            let rs = wrap(start - heading);
            for shift in [0.0, -std::f64::consts::TAU] {
                let lo = ((rs + shift - angle_min) / inc).floor() as i64 - 1;
                let hi = ((rs + shift + width - angle_min) / inc).ceil() as i64 + 1;
                for k in lo.max(0)..=hi.min(beams as i64 - 1) {
                    test(k as usize, ranges);
                }
            }
        }
    };
    for (c, r) in discs {
        let d = c - origin;
        let dist = d.norm();
        if dist - r > range {
            continue;
        }
        let half = if dist <= r {
            std::f64::consts::PI
        } else {
            (r / dist).asin()
        };
        each(d.y.atan2(d.x) - half, 2.0 * half, &mut |dir| {
            ray_disc(origin, dir, c, r)
        });
    }
    for w in walls {
        if (w.closest_point(origin) - origin).norm() > range {
            continue;
        }
        let (da, db) = (w.a - origin, w.b - origin);
        let (ta, tb) = (da.y.atan2(da.x), db.y.atan2(db.x));
        let delta = wrap(tb - ta);
        let cross = da.x * db.y - da.y * db.x;
        // The origin on the segment's line: every beam.
        let width = if cross.abs() <= 1e-12 * (da.norm() * db.norm()).max(1e-300) {
            std::f64::consts::PI
        } else {
            delta.abs()
        };
        let start = if delta >= 0.0 { ta } else { tb };
        each(start, width, &mut |dir| ray_segment(origin, dir, w));
    }
    for t in ranges.iter_mut() {
        if *t > range {
            *t = f64::INFINITY;
        } else if config.noise > 0.0 {
            *t = (*t + config.noise * gaussian()).clamp(0.0, range);
        }
    }
}

/// Angle `a` wrapped to (-pi, pi].
fn wrap(a: f64) -> f64 {
    let w = a.rem_euclid(std::f64::consts::TAU);
    if w > std::f64::consts::PI {
        w - std::f64::consts::TAU
    } else {
        w
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::{FRAC_PI_2, PI};

    fn full(beams: u32) -> LidarConfig {
        LidarConfig {
            beams,
            fov: 2.0 * PI,
            range: 10.0,
            noise: 0.0,
        }
    }

    fn no_noise() -> f64 {
        panic!("no noise asked for")
    }

    #[test]
    fn a_disc_ahead_reads_its_centre_distance_less_its_radius() {
        let mut s = LaserScan::default();
        // 4 beams: -pi, -pi/2, 0, pi/2.
        scan(
            &mut s,
            &full(4),
            Vec2::new(1.0, 1.0),
            0.0,
            [(Vec2::new(4.0, 1.0), 0.5)],
            &[],
            &mut no_noise,
        );
        assert_eq!(s.angle_min, -PI);
        assert!((s.angle_increment - FRAC_PI_2).abs() < 1e-15);
        assert!((s.ranges[2] - 2.5).abs() < 1e-12, "{:?}", s.ranges);
        assert!(s.ranges[0].is_infinite() && s.ranges[1].is_infinite());
        assert!(s.ranges[3].is_infinite());
    }

    #[test]
    fn an_oblique_beam_meets_a_disc_where_the_quadratic_says() {
        // Beam at 45 degrees from the origin; disc at (3, 2) radius 1: the
        // line y = x meets (x-3)² + (x-2)² = 1 at x = 2 (and 3).
        let d = Vec2::new(1.0, 1.0).normalize();
        let t = ray_disc(Vec2::zeros(), d, Vec2::new(3.0, 2.0), 1.0).unwrap();
        assert!((t - 2.0 * 2f64.sqrt()).abs() < 1e-12, "{t}");
        assert_eq!(ray_disc(Vec2::zeros(), -d, Vec2::new(3.0, 2.0), 1.0), None);
        assert_eq!(
            ray_disc(Vec2::zeros(), d, Vec2::new(0.1, 0.0), 0.5),
            Some(0.0)
        );
    }

    #[test]
    fn a_wall_corner_reads_the_perpendicular_distance_to_each_side() {
        // A corner at (2, 3): walls x = 2 (y <= 3) and y = 3 (x <= 2).
        let walls = [
            Segment {
                a: Vec2::new(2.0, -5.0),
                b: Vec2::new(2.0, 3.0),
            },
            Segment {
                a: Vec2::new(-5.0, 3.0),
                b: Vec2::new(2.0, 3.0),
            },
        ];
        let mut s = LaserScan::default();
        // 8 beams every 45 degrees from -pi; robot heading pi/2 (the
        // beam at angle 0 points along +y).
        scan(
            &mut s,
            &full(8),
            Vec2::zeros(),
            FRAC_PI_2,
            [],
            &walls,
            &mut no_noise,
        );
        // Beam 4: +y, hits y = 3 at distance 3.
        assert!((s.ranges[4] - 3.0).abs() < 1e-12, "{:?}", s.ranges);
        // Beam 2: angle -pi/2 from +y = +x, hits x = 2 at 2.
        assert!((s.ranges[2] - 2.0).abs() < 1e-12);
        // Beam 3: 45 degrees between them; the line y = x meets x = 2 at
        // y = 2 < 3, so the side wall, at 2 sqrt 2.
        assert!((s.ranges[3] - 2.0 * 2f64.sqrt()).abs() < 1e-12);
        // Beams 0 (-y) and 6 (-x) see nothing: the segments end before.
        assert!(s.ranges[0].is_infinite() && s.ranges[6].is_infinite());
        // Beam 5 (up-left): y = 3 at x = -3, distance 3 sqrt 2.
        assert!((s.ranges[5] - 3.0 * 2f64.sqrt()).abs() < 1e-12);
    }

    #[test]
    fn the_nearest_surface_wins_and_far_ones_read_infinity() {
        let walls = [Segment {
            a: Vec2::new(5.0, -1.0),
            b: Vec2::new(5.0, 1.0),
        }];
        let mut cfg = full(1);
        cfg.fov = 0.1;
        let mut s = LaserScan::default();
        scan(
            &mut s,
            &cfg,
            Vec2::zeros(),
            0.0,
            [(Vec2::new(3.0, 0.0), 0.5)],
            &walls,
            &mut no_noise,
        );
        assert_eq!(s.ranges, vec![2.5]);
        cfg.range = 2.0;
        scan(
            &mut s,
            &cfg,
            Vec2::zeros(),
            0.0,
            [(Vec2::new(3.0, 0.0), 0.5)],
            &walls,
            &mut no_noise,
        );
        assert_eq!(s.ranges, vec![f64::INFINITY]);
    }

    #[test]
    fn the_beams_tested_per_surface_give_what_testing_every_beam_gives() {
        // Pseudo-random discs and walls around the origin; each scan equals
        // the brute force over every beam and surface.
        let mut x: u64 = 7;
        let mut next = || {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (x >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let discs: Vec<(Vec2, f64)> = (0..20)
            .map(|_| {
                (
                    Vec2::new(6.0 * next(), 6.0 * next()),
                    0.2 + 0.3 * next().abs(),
                )
            })
            .collect();
        let walls: Vec<Segment> = (0..20)
            .map(|_| Segment {
                a: Vec2::new(8.0 * next(), 8.0 * next()),
                b: Vec2::new(8.0 * next(), 8.0 * next()),
            })
            .collect();
        for (beams, fov, heading) in [(360, 2.0 * PI, 0.3), (91, 1.5, -2.9), (7, 3.0, 3.1)] {
            let cfg = LidarConfig {
                beams,
                fov,
                range: 7.0,
                noise: 0.0,
            };
            let mut s = LaserScan::default();
            let o = Vec2::new(0.1, -0.2);
            scan(
                &mut s,
                &cfg,
                o,
                heading,
                discs.iter().copied(),
                &walls,
                &mut no_noise,
            );
            let (a0, inc) = cfg.angles();
            for (k, r) in s.ranges.iter().enumerate() {
                let a = heading + a0 + inc * k as f64;
                let d = Vec2::new(a.cos(), a.sin());
                let brute = discs
                    .iter()
                    .filter_map(|(c, rr)| ray_disc(o, d, *c, *rr))
                    .chain(walls.iter().filter_map(|w| ray_segment(o, d, w)))
                    .fold(f64::INFINITY, f64::min);
                let brute = if brute > 7.0 { f64::INFINITY } else { brute };
                assert_eq!(*r, brute, "beams {beams}, beam {k}");
            }
        }
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

    #[test]
    fn noise_moves_hits_only_and_stays_within_the_range() {
        let mut cfg = full(4);
        cfg.noise = 0.1;
        let mut s = LaserScan::default();
        let mut calls = 0;
        let mut g = || {
            calls += 1;
            100.0
        };
        scan(
            &mut s,
            &cfg,
            Vec2::zeros(),
            0.0,
            [(Vec2::new(3.0, 0.0), 0.5)],
            &[],
            &mut g,
        );
        assert_eq!(calls, 1);
        assert_eq!(s.ranges[2], 10.0);
        assert!(s.ranges[0].is_infinite());
    }
}
