//! Admission: who drives which robot, and which commands count.
//!
//! A join gives the agent a random token; a command is accepted only if it
//! carries its robot's current token and answers the current tick, sent
//! after the tick was published (and, in realtime, before its deadline),
//! once, with a known kind and finite values. Everything here returns a
//! verdict and the events it caused; the caller records, logs and moves
//! the robots accordingly, so admission can be tested on its own.

use mrsim_proto::{CommandMsg, FixedStr, JoinReply, JoinRequest, PROTOCOL_VERSION, command_kind};

/// Who drives a robot.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Agent {
    /// No agent has joined for it yet.
    Waiting,
    /// Driven by process `pid`, whose commands carry `token`.
    Live {
        /// The agent's process.
        pid: u32,
        /// Its token.
        token: u64,
    },
    /// Its agent died or stalled; the robot brakes. The same agent may
    /// answer again (and rejoins), or a new one join.
    Lost {
        /// The agent's process.
        pid: u32,
        /// Its token, still honoured.
        token: u64,
    },
}

/// Something admission did that the run must record.
#[derive(Debug, Clone, PartialEq)]
pub enum Event {
    /// A first agent took robot `robot`.
    Joined {
        /// The robot.
        robot: usize,
        /// The agent's process.
        pid: u32,
    },
    /// An agent took up a robot whose agent was lost: by joining anew, or
    /// (`by_command`) the lost agent answering again.
    Rejoined {
        /// The robot.
        robot: usize,
        /// The agent's process.
        pid: u32,
        /// The lost agent answered again (rather than a new join).
        by_command: bool,
    },
    /// A join was refused.
    JoinRefused {
        /// The robot named in the request.
        robot: String,
        /// The asking process.
        pid: u32,
        /// Why (also in the reply).
        reason: String,
    },
    /// Robot `robot`'s agent was lost.
    Lost {
        /// The robot.
        robot: usize,
        /// The lost agent's process.
        pid: u32,
        /// Why.
        reason: String,
    },
}

/// What became of one command.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Verdict {
    /// It drives robot `robot` this tick. `rejoined`: its agent had been
    /// lost and is live again (process id).
    Accepted {
        /// The robot.
        robot: usize,
        /// The pid of a lost agent that answered again.
        rejoined: Option<u32>,
    },
    /// The agent of `robot` says it is ready.
    Ready {
        /// The robot.
        robot: usize,
    },
    /// It came after its tick's deadline: a miss, counted as late.
    Late {
        /// The robot.
        robot: usize,
    },
    /// Refused; `robot` is `None` when its id names no robot.
    Rejected {
        /// The robot named, if it is one.
        robot: Option<usize>,
        /// Why.
        reason: &'static str,
    },
}

/// The current tick as admission judges commands against it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TickWindow {
    /// The tick being answered.
    pub tick: u64,
    /// When its snapshot was published (CLOCK_MONOTONIC ns).
    pub published_ns: u64,
    /// Its deadline (realtime; `u64::MAX` in lockstep): a command sent
    /// after it is late even if the world, itself late, takes it in before
    /// it stops waiting.
    pub deadline_ns: u64,
    /// Realtime: an answer to the previous tick is late, not rejected.
    pub realtime: bool,
}

/// Why an answer to a tick before the previous one is rejected.
pub const PAST_TICK: &str = "command for a past tick";

/// The agent table and this tick's answers.
#[derive(Debug, Clone)]
pub struct Admission {
    agents: Vec<Agent>,
    /// The robots' names, for refusals.
    names: Vec<String>,
    /// Each name's robot: a join is found in O(1), not by a scan of every
    /// name (thousands of joins each scanning thousands of names).
    index: std::collections::HashMap<String, usize>,
    /// Agents that have said they are ready (setup read, planner built).
    pub ready: Vec<bool>,
    /// This tick's accepted command per robot.
    pub got: Vec<Option<CommandMsg>>,
    /// This tick's answer per robot was garbage (rejected; it brakes).
    pub garbage: Vec<bool>,
    world_pid: u32,
    /// The most robots one process may join as: what the transport's
    /// buffer for one process's commands holds (`None`: no such limit).
    room: Option<usize>,
}

fn splitmix(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    x ^ (x >> 31)
}

impl Admission {
    /// Robots called `names`, no agent yet; replies name `world_pid`.
    pub fn new(names: Vec<String>, world_pid: u32) -> Self {
        let n = names.len();
        Self {
            agents: vec![Agent::Waiting; n],
            index: names
                .iter()
                .enumerate()
                .rev()
                .map(|(i, n)| (n.clone(), i))
                .collect(),
            names,
            ready: vec![false; n],
            got: vec![None; n],
            garbage: vec![false; n],
            world_pid,
            room: None,
        }
    }

    /// The same, refusing a process that joins as more robots than `room`
    /// (the commands it sends at once would not all fit the buffer the
    /// world keeps for one process's commands).
    pub fn with_room(mut self, room: Option<usize>) -> Self {
        self.room = room;
        self
    }

    /// Every robot's agent.
    pub fn agents(&self) -> &[Agent] {
        &self.agents
    }

    /// Agents live now.
    pub fn live(&self) -> usize {
        self.agents
            .iter()
            .filter(|a| matches!(a, Agent::Live { .. }))
            .count()
    }

    /// Forgets this tick's answers.
    pub fn new_tick(&mut self) {
        self.got.iter_mut().for_each(|g| *g = None);
        self.garbage.iter_mut().for_each(|g| *g = false);
    }

    /// Answers a join request (`now_ns` seeds the token; `alive` says
    /// whether a process runs), with what it changed.
    pub fn join(
        &mut self,
        req: &JoinRequest,
        now_ns: u64,
        alive: impl Fn(u32) -> bool,
    ) -> (JoinReply, Vec<Event>) {
        let name = req.robot.as_str().to_string();
        let mut events = Vec::new();
        let world_pid = self.world_pid;
        let refuse = |reason: String| JoinReply {
            nonce: req.nonce,
            accepted: 0,
            robot_id: u32::MAX,
            token: 0,
            protocol_version: PROTOCOL_VERSION,
            world_pid,
            reason: FixedStr::new(&reason),
        };
        let accept = |i: usize, token: u64| JoinReply {
            nonce: req.nonce,
            accepted: 1,
            robot_id: i as u32,
            token,
            protocol_version: PROTOCOL_VERSION,
            world_pid,
            reason: FixedStr::default(),
        };
        let idx = self.index.get(&name).copied();
        let reply = if req.protocol_version != PROTOCOL_VERSION {
            refuse(format!(
                "protocol version {} refused: this world speaks version {PROTOCOL_VERSION}",
                req.protocol_version
            ))
        } else if let Some(room) = self.room.filter(|&r| req.group as usize > r) {
            refuse(format!(
                "process {} joins as {} robots; this world holds the commands of {room} \
                 robots from one process ([world] robots_per_agent)",
                req.pid, req.group
            ))
        } else if let Some(i) = idx {
            match self.agents[i] {
                Agent::Live { pid, .. } if pid != req.pid && alive(pid) => {
                    refuse(format!("robot `{name}` is already driven by process {pid}"))
                }
                // The same process asking again (its first reply was slow
                // and it re-asked): the same answer, not a second token the
                // agent would never see.
                Agent::Live { pid, token } if pid == req.pid => accept(i, token),
                previous => {
                    // A new process for a robot whose agent died before the
                    // periodic liveness check noticed: the loss first, so
                    // the events read lost, then rejoined.
                    if let Agent::Live { pid, .. } = previous {
                        events.extend(self.lose(i, format!("agent process {pid} died")));
                    }
                    let token =
                        splitmix(now_ns ^ ((req.pid as u64) << 32) ^ i as u64 ^ req.nonce) | 1;
                    let was_lost = matches!(self.agents[i], Agent::Lost { .. });
                    self.agents[i] = Agent::Live {
                        pid: req.pid,
                        token,
                    };
                    events.push(if was_lost {
                        Event::Rejoined {
                            robot: i,
                            pid: req.pid,
                            by_command: false,
                        }
                    } else {
                        Event::Joined {
                            robot: i,
                            pid: req.pid,
                        }
                    });
                    accept(i, token)
                }
            }
        } else {
            let known: Vec<&str> = self.names.iter().map(String::as_str).collect();
            let list = if known.len() > 12 {
                format!("{}, ... ({} robots)", known[..12].join(", "), known.len())
            } else {
                known.join(", ")
            };
            refuse(format!(
                "no robot named `{name}` in this run (robots: {list})"
            ))
        };
        if reply.accepted == 0 {
            events.push(Event::JoinRefused {
                robot: name,
                pid: req.pid,
                reason: reply.reason.as_str().to_string(),
            });
        }
        (reply, events)
    }

    /// Judges one command against the tick `now`.
    pub fn command(&mut self, cmd: &CommandMsg, now: TickWindow) -> Verdict {
        let i = cmd.robot_id as usize;
        let reject = |reason| Verdict::Rejected {
            robot: (i < self.agents.len()).then_some(i),
            reason,
        };
        if i >= self.agents.len() {
            return reject("no robot with this id");
        }
        let (owner_ok, was_lost, pid) = match self.agents[i] {
            Agent::Live { token, pid } => (token == cmd.token, false, pid),
            Agent::Lost { token, pid } => (token == cmd.token, true, pid),
            Agent::Waiting => (false, false, 0),
        };
        if !owner_ok {
            return reject("not sent by the agent that owns this robot");
        }
        if cmd.kind == command_kind::READY {
            self.ready[i] = true;
            return Verdict::Ready { robot: i };
        }
        if cmd.tick > now.tick {
            return reject("command for a future tick");
        }
        if cmd.tick < now.tick {
            if now.realtime && cmd.tick + 1 == now.tick {
                // Answered the previous tick after its deadline: already a miss.
                return Verdict::Late { robot: i };
            }
            return reject(PAST_TICK);
        }
        if cmd.sent_ns < now.published_ns {
            // Named this tick before the tick existed: a guess, not an answer.
            return reject("command for a future tick (sent before it was published)");
        }
        if self.got[i].is_some() {
            return reject("second command in one tick");
        }
        if cmd.sent_ns > now.deadline_ns {
            // Sent after this tick's deadline: a miss, however soon the
            // world looked.
            return Verdict::Late { robot: i };
        }
        if !matches!(
            cmd.kind,
            command_kind::FORCE
                | command_kind::VELOCITY
                | command_kind::UNICYCLE
                | command_kind::ACKERMANN
                | command_kind::NONE
                | command_kind::LOST
        ) {
            self.garbage[i] = true;
            return reject("unknown command kind");
        }
        if !cmd.value.iter().all(|v| v.is_finite()) {
            self.garbage[i] = true;
            return reject("non-finite command value (robot brakes)");
        }
        let rejoined = was_lost.then(|| {
            self.agents[i] = Agent::Live {
                pid,
                token: cmd.token,
            };
            pid
        });
        self.got[i] = Some(*cmd);
        Verdict::Accepted { robot: i, rejoined }
    }

    /// Marks robot `i`'s agent lost, if it is live.
    pub fn lose(&mut self, i: usize, reason: String) -> Option<Event> {
        let Agent::Live { pid, token } = self.agents[i] else {
            return None;
        };
        self.agents[i] = Agent::Lost { pid, token };
        Some(Event::Lost {
            robot: i,
            pid,
            reason,
        })
    }

    /// Live agents whose process is gone by `alive`, in robot order;
    /// agents of process `own` (threads of this one) are not looked at.
    /// Each process is looked at once, however many robots it drives.
    pub fn dead(&self, alive: impl Fn(u32) -> bool, own: u32) -> Vec<usize> {
        let mut seen = std::collections::HashMap::new();
        (0..self.agents.len())
            .filter(|&i| match self.agents[i] {
                Agent::Live { pid, .. } if pid != own => {
                    !*seen.entry(pid).or_insert_with(|| alive(pid))
                }
                _ => false,
            })
            .collect()
    }

    /// Live agents that have neither answered this tick nor sent garbage.
    pub fn silent(&self) -> Vec<usize> {
        (0..self.agents.len())
            .filter(|&i| {
                matches!(self.agents[i], Agent::Live { .. })
                    && self.got[i].is_none()
                    && !self.garbage[i]
            })
            .collect()
    }

    /// Some robot is still waiting for its first agent.
    pub fn any_waiting(&self) -> bool {
        self.agents.contains(&Agent::Waiting)
    }

    /// Robots without an agent, or whose agent is not ready yet.
    pub fn not_ready(&self) -> Vec<usize> {
        (0..self.agents.len())
            .filter(|&i| self.agents[i] == Agent::Waiting || !self.ready[i])
            .collect()
    }

    /// Every live agent has said it is ready.
    pub fn all_ready(&self) -> bool {
        self.agents
            .iter()
            .zip(&self.ready)
            .all(|(a, r)| !matches!(a, Agent::Live { .. }) || *r)
    }

    /// Every live agent has answered this tick: with a valid command, or
    /// with garbage (rejected; the robot brakes and the world moves on
    /// rather than waiting `stall_timeout` for an answer that came).
    pub fn all_answered(&self) -> bool {
        self.agents
            .iter()
            .zip(self.got.iter().zip(&self.garbage))
            .all(|(a, (g, bad))| !matches!(a, Agent::Live { .. }) || g.is_some() || *bad)
    }

    /// Every robot reached its goal (`reached`) or lost its agent.
    pub fn done(&self, reached: impl Fn(usize) -> bool) -> bool {
        (0..self.agents.len()).all(|i| reached(i) || matches!(self.agents[i], Agent::Lost { .. }))
    }
}
