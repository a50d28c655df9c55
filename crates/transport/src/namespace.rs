//! Per-run isolation: every run gets its own iceoryx2 prefix and root path,
//! derived from its run id, so two runs (or tests in parallel) never see
//! each other and a run's leftovers can be found and removed.

use std::path::PathBuf;

/// A run's namespace.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Namespace {
    run_id: String,
}

/// Why a run id was refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum NamespaceError {
    /// Empty, too long, or with characters other than `a-z 0-9 -`.
    #[error("run id `{0}` must be 1-24 characters of a-z, 0-9 and '-'")]
    BadRunId(String),
}

impl Namespace {
    /// The namespace of run `run_id`.
    pub fn new(run_id: &str) -> Result<Self, NamespaceError> {
        let ok = !run_id.is_empty()
            && run_id.len() <= 24
            && run_id
                .bytes()
                .all(|b| b.is_ascii_lowercase() || b.is_ascii_digit() || b == b'-');
        if ok {
            Ok(Self {
                run_id: run_id.to_string(),
            })
        } else {
            Err(NamespaceError::BadRunId(run_id.to_string()))
        }
    }

    /// A fresh, unique run id: process id and clock, base 36.
    pub fn fresh_run_id() -> String {
        let t = mrsim_proto::now_ns() ^ (std::process::id() as u64).rotate_left(40);
        let mut n = t;
        let mut s = String::new();
        while n > 0 && s.len() < 10 {
            let d = (n % 36) as u32;
            s.push(char::from_digit(d, 36).unwrap_or('0'));
            n /= 36;
        }
        format!("r{s}")
    }

    /// The run id.
    pub fn run_id(&self) -> &str {
        &self.run_id
    }

    /// The iceoryx2 file prefix: every shared-memory file of the run starts
    /// with it.
    pub fn prefix(&self) -> String {
        format!("mrsim_{}_", self.run_id)
    }

    /// The iceoryx2 root path (listener sockets, node and service records).
    /// Short on purpose: Unix socket paths are limited to 108 bytes.
    pub fn root_path(&self) -> PathBuf {
        PathBuf::from(format!("/tmp/mrsim/{}/", self.run_id))
    }

    /// Removes everything the run may have left: its root path, and files
    /// in /dev/shm and /tmp/iceoryx2 that start with its prefix. Returns how
    /// many entries were removed.
    pub fn remove_leftovers(&self) -> usize {
        let mut removed = 0;
        if std::fs::remove_dir_all(self.root_path()).is_ok() {
            removed += 1;
        }
        let prefix = self.prefix();
        for dir in ["/dev/shm", "/tmp/iceoryx2"] {
            if let Ok(entries) = std::fs::read_dir(dir) {
                for e in entries.flatten() {
                    if e.file_name().to_string_lossy().starts_with(&prefix) {
                        let p = e.path();
                        let gone = if p.is_dir() {
                            std::fs::remove_dir_all(&p).is_ok()
                        } else {
                            std::fs::remove_file(&p).is_ok()
                        };
                        removed += usize::from(gone);
                    }
                }
            }
        }
        removed
    }

    /// Takes group and other permissions off every /dev/shm entry of the
    /// run that has them. iceoryx2 0.10 creates its data segments, service
    /// records and sockets user-only, but its 16-byte global management
    /// segment (`*.global_mgmt`) world read-write
    /// (`enable_global_access(true)`, not configurable): this closes it
    /// right after the node that created it exists. Returns how many
    /// entries were changed.
    pub fn make_private(&self) -> usize {
        use std::os::unix::fs::PermissionsExt;
        let prefix = self.prefix();
        let Ok(entries) = std::fs::read_dir("/dev/shm") else {
            return 0;
        };
        let mut changed = 0;
        for e in entries.flatten() {
            if !e.file_name().to_string_lossy().starts_with(&prefix) {
                continue;
            }
            let Ok(meta) = e.metadata() else { continue };
            let mode = meta.permissions().mode();
            if mode & 0o077 != 0 {
                let private = std::fs::Permissions::from_mode(mode & 0o700);
                changed += usize::from(std::fs::set_permissions(e.path(), private).is_ok());
            }
        }
        changed
    }

    /// Lists what the run has left in /dev/shm (for tests and `--check`).
    pub fn shm_leftovers(&self) -> Vec<String> {
        let prefix = self.prefix();
        std::fs::read_dir("/dev/shm")
            .map(|entries| {
                entries
                    .flatten()
                    .map(|e| e.file_name().to_string_lossy().into_owned())
                    .filter(|n| n.starts_with(&prefix))
                    .collect()
            })
            .unwrap_or_default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn run_ids_are_checked() {
        assert!(Namespace::new("r1-abc").is_ok());
        assert!(Namespace::new("").is_err());
        assert!(Namespace::new("Bad_Id").is_err());
        assert!(Namespace::new(&"x".repeat(25)).is_err());
    }

    #[test]
    fn fresh_run_ids_are_valid_and_paths_short() {
        let id = Namespace::fresh_run_id();
        let ns = Namespace::new(&id).unwrap();
        assert!(ns.root_path().to_string_lossy().len() + ns.prefix().len() < 60);
    }
}
