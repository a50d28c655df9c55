//! Validation, once: a scenario file and its overrides become a
//! [`Validated`] value (the resolved scenario, every planner built once to
//! check its parameters, and the world built from it) that the launcher, the
//! world and the in-process run take instead of checking again.

use crate::error::Invalid;
use mrsim_planners::{BuildError, EXTERNAL, ROS2, Registry};
use mrsim_scenario::{Loaded, Mode, Scenario};
use mrsim_world::World;
use std::path::PathBuf;
use std::sync::Arc;

/// Where a scenario comes from: a file (or the built-in demo) and the
/// overrides applied to it.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ScenarioSource {
    /// The scenario file; `None` for the built-in demo.
    pub path: Option<PathBuf>,
    /// Overrides the scenario's time mode.
    pub mode: Option<Mode>,
    /// Overrides as `KEY=VALUE`, KEY a dotted path (`world.dt`,
    /// `robot.r0.max_speed`, `robot.*.params.alpha`, `planner`); a bare word
    /// as VALUE is a string.
    pub set: Vec<String>,
}

impl ScenarioSource {
    /// The overrides as (key, TOML value) pairs.
    fn overrides(&self) -> Result<Vec<(String, String)>, Invalid> {
        let mut overrides = Vec::new();
        for s in &self.set {
            let (k, v) = s
                .split_once('=')
                .ok_or_else(|| Invalid(format!("--set {s}: expected KEY=VALUE")))?;
            let v = v.trim();
            // Bare words are strings: `--set planner=orca`.
            let looks_like_toml = v.parse::<f64>().is_ok()
                || v == "true"
                || v == "false"
                || v.starts_with(['[', '{', '"', '\'']);
            let v = if looks_like_toml {
                v.to_string()
            } else {
                format!("\"{v}\"")
            };
            overrides.push((k.trim().to_string(), v));
        }
        if let Some(mode) = self.mode {
            overrides.push(("world.mode".to_string(), format!("\"{}\"", mode_name(mode))));
        }
        Ok(overrides)
    }
}

/// The name of a time mode in a scenario file and on the command line.
pub fn mode_name(mode: Mode) -> &'static str {
    match mode {
        Mode::Lockstep => "lockstep",
        Mode::Realtime => "realtime",
    }
}

/// A scenario that passed every check: the file and its overrides, every
/// robot's planner and parameters (against the [`Registry`] it was
/// validated with; a robot whose planner is `external` builds nothing), and
/// whether the world can run it (the obstacles' motion models). Built once
/// per process; the world built while checking is kept for the run.
pub struct Validated {
    source: ScenarioSource,
    loaded: Loaded,
    world: World,
    registry: Arc<Registry>,
}

impl std::fmt::Debug for Validated {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Validated")
            .field("source", &self.source)
            .field("origin", &self.loaded.origin())
            .finish_non_exhaustive()
    }
}

impl Validated {
    /// Loads the scenario of `source` and checks it fully, against the
    /// built-in planners. A refusal names the file, line and key where it
    /// can.
    pub fn new(source: ScenarioSource) -> Result<Self, Invalid> {
        Self::with_registry(source, Arc::new(Registry::builtin()))
    }

    /// [`Self::new`], every robot's planner looked up in `registry` (the
    /// built-in planners and a program's own).
    pub fn with_registry(source: ScenarioSource, registry: Arc<Registry>) -> Result<Self, Invalid> {
        let overrides = source.overrides()?;
        let loaded = match &source.path {
            Some(path) => mrsim_scenario::load_with_overrides(path, &overrides),
            None if overrides.is_empty() => Ok(mrsim_scenario::demo()),
            None => {
                let demo = mrsim_scenario::demo();
                mrsim_scenario::parse_with_overrides(demo.source(), demo.origin(), &overrides)
            }
        }
        .map_err(|e| Invalid(e.to_string()))?;
        for r in &loaded.scenario.robots {
            if r.planner == EXTERNAL || r.planner == ROS2 {
                if r.planner == ROS2 && !mrsim_ros2::names::is_ros_token(&r.name) {
                    return Err(Invalid(format!(
                        "{}: robot `{}` has planner = \"ros2\": its name becomes its ROS 2 \
                         namespace (/{}/cmd_vel), so it must be a letter or `_` followed by \
                         letters, digits and `_`",
                        loaded.origin(),
                        r.name,
                        r.name
                    )));
                }
                continue;
            }
            let built = mrsim_agents::build_planner_in(&registry, r);
            if let Ok(p) = &built
                && p.needs_scan()
                && r.sensor.is_none()
            {
                let key = format!("robot.{}.params.obstacles", r.name);
                let why = format!(
                    "planner `{}` avoids what the laser scan shows (obstacles = \"scan\"), but \
                     the robot has no scanner: give it sensor = {{ kind = \"lidar\" }}",
                    r.planner
                );
                return Err(Invalid(loaded.error_at(&key, why).to_string()));
            }
            if let Err(e) = built {
                let key = match &e {
                    BuildError::Param(p) => format!("robot.{}.params.{}", r.name, p.key()),
                    BuildError::UnknownPlanner { .. } | BuildError::External => {
                        format!("robot.{}.planner", r.name)
                    }
                    BuildError::Other(_) => format!("robot.{}.params", r.name),
                };
                return Err(Invalid(loaded.error_at(&key, e.to_string()).to_string()));
            }
        }
        let scene = mrsim_agents::route::RouteScene::of(&loaded.scenario);
        for r in &loaded.scenario.robots {
            if r.route == mrsim_scenario::Route::Shortest
                && let Err(e) = scene.check(r)
            {
                let key = format!("robot.{}.goal", r.name);
                let why = format!(
                    "route = \"shortest\": the goal cannot be reached from the start [{}, {}]: {e}",
                    r.start[0], r.start[1]
                );
                return Err(Invalid(loaded.error_at(&key, why).to_string()));
            }
        }
        let world = match World::new(&loaded.scenario) {
            Ok(w) => w,
            Err(e) => {
                let key = match &e {
                    mrsim_world::WorldError::Motion { name, .. } => {
                        format!("obstacle.{name}.motion")
                    }
                };
                return Err(Invalid(loaded.error_at(&key, e.to_string()).to_string()));
            }
        };
        Ok(Self {
            source,
            loaded,
            world,
            registry,
        })
    }

    /// The planners the scenario was validated against.
    pub fn registry(&self) -> &Arc<Registry> {
        &self.registry
    }

    /// The robots whose planner is `external` (driven by the user's own
    /// program, which joins the run as their agent).
    pub fn external_robots(&self) -> Vec<&str> {
        self.robots_where(|planner| planner == EXTERNAL)
    }

    /// The robots whose planner is `ros2` (driven by a ROS 2 node through
    /// the ROS 2 agent, `mrsim ros2`, which `mrsim run` starts).
    pub fn ros2_robots(&self) -> Vec<&str> {
        self.robots_where(|planner| planner == ROS2)
    }

    /// The robots whose planner this program registered (not built in):
    /// only an in-process run can build them.
    pub fn robots_with_own_planners(&self) -> Vec<&str> {
        self.robots_where(|planner| self.registry.get(planner).is_some_and(|e| !e.is_builtin()))
    }

    fn robots_where(&self, f: impl Fn(&str) -> bool) -> Vec<&str> {
        self.scenario()
            .robots
            .iter()
            .filter(|r| f(&r.planner))
            .map(|r| r.name.as_str())
            .collect()
    }

    /// The resolved scenario (defaults applied, generated robots expanded).
    pub fn scenario(&self) -> &Scenario {
        &self.loaded.scenario
    }

    /// Where the scenario came from, as it names it in errors (the file, or
    /// the built-in demo).
    pub fn origin(&self) -> &str {
        self.loaded.origin()
    }

    /// The file and overrides it was loaded from.
    pub fn source(&self) -> &ScenarioSource {
        &self.source
    }

    /// The world built from the scenario, ready to run.
    pub fn into_world(self) -> (Scenario, World) {
        (self.loaded.scenario, self.world)
    }

    /// The same scenario with every robot replaying the planner calls
    /// `calls` gives it (by robot name; a robot without any replays none:
    /// it never answered), the world rebuilt for it (`mrsim rerun`).
    pub fn with_replay(
        self,
        calls: std::collections::BTreeMap<String, Vec<mrsim_scenario::timing::RecordedCall>>,
    ) -> Result<Self, Invalid> {
        self.with_replay_except(calls, &[])
    }

    /// [`Validated::with_replay`], but the robots named in `modelled` keep
    /// their timing model (their recorded calls are dropped).
    pub fn with_replay_except(
        mut self,
        mut calls: std::collections::BTreeMap<String, Vec<mrsim_scenario::timing::RecordedCall>>,
        modelled: &[String],
    ) -> Result<Self, Invalid> {
        for r in &mut self.loaded.scenario.robots {
            let recorded = calls.remove(&r.name).unwrap_or_default();
            if !modelled.contains(&r.name) {
                r.replay = Some(recorded);
            }
        }
        if let Some(name) = calls.keys().next() {
            return Err(Invalid(format!(
                "the recorded timing names robot `{name}`, which {} does not have",
                self.loaded.origin()
            )));
        }
        self.world = World::new(&self.loaded.scenario).map_err(|e| Invalid(e.to_string()))?;
        Ok(self)
    }

    /// Where the scenario came from and the scenario itself, without the
    /// world (for a process that starts the world elsewhere).
    pub fn into_scenario(self) -> (ScenarioSource, Scenario) {
        (self.source, self.loaded.scenario)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_demo_is_valid_and_its_overrides_are_applied() {
        let v = Validated::new(ScenarioSource {
            set: vec!["world.dt=0.05".into()],
            mode: Some(Mode::Lockstep),
            ..Default::default()
        })
        .expect("the demo with overrides");
        assert_eq!(v.scenario().world.dt, 0.05);
        assert_eq!(v.scenario().world.mode, Mode::Lockstep);
    }

    #[test]
    fn an_override_without_a_value_or_an_unknown_planner_is_refused() {
        let refused = |set: &str| {
            Validated::new(ScenarioSource {
                set: vec![set.into()],
                ..Default::default()
            })
            .expect_err(set)
            .to_string()
        };
        assert!(refused("world.dt").contains("expected KEY=VALUE"));
        assert!(refused("planner=nope").contains("nope"));
    }

    struct Still;
    impl mrsim_planners::Planner for Still {
        fn plan(&mut self, _obs: &mrsim_planners::Observation) -> mrsim_planners::Command {
            mrsim_planners::Command::Velocity(Default::default())
        }
    }

    #[test]
    fn every_robots_planner_is_checked_against_the_registry_and_external_builds_nothing() {
        let demo = |set: &str, registry: &Arc<Registry>| {
            Validated::with_registry(
                ScenarioSource {
                    set: vec![set.into()],
                    ..Default::default()
                },
                registry.clone(),
            )
        };
        let builtin = Arc::new(Registry::builtin());
        let mut own = Registry::builtin();
        own.register_simple("still", "stands", || Still)
            .expect("a new name");
        let own = Arc::new(own);
        let refused = demo("planner=still", &builtin).expect_err("unknown to the built-ins");
        assert!(refused.to_string().contains("still"), "{refused}");
        let v = demo("planner=still", &own).expect("registered");
        assert_eq!(
            v.robots_with_own_planners().len(),
            v.scenario().robots.len()
        );
        assert!(v.external_robots().is_empty());
        let v = demo("robot.r0.planner=external", &builtin).expect("external is valid");
        assert_eq!(v.external_robots(), ["r0"]);
        assert!(v.robots_with_own_planners().is_empty());
        let refused = demo("robot.r0.params.gain=1", &own).expect_err("an unknown param");
        assert!(refused.to_string().contains("gain"), "{refused}");
    }

    #[test]
    fn a_ros2_robot_builds_nothing_and_needs_a_name_ros_accepts_as_a_namespace() {
        let demo = |sets: &[&str]| {
            Validated::new(ScenarioSource {
                set: sets.iter().map(|s| s.to_string()).collect(),
                ..Default::default()
            })
        };
        let v = demo(&["robot.r0.planner=ros2"]).expect("ros2 is valid");
        assert_eq!(v.ros2_robots(), ["r0"]);
        assert!(v.external_robots().is_empty());
        let dir = std::env::temp_dir().join(format!("mrsim-ros2-name-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let file = dir.join("dash.toml");
        std::fs::write(
            &file,
            "name = \"dash\"\n[world]\ndt = 0.1\nduration = 1.0\n\n[[robot]]\n\
             name = \"r-0\"\nplanner = \"ros2\"\nstart = [0.0, 0.0]\ngoal = [1.0, 0.0]\n",
        )
        .expect("write the scene");
        let refused = Validated::new(ScenarioSource {
            path: Some(file),
            ..Default::default()
        })
        .expect_err("r-0 is no ROS name");
        let _ = std::fs::remove_dir_all(&dir);
        assert!(refused.to_string().contains("`r-0`"), "{refused}");
        assert!(refused.to_string().contains("namespace"), "{refused}");
    }
}
