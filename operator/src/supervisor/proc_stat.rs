//! A process as `/proc` and `kill(pid, 0)` see it: alive or not, when it started (so that a
//! reused pid is never taken for the process a record names), and the CPU time it used.
//!
//! The registry keeps start times beside pids; `hnav ps`, `hnav kill` and `hnav clean` ask
//! whether a recorded process is still the one that started; `hnav top` turns CPU time into
//! a share. Linux only: without `/proc`, a pid is all there is.

/// Whether a pid names a live process: `kill(pid, 0)` succeeds (or is refused, which means
/// the process exists but belongs to someone else), and it is not a zombie.
pub fn pid_alive(pid: u32) -> bool {
    // pid 0 and negative values address process groups, not a process.
    let Ok(raw) = i32::try_from(pid) else {
        return false;
    };
    if raw <= 0 {
        return false;
    }
    match nix::sys::signal::kill(nix::unistd::Pid::from_raw(raw), None) {
        Ok(()) | Err(nix::errno::Errno::EPERM) => !is_zombie(pid),
        Err(_) => false,
    }
}

/// Whether `pid` is alive ([`pid_alive`]) and, when `start_ticks` is known, is still the
/// process that started then rather than a later one that got the same pid.
pub fn process_alive(pid: u32, start_ticks: Option<u64>) -> bool {
    if !pid_alive(pid) {
        return false;
    }
    match (start_ticks, process_start_ticks(pid)) {
        (Some(want), Some(now)) => want == now,
        // Without /proc to ask, the pid is all there is.
        _ => true,
    }
}

/// When `pid` started, in clock ticks since boot: field 22 of `/proc/<pid>/stat`.
pub fn process_start_ticks(pid: u32) -> Option<u64> {
    stat_field(pid, 22)
}

/// The CPU time `pid` has used so far, user and system, in clock ticks: fields 14 and 15
/// of `/proc/<pid>/stat`. `hnav top` turns two readings into a CPU share.
pub fn process_cpu_ticks(pid: u32) -> Option<u64> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    let fields = fields_after_name(&stat)?;
    let mut fields = fields.skip(11);
    let user: u64 = fields.next()?.parse().ok()?;
    let system: u64 = fields.next()?.parse().ok()?;
    Some(user + system)
}

/// The kernel's flag of a task in `do_exit` (`PF_EXITING`, `include/linux/sched.h`): set
/// before the task gives up its memory, and never cleared; a task with it runs no more user
/// code.
const PF_EXITING: u64 = 0x4;

/// Whether every thread of `pid` has entered the kernel's exit (`PF_EXITING` in field 9 of
/// its `/proc/<pid>/task/<tid>/stat`, a zombie, or gone), so that the process will never run
/// another instruction of its own, although the kernel may take tens of milliseconds more to
/// tear it down before its parent can reap it. False when `/proc` cannot tell (no `/proc`,
/// the process not ours to read, or a thread still running).
///
/// A supervisor that sent SIGKILL can say the process is down at this point instead of at
/// the reap: see `run/dying.rs`.
pub fn exiting(pid: u32) -> bool {
    let Ok(tasks) = std::fs::read_dir(format!("/proc/{pid}/task")) else {
        return false;
    };
    tasks.flatten().all(|task| {
        let Ok(stat) = std::fs::read_to_string(task.path().join("stat")) else {
            // The thread is gone between the listing and the read: it has exited.
            return true;
        };
        let Some(mut fields) = fields_after_name(&stat) else {
            return false;
        };
        let state = fields.next();
        let flags = fields.nth(5).and_then(|f| f.parse::<u64>().ok());
        matches!(state, Some("Z" | "X")) || flags.is_some_and(|f| f & PF_EXITING != 0)
    })
}

/// Field `n` (1-based, as `proc(5)` numbers them; `n >= 3`) of `/proc/<pid>/stat`.
fn stat_field(pid: u32, n: usize) -> Option<u64> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    let field = fields_after_name(&stat)?.nth(n - 3)?.parse().ok();
    field
}

/// The fields of a `/proc/<pid>/stat` line from field 3 (the state) on.
fn fields_after_name(stat: &str) -> Option<impl Iterator<Item = &str>> {
    // The command name (field 2) is parenthesised and may itself hold spaces or ')'.
    Some(stat[stat.rfind(')')? + 1..].split_whitespace())
}

/// Whether the state letter of `/proc/<pid>/stat` (field 3) says zombie.
fn is_zombie(pid: u32) -> bool {
    std::fs::read_to_string(format!("/proc/{pid}/stat"))
        .ok()
        .and_then(|stat| fields_after_name(&stat)?.next().map(|state| state == "Z"))
        .unwrap_or(false)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn this_process_is_alive_and_a_wrong_start_time_is_not() {
        let me = std::process::id();
        let ticks = process_start_ticks(me).expect("/proc names our start time");
        assert!(process_alive(me, Some(ticks)));
        assert!(process_alive(me, None));
        assert!(!process_alive(me, Some(ticks + 1)), "a reused pid");
    }

    #[test]
    fn a_running_process_is_not_exiting_and_a_killed_one_soon_is() {
        let mut child = std::process::Command::new("sleep")
            .arg("30")
            .spawn()
            .expect("sleep runs");
        let pid = child.id();
        assert!(!exiting(pid), "a sleeping process is not exiting");
        assert!(!exiting(std::process::id()), "this test is not exiting");
        child.kill().expect("SIGKILL is sent");
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs(10);
        while !exiting(pid) && std::time::Instant::now() < deadline {
            std::thread::sleep(std::time::Duration::from_millis(1));
        }
        assert!(
            exiting(pid),
            "a SIGKILLed process is seen exiting within 10 s"
        );
        child.wait().expect("reaped");
    }

    #[test]
    fn cpu_ticks_grow_while_this_process_computes() {
        let me = std::process::id();
        let before = process_cpu_ticks(me).expect("/proc names our CPU time");
        let spin_until = std::time::Instant::now() + std::time::Duration::from_secs(5);
        let mut x = 0u64;
        while process_cpu_ticks(me).unwrap() < before + 2 && std::time::Instant::now() < spin_until
        {
            for i in 0..100_000u64 {
                x = std::hint::black_box(x.wrapping_mul(31).wrapping_add(i));
            }
        }
        assert!(
            process_cpu_ticks(me).unwrap() >= before + 2,
            "no CPU time counted in 5 s of computing"
        );
    }
}
