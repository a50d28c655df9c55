//! The scenario loader's tests, one test binary with one module per theme
//! (`cargo test --release -p mrsim-scenario --test it maps::` runs one).

mod common;

mod cars;
mod cores;
mod files;
mod fuzz;
mod generate;
mod maps;
mod output;
mod overrides;
mod people;
mod robots;
mod shapes;
mod timing;
mod validation;
