//! The `hnav` and `hnav-bench` command lines a piece of code in the docs names.
//!
//! A command starts at a word that is the binary (`hnav`, `hnav-bench`, or a path ending in
//! `/hnav` or `/hnav-bench`: `target/release/hnav`) or at `cargo run ... -- ` for one of them
//! (`--bin hnav`, `--bin hnav-bench`, or `-p hnav-bench` / `-p hnav-operator` without
//! `--bin`). It ends at the end of the piece, at a shell comment (`#` after a space), or at
//! `&&`, `||`, `;` or ` | `. Any other tool's command (`cargo test --release`, `ip netns
//! exec`) names nothing. Brackets, quotes and `...` around words are usage notation and are
//! dropped: `[--mode lockstep|realtime]` names the flag `--mode`.

/// The binaries whose command lines are checked.
pub const BINARIES: [&str; 2] = ["hnav", "hnav-bench"];

/// One command line: the binary and the words after it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CommandLine {
    /// `hnav` or `hnav-bench`.
    pub bin: &'static str,
    /// The words after the binary, usage brackets and quotes dropped.
    pub words: Vec<String>,
}

/// The commands a fence line names (`fence` true: a `#` starts a comment) or a code span
/// names.
pub fn commands(text: &str, fence: bool) -> Vec<CommandLine> {
    let text = if fence {
        let t = text.trim_start();
        t.strip_prefix("$ ").unwrap_or(t)
    } else {
        text
    };
    let text = if fence { strip_comment(text) } else { text };
    let mut out = Vec::new();
    for segment in split_segments(text) {
        let words: Vec<String> = segment.split_whitespace().map(clean).collect();
        if let Some(c) = from_words(&words) {
            out.push(c);
        }
    }
    out
}

/// The flags (`--name`) one word holds: `--kill|--term|--freeze` holds three,
/// `--kill/--term` two, `--mode=lockstep` one, `--` and `a--b` none.
pub fn flags(word: &str) -> Vec<String> {
    word.split(['|', '/', ','])
        .filter_map(|part| {
            let name = part.strip_prefix("--")?;
            let len = name
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '-'))
                .unwrap_or(name.len());
            let name = &name[..len];
            name.starts_with(|c: char| c.is_ascii_alphanumeric())
                .then(|| format!("--{name}"))
        })
        .collect()
}

/// `text` up to a `#` that starts a shell comment.
fn strip_comment(text: &str) -> &str {
    let bytes = text.as_bytes();
    for (i, b) in bytes.iter().enumerate() {
        if *b == b'#' && (i == 0 || bytes[i - 1].is_ascii_whitespace()) {
            return &text[..i];
        }
    }
    text
}

/// The pieces of a shell line between `&&`, `||`, `;` and ` | `.
fn split_segments(text: &str) -> Vec<&str> {
    let mut out = Vec::new();
    let mut start = 0;
    let bytes = text.as_bytes();
    let mut i = 0;
    while i < bytes.len() {
        let two = &bytes[i..(i + 2).min(bytes.len())];
        let cut = if two == b"&&" || two == b"||" {
            2
        } else if bytes[i] == b';'
            || (bytes[i] == b'|'
                && i > 0
                && bytes[i - 1] == b' '
                && bytes.get(i + 1) == Some(&b' '))
        {
            1
        } else {
            0
        };
        if cut > 0 {
            out.push(&text[start..i]);
            i += cut;
            start = i;
        } else {
            i += 1;
        }
    }
    out.push(&text[start..]);
    out
}

/// A word without the usage notation and quoting around it.
fn clean(word: &str) -> String {
    word.trim_start_matches(['[', '(', '\'', '"', '`'])
        .trim_end_matches([']', ')', '\'', '"', '`', ',', '.'])
        .to_string()
}

/// The binary a word names, if it is one of [`BINARIES`].
fn binary(word: &str) -> Option<&'static str> {
    let name = word.rsplit('/').next().unwrap_or(word);
    BINARIES.into_iter().find(|b| *b == name)
}

/// The command in one segment's words.
fn from_words(words: &[String]) -> Option<CommandLine> {
    if let Some(pos) = words.iter().position(|w| w == "cargo") {
        if words.get(pos + 1).map(String::as_str) == Some("run") {
            return cargo_run(&words[pos + 2..]);
        }
        return None;
    }
    let pos = words.iter().position(|w| binary(w).is_some())?;
    Some(CommandLine {
        bin: binary(&words[pos])?,
        words: words[pos + 1..]
            .iter()
            .filter(|w| !w.is_empty())
            .cloned()
            .collect(),
    })
}

/// `cargo run [OPTIONS] -- WORDS` of one of [`BINARIES`].
fn cargo_run(words: &[String]) -> Option<CommandLine> {
    let dashes = words.iter().position(|w| w == "--");
    let options = &words[..dashes.unwrap_or(words.len())];
    let value = |flag: &str| {
        options
            .iter()
            .position(|w| w == flag)
            .and_then(|i| options.get(i + 1))
            .map(String::as_str)
    };
    let bin = match (value("--bin"), value("-p").or(value("--package"))) {
        (Some(b), _) => binary(b)?,
        (None, Some("hnav-bench")) => "hnav-bench",
        (None, Some("hnav-operator")) => "hnav",
        _ => return None,
    };
    let words = match dashes {
        Some(d) => words[d + 1..].to_vec(),
        None => Vec::new(),
    };
    Some(CommandLine { bin, words })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn one(text: &str, fence: bool) -> (&'static str, Vec<String>) {
        let c = commands(text, fence);
        assert_eq!(c.len(), 1, "{text}: {c:?}");
        (c[0].bin, c[0].words.clone())
    }

    #[test]
    fn names_subcommands_and_flags_of_both_binaries() {
        let (bin, words) = one("hnav run scenarios/demo.toml --replicas 3", false);
        assert_eq!(bin, "hnav");
        assert_eq!(words, ["run", "scenarios/demo.toml", "--replicas", "3"]);
        let (bin, words) = one(
            "cargo build --release && target/release/hnav run x.toml --force   # run (--nope)",
            true,
        );
        assert_eq!((bin, words[0].as_str(), words.len()), ("hnav", "run", 3));
        let (bin, words) = one("./target/debug/hnav-bench chaos --class kill-leader", true);
        assert_eq!((bin, words.len()), ("hnav-bench", 3));
    }

    #[test]
    fn cargo_run_names_its_binary_after_the_dashes() {
        let (bin, words) = one(
            "cargo run -p hnav-operator --bin hnav -- map check a.map --scen a.scen",
            false,
        );
        assert_eq!(
            (bin, words[0].as_str(), words[1].as_str()),
            ("hnav", "map", "check")
        );
        let (bin, words) = one("cargo run --release -p hnav-bench -- neural-map", true);
        assert_eq!((bin, words), ("hnav-bench", vec!["neural-map".to_string()]));
    }

    #[test]
    fn other_tools_name_nothing() {
        assert!(commands("cargo test --release -p hnav-coordinator --lib", true).is_empty());
        assert!(commands("cargo bench -p hnav-bench --bench astar", true).is_empty());
        assert!(commands("hnav_runtime::scenario", false).is_empty());
        assert!(commands("target/hnav-out/demo/summary.json", false).is_empty());
        assert!(commands("cargo run -p hnav-agent -- --x", false).is_empty());
    }

    #[test]
    fn usage_notation_is_dropped() {
        let (_, words) = one(
            "hnav run SCENARIO [--mode lockstep|realtime] [--kill|--term|--freeze FAULT]...",
            false,
        );
        assert_eq!(words[2], "--mode");
        assert_eq!(flags(&words[4]), ["--kill", "--term", "--freeze"]);
        assert_eq!(flags("--kill/--term"), ["--kill", "--term"]);
        assert_eq!(flags("--mode=lockstep"), ["--mode"]);
        assert!(flags("--").is_empty());
        assert!(flags("a--b").is_empty());
        let (_, words) = one("'hnav top topdemo-1'", false);
        assert_eq!(words, ["top", "topdemo-1"]);
    }
}
