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
        name: "chung-1",
        summary: "potential field on relative positions (Chung et al. Strategy I, eq 3)",
    },
    PlannerInfo {
        name: "chung-2",
        summary: "potential field on relative positions and velocities (Chung et al. Strategy II, eq 4)",
    },
    PlannerInfo {
        name: "chung-3",
        summary: "Strategy II with the velocity term over distance cubed (Chung et al. Strategy III, eq 5)",
    },
    PlannerInfo {
        name: "vdf",
        summary: "virtual-distance potential field under acceleration and speed limits (Ko & Choi eqs 1-22)",
    },
    PlannerInfo {
        name: "khatib",
        summary: "classic potential field (Khatib 1986) as Ko & Choi's case 7 limit of vdf",
    },
    PlannerInfo {
        name: "hydro",
        summary: "guiding velocity of a sink-and-cylinder flow, circle or ellipse, binary or smooth anti-chasing (Sugiyama et al.)",
    },
    PlannerInfo {
        name: "orca",
        summary: "optimal reciprocal collision avoidance, as in RVO2 (van den Berg et al. 2011)",
    },
    PlannerInfo {
        name: "dwa",
        summary: "dynamic window approach for a holonomic disc (Fox, Burgard & Thrun 1997)",
    },
    PlannerInfo {
        name: "social-force",
        summary: "social force model: goal relaxation plus exponential repulsion (Helbing & Molnar 1995)",
    },
    PlannerInfo {
        name: "designated-path",
        summary: "subgoals on a designated path, via points in (x, y, t) at several speeds chosen by eq (1) (Yamada et al.)",
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
        "chung-1" => Box::new(crate::chung::Chung::from_params(
            crate::chung::Strategy::I,
            params,
        )?),
        "chung-2" => Box::new(crate::chung::Chung::from_params(
            crate::chung::Strategy::II,
            params,
        )?),
        "chung-3" => Box::new(crate::chung::Chung::from_params(
            crate::chung::Strategy::III,
            params,
        )?),
        "vdf" => Box::new(crate::vdf::Vdf::from_params(params)?),
        "khatib" => Box::new(crate::khatib::khatib_from_params(params)?),
        "hydro" => Box::new(crate::hydro::Hydro::from_params(params)?),
        "orca" => Box::new(crate::orca::Orca::from_params(params)?),
        "dwa" => Box::new(crate::dwa::Dwa::from_params(params)?),
        "social-force" => Box::new(crate::social_force::SocialForce::from_params(params)?),
        "designated-path" => Box::new(crate::designated_path::DesignatedPathPlanner::from_params(
            params,
        )?),
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
