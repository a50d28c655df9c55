//! Bodies of other shapes in the world: rapier collides rectangles and
//! polygons as they are, a unicycle's rectangle turns with its heading,
//! contacts are counted at the true surfaces, and the gap every metric
//! takes agrees with parry's own distance and contact queries.

use mrsim_shape::{Polygon, Pose, Shape, gap};
use mrsim_world::physics::Owner;
use mrsim_world::{Applied, World};
use rapier2d::parry::query;
use rapier2d::parry::shape::{Ball, ConvexPolygon};
use rapier2d::prelude::{Pose as RPose, Vector};

fn world(src: &str) -> World {
    let loaded = mrsim_scenario::parse(src, "inline.toml").expect("valid scenario");
    World::new(&loaded.scenario).expect("world")
}

#[test]
fn rectangles_side_by_side_drive_past_each_other_without_contact() {
    // Two 0.9 x 0.6 AGVs 0.7 apart across their width (a 0.1 gap; their
    // circumscribed discs of 0.54 overlap by 0.38) drive along their
    // length: no contact, and they keep their gap.
    let src = "[world]\ndt = 0.1\nsubsteps = 10\nduration = 5.0\n\
               [defaults]\nshape = { kind = \"rectangle\", length = 0.9, width = 0.6 }\nmax_speed = 1.0\n\
               [[robot]]\nname = \"a\"\nstart = [0.0, 0.0]\ngoal = [5.0, 0.0]\n\
               [[robot]]\nname = \"b\"\nstart = [0.0, 0.7]\ngoal = [5.0, 0.7]\n";
    let mut w = world(src);
    let mut contacts = Vec::new();
    for _ in 0..20 {
        w.set_command(0, Applied::Velocity([1.0, 0.0]));
        w.set_command(1, Applied::Velocity([1.0, 0.0]));
        w.step(&mut contacts);
        assert!(contacts.is_empty(), "{contacts:?}");
    }
    let s = w.states();
    assert!(s[0].position[0] > 1.5);
    assert!((s[1].position[1] - s[0].position[1] - 0.7).abs() < 1e-5);
}

#[test]
fn a_rectangle_stops_on_another_at_its_true_surface_and_the_contact_is_counted() {
    // Nose to nose along x: 2 x 1 rectangles at 0 and 3 (a gap of 1); a
    // drives at b. They touch when a has gone 1, where the discs of 1.118
    // would have touched after 0.76.
    let src = "[world]\ndt = 0.1\nsubsteps = 10\nduration = 5.0\n\
               [defaults]\nshape = { kind = \"rectangle\", length = 2.0, width = 1.0 }\nmax_speed = 0.5\nmax_accel = 100.0\n\
               [[robot]]\nname = \"a\"\nstart = [0.0, 0.0]\ngoal = [5.0, 0.0]\n\
               [[obstacle]]\nname = \"b\"\nstart = [3.0, 0.0]\nshape = { kind = \"rectangle\", length = 2.0, width = 1.0 }\n";
    let mut w = world(src);
    let (mut contacts, mut first) = (Vec::new(), None);
    for t in 0..40 {
        w.set_command(0, Applied::Velocity([0.5, 0.0]));
        w.step(&mut contacts);
        if let Some(c) = contacts.first() {
            assert_eq!((c.a, c.b), (Owner::Robot(0), Owner::Obstacle(0)));
            first.get_or_insert((t, w.states()[0].position[0]));
        }
    }
    let (tick, x) = first.expect("a contact");
    // 1 m at 0.5 m/s: during the 20th tick.
    assert!((18..=20).contains(&tick), "tick {tick}");
    assert!((x - 1.0).abs() < 0.01, "x {x}");
    // Held against it, it never goes more than 1 mm in.
    assert!(w.states()[0].position[0] < 1.0 + 1e-3);
}

#[test]
fn a_unicycle_rectangle_turns_its_collider_with_its_heading() {
    // A 2 x 0.5 unicycle at the origin, facing its goal (+x), turns a
    // quarter in place; a wall at y = 0.8 is then 0.8 - 1.0 inside its
    // reach: it must be pushed off it, ending with its nose short of the
    // wall. Facing +x it reached only 0.25 in y.
    let src = "[world]\ndt = 0.1\nsubsteps = 10\nduration = 5.0\n\
               [[robot]]\nname = \"a\"\nstart = [0.0, 0.0]\ngoal = [5.0, 0.0]\nkinematics = \"unicycle\"\n\
               max_angular_speed = 1.0\nmax_angular_accel = 100.0\n\
               shape = { kind = \"rectangle\", length = 2.0, width = 0.5 }\n\
               [[wall]]\nsegment = [[-3.0, 1.2], [3.0, 1.2]]\n";
    let mut w = world(src);
    let mut contacts = Vec::new();
    let mut hit = false;
    for _ in 0..25 {
        let s = w.states()[0];
        let omega = if s.heading < std::f64::consts::FRAC_PI_2 {
            1.0
        } else {
            0.0
        };
        w.set_command(0, Applied::Unicycle([0.5, omega]));
        w.step(&mut contacts);
        hit |= contacts.iter().any(|c| matches!(c.b, Owner::Wall(_)));
    }
    let s = w.states()[0];
    // Its nose (1 ahead of the centre) is at the wall, not through it.
    let nose = s.position[1] + s.heading.sin();
    assert!(hit, "the turned rectangle reaches the wall");
    assert!(nose < 1.2 + 1e-3, "nose at {nose}");
    assert!(s.heading > 1.4, "heading {}", s.heading);
}

/// Our gap against parry's, for shapes built the world's way (f32).
fn parry_gap(a: &Shape, pa: Pose, b: &Shape, pb: Pose) -> f64 {
    let pose = |p: Pose| {
        RPose::new(
            Vector::new(p.position[0] as f32, p.position[1] as f32),
            p.heading as f32,
        )
    };
    let shape = |s: &Shape| -> Box<dyn rapier2d::parry::shape::Shape> {
        match s {
            Shape::Disc { radius } => Box::new(Ball::new(*radius as f32)),
            Shape::Polygon(p) => Box::new(
                ConvexPolygon::from_convex_polyline(
                    p.points()
                        .iter()
                        .map(|q| Vector::new(q[0] as f32, q[1] as f32))
                        .collect(),
                )
                .expect("convex"),
            ),
        }
    };
    let (ga, gb) = (shape(a), shape(b));
    match query::contact(&pose(pa), &*ga, &pose(pb), &*gb, 0.0).expect("supported") {
        Some(c) if c.dist <= 0.0 => c.dist as f64,
        _ => {
            query::distance(&pose(pa), &*ga, &pose(pb), &*gb)
                .expect("supported")
                .distance as f64
        }
    }
}

#[test]
fn the_gap_agrees_with_parry_for_rectangles_polygons_and_discs() {
    let mut x = 12345u64;
    let mut next = || {
        x = x
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (x >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut worst: f64 = 0.0;
    for _ in 0..2000 {
        let shape = |k: f64, next: &mut dyn FnMut() -> f64| -> Shape {
            if k < 0.2 {
                Shape::disc(0.1 + next())
            } else if k < 0.6 {
                Shape::Polygon(Polygon::rectangle(0.2 + 2.0 * next(), 0.2 + next()).unwrap())
            } else {
                let n = 3 + (next() * 6.0) as usize;
                let r = 0.2 + next();
                let pts: Vec<[f64; 2]> = (0..n)
                    .map(|i| {
                        let a = i as f64 * std::f64::consts::TAU / n as f64;
                        [r * a.cos(), 0.6 * r * a.sin()]
                    })
                    .collect();
                Shape::Polygon(Polygon::new(&pts).unwrap())
            }
        };
        let ka = next();
        let a = shape(ka, &mut next);
        let kb = next();
        let b = shape(kb, &mut next);
        let pa = Pose::new([4.0 * next() - 2.0, 4.0 * next() - 2.0], 6.0 * next());
        let pb = Pose::new([4.0 * next() - 2.0, 4.0 * next() - 2.0], 6.0 * next());
        let ours = gap(&a, pa, &b, pb);
        let theirs = parry_gap(&a, pa, &b, pb);
        worst = worst.max((ours - theirs).abs() / (1.0 + theirs.abs()));
    }
    // parry works in f32, and its GJK stops within about 1e-4 of the
    // distance of shapes a few metres apart: agreement to that.
    assert!(worst < 2e-4, "largest relative difference {worst}");
}
