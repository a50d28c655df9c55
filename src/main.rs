//! `mrsim`: parse the command line, run the subcommand, exit with its status.
use clap::Parser;
use mrsim::cli::{Cli, Command};

fn main() {
    let result = match Cli::parse()
        .command
        .unwrap_or(Command::Run(Default::default()))
    {
        Command::Run(args) => mrsim::run::main(&args),
        Command::Bench(args) => mrsim::bench::main(&args),
        Command::World(args) => mrsim::world::main(&args),
        Command::Agent(args) => mrsim::agent::main(&args),
        Command::Ros2(args) => mrsim::ros2::main(&args),
        Command::Top(w) => mrsim::top::run(&w.run, w.timeout, w.zenoh()),
        Command::View { watch, live } => {
            mrsim::view::run(&watch.run, watch.timeout, watch.zenoh(), &live)
        }
        Command::Report { dir } => mrsim::report::main(&dir),
        Command::Export { dir, mcap } => mrsim::export::main(&dir, mcap),
        Command::Planners => mrsim::planners::main(),
        Command::Sweep(args) => mrsim::sweep::main(&args),
        Command::Spin { parent } => {
            mrsim_sys::sched::spin_while_child_of(parent);
            Ok(0)
        }
        Command::Rerun(args) => mrsim::rerun::main(&args),
        Command::Check { scenario } => mrsim::check::main(&scenario),
    };
    std::process::exit(mrsim::exit::code(result));
}
