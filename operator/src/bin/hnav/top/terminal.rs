//! The terminal of `hnav top`: raw mode and the alternate screen for as long as a
//! [`TerminalGuard`] lives, restored when it is dropped (a normal exit, an error returned)
//! and by ratatui's panic hook when a panic unwinds past it.

use std::io::IsTerminal;

use ratatui::DefaultTerminal;

/// Why the terminal could not be taken over.
#[derive(Debug, thiserror::Error)]
pub enum TerminalError {
    /// Standard output is a file or a pipe.
    #[error("hnav top draws on a terminal, and its standard output is not one")]
    NotATerminal,
    /// Raw mode or the alternate screen was refused.
    #[error("cannot set up the terminal: {0}")]
    Setup(std::io::Error),
}

/// The terminal in raw mode on the alternate screen; dropping it gives the terminal back.
pub struct TerminalGuard {
    terminal: DefaultTerminal,
}

impl TerminalGuard {
    /// Takes the terminal over (and installs ratatui's panic hook, which restores it too).
    pub fn enter() -> Result<TerminalGuard, TerminalError> {
        if !std::io::stdout().is_terminal() {
            return Err(TerminalError::NotATerminal);
        }
        let terminal = ratatui::try_init().map_err(TerminalError::Setup)?;
        Ok(TerminalGuard { terminal })
    }

    /// The terminal to draw on.
    pub fn terminal(&mut self) -> &mut DefaultTerminal {
        &mut self.terminal
    }
}

impl Drop for TerminalGuard {
    fn drop(&mut self) {
        // Leaves raw mode and the alternate screen, and shows the cursor again.
        ratatui::restore();
    }
}
