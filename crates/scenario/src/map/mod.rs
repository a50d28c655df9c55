//! Occupancy maps in ROS map_server's format: a YAML file that names an
//! image (PGM or PNG) and says how to read it.
//!
//! The YAML's keys are map_server's: `image` (relative to the YAML's folder
//! unless absolute), `resolution` (metres a pixel), `origin` (`[x, y, yaw]`,
//! the pose of the image's lower-left pixel), `negate`, `occupied_thresh`,
//! `free_thresh`, and optionally `mode` (`trinary`, the default, `scale` or
//! `raw`, in any case); other keys are ignored, as map_server ignores them.
//! Values are read as map_server's YAML library reads them: a number may be
//! quoted (`resolution: "0.05"`), `negate` is an integer or a boolean in
//! any of YAML 1.1's spellings (`true`, `no`, `On`, ...), and a leading
//! byte-order mark is skipped. Each pixel
//! becomes the value map_server would publish (nav2's `map_io`): the
//! channels' mean `shade` in [0, 1] (gray counts as three equal channels; in
//! trinary mode an alpha channel's opacity is averaged in), the occupancy
//! `p = 1 - shade` (`shade` with `negate`), then 100 (occupied) if
//! `p > occupied_thresh`, 0 (free) if `p < free_thresh`, else -1 (unknown)
//! in trinary mode, a value scaled into 0..100 in scale mode (where a
//! transparent pixel is unknown), and `round(shade * 255)` if in 0..=100
//! (else unknown) in raw mode.
//!
//! For the simulation a cell is a wall if its value is 100; an unknown cell
//! is a wall or free as the scenario's `[map] unknown` says (a wall by
//! default: nobody has seen what is there); any other value is free.
//! [`OccupancyMap::walls`] traces the walls' outlines into segments.

#[cfg(test)]
mod fuzz;
mod image;
mod trace;

use crate::types::UnknownCells;
use serde::Deserialize;
use serde_norway::Value;
use std::path::{Path, PathBuf};

/// Why a map was refused; each names the file it is about.
#[derive(Debug, thiserror::Error)]
pub enum MapError {
    /// A file could not be read.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What the OS said.
        source: std::io::Error,
    },
    /// The YAML file is not a valid map_server map description.
    #[error("{}: {reason}", path.display())]
    Yaml {
        /// The YAML file.
        path: PathBuf,
        /// Why.
        reason: String,
    },
    /// The image is not a PGM or PNG, or is damaged.
    #[error("{}: {reason}", path.display())]
    Image {
        /// The image file.
        path: PathBuf,
        /// Why.
        reason: String,
    },
}

/// How map_server turns pixels into occupancy values (the YAML's `mode`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum MapMode {
    /// Occupied, free or unknown by the thresholds (the default).
    #[default]
    Trinary,
    /// As trinary, but values between the thresholds are scaled into
    /// 0..100, and transparent pixels are unknown.
    Scale,
    /// The pixel's value itself, 0..=100, anything above it unknown.
    Raw,
}

/// A map's YAML file, checked.
#[derive(Debug, Clone, PartialEq)]
pub struct MapMeta {
    /// The image file, resolved against the YAML's folder.
    pub image: PathBuf,
    /// Metres a pixel, > 0.
    pub resolution: f64,
    /// Pose of the lower-left pixel: x, y (metres), yaw (radians,
    /// counter-clockwise).
    pub origin: [f64; 3],
    /// Dark is free and light occupied.
    pub negate: bool,
    /// Occupancy above which a pixel is occupied.
    pub occupied_thresh: f64,
    /// Occupancy below which a pixel is free.
    pub free_thresh: f64,
    /// How pixels become values.
    pub mode: MapMode,
}

/// A loaded map: its description and map_server's occupancy values.
#[derive(Debug, Clone, PartialEq)]
pub struct OccupancyMap {
    /// The YAML file it came from.
    pub yaml: PathBuf,
    /// What the YAML says.
    pub meta: MapMeta,
    /// Cells across (the image's width).
    pub width: usize,
    /// Cells up (the image's height).
    pub height: usize,
    /// map_server's values, row by row from the bottom row (as in a ROS
    /// `OccupancyGrid`): 100 occupied, 0 free, -1 unknown, or between.
    pub values: Vec<i8>,
}

/// The YAML as written; every key optional so that a missing one gets its
/// own message, and every value as YAML gave it: map_server (yaml-cpp's
/// `as<T>()`) converts a scalar whatever its quoting or style, so each is
/// converted here the same way (see [`number`] and [`negate`]).
#[derive(Deserialize)]
struct RawYaml {
    image: Option<Value>,
    resolution: Option<Value>,
    origin: Option<Vec<Value>>,
    negate: Option<Value>,
    occupied_thresh: Option<Value>,
    free_thresh: Option<Value>,
    mode: Option<Value>,
}

/// A scalar's text as yaml-cpp would see it: a string as written, a number
/// or boolean as YAML printed it; None for anything else.
fn scalar(v: &Value) -> Option<String> {
    match v {
        Value::String(s) => Some(s.clone()),
        Value::Number(n) => Some(n.to_string()),
        Value::Bool(b) => Some(b.to_string()),
        _ => None,
    }
}

/// A number as map_server reads one: a YAML number, or a string that reads
/// as one (`resolution: "0.05"`, which yaml-cpp's `as<double>()` takes).
fn number(v: &Value) -> Option<f64> {
    match v {
        Value::Number(n) => n.as_f64(),
        Value::String(s) => s.trim().parse().ok(),
        _ => None,
    }
}

/// `negate` as map_server reads it: an integer (non-zero is true), or
/// failing that one of YAML's booleans as yaml-cpp knows them (`true`,
/// `false`, `yes`, `no`, `on`, `off`, `y`, `n`, in lower, upper or title
/// case); None if it is neither.
fn negate(v: &Value) -> Option<bool> {
    if let Value::Bool(b) = v {
        return Some(*b);
    }
    if let Value::Number(n) = v {
        return n.as_i64().map(|n| n != 0);
    }
    let text = scalar(v)?;
    let text = text.trim();
    if let Ok(n) = text.parse::<i64>() {
        return Some(n != 0);
    }
    let lower = text.to_ascii_lowercase();
    let cased = [
        lower.clone(),
        lower.to_ascii_uppercase(),
        lower
            .chars()
            .enumerate()
            .map(|(k, c)| if k == 0 { c.to_ascii_uppercase() } else { c })
            .collect(),
    ];
    if !cased.iter().any(|c| c == text) {
        return None;
    }
    match lower.as_str() {
        "true" | "yes" | "on" | "y" => Some(true),
        "false" | "no" | "off" | "n" => Some(false),
        _ => None,
    }
}

/// Reads and checks a map's YAML (not its image).
pub fn load_meta(yaml: &Path) -> Result<MapMeta, MapError> {
    let text = std::fs::read_to_string(yaml).map_err(|source| MapError::Io {
        path: yaml.to_path_buf(),
        source,
    })?;
    parse_meta(&text, yaml)
}

/// Checks a map's YAML text; `yaml` is where it came from (for the image's
/// folder and the errors).
pub fn parse_meta(text: &str, yaml: &Path) -> Result<MapMeta, MapError> {
    let bad = |reason: String| MapError::Yaml {
        path: yaml.to_path_buf(),
        reason,
    };
    // yaml-cpp skips a byte-order mark (an editor's, on Windows) at the start.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let raw: RawYaml = serde_norway::from_str(text)
        .map_err(|e| bad(format!("not a map_server map description: {e}")))?;
    let need = |key: &str| {
        bad(format!(
            "missing `{key}` (map_server needs image, resolution, origin, negate, occupied_thresh and free_thresh)"
        ))
    };
    let shown = |v: &Value| {
        serde_norway::to_string(v)
            .map(|s| s.trim().to_string())
            .unwrap_or_else(|_| format!("{v:?}"))
    };
    let num = |key: &str, v: Option<Value>| -> Result<f64, MapError> {
        let v = v.ok_or_else(|| need(key))?;
        number(&v).ok_or_else(|| bad(format!("`{key}` must be a number, got {}", shown(&v))))
    };
    let image = raw.image.ok_or_else(|| need("image"))?;
    let image = match &image {
        Value::String(s) => s.clone(),
        other => scalar(other)
            .ok_or_else(|| bad(format!("`image` must be a file name, got {}", shown(other))))?,
    };
    if image.trim().is_empty() {
        return Err(bad("`image` is empty".into()));
    }
    let resolution = num("resolution", raw.resolution)?;
    if !(resolution.is_finite() && resolution > 0.0) {
        return Err(bad(format!(
            "resolution must be a finite number > 0 (metres a pixel), got {resolution}"
        )));
    }
    let origin = raw.origin.ok_or_else(|| need("origin"))?;
    let origin: Vec<f64> = origin
        .iter()
        .map(|v| {
            number(v).ok_or_else(|| {
                bad(format!(
                    "origin must be 3 numbers [x, y, yaw], got {} in it",
                    shown(v)
                ))
            })
        })
        .collect::<Result<_, _>>()?;
    let origin: [f64; 3] = origin.as_slice().try_into().map_err(|_| {
        bad(format!(
            "origin must have 3 elements [x, y, yaw], not {}",
            origin.len()
        ))
    })?;
    if !origin.iter().all(|x| x.is_finite()) {
        return Err(bad(format!(
            "origin must be finite numbers, got [{}, {}, {}]",
            origin[0], origin[1], origin[2]
        )));
    }
    let negate_value = raw.negate.ok_or_else(|| need("negate"))?;
    let negate = negate(&negate_value).ok_or_else(|| {
        bad(format!(
            "`negate` must be an integer (0: dark is occupied, else dark is free) or a \
             boolean, got {}",
            shown(&negate_value)
        ))
    })?;
    let occupied_thresh = num("occupied_thresh", raw.occupied_thresh)?;
    let free_thresh = num("free_thresh", raw.free_thresh)?;
    if !((0.0..=1.0).contains(&free_thresh)
        && (0.0..=1.0).contains(&occupied_thresh)
        && free_thresh <= occupied_thresh)
    {
        return Err(bad(format!(
            "thresholds must satisfy 0 <= free_thresh <= occupied_thresh <= 1, got \
             free_thresh {free_thresh}, occupied_thresh {occupied_thresh}"
        )));
    }
    // map_server reads the mode in any case (`Trinary`, `SCALE`).
    let mode_text = match &raw.mode {
        None => None,
        Some(v) => Some(scalar(v).ok_or_else(|| {
            bad(format!(
                "`mode` must be trinary, scale or raw, got {}",
                shown(v)
            ))
        })?),
    };
    let mode = match mode_text.as_deref().map(str::to_ascii_lowercase).as_deref() {
        None | Some("trinary") => MapMode::Trinary,
        Some("scale") => MapMode::Scale,
        Some("raw") => MapMode::Raw,
        Some(_) => {
            return Err(bad(format!(
                "unknown mode `{}`; expected trinary, scale or raw (in any case)",
                mode_text.unwrap_or_default()
            )));
        }
    };
    let image = Path::new(&image);
    let image = if image.is_absolute() {
        image.to_path_buf()
    } else {
        yaml.parent().unwrap_or(Path::new("")).join(image)
    };
    Ok(MapMeta {
        image,
        resolution,
        origin,
        negate,
        occupied_thresh,
        free_thresh,
        mode,
    })
}

/// Loads a map: its YAML, then its image.
pub fn load(yaml: &Path) -> Result<OccupancyMap, MapError> {
    let meta = load_meta(yaml)?;
    let bytes = std::fs::read(&meta.image).map_err(|source| MapError::Io {
        path: meta.image.clone(),
        source,
    })?;
    from_image(yaml, meta, &bytes)
}

/// A map from its checked YAML `meta` (read from `yaml`) and its image's
/// bytes.
fn from_image(yaml: &Path, meta: MapMeta, bytes: &[u8]) -> Result<OccupancyMap, MapError> {
    let pixels = image::decode(bytes).map_err(|reason| MapError::Image {
        path: meta.image.clone(),
        reason,
    })?;
    let (width, height) = (pixels.width, pixels.height);
    let mut values = vec![0i8; width * height];
    for y in 0..height {
        // Image row 0 is the map's top row.
        let row = &mut values[(height - 1 - y) * width..(height - y) * width];
        for (x, v) in row.iter_mut().enumerate() {
            *v = value(&meta, &pixels, pixels.pixel(x, y));
        }
    }
    Ok(OccupancyMap {
        yaml: yaml.to_path_buf(),
        meta,
        width,
        height,
        values,
    })
}

/// map_server's value of one pixel (nav2 `map_io::loadMapFromFile`).
fn value(meta: &MapMeta, pixels: &image::Pixels, px: &[u16]) -> i8 {
    let alpha = pixels.has_alpha().then(|| px[px.len() - 1]);
    let (r, g, b) = match px.len() {
        1 | 2 => (px[0], px[0], px[0]),
        _ => (px[0], px[1], px[2]),
    };
    let mut sum = f64::from(r) + f64::from(g) + f64::from(b);
    let mut n = 3.0;
    if let (MapMode::Trinary, Some(a)) = (meta.mode, alpha) {
        sum += f64::from(a);
        n += 1.0;
    }
    let shade = sum / n / f64::from(pixels.max);
    let occ = if meta.negate { shade } else { 1.0 - shade };
    let (occupied, free, unknown) = (100, 0, -1);
    match meta.mode {
        MapMode::Trinary => {
            if meta.occupied_thresh < occ {
                occupied
            } else if occ < meta.free_thresh {
                free
            } else {
                unknown
            }
        }
        MapMode::Scale => {
            if alpha.is_some_and(|a| a != pixels.max) {
                unknown
            } else if meta.occupied_thresh < occ {
                occupied
            } else if occ < meta.free_thresh {
                free
            } else {
                ((occ - meta.free_thresh) / (meta.occupied_thresh - meta.free_thresh) * 100.0)
                    .round_ties_even() as i8
            }
        }
        MapMode::Raw => {
            let v = (shade * 255.0).round();
            if (0.0..=100.0).contains(&v) {
                v as i8
            } else {
                unknown
            }
        }
    }
}

impl OccupancyMap {
    /// map_server's value of cell `(i, j)` (column, row from the bottom).
    pub fn value(&self, i: usize, j: usize) -> i8 {
        self.values[j * self.width + i]
    }

    /// Is cell `(i, j)` a wall, with unknown cells taken as `unknown` says?
    pub fn is_wall(&self, i: usize, j: usize, unknown: UnknownCells) -> bool {
        match self.value(i, j) {
            100 => true,
            -1 => unknown == UnknownCells::Occupied,
            _ => false,
        }
    }

    /// The walls' outlines as segments in metres, in the map's frame turned
    /// by `origin` (see the `trace` module: edges between wall and free
    /// cells, and the image's border, merged into maximal straight
    /// segments, free cells on each segment's left).
    pub fn walls(&self, unknown: UnknownCells) -> Vec<[[f64; 2]; 2]> {
        trace::outline(self.width, self.height, |i, j| self.is_wall(i, j, unknown))
            .into_iter()
            .map(|[a, b]| [self.to_world(a), self.to_world(b)])
            .collect()
    }

    /// The free regions: for each cell (row by row from the bottom), 0 if
    /// it is a wall (with unknown cells taken as `unknown` says), else the
    /// number of its region, the free cells joined to it through free
    /// cells sharing a side. Two free cells that touch only at a corner
    /// are not joined: their walls' outlines meet there, and nothing of
    /// any size passes between them.
    pub fn regions(&self, unknown: UnknownCells) -> Vec<u32> {
        let (w, h) = (self.width, self.height);
        let mut label = vec![0u32; w * h];
        let mut next = 0u32;
        let mut stack = Vec::new();
        for k in 0..w * h {
            if label[k] != 0 || self.is_wall(k % w, k / w, unknown) {
                continue;
            }
            next += 1;
            label[k] = next;
            stack.push(k);
            while let Some(c) = stack.pop() {
                let (i, j) = (c % w, c / w);
                let sides = [
                    (i > 0).then(|| c - 1),
                    (i + 1 < w).then(|| c + 1),
                    (j > 0).then(|| c - w),
                    (j + 1 < h).then(|| c + w),
                ];
                for n in sides.into_iter().flatten() {
                    if label[n] == 0 && !self.is_wall(n % w, n / w, unknown) {
                        label[n] = next;
                        stack.push(n);
                    }
                }
            }
        }
        label
    }

    /// A grid corner `[i, j]` in metres.
    fn to_world(&self, [i, j]: [u32; 2]) -> [f64; 2] {
        let res = self.meta.resolution;
        let [ox, oy, yaw] = self.meta.origin;
        let (x, y) = (f64::from(i) * res, f64::from(j) * res);
        if yaw == 0.0 {
            return [ox + x, oy + y];
        }
        let (s, c) = yaw.sin_cos();
        [ox + c * x - s * y, oy + s * x + c * y]
    }

    /// The cell a point (metres) lies in, or None outside the image.
    pub fn cell_of(&self, p: [f64; 2]) -> Option<(usize, usize)> {
        let [ox, oy, yaw] = self.meta.origin;
        let (dx, dy) = (p[0] - ox, p[1] - oy);
        let (x, y) = if yaw == 0.0 {
            (dx, dy)
        } else {
            let (s, c) = yaw.sin_cos();
            (c * dx + s * dy, -s * dx + c * dy)
        };
        let (i, j) = (
            (x / self.meta.resolution).floor(),
            (y / self.meta.resolution).floor(),
        );
        (i >= 0.0 && j >= 0.0 && i < self.width as f64 && j < self.height as f64)
            .then_some((i as usize, j as usize))
    }
}
