//! Your own planner driving one robot of a running world, as `mrsim agent`
//! drives one with a built-in planner: `my_agent RUN_ID ROBOT`.
use mrsim::{Command, LiveAgent, Observation, Planner};
use std::time::Duration;

/// Straight at the goal; slower the nearer another body is.
struct Cautious {
    /// Surface gap (m) below which it slows down.
    slow_within: f64,
}

impl Planner for Cautious {
    fn plan(&mut self, obs: &Observation) -> Command {
        let to_goal = obs.goal - obs.me.position;
        // Surface to surface: each body's true shape (disc, rectangle or
        // polygon at its heading) less this robot's radius.
        let gap = (obs.others.iter())
            .map(|o| o.distance_to(obs.me.position) - obs.me.radius)
            .fold(f64::INFINITY, f64::min);
        let (d, a) = (to_goal.norm(), obs.me.max_accel);
        let speed = obs.me.max_speed * (gap / self.slow_within).clamp(0.2, 1.0);
        // No faster than it can still stop at the goal.
        let speed = speed.min((2.0 * a * d).sqrt()).min(d / obs.dt);
        Command::Velocity(to_goal.try_normalize(1e-12).unwrap_or_default() * speed)
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let (Some(run), Some(robot)) = (args.next(), args.next()) else {
        eprintln!("usage: my_agent RUN_ID ROBOT");
        std::process::exit(2);
    };
    let agent = LiveAgent::join(&run, &robot, Duration::from_secs(60))?;
    let exit = agent.drive(&mut Cautious { slow_within: 1.0 })?;
    println!("{robot}: {exit:?}");
    Ok(())
}
