//! The forceful end of a run: escalate from waiting to SIGTERM to SIGKILL, and reap.
//!
//! By the time [`stop_all`] runs, the supervisor has already asked every process to finish
//! over the run's lifecycle topic, which lets them flush logs and drop their iceoryx2 nodes
//! cleanly. Whatever is still running after `grace` gets SIGTERM on its whole process group
//! (iceoryx2 turns that into a termination request, still a clean exit; a SIGCONT with it
//! wakes a stopped process to act on it), and after another
//! `grace` SIGKILL, which cannot be refused. Waiting is blocking on the children's exit
//! descriptors with `poll(2)`, so the supervisor sleeps until an exit or the deadline.
//!
//! Every child is reaped before this returns; grandchildren die with their group.

use std::os::fd::RawFd;
use std::time::{Duration, Instant};

use super::child::{Child, ExitInfo, Signal};
use super::exit_fd::poll_readable;
use hnav_runtime::msg::Role;

/// At which step a child ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum StopHow {
    /// It exited on its own (or had already been reaped) within the first grace period.
    ByItself,
    /// It exited after SIGTERM to its process group.
    AfterSigterm,
    /// It had to be killed with SIGKILL.
    AfterSigkill,
}

/// How one child ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Stopped {
    /// Its role.
    pub role: Role,
    /// Its index.
    pub index: u32,
    /// Its pid.
    pub pid: u32,
    /// At which step it ended.
    pub how: StopHow,
    /// Its exit as reaped.
    pub exit: ExitInfo,
}

/// Waits up to `grace` for `children` to exit, then SIGTERMs the process groups of the ones
/// still running, waits up to `grace` again, then SIGKILLs the rest and reaps everything.
/// Returns one [`Stopped`] per child, in the order given.
pub fn stop_all<'a, I>(children: I, grace: Duration) -> Vec<Stopped>
where
    I: IntoIterator<Item = &'a Child>,
{
    let children: Vec<&Child> = children.into_iter().collect();
    let mut how: Vec<Option<StopHow>> = vec![None; children.len()];
    let steps = [
        (None, StopHow::ByItself),
        (Some(Signal::SIGTERM), StopHow::AfterSigterm),
        (Some(Signal::SIGKILL), StopHow::AfterSigkill),
    ];
    for (signal, label) in steps {
        if let Some(signal) = signal {
            for (child, done) in children.iter().zip(&how) {
                if done.is_none() {
                    tracing::debug!(pid = child.pid(), %signal, "escalating stop");
                    if let Err(e) = child.signal_group(signal) {
                        tracing::warn!(error = %e, "stop: signal failed");
                    }
                    // A stopped process (`hnav kill --signal STOP`) acts on SIGTERM only
                    // once continued; to a running one SIGCONT is nothing.
                    if signal == Signal::SIGTERM {
                        let _ = child.signal_group(Signal::SIGCONT);
                    }
                }
            }
        }
        // SIGKILL cannot be caught or ignored: after it, wait for as long as the kernel takes.
        let deadline = (label != StopHow::AfterSigkill).then(|| Instant::now() + grace);
        wait_for_exits(&children, &mut how, deadline, label);
    }
    children
        .iter()
        .zip(how)
        .map(|(child, how)| Stopped {
            role: child.spec().role,
            index: child.spec().index,
            pid: child.pid(),
            how: how.unwrap_or(StopHow::AfterSigkill),
            exit: child.exit().unwrap_or(ExitInfo::Lost),
        })
        .collect()
}

/// Reaps what has exited, labelling it `label`, and blocks on the exit descriptors of the
/// rest until they all exited or `deadline` passed (`None`: until all exited).
fn wait_for_exits(
    children: &[&Child],
    how: &mut [Option<StopHow>],
    deadline: Option<Instant>,
    label: StopHow,
) {
    loop {
        let mut pending: Vec<(usize, RawFd)> = Vec::new();
        for (i, child) in children.iter().enumerate() {
            if how[i].is_some() {
                continue;
            }
            if child.try_reap().is_some() {
                how[i] = Some(label);
            } else {
                pending.push((i, child.exit_fd().as_raw_fd()));
            }
        }
        if pending.is_empty() {
            return;
        }
        let left = deadline.map(|d| d.saturating_duration_since(Instant::now()));
        if left == Some(Duration::ZERO) {
            return;
        }
        let fds: Vec<RawFd> = pending.iter().map(|&(_, fd)| fd).collect();
        match poll_readable(&fds, left) {
            Ok(_) => {}
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => {
                // Without a working poll, fall back to what needs no descriptor at all.
                tracing::warn!(error = %e, "stop: poll failed; waiting per child instead");
                if deadline.is_none() {
                    for &(i, _) in &pending {
                        children[i].reap_blocking();
                        how[i] = Some(label);
                    }
                }
                return;
            }
        }
    }
}
