//! The planners by scenario name: one table of the built-in ones,
//! [`PLANNERS`], from which both the listing (`mrsim planners`, the guide,
//! error messages) and [`build`] come, so a planner is added or renamed in
//! one place; and a [`Registry`]: the built-in planners, the name
//! [`EXTERNAL`], and planners a program registers under names of its own
//! (what an in-process run with a user's planners builds from).

use crate::{ParamError, ParamReader, Params, Planner};
use std::sync::Arc;

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

/// Every planner [`build`] knows, in the order the guide (docs/planners.md) lists them.
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

/// The planner name of a robot that mrsim does not drive: no agent is
/// started for it, and the world waits for the user's own program to join
/// as its agent (`mrsim_agents::LiveAgent`).
pub const EXTERNAL: &str = "external";

/// The planner name of a robot driven by a ROS 2 node over rmw_zenoh: like
/// [`EXTERNAL`] mrsim builds no planner for it; `mrsim run` starts the ROS 2
/// agent (`mrsim ros2`), which joins as the robot and relays `cmd_vel` in
/// and odometry, scans, tf, the clock and the map out.
pub const ROS2: &str = "ros2";

/// What [`ROS2`] means, in listings.
const ROS2_SUMMARY: &str = "driven by a ROS 2 node over rmw_zenoh: cmd_vel in; odom, scan, tf, clock, map out (mrsim ros2)";

/// What [`EXTERNAL`] means, in listings.
const EXTERNAL_SUMMARY: &str =
    "driven by your own program, which joins the run as the robot's agent (mrsim::LiveAgent)";

/// A registered planner's constructor: the robot's params in, the planner
/// (or why not) out. It may be called from any thread, once per robot
/// (and once more per robot when the scenario is validated).
pub type Factory = dyn Fn(&Params) -> Result<Box<dyn Planner>, BuildError> + Send + Sync;

/// Planners by name: the built-in ones ([`PLANNERS`]), [`EXTERNAL`], and
/// any a program registers (in-process runs only: an agent process knows
/// the built-in ones alone). Cheap to clone (the factories are shared).
///
/// ```
/// use mrsim_planners::{Command, Observation, Planner, Registry};
///
/// struct Still;
/// impl Planner for Still {
///     fn plan(&mut self, _obs: &Observation) -> Command {
///         Command::Velocity(Default::default())
///     }
/// }
///
/// let mut registry = Registry::builtin();
/// registry
///     .register_simple("still", "stands still", || Still)
///     .expect("a new name");
/// assert!(registry.build("still", &Default::default()).is_ok());
/// assert!(registry.get("orca").is_some());
/// assert!(registry.register_simple("orca", "", || Still).is_err());
/// ```
#[derive(Clone)]
pub struct Registry {
    entries: Vec<Entry>,
}

/// One planner of a [`Registry`].
#[derive(Clone)]
pub struct Entry {
    name: String,
    summary: String,
    source: Source,
}

/// Where an entry's planners come from.
#[derive(Clone)]
enum Source {
    Builtin(FromParams),
    External,
    User(Arc<Factory>),
}

impl Entry {
    /// The name scenarios use (`planner = "..."`).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// One line: what it is.
    pub fn summary(&self) -> &str {
        &self.summary
    }

    /// True for a planner every mrsim process knows (a built-in one, or
    /// [`EXTERNAL`]); false for one registered by this program, which only
    /// an in-process run can use.
    pub fn is_builtin(&self) -> bool {
        !matches!(self.source, Source::User(_))
    }

    /// True for [`EXTERNAL`]: nothing is built, the user's program drives.
    pub fn is_external(&self) -> bool {
        matches!(self.source, Source::External)
    }
}

/// Why a planner could not be registered.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum RegisterError {
    /// The name is taken (by a built-in planner, `external`, or an earlier
    /// registration).
    #[error("a planner named `{0}` is already registered")]
    Taken(String),
    /// The name is empty or holds whitespace, quotes or control characters.
    #[error(
        "`{0}` cannot be a planner name (non-empty, no whitespace, quotes or control characters)"
    )]
    BadName(String),
}

impl Default for Registry {
    fn default() -> Self {
        Self::builtin()
    }
}

impl std::fmt::Debug for Registry {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list()
            .entries(self.entries.iter().map(|e| &e.name))
            .finish()
    }
}

impl std::fmt::Debug for Entry {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Entry")
            .field("name", &self.name)
            .field("builtin", &self.is_builtin())
            .finish_non_exhaustive()
    }
}

impl Registry {
    /// The built-in planners ([`PLANNERS`], in their order), then
    /// [`EXTERNAL`].
    pub fn builtin() -> Self {
        let mut entries: Vec<Entry> = PLANNERS
            .iter()
            .map(|p| Entry {
                name: p.name.to_string(),
                summary: p.summary.to_string(),
                source: Source::Builtin(p.from_params),
            })
            .collect();
        entries.push(Entry {
            name: EXTERNAL.to_string(),
            summary: EXTERNAL_SUMMARY.to_string(),
            source: Source::External,
        });
        entries.push(Entry {
            name: ROS2.to_string(),
            summary: ROS2_SUMMARY.to_string(),
            source: Source::External,
        });
        Self { entries }
    }

    /// Registers `factory` under `name`, with a one-line `summary`. The
    /// factory reads the robot's params (refusing unknown ones, as the
    /// built-in planners do: [`ParamReader`] helps).
    pub fn register<F>(
        &mut self,
        name: &str,
        summary: &str,
        factory: F,
    ) -> Result<&mut Self, RegisterError>
    where
        F: Fn(&Params) -> Result<Box<dyn Planner>, BuildError> + Send + Sync + 'static,
    {
        let bad = name.is_empty()
            || name
                .chars()
                .any(|c| c.is_whitespace() || c.is_control() || c == '"' || c == '\'');
        if bad {
            return Err(RegisterError::BadName(name.to_string()));
        }
        if self.get(name).is_some() {
            return Err(RegisterError::Taken(name.to_string()));
        }
        self.entries.push(Entry {
            name: name.to_string(),
            summary: summary.to_string(),
            source: Source::User(Arc::new(factory)),
        });
        Ok(self)
    }

    /// Registers a planner without parameters: `make` builds one per
    /// robot, and a robot that gives it any parameter is refused.
    pub fn register_simple<P, M>(
        &mut self,
        name: &str,
        summary: &str,
        make: M,
    ) -> Result<&mut Self, RegisterError>
    where
        P: Planner + 'static,
        M: Fn() -> P + Send + Sync + 'static,
    {
        let owned = name.to_string();
        self.register(name, summary, move |params| {
            ParamReader::new(&owned, params).finish()?;
            Ok(Box::new(make()))
        })
    }

    /// The entry called `name`.
    pub fn get(&self, name: &str) -> Option<&Entry> {
        self.entries.iter().find(|e| e.name == name)
    }

    /// Every entry: the built-in planners, [`EXTERNAL`], then the
    /// registered ones in the order they were registered.
    pub fn entries(&self) -> &[Entry] {
        &self.entries
    }

    /// Builds the planner called `name` with a robot's `params`.
    pub fn build(&self, name: &str, params: &Params) -> Result<Box<dyn Planner>, BuildError> {
        let Some(entry) = self.get(name) else {
            return Err(BuildError::UnknownPlanner {
                name: name.to_string(),
                known: self
                    .entries
                    .iter()
                    .map(|e| e.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
            });
        };
        match &entry.source {
            Source::Builtin(from_params) => Ok(from_params(params)?),
            Source::External => Err(BuildError::External),
            Source::User(factory) => factory(params),
        }
    }
}

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
    /// The robot's planner is [`EXTERNAL`]: mrsim builds nothing for it,
    /// the user's own program drives it.
    #[error(
        "planner `external` is not built by mrsim: the robot is driven by your own program, \
         which joins the run as its agent (mrsim::LiveAgent)"
    )]
    External,
    /// A registered planner's factory refused (its own message).
    #[error("{0}")]
    Other(String),
}

/// Builds the planner called `name` with the robot's `params`: the entry of
/// [`PLANNERS`] of that name ([`EXTERNAL`] builds nothing).
pub fn build(name: &str, params: &Params) -> Result<Box<dyn Planner>, BuildError> {
    let Some(info) = PLANNERS.iter().find(|p| p.name == name) else {
        if name == EXTERNAL || name == ROS2 {
            return Err(BuildError::External);
        }
        return Err(BuildError::UnknownPlanner {
            name: name.to_string(),
            known: PLANNERS
                .iter()
                .map(|p| p.name)
                .chain([EXTERNAL, ROS2])
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

    struct Still;
    impl Planner for Still {
        fn plan(&mut self, _obs: &crate::Observation) -> crate::Command {
            crate::Command::Velocity(crate::Vec2::zeros())
        }
    }

    #[test]
    fn a_registered_planner_is_built_by_name_and_listed_after_the_builtin_ones() {
        let mut r = Registry::builtin();
        r.register_simple("still", "stands", || Still).expect("new");
        assert!(r.build("still", &Params::new()).is_ok());
        let names: Vec<&str> = r.entries().iter().map(Entry::name).collect();
        assert_eq!(names.len(), PLANNERS.len() + 3);
        assert_eq!(names[names.len() - 3..], [EXTERNAL, ROS2, "still"]);
        assert!(!r.get("still").expect("still").is_builtin());
        assert!(r.get("orca").expect("orca").is_builtin());
        let err = r.build("nope", &Params::new()).err().expect("unknown");
        assert!(err.to_string().contains("still"), "{err}");
    }

    #[test]
    fn a_taken_or_malformed_name_is_refused() {
        let mut r = Registry::builtin();
        for name in ["homing", EXTERNAL] {
            assert_eq!(
                r.register_simple(name, "", || Still).err(),
                Some(RegisterError::Taken(name.into()))
            );
        }
        r.register_simple("mine", "", || Still).expect("new");
        assert!(matches!(
            r.register_simple("mine", "", || Still),
            Err(RegisterError::Taken(_))
        ));
        for bad in ["", "my planner", "a\"b"] {
            assert!(matches!(
                r.register_simple(bad, "", || Still),
                Err(RegisterError::BadName(_))
            ));
        }
    }

    #[test]
    fn a_simple_planner_refuses_any_parameter_and_external_builds_nothing() {
        let mut r = Registry::builtin();
        r.register_simple("still", "", || Still).expect("new");
        let mut params = Params::new();
        params.insert("gain".into(), crate::ParamValue::Number(1.0));
        let err = r.build("still", &params).err().expect("refused");
        assert!(
            matches!(&err, BuildError::Param(p) if p.key() == "gain"),
            "{err}"
        );
        assert_eq!(
            r.build(EXTERNAL, &Params::new()).err(),
            Some(BuildError::External)
        );
        assert_eq!(
            build(EXTERNAL, &Params::new()).err(),
            Some(BuildError::External)
        );
    }

    #[test]
    fn unknown_planner_names_the_known_ones() {
        let err = build("teleport", &Params::new()).err().expect("must fail");
        assert!(err.to_string().contains("homing"), "{err}");
    }
}
