//! A scenario's `[map]`: load the map, refuse robots and obstacles that
//! start (or robots whose goal is) in or too near its walls, and robots
//! whose goal the map's walls shut off from their start (no way through
//! free cells joins the two: no planner and no route could get there), and
//! add its traced walls to the scenario's.

use super::robots::RobotSpans;
use super::scene::dist_to_segment;
use crate::error::Fail;
use crate::map::OccupancyMap;
use crate::raw::{RawMap, S};
use crate::types::{MapInfo, Scenario, WallSpec};
use std::ops::Range;
use std::path::Path;

/// Loads `[map]` (its `file` relative to the folder of the scenario file
/// `origin`), checks the bodies against it and appends its walls to
/// `scenario.walls`, in the scenario's length unit (the map's are metres).
pub(crate) fn attach(
    raw: &S<RawMap>,
    origin: &str,
    scenario: &mut Scenario,
    robot_spans: &[RobotSpans],
    obstacle_spans: &[Range<usize>],
) -> Result<(), Fail> {
    let m = raw.get_ref();
    let Some(file) = &m.file else {
        return Err(Fail::new(
            Some(raw.span()),
            "map",
            "missing `file` (the map's YAML in ROS map_server's format, relative to the scenario's folder)",
        ));
    };
    let given = Path::new(file.get_ref());
    let path = if given.is_absolute() {
        given.to_path_buf()
    } else {
        Path::new(origin)
            .parent()
            .unwrap_or(Path::new(""))
            .join(given)
    };
    let map =
        crate::map::load(&path).map_err(|e| Fail::new(Some(file.span()), "map", e.to_string()))?;
    let unknown = m.unknown.as_ref().map(|u| *u.get_ref()).unwrap_or_default();
    let scale = scenario.length_unit.per_metre();
    let walls: Vec<[[f64; 2]; 2]> = map
        .walls(unknown)
        .into_iter()
        .map(|[a, b]| [[a[0] * scale, a[1] * scale], [b[0] * scale, b[1] * scale]])
        .collect();
    let name = path.display().to_string();
    let check = Check {
        map: &map,
        name: &name,
        walls: &walls,
        scale,
        unknown,
    };
    for (r, sp) in scenario.robots.iter().zip(robot_spans) {
        let what = format!("robot `{}`", r.name);
        check
            .place(r.start, r.radius, "start")
            .map_err(|reason| Fail::new(sp.start.clone(), &what, reason))?;
        check
            .place(r.goal, r.radius, "goal")
            .map_err(|reason| Fail::new(sp.goal.clone(), &what, reason))?;
    }
    // Computed once, and only for a scenario with robots.
    let regions = (!scenario.robots.is_empty()).then(|| map.regions(unknown));
    for (r, sp) in scenario.robots.iter().zip(robot_spans) {
        if let Some(regions) = &regions {
            check.joined(regions, r.start, r.goal).map_err(|reason| {
                Fail::new(sp.goal.clone(), format!("robot `{}`", r.name), reason)
            })?;
        }
    }
    for (o, sp) in scenario.obstacles.iter().zip(obstacle_spans) {
        check.place(o.start, 0.0, "start").map_err(|reason| {
            Fail::new(Some(sp.clone()), format!("obstacle `{}`", o.name), reason)
        })?;
    }
    scenario.map = Some(MapInfo {
        file: name,
        image: map.meta.image.display().to_string(),
        size: [map.width, map.height],
        resolution: map.meta.resolution,
        origin: map.meta.origin,
        unknown,
        walls: walls.len(),
    });
    scenario
        .walls
        .extend(walls.into_iter().map(|segment| WallSpec { segment }));
    Ok(())
}

struct Check<'a> {
    map: &'a OccupancyMap,
    name: &'a str,
    walls: &'a [[[f64; 2]; 2]],
    scale: f64,
    unknown: crate::types::UnknownCells,
}

impl Check<'_> {
    /// Is a disc of `radius` at `p` (scenario units) clear of the map's
    /// walls? The error says why not.
    fn place(&self, p: [f64; 2], radius: f64, key: &str) -> Result<(), String> {
        let at = format!("{key} [{}, {}]", p[0], p[1]);
        let metres = [p[0] / self.scale, p[1] / self.scale];
        let Some((i, j)) = self.map.cell_of(metres) else {
            return Err(format!(
                "{at} is outside map {} ({} x {} cells)",
                self.name, self.map.width, self.map.height
            ));
        };
        if self.map.is_wall(i, j, self.unknown) {
            let kind = if self.map.value(i, j) == 100 {
                "an occupied"
            } else {
                "an unknown"
            };
            return Err(format!(
                "{at} is inside a wall of map {}: {kind} cell (column {i}, row {j} from the \
                 lower left)",
                self.name
            ));
        }
        if radius > 0.0
            && let Some(d) = self
                .walls
                .iter()
                .map(|w| dist_to_segment(p, *w))
                .min_by(f64::total_cmp)
            && d < radius
        {
            return Err(format!(
                "{at} is {d:.4} from a wall of map {}, less than the radius {radius}",
                self.name
            ));
        }
        Ok(())
    }

    /// Does a way through the map's free cells join `start` to `goal`
    /// (both already checked to lie in free cells)? The error says why
    /// not.
    fn joined(&self, regions: &[u32], start: [f64; 2], goal: [f64; 2]) -> Result<(), String> {
        let region = |p: [f64; 2]| {
            self.map
                .cell_of([p[0] / self.scale, p[1] / self.scale])
                .map(|(i, j)| (regions[j * self.map.width + i], (i, j)))
        };
        let (Some((a, _)), Some((b, (i, j)))) = (region(start), region(goal)) else {
            return Ok(());
        };
        if a == b {
            return Ok(());
        }
        let cells = regions.iter().filter(|&&r| r == b).count();
        let area = cells as f64 * self.map.meta.resolution.powi(2);
        let hint = if self.unknown == crate::types::UnknownCells::Occupied {
            " (unknown cells count as walls; `unknown = \"free\"` in [map] makes them free)"
        } else {
            ""
        };
        Err(format!(
            "goal [{}, {}] is shut off from the start [{}, {}] by the walls of map {}: no way \
             through free cells joins them; the goal's cell (column {i}, row {j} from the lower \
             left) lies in a closed region of {cells} cells ({area:.2} m²){hint}",
            goal[0], goal[1], start[0], start[1], self.name
        ))
    }
}
