//! Scripted obstacle motion models, evaluated by the world each substep.

use mrsim_scenario::Motion;

/// The moving state of one scripted obstacle.
#[derive(Debug, Clone)]
pub struct MotionState {
    model: Motion,
    /// Current position.
    pub position: [f64; 2],
    /// Current velocity.
    pub velocity: [f64; 2],
    /// Waypoints: index of the point being approached.
    next: usize,
    /// Waypoints: done (stays at the last point).
    done: bool,
}

/// Why a motion model cannot be run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MotionError {
    /// The model is in the scenario format but this world cannot run it yet.
    #[error("motion model `{0}` is not supported by this world yet")]
    Unsupported(&'static str),
}

impl MotionState {
    /// Starts `model` at `start`. Fails for models the world cannot run.
    pub fn new(model: &Motion, start: [f64; 2]) -> Result<Self, MotionError> {
        match model {
            Motion::Random { .. } => return Err(MotionError::Unsupported("random")),
            Motion::Intentional { .. } => return Err(MotionError::Unsupported("intentional")),
            _ => {}
        }
        let velocity = match model {
            Motion::ConstantVelocity { velocity } => *velocity,
            _ => [0.0, 0.0],
        };
        Ok(Self {
            model: model.clone(),
            position: start,
            velocity,
            next: 0,
            done: false,
        })
    }

    /// True if the obstacle never moves.
    pub fn is_static(&self) -> bool {
        matches!(self.model, Motion::Static)
    }

    /// Advances by `h` seconds.
    pub fn advance(&mut self, h: f64) {
        match &self.model {
            // Static: stays where it started.
            Motion::Static => {}
            // Constant velocity (Zhu & Loh 2.13-2.15): p += v h.
            Motion::ConstantVelocity { velocity } => {
                self.position[0] += velocity[0] * h;
                self.position[1] += velocity[1] * h;
            }
            // Waypoints: straight at `speed` to each point in turn.
            Motion::Waypoints {
                points,
                speed,
                r#loop,
            } => {
                let mut budget = speed * h;
                let start = self.position;
                while budget > 0.0 && !self.done && !points.is_empty() {
                    let target = points[self.next];
                    let d = [target[0] - self.position[0], target[1] - self.position[1]];
                    let dist = d[0].hypot(d[1]);
                    if dist <= budget {
                        self.position = target;
                        budget -= dist;
                        self.next += 1;
                        if self.next == points.len() {
                            if *r#loop {
                                self.next = 0;
                            } else {
                                self.done = true;
                            }
                        }
                        if dist == 0.0 && points.len() == 1 {
                            break;
                        }
                    } else {
                        self.position[0] += d[0] / dist * budget;
                        self.position[1] += d[1] / dist * budget;
                        budget = 0.0;
                    }
                }
                self.velocity = if h > 0.0 {
                    [
                        (self.position[0] - start[0]) / h,
                        (self.position[1] - start[1]) / h,
                    ]
                } else {
                    [0.0, 0.0]
                };
            }
            Motion::Random { .. } | Motion::Intentional { .. } => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constant_velocity_keeps_speed() {
        let mut m = MotionState::new(
            &Motion::ConstantVelocity {
                velocity: [1.0, -2.0],
            },
            [0.0, 0.0],
        )
        .unwrap();
        for _ in 0..100 {
            m.advance(0.01);
        }
        assert!((m.position[0] - 1.0).abs() < 1e-9 && (m.position[1] + 2.0).abs() < 1e-9);
    }

    #[test]
    fn waypoints_turn_corners_and_stop_at_the_end() {
        let model = Motion::Waypoints {
            points: vec![[1.0, 0.0], [1.0, 1.0]],
            speed: 1.0,
            r#loop: false,
        };
        let mut m = MotionState::new(&model, [0.0, 0.0]).unwrap();
        m.advance(1.5);
        assert!((m.position[0] - 1.0).abs() < 1e-9 && (m.position[1] - 0.5).abs() < 1e-9);
        m.advance(5.0);
        assert_eq!(m.position, [1.0, 1.0]);
        m.advance(1.0);
        assert_eq!(m.velocity, [0.0, 0.0]);
    }
}
