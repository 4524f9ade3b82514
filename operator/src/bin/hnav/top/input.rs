//! The keys `hnav top` listens to: `q`, Esc and Ctrl-C leave; once the run has ended any key
//! does. In raw mode Ctrl-C is a key like the others, not a SIGINT.

use std::time::Duration;

use ratatui::crossterm::event::{self, Event, KeyCode, KeyEvent, KeyEventKind, KeyModifiers};

/// What the events since the last look ask for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Input {
    /// `q`, Esc or Ctrl-C.
    pub quit: bool,
    /// Any key at all.
    pub key: bool,
    /// The terminal changed size: draw again now.
    pub resized: bool,
}

/// Waits up to `timeout` for the first event, then takes every event already queued.
pub fn poll(timeout: Duration) -> std::io::Result<Input> {
    let mut input = Input::default();
    let mut wait = timeout;
    while event::poll(wait)? {
        wait = Duration::ZERO;
        match event::read()? {
            Event::Key(k) if k.kind != KeyEventKind::Release => {
                input.key = true;
                input.quit |= is_quit(&k);
            }
            Event::Resize(..) => input.resized = true,
            _ => {}
        }
    }
    Ok(input)
}

fn is_quit(k: &KeyEvent) -> bool {
    match k.code {
        KeyCode::Char('q') | KeyCode::Char('Q') | KeyCode::Esc => true,
        KeyCode::Char('c') => k.modifiers.contains(KeyModifiers::CONTROL),
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn q_escape_and_ctrl_c_quit_other_keys_do_not() {
        let key = |code, modifiers| KeyEvent::new(code, modifiers);
        assert!(is_quit(&key(KeyCode::Char('q'), KeyModifiers::NONE)));
        assert!(is_quit(&key(KeyCode::Esc, KeyModifiers::NONE)));
        assert!(is_quit(&key(KeyCode::Char('c'), KeyModifiers::CONTROL)));
        assert!(!is_quit(&key(KeyCode::Char('c'), KeyModifiers::NONE)));
        assert!(!is_quit(&key(KeyCode::Enter, KeyModifiers::NONE)));
    }
}
