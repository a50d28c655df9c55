//! ORCA's linear programs (van den Berg et al. 2011, section 5.1; RVO2's
//! `Agent.cc`: `linearProgram1`, `linearProgram2`, `linearProgram3`).
//!
//! Every constraint is a directed [`Line`] whose left side is admissible.
//! [`linear_program2`] finds the point of the speed disc inside every
//! half-plane closest to the preferred velocity, adding one line at a time
//! and solving the 1-D program on the line that cuts the current optimum
//! off ([`linear_program1`]). When the half-planes leave nothing,
//! [`linear_program3`] keeps the static obstacles' lines hard and minimises
//! the largest violation of the others (the paper's 3-D program).

use crate::Vec2;

/// RVO2's tolerance for parallel lines and covered obstacles.
pub(super) const RVO_EPSILON: f64 = 1e-5;

/// 2-D cross product (RVO2's `det`).
pub(super) fn det(a: Vec2, b: Vec2) -> f64 {
    a.x * b.y - a.y * b.x
}

/// `v / |v|`, or `fallback` when `v` is (nearly) zero.
pub(super) fn normalize_or(v: Vec2, fallback: Vec2) -> Vec2 {
    let n = v.norm();
    if n > f64::EPSILON { v / n } else { fallback }
}

/// A directed line; the admissible half-plane lies on its left.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Line {
    /// A point on the line.
    pub(super) point: Vec2,
    /// Unit direction; the admissible side is to its left.
    pub(super) direction: Vec2,
}

impl Line {
    /// How far `v` lies on the forbidden (right) side; negative inside.
    pub(super) fn violation(&self, v: Vec2) -> f64 {
        det(self.direction, self.point - v)
    }
}

/// Solves the 1-D program on line `line_no` under the earlier lines and the
/// speed disc of `radius` (RVO2's `linearProgram1`). `None` when the
/// constraints leave nothing of the line.
pub(super) fn linear_program1(
    lines: &[Line],
    line_no: usize,
    radius: f64,
    opt: Vec2,
    direction_opt: bool,
) -> Option<Vec2> {
    let line = lines[line_no];
    let dot = line.point.dot(&line.direction);
    let discriminant = dot * dot + radius * radius - line.point.norm_squared();
    if discriminant < 0.0 {
        // Max speed circle fully invalidates line `line_no`.
        return None;
    }
    let sqrt_disc = discriminant.sqrt();
    let mut t_left = -dot - sqrt_disc;
    let mut t_right = -dot + sqrt_disc;
    for other in &lines[..line_no] {
        let denominator = det(line.direction, other.direction);
        let numerator = det(other.direction, line.point - other.point);
        if denominator.abs() <= RVO_EPSILON {
            // Lines `line_no` and `other` are (almost) parallel.
            if numerator < 0.0 {
                return None;
            }
            continue;
        }
        let t = numerator / denominator;
        if denominator >= 0.0 {
            // Line `other` bounds line `line_no` on the right.
            t_right = t_right.min(t);
        } else {
            // Line `other` bounds line `line_no` on the left.
            t_left = t_left.max(t);
        }
        if t_left > t_right {
            return None;
        }
    }
    let t = if direction_opt {
        // Optimise direction: take the extreme along `opt`.
        if opt.dot(&line.direction) > 0.0 {
            t_right
        } else {
            t_left
        }
    } else {
        // Optimise closest point.
        line.direction
            .dot(&(opt - line.point))
            .clamp(t_left, t_right)
    };
    Some(line.point + line.direction * t)
}

/// The point of the disc of `radius` left of every line that is closest to
/// `opt` (or furthest along the unit `opt` when `direction_opt`), added one
/// line at a time (RVO2's `linearProgram2`). Returns `lines.len()` on
/// success, else the index of the line that made it infeasible, `result`
/// being the optimum of the lines before it.
pub(super) fn linear_program2(
    lines: &[Line],
    radius: f64,
    opt: Vec2,
    direction_opt: bool,
    result: &mut Vec2,
) -> usize {
    *result = if direction_opt {
        // Optimise direction (`opt` is a unit vector here).
        opt * radius
    } else if opt.norm_squared() > radius * radius {
        // Optimise closest point, outside the circle.
        opt.normalize() * radius
    } else {
        // Optimise closest point, inside the circle.
        opt
    };
    for i in 0..lines.len() {
        if lines[i].violation(*result) > 0.0 {
            // The result breaks constraint i: the new optimum is on line i.
            match linear_program1(lines, i, radius, opt, direction_opt) {
                Some(r) => *result = r,
                None => return i,
            }
        }
    }
    lines.len()
}

/// When the 2-D program is infeasible from line `begin_line` on: keeps the
/// first `num_obst_lines` (static obstacles) hard and minimises the largest
/// violation of the other lines, by a 2-D program in the space of the
/// bisectors for each line that is violated more than the current optimum
/// (RVO2's `linearProgram3`, the paper's 3-D program).
pub(super) fn linear_program3(
    lines: &[Line],
    num_obst_lines: usize,
    begin_line: usize,
    radius: f64,
    result: &mut Vec2,
    proj_lines: &mut Vec<Line>,
) {
    let mut distance = 0.0;
    for i in begin_line..lines.len() {
        if lines[i].violation(*result) <= distance {
            continue;
        }
        // The result breaks line i by more than the current optimum.
        proj_lines.clear();
        proj_lines.extend_from_slice(&lines[..num_obst_lines]);
        for j in num_obst_lines..i {
            let determinant = det(lines[i].direction, lines[j].direction);
            let point = if determinant.abs() <= RVO_EPSILON {
                // Lines i and j are parallel.
                if lines[i].direction.dot(&lines[j].direction) > 0.0 {
                    // Same direction: j adds nothing.
                    continue;
                }
                // Opposite directions: the bisector is half way.
                (lines[i].point + lines[j].point) * 0.5
            } else {
                lines[i].point
                    + lines[i].direction
                        * (det(lines[j].direction, lines[i].point - lines[j].point) / determinant)
            };
            proj_lines.push(Line {
                point,
                direction: (lines[j].direction - lines[i].direction).normalize(),
            });
        }
        let previous = *result;
        let away = Vec2::new(-lines[i].direction.y, lines[i].direction.x);
        if linear_program2(proj_lines, radius, away, true, result) < proj_lines.len() {
            // In principle impossible (the result is feasible by
            // construction); only rounding gets here: keep the last result.
            *result = previous;
        }
        distance = lines[i].violation(*result);
    }
}
