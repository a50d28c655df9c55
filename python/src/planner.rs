//! A planner written in Python, as a Rust [`Planner`]: the observation
//! handed to the Python object's `plan` as an [`PyObservation`] (numpy
//! arrays), its answer checked and turned into a command.
//!
//! `plan` may fail four ways: it raises, returns something that is not two
//! numbers, returns NaN or infinity, or takes longer than the limit. The
//! first and second panic with a message that says what happened (the
//! Python exception's text included); the third returns the non-finite
//! command. Either way the agents crate's guard (`plan_checked`) turns it
//! into a failure naming the robot and the tick, and an in-process lockstep
//! run stops with the outputs so far written. The fourth is the run's
//! watchdog's (`plan_timeout`), which stops the run while the call is still
//! running, so a `plan` that never returns does not hang it.

use mrsim_planners::{BodyKind, Command, Observation, Planner, Vec2};
use numpy::{PyArray1, PyArray2, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyList;

/// What a robot knows at one tick, as a Python planner sees it: its own
/// state, its goal, the bodies it senses (sensing range, field of view and
/// noise already applied) and the walls, as numpy arrays.
#[pyclass(name = "Observation", module = "mrsim._mrsim", frozen, get_all)]
pub struct PyObservation {
    /// Tick number.
    tick: u64,
    /// Simulated time, s.
    time: f64,
    /// Control period, s.
    dt: f64,
    /// The robot's index in the scenario.
    id: u32,
    /// Own position, (2,).
    position: Py<PyArray1<f64>>,
    /// Own velocity, (2,).
    velocity: Py<PyArray1<f64>>,
    /// Own radius.
    radius: f64,
    /// Own mass.
    mass: f64,
    /// Own damping.
    damping: f64,
    /// Top speed.
    max_speed: f64,
    /// Top acceleration.
    max_accel: f64,
    /// The goal, (2,).
    goal: Py<PyArray1<f64>>,
    /// Distance to the goal that counts as reached.
    goal_tolerance: f64,
    /// The sensed bodies' ids, (n,).
    others_id: Py<PyArray1<u32>>,
    /// Their positions, (n, 2).
    others_position: Py<PyArray2<f64>>,
    /// Their velocities, (n, 2).
    others_velocity: Py<PyArray2<f64>>,
    /// Their radii, (n,): a disc's own, a rectangle's or polygon's
    /// circumscribed one.
    others_radius: Py<PyArray1<f64>>,
    /// Their headings, rad, (n,): the x axis of each body's shape.
    others_heading: Py<PyArray1<f64>>,
    /// Their shapes in the world, a list of n arrays: a rectangle's or
    /// polygon's vertices at its pose, (k, 2) counter-clockwise; (0, 2) for
    /// a disc.
    others_vertices: Py<PyList>,
    /// Their kinds, (n,): 0 robot, 1 obstacle, 2 person (`mrsim.KINDS`
    /// names them).
    others_kind: Py<PyArray1<u8>>,
    /// Wall segments (the arena's included), (m, 4): x0, y0, x1, y1.
    walls: Py<PyArray2<f64>>,
    /// Own heading, rad (a unicycle's or a car's; 0 for a holonomic robot).
    heading: f64,
    /// Own turn rate, rad/s.
    angular_velocity: f64,
    /// Own steering angle, rad (a car's; 0 for the others).
    steering: f64,
    /// `"holonomic"`, `"unicycle"` or `"ackermann"` (a unicycle's velocity
    /// commands go through the look-ahead point controller, a car's
    /// through the tracking controller).
    kinematics: &'static str,
    /// A car's wheelbase (0 for the others).
    wheelbase: f64,
    /// A car's steering limit either way, rad (0 for the others).
    max_steering: f64,
    /// A car's steering-rate limit, rad/s (0 for the others).
    max_steering_rate: f64,
    /// A car's fastest speed backwards (0 for the others, and for a car
    /// that never reverses).
    max_reverse_speed: f64,
    /// The laser scan's ranges, (beams,), `inf` where no return; `None`
    /// without a `sensor`.
    scan_ranges: Option<Py<PyArray1<f64>>>,
    /// Angle of the first beam in the robot's frame, rad (0 without a scan).
    scan_angle_min: f64,
    /// Angle between beams, rad (0 without a scan).
    scan_angle_increment: f64,
}

/// A (rows, 2) or (rows, 4) array from a flat row-major vector.
fn rows<'py>(py: Python<'py>, flat: Vec<f64>, cols: usize) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let n = flat.len() / cols;
    PyArray1::from_vec(py, flat).reshape([n, cols])
}

fn pair(py: Python<'_>, v: Vec2) -> Py<PyArray1<f64>> {
    PyArray1::from_slice(py, &[v.x, v.y]).unbind()
}

impl PyObservation {
    /// The Python form of `obs`.
    pub fn new(py: Python<'_>, obs: &Observation) -> PyResult<Self> {
        let o = obs.others;
        let walls = obs.walls.iter().flat_map(|w| [w.a.x, w.a.y, w.b.x, w.b.y]);
        let car = mrsim_planners::ackermann::Car::of(&obs.me);
        Ok(Self {
            tick: obs.tick,
            time: obs.time,
            dt: obs.dt,
            id: obs.me.id,
            position: pair(py, obs.me.position),
            velocity: pair(py, obs.me.velocity),
            radius: obs.me.radius,
            mass: obs.me.mass,
            damping: obs.me.damping,
            max_speed: obs.me.max_speed,
            max_accel: obs.me.max_accel,
            goal: pair(py, obs.goal),
            goal_tolerance: obs.goal_tolerance,
            others_id: PyArray1::from_iter(py, o.iter().map(|s| s.id)).unbind(),
            others_position: rows(
                py,
                o.iter()
                    .flat_map(|s| [s.position.x, s.position.y])
                    .collect(),
                2,
            )?
            .unbind(),
            others_velocity: rows(
                py,
                o.iter()
                    .flat_map(|s| [s.velocity.x, s.velocity.y])
                    .collect(),
                2,
            )?
            .unbind(),
            others_radius: PyArray1::from_iter(py, o.iter().map(|s| s.radius)).unbind(),
            others_heading: PyArray1::from_iter(py, o.iter().map(|s| s.heading)).unbind(),
            others_vertices: PyList::new(
                py,
                o.iter()
                    .map(|s| {
                        let flat = s.placed().map_or_else(Vec::new, |p| p.points().concat());
                        rows(py, flat, 2)
                    })
                    .collect::<PyResult<Vec<_>>>()?,
            )?
            .unbind(),
            others_kind: PyArray1::from_iter(
                py,
                o.iter().map(|s| match s.kind {
                    BodyKind::Robot => 0u8,
                    BodyKind::Obstacle => 1,
                    BodyKind::Person => 2,
                }),
            )
            .unbind(),
            walls: rows(py, walls.collect(), 4)?.unbind(),
            heading: obs.me.heading,
            angular_velocity: obs.me.angular_velocity,
            steering: obs.me.steering,
            kinematics: match obs.me.kinematics {
                mrsim_planners::Kinematics::Holonomic => "holonomic",
                mrsim_planners::Kinematics::Unicycle { .. } => "unicycle",
                mrsim_planners::Kinematics::Ackermann { .. } => "ackermann",
            },
            wheelbase: car.map_or(0.0, |c| c.wheelbase),
            max_steering: car.map_or(0.0, |c| c.max_steering),
            max_steering_rate: car.map_or(0.0, |c| c.max_steering_rate),
            max_reverse_speed: car.map_or(0.0, |c| c.max_reverse_speed),
            scan_ranges: obs
                .scan
                .map(|s| PyArray1::from_slice(py, &s.ranges).unbind()),
            scan_angle_min: obs.scan.map_or(0.0, |s| s.angle_min),
            scan_angle_increment: obs.scan.map_or(0.0, |s| s.angle_increment),
        })
    }
}

#[pymethods]
impl PyObservation {
    fn __repr__(&self, py: Python<'_>) -> String {
        format!(
            "Observation(tick={}, time={:.3}, id={}, others={})",
            self.tick,
            self.time,
            self.id,
            PyUntypedArrayMethods::len(self.others_radius.bind(py))
        )
    }
}

/// What a Python planner's two numbers are: its class attribute `command`
/// (`"force"`, `"velocity"`, the default, or `"ackermann"`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// Forces, N.
    Force,
    /// Velocities, m/s.
    Velocity,
    /// A car's speed along its heading and steering angle, rad
    /// ([`Command::Ackermann`]; any other robot brakes).
    Ackermann,
}

impl Kind {
    /// The kind named `name`; an error naming the bad value.
    pub fn named(name: &str) -> PyResult<Self> {
        match name {
            "velocity" => Ok(Kind::Velocity),
            "force" => Ok(Kind::Force),
            "ackermann" => Ok(Kind::Ackermann),
            other => Err(pyo3::exceptions::PyValueError::new_err(format!(
                "a command is \"velocity\", \"force\" or \"ackermann\", not {other:?}"
            ))),
        }
    }

    /// The kind `planner` declares.
    pub fn of(planner: &Bound<'_, PyAny>) -> PyResult<Self> {
        match planner.getattr("command") {
            Err(_) => Ok(Kind::Velocity),
            Ok(v) => Self::named(v.extract::<String>()?.as_str()),
        }
    }

    /// The command of two numbers of this kind.
    pub fn command(self, v: [f64; 2]) -> Command {
        match self {
            Kind::Force => Command::Force(Vec2::new(v[0], v[1])),
            Kind::Velocity => Command::Velocity(Vec2::new(v[0], v[1])),
            Kind::Ackermann => Command::Ackermann {
                speed: v[0],
                steering: v[1],
            },
        }
    }
}

/// Two numbers from a planner's answer, or why not.
pub fn two_numbers(answer: &Bound<'_, PyAny>) -> Result<[f64; 2], String> {
    let shape = || {
        format!(
            "plan returned {}, expected two numbers (x, y)",
            answer
                .repr()
                .map(|r| r.to_string())
                .unwrap_or_else(|_| "an unprintable value".into())
        )
    };
    let v: Vec<f64> = answer.extract().map_err(|_| shape())?;
    match v[..] {
        [x, y] => Ok([x, y]),
        _ => Err(shape()),
    }
}

/// The text of a Python exception, with its type.
pub fn describe(py: Python<'_>, e: &PyErr) -> String {
    let ty = e
        .get_type(py)
        .name()
        .map(|n| n.to_string())
        .unwrap_or_else(|_| "Exception".into());
    format!("{ty}: {}", e.value(py))
}

/// How every message of a Python planner's failure begins.
const FAILED: &str = "the Python planner";

/// Keeps the panic hook from printing a Python planner's failure (with a
/// backtrace) to stderr: it is not a bug of mrsim, and the run's error
/// carries the message. Other panics print as before. Installed once.
pub fn quiet_planner_panics() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            let ours = info
                .payload()
                .downcast_ref::<String>()
                .is_some_and(|m| m.starts_with(FAILED));
            if !ours {
                previous(info);
            }
        }));
    });
}

/// A Python object with a `plan(observation)` method, as a [`Planner`].
pub struct PyPlanner {
    object: Py<PyAny>,
    kind: Kind,
}

impl PyPlanner {
    /// Wraps `object` (its `command` attribute read now); refuses one
    /// without a callable `plan`.
    pub fn new(object: Bound<'_, PyAny>) -> PyResult<Self> {
        let callable = object
            .getattr("plan")
            .map(|p| p.is_callable())
            .unwrap_or(false);
        if !callable {
            return Err(pyo3::exceptions::PyTypeError::new_err(format!(
                "{} has no plan(observation) method",
                object
                    .get_type()
                    .name()
                    .map(|n| n.to_string())
                    .unwrap_or_else(|_| "the planner".into())
            )));
        }
        Ok(Self {
            kind: Kind::of(&object)?,
            object: object.unbind(),
        })
    }
}

impl Planner for PyPlanner {
    fn plan(&mut self, obs: &Observation) -> Command {
        let answer = Python::attach(|py| -> Result<[f64; 2], String> {
            let o = PyObservation::new(py, obs)
                .map_err(|e| format!("{FAILED}: {}", describe(py, &e)))?;
            let r = self
                .object
                .bind(py)
                .call_method1("plan", (o,))
                .map_err(|e| format!("{FAILED} raised {}", describe(py, &e)))?;
            two_numbers(&r).map_err(|e| format!("{FAILED}: {e}"))
        });
        let v = match answer {
            Ok(v) => v,
            // The guard around every plan call turns this into an error
            // naming the robot and the tick.
            Err(msg) => std::panic::panic_any(msg),
        };
        self.kind.command(v)
    }

    /// A planner of a car's own commands sees the car itself, not the
    /// tracking controller's enlarged disc.
    fn native_ackermann(&self) -> bool {
        self.kind == Kind::Ackermann
    }
}
