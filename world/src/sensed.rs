//! How many bodies a robot senses in the world's true state: the `sensed`
//! of a `per-body` compute model when the world decides a robot's timing
//! (lockstep under `[world.cpus]`). The rule is the agents' observation's
//! (`mrsim_agents::observe`): every other body within `sensing_range`,
//! surface to surface, and within `field_of_view_deg` centred on the
//! heading (a unicycle's or a car's body heading; else the direction of its velocity,
//! or towards its goal at rest). Unlike the agent's, it counts true
//! positions: no position noise, no observation delay.

use mrsim_proto::BodyState;
use mrsim_scenario::RobotSpec;

/// The bodies of `states` robot `me` (spec `spec`) senses.
pub fn count(states: &[BodyState], me: usize, spec: &RobotSpec) -> usize {
    let Some(s) = states.get(me) else {
        return 0;
    };
    let (px, py) = (s.position[0], s.position[1]);
    let (vx, vy) = (s.velocity[0], s.velocity[1]);
    let heading = if spec.turns() {
        (s.heading.cos(), s.heading.sin())
    } else if vx.hypot(vy) > 1e-9 {
        let n = vx.hypot(vy);
        (vx / n, vy / n)
    } else {
        let (gx, gy) = (spec.goal[0] - px, spec.goal[1] - py);
        let n = gx.hypot(gy);
        if n > 1e-12 {
            (gx / n, gy / n)
        } else {
            (1.0, 0.0)
        }
    };
    let cos_half =
        (spec.field_of_view_deg < 360.0).then(|| (spec.field_of_view_deg / 2.0).to_radians().cos());
    states
        .iter()
        .filter(|b| b.id as usize != me)
        .filter(|b| {
            let (dx, dy) = (b.position[0] - px, b.position[1] - py);
            let dist = dx.hypot(dy);
            if dist - b.radius - spec.radius > spec.sensing_range {
                return false;
            }
            match cos_half {
                Some(c) if dist > 1e-12 => (dx * heading.0 + dy * heading.1) / dist >= c,
                _ => true,
            }
        })
        .count()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn body(id: u32, x: f64, y: f64) -> BodyState {
        BodyState {
            id,
            position: [x, y],
            radius: 0.5,
            ..BodyState::default()
        }
    }

    #[test]
    fn a_robot_senses_the_bodies_within_its_range_and_field_of_view() {
        let scenario = mrsim_scenario::parse(
            "[[robot]]\nname = \"a\"\nstart = [0, 0]\ngoal = [10, 0]\nradius = 0.5\n\
             sensing_range = 3.0\nfield_of_view_deg = 90\n",
            "t.toml",
        )
        .unwrap()
        .scenario;
        let spec = &scenario.robots[0];
        // At rest the heading is towards the goal (+x).
        let states = [
            body(0, 0.0, 0.0),
            body(1, 3.5, 0.0),  // 3.5 - 1 = 2.5 within 3, ahead
            body(2, 4.5, 0.0),  // 3.5 beyond 3
            body(3, -2.0, 0.0), // behind
            body(4, 2.0, 1.0),  // 26.6 degrees off the heading, within 45
            body(5, 1.0, 2.0),  // 63 degrees off
        ];
        assert_eq!(count(&states, 0, spec), 2);
    }
}
