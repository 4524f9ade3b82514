//! Where in the scenario text a value came from: `toml` byte spans turned into the 1-based
//! lines every [`ScenarioError`] names, and `toml`'s own errors turned into ours.
//!
//! Its own module because both the section builders (`build_params`) and the agent and fault
//! checks (`validate`) need it, and `build` needs them: kept in `build`, it made the two
//! depend on each other.

use toml::Spanned;

use super::error::{Loc, ScenarioError};

/// Byte offset to 1-based line.
pub(crate) struct Lines<'a> {
    pub(crate) source_name: &'a str,
    starts: Vec<usize>,
}

impl<'a> Lines<'a> {
    pub(crate) fn new(text: &str, source_name: &'a str) -> Self {
        let starts = std::iter::once(0)
            .chain(text.match_indices('\n').map(|(i, _)| i + 1))
            .collect();
        Lines {
            source_name,
            starts,
        }
    }

    pub(crate) fn line(&self, offset: usize) -> usize {
        self.starts.partition_point(|&s| s <= offset).max(1)
    }

    pub(crate) fn at<T>(&self, s: &Spanned<T>) -> Loc {
        Loc::new(self.source_name, self.line(s.span().start))
    }

    pub(super) fn at_opt<T>(&self, s: &Option<Spanned<T>>, fallback: &Loc) -> Loc {
        s.as_ref().map_or_else(|| fallback.clone(), |s| self.at(s))
    }
}

/// Converts a `toml` error, recognising serde's unknown/missing field messages so they get
/// their own variants.
pub(super) fn toml_error(e: &toml::de::Error, lines: &Lines<'_>) -> ScenarioError {
    let at = Loc::new(
        lines.source_name,
        e.span().map_or(1, |s| lines.line(s.start)),
    );
    let message = e.message().trim().to_string();
    let quoted = |rest: &str| {
        rest.split_once('`')
            .map(|(key, tail)| (key.to_string(), tail.to_string()))
    };
    if let Some((key, tail)) = message.strip_prefix("unknown field `").and_then(quoted) {
        let expected = tail.trim_start_matches(',').trim().to_string();
        return ScenarioError::UnknownKey { at, key, expected };
    }
    if let Some((key, _)) = message.strip_prefix("missing field `").and_then(quoted) {
        return ScenarioError::MissingKey { at, key };
    }
    ScenarioError::Toml { at, message }
}
