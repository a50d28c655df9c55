//! scan.csv: the laser scans of the robots whose `sensor` has
//! `record = true`, one row per robot and tick, written by the recording
//! thread. Each scan is computed here again, by the function the agent's
//! observation uses ([`mrsim_lidar::Scanner::scan_robot`], with the same
//! bodies and shapes, walls and per-tick noise stream), from the states of
//! the trajectory row of the same tick: the very scan the planner got.
//!
//! The file's name, columns and reader are [`mrsim_runfolder::scan`]'s;
//! rows are whole ([`RowFile`]) and reach the disk when the recording
//! thread flushes.

use mrsim_lidar::{Scanner, Walls};
use mrsim_planners::lidar::LaserScan;
use mrsim_proto::BodyState;
use mrsim_runfolder::SCAN_FILE;
use mrsim_runfolder::stream::RowFile;
use mrsim_scenario::{RobotSpec, Scenario};
use std::io::Write;
use std::path::Path;

/// Writes scan.csv.
pub struct ScanWriter {
    out: RowFile,
    /// (robot index, entry) of every recorded robot.
    robots: Vec<(usize, RobotSpec)>,
    scanner: Scanner,
    /// Every body's shape ([`Scenario::body_shapes`]); empty when all
    /// are discs (the states' radii).
    shapes: Vec<mrsim_shape::Shape>,
    seed: u64,
    width: usize,
    scan: LaserScan,
    line: String,
}

impl ScanWriter {
    /// Creates scan.csv in `dir` if a robot of `scenario` records its
    /// scans; `None` otherwise.
    pub fn create(dir: &Path, scenario: &Scenario) -> std::io::Result<Option<Self>> {
        let robots: Vec<(usize, RobotSpec)> = scenario
            .robots
            .iter()
            .enumerate()
            .filter(|(_, r)| r.sensor.is_some_and(|l| l.record))
            .map(|(i, r)| (i, r.clone()))
            .collect();
        if robots.is_empty() {
            return Ok(None);
        }
        let width = robots
            .iter()
            .filter_map(|(_, r)| r.sensor.map(|l| l.beams as usize))
            .max()
            .unwrap_or(0);
        let out = RowFile::create(&dir.join(SCAN_FILE), &mrsim_runfolder::scan::header(width))?;
        Ok(Some(Self {
            out,
            robots,
            scanner: Scanner::new(Walls::new(scenario.all_walls())),
            shapes: if scenario.has_shapes() {
                scenario.body_shapes()
            } else {
                Vec::new()
            },
            seed: scenario.world.seed,
            width,
            scan: LaserScan::default(),
            line: String::new(),
        }))
    }

    /// Writes the scans of tick `tick` (every body's state in `bodies`).
    pub fn write(&mut self, tick: u64, bodies: &[BodyState]) -> std::io::Result<()> {
        use std::fmt::Write as _;
        for (me, spec) in &self.robots {
            if !self.scanner.scan_robot(
                &mut self.scan,
                self.seed,
                tick,
                *me,
                spec,
                bodies,
                &self.shapes,
            ) {
                continue;
            }
            self.line.clear();
            let _ = write!(
                self.line,
                "{tick},{},{},{},{}",
                spec.name, self.scan.angle_min, self.scan.angle_increment, self.scan.range_max
            );
            for r in &self.scan.ranges {
                let _ = if r.is_finite() {
                    write!(self.line, ",{r:.6}")
                } else {
                    write!(self.line, ",inf")
                };
            }
            for _ in self.scan.ranges.len()..self.width {
                self.line.push(',');
            }
            self.line.push('\n');
            self.out.write_all(self.line.as_bytes())?;
        }
        Ok(())
    }

    /// Puts the rows held on the disk.
    pub fn flush(&mut self) -> std::io::Result<()> {
        self.out.write_out()
    }

    /// Holds enough rows to be written out.
    pub fn is_full(&self) -> bool {
        self.out.is_full()
    }
}
