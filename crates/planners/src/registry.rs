//! The planners by scenario name: one table, [`PLANNERS`], from which both
//! the listing (`mrsim --help`, the README, error messages) and [`build`]
//! come, so a planner is added or renamed in one place.

use crate::{ParamError, Params, Planner};

/// A planner's constructor: reads the robot's params (each planner's
/// `from_params` documents its keys and defaults) and refuses unknown or
/// invalid ones.
pub type FromParams = fn(&Params) -> Result<Box<dyn Planner>, ParamError>;

/// One planner of the table: its scenario name, what it is, and how it is
/// built.
#[derive(Debug, Clone, Copy)]
pub struct PlannerInfo {
    /// Name used in scenario files (`planner = "..."`).
    pub name: &'static str,
    /// One line: what it does and where it comes from.
    pub summary: &'static str,
    /// Builds the planner from a robot's params.
    pub from_params: FromParams,
}

/// Boxes a planner built by its own `from_params`.
fn boxed<P: Planner + 'static>(
    planner: Result<P, ParamError>,
) -> Result<Box<dyn Planner>, ParamError> {
    Ok(Box::new(planner?))
}

/// Every planner [`build`] knows, in the order the README lists them.
pub const PLANNERS: &[PlannerInfo] = &[
    PlannerInfo {
        name: "homing",
        summary: "attraction to the goal with velocity damping, no avoidance (Chung et al. eq 2)",
        from_params: |p| boxed(crate::homing::Homing::from_params(p)),
    },
    PlannerInfo {
        name: "chung-1",
        summary: "potential field on relative positions (Chung et al. Strategy I, eq 3)",
        from_params: |p| {
            boxed(crate::chung::Chung::from_params(
                crate::chung::Strategy::I,
                p,
            ))
        },
    },
    PlannerInfo {
        name: "chung-2",
        summary: "potential field on relative positions and velocities (Chung et al. Strategy II, eq 4)",
        from_params: |p| {
            boxed(crate::chung::Chung::from_params(
                crate::chung::Strategy::II,
                p,
            ))
        },
    },
    PlannerInfo {
        name: "chung-3",
        summary: "Strategy II with the velocity term over distance cubed (Chung et al. Strategy III, eq 5)",
        from_params: |p| {
            boxed(crate::chung::Chung::from_params(
                crate::chung::Strategy::III,
                p,
            ))
        },
    },
    PlannerInfo {
        name: "vdf",
        summary: "virtual-distance potential field under acceleration and speed limits (Ko & Choi eqs 1-22)",
        from_params: |p| boxed(crate::vdf::Vdf::from_params(p)),
    },
    PlannerInfo {
        name: "khatib",
        summary: "classic potential field (Khatib 1986) as Ko & Choi's case 7 limit of vdf",
        from_params: |p| boxed(crate::khatib::khatib_from_params(p)),
    },
    PlannerInfo {
        name: "hydro",
        summary: "guiding velocity of a sink-and-cylinder flow, circle or ellipse, binary or smooth anti-chasing (Sugiyama et al.)",
        from_params: |p| boxed(crate::hydro::Hydro::from_params(p)),
    },
    PlannerInfo {
        name: "orca",
        summary: "optimal reciprocal collision avoidance, as in RVO2 (van den Berg et al. 2011)",
        from_params: |p| boxed(crate::orca::Orca::from_params(p)),
    },
    PlannerInfo {
        name: "dwa",
        summary: "dynamic window approach for a holonomic disc (Fox, Burgard & Thrun 1997)",
        from_params: |p| boxed(crate::dwa::Dwa::from_params(p)),
    },
    PlannerInfo {
        name: "social-force",
        summary: "social force model: goal relaxation plus exponential repulsion (Helbing & Molnar 1995)",
        from_params: |p| boxed(crate::social_force::SocialForce::from_params(p)),
    },
    PlannerInfo {
        name: "designated-path",
        summary: "subgoals on a designated path, via points in (x, y, t) at several speeds chosen by eq (1) (Yamada et al.)",
        from_params: |p| {
            boxed(crate::designated_path::DesignatedPathPlanner::from_params(
                p,
            ))
        },
    },
    PlannerInfo {
        name: "trajectory-guided",
        summary: "first collision-free candidate trajectory against predicted obstacles (Zhu & Loh 3.3b)",
        from_params: |p| boxed(crate::trajectory_guided::TrajectoryGuided::from_params(p)),
    },
    PlannerInfo {
        name: "free-space",
        summary: "search for a wide-enough free path through (x, y, t) occupancy frames (Zhu & Loh 3.3a)",
        from_params: |p| boxed(crate::free_space::FreeSpace::from_params(p)),
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

/// Builds the planner called `name` with the robot's `params`: the entry of
/// [`PLANNERS`] of that name.
pub fn build(name: &str, params: &Params) -> Result<Box<dyn Planner>, BuildError> {
    let Some(info) = PLANNERS.iter().find(|p| p.name == name) else {
        return Err(BuildError::UnknownPlanner {
            name: name.to_string(),
            known: PLANNERS
                .iter()
                .map(|p| p.name)
                .collect::<Vec<_>>()
                .join(", "),
        });
    };
    Ok((info.from_params)(params)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_listed_planner_builds_with_default_parameters() {
        for info in PLANNERS {
            assert!(build(info.name, &Params::new()).is_ok(), "{}", info.name);
            assert!((info.from_params)(&Params::new()).is_ok(), "{}", info.name);
        }
    }

    #[test]
    fn no_two_planners_share_a_name() {
        let mut names: Vec<&str> = PLANNERS.iter().map(|p| p.name).collect();
        names.sort_unstable();
        let before = names.len();
        names.dedup();
        assert_eq!(names.len(), before, "{names:?}");
    }

    #[test]
    fn every_planner_refuses_a_parameter_it_does_not_know() {
        let mut params = Params::new();
        params.insert("no_such_key".into(), crate::ParamValue::Number(1.0));
        for info in PLANNERS {
            let err = build(info.name, &params).err().expect(info.name);
            assert!(
                matches!(&err, BuildError::Param(p) if p.key() == "no_such_key"),
                "{}: {err}",
                info.name
            );
        }
    }

    #[test]
    fn unknown_planner_names_the_known_ones() {
        let err = build("teleport", &Params::new()).err().expect("must fail");
        assert!(err.to_string().contains("homing"), "{err}");
    }
}
