//! Routes a car can drive, on real geometry: reversing into a parking bay,
//! turning round in a corridor too narrow for a U-turn, and crossing the
//! office map; and following such a route by pure pursuit.

mod common;

use common::{assert_drivable, close, dist};
use mrsim_route::drive::wrap;
use mrsim_route::{
    Car, CarMap, CarPath, CarRouteError, Gear, Goal, Pursuit, Scene, Search, outline, reeds_shepp,
    turning_radius,
};
use mrsim_shape::{Polygon, Pose, Shape};
use std::f64::consts::{FRAC_PI_2, PI};

/// A 4.6 x 1.6 car, wheelbase 3.0, steering at most 35 degrees.
fn car(reverse: bool) -> Car {
    Car {
        shape: Shape::Polygon(Polygon::rectangle(4.6, 1.6).expect("a rectangle")),
        radius: turning_radius(3.0, 35f64.to_radians(), 0.0),
        reverse,
    }
}

/// The walls of the rectangle `[x0, x1] x [y0, y1]`.
fn room(x0: f64, y0: f64, x1: f64, y1: f64) -> Vec<[[f64; 2]; 2]> {
    vec![
        [[x0, y0], [x1, y0]],
        [[x1, y0], [x1, y1]],
        [[x1, y1], [x0, y1]],
        [[x0, y1], [x0, y0]],
    ]
}

fn map_of(walls: &[[[f64; 2]; 2]], points: &[[f64; 2]], pad: f64) -> CarMap {
    CarMap::build(&Scene {
        walls,
        discs: &[],
        points,
        resolution: 0.05,
        pad,
    })
}

/// Every pose of the path `step` apart keeps the footprint off every wall
/// (the exact gap over all of them), and the path turns no tighter than
/// its radius and ends at `goal`.
fn check(map: &CarMap, shape: &Shape, path: &CarPath, goal: Pose, step: f64) {
    let poses = path.poses(step);
    assert_drivable(&poses, path.radius());
    for p in &poses {
        let g = map.gap_at(shape, p.pose());
        assert!(g >= 0.0, "the footprint overlaps by {} at {p:?}", -g);
    }
    let end = poses.last().expect("poses").pose();
    assert!(close(end, goal, 1e-6), "ends at {end:?}, not {goal:?}");
}

#[test]
fn a_car_reverses_into_a_bay_between_two_parked_cars() {
    let c = car(true);
    // A lot 24 x 11 along a kerb at y = 0; two cars parked nose out, 0.2
    // off the kerb, leaving a bay 2.5 wide between them at x = 0.
    let mut walls = room(-12.0, 0.0, 12.0, 11.0);
    let parked: Vec<Pose> = [-2.05, 2.05]
        .iter()
        .map(|&x| Pose::new([x, 2.5], FRAC_PI_2))
        .collect();
    for &p in &parked {
        walls.extend(outline(&c.shape, p));
    }
    let start = Pose::new([-8.0, 8.0], 0.0);
    let goal = Pose::new([0.0, 2.5], FRAC_PI_2);
    let map = map_of(&walls, &[], 3.0);
    let search = Search {
        margin: 0.05,
        ..Search::default()
    };
    let route = map
        .route(&c, start, &Goal::pose(goal), &search)
        .expect("a way into the bay");
    let path = &route.path;
    check(&map, &c.shape, path, goal, 0.02);
    // It backs in: the last piece is driven in reverse.
    let last = path.pieces().last().expect("pieces");
    assert_eq!(last.gear(), Gear::Reverse, "{:?}", path.pieces());
    // At its end the car is inside the bay: every corner between the
    // parked cars and off the kerb.
    let at = c.shape.placed(path.end()).expect("a polygon");
    for q in at.points() {
        assert!(q[0].abs() < 1.25 && q[1] > 0.0 && q[1] < 5.0, "{q:?}");
    }
    // And never touches the parked cars (their own gap, not just walls).
    for p in path.poses(0.02) {
        for &q in &parked {
            assert!(mrsim_shape::gap(&c.shape, p.pose(), &c.shape, q) >= 0.0);
        }
    }
    eprintln!(
        "parking: {} poses expanded, length {:.2}, {} gear changes",
        route.expanded,
        path.length(),
        path.gear_changes()
    );
}

/// A closed corridor 20 long and `width` wide, and a U-turn in it: from
/// the lower lane heading east to the upper lane heading west (each lane 2
/// from its wall).
fn corridor(width: f64) -> (CarMap, Pose, Pose) {
    let walls = room(-10.0, 0.0, 10.0, width);
    let map = map_of(&walls, &[], 3.0);
    (
        map,
        Pose::new([-5.0, 2.0], 0.0),
        Pose::new([-5.0, width - 2.0], PI),
    )
}

#[test]
fn turning_round_in_a_narrow_corridor_needs_reversing() {
    // Too narrow for a U-turn (the car sweeps a ring from 3.5 to 5.6 about
    // its turning centre, 11.2 across), wide enough for a three-point
    // turn.
    let (map, start, goal) = corridor(8.0);
    let search = Search {
        margin: 0.05,
        ..Search::default()
    };
    let route = map
        .route(&car(true), start, &Goal::pose(goal), &search)
        .expect("a three-point turn");
    check(&map, &car(true).shape, &route.path, goal, 0.02);
    assert!(route.path.gear_changes() >= 1, "{:?}", route.path.pieces());
    eprintln!(
        "three-point turn: {} poses expanded, length {:.2}, {} gear changes",
        route.expanded,
        route.path.length(),
        route.path.gear_changes()
    );
    // Forwards only there is no way round.
    let err = map
        .route(&car(false), start, &Goal::pose(goal), &search)
        .expect_err("no U-turn in 8 m");
    let CarRouteError::Unreachable {
        reverse: false,
        expanded,
        ..
    } = err
    else {
        panic!("{err}");
    };
    eprintln!("forwards only: unreachable after {expanded} poses");
    // In a corridor wide enough, forwards is enough.
    let (map, start, goal) = corridor(12.5);
    let route = map
        .route(&car(false), start, &Goal::pose(goal), &search)
        .expect("a U-turn in 12.5 m");
    check(&map, &car(false).shape, &route.path, goal, 0.02);
    assert_eq!(route.path.gear_changes(), 0);
}

#[test]
fn a_goal_without_a_heading_or_with_a_tolerance_ends_within_it() {
    let (map, start, _) = corridor(12.5);
    let search = Search {
        margin: 0.05,
        ..Search::default()
    };
    let anywhere = Goal {
        position: [5.0, 8.0],
        heading: None,
        heading_tolerance: 0.0,
        offset: 0.0,
    };
    let route = map
        .route(&car(false), start, &anywhere, &search)
        .expect("a way there");
    let end = route.path.end();
    assert!(dist(end.position, anywhere.position) < 1e-6, "{end:?}");
    assert_drivable(&route.path.poses(0.02), route.path.radius());
    // Facing west give or take 0.3 rad, forwards only.
    let loose = Goal {
        position: [-5.0, 10.5],
        heading: Some(PI),
        heading_tolerance: 0.3,
        offset: 0.0,
    };
    let route = map
        .route(&car(false), start, &loose, &search)
        .expect("a way there");
    let end = route.path.end();
    assert!(dist(end.position, loose.position) < 1e-6, "{end:?}");
    assert!(wrap(end.heading - PI).abs() <= 0.3 + 1e-9, "{end:?}");
    for p in route.path.poses(0.02) {
        assert!(map.gap_at(&car(false).shape, p.pose()) >= 0.0, "{p:?}");
    }
}

#[test]
fn the_search_stops_at_its_limit_with_its_own_error() {
    let (map, start, goal) = corridor(8.0);
    let search = Search {
        max_nodes: 50,
        shot_range: 0.0,
        ..Search::default()
    };
    assert_eq!(
        map.route(&car(true), start, &Goal::pose(goal), &search)
            .expect_err("50 poses are not enough"),
        CarRouteError::Effort { limit: 50 }
    );
}

#[test]
fn a_goal_the_car_does_not_fit_at_or_cannot_get_to_is_refused() {
    let (map, start, _) = corridor(8.0);
    let search = Search::default();
    // Half into the wall.
    let err = map
        .route(
            &car(true),
            start,
            &Goal::pose(Pose::new([0.0, 0.3], 0.0)),
            &search,
        )
        .expect_err("in the wall");
    assert!(matches!(err, CarRouteError::GoalBlocked { .. }), "{err}");
    // Behind a wall across the corridor with a gap narrower than the car.
    let mut walls = room(-10.0, 0.0, 10.0, 8.0);
    walls.push([[3.0, 0.0], [3.0, 3.6]]);
    walls.push([[3.0, 4.4], [3.0, 8.0]]);
    let map = map_of(&walls, &[], 3.0);
    let err = map
        .route(
            &car(true),
            start,
            &Goal::pose(Pose::new([7.0, 4.0], 0.0)),
            &search,
        )
        .expect_err("through 0.8 m");
    assert!(matches!(err, CarRouteError::NoWay { .. }), "{err}");
    let bad = Car {
        radius: 0.0,
        ..car(true)
    };
    assert!(matches!(
        map.route(&bad, start, &Goal::pose(start), &search),
        Err(CarRouteError::Bad(_))
    ));
}

#[test]
fn a_small_rectangle_crosses_the_office_map_through_two_doors() {
    let yaml =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/maps/office.yaml");
    let office = mrsim_scenario::map::load(&yaml).expect("the office map");
    let walls = office.walls(mrsim_scenario::UnknownCells::Occupied);
    let shape = Shape::Polygon(Polygon::rectangle(0.9, 0.6).expect("a rectangle"));
    let map = map_of(&walls, &[], 1.0);
    let start = Pose::new([-9.0, -5.0], FRAC_PI_2);
    let goal = Pose::new([-3.0, 5.0], FRAC_PI_2);
    for reverse in [true, false] {
        let c = Car {
            shape,
            radius: 0.5,
            reverse,
        };
        let route = map
            .route(
                &c,
                start,
                &Goal::pose(goal),
                &Search {
                    margin: 0.03,
                    ..Search::default()
                },
            )
            .expect("a way through the doors");
        check(&map, &shape, &route.path, goal, 0.01);
        // Out of the lower room's door and into the upper room's: it
        // crosses the corridor's two walls near the doors' middles.
        let poses = route.path.poses(0.01);
        for (y, x) in [(-1.0, -9.0), (1.0, -3.0)] {
            let p = poses
                .windows(2)
                .find(|w| (w[0].position[1] - y) * (w[1].position[1] - y) <= 0.0)
                .expect("crosses the wall");
            assert!((p[0].position[0] - x).abs() < 0.35, "{p:?}");
        }
        assert!(route.path.length() < 2.0 * (4.0 + 6.0 + 4.0));
        eprintln!(
            "office (reverse {reverse}): {} poses expanded, length {:.2}, {} gear changes",
            route.expanded,
            route.path.length(),
            route.path.gear_changes()
        );
    }
}

/// Drives a kinematic bicycle (its reference point the one the path is
/// for) along `path` by pure pursuit; returns its last pose, the largest
/// distance from the path and how many times it changed gear.
fn drive(path: &CarPath, wheelbase: f64, max_steer: f64, lookahead: f64) -> (Pose, f64, usize) {
    let mut f = Pursuit::new(path, lookahead, 0.1, 5.0);
    let mut p = path.start();
    let dt = 0.01;
    let mut worst: f64 = 0.0;
    let mut switches = 0;
    let mut gear = f.poses()[0].gear;
    for k in 0..200_000 {
        let t = f.target(p, k as f64 * dt);
        if t.gear != gear {
            switches += 1;
            gear = t.gear;
        }
        if t.last && t.to_stop < 1e-3 {
            break;
        }
        let speed = (t.to_stop * 2.0).clamp(0.05, 1.0);
        let v = if t.gear == Gear::Forward {
            speed
        } else {
            -speed
        };
        let delta = t.steering(wheelbase, max_steer);
        let h = p.heading;
        p = Pose::new(
            [
                p.position[0] + v * dt * h.cos(),
                p.position[1] + v * dt * h.sin(),
            ],
            h + v * dt * delta.tan() / wheelbase,
        );
        let d = f
            .poses()
            .iter()
            .map(|q| dist(q.position, p.position))
            .fold(f64::INFINITY, f64::min);
        worst = worst.max(d);
    }
    (p, worst, switches)
}

#[test]
fn pure_pursuit_aims_ahead_on_the_path_and_steers_towards_it() {
    let path = CarPath::new(
        Pose::new([0.0, 0.0], 0.0),
        1.0,
        [mrsim_route::Piece {
            steer: mrsim_route::Steer::Straight,
            length: 10.0,
        }],
    );
    let mut f = Pursuit::new(&path, 2.0, 0.2, 5.0);
    // The car 0.5 left of the path, heading along it.
    let t = f.target(Pose::new([1.0, 0.5], 0.0), 0.0);
    assert!(
        (t.point[0] - 3.0).abs() < 1e-9 && t.point[1].abs() < 1e-9,
        "{t:?}"
    );
    assert_eq!(t.gear, Gear::Forward);
    assert!(t.heading.abs() < 1e-12);
    // y = -0.5, l^2 = 4.25: Coulter's 2 y / l^2, to the right.
    assert!((t.curvature - 2.0 * -0.5 / 4.25).abs() < 1e-9, "{t:?}");
    assert!((t.to_stop - 9.0).abs() < 1e-9);
    assert!(t.last && !f.at_end());
    assert!(t.steering(3.0, 0.6) < 0.0);
    // Backwards, the point behind is pursued with the same formula.
    let back = CarPath::new(
        Pose::new([0.0, 0.0], 0.0),
        1.0,
        [mrsim_route::Piece {
            steer: mrsim_route::Steer::Straight,
            length: -10.0,
        }],
    );
    let mut f = Pursuit::new(&back, 2.0, 0.2, 5.0);
    let t = f.target(Pose::new([-1.0, 0.5], 0.0), 0.0);
    assert_eq!(t.gear, Gear::Reverse);
    assert!((t.point[0] + 3.0).abs() < 1e-9, "{t:?}");
    // The path is on the car's right: the wheels turned right, backing
    // turns the heading left and swings the rear right, onto the path.
    assert!(t.curvature < 0.0, "{t:?}");
}

#[test]
fn a_bicycle_follows_a_path_with_cusps_by_pure_pursuit_to_its_end() {
    let (wheelbase, steer) = (1.0, 0.6f64);
    // Planned a quarter wider than the car can turn: a path at full lock
    // leaves the pursuit no steering to correct with.
    let r = 1.25 * turning_radius(wheelbase, steer, 0.0);
    // A sideways shift: backwards, forwards and backwards again.
    let goal = Pose::new([0.5, 1.2], 0.0);
    let path = reeds_shepp::shortest(Pose::new([0.0, 0.0], 0.0), goal, r);
    assert!(path.gear_changes() >= 1, "{path:?}");
    let (end, worst, switches) = drive(&path, wheelbase, steer, 0.5);
    assert_eq!(switches, path.gear_changes());
    assert!(dist(end.position, goal.position) < 0.1, "{end:?}");
    assert!(wrap(end.heading - goal.heading).abs() < 0.1, "{end:?}");
    assert!(worst < 0.2, "{worst}");
}

#[test]
fn a_car_follows_its_parking_route_by_pure_pursuit_into_the_bay() {
    let c = car(true);
    let walls = room(-12.0, 0.0, 12.0, 11.0);
    let start = Pose::new([-8.0, 8.0], 0.0);
    let goal = Pose::new([0.0, 2.5], FRAC_PI_2);
    let map = map_of(&walls, &[], 3.0);
    let route = map
        .route(&c, start, &Goal::pose(goal), &Search::default())
        .expect("a route");
    let (end, worst, switches) = drive(&route.path, 3.0, 35f64.to_radians(), 1.5);
    assert_eq!(switches, route.path.gear_changes());
    assert!(dist(end.position, goal.position) < 0.2, "{end:?}");
    assert!(wrap(end.heading - goal.heading).abs() < 0.1, "{end:?}");
    assert!(worst < 0.3, "{worst}");
}
