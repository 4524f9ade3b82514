//! The blocks of a markdown file that `tests/docs.rs` runs, marked by an HTML comment on the
//! line before the fence (invisible on GitHub):
//!
//! - `<!-- docs-test: file NAME -->` before a block: the block is written to `NAME` in the
//!   sandbox (a file the page tells the reader to save);
//! - `<!-- docs-test: append NAME -->`: the block is appended to `NAME` (the page adds a
//!   section to that file);
//! - `<!-- docs-test: run -->` before a `sh` block: the block is run with `sh -e` in the
//!   sandbox, after the blocks above it, and must exit 0 (`run exit N`: must exit N).
//!
//! An unmarked `sh` block is not run; its `hnav` commands are checked against `--help` like
//! every other command of the docs ([`super::check_commands`]).

/// The marker's opening.
pub const MARKER: &str = "<!-- docs-test:";

/// What the test does with one marked block.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Action {
    /// Write the block to this file, replacing it.
    File(String),
    /// Append the block to this file.
    Append(String),
    /// Run the block; the exit code it must give.
    Run(i32),
}

/// One marked block, in the order of the page.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Step {
    /// 1-based line of the block's first line of code.
    pub line: usize,
    /// What to do with it.
    pub action: Action,
    /// The block's text, every line ending in a newline.
    pub text: String,
}

/// The marked blocks of `markdown`, or what is wrong with a marker (with its line).
pub fn steps(markdown: &str) -> Result<Vec<Step>, (usize, String)> {
    let lines: Vec<&str> = markdown.lines().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        let Some(directive) = lines[i].trim().strip_prefix(MARKER) else {
            i += 1;
            continue;
        };
        let at = i + 1;
        let directive = directive
            .strip_suffix("-->")
            .ok_or((
                at,
                "a docs-test marker ends with `-->` on its line".to_string(),
            ))?
            .trim();
        let action = action(directive).map_err(|e| (at, e))?;
        let fence = lines.get(i + 1).map(|l| l.trim_start()).unwrap_or("");
        let ticks = fence.chars().take_while(|c| *c == '`').count();
        if ticks < 3 {
            return Err((at, "a docs-test marker must be followed by a fence".into()));
        }
        let lang = fence[ticks..].trim();
        if matches!(action, Action::Run(_)) && lang != "sh" {
            return Err((at, format!("`run` marks a ```sh block, not ```{lang}")));
        }
        let close = "`".repeat(ticks);
        let mut text = String::new();
        let mut j = i + 2;
        while j < lines.len() && lines[j].trim() != close {
            text.push_str(lines[j]);
            text.push('\n');
            j += 1;
        }
        if j == lines.len() {
            return Err((at, "the marked block is never closed".into()));
        }
        out.push(Step {
            line: i + 3,
            action,
            text,
        });
        i = j + 1;
    }
    Ok(out)
}

fn action(directive: &str) -> Result<Action, String> {
    let words: Vec<&str> = directive.split_whitespace().collect();
    match words[..] {
        ["file", name] => Ok(Action::File(name.into())),
        ["append", name] => Ok(Action::Append(name.into())),
        ["run"] => Ok(Action::Run(0)),
        ["run", "exit", code] => code
            .parse()
            .map(Action::Run)
            .map_err(|_| format!("`run exit {code}`: the exit code is a number")),
        _ => Err(format!(
            "unknown docs-test marker `{directive}`: file NAME, append NAME, run, run exit N"
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn marked_blocks_are_found_in_order_and_unmarked_ones_left_alone() {
        let md = "# T\n\n<!-- docs-test: file a.toml -->\n```toml\nx = 1\n```\n\n```sh\nhnav ps\n```\n\
                  <!-- docs-test: append a.toml -->\n```toml\ny = 2\n```\n<!-- docs-test: run exit 2 -->\n\
                  ```sh\nhnav check a.toml\n```\n";
        let s = steps(md).unwrap();
        assert_eq!(s.len(), 3);
        assert_eq!(s[0].action, Action::File("a.toml".into()));
        assert_eq!((s[0].line, s[0].text.as_str()), (5, "x = 1\n"));
        assert_eq!(s[1].action, Action::Append("a.toml".into()));
        assert_eq!(s[2].action, Action::Run(2));
        assert_eq!(s[2].text, "hnav check a.toml\n");
    }

    #[test]
    fn a_bad_marker_is_named_with_its_line() {
        assert_eq!(
            steps("\n<!-- docs-test: runs -->\n```sh\nx\n```\n")
                .unwrap_err()
                .0,
            2
        );
        assert!(steps("<!-- docs-test: run -->\n```toml\nx\n```\n")
            .unwrap_err()
            .1
            .contains("```sh"));
        assert!(steps("<!-- docs-test: run -->\n\n```sh\nx\n```\n")
            .unwrap_err()
            .1
            .contains("followed by a fence"));
        assert!(steps("<!-- docs-test: run -->\n```sh\nx\n")
            .unwrap_err()
            .1
            .contains("never closed"));
    }
}
