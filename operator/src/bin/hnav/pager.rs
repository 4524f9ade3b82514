//! Long output to a terminal goes through a pager, as `git log` does: `hnav log show` of a
//! thousand-robot run prints a line per round with a decision per robot, thousands of
//! screens. Only when standard output is a terminal; a pipe or a file gets the lines as
//! they are read, at once.
//!
//! The pager is `$HNAV_PAGER`, else `$PAGER`, else `less` with `LESS=FRX` (leave at once when
//! the output fits one screen, keep colours, do not clear the screen on exit: git's
//! defaults). An empty `HNAV_PAGER` or `PAGER`, or `cat`, means none. A pager that cannot be
//! started is no error: the lines go to the terminal.

use std::io::{IsTerminal, Write};
use std::process::{Child, ChildStdin, Command, Stdio};

/// Where paged output goes: the pager's input, or standard output.
pub enum Paged {
    /// A pager reads what is written; [`Paged::finish`] waits for the reader to leave.
    Pager(Child, ChildStdin),
    /// Standard output itself.
    Stdout(std::io::Stdout),
}

impl Paged {
    /// A pager if standard output is a terminal and `enabled`, else standard output.
    pub fn start(enabled: bool) -> Paged {
        let stdout = std::io::stdout();
        if !enabled || !stdout.is_terminal() {
            return Paged::Stdout(stdout);
        }
        let chosen = std::env::var("HNAV_PAGER")
            .or_else(|_| std::env::var("PAGER"))
            .unwrap_or_else(|_| "less".to_string());
        let mut words = chosen.split_whitespace();
        let Some(program) = words.next().filter(|p| *p != "cat") else {
            return Paged::Stdout(stdout);
        };
        let mut cmd = Command::new(program);
        cmd.args(words).stdin(Stdio::piped());
        if std::env::var_os("LESS").is_none() {
            cmd.env("LESS", "FRX");
        }
        match cmd.spawn() {
            Ok(mut child) => match child.stdin.take() {
                Some(input) => Paged::Pager(child, input),
                None => Paged::Stdout(stdout),
            },
            Err(_) => Paged::Stdout(stdout),
        }
    }

    /// Closes the pager's input and waits until the reader leaves it.
    pub fn finish(self) {
        if let Paged::Pager(mut child, input) = self {
            drop(input);
            let _ = child.wait();
        }
    }
}

impl Write for Paged {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        match self {
            Paged::Pager(_, input) => input.write(buf),
            Paged::Stdout(out) => out.write(buf),
        }
    }

    fn flush(&mut self) -> std::io::Result<()> {
        match self {
            Paged::Pager(_, input) => input.flush(),
            Paged::Stdout(out) => out.flush(),
        }
    }
}
