//! Your own planner run in this process, headless, beside the built-in ones:
//! robot g00 of the jittered crossing drives straight at its goal (and
//! waits while another body is close ahead), the other seven run ORCA.
//! `in_process [SCENARIO]`, from the repository's root.
use mrsim::{Command, InProcess, Observation, Planner, Registry, ScenarioSource};
use std::path::PathBuf;
use std::sync::Arc;

/// Straight at the goal, as fast as it can still stop there; it stands
/// while another body is within `wait_within` (m, surface to surface)
/// ahead of it.
struct Polite {
    wait_within: f64,
}

impl Planner for Polite {
    fn plan(&mut self, obs: &Observation) -> Command {
        let to_goal = obs.goal - obs.me.position;
        let d = to_goal.norm();
        let heading = to_goal.try_normalize(1e-12).unwrap_or_default();
        let blocked = obs.others.iter().any(|o| {
            let rel = o.position - obs.me.position;
            let gap = rel.norm() - o.radius - obs.me.radius;
            gap < self.wait_within && rel.dot(&heading) > 0.0
        });
        if blocked {
            return Command::Velocity(Default::default());
        }
        let speed = (obs.me.max_speed)
            .min((2.0 * obs.me.max_accel * d).sqrt())
            .min(d / obs.dt);
        Command::Velocity(heading * speed)
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let scenario = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "scenarios/crossing-jitter.toml".to_string());
    let mut registry = Registry::builtin();
    registry.register_simple("polite", "straight at the goal, waits for others", || {
        Polite { wait_within: 0.5 }
    })?;
    let run = mrsim::run_in_process(&InProcess {
        scenario: ScenarioSource {
            path: Some(PathBuf::from(scenario)),
            set: vec!["planner=orca".into(), "robot.g00.planner=polite".into()],
            ..Default::default()
        },
        registry: Arc::new(registry),
        out: None,
        render: true,
        plan_timeout: None,
    })?;
    let m = &run.metrics;
    let g00 = &m.robots["g00"];
    println!("g00 (polite) reached its goal: {}", g00.reached_goal);
    println!(
        "success {:.0}%, collisions {}",
        100.0 * m.success_rate,
        m.collisions_total
    );
    println!("run folder: {}", run.dir.display());
    Ok(())
}
