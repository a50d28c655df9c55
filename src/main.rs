//! `mrsim`: parse the command line and hand over to the library.
use clap::Parser;

fn main() {
    let cli = mrsim::cli::Cli::parse();
    std::process::exit(mrsim::cli::main(cli));
}
