//! `mrsim`: parse the command line, run the subcommand, exit with its status.
use clap::Parser;
use cli::{Cli, Command};

mod agent;
mod bench;
mod check;
mod cli;
mod exit;
mod export;
mod outcome;
mod planners;
mod progress;
mod report;
mod rerun;
mod ros2;
mod run;
mod start;
mod sweep;
mod table;
mod top;
mod view;
mod watch;
mod world;

fn main() {
    let command = Cli::parse()
        .command
        .unwrap_or(Command::Run(Default::default()));
    // Zenoh's threads for an agent and for the world (unless ZENOH_RUNTIME
    // says otherwise), set before Zenoh reads them.
    match command {
        // SAFETY: parsing the command line started no thread; nothing
        // else has run yet.
        Command::Agent(_) => unsafe { mrsim_transport::zenoh::default_runtime() },
        // SAFETY: as above.
        Command::World(_) => unsafe { mrsim_transport::zenoh::world_runtime() },
        _ => {}
    }
    let result = match command {
        Command::Run(args) => crate::run::main(&args),
        Command::Bench(args) => crate::bench::main(&args),
        Command::World(args) => crate::world::main(&args),
        Command::Agent(args) => crate::agent::main(&args),
        Command::Ros2(args) => crate::ros2::main(&args),
        Command::Top(w) => crate::top::run(&w.run, w.timeout, w.link.zenoh()),
        Command::View { watch, live } => {
            crate::view::run(&watch.run, watch.timeout, watch.link.zenoh(), &live)
        }
        Command::Report { dir } => crate::report::main(&dir),
        Command::Export { dir, mcap } => crate::export::main(&dir, mcap),
        Command::Planners => crate::planners::main(),
        Command::Sweep(args) => crate::sweep::main(&args),
        Command::Spin { parent } => {
            mrsim_sys::sched::spin_while_child_of(parent);
            Ok(0)
        }
        Command::Rerun(args) => crate::rerun::main(&args),
        Command::Check { scenario } => crate::check::main(&scenario),
    };
    std::process::exit(crate::exit::code(result));
}
