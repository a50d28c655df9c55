//! What a dwa planner is: its parameters, read from a scenario's
//! `[robot.params]`, and the state a unicycle carries between ticks (the
//! module documentation of `dwa` says what each does).

use crate::{ParamError, ParamReader, Params};

/// What dwa avoids (its `obstacles` parameter).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Obstacles {
    /// The sensed bodies (at their sensed velocities) and the walls
    /// (default).
    #[default]
    Truth,
    /// The robot's laser scan alone: every return is a still point in the
    /// robot's frame; no body's state is used, and the walls only to tell
    /// a return that is not a wall (keeping right on meeting).
    Scan,
}

/// Dynamic window approach for a holonomic disc.
#[derive(Debug, Clone)]
pub struct Dwa {
    /// Grid points per axis over the dynamic window.
    pub samples: usize,
    /// Weight of the heading term (paper's alpha).
    pub w_heading: f64,
    /// Weight of the clearance term (paper's beta).
    pub w_clearance: f64,
    /// Weight of the speed term (paper's gamma).
    pub w_speed: f64,
    /// Look-ahead time at which clearance saturates, s.
    pub horizon: f64,
    /// Bodies and walls, or the laser scan.
    pub obstacles: Obstacles,
    /// A unicycle's safety distance, kept from everything as if its disc
    /// were that much larger; `None`: a quarter of its radius.
    pub padding: Option<f64>,
    /// A unicycle's recovery state.
    pub(super) recovery: Recovery,
    /// The walls' grid (true states), built at the first tick.
    pub(super) walls: super::walls::WallGrid,
    /// The others' turn rates (true states, unicycle), from their last
    /// velocities.
    pub(super) turns: super::brake::TurnRates,
}

impl Default for Dwa {
    fn default() -> Self {
        Self {
            samples: 11,
            w_heading: 2.0,
            w_clearance: 0.2,
            w_speed: 0.2,
            horizon: 3.0,
            obstacles: Obstacles::Truth,
            padding: None,
            recovery: Default::default(),
            walls: Default::default(),
            turns: Default::default(),
        }
    }
}

impl Dwa {
    /// Reads `samples`, `w_heading`, `w_clearance`, `w_speed`, `horizon`,
    /// `obstacles` (`truth` or `scan`) and `padding` (>= 0).
    pub fn from_params(params: &Params) -> Result<Self, ParamError> {
        let d = Self::default();
        let mut r = ParamReader::new("dwa", params);
        let samples = r.count("samples", d.samples, 2)?;
        let w_heading = r.non_negative("w_heading", d.w_heading)?;
        let w_clearance = r.non_negative("w_clearance", d.w_clearance)?;
        let w_speed = r.non_negative("w_speed", d.w_speed)?;
        let horizon = r.positive("horizon", d.horizon)?;
        let obstacles = match r.choice("obstacles", &["truth", "scan"], "truth")? {
            "scan" => Obstacles::Scan,
            _ => Obstacles::Truth,
        };
        let padding = match r.number("padding", f64::NAN)? {
            p if p.is_nan() => None,
            p if p >= 0.0 => Some(p),
            p => return Err(r.invalid("padding", format!("must be >= 0, got {p}"))),
        };
        r.finish()?;
        Ok(Self {
            samples,
            w_heading,
            w_clearance,
            w_speed,
            horizon,
            obstacles,
            padding,
            recovery: Default::default(),
            walls: Default::default(),
            turns: Default::default(),
        })
    }
}

/// A unicycle's way out of contact or a standstill (module documentation
/// of `dwa`, "Recovery").
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Recovery {
    /// Since when the robot, facing its goal, has stood still (NaN: not).
    pub(super) still_since: f64,
    /// Backing off: until when, at which (v, omega).
    pub(super) backing: Option<(f64, f64, f64)>,
    /// Where the robot last was, and when, half a radius from the place
    /// before (its progress; NaN time: not yet).
    pub(super) mark: (crate::Vec2, f64),
    /// Going round what blocks it: until when, and on which side (-1:
    /// turning right of it, +1: left).
    pub(super) detour: Option<(f64, f64)>,
    /// When the robot, from the scan, last met something in its way (NaN:
    /// never).
    pub(super) met: f64,
}

impl Default for Recovery {
    fn default() -> Self {
        Self {
            still_since: f64::NAN,
            backing: None,
            mark: (crate::Vec2::zeros(), f64::NAN),
            detour: None,
            met: f64::NAN,
        }
    }
}
