//! A ROS 2 node on a Zenoh session, as rmw_zenoh makes one: a liveliness
//! token for the node and one for each publisher and subscriber; samples
//! under the topic's key expression with the 33-byte attachment.
//!
//! A transient-local publisher keeps its last `depth` samples for
//! subscribers that come later, as rmw_zenoh's does: rmw_zenoh
//! (`rmw_zenoh_cpp/src/detail/rmw_publisher_data.cpp` at commit
//! 3e19ec730c529035a648aec80c0ae0a056943b8c, `PublisherData::make`)
//! declares a Zenoh `AdvancedPublisher` with a cache of `depth` samples and
//! publisher detection, and its transient-local subscribers
//! (`rmw_subscription_data.cpp`, `SubscriptionData::init`) an
//! `AdvancedSubscriber` with history (`max_samples` = depth) that detects
//! late publishers. On the wire (zenoh-ext 1.10, `advanced_publisher.rs`,
//! `advanced_cache.rs`) that publisher is a queryable and a liveliness
//! token on `<key>/@adv/pub/<zid>/<eid>/_`, answering a query with the
//! cached samples under `<key>`; the subscriber queries `<key>/@adv/**`
//! when it starts and each publisher's key when its token appears. mrsim
//! declares the same queryable and token with the zenoh crate's stable API
//! (no zenoh-ext, whose advanced publisher needs zenoh's `unstable`
//! feature): what it cannot add is zenoh's source info (publisher id and
//! sequence number, an unstable API) on each sample, so a late subscriber
//! may be handed the cached sample twice (once per query) and there is no
//! miss-detection heartbeat.
//!
//! The session is a Zenoh peer that connects where it is told (a router,
//! `rmw_zenohd`, by default `tcp/localhost:7447` as rmw_zenoh's own
//! sessions do) with multicast scouting off, as in rmw_zenoh's
//! `DEFAULT_RMW_ZENOH_SESSION_CONFIG.json5`; a Zenoh config file replaces
//! all of that.

use crate::attachment::{Attachment, gid_of};
use crate::names::{EntityKind, MsgType, NodeInfo, Qos, endpoint_token, node_token, topic_key};
use std::collections::VecDeque;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::{SystemTime, UNIX_EPOCH};
use zenoh::Wait;
use zenoh::liveliness::LivelinessToken;
use zenoh::sample::Sample;

/// Where rmw_zenoh's sessions look for their router by default.
pub const DEFAULT_ROUTER: &str = "tcp/localhost:7447";

/// Why the node could not be set up or could not publish.
#[derive(Debug, thiserror::Error)]
pub enum NodeError {
    /// The Zenoh configuration was refused.
    #[error("zenoh config: {0}")]
    Config(String),
    /// The session did not open.
    #[error("cannot open a zenoh session to {endpoint}: {detail}")]
    Open {
        /// Where it tried to connect.
        endpoint: String,
        /// Zenoh's reason.
        detail: String,
    },
    /// A publisher, subscriber or token was refused.
    #[error("cannot declare the {what}: {detail}")]
    Declare {
        /// What.
        what: String,
        /// Zenoh's reason.
        detail: String,
    },
    /// A sample was not sent.
    #[error("cannot publish on {topic}: {detail}")]
    Put {
        /// The topic.
        topic: String,
        /// Zenoh's reason.
        detail: String,
    },
}

/// How to reach the ROS 2 side.
#[derive(Debug, Clone, Default)]
pub struct NodeOptions {
    /// ROS domain id.
    pub domain: u32,
    /// Connect to this Zenoh endpoint (default [`DEFAULT_ROUTER`]).
    pub connect: Option<String>,
    /// A Zenoh config file (then `connect` only if given).
    pub config_file: Option<PathBuf>,
    /// The node's name.
    pub name: String,
}

/// A node on its session.
pub struct Node {
    session: zenoh::Session,
    info: NodeInfo,
    next_id: u32,
    _token: LivelinessToken,
}

impl std::fmt::Debug for Node {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Node")
            .field("info", &self.info)
            .finish_non_exhaustive()
    }
}

fn declare_err(what: &str, e: impl std::fmt::Display) -> NodeError {
    NodeError::Declare {
        what: what.to_string(),
        detail: e.to_string(),
    }
}

/// The Zenoh config of `opts`.
pub fn config(opts: &NodeOptions) -> Result<zenoh::Config, NodeError> {
    let mut cfg = match &opts.config_file {
        Some(p) => zenoh::Config::from_file(p)
            .map_err(|e| NodeError::Config(format!("{}: {e}", p.display())))?,
        None => zenoh::Config::default(),
    };
    let mut set = |key: &str, value: &str| {
        cfg.insert_json5(key, value)
            .map_err(|e| NodeError::Config(format!("{key} = {value}: {e}")))
    };
    if opts.config_file.is_none() {
        set("mode", r#""peer""#)?;
        set("scouting/multicast/enabled", "false")?;
        set("listen/endpoints", "[]")?;
    }
    let endpoint = match (&opts.connect, &opts.config_file) {
        (Some(e), _) => Some(e.clone()),
        (None, None) => Some(DEFAULT_ROUTER.to_string()),
        (None, Some(_)) => None,
    };
    if let Some(e) = endpoint {
        let quoted = e.replace('\\', "\\\\").replace('"', "\\\"");
        set("connect/endpoints", &format!(r#"["{quoted}"]"#))?;
    }
    Ok(cfg)
}

/// The samples a transient-local publisher keeps: (payload, attachment),
/// the newest last.
type Cached = Arc<Mutex<VecDeque<(Vec<u8>, Vec<u8>)>>>;

/// A transient-local publisher's cache and what serves it.
struct Cache {
    samples: Cached,
    depth: usize,
    key: String,
    _queryable: zenoh::query::Queryable<()>,
    _token: LivelinessToken,
}

/// A publisher of one topic.
pub struct Publisher {
    publisher: zenoh::pubsub::Publisher<'static>,
    topic: String,
    seq: i64,
    gid: [u8; 16],
    token: String,
    cache: Option<Cache>,
    _token: LivelinessToken,
}

impl std::fmt::Debug for Publisher {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Publisher")
            .field("topic", &self.topic)
            .finish_non_exhaustive()
    }
}

impl Publisher {
    /// Publishes one CDR payload with the next attachment.
    pub fn put(&mut self, payload: Vec<u8>) -> Result<(), NodeError> {
        let now = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map(|d| i64::try_from(d.as_nanos()).unwrap_or(i64::MAX))
            .unwrap_or(0);
        let att = Attachment {
            sequence_number: self.seq,
            source_timestamp: now,
            gid: self.gid,
        };
        self.seq += 1;
        let att = att.encode().to_vec();
        if let Some(c) = &self.cache
            && let Ok(mut q) = c.samples.lock()
        {
            while q.len() >= c.depth {
                q.pop_front();
            }
            q.push_back((payload.clone(), att.clone()));
        }
        self.publisher
            .put(payload)
            .attachment(att)
            .wait()
            .map_err(|e| NodeError::Put {
                topic: self.topic.clone(),
                detail: e.to_string(),
            })
    }

    /// Its liveliness token's key expression.
    pub fn token(&self) -> &str {
        &self.token
    }

    /// Its GID (as its samples' attachments carry it).
    pub fn gid(&self) -> [u8; 16] {
        self.gid
    }

    /// A transient-local publisher's cache key expression
    /// (`<key>/@adv/pub/<zid>/<eid>/_`), where late subscribers query it and
    /// its cache's liveliness token sits; `None` for a volatile one.
    pub fn cache_key(&self) -> Option<&str> {
        self.cache.as_ref().map(|c| c.key.as_str())
    }
}

/// The key expression of a transient-local publisher's cache, as zenoh-ext
/// 1.10's `AdvancedPublisher` forms it (sequenced by number, no metadata):
/// `<key>/@adv/pub/<zid>/<eid>/_`.
pub fn cache_key(key: &str, zid: &str, eid: u32) -> String {
    format!("{key}/@adv/pub/{zid}/{eid}/_")
}

/// A subscriber: dropping it undeclares it.
pub struct Subscription {
    _sub: zenoh::pubsub::Subscriber<()>,
    token: String,
    _token: LivelinessToken,
}

impl std::fmt::Debug for Subscription {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Subscription")
            .field("token", &self.token)
            .finish_non_exhaustive()
    }
}

impl Subscription {
    /// Its liveliness token's key expression.
    pub fn token(&self) -> &str {
        &self.token
    }
}

/// What a subscription hands its callback: whether the sample came under
/// the expected type's key, its payload and its attachment (if any).
#[derive(Debug)]
pub struct Received<'a> {
    /// The sample's key expression.
    pub key: &'a str,
    /// True if the key names the subscribed type and hash; false for
    /// another type published under the same topic name.
    pub right_type: bool,
    /// The CDR payload.
    pub payload: Vec<u8>,
    /// The attachment, if the sample had one.
    pub attachment: Option<Vec<u8>>,
}

impl Node {
    /// Opens a session and declares the node (`name` in namespace `/`).
    pub fn open(opts: &NodeOptions) -> Result<Self, NodeError> {
        let cfg = config(opts)?;
        let session = zenoh::open(cfg).wait().map_err(|e| NodeError::Open {
            endpoint: opts
                .connect
                .clone()
                .unwrap_or_else(|| DEFAULT_ROUTER.to_string()),
            detail: e.to_string(),
        })?;
        let info = NodeInfo {
            domain: opts.domain,
            zid: session.zid().to_string(),
            nid: 0,
            namespace: "/".to_string(),
            name: opts.name.clone(),
        };
        let token = session
            .liveliness()
            .declare_token(node_token(&info))
            .wait()
            .map_err(|e| declare_err("node's liveliness token", e))?;
        Ok(Self {
            session,
            info,
            next_id: 1,
            _token: token,
        })
    }

    /// The node as its tokens name it.
    pub fn info(&self) -> &NodeInfo {
        &self.info
    }

    /// The node's liveliness token.
    pub fn token(&self) -> String {
        node_token(&self.info)
    }

    /// Declares a publisher of `topic` (fully qualified) of type `ty`.
    pub fn publisher(
        &mut self,
        topic: &str,
        ty: &MsgType,
        qos: Qos,
    ) -> Result<Publisher, NodeError> {
        let id = self.next_id;
        self.next_id += 1;
        let key = topic_key(self.info.domain, topic, ty);
        let token = endpoint_token(&self.info, id, EntityKind::Publisher, topic, ty, &qos);
        let publisher = self
            .session
            .declare_publisher(key.clone())
            .wait()
            .map_err(|e| declare_err(&format!("publisher of {topic}"), e))?;
        let cache = if qos.transient_local {
            Some(self.cache(&key, id, qos.depth.max(1) as usize, topic)?)
        } else {
            None
        };
        let lv = self
            .session
            .liveliness()
            .declare_token(token.clone())
            .wait()
            .map_err(|e| {
                declare_err(&format!("liveliness token of the publisher of {topic}"), e)
            })?;
        Ok(Publisher {
            publisher,
            topic: topic.to_string(),
            seq: 1,
            gid: gid_of(&token),
            token,
            cache,
            _token: lv,
        })
    }

    /// The cache of a transient-local publisher of `key` (entity `eid`):
    /// a queryable that answers with the kept samples under `key`, and a
    /// liveliness token by which subscribers detect it.
    fn cache(&self, key: &str, eid: u32, depth: usize, topic: &str) -> Result<Cache, NodeError> {
        let at = cache_key(key, &self.info.zid, eid);
        let samples: Cached = Arc::default();
        let kept = samples.clone();
        let reply_key = key.to_string();
        let queryable = self
            .session
            .declare_queryable(at.clone())
            .complete(true)
            .callback(move |q: zenoh::query::Query| {
                // Copied out: a reply may wait on the network, a put must not
                // wait on it.
                let Ok(all) = kept.lock().map(|q| q.clone()) else {
                    return;
                };
                for (payload, att) in all {
                    // A query that does not accept replies under another
                    // key than its own is refused by zenoh: nothing to do.
                    let _ = q.reply(reply_key.clone(), payload).attachment(att).wait();
                }
            })
            .wait()
            .map_err(|e| declare_err(&format!("cache of the publisher of {topic}"), e))?;
        let token = self
            .session
            .liveliness()
            .declare_token(at.clone())
            .wait()
            .map_err(|e| {
                declare_err(
                    &format!("liveliness token of the cache of the publisher of {topic}"),
                    e,
                )
            })?;
        Ok(Cache {
            samples,
            depth,
            key: at,
            _queryable: queryable,
            _token: token,
        })
    }

    /// Declares a subscriber of `topic` of type `ty`: `on` gets every
    /// sample under the topic's name, of this type or not (so one of
    /// another type is seen and counted, not silently missed).
    pub fn subscribe(
        &mut self,
        topic: &str,
        ty: &MsgType,
        qos: Qos,
        on: impl Fn(Received<'_>) + Send + Sync + 'static,
    ) -> Result<Subscription, NodeError> {
        let id = self.next_id;
        self.next_id += 1;
        let own = topic_key(self.info.domain, topic, ty);
        let name = topic.trim_matches('/');
        let any_type = format!("{}/{name}/*/*", self.info.domain);
        let token = endpoint_token(&self.info, id, EntityKind::Subscriber, topic, ty, &qos);
        let sub = self
            .session
            .declare_subscriber(any_type)
            .callback(move |s: Sample| {
                let key = s.key_expr().as_str();
                on(Received {
                    key,
                    right_type: key == own,
                    payload: s.payload().to_bytes().into_owned(),
                    attachment: s.attachment().map(|a| a.to_bytes().into_owned()),
                })
            })
            .wait()
            .map_err(|e| declare_err(&format!("subscriber of {topic}"), e))?;
        let lv = self
            .session
            .liveliness()
            .declare_token(token.clone())
            .wait()
            .map_err(|e| {
                declare_err(&format!("liveliness token of the subscriber of {topic}"), e)
            })?;
        Ok(Subscription {
            _sub: sub,
            token,
            _token: lv,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_node_connects_to_the_local_router_by_default_as_rmw_zenoh_does() {
        let cfg = config(&NodeOptions::default()).unwrap();
        assert!(
            cfg.get_json("connect/endpoints")
                .unwrap()
                .contains("tcp/localhost:7447")
        );
        assert!(cfg.get_json("mode").unwrap().contains("peer"));
        assert_eq!(cfg.get_json("scouting/multicast/enabled").unwrap(), "false");
    }

    #[test]
    fn a_transient_local_publishers_cache_sits_under_its_key_as_zenoh_ext_puts_it() {
        assert_eq!(
            cache_key(
                "0/map/nav_msgs::msg::dds_::OccupancyGrid_/RIHS01_ab",
                "1f2e",
                3
            ),
            "0/map/nav_msgs::msg::dds_::OccupancyGrid_/RIHS01_ab/@adv/pub/1f2e/3/_"
        );
    }

    #[test]
    fn a_missing_config_file_is_an_error_naming_it() {
        let opts = NodeOptions {
            config_file: Some("/nonexistent/zenoh.json5".into()),
            ..NodeOptions::default()
        };
        let e = config(&opts).unwrap_err().to_string();
        assert!(e.contains("/nonexistent/zenoh.json5"), "{e}");
    }
}
