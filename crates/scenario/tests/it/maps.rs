//! `[map]`: ROS map_server maps (YAML + PGM or PNG) read as map_server reads
//! them, traced into wall segments, and checked against the robots.

use mrsim_scenario::map::{self, MapError};
use mrsim_scenario::{ScenarioError, UnknownCells};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// A fresh, empty folder.
fn dir(tag: &str) -> PathBuf {
    static N: AtomicUsize = AtomicUsize::new(0);
    let d = std::env::temp_dir().join(format!(
        "mrsim-maps-{tag}-{}-{}",
        std::process::id(),
        N.fetch_add(1, Ordering::SeqCst)
    ));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("create test dir");
    d
}

/// A binary PGM of `rows` (top row first).
fn pgm(rows: &[&[u8]]) -> Vec<u8> {
    let mut out = format!("P5\n# test\n{} {}\n255\n", rows[0].len(), rows.len()).into_bytes();
    for r in rows {
        out.extend_from_slice(r);
    }
    out
}

/// A PNG of `width` x `height` with `channels` samples a pixel.
fn png_bytes(width: u32, height: u32, color: png::ColorType, data: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut enc = png::Encoder::new(&mut out, width, height);
    enc.set_color(color);
    enc.set_depth(png::BitDepth::Eight);
    let mut w = enc.write_header().expect("png header");
    w.write_image_data(data).expect("png data");
    w.finish().expect("png end");
    out
}

const YAML: &str = "image: room.pgm\nresolution: 0.5\norigin: [-1.0, 2.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";

/// Writes `yaml` as map.yaml and `image` as `name` in a fresh folder.
fn write_map(tag: &str, yaml: &str, name: &str, image: &[u8]) -> PathBuf {
    let d = dir(tag);
    std::fs::write(d.join("map.yaml"), yaml).unwrap();
    std::fs::write(d.join(name), image).unwrap();
    d.join("map.yaml")
}

const F: u8 = 254;
const O: u8 = 0;
const U: u8 = 205;

/// A 5 x 4 room: walls all round, 3 x 2 free cells inside.
fn room() -> Vec<u8> {
    pgm(&[
        &[O, O, O, O, O],
        &[O, F, F, F, O],
        &[O, F, F, F, O],
        &[O, O, O, O, O],
    ])
}

fn segments(m: &map::OccupancyMap, unknown: UnknownCells) -> BTreeSet<[[i64; 2]; 2]> {
    // In millimetres, to compare exactly.
    let mm = |p: [f64; 2]| {
        [
            (p[0] * 1000.0).round() as i64,
            (p[1] * 1000.0).round() as i64,
        ]
    };
    m.walls(unknown)
        .into_iter()
        .map(|[a, b]| [mm(a), mm(b)])
        .collect()
}

#[test]
fn a_walled_room_traces_to_its_four_inner_walls_at_the_origin_and_resolution() {
    let m = map::load(&write_map("room", YAML, "room.pgm", &room())).unwrap();
    assert_eq!((m.width, m.height), (5, 4));
    // Free cells span columns 1..4, rows 1..3 from the bottom: x -0.5..1.0,
    // y 2.5..3.5; counter-clockwise around the free space.
    let want: BTreeSet<_> = [
        [[-500, 2500], [1000, 2500]],
        [[1000, 2500], [1000, 3500]],
        [[1000, 3500], [-500, 3500]],
        [[-500, 3500], [-500, 2500]],
    ]
    .into_iter()
    .collect();
    assert_eq!(segments(&m, UnknownCells::Occupied), want);
}

#[test]
fn a_room_of_free_cells_to_the_image_border_is_closed_by_the_border() {
    let img = pgm(&[&[F, F], &[F, F]]);
    let m = map::load(&write_map("open", YAML, "room.pgm", &img)).unwrap();
    let s = segments(&m, UnknownCells::Occupied);
    assert_eq!(s.len(), 4, "{s:?}");
    assert!(s.contains(&[[-1000, 2000], [0, 2000]]), "{s:?}");
}

#[test]
fn a_pillar_is_a_clockwise_loop_inside_the_rooms_counter_clockwise_one() {
    let img = pgm(&[&[F, F, F], &[F, O, F], &[F, F, F]]);
    let m = map::load(&write_map("pillar", YAML, "room.pgm", &img)).unwrap();
    let walls = m.walls(UnknownCells::Occupied);
    assert_eq!(walls.len(), 8);
    // Free space on each segment's left: the pillar's cell centre (-0.25,
    // 2.75) is on the right of its four sides.
    let c = [-0.25, 2.75];
    let pillar: Vec<_> = walls
        .iter()
        .filter(|[a, b]| {
            let mid = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
            (mid[0] - c[0]).abs() <= 0.25 + 1e-9 && (mid[1] - c[1]).abs() <= 0.25 + 1e-9
        })
        .collect();
    assert_eq!(pillar.len(), 4);
    for [a, b] in pillar {
        let cross = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
        assert!(
            cross < 0.0,
            "pillar centre not on the right of {a:?} -> {b:?}"
        );
    }
}

#[test]
fn collinear_cell_edges_merge_into_one_segment_and_a_diagonal_touch_splits_them() {
    // A wall row 4 cells long gives one segment a side.
    let img = pgm(&[
        &[F, F, F, F, F, F],
        &[F, O, O, O, O, F],
        &[F, F, F, F, F, F],
    ]);
    let m = map::load(&write_map("merge", YAML, "room.pgm", &img)).unwrap();
    assert_eq!(m.walls(UnknownCells::Occupied).len(), 4 + 4);
    // Two wall cells touching at a corner: two separate squares.
    let img = pgm(&[&[F, F, F, F], &[F, O, F, F], &[F, F, O, F], &[F, F, F, F]]);
    let m = map::load(&write_map("diag", YAML, "room.pgm", &img)).unwrap();
    assert_eq!(m.walls(UnknownCells::Occupied).len(), 4 + 8);
}

#[test]
fn pixels_become_map_servers_values_by_the_thresholds() {
    // occ = 1 - v / 255: 89 -> 0.651 (occupied), 90 -> 0.647 (unknown),
    // 205 -> 0.196078 (unknown: not below 0.196), 206 -> 0.192 (free).
    let img = pgm(&[&[89, 90, 205, 206, 254]]);
    let m = map::load(&write_map("thresh", YAML, "room.pgm", &img)).unwrap();
    let v: Vec<i8> = (0..5).map(|i| m.value(i, 0)).collect();
    assert_eq!(v, [100, -1, -1, 0, 0]);
}

#[test]
fn negate_makes_dark_pixels_free() {
    let yaml = YAML.replace("negate: 0", "negate: 1");
    let img = pgm(&[&[0, 255, 205]]);
    let m = map::load(&write_map("negate", &yaml, "room.pgm", &img)).unwrap();
    // occ = v / 255: 0 free, 255 occupied, 205 -> 0.804 occupied.
    assert_eq!([m.value(0, 0), m.value(1, 0), m.value(2, 0)], [0, 100, 100]);
    let yaml = YAML.replace("negate: 0", "negate: true");
    let m = map::load(&write_map("negate-bool", &yaml, "room.pgm", &img)).unwrap();
    assert!(m.meta.negate);
}

#[test]
fn unknown_cells_are_walls_by_default_and_free_when_asked() {
    let img = pgm(&[&[F, F, F], &[F, U, F], &[F, F, F]]);
    let m = map::load(&write_map("unknown", YAML, "room.pgm", &img)).unwrap();
    assert_eq!(m.walls(UnknownCells::Occupied).len(), 8);
    assert_eq!(m.walls(UnknownCells::Free).len(), 4);
}

#[test]
fn image_row_zero_is_the_top_of_the_map() {
    // Wall in the top-left pixel: cell column 0, row 1 from the bottom.
    let img = pgm(&[&[O, F], &[F, F]]);
    let m = map::load(&write_map("top", YAML, "room.pgm", &img)).unwrap();
    assert_eq!(m.value(0, 1), 100);
    assert_eq!(m.value(0, 0), 0);
    assert_eq!(m.cell_of([-0.75, 2.75]), Some((0, 1)));
    assert_eq!(m.cell_of([-1.5, 2.75]), None);
}

#[test]
fn a_plain_p2_pgm_and_a_16_bit_pgm_read_like_the_binary_one() {
    let plain = b"P2\n# plain\n5 4\n255\n0 0 0 0 0\n0 254 254 254 0\n0 254 254 254 0\n0 0 0 0 0\n";
    let a = map::load(&write_map("p2", YAML, "room.pgm", plain)).unwrap();
    let b = map::load(&write_map("p5", YAML, "room.pgm", &room())).unwrap();
    assert_eq!(a.values, b.values);
    let mut wide = b"P5 5 4 65535\n".to_vec();
    for v in [
        0u8, 0, 0, 0, 0, 0, 254, 254, 254, 0, 0, 254, 254, 254, 0, 0, 0, 0, 0, 0,
    ] {
        wide.extend_from_slice(&(u16::from(v) * 257).to_be_bytes());
    }
    let c = map::load(&write_map("p5-16", YAML, "room.pgm", &wide)).unwrap();
    assert_eq!(c.values, b.values);
}

#[test]
fn a_gray_png_reads_like_the_pgm() {
    let gray: Vec<u8> = [O, O, O, O, O, O, F, F, F, O, O, F, F, F, O, O, O, O, O, O].to_vec();
    let png = png_bytes(5, 4, png::ColorType::Grayscale, &gray);
    let yaml = YAML.replace("room.pgm", "room.png");
    let a = map::load(&write_map("png", &yaml, "room.png", &png)).unwrap();
    let b = map::load(&write_map("pgm", YAML, "room.pgm", &room())).unwrap();
    assert_eq!(a.values, b.values);
}

#[test]
fn an_rgb_png_is_averaged_and_an_alpha_channel_counts_in_trinary_mode() {
    // (255, 0, 0): mean 85, occ 0.667 -> occupied; (255, 255, 0): mean 170,
    // occ 0.333 -> unknown.
    let rgb = [255, 0, 0, 255, 255, 0];
    let yaml = YAML.replace("room.pgm", "c.png");
    let m = map::load(&write_map(
        "rgb",
        &yaml,
        "c.png",
        &png_bytes(2, 1, png::ColorType::Rgb, &rgb),
    ))
    .unwrap();
    assert_eq!([m.value(0, 0), m.value(1, 0)], [100, -1]);
    // White but fully transparent: (255 * 3 + 0) / 4 = 191, occ 0.25 ->
    // unknown in trinary; transparent is unknown in scale mode too; opaque
    // white is free in both.
    let rgba = [255, 255, 255, 0, 255, 255, 255, 255];
    let png = png_bytes(2, 1, png::ColorType::Rgba, &rgba);
    let m = map::load(&write_map("rgba", &yaml, "c.png", &png)).unwrap();
    assert_eq!([m.value(0, 0), m.value(1, 0)], [-1, 0]);
    let scale = format!("{yaml}mode: scale\n");
    let m = map::load(&write_map("rgba-scale", &scale, "c.png", &png)).unwrap();
    assert_eq!([m.value(0, 0), m.value(1, 0)], [-1, 0]);
}

#[test]
fn scale_and_raw_modes_give_map_servers_values() {
    // Scale: occ between the thresholds is scaled into 0..100.
    let img = pgm(&[&[128, 0, 254]]);
    let yaml = format!("{YAML}mode: scale\n").replace("0.196", "0.25");
    let m = map::load(&write_map("scale", &yaml, "room.pgm", &img)).unwrap();
    // occ = 1 - 128/255 = 0.498: (0.498 - 0.25) / 0.4 * 100 = 62.
    assert_eq!([m.value(0, 0), m.value(1, 0), m.value(2, 0)], [62, 100, 0]);
    let yaml = format!("{YAML}mode: raw\n");
    let img = pgm(&[&[0, 100, 101, 255]]);
    let m = map::load(&write_map("raw", &yaml, "room.pgm", &img)).unwrap();
    let v: Vec<i8> = (0..4).map(|i| m.value(i, 0)).collect();
    assert_eq!(v, [0, 100, -1, -1]);
    // Only 100 is a wall.
    assert!(m.is_wall(1, 0, UnknownCells::Free));
    assert!(!m.is_wall(0, 0, UnknownCells::Occupied));
}

#[test]
fn a_turned_origin_turns_the_walls() {
    let yaml = YAML.replace("[-1.0, 2.0, 0.0]", "[1.0, 1.0, 1.5707963267948966]");
    let img = pgm(&[&[F, F]]);
    let m = map::load(&write_map("yaw", &yaml, "room.pgm", &img)).unwrap();
    let s = segments(&m, UnknownCells::Occupied);
    // The 1 m x 0.5 m strip turned a quarter round about (1, 1): x 0.5..1,
    // y 1..2.
    assert!(s.contains(&[[1000, 1000], [1000, 2000]]), "{s:?}");
    assert!(s.contains(&[[500, 2000], [500, 1000]]), "{s:?}");
    assert_eq!(m.cell_of([0.75, 1.75]), Some((1, 0)));
}

fn refused(tag: &str, yaml: &str, name: &str, image: &[u8]) -> String {
    let path = write_map(tag, yaml, name, image);
    match map::load(&path) {
        Ok(_) => panic!("accepted {}", path.display()),
        Err(e) => e.to_string(),
    }
}

/// Tag, YAML, image name, image bytes, file named and reason given.
type BadCase<'a> = (&'a str, String, &'a str, &'a [u8], &'a str, &'a str);

#[test]
fn bad_maps_are_refused_naming_the_file_and_the_reason() {
    let cases: [BadCase; 9] = [
        (
            "missing-image",
            YAML.replace("room.pgm", "nothere.pgm"),
            "room.pgm",
            &room(),
            "nothere.pgm",
            "No such file",
        ),
        (
            "zero-res",
            YAML.replace("resolution: 0.5", "resolution: 0"),
            "room.pgm",
            &room(),
            "map.yaml",
            "resolution must be a finite number > 0",
        ),
        (
            "neg-res",
            YAML.replace("resolution: 0.5", "resolution: -0.05"),
            "room.pgm",
            &room(),
            "map.yaml",
            "resolution must be",
        ),
        (
            "no-negate",
            YAML.replace("negate: 0\n", ""),
            "room.pgm",
            &room(),
            "map.yaml",
            "missing `negate`",
        ),
        (
            "origin-2",
            YAML.replace("[-1.0, 2.0, 0.0]", "[0, 0]"),
            "room.pgm",
            &room(),
            "map.yaml",
            "origin must have 3 elements",
        ),
        (
            "mode",
            format!("{YAML}mode: fancy\n"),
            "room.pgm",
            &room(),
            "map.yaml",
            "unknown mode `fancy`",
        ),
        (
            "thresholds",
            YAML.replace("0.65", "0.1"),
            "room.pgm",
            &room(),
            "map.yaml",
            "free_thresh <= occupied_thresh",
        ),
        (
            "header",
            YAML.to_string(),
            "room.pgm",
            b"P5\n5 x\n255\n",
            "room.pgm",
            "bad PGM header",
        ),
        (
            "short",
            YAML.to_string(),
            "room.pgm",
            b"P5\n5 4\n255\n\x00\x00",
            "room.pgm",
            "too short",
        ),
    ];
    for (tag, yaml, name, image, file, reason) in cases {
        let e = refused(tag, &yaml, name, image);
        assert!(e.contains(file), "{tag}: `{e}` does not name {file}");
        assert!(e.contains(reason), "{tag}: `{e}` lacks `{reason}`");
    }
    let e = refused("not-image", YAML, "room.pgm", b"GIF89a");
    assert!(e.contains("not a PGM (P5 or P2) or PNG"), "{e}");
    let e = refused("not-yaml", "image: [unclosed\n", "room.pgm", &room());
    assert!(
        e.contains("map.yaml") && e.contains("not a map_server map description"),
        "{e}"
    );
    assert!(matches!(
        map::load(Path::new("/nonexistent/map.yaml")),
        Err(MapError::Io { .. })
    ));
}

/// A scenario file next to the room map (5 x 4 cells of 0.5 m from (-1, 2):
/// free x -0.5..1.0, y 2.5..3.5).
fn scenario_with_room(tag: &str, robot: &str, map_extra: &str) -> (PathBuf, String) {
    let path = write_map(tag, YAML, "room.pgm", &room());
    let d = path.parent().unwrap().to_path_buf();
    let toml = format!(
        "[map]\nfile = \"map.yaml\"\n{map_extra}\n[[robot]]\nname = \"r0\"\nradius = 0.2\n{robot}\n"
    );
    let file = d.join("s.toml");
    std::fs::write(&file, &toml).unwrap();
    (file, toml)
}

#[test]
fn a_scenarios_map_adds_its_walls_relative_to_the_scenario_file() {
    let (file, _) = scenario_with_room("scn", "start = [0.0, 3.0]\ngoal = [0.5, 3.0]", "");
    let l = mrsim_scenario::load(&file).unwrap();
    let s = &l.scenario;
    assert_eq!(s.walls.len(), 4);
    let info = s.map.as_ref().expect("map info");
    assert_eq!(info.walls, 4);
    assert_eq!(info.size, [5, 4]);
    assert!(info.file.ends_with("map.yaml"));
    // The JSON of a scenario without a map has no `map` key.
    let json = serde_json::to_string(&mrsim_scenario::demo().scenario).unwrap();
    assert!(!json.contains("\"map\""));
}

#[test]
fn map_lengths_are_metres_converted_to_the_scenarios_unit() {
    let (file, toml) = scenario_with_room("cm", "start = [0.0, 300.0]\ngoal = [50.0, 300.0]", "");
    std::fs::write(&file, format!("length_unit = \"cm\"\n{toml}")).unwrap();
    let l = mrsim_scenario::load(&file).unwrap();
    let xs: BTreeSet<i64> = l
        .scenario
        .walls
        .iter()
        .flat_map(|w| w.segment)
        .map(|p| p[0].round() as i64)
        .collect();
    assert_eq!(xs, [-50, 100].into_iter().collect());
}

fn scenario_error(tag: &str, robot: &str) -> (ScenarioError, String) {
    let (file, toml) = scenario_with_room(tag, robot, "");
    let e = mrsim_scenario::load(&file).expect_err("refused");
    (e, toml)
}

#[test]
fn a_robot_starting_inside_a_wall_is_refused_naming_robot_map_and_line() {
    let (e, toml) = scenario_error("in-wall", "start = [-0.8, 3.0]\ngoal = [0.5, 3.0]");
    let shown = e.to_string();
    let line = toml.lines().position(|l| l.starts_with("start")).unwrap() + 1;
    assert_eq!(e.line(), Some(line), "{shown}");
    assert!(shown.contains("robot `r0`"), "{shown}");
    assert!(
        shown.contains("inside a wall of map") && shown.contains("map.yaml"),
        "{shown}"
    );
}

#[test]
fn a_goal_inside_a_wall_or_within_the_radius_of_one_is_refused() {
    let (e, _) = scenario_error("goal-wall", "start = [0.0, 3.0]\ngoal = [1.2, 3.0]");
    assert!(
        e.to_string().contains("goal [1.2, 3] is inside a wall"),
        "{e}"
    );
    let (e, _) = scenario_error("goal-near", "start = [0.0, 3.0]\ngoal = [0.9, 3.0]");
    assert!(e.to_string().contains("from a wall of map"), "{e}");
    assert!(e.to_string().contains("less than the radius 0.2"), "{e}");
    let (e, _) = scenario_error("outside", "start = [0.0, 3.0]\ngoal = [9.0, 3.0]");
    assert!(e.to_string().contains("outside map"), "{e}");
}

#[test]
fn a_bad_map_refuses_the_scenario_at_the_map_file_line() {
    let (file, toml) = scenario_with_room("bad-scn", "start = [0.0, 3.0]\ngoal = [0.5, 3.0]", "");
    std::fs::write(
        file.with_file_name("map.yaml"),
        YAML.replace("resolution: 0.5", "resolution: 0"),
    )
    .unwrap();
    let e = mrsim_scenario::load(&file).expect_err("refused");
    let line = toml.lines().position(|l| l.starts_with("file")).unwrap() + 1;
    assert_eq!(e.line(), Some(line), "{e}");
    assert!(
        e.to_string().contains("map.yaml: resolution must be"),
        "{e}"
    );
}

#[test]
fn unknown_and_file_keys_of_map_are_checked_and_unknown_keys_refused() {
    let (file, _) = scenario_with_room(
        "unk",
        "start = [0.0, 3.0]\ngoal = [0.5, 3.0]",
        "unknown = \"free\"",
    );
    let l = mrsim_scenario::load(&file).unwrap();
    assert_eq!(l.scenario.map.unwrap().unknown, UnknownCells::Free);
    let (file, _) = scenario_with_room(
        "unk-bad",
        "start = [0.0, 3.0]\ngoal = [0.5, 3.0]",
        "colour = 1",
    );
    let e = mrsim_scenario::load(&file).expect_err("refused");
    assert!(e.to_string().contains("unknown field `colour`"), "{e}");
    let (file, _) = scenario_with_room("override", "start = [0.0, 3.0]\ngoal = [0.5, 3.0]", "");
    let e =
        mrsim_scenario::load_with_overrides(&file, &[("map.file".into(), "\"gone.yaml\"".into())])
            .expect_err("refused");
    assert!(e.to_string().contains("gone.yaml"), "{e}");
}

#[test]
fn yaml_values_read_as_map_servers_yaml_library_reads_them() {
    let plain = map::load(&write_map("plain", YAML, "room.pgm", &room())).unwrap();
    // Quoted numbers, a mode in capitals, an origin of integers in block
    // style, a byte-order mark and Windows line ends: all read by map_server.
    let odd = "\u{feff}image: \"room.pgm\"\r\nresolution: \"0.5\"\r\norigin:\r\n  - -1\r\n  - 2\r\n  - 0\r\n\
               negate: \"0\"\r\noccupied_thresh: '0.65'\r\nfree_thresh: 0.196\r\nmode: TRINARY\r\n";
    let m = map::load(&write_map("odd", odd, "room.pgm", &room())).unwrap();
    assert_eq!(
        m.meta,
        map::MapMeta {
            image: m.meta.image.clone(),
            ..plain.meta.clone()
        }
    );
    assert_eq!(m.values, plain.values);
    // `negate` as yaml-cpp's booleans: dark becomes free.
    for (spelling, want) in [
        ("yes", true),
        ("On", true),
        ("Y", true),
        ("1", true),
        ("no", false),
        ("OFF", false),
        ("false", false),
        ("2", true),
    ] {
        let yaml = YAML.replace("negate: 0", &format!("negate: {spelling}"));
        let m = map::load(&write_map("neg", &yaml, "room.pgm", &room())).unwrap();
        assert_eq!(m.meta.negate, want, "negate: {spelling}");
    }
    let yaml = format!("{YAML}mode: Scale\n");
    let m = map::load(&write_map("scale-case", &yaml, "room.pgm", &room())).unwrap();
    assert_eq!(m.meta.mode, map::MapMode::Scale);
}

#[test]
fn yaml_values_map_server_cannot_read_are_refused_naming_the_key() {
    for (tag, from, to, reason) in [
        (
            "neg-word",
            "negate: 0",
            "negate: maybe",
            "`negate` must be an integer",
        ),
        (
            "neg-mixed",
            "negate: 0",
            "negate: yEs",
            "`negate` must be an integer",
        ),
        (
            "neg-float",
            "negate: 0",
            "negate: 0.5",
            "`negate` must be an integer",
        ),
        (
            "res-word",
            "resolution: 0.5",
            "resolution: fine",
            "`resolution` must be a number",
        ),
        (
            "origin-word",
            "[-1.0, 2.0, 0.0]",
            "[-1.0, north, 0.0]",
            "origin must be 3 numbers",
        ),
        (
            "thresh",
            "free_thresh: 0.196",
            "free_thresh: [0.1]",
            "`free_thresh` must be a number",
        ),
    ] {
        let e = refused(tag, &YAML.replace(from, to), "room.pgm", &room());
        assert!(e.contains("map.yaml") && e.contains(reason), "{tag}: {e}");
    }
}

/// A 7 x 4 map of 0.5 m from (-1, 2): two rooms of 2 x 2 free cells, x
/// -0.5..0.5 and 1.0..2.0, y 2.5..3.5, parted by a wall of `parting` cells.
fn two_rooms(parting: u8) -> Vec<u8> {
    pgm(&[
        &[O, O, O, O, O, O, O],
        &[O, F, F, parting, F, F, O],
        &[O, F, F, parting, F, F, O],
        &[O, O, O, O, O, O, O],
    ])
}

#[test]
fn a_goal_the_walls_shut_off_from_the_start_is_refused_at_its_line() {
    let scene = |tag: &str, parting: u8, map_extra: &str| {
        let path = write_map(tag, YAML, "room.pgm", &two_rooms(parting));
        let toml = format!(
            "[map]\nfile = \"map.yaml\"\n{map_extra}\n[[robot]]\nname = \"r0\"\nradius = 0.2\n\
             start = [0.0, 3.0]\ngoal = [1.5, 3.0]\n"
        );
        let file = path.with_file_name("s.toml");
        std::fs::write(&file, &toml).unwrap();
        (mrsim_scenario::load(&file), toml)
    };
    let (got, toml) = scene("shut", O, "");
    let e = got.expect_err("refused");
    let line = toml.lines().position(|l| l.starts_with("goal")).unwrap() + 1;
    assert_eq!(e.line(), Some(line), "{e}");
    let shown = e.to_string();
    for want in [
        "robot `r0`",
        "goal [1.5, 3] is shut off from the start [0, 3]",
        "map.yaml",
        "4 cells (1.00 m²)",
    ] {
        assert!(shown.contains(want), "no `{want}` in: {shown}");
    }
    // Unknown cells part the rooms too, unless the scenario says they are free.
    let (got, _) = scene("shut-unknown", U, "");
    let e = got.expect_err("refused");
    assert!(e.to_string().contains("unknown = \"free\""), "{e}");
    let (got, _) = scene("open-unknown", U, "unknown = \"free\"");
    assert!(got.is_ok(), "{:?}", got.err());
}

#[test]
fn free_cells_touching_only_at_a_corner_are_not_joined() {
    let img = pgm(&[&[F, O], &[O, F]]);
    let m = map::load(&write_map("corner", YAML, "room.pgm", &img)).unwrap();
    let r = m.regions(UnknownCells::Occupied);
    // Row by row from the bottom: (0,0) wall, (1,0) free, (0,1) free, (1,1) wall.
    assert_eq!(r[0], 0);
    assert_eq!(r[3], 0);
    assert!(r[1] != 0 && r[2] != 0 && r[1] != r[2], "{r:?}");
}

#[test]
fn a_16_bit_png_keeps_its_precision_at_the_thresholds() {
    // 0xCDFF / 0xFFFF: shade 0.8047, occupancy 0.1953 < 0.196: free. Cut to
    // its high byte (0xCD = 205: occupancy 0.196) it would be unknown.
    let mut out = Vec::new();
    let mut enc = png::Encoder::new(&mut out, 2, 1);
    enc.set_color(png::ColorType::Grayscale);
    enc.set_depth(png::BitDepth::Sixteen);
    let mut w = enc.write_header().expect("png header");
    w.write_image_data(&[0xCD, 0xFF, 0x00, 0x00])
        .expect("png data");
    w.finish().expect("png end");
    let yaml = YAML.replace("room.pgm", "deep.png");
    let m = map::load(&write_map("png16", &yaml, "deep.png", &out)).unwrap();
    assert_eq!([m.value(0, 0), m.value(1, 0)], [0, 100]);
    // A palette image reads as the colours its palette gives.
    let mut out = Vec::new();
    let mut enc = png::Encoder::new(&mut out, 2, 1);
    enc.set_color(png::ColorType::Indexed);
    enc.set_depth(png::BitDepth::Eight);
    enc.set_palette(vec![0, 0, 0, 254, 254, 254]);
    let mut w = enc.write_header().expect("png header");
    w.write_image_data(&[1, 0]).expect("png data");
    w.finish().expect("png end");
    let yaml = YAML.replace("room.pgm", "pal.png");
    let m = map::load(&write_map("palette", &yaml, "pal.png", &out)).unwrap();
    assert_eq!([m.value(0, 0), m.value(1, 0)], [0, 100]);
    // One bit a pixel: 1 is white.
    let mut out = Vec::new();
    let mut enc = png::Encoder::new(&mut out, 2, 1);
    enc.set_color(png::ColorType::Grayscale);
    enc.set_depth(png::BitDepth::One);
    let mut w = enc.write_header().expect("png header");
    w.write_image_data(&[0b1000_0000]).expect("png data");
    w.finish().expect("png end");
    let yaml = YAML.replace("room.pgm", "bits.png");
    let m = map::load(&write_map("one-bit", &yaml, "bits.png", &out)).unwrap();
    assert_eq!([m.value(0, 0), m.value(1, 0)], [0, 100]);
}
