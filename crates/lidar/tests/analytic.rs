//! The scanner's ranges (parry's ray casts, f32) against exact analytic
//! distances (f64) to known shapes: discs, segments, rectangles, turned
//! rectangle and polygon bodies, and the office map's traced outlines. The analytic ray tests here are the
//! oracle only; the simulator uses `mrsim_lidar`.

use mrsim_lidar::{Body, Scanner, Walls};
use mrsim_planners::lidar::{LaserScan, LidarConfig};
use mrsim_planners::{Polygon, Pose, Segment, Shape, Vec2};
use std::f64::consts::{FRAC_PI_2, PI, TAU};

/// f32 rounding of shapes a few to a few tens of units from the origin,
/// relative to the range beyond 1 unit: parry's ray-segment test solves for
/// the crossing with a determinant that loses precision as the beam
/// approaches the wall's direction (relative error ~ f32 epsilon / sin² of
/// the angle between them: 1.2e-4 at 7 m for a beam 4 degrees off a 20 m
/// corridor wall).
const TOL: f64 = 1e-4;

/// Distance along the unit ray `p + t d` to the disc of centre `c` and
/// radius `r` (0 if `p` is inside): the smaller root of
/// t² + 2 t d.(p - c) + |p - c|² - r² = 0.
fn ray_disc(p: Vec2, d: Vec2, c: Vec2, r: f64) -> Option<f64> {
    let m = p - c;
    let b = m.dot(&d);
    let cc = m.norm_squared() - r * r;
    if cc <= 0.0 {
        return Some(0.0);
    }
    if b > 0.0 {
        return None;
    }
    let disc = b * b - cc;
    if disc < 0.0 {
        return None;
    }
    Some((-b - disc.sqrt()).max(0.0))
}

/// Distance along the unit ray `p + t d` to segment `s` (where the two
/// lines' cross products put the crossing), if it meets it.
fn ray_segment(p: Vec2, d: Vec2, s: &Segment) -> Option<f64> {
    let e = s.b - s.a;
    let cross = |u: Vec2, v: Vec2| u.x * v.y - u.y * v.x;
    let denom = cross(d, e);
    if denom.abs() <= 1e-15 * e.norm() {
        return None;
    }
    let ap = s.a - p;
    let t = cross(ap, e) / denom;
    let u = cross(ap, d) / denom;
    (t >= 0.0 && (0.0..=1.0).contains(&u)).then_some(t)
}

/// The oracle's range along the ray at world angle `a`.
fn oracle(o: Vec2, a: f64, discs: &[(Vec2, f64)], walls: &[Segment], range: f64) -> f64 {
    let d = Vec2::new(a.cos(), a.sin());
    let t = discs
        .iter()
        .filter_map(|(c, r)| ray_disc(o, d, *c, *r))
        .chain(walls.iter().filter_map(|w| ray_segment(o, d, w)))
        .fold(f64::INFINITY, f64::min);
    if t > range { f64::INFINITY } else { t }
}

fn seg(a: [f64; 2], b: [f64; 2]) -> Segment {
    Segment {
        a: Vec2::new(a[0], a[1]),
        b: Vec2::new(b[0], b[1]),
    }
}

fn full(beams: u32, range: f64) -> LidarConfig {
    LidarConfig {
        beams,
        fov: TAU,
        range,
        noise: 0.0,
    }
}

fn no_noise() -> f64 {
    panic!("no noise asked for")
}

fn scan(
    cfg: &LidarConfig,
    o: Vec2,
    heading: f64,
    discs: &[(Vec2, f64)],
    walls: &[Segment],
) -> LaserScan {
    let mut s = LaserScan::default();
    Scanner::new(Walls::from_segments(walls)).scan(
        &mut s,
        cfg,
        o,
        heading,
        discs.iter().copied(),
        &mut no_noise,
    );
    s
}

/// Every beam of the scan equals the oracle within [`TOL`], or (a beam
/// grazing an edge, where f32 and f64 may fall either side) the oracle of
/// a direction within 1e-5 rad; returns how many needed that.
fn assert_matches_oracle(
    cfg: &LidarConfig,
    o: Vec2,
    heading: f64,
    discs: &[(Vec2, f64)],
    walls: &[Segment],
) -> usize {
    let s = scan(cfg, o, heading, discs, walls);
    let (a0, inc) = cfg.angles();
    assert_eq!((s.angle_min, s.angle_increment), (a0, inc));
    assert_eq!(s.range_max, cfg.range);
    assert_eq!(s.ranges.len(), cfg.beams as usize);
    let close =
        |r: f64, e: f64| (r.is_infinite() && e.is_infinite()) || (r - e).abs() <= TOL * e.max(1.0);
    let mut grazing = 0;
    for (k, r) in s.ranges.iter().enumerate() {
        let a = heading + a0 + inc * k as f64;
        let e = oracle(o, a, discs, walls, cfg.range);
        if close(*r, e) {
            continue;
        }
        let near = [-1e-5, 1e-5]
            .iter()
            .any(|da| close(*r, oracle(o, a + da, discs, walls, cfg.range)));
        assert!(near, "beam {k} at {a} rad from {o:?}: {r} vs exact {e}");
        grazing += 1;
    }
    grazing
}

#[test]
fn a_disc_ahead_reads_its_centre_distance_less_its_radius() {
    // 4 beams: -pi, -pi/2, 0, pi/2.
    let s = scan(
        &full(4, 10.0),
        Vec2::new(1.0, 1.0),
        0.0,
        &[(Vec2::new(4.0, 1.0), 0.5)],
        &[],
    );
    assert_eq!(s.angle_min, -PI);
    assert!((s.angle_increment - FRAC_PI_2).abs() < 1e-15);
    assert!((s.ranges[2] - 2.5).abs() < TOL, "{:?}", s.ranges);
    assert!(s.ranges[0].is_infinite() && s.ranges[1].is_infinite());
    assert!(s.ranges[3].is_infinite());
}

#[test]
fn an_oblique_beam_meets_a_disc_where_the_quadratic_says() {
    // The beam at 45 degrees meets the disc at (3, 2) radius 1 at (2, 2).
    let mut cfg = full(1, 10.0);
    cfg.fov = 0.1;
    let s = scan(
        &cfg,
        Vec2::zeros(),
        PI / 4.0,
        &[(Vec2::new(3.0, 2.0), 1.0)],
        &[],
    );
    assert!(
        (s.ranges[0] - 2.0 * 2f64.sqrt()).abs() < TOL,
        "{:?}",
        s.ranges
    );
    // Facing away: nothing.
    let s = scan(
        &cfg,
        Vec2::zeros(),
        -3.0 * PI / 4.0,
        &[(Vec2::new(3.0, 2.0), 1.0)],
        &[],
    );
    assert!(s.ranges[0].is_infinite());
}

#[test]
fn a_scanner_inside_a_disc_reads_zero_on_every_beam() {
    let s = scan(
        &full(8, 5.0),
        Vec2::zeros(),
        0.0,
        &[(Vec2::new(0.1, 0.0), 0.5)],
        &[],
    );
    assert!(s.ranges.iter().all(|r| *r == 0.0), "{:?}", s.ranges);
}

#[test]
fn a_wall_corner_reads_the_perpendicular_distance_to_each_side() {
    // A corner at (2, 3): walls x = 2 (y <= 3) and y = 3 (x <= 2); 8 beams
    // every 45 degrees from -pi, heading pi/2 (beam 4 points along +y).
    let walls = [seg([2.0, -5.0], [2.0, 3.0]), seg([-5.0, 3.0], [2.0, 3.0])];
    let s = scan(&full(8, 10.0), Vec2::zeros(), FRAC_PI_2, &[], &walls);
    assert!((s.ranges[4] - 3.0).abs() < TOL, "{:?}", s.ranges);
    assert!((s.ranges[2] - 2.0).abs() < TOL);
    // 45 degrees between: the line y = x meets x = 2 at y = 2 < 3.
    assert!((s.ranges[3] - 2.0 * 2f64.sqrt()).abs() < TOL);
    // -y and -x: the segments end before.
    assert!(s.ranges[0].is_infinite() && s.ranges[6].is_infinite());
    // Up-left: y = 3 at x = -3.
    assert!((s.ranges[5] - 3.0 * 2f64.sqrt()).abs() < TOL);
}

#[test]
fn the_nearest_surface_wins_and_beyond_the_range_reads_infinity() {
    let walls = [seg([5.0, -1.0], [5.0, 1.0])];
    let mut cfg = full(1, 10.0);
    cfg.fov = 0.1;
    let disc = [(Vec2::new(3.0, 0.0), 0.5)];
    let s = scan(&cfg, Vec2::zeros(), 0.0, &disc, &walls);
    assert!((s.ranges[0] - 2.5).abs() < TOL);
    // The disc out of the way: the wall behind it.
    let s = scan(
        &cfg,
        Vec2::zeros(),
        0.0,
        &[(Vec2::new(3.0, 2.0), 0.5)],
        &walls,
    );
    assert!((s.ranges[0] - 5.0).abs() < TOL);
    cfg.range = 2.0;
    let s = scan(&cfg, Vec2::zeros(), 0.0, &disc, &walls);
    assert_eq!(s.ranges, vec![f64::INFINITY]);
}

#[test]
fn a_beam_along_the_edge_of_a_box_still_meets_what_lies_on_that_edge() {
    // The beam along +x from (0, 0) runs along y = 0, where the first
    // wall's box begins and the second wall ends: both count.
    let mut cfg = full(1, 10.0);
    cfg.fov = 0.1;
    let s = scan(
        &cfg,
        Vec2::zeros(),
        0.0,
        &[],
        &[seg([5.0, 0.0], [5.0, 2.0])],
    );
    assert!((s.ranges[0] - 5.0).abs() < TOL, "{:?}", s.ranges);
    let s = scan(
        &cfg,
        Vec2::zeros(),
        0.0,
        &[],
        &[seg([4.0, -2.0], [4.0, 0.0])],
    );
    assert!((s.ranges[0] - 4.0).abs() < TOL, "{:?}", s.ranges);
}

#[test]
fn inside_a_rectangle_every_beam_reads_the_distance_to_its_sides() {
    // A 6 x 4 room from (-1, -1): from (1, 0.5) a beam at angle a meets
    // x = 5 at (5 - 1) / cos a, x = -1 at 2 / -cos a, y = 3 at 2.5 / sin a,
    // y = -1 at 1.5 / -sin a, whichever comes first.
    let walls = [
        seg([-1.0, -1.0], [5.0, -1.0]),
        seg([5.0, -1.0], [5.0, 3.0]),
        seg([5.0, 3.0], [-1.0, 3.0]),
        seg([-1.0, 3.0], [-1.0, -1.0]),
    ];
    let cfg = full(360, 20.0);
    let o = Vec2::new(1.0, 0.5);
    let s = scan(&cfg, o, 0.3, &[], &walls);
    let (a0, inc) = cfg.angles();
    for (k, r) in s.ranges.iter().enumerate() {
        let a = 0.3 + a0 + inc * k as f64;
        let (c, sn) = (a.cos(), a.sin());
        let tx = if c > 0.0 { 4.0 / c } else { 2.0 / -c };
        let ty = if sn > 0.0 { 2.5 / sn } else { 1.5 / -sn };
        let e = tx.min(ty);
        assert!((r - e).abs() < TOL, "beam {k}: {r} vs {e}");
    }
}

/// A small linear congruential generator in [-1, 1).
fn lcg(seed: u64) -> impl FnMut() -> f64 {
    let mut x = seed;
    move || {
        x = x
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (x >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
}

#[test]
fn random_discs_and_walls_read_what_the_exact_ray_tests_read() {
    let mut next = lcg(7);
    // 20 discs (one cast each) and 120 (through the discs' hierarchy).
    for n in [20, 120] {
        let discs: Vec<(Vec2, f64)> = (0..n)
            .map(|_| {
                (
                    Vec2::new(6.0 * next(), 6.0 * next()),
                    0.1 + 0.3 * next().abs(),
                )
            })
            .filter(|(c, r)| (c - Vec2::new(0.1, -0.2)).norm() > *r)
            .collect();
        let walls: Vec<Segment> = (0..20)
            .map(|_| seg([8.0 * next(), 8.0 * next()], [8.0 * next(), 8.0 * next()]))
            .collect();
        let mut grazing = 0;
        for (beams, fov, heading) in [(360, TAU, 0.3), (91, 1.5, -2.9), (7, 3.0, 3.1)] {
            let cfg = LidarConfig {
                beams,
                fov,
                range: 7.0,
                noise: 0.0,
            };
            grazing += assert_matches_oracle(&cfg, Vec2::new(0.1, -0.2), heading, &discs, &walls);
        }
        assert!(grazing <= 2, "{grazing} grazing beams among {n} discs");
    }
}

#[test]
fn every_robot_of_the_office_map_scans_what_the_exact_ray_tests_read() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let loaded = mrsim_scenario::load(&root.join("scenarios/maps/office.toml")).expect("office");
    let sc = loaded.scenario;
    let walls: Vec<Segment> = sc.all_walls().iter().map(|w| seg(w[0], w[1])).collect();
    assert!(walls.len() > 20, "{} walls", walls.len());
    let discs: Vec<(Vec2, f64)> = sc
        .robots
        .iter()
        .map(|r| (Vec2::new(r.start[0], r.start[1]), r.radius))
        .collect();
    let mut grazing = 0;
    for (me, (o, _)) in discs.iter().enumerate() {
        let others: Vec<(Vec2, f64)> = discs
            .iter()
            .enumerate()
            .filter(|(k, _)| *k != me)
            .map(|(_, d)| *d)
            .collect();
        for heading in [0.0, 0.7] {
            grazing += assert_matches_oracle(&full(360, 10.0), *o, heading, &others, &walls);
        }
    }
    // Beams through a corner where two outlines meet may graze (none do).
    assert!(grazing <= 2, "{grazing} grazing beams");
}

#[test]
fn noise_moves_hits_only_and_stays_within_the_range() {
    let mut cfg = full(4, 10.0);
    cfg.noise = 0.1;
    let mut s = LaserScan::default();
    let mut calls = 0;
    let mut g = || {
        calls += 1;
        100.0
    };
    Scanner::new(Walls::new([])).scan(
        &mut s,
        &cfg,
        Vec2::zeros(),
        0.0,
        [(Vec2::new(3.0, 0.0), 0.5)],
        &mut g,
    );
    assert_eq!(calls, 1);
    assert_eq!(s.ranges[2], 10.0);
    assert!(s.ranges[0].is_infinite());
}

#[test]
fn a_robot_scans_the_others_and_not_itself_and_one_without_a_sensor_gets_none() {
    let text = r#"
        [world]
        arena = { min = [-5.0, -5.0], max = [5.0, 5.0] }
        [[robot]]
        name = "a"
        start = [0.0, 0.0]
        goal = [1.0, 0.0]
        planner = "homing"
        radius = 0.25
        sensor = { kind = "lidar", beams = 4, fov_deg = 360, range = 8.0 }
        [[robot]]
        name = "b"
        start = [2.0, 0.0]
        goal = [3.0, 0.0]
        planner = "homing"
        radius = 0.5
    "#;
    let sc = mrsim_scenario::parse(text, "inline.toml")
        .expect("scenario")
        .scenario;
    let bodies: Vec<mrsim_proto::BodyState> = sc
        .robots
        .iter()
        .enumerate()
        .map(|(i, r)| mrsim_proto::BodyState {
            id: i as u32,
            position: r.start,
            radius: r.radius,
            ..Default::default()
        })
        .collect();
    let mut scanner = Scanner::new(Walls::new(sc.all_walls()));
    let mut s = LaserScan::default();
    assert!(scanner.scan_robot(&mut s, 1, 0, 0, &sc.robots[0], &bodies, &[]));
    // Beams -pi, -pi/2, 0, pi/2: the arena at 5, b at 1.5 on beam 2.
    assert!((s.ranges[0] - 5.0).abs() < TOL, "{:?}", s.ranges);
    assert!((s.ranges[1] - 5.0).abs() < TOL);
    assert!((s.ranges[2] - 1.5).abs() < TOL);
    assert!((s.ranges[3] - 5.0).abs() < TOL);
    assert!(!scanner.scan_robot(&mut s, 1, 0, 1, &sc.robots[1], &bodies, &[]));
}

/// One beam along `heading` from `o` among `bodies`, range 10.
fn beam(o: Vec2, heading: f64, bodies: &[Body]) -> f64 {
    let mut cfg = full(1, 10.0);
    cfg.fov = 0.1;
    let mut s = LaserScan::default();
    Scanner::new(Walls::new([])).scan(
        &mut s,
        &cfg,
        o,
        heading,
        bodies.iter().copied(),
        &mut no_noise,
    );
    s.ranges[0]
}

fn rectangle(length: f64, width: f64) -> Shape {
    Shape::Polygon(Polygon::rectangle(length, width).expect("a rectangle"))
}

#[test]
fn a_rectangle_turned_30_degrees_reads_its_sides_not_its_disc() {
    // A 2 x 1 box centred at c = (4, 0), heading 30 degrees: its length
    // along u = (cos 30, sin 30) = (sqrt 3 / 2, 1 / 2), its width along
    // v = (-1 / 2, sqrt 3 / 2); it is the points c + a u + b v with
    // |a| <= 1 and |b| <= 1 / 2. Its circumscribed disc has radius
    // sqrt(1 + 1/4) = 1.118.
    let (deg30, c) = (PI / 6.0, Vec2::new(4.0, 0.0));
    let rect = Body {
        position: c,
        heading: deg30,
        shape: rectangle(2.0, 1.0),
    };
    let u = Vec2::new(deg30.cos(), deg30.sin());
    let v = Vec2::new(-deg30.sin(), deg30.cos());
    // From the origin along +x: the point (t, 0) is at a = (t - 4) sqrt 3 / 2,
    // b = -(t - 4) / 2; the box holds it from b = 1/2, t = 3 (a = -0.87,
    // within the length): the long side at 3, where the disc is met at
    // 4 - 1.118 = 2.882.
    let r = beam(Vec2::zeros(), 0.0, &[rect]);
    assert!((r - 3.0).abs() < TOL, "{r}");
    // From c - 3u along u (heading 30 degrees): the near end, a = -1, is
    // 3 - 1 = 2 away.
    let r = beam(c - 3.0 * u, deg30, &[rect]);
    assert!((r - 2.0).abs() < TOL, "{r}");
    // From c - 3v along v (heading 120 degrees): the long side b = -1/2 is
    // 3 - 1/2 = 2.5 away.
    let r = beam(c - 3.0 * v, deg30 + FRAC_PI_2, &[rect]);
    assert!((r - 2.5).abs() < TOL, "{r}");
    // Along u but 0.8 to its side (b = 0.8 > 1/2): past the box, though
    // 0.8 from the centre, within its disc.
    assert!(beam(c - 3.0 * u + 0.8 * v, deg30, &[rect]).is_infinite());
    // The same box unturned (heading 0), from the origin along +x: its
    // end x = 3.
    let flat = Body {
        heading: 0.0,
        ..rect
    };
    assert!((beam(Vec2::zeros(), 0.0, &[flat]) - 3.0).abs() < TOL);
    // And along +y from (4, -2): flat, its long side y = -1/2 at 1.5;
    // turned, the point (4, y) is at a = y / 2, b = y sqrt 3 / 2, which
    // the box holds from b = -1/2, y = -1 / sqrt 3: 2 - 0.577 away.
    assert!((beam(Vec2::new(4.0, -2.0), FRAC_PI_2, &[flat]) - 1.5).abs() < TOL);
    let r = beam(Vec2::new(4.0, -2.0), FRAC_PI_2, &[rect]);
    assert!((r - (2.0 - 1.0 / 3f64.sqrt())).abs() < TOL, "{r}");
}

#[test]
fn a_triangle_reads_its_edges_and_zero_from_inside() {
    // The triangle (0, 0), (2, 0), (0, 2) of its frame at (5, 0) turned a
    // quarter turn, (x, y) -> (5 - y, x): the world's (5, 0), (5, 2),
    // (3, 0), the region x <= 5, y >= 0, x - y >= 3 (the hypotenuse on
    // x - y = 3). Its disc about its origin (5, 0) has radius 2.
    let tri = Body {
        position: Vec2::new(5.0, 0.0),
        heading: FRAC_PI_2,
        shape: Shape::Polygon(
            Polygon::new(&[[0.0, 0.0], [2.0, 0.0], [0.0, 2.0]]).expect("a triangle"),
        ),
    };
    // From (0, 1) along +x: the hypotenuse at x = 1 + 3 = 4 (the disc
    // would be met at 5 - sqrt 3 = 3.27).
    let r = beam(Vec2::new(0.0, 1.0), 0.0, &[tri]);
    assert!((r - 4.0).abs() < TOL, "{r}");
    // From (8, 1) along -x: the side x = 5, 3 away.
    let r = beam(Vec2::new(8.0, 1.0), PI, &[tri]);
    assert!((r - 3.0).abs() < TOL, "{r}");
    // From (4, -2) along +y: the side y = 0, 2 away.
    let r = beam(Vec2::new(4.0, -2.0), FRAC_PI_2, &[tri]);
    assert!((r - 2.0).abs() < TOL, "{r}");
    // From (0, 1) at 45 degrees: the line x - y = -1, parallel to the
    // hypotenuse and outside it (the disc, 6 / sqrt 2 = 4.2 from its
    // centre, is passed by too).
    assert!(beam(Vec2::new(0.0, 1.0), PI / 4.0, &[tri]).is_infinite());
    // From (6, 3.5) heading -135 degrees, (-1, -1) / sqrt 2: the line
    // x - y = 2.5, just left of the hypotenuse: a miss, where the disc,
    // 2.5 / sqrt 2 = 1.77 from its centre, would be met.
    assert!(beam(Vec2::new(6.0, 3.5), -3.0 * PI / 4.0, &[tri]).is_infinite());
    // Inside, at (4.5, 0.5): every beam reads 0.
    let mut s = LaserScan::default();
    Scanner::new(Walls::new([])).scan(
        &mut s,
        &full(8, 5.0),
        Vec2::new(4.5, 0.5),
        0.0,
        [tri],
        &mut no_noise,
    );
    assert!(s.ranges.iter().all(|r| *r == 0.0), "{:?}", s.ranges);
}

/// Distance along the unit ray `p + t d` to the convex polygon `pts`
/// (counter-clockwise): 0 if `p` is inside, else the nearest edge crossed.
fn ray_polygon(p: Vec2, d: Vec2, pts: &[[f64; 2]]) -> Option<f64> {
    let n = pts.len();
    let at = |k: usize| Vec2::new(pts[k % n][0], pts[k % n][1]);
    let cross = |u: Vec2, v: Vec2| u.x * v.y - u.y * v.x;
    if (0..n).all(|k| cross(at(k + 1) - at(k), p - at(k)) >= 0.0) {
        return Some(0.0);
    }
    (0..n)
        .filter_map(|k| {
            ray_segment(
                p,
                d,
                &Segment {
                    a: at(k),
                    b: at(k + 1),
                },
            )
        })
        .reduce(f64::min)
}

#[test]
fn random_polygons_and_discs_read_what_the_exact_ray_tests_read() {
    let mut next = lcg(11);
    let o = Vec2::new(0.2, -0.1);
    // 10 bodies (one cast each) and 60 (through their hierarchy): discs,
    // rectangles and pentagons at random headings, none over the scanner.
    for n in [10, 60] {
        let bodies: Vec<Body> = (0..n)
            .map(|k| {
                let position = Vec2::new(7.0 * next(), 7.0 * next());
                let heading = PI * next();
                let shape = match k % 3 {
                    0 => Shape::disc(0.1 + 0.3 * next().abs()),
                    1 => rectangle(0.2 + 0.8 * next().abs(), 0.1 + 0.4 * next().abs()),
                    _ => {
                        let r = 0.2 + 0.4 * next().abs();
                        let pts: Vec<[f64; 2]> = (0..5)
                            .map(|i| {
                                let a = TAU * i as f64 / 5.0 + 0.3 * next();
                                [r * a.cos(), r * a.sin()]
                            })
                            .collect();
                        Shape::Polygon(Polygon::new(&pts).expect("a convex pentagon"))
                    }
                };
                Body {
                    position,
                    heading,
                    shape,
                }
            })
            .filter(|b| (b.position - o).norm() > b.shape.circumradius() + 0.05)
            .collect();
        let exact = |a: f64| {
            let d = Vec2::new(a.cos(), a.sin());
            let t = bodies
                .iter()
                .filter_map(|b| {
                    match b
                        .shape
                        .placed(Pose::new([b.position.x, b.position.y], b.heading))
                    {
                        Some(p) => ray_polygon(o, d, p.points()),
                        None => ray_disc(o, d, b.position, b.shape.circumradius()),
                    }
                })
                .fold(f64::INFINITY, f64::min);
            if t > 9.0 { f64::INFINITY } else { t }
        };
        let cfg = full(720, 9.0);
        let mut s = LaserScan::default();
        Scanner::new(Walls::new([])).scan(
            &mut s,
            &cfg,
            o,
            0.4,
            bodies.iter().copied(),
            &mut no_noise,
        );
        let (a0, inc) = cfg.angles();
        let close = |r: f64, e: f64| {
            (r.is_infinite() && e.is_infinite()) || (r - e).abs() <= TOL * e.max(1.0)
        };
        let (mut hits, mut grazing) = (0, 0);
        for (k, r) in s.ranges.iter().enumerate() {
            let a = 0.4 + a0 + inc * k as f64;
            let e = exact(a);
            hits += usize::from(e.is_finite());
            if close(*r, e) {
                continue;
            }
            let near = [-1e-5, 1e-5].iter().any(|da| close(*r, exact(a + da)));
            assert!(near, "{n} bodies, beam {k} at {a} rad: {r} vs exact {e}");
            grazing += 1;
        }
        assert!(grazing <= 2, "{grazing} grazing beams among {n} bodies");
        assert!(hits > 100, "only {hits} beams meet a body among {n}");
    }
}

#[test]
fn a_robot_scans_another_robots_rectangle_at_its_heading() {
    // Robot b is a 1 x 0.4 rectangle (radius sqrt(0.29) = 0.539) at
    // (2, 0): heading 0, its end x = 1.5 is 1.5 from a; turned a quarter
    // turn, its long side x = 2 - 0.2 is 1.8 away.
    let text = r#"
        [[robot]]
        name = "a"
        start = [0.0, 0.0]
        goal = [1.0, 0.0]
        planner = "homing"
        radius = 0.25
        sensor = { kind = "lidar", beams = 4, fov_deg = 360, range = 8.0 }
        [[robot]]
        name = "b"
        start = [2.0, 0.0]
        goal = [3.0, 0.0]
        planner = "homing"
        shape = { kind = "rectangle", length = 1.0, width = 0.4 }
    "#;
    let sc = mrsim_scenario::parse(text, "inline.toml")
        .expect("scenario")
        .scenario;
    let shapes = sc.body_shapes();
    let body = |heading: f64| {
        sc.robots
            .iter()
            .enumerate()
            .map(|(i, r)| mrsim_proto::BodyState {
                id: i as u32,
                position: r.start,
                radius: r.radius,
                heading: if i == 1 { heading } else { 0.0 },
                ..Default::default()
            })
            .collect::<Vec<_>>()
    };
    let mut scanner = Scanner::new(Walls::new(sc.all_walls()));
    let mut s = LaserScan::default();
    // Beam 2 of -pi, -pi/2, 0, pi/2 points at b.
    assert!(scanner.scan_robot(&mut s, 1, 0, 0, &sc.robots[0], &body(0.0), &shapes));
    assert!((s.ranges[2] - 1.5).abs() < TOL, "{:?}", s.ranges);
    assert!(scanner.scan_robot(&mut s, 1, 0, 0, &sc.robots[0], &body(FRAC_PI_2), &shapes));
    assert!((s.ranges[2] - 1.8).abs() < TOL, "{:?}", s.ranges);
    // Without the shapes, the disc around it: 2 - 0.539.
    assert!(scanner.scan_robot(&mut s, 1, 0, 0, &sc.robots[0], &body(FRAC_PI_2), &[]));
    assert!(
        (s.ranges[2] - (2.0 - 0.29f64.sqrt())).abs() < TOL,
        "{:?}",
        s.ranges
    );
}
