//! What a process given up on means to the run, in words: the verdict on the run after a
//! reaping ([`Gone`]) and what a process stopped on a full disk was writing.

use std::path::Path;

use crate::supervisor::child::ExitInfo;
use crate::supervisor::restart::GiveUpReason;
use hnav_runtime::msg::Role;
use hnav_runtime::scenario::GiveUpAction;

/// The processes given up on in one reaping, for the verdict on the run.
#[derive(Default)]
pub(super) struct Gone {
    /// The sim, the coordinator or a bridge (or an agent under `on_give_up = "stop"`): the
    /// run ends.
    pub(super) core: Option<String>,
    /// A coordinator replica: the run ends once no majority is left.
    pub(super) replica: Option<String>,
    /// An agent: the run ends if it was the last one.
    pub(super) agent: Option<String>,
}

impl Gone {
    /// Notes that `role`/`index` `ended` and is not restarted (`on_give_up`: what an agent
    /// gone for good does to the run); returns what that means to the run, for the journal.
    pub(super) fn note(
        &mut self,
        role: Role,
        index: u32,
        ended: &str,
        on_give_up: GiveUpAction,
    ) -> String {
        let replica = role == Role::Coordinator && index > 0;
        let gone = if replica {
            format!("{ended}: the cluster goes on while a majority of it is left")
        } else {
            format!("{ended}: the run cannot go on")
        };
        match role {
            Role::Agent if on_give_up == GiveUpAction::Stop => {
                self.core = Some(format!(
                    "{ended}, and [restart] on_give_up = \"stop\" ends the run"
                ));
            }
            Role::Agent => self.agent = Some(gone.clone()),
            Role::Coordinator if replica => self.replica = Some(ended.to_string()),
            Role::Sim | Role::Coordinator | Role::Bridge => self.core = Some(gone.clone()),
        }
        gone
    }
}

/// That `role`'s process of `robots` (an agent process's robots; one index otherwise) ended
/// with `exit` and is not restarted for `why`, in words.
pub(super) fn not_restarted(
    role: Role,
    robots: std::ops::Range<u32>,
    exit: &ExitInfo,
    why: GiveUpReason,
) -> String {
    let who = match role {
        Role::Agent if robots.len() > 1 => format!(
            "hnav-agent {} (robots {} to {})",
            robots.start,
            robots.start,
            robots.end - 1
        ),
        Role::Agent => format!("hnav-agent {}", robots.start),
        other => format!("hnav-{}", other.name()),
    };
    format!("{who} ended ({exit}) and is not restarted ({why})")
}

/// What a process of `role` writes in the run directory `dir`, for the message of a run that
/// ended on a full disk.
pub(super) fn role_writes(role: Role, index: u32, dir: &Path) -> String {
    let log = dir
        .join("logs")
        .join(format!("{}.log", role.node_name(index)));
    match role {
        Role::Coordinator if index > 0 => format!(
            "its replica's consensus log in {}",
            dir.join("log").join(index.to_string()).display()
        ),
        Role::Coordinator => format!("the consensus log in {}", dir.join("log").display()),
        Role::Agent => format!(
            "its checkpoint {} or its log {}",
            dir.join("agents").join(format!("{index}.ckpt")).display(),
            log.display()
        ),
        Role::Sim => format!(
            "its checkpoint {} or its log {}",
            dir.join("sim.ckpt.{0,1}").display(),
            log.display()
        ),
        Role::Bridge => format!("its log {}", log.display()),
    }
}
