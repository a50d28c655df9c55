//! The planners by scenario name.

use crate::{ParamError, Params, Planner};

/// What a planner is, for `--help`, the README and error messages.
#[derive(Debug, Clone, Copy)]
pub struct PlannerInfo {
    /// Name used in scenario files (`planner = "..."`).
    pub name: &'static str,
    /// One line: what it does and where it comes from.
    pub summary: &'static str,
}

/// Every planner [`build`] knows, in the order the README lists them.
pub const PLANNERS: &[PlannerInfo] = &[
    PlannerInfo {
        name: "homing",
        summary: "attraction to the goal with velocity damping, no avoidance (Chung et al. eq 2)",
    },
    PlannerInfo {
        name: "trajectory-guided",
        summary: "first collision-free candidate trajectory against predicted obstacles (Zhu & Loh 3.3b)",
    },
    PlannerInfo {
        name: "free-space",
        summary: "search for a wide-enough free path through (x, y, t) occupancy frames (Zhu & Loh 3.3a)",
    },
];

/// Why a planner could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BuildError {
    /// No planner has that name.
    #[error("unknown planner `{name}` (known: {known})")]
    UnknownPlanner {
        /// The name asked for.
        name: String,
        /// Comma-separated list of the known names.
        known: String,
    },
    /// The planner refused its parameters.
    #[error(transparent)]
    Param(#[from] ParamError),
}

/// Builds the planner called `name` with the robot's `params`.
pub fn build(name: &str, params: &Params) -> Result<Box<dyn Planner>, BuildError> {
    Ok(match name {
        "homing" => Box::new(crate::homing::Homing::from_params(params)?),
        "trajectory-guided" => Box::new(crate::trajectory_guided::TrajectoryGuided::from_params(
            params,
        )?),
        "free-space" => Box::new(crate::free_space::FreeSpace::from_params(params)?),
        _ => {
            return Err(BuildError::UnknownPlanner {
                name: name.to_string(),
                known: PLANNERS
                    .iter()
                    .map(|p| p.name)
                    .collect::<Vec<_>>()
                    .join(", "),
            });
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_listed_planner_builds_with_default_parameters() {
        for info in PLANNERS {
            assert!(build(info.name, &Params::new()).is_ok(), "{}", info.name);
        }
    }

    #[test]
    fn unknown_planner_names_the_known_ones() {
        let err = build("teleport", &Params::new()).err().expect("must fail");
        assert!(err.to_string().contains("homing"), "{err}");
    }
}
