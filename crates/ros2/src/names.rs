//! Names on the wire of rmw_zenoh: the key expression a topic's samples go
//! under, the message types' DDS names and RIHS01 hashes, and the
//! liveliness tokens that make a node and its publishers and subscribers
//! visible to `ros2 node list` and `ros2 topic list`.
//!
//! From rmw_zenoh (<https://github.com/ros2/rmw_zenoh>): `docs/design.md`
//! ("Topic and Service name mapping to Zenoh key expressions", "Graph
//! Cache"), `rmw_zenoh_cpp/src/detail/liveliness_utils.cpp` (`TopicInfo`:
//! `<domain>/<name without its leading and trailing slash>/<type>/<hash>`;
//! `Entity`: the token's chunks `@ros2_lv/<domain>/<zid>/<nid>/<id>/<kind>/
//! <enclave>/<namespace>/<node>[/<topic>/<type>/<hash>/<qos>]`, each name
//! with every `/` replaced by `%`, an empty one as `%`; `qos_to_keyexpr`:
//! the QoS chunk with a default component left empty) and
//! `rmw_zenoh_cpp/src/detail/type_support_common.cpp` (the type as
//! `<pkg>::msg::dds_::<Type>_`), read at the rolling branch, commit
//! bfc065f8c80cc3bc4d1963dc44ac5a472460903a (rmw_zenoh_cpp 0.2 series),
//! whose token layout and QoS encoding the later releases (0.6, Jazzy and
//! Kilted) keep.
//!
//! The RIHS01 hashes (REP 2016, "ROS 2 Interface Type Descriptions":
//! SHA-256 of the type description's canonical JSON) of the fixed set of
//! types mrsim uses are constants here; the Python tests check each against
//! the `rosbags` package's own computation from the message definitions.

/// A ROS 2 message type mrsim sends or takes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MsgType {
    /// The ROS name, `pkg/msg/Type`.
    pub ros: &'static str,
    /// Its RIHS01 type hash, `RIHS01_<64 hex digits>`.
    pub hash: &'static str,
}

impl MsgType {
    /// The DDS-mangled name rmw_zenoh puts in key expressions:
    /// `pkg::msg::dds_::Type_`.
    pub fn dds(&self) -> String {
        let mut parts = self.ros.rsplitn(2, '/');
        let name = parts.next().unwrap_or_default();
        let ns = parts.next().unwrap_or_default().replace('/', "::");
        format!("{ns}::dds_::{name}_")
    }
}

/// `geometry_msgs/msg/Twist`.
pub const TWIST: MsgType = MsgType {
    ros: "geometry_msgs/msg/Twist",
    hash: "RIHS01_9c45bf16fe0983d80e3cfe750d6835843d265a9a6c46bd2e609fcddde6fb8d2a",
};
/// `nav_msgs/msg/Odometry`.
pub const ODOMETRY: MsgType = MsgType {
    ros: "nav_msgs/msg/Odometry",
    hash: "RIHS01_3cc97dc7fb7502f8714462c526d369e35b603cfc34d946e3f2eda2766dfec6e0",
};
/// `sensor_msgs/msg/LaserScan`.
pub const LASER_SCAN: MsgType = MsgType {
    ros: "sensor_msgs/msg/LaserScan",
    hash: "RIHS01_64c191398013af96509d518dac71d5164f9382553fce5c1f8cca5be7924bd828",
};
/// `tf2_msgs/msg/TFMessage`.
pub const TF_MESSAGE: MsgType = MsgType {
    ros: "tf2_msgs/msg/TFMessage",
    hash: "RIHS01_e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087",
};
/// `rosgraph_msgs/msg/Clock`.
pub const CLOCK: MsgType = MsgType {
    ros: "rosgraph_msgs/msg/Clock",
    hash: "RIHS01_692f7a66e93a3c83e71765d033b60349ba68023a8c689a79e48078bcb5c58564",
};
/// `nav_msgs/msg/OccupancyGrid`.
pub const OCCUPANCY_GRID: MsgType = MsgType {
    ros: "nav_msgs/msg/OccupancyGrid",
    hash: "RIHS01_8d348150c12913a31ee0ec170fbf25089e4745d17035792a1ba94d6f0bc0cfc7",
};

/// Every type mrsim uses.
pub const ALL_TYPES: [MsgType; 6] = [
    TWIST,
    ODOMETRY,
    LASER_SCAN,
    TF_MESSAGE,
    CLOCK,
    OCCUPANCY_GRID,
];

/// The key expression of topic `name` (fully qualified, `/a0/odom`) of
/// type `ty` in `domain`: `<domain>/<name>/<type>/<hash>`, one leading and
/// one trailing `/` of the name dropped.
pub fn topic_key(domain: u32, name: &str, ty: &MsgType) -> String {
    let name = name.strip_prefix('/').unwrap_or(name);
    let name = name.strip_suffix('/').unwrap_or(name);
    format!("{domain}/{name}/{}/{}", ty.dds(), ty.hash)
}

/// A name in a liveliness token: every `/` as `%` (an empty name, or `/`,
/// is `%`).
pub fn mangle(name: &str) -> String {
    if name.is_empty() {
        return "%".to_string();
    }
    name.replace('/', "%")
}

/// `RMW_QOS_POLICY_RELIABILITY_BEST_EFFORT`.
pub const BEST_EFFORT: u8 = 2;
/// `RMW_QOS_POLICY_DURABILITY_TRANSIENT_LOCAL`.
pub const TRANSIENT_LOCAL: u8 = 1;

/// The QoS of a publisher or subscriber, as far as mrsim sets it: the rest
/// (history keep-last, infinite deadline, lifespan and lease, automatic
/// liveliness) is rmw_zenoh's default.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Qos {
    /// Best effort (`true`) or reliable (rmw_zenoh's default).
    pub best_effort: bool,
    /// Transient local (`true`) or volatile (the default).
    pub transient_local: bool,
    /// History depth (rmw_zenoh's default is 42).
    pub depth: u32,
}

impl Qos {
    /// Reliable, volatile, keep last `depth`.
    pub const fn reliable(depth: u32) -> Self {
        Self {
            best_effort: false,
            transient_local: false,
            depth,
        }
    }

    /// The token's QoS chunk: `<reliability>:<durability>:<history>,<depth>:
    /// <deadline s>,<ns>:<lifespan s>,<ns>:<liveliness>,<lease s>,<ns>`, a
    /// component left empty where it is rmw_zenoh's default.
    pub fn chunk(&self) -> String {
        let rel = if self.best_effort {
            BEST_EFFORT.to_string()
        } else {
            String::new()
        };
        let dur = if self.transient_local {
            TRANSIENT_LOCAL.to_string()
        } else {
            String::new()
        };
        let depth = if self.depth == 42 {
            String::new()
        } else {
            self.depth.to_string()
        };
        format!("{rel}:{dur}:,{depth}:,:,:,,")
    }
}

/// What a liveliness token declares.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EntityKind {
    /// A node (`NN`).
    Node,
    /// A publisher (`MP`).
    Publisher,
    /// A subscriber (`MS`).
    Subscriber,
}

impl EntityKind {
    fn code(self) -> &'static str {
        match self {
            EntityKind::Node => "NN",
            EntityKind::Publisher => "MP",
            EntityKind::Subscriber => "MS",
        }
    }
}

/// The node the tokens belong to.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NodeInfo {
    /// ROS domain id.
    pub domain: u32,
    /// The Zenoh session's id, as Zenoh prints it (lowercase hex).
    pub zid: String,
    /// The node's id within the session.
    pub nid: u32,
    /// The node's namespace (`/` for none).
    pub namespace: String,
    /// The node's name.
    pub name: String,
}

/// The liveliness token of the node itself.
pub fn node_token(node: &NodeInfo) -> String {
    format!(
        "@ros2_lv/{}/{}/{}/{}/{}/%/{}/{}",
        node.domain,
        node.zid,
        node.nid,
        node.nid,
        EntityKind::Node.code(),
        mangle(&node.namespace),
        mangle(&node.name)
    )
}

/// The liveliness token of a publisher or subscriber `id` of `node` on
/// topic `topic` (fully qualified) of type `ty`.
pub fn endpoint_token(
    node: &NodeInfo,
    id: u32,
    kind: EntityKind,
    topic: &str,
    ty: &MsgType,
    qos: &Qos,
) -> String {
    format!(
        "@ros2_lv/{}/{}/{}/{}/{}/%/{}/{}/{}/{}/{}/{}",
        node.domain,
        node.zid,
        node.nid,
        id,
        kind.code(),
        mangle(&node.namespace),
        mangle(&node.name),
        mangle(topic),
        ty.dds(),
        ty.hash,
        qos.chunk()
    )
}

/// The name of `topic` of `robot` under `prefix`: `/<prefix><robot>/<topic>`.
pub fn robot_topic(prefix: &str, robot: &str, topic: &str) -> String {
    let prefix = prefix.trim_matches('/');
    if prefix.is_empty() {
        format!("/{robot}/{topic}")
    } else {
        format!("/{prefix}/{robot}/{topic}")
    }
}

/// True if `name` is a valid ROS name token (a letter or `_`, then letters,
/// digits and `_`): what a robot's name must be to be a namespace.
pub fn is_ros_token(name: &str) -> bool {
    let mut chars = name.chars();
    matches!(chars.next(), Some(c) if c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

#[cfg(test)]
mod tests {
    use super::*;

    fn node() -> NodeInfo {
        NodeInfo {
            domain: 0,
            zid: "8b20917502ee955ac4476e0266340d5c".into(),
            nid: 0,
            namespace: "/".into(),
            name: "mrsim".into(),
        }
    }

    #[test]
    fn a_type_is_named_as_dds_names_it() {
        assert_eq!(TWIST.dds(), "geometry_msgs::msg::dds_::Twist_");
        assert_eq!(TF_MESSAGE.dds(), "tf2_msgs::msg::dds_::TFMessage_");
        for t in ALL_TYPES {
            assert_eq!(t.hash.len(), 71, "{}", t.ros);
            assert!(t.hash.starts_with("RIHS01_"));
        }
    }

    #[test]
    fn a_topic_key_is_domain_name_type_and_hash() {
        assert_eq!(
            topic_key(3, "/a0/cmd_vel", &TWIST),
            "3/a0/cmd_vel/geometry_msgs::msg::dds_::Twist_/\
             RIHS01_9c45bf16fe0983d80e3cfe750d6835843d265a9a6c46bd2e609fcddde6fb8d2a"
        );
        assert!(
            topic_key(0, "/clock", &CLOCK).starts_with("0/clock/rosgraph_msgs::msg::dds_::Clock_/")
        );
    }

    #[test]
    fn tokens_have_the_chunks_of_rmw_zenoh_in_order() {
        assert_eq!(
            node_token(&node()),
            "@ros2_lv/0/8b20917502ee955ac4476e0266340d5c/0/0/NN/%/%/mrsim"
        );
        // The design document's example of a publisher with depth 7.
        let t = endpoint_token(
            &node(),
            10,
            EntityKind::Publisher,
            "/chatter",
            &TWIST,
            &Qos::reliable(7),
        );
        assert_eq!(
            t,
            "@ros2_lv/0/8b20917502ee955ac4476e0266340d5c/0/10/MP/%/%/mrsim/%chatter/\
             geometry_msgs::msg::dds_::Twist_/\
             RIHS01_9c45bf16fe0983d80e3cfe750d6835843d265a9a6c46bd2e609fcddde6fb8d2a/::,7:,:,:,,"
        );
    }

    #[test]
    fn default_qos_components_are_left_empty() {
        assert_eq!(Qos::reliable(42).chunk(), "::,:,:,:,,");
        let q = Qos {
            best_effort: true,
            transient_local: true,
            depth: 1,
        };
        assert_eq!(q.chunk(), "2:1:,1:,:,:,,");
    }

    #[test]
    fn robot_topics_sit_under_the_prefix_and_the_robot() {
        assert_eq!(robot_topic("", "a0", "odom"), "/a0/odom");
        assert_eq!(robot_topic("/sim/", "a0", "odom"), "/sim/a0/odom");
        assert!(is_ros_token("a0") && is_ros_token("_r"));
        assert!(!is_ros_token("0a") && !is_ros_token("a-0") && !is_ros_token(""));
    }
}
