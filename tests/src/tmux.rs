//! A terminal for tests of full-screen programs (`hnav top`, the playback view): a tmux
//! server of the test's own, its pane's screen read as text.

use std::time::{Duration, Instant};

/// A tmux server of its own (`tmux -L NAME`), killed with every session in it when dropped,
/// also when the test fails.
pub struct Tmux {
    socket: String,
}

impl Tmux {
    /// A server on socket `hnav-<id>`; `None` (after saying so on stderr) when tmux is not
    /// installed (`.ci/run` installs it), so the caller can skip.
    pub fn new(id: &str) -> Option<Tmux> {
        if std::process::Command::new("tmux")
            .arg("-V")
            .output()
            .is_err()
        {
            eprintln!("SKIPPED: tmux is not installed (`.ci/run` installs it)");
            return None;
        }
        Some(Tmux {
            socket: format!("hnav-{id}"),
        })
    }

    /// Runs a tmux command on this server.
    pub fn cmd(&self, args: &[&str]) -> std::process::Output {
        std::process::Command::new("tmux")
            .args(["-L", &self.socket])
            .args(args)
            .output()
            .expect("tmux runs")
    }

    /// Starts `command` (a shell line) in a detached session `top` of `cols` x `rows`.
    pub fn start(&self, cols: u16, rows: u16, command: &str) -> std::process::Output {
        let (cols, rows) = (cols.to_string(), rows.to_string());
        self.cmd(&[
            "new-session",
            "-d",
            "-s",
            "top",
            "-x",
            &cols,
            "-y",
            &rows,
            command,
        ])
    }

    /// The pane's screen as text.
    pub fn capture(&self) -> String {
        String::from_utf8_lossy(&self.cmd(&["capture-pane", "-p", "-t", "top"]).stdout).into()
    }

    /// Waits up to `timeout` for the screen to satisfy `ok`; returns the last capture (as
    /// the error when it never did).
    pub fn wait_for(&self, timeout: Duration, ok: impl Fn(&str) -> bool) -> Result<String, String> {
        let deadline = Instant::now() + timeout;
        loop {
            let screen = self.capture();
            if ok(&screen) {
                return Ok(screen);
            }
            if Instant::now() >= deadline {
                return Err(screen);
            }
            std::thread::sleep(Duration::from_millis(50));
        }
    }
}

impl Drop for Tmux {
    fn drop(&mut self) {
        self.cmd(&["kill-server"]);
    }
}
