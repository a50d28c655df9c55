//! Linux's scheduling policies for one thread, through `sched_setattr`:
//! SCHED_OTHER, SCHED_FIFO at a priority, SCHED_DEADLINE over a
//! reservation; the deadline admission limit; a probe that asks the kernel
//! before anything runs; and the count of reservation overruns (SIGXCPU).
//!
//! A SCHED_DEADLINE thread is set with `SCHED_FLAG_RESET_ON_FORK` (without
//! it the kernel refuses to let it start a thread or a process: a
//! reservation cannot be inherited) and `SCHED_FLAG_DL_OVERRUN`: a job
//! that uses up its runtime before its deadline makes the kernel send the
//! process SIGXCPU, which [`count_overruns`] turns into a count instead of
//! the signal's default (ending the process).

use std::sync::atomic::{AtomicU64, Ordering};

/// SCHED_DEADLINE (not in libc for every Linux target).
const SCHED_DEADLINE: u32 = 6;

/// One thread's scheduling policy.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Policy {
    /// SCHED_OTHER at nice 0: the kernel's fair share (CFS / EEVDF).
    Other,
    /// SCHED_FIFO at `priority` (1..=99, higher runs first).
    Fifo {
        /// The static priority.
        priority: u8,
    },
    /// SCHED_DEADLINE: `runtime_ns` of CPU every `period_ns`, the deadline
    /// at the end of each period (implicit deadlines).
    Deadline {
        /// CPU time per period (the reservation's budget).
        runtime_ns: u64,
        /// The period, and the relative deadline.
        period_ns: u64,
    },
}

impl std::fmt::Display for Policy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Policy::Other => write!(f, "SCHED_OTHER"),
            Policy::Fifo { priority } => write!(f, "SCHED_FIFO at priority {priority}"),
            Policy::Deadline {
                runtime_ns,
                period_ns,
            } => write!(
                f,
                "SCHED_DEADLINE with runtime {} ms every {} ms",
                ms(runtime_ns),
                ms(period_ns)
            ),
        }
    }
}

impl Policy {
    /// The share of one core a deadline policy reserves (runtime over
    /// period); 0 for the others.
    pub fn bandwidth(&self) -> f64 {
        match *self {
            Policy::Deadline {
                runtime_ns,
                period_ns,
            } if period_ns > 0 => runtime_ns as f64 / period_ns as f64,
            _ => 0.0,
        }
    }
}

/// Milliseconds, for messages.
fn ms(ns: u64) -> f64 {
    ns as f64 / 1e6
}

/// The kernel refused a policy ([`set_policy`], [`probe`]). Each variant
/// carries the kernel's errno and a plain reason.
#[derive(Debug, thiserror::Error)]
pub enum PolicyError {
    /// EPERM: the thread may not take the policy: no CAP_SYS_NICE (nor,
    /// for SCHED_FIFO, an RLIMIT_RTPRIO that high), or, for
    /// SCHED_DEADLINE, an affinity narrower than the root domain (every
    /// CPU of the thread's cpuset must be allowed).
    #[error("{policy}: the kernel refused it (EPERM, errno {errno}): {reason}")]
    NotPermitted {
        /// The policy asked for.
        policy: Policy,
        /// The kernel's errno.
        errno: i32,
        /// Why, in plain words.
        reason: String,
    },
    /// EBUSY: SCHED_DEADLINE's admission control: with this reservation
    /// the deadline reservations would exceed the limit
    /// `sched_rt_runtime_us / sched_rt_period_us` x cores.
    #[error("{policy}: the kernel refused it (EBUSY, errno {errno}): {reason}")]
    OverAdmission {
        /// The policy asked for.
        policy: Policy,
        /// The kernel's errno.
        errno: i32,
        /// The sum against the limit, in plain words.
        reason: String,
    },
    /// EINVAL: the kernel does not take these parameters (a priority out
    /// of 1..99, a runtime below 1 us or above the period, a period the
    /// kernel's `sched_deadline_period_{min,max}_us` exclude, a policy
    /// this kernel lacks).
    #[error("{policy}: the kernel refused it (EINVAL, errno {errno}): {reason}")]
    Invalid {
        /// The policy asked for.
        policy: Policy,
        /// The kernel's errno.
        errno: i32,
        /// Why, in plain words.
        reason: String,
    },
    /// Any other errno (ENOSYS, ESRCH...), or a probe thread that could
    /// not be started.
    #[error("{policy}: the kernel refused it (errno {errno}): {reason}")]
    Refused {
        /// The policy asked for.
        policy: Policy,
        /// The kernel's errno (0: not the kernel's answer).
        errno: i32,
        /// The system's own message.
        reason: String,
    },
}

impl PolicyError {
    /// The kernel's errno.
    pub fn errno(&self) -> i32 {
        match self {
            PolicyError::NotPermitted { errno, .. }
            | PolicyError::OverAdmission { errno, .. }
            | PolicyError::Invalid { errno, .. }
            | PolicyError::Refused { errno, .. } => *errno,
        }
    }
}

/// The deadline admission limit: the share of each core that
/// SCHED_DEADLINE (and SCHED_FIFO / SCHED_RR) tasks may take,
/// `sched_rt_runtime_us / sched_rt_period_us`; `None` when unlimited
/// (`sched_rt_runtime_us = -1`) or unreadable.
pub fn admission_share() -> Option<f64> {
    let read = |name: &str| -> Option<i64> {
        std::fs::read_to_string(format!("/proc/sys/kernel/{name}"))
            .ok()?
            .trim()
            .parse()
            .ok()
    };
    let runtime = read("sched_rt_runtime_us")?;
    let period = read("sched_rt_period_us")?;
    (runtime >= 0 && period > 0).then(|| runtime as f64 / period as f64)
}

/// The kernel's admission test for deadline reservations whose bandwidths
/// (runtime / period) are `bandwidths`, on a root domain of `cores` CPUs
/// with `share` of each for them: refused when the sum exceeds
/// `share x cores`.
#[derive(Debug, thiserror::Error)]
#[error(
    "the deadline reservations sum to {sum:.3} of a core, above the admission limit \
     {share:.2} x {cores} cores = {limit:.3} (sched_rt_runtime_us / sched_rt_period_us x cores)"
)]
pub struct OverLimit {
    /// The sum of the reservations' runtime / period.
    pub sum: f64,
    /// The admission share of each core.
    pub share: f64,
    /// The CPUs of the root domain.
    pub cores: usize,
    /// `share x cores`.
    pub limit: f64,
}

/// Checks reservations of `bandwidths` against the admission limit of
/// `cores` CPUs at `share` each (see [`admission_share`]), as the kernel
/// does before it admits one more.
pub fn admit(bandwidths: &[f64], share: f64, cores: usize) -> Result<(), OverLimit> {
    let sum: f64 = bandwidths.iter().sum();
    let limit = share * cores as f64;
    if sum > limit + 1e-12 {
        return Err(OverLimit {
            sum,
            share,
            cores,
            limit,
        });
    }
    Ok(())
}

/// True if the process has CAP_SYS_NICE in its effective set (root has).
fn has_sys_nice() -> bool {
    const CAP_SYS_NICE: u32 = 23;
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find_map(|l| l.strip_prefix("CapEff:"))
                .and_then(|hex| u64::from_str_radix(hex.trim(), 16).ok())
        })
        .is_some_and(|caps| caps & (1 << CAP_SYS_NICE) != 0)
}

/// The plain reason of an errno for `policy`, asked by a thread that may
/// run on `allowed` of the machine's CPUs.
fn refusal(policy: Policy, errno: i32, allowed: &[usize]) -> PolicyError {
    let online = crate::sched::online_cpus();
    match errno {
        libc::EPERM => {
            let reason = if !has_sys_nice() {
                match policy {
                    Policy::Fifo { priority } => format!(
                        "no CAP_SYS_NICE and no RLIMIT_RTPRIO of at least {priority} \
                         (run as root or give the binary CAP_SYS_NICE)"
                    ),
                    _ => {
                        "no CAP_SYS_NICE (run as root or give the binary CAP_SYS_NICE)".to_string()
                    }
                }
            } else if matches!(policy, Policy::Deadline { .. }) && allowed.len() < online {
                format!(
                    "the thread's affinity (CPUs {}) is narrower than its root domain \
                     ({online} CPUs): SCHED_DEADLINE needs an affinity that covers every \
                     CPU of the root domain (use all the CPUs, or a cpuset of its own)",
                    list(allowed)
                )
            } else {
                "the kernel does not permit it here (a cpuset or a container's limits)".to_string()
            };
            PolicyError::NotPermitted {
                policy,
                errno,
                reason,
            }
        }
        libc::EBUSY => {
            let reason = match admission_share() {
                Some(share) => format!(
                    "the deadline reservations already admitted on this machine plus this \
                     one ({:.3} of a core) exceed the admission limit {share:.2} x {online} \
                     cores = {:.3} (sched_rt_runtime_us / sched_rt_period_us x cores)",
                    policy.bandwidth(),
                    share * online as f64
                ),
                None => "the deadline admission control refused the reservation".to_string(),
            };
            PolicyError::OverAdmission {
                policy,
                errno,
                reason,
            }
        }
        libc::EINVAL => PolicyError::Invalid {
            policy,
            errno,
            reason: match policy {
                Policy::Fifo { .. } => "SCHED_FIFO priorities are 1..99".to_string(),
                Policy::Deadline { .. } => "SCHED_DEADLINE needs 1 us <= runtime <= period, \
                     and a period within the kernel's sched_deadline_period_min_us.. \
                     sched_deadline_period_max_us"
                    .to_string(),
                Policy::Other => "the kernel does not take these parameters".to_string(),
            },
        },
        _ => PolicyError::Refused {
            policy,
            errno,
            reason: std::io::Error::from_raw_os_error(errno).to_string(),
        },
    }
}

/// A CPU list for messages (`0,1`).
fn list(cpus: &[usize]) -> String {
    cpus.iter()
        .map(usize::to_string)
        .collect::<Vec<_>>()
        .join(",")
}

/// Puts the calling thread (only it: other threads of the process keep
/// theirs) under `policy`. Under SCHED_DEADLINE the thread may still start
/// threads and processes (they get SCHED_OTHER), and an overrun sends the
/// process SIGXCPU: call [`count_overruns`] first, or the signal ends it.
pub fn set_policy(policy: Policy) -> Result<(), PolicyError> {
    let mut attr = libc::sched_attr {
        size: std::mem::size_of::<libc::sched_attr>() as u32,
        sched_policy: libc::SCHED_OTHER as u32,
        sched_flags: 0,
        sched_nice: 0,
        sched_priority: 0,
        sched_runtime: 0,
        sched_deadline: 0,
        sched_period: 0,
    };
    match policy {
        Policy::Other => {}
        Policy::Fifo { priority } => {
            attr.sched_policy = libc::SCHED_FIFO as u32;
            attr.sched_priority = u32::from(priority);
        }
        Policy::Deadline {
            runtime_ns,
            period_ns,
        } => {
            attr.sched_policy = SCHED_DEADLINE;
            attr.sched_flags =
                (libc::SCHED_FLAG_RESET_ON_FORK | libc::SCHED_FLAG_DL_OVERRUN) as u64;
            attr.sched_runtime = runtime_ns;
            attr.sched_deadline = period_ns;
            attr.sched_period = period_ns;
        }
    }
    // SAFETY: pid 0 is the calling thread; the attr struct lives for the
    // call, its size field says how much the kernel may read, flags 0.
    let r = unsafe {
        libc::syscall(
            libc::SYS_sched_setattr,
            0,
            &mut attr as *mut libc::sched_attr,
            0,
        )
    };
    if r != 0 {
        let errno = std::io::Error::last_os_error().raw_os_error().unwrap_or(0);
        let allowed = crate::sched::affinity().unwrap_or_default();
        return Err(refusal(policy, errno, &allowed));
    }
    Ok(())
}

/// The calling thread's policy as the kernel reports it (`sched_getattr`);
/// `None` if it cannot be read or is none of [`Policy`]'s.
pub fn policy() -> Option<Policy> {
    // SAFETY: a zeroed sched_attr is plain data.
    let mut attr: libc::sched_attr = unsafe { std::mem::zeroed() };
    let size = std::mem::size_of::<libc::sched_attr>() as u32;
    // SAFETY: the kernel writes at most `size` bytes into attr.
    let r = unsafe {
        libc::syscall(
            libc::SYS_sched_getattr,
            0,
            &mut attr as *mut libc::sched_attr,
            size,
            0,
        )
    };
    if r != 0 {
        return None;
    }
    match attr.sched_policy {
        p if p == libc::SCHED_OTHER as u32 => Some(Policy::Other),
        p if p == libc::SCHED_FIFO as u32 => Some(Policy::Fifo {
            priority: u8::try_from(attr.sched_priority).ok()?,
        }),
        SCHED_DEADLINE => Some(Policy::Deadline {
            runtime_ns: attr.sched_runtime,
            period_ns: attr.sched_period,
        }),
        _ => None,
    }
}

/// Asks the kernel whether threads pinned to `cpus` may take every one of
/// `policies` at once, before anything runs: one thread per policy pins
/// itself and sets it, all hold them together (so the deadline admission
/// test sees the sum), then each goes back to SCHED_OTHER and ends.
/// Nothing of the caller changes. The first refusal is returned with the
/// index of its policy.
pub fn probe(policies: &[Policy], cpus: &[usize]) -> Result<(), (usize, PolicyError)> {
    use std::sync::{Arc, Condvar, Mutex};
    // Set once every thread has asked (or the probe gives up): then each
    // lets its policy go.
    let release = Arc::new((Mutex::new(false), Condvar::new()));
    let let_go = |release: &(Mutex<bool>, Condvar)| {
        *release.0.lock().unwrap_or_else(|e| e.into_inner()) = true;
        release.1.notify_all();
    };
    let (tx, rx) = std::sync::mpsc::channel();
    let mut threads = Vec::with_capacity(policies.len());
    let mut first = None;
    for (i, &policy) in policies.iter().enumerate() {
        let release = release.clone();
        let cpus = cpus.to_vec();
        let tx = tx.clone();
        let spawned = std::thread::Builder::new()
            .name(format!("probe-{i}"))
            .spawn(move || {
                let set = if cpus.is_empty() {
                    Ok(())
                } else {
                    crate::sched::set_affinity(&cpus).map_err(|e| PolicyError::Refused {
                        policy,
                        errno: e.raw_os_error().unwrap_or(0),
                        reason: format!("sched_setaffinity to CPUs {}: {e}", list(&cpus)),
                    })
                }
                .and_then(|()| set_policy(policy));
                let held = set.is_ok();
                let _ = tx.send((i, set));
                // Held until every probe thread has asked.
                let (lock, cvar) = &*release;
                let mut go = lock.lock().unwrap_or_else(|e| e.into_inner());
                while !*go {
                    go = cvar.wait(go).unwrap_or_else(|e| e.into_inner());
                }
                drop(go);
                if held {
                    let _ = set_policy(Policy::Other);
                }
            });
        match spawned {
            Ok(t) => threads.push(t),
            Err(e) => {
                first = Some((
                    i,
                    PolicyError::Refused {
                        policy,
                        errno: e.raw_os_error().unwrap_or(0),
                        reason: format!("could not start a probe thread: {e}"),
                    },
                ));
                break;
            }
        }
    }
    drop(tx);
    let mut answers: Vec<(usize, Result<(), PolicyError>)> =
        rx.iter().take(threads.len()).collect();
    let_go(&release);
    for t in threads {
        let _ = t.join();
    }
    answers.sort_by_key(|(i, _)| *i);
    if let Some((i, Err(e))) = answers.into_iter().find(|(_, r)| r.is_err()) {
        return Err((i, e));
    }
    first.map_or(Ok(()), Err)
}

static OVERRUNS: AtomicU64 = AtomicU64::new(0);

extern "C" fn on_overrun(_sig: libc::c_int) {
    OVERRUNS.fetch_add(1, Ordering::Relaxed);
}

/// From now on SIGXCPU (the kernel's notice that a SCHED_DEADLINE job of
/// this process used up its runtime, `SCHED_FLAG_DL_OVERRUN`) is counted
/// instead of ending the process; [`overruns`] reads the count. Interrupted
/// system calls restart (SA_RESTART).
///
/// The kernel sends the signal at the first scheduler tick (1/HZ) at which
/// the overrunning thread runs again: a job whose runtime is shorter than a
/// tick and whose period keeps the same phase to the ticks can overrun
/// without a tick ever finding it running, and goes uncounted (it is
/// throttled all the same).
pub fn count_overruns() -> std::io::Result<()> {
    // SAFETY: a zeroed sigaction is valid; the handler only adds to an
    // atomic, which is async-signal-safe.
    unsafe {
        let mut sa: libc::sigaction = std::mem::zeroed();
        sa.sa_sigaction = on_overrun as *const () as libc::sighandler_t;
        sa.sa_flags = libc::SA_RESTART;
        libc::sigemptyset(&mut sa.sa_mask);
        if libc::sigaction(libc::SIGXCPU, &sa, std::ptr::null_mut()) != 0 {
            return Err(std::io::Error::last_os_error());
        }
    }
    Ok(())
}

/// The SIGXCPU overruns counted since [`count_overruns`].
pub fn overruns() -> u64 {
    OVERRUNS.load(Ordering::Relaxed)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Held by the tests that change scheduling: they would otherwise
    /// compete for the same reservations.
    static SCHED: std::sync::Mutex<()> = std::sync::Mutex::new(());

    fn lock() -> std::sync::MutexGuard<'static, ()> {
        SCHED.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The kernel lets this process take real-time policies (root or
    /// CAP_SYS_NICE); the tests that need it say so when it does not.
    fn privileged() -> bool {
        if has_sys_nice() {
            return true;
        }
        eprintln!("skipped: no CAP_SYS_NICE here, the kernel refuses every real-time policy");
        false
    }

    fn deadline(runtime_ms: u64, period_ms: u64) -> Policy {
        Policy::Deadline {
            runtime_ns: runtime_ms * 1_000_000,
            period_ns: period_ms * 1_000_000,
        }
    }

    fn all_cpus() -> Vec<usize> {
        (0..crate::sched::online_cpus()).collect()
    }

    #[test]
    fn reservations_above_the_share_of_the_cores_are_not_admitted() {
        assert!(admit(&[0.2; 9], 0.95, 2).is_ok());
        let e = admit(&[0.2; 10], 0.95, 2).expect_err("2.0 > 1.9");
        assert!((e.sum - 2.0).abs() < 1e-9);
        assert!((e.limit - 1.9).abs() < 1e-9);
        let text = e.to_string();
        assert!(text.contains("2.000") && text.contains("1.900"), "{text}");
    }

    #[test]
    fn each_policy_is_set_read_back_and_left() {
        if !privileged() {
            return;
        }
        let _one = lock();
        let t = std::thread::spawn(|| {
            let mut seen = Vec::new();
            for p in [
                Policy::Fifo { priority: 7 },
                deadline(2, 100),
                Policy::Other,
            ] {
                set_policy(p).map_err(|e| e.to_string())?;
                seen.push(policy());
            }
            Ok::<_, String>(seen)
        });
        let seen = t.join().expect("thread").expect("policies");
        assert_eq!(
            seen,
            vec![
                Some(Policy::Fifo { priority: 7 }),
                Some(deadline(2, 100)),
                Some(Policy::Other)
            ]
        );
    }

    #[test]
    fn a_deadline_thread_may_still_start_a_thread() {
        if !privileged() {
            return;
        }
        let _one = lock();
        let t = std::thread::spawn(|| {
            set_policy(deadline(2, 100)).map_err(|e| e.to_string())?;
            let child = std::thread::spawn(policy)
                .join()
                .map_err(|_| "child panicked")?;
            let _ = set_policy(Policy::Other);
            Ok::<_, String>(child)
        });
        let child = t.join().expect("thread").expect("deadline");
        assert_eq!(
            child,
            Some(Policy::Other),
            "the reservation is not inherited"
        );
    }

    #[test]
    fn reservations_summing_above_the_admission_limit_are_refused_with_ebusy() {
        if !privileged() {
            return;
        }
        let Some(share) = admission_share() else {
            eprintln!("skipped: no deadline admission limit on this kernel");
            return;
        };
        let _one = lock();
        let cores = crate::sched::online_cpus();
        // Each 0.5 of a core: 2 per core + 1 goes over share x cores when
        // share < 1 (0.95 by default).
        let n = (share * cores as f64 / 0.5).floor() as usize + 1;
        let set = vec![deadline(50, 100); n];
        let (i, e) = probe(&set, &all_cpus()).expect_err("above the limit");
        assert!(i < n);
        assert_eq!(e.errno(), libc::EBUSY, "{e}");
        assert!(matches!(e, PolicyError::OverAdmission { .. }), "{e}");
        // Below the limit they all fit at once, and the probe left nothing
        // held behind it.
        probe(&vec![deadline(50, 100); n - 1], &all_cpus()).expect("below the limit");
    }

    #[test]
    fn a_deadline_policy_on_fewer_cpus_than_the_root_domain_is_refused_with_eperm() {
        if !privileged() {
            return;
        }
        if crate::sched::online_cpus() < 2 {
            eprintln!("skipped: one CPU, no affinity is narrower than the root domain");
            return;
        }
        let _one = lock();
        let (_, e) = probe(&[deadline(5, 100)], &[0]).expect_err("narrower affinity");
        assert_eq!(e.errno(), libc::EPERM, "{e}");
        assert!(
            e.to_string().contains("narrower than its root domain"),
            "{e}"
        );
        // The same reservation over every CPU is taken.
        probe(&[deadline(5, 100)], &all_cpus()).expect("whole root domain");
    }

    #[test]
    fn a_runtime_longer_than_its_period_is_refused_with_einval() {
        if !privileged() {
            return;
        }
        let _one = lock();
        let (_, e) = probe(&[deadline(20, 10)], &all_cpus()).expect_err("runtime > period");
        assert_eq!(e.errno(), libc::EINVAL, "{e}");
        let (_, e) = probe(&[Policy::Fifo { priority: 100 }], &[]).expect_err("priority 100");
        assert_eq!(e.errno(), libc::EINVAL, "{e}");
    }

    #[test]
    fn an_overrunning_reservation_is_throttled_and_counted() {
        if !privileged() {
            return;
        }
        let _one = lock();
        count_overruns().expect("SIGXCPU handler");
        let before = overruns();
        let t = std::thread::spawn(|| {
            // 10 ms every 100 ms; 50 ms of CPU wanted in one go. (The
            // kernel notices an overrun at its next tick while the thread
            // runs: a runtime shorter than a tick, 4 ms at HZ = 250, can go
            // unnoticed when its periods keep the same phase to the ticks.)
            set_policy(deadline(10, 100)).map_err(|e| e.to_string())?;
            let wall = std::time::Instant::now();
            let start = crate::cpu::thread_cpu_ns();
            crate::cpu::burn_until(start, 50_000_000);
            let elapsed = wall.elapsed();
            let _ = set_policy(Policy::Other);
            Ok::<_, String>(elapsed)
        });
        let elapsed = t.join().expect("thread").expect("deadline");
        // 50 ms of CPU at 10 ms per 100 ms cannot end before the start of
        // its fifth period (400 ms); unthrottled it takes 50 ms. A lower
        // bound only, which load can only raise: that the kernel held it
        // back at all.
        assert!(
            elapsed >= std::time::Duration::from_millis(350),
            "50 ms of CPU at 10 ms per 100 ms ran in {elapsed:?}"
        );
        assert!(overruns() > before, "no overrun counted");
    }
}
