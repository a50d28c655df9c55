//! `[[person]]`: its defaults, its route, its crowd model, and every bad
//! value refused at its line.

use crate::common::*;
use mrsim_scenario::{Behavior, PersonMotion, Reaction};

const PERSON: &str = r#"
[[person]]
name = "h0"
start = [4.0, 0.3]
goal = [-4.0, -0.3]
"#;

fn with_person(table: &str) -> String {
    format!("{BASE}{table}")
}

#[test]
fn a_person_takes_crowdnavs_defaults() {
    let l = accept(&with_person(PERSON));
    let p = &l.scenario.people[0];
    assert_eq!(p.waypoints, vec![[-4.0, -0.3]]);
    assert_eq!((p.radius, p.preferred_speed), (0.3, 1.0));
    assert!(p.sees_robots && !p.cyclic && p.group.is_none());
    assert_eq!(p.behavior, Behavior::Regular);
    assert_eq!(
        p.motion,
        PersonMotion::Orca {
            neighbor_dist: 10.0,
            max_neighbors: 10,
            time_horizon: 5.0,
            time_horizon_obst: 5.0,
            radius_margin: 0.0,
        }
    );
    assert_eq!(l.scenario.body_count(), 4);
    assert_eq!(l.scenario.body_names()[3], "h0");
}

#[test]
fn a_person_walks_cyclic_waypoints_with_its_own_orca_parameters() {
    let l = accept(&with_person(
        r#"
[[person]]
name = "h0"
start = [4.0, 0.3]
waypoints = [[-4.0, 0.0], [0.0, -4.0]]
cyclic = true
radius = 0.25
preferred_speed = 1.3
sees_robots = false
group = "g1"
motion = { model = "orca", neighbor_dist = 5.0, max_neighbors = 3, time_horizon = 2.0 }
"#,
    ));
    let p = &l.scenario.people[0];
    assert_eq!(p.waypoints, vec![[-4.0, 0.0], [0.0, -4.0]]);
    assert!(p.cyclic && !p.sees_robots);
    assert_eq!(p.group.as_deref(), Some("g1"));
    match p.motion {
        PersonMotion::Orca {
            neighbor_dist,
            max_neighbors,
            time_horizon,
            ..
        } => assert_eq!((neighbor_dist, max_neighbors, time_horizon), (5.0, 3, 2.0)),
        #[allow(unreachable_patterns)]
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_scenario_without_people_writes_no_people_key() {
    let l = accept(BASE);
    let json = serde_json::to_string(&l.scenario).unwrap();
    assert!(!json.contains("people"), "{json}");
}

#[test]
fn bad_person_values_are_refused_at_their_line() {
    let cases = [
        (
            "goal = [-4.0, -0.3]",
            "radius = -0.1\ngoal = [-4.0, -0.3]",
            "radius = -0.1",
            "radius must be > 0",
        ),
        (
            "goal = [-4.0, -0.3]",
            "goal = [-4.0, -0.3]\npreferred_speed = 0",
            "preferred_speed",
            "preferred_speed must be > 0",
        ),
        (
            "goal = [-4.0, -0.3]",
            "goal = [-4.0, -0.3]\nbehavior = \"bored\"",
            "bored",
            "unknown behavior `bored`",
        ),
        (
            "goal = [-4.0, -0.3]",
            "goal = [-4.0, -0.3]\nmotion = { model = \"rvo\" }",
            "rvo",
            "unknown crowd model `rvo`",
        ),
        (
            "goal = [-4.0, -0.3]",
            "goal = [-4.0, -0.3]\nmotion = { model = \"orca\", time_horizon = 0 }",
            "time_horizon = 0",
            "time_horizon must be > 0",
        ),
        (
            "goal = [-4.0, -0.3]",
            "goal = [-4.0, -0.3]\nmotion = { model = \"orca\", max_neighbors = -1 }",
            "max_neighbors",
            "max_neighbors must be >= 0",
        ),
        (
            "goal = [-4.0, -0.3]",
            "goal = [-4.0, -0.3]\ncyclic = true",
            "cyclic",
            "cyclic applies to `waypoints`",
        ),
        (
            "goal = [-4.0, -0.3]",
            "goal = [-4.0, -0.3]\nwaypoints = [[1.0, 1.0]]",
            "goal = [-4.0, -0.3]\nwaypoints",
            "not both",
        ),
        (
            "goal = [-4.0, -0.3]",
            "goal = [-4.0, -0.3]\ncolour = \"red\"",
            "colour",
            "unknown field `colour`",
        ),
        (
            "goal = [-4.0, -0.3]",
            "goal = [-40.0, -0.3]",
            "goal = [-40.0",
            "outside the arena",
        ),
    ];
    for (old, new, needle, words) in cases {
        let src = with(&with_person(PERSON), old, new);
        let e = refused_at(&src, needle, words);
        assert!(e.to_string().contains("person"), "{e}");
    }
}

#[test]
fn a_person_starting_on_a_robot_or_sharing_its_name_is_refused() {
    let src = with(
        &with_person(PERSON),
        "start = [4.0, 0.3]",
        "start = [0.1, 0.0]",
    );
    refused_at(&src, "start = [0.1, 0.0]", "starts overlapping robot `r0`");
    let src = with(&with_person(PERSON), "name = \"h0\"", "name = \"r1\"");
    refused_at(&src, "name = \"r1\"\nstart = [4.0", "duplicate name");
}

#[test]
fn a_person_without_a_goal_is_refused_at_its_table() {
    let src = with(&with_person(PERSON), "goal = [-4.0, -0.3]\n", "");
    refused_at(&src, "[[person]]", "missing `goal`");
}

const CROWD: &str = r#"
[[crowd]]
count = 5
pattern = "circle-crossing"
sees_robots = false
"#;

/// A scene of one robot from (0, -4) to (0, 4), as CrowdNav's, and `crowd`.
fn crowdnav(crowd: &str, seed: u64) -> String {
    format!(
        "[world]\nseed = {seed}\n\n[[robot]]\nname = \"robot\"\nstart = [0.0, -4.0]\n\
         goal = [0.0, 4.0]\nradius = 0.3\n{crowd}"
    )
}

#[test]
fn a_circle_crossing_crowd_is_crowdnavs_humans_drawn_from_the_seed() {
    let a = accept(&crowdnav(CROWD, 1)).scenario;
    let again = accept(&crowdnav(CROWD, 1)).scenario;
    let other = accept(&crowdnav(CROWD, 2)).scenario;
    assert_eq!(a.people, again.people);
    assert_ne!(a.people, other.people);
    assert_eq!(a.people.len(), 5);
    for (k, p) in a.people.iter().enumerate() {
        assert_eq!(p.name, format!("h{k}"));
        assert!(!p.sees_robots);
        // On the circle of 4 m, moved by at most 0.5 m in x and in y.
        let r = p.start[0].hypot(p.start[1]);
        assert!((r - 4.0).abs() <= 0.5f64.hypot(0.5), "{r}");
        // The goal is the start mirrored through the centre.
        assert_eq!(p.waypoints, vec![[-p.start[0], -p.start[1]]]);
        // Clear of the robot and of each other by CrowdNav's 0.2 m.
        let robot = [0.0, -4.0];
        assert!((p.start[0] - robot[0]).hypot(p.start[1] - robot[1]) >= 0.8);
        for q in &a.people[..k] {
            assert!((p.start[0] - q.start[0]).hypot(p.start[1] - q.start[1]) >= 0.8);
        }
    }
}

#[test]
fn square_crossing_and_flow_crowds_stay_in_their_areas() {
    let sq = accept(&crowdnav(
        "[[crowd]]\ncount = 8\npattern = \"square-crossing\"\nsquare_width = 10.0\n",
        3,
    ))
    .scenario;
    for p in &sq.people {
        let g = p.waypoints[0];
        // Start and goal on opposite halves of the square.
        assert!(p.start[0] * g[0] <= 0.0, "{:?} {g:?}", p.start);
        assert!(p.start[1].abs() <= 5.0 && g[1].abs() <= 5.0);
    }
    let flow = accept(&crowdnav(
        "[[crowd]]\ncount = 6\npattern = \"flow\"\narea = { min = [-5.0, -1.0], max = [5.0, 1.0] }\n",
        3,
    ))
    .scenario;
    for (k, p) in flow.people.iter().enumerate() {
        assert!(p.cyclic && p.waypoints.len() == 2);
        assert!(p.start[1].abs() <= 0.7, "{:?}", p.start);
        // The first half heads right first, the others left.
        assert_eq!(p.waypoints[0][0] > 0.0, k < 3, "{k}");
    }
}

#[test]
fn bad_crowd_values_are_refused_at_their_line() {
    let src = crowdnav(&CROWD.replace("count = 5", "count = 0"), 1);
    refused_at(&src, "count = 0", "count must be in 1..=");
    let src = crowdnav(&CROWD.replace("circle-crossing", "spiral"), 1);
    refused_at(&src, "spiral", "unknown pattern `spiral`");
    let src = crowdnav(&CROWD.replace("sees_robots = false", "radius = -1.0"), 1);
    refused_at(&src, "radius = -1.0", "radius must be > 0");
    let src = crowdnav(&format!("{CROWD}square_width = 3.0\n"), 1);
    refused_at(
        &src,
        "square_width",
        "does not apply to pattern `circle-crossing`",
    );
    let src = crowdnav(&CROWD.replace("count = 5", "count = 500"), 1);
    refused_at(&src, "[[crowd]]", "could not place person");
}

#[test]
fn a_behaviour_by_name_takes_hunavsims_defaults_and_a_table_its_own_values() {
    let named = |b: &str| {
        let src = with(
            &with_person(PERSON),
            "goal = [-4.0, -0.3]",
            &format!("goal = [-4.0, -0.3]\npreferred_speed = 1.2\nbehavior = {b}"),
        );
        accept(&src).scenario.people[0].behavior
    };
    let r = |detect_dist, duration| Reaction {
        detect_dist,
        duration,
        once: true,
    };
    assert_eq!(named("\"regular\""), Behavior::Regular);
    assert_eq!(named("\"impassive\""), Behavior::Impassive);
    assert_eq!(named("\"surprised\""), Behavior::Surprised(r(4.0, 30.0)));
    assert_eq!(
        named("\"scared\""),
        Behavior::Scared {
            reaction: r(3.0, 40.0),
            vel: 0.6,
            other_force_factor: 20.0
        }
    );
    assert_eq!(
        named("\"curious\""),
        Behavior::Curious {
            reaction: r(10.0, 40.0),
            vel: 1.2,
            stop_dist: 1.5
        }
    );
    assert_eq!(
        named("\"threatening\""),
        Behavior::Threatening {
            reaction: r(4.0, 40.0),
            vel: 2.0,
            front_dist: 1.4
        }
    );
    assert_eq!(
        named(
            "{ kind = \"scared\", detect_dist = 5.0, duration = 10.0, once = false, vel = 0.4, other_force_factor = 12.0 }"
        ),
        Behavior::Scared {
            reaction: Reaction {
                detect_dist: 5.0,
                duration: 10.0,
                once: false
            },
            vel: 0.4,
            other_force_factor: 12.0
        }
    );
    assert_eq!(
        named("{ kind = \"threatening\", front_dist = 2.0 }"),
        Behavior::Threatening {
            reaction: r(4.0, 40.0),
            vel: 2.0,
            front_dist: 2.0
        }
    );
}

#[test]
fn bad_behaviour_keys_are_refused_at_their_line() {
    let cases = [
        (
            "behavior = { vel = 1.0 }",
            "behavior = {",
            "behavior needs a `kind`",
        ),
        (
            "behavior = { kind = \"bored\" }",
            "\"bored\"",
            "unknown behavior `bored`",
        ),
        (
            "behavior = { kind = \"surprised\", vel = 1.0 }",
            "vel = 1.0",
            "`vel` does not apply to behavior `surprised`",
        ),
        (
            "behavior = { kind = \"regular\", duration = 3.0 }",
            "duration = 3.0",
            "it takes: no keys",
        ),
        (
            "behavior = { kind = \"scared\", vel = 0 }",
            "vel = 0",
            "vel must be > 0",
        ),
        (
            "behavior = { kind = \"curious\", stop_dist = -1.0 }",
            "stop_dist = -1.0",
            "stop_dist must be >= 0",
        ),
        (
            "behavior = { kind = \"scared\", fear = 2.0 }",
            "fear",
            "unknown field `fear`",
        ),
        (
            "behavior = 3",
            "behavior = 3",
            "a behaviour name or a table",
        ),
    ];
    for (line, needle, words) in cases {
        let src = with(
            &with_person(PERSON),
            "goal = [-4.0, -0.3]",
            &format!("goal = [-4.0, -0.3]\n{line}"),
        );
        let e = refused_at(&src, needle, words);
        assert!(e.to_string().contains("person"), "{e}");
    }
}

#[test]
fn people_and_crowds_are_reachable_with_overrides() {
    let sets = |pairs: &[(&str, &str)]| -> Vec<(String, String)> {
        pairs
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect()
    };
    let walker = "[[person]]\nname = \"p0\"\nstart = [0.0, 9.0]\ngoal = [0.0, 8.0]\n";
    let src = format!("{}{walker}", crowdnav(CROWD, 1));
    let l = mrsim_scenario::parse_with_overrides(
        &src,
        "t.toml",
        &sets(&[
            ("crowd.0.count", "3"),
            ("crowd.0.motion", "{ model = \"social-force\" }"),
            ("person.p0.preferred_speed", "1.4"),
            ("person.*.radius", "0.25"),
        ]),
    )
    .expect("the overrides apply");
    let people = &l.scenario.people;
    assert_eq!(people.len(), 4);
    let p0 = people.iter().find(|p| p.name == "p0").expect("p0");
    assert_eq!((p0.preferred_speed, p0.radius), (1.4, 0.25));
    assert!(
        people
            .iter()
            .filter(|p| p.name != "p0")
            .all(|p| matches!(p.motion, PersonMotion::SocialForce(_)))
    );
    for (key, said) in [
        ("crowd.1.count", "there is no crowd 1"),
        ("crowd.x.count", "`x` is not a crowd index"),
        ("person.nobody.radius", "no person named `nobody`"),
    ] {
        let e = mrsim_scenario::parse_with_overrides(&src, "t.toml", &sets(&[(key, "2")]))
            .expect_err(key)
            .to_string();
        assert!(e.contains(said), "{key}: {e}");
    }
}
