//! Routes for robots' discs through walls and static obstacles.
//!
//! A [`Clearance`] grid holds, at the centre of each cell, the distance to
//! the nearest wall segment or static disc; a robot of radius r can stand
//! where that distance is at least r. [`Clearance::route`] searches the grid
//! for the shortest way from a start to a goal that the disc fits along,
//! preferring to keep a margin more than the radius where the map leaves
//! room, and pulls the grid path taut into straight legs. A [`Path`] is the
//! result, and [`Follower`] leads a robot along it: a waypoint a fixed
//! distance ahead of its progress, and a sign when it stops progressing.
//!
//! **Why a grid.** The scenes this serves are mostly traced occupancy maps
//! (thousands of short outline segments from a SLAM map's cells), where a
//! visibility graph grows with the square of the segments' corners and
//! needs the obstacles grown by the radius exactly; the grid's cost is its
//! cell count whatever the walls, its clearance is computed once for every
//! radius, and it can tell a robot *why* no way exists (the widest way's
//! narrowest gap). A* on the 8-connected grid is followed by string pulling
//! (each leg straightened while the straight line keeps as much clearance
//! as the grid path it replaces), which gives the any-angle paths of
//! Theta* (A. Nash, K. Daniel, S. Koenig & A. Felner, "Theta*: Any-Angle
//! Path Planning on Grids", AAAI 2007) by a second pass instead of during
//! the search.
//!
//! **The clearance.** Every segment is sampled at half a cell's spacing and
//! every disc's rim likewise; each sample seeds the cell it falls in, and
//! two sweeps of the grid hand each cell its neighbours' nearest sample
//! when that is nearer (the vector propagation of P.-E. Danielsson,
//! "Euclidean distance mapping", CGIP 14, 1980, with 8 neighbours). The
//! distance from a cell's centre to its sample is the clearance, exact to
//! about a tenth of a cell. A cell outside the grid is a wall.
//!
//! **The margin.** A route keeps the robot's centre at least `radius +
//! margin` from walls wherever it can: cells with less clearance cost
//! more to cross (up to [`NARROW_COST`] times their length at the bare
//! radius), so a way through a door the disc fits only tightly is taken
//! only when no roomier way is much longer, and cells with less than the
//! radius are not crossed at all (but near the start and the goal, which
//! the scenario has already checked).
//!
//! **Lanes.** A shortest route runs down the middle of a corridor, or
//! grazes its inner corners, whichever way it is travelled, so robots going
//! opposite ways along it meet head-on and must both swerve, to the same
//! side as often as not. [`Clearance::keep_to`] moves a route sideways, to
//! the right (or the left) of its direction of travel, by up to a given
//! offset wherever the walls leave room: at each point (every half cell
//! along it) as far towards that side as the clearance stays at least a
//! given `need` (the route's `radius + margin`), at most the offset, and
//! nowhere more than half the distance from the route's nearer end, nor
//! changing faster than half a metre sideways a metre along (so it leaves
//! the start and reaches the goal exactly and enters and leaves a lane at
//! about 27 degrees). Two routes travelled opposite ways along a corridor
//! wide enough for two then lie up to twice the offset apart, and each
//! robot's look-ahead waypoint leads it into its own lane: the traffic rule
//! of keeping to one side, which people and vehicles follow so that
//! opposing flows pass instead of meeting. Through a door or a corridor
//! that leaves no room beyond `need` the route is unchanged. The moved
//! polyline is simplified (Douglas-Peucker, a quarter cell) and kept only
//! if every leg still clears the bare radius.
//!
//! **Cars.** A robot that steers like a car (a kinematic bicycle: it turns
//! no tighter than a radius R = wheelbase / tan(max steering), and may or
//! may not reverse) cannot follow a polyline's corners. Its routes are
//! [`CarPath`]s, arcs of radius R and straights driven forwards or
//! backwards ([`drive`]): [`dubins`] and [`reeds_shepp`] give the shortest
//! such path between two poses without obstacles (forwards only, and both
//! ways), [`CarMap::route`] searches one through walls and obstacles by
//! Hybrid A* with the robot's true footprint ([`hybrid`]), and [`Pursuit`]
//! leads a car along it by pure pursuit, one gear at a time ([`pursuit`]).

#![warn(missing_docs)]

pub mod drive;
pub mod dubins;
mod follow;
mod grid;
pub mod hybrid;
mod lanes;
pub mod pursuit;
pub mod reeds_shepp;
mod refuge;
mod search;

pub use drive::{CarPath, CarPose, Gear, Piece, Steer, turning_radius};
pub use follow::{Follower, Path};
pub use grid::{Clearance, Scene};
pub use hybrid::{Car, CarMap, CarRoute, CarRouteError, Goal, Search, outline};
pub use lanes::Side;
pub use pursuit::{Pursuit, Target};
pub use refuge::{Refuge, to_way};

/// A point, in the scenario's units.
pub type P = [f64; 2];

/// How much more a step costs where the clearance is the bare radius than
/// where it is `radius + margin` or more (linear in between).
pub const NARROW_COST: f64 = 4.0;

/// Why no route was found.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RouteError {
    /// The start or the goal lies outside the grid (the scene's extent).
    #[error("{which} [{}, {}] is outside the area the walls span", at[0], at[1])]
    Outside {
        /// `start` or `goal`.
        which: &'static str,
        /// The point.
        at: P,
    },
    /// Every way from the start to the goal has a gap narrower than the
    /// robot's disc; `widest` is the clearance at the narrowest point of
    /// the widest way (the largest radius that could pass).
    #[error(
        "no way from the start to the goal is wide enough for a disc of radius {radius}: \
         the widest way narrows to a clearance of {widest:.3} (a disc of at most that radius \
         passes)"
    )]
    TooNarrow {
        /// The robot's radius.
        radius: f64,
        /// Clearance at the narrowest point of the widest way.
        widest: f64,
    },
}

/// Euclidean distance.
pub(crate) fn dist(a: P, b: P) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// Where the point of the segment `a`-`b` nearest to `p` lies along it, as a
/// fraction of its length (0 for a segment of no length).
pub(crate) fn along(p: P, a: P, b: P) -> f64 {
    let ab = [b[0] - a[0], b[1] - a[1]];
    let len2 = ab[0] * ab[0] + ab[1] * ab[1];
    if len2 <= 0.0 {
        0.0
    } else {
        (((p[0] - a[0]) * ab[0] + (p[1] - a[1]) * ab[1]) / len2).clamp(0.0, 1.0)
    }
}

/// An entry of the searches' open sets (a max-heap made a min-heap): the
/// smallest `key` first, ties by cell, so that searches are deterministic.
#[derive(PartialEq)]
pub(crate) struct Entry {
    pub(crate) key: f64,
    pub(crate) cell: usize,
}

impl Eq for Entry {}

impl Ord for Entry {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        other
            .key
            .total_cmp(&self.key)
            .then(other.cell.cmp(&self.cell))
    }
}

impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}
