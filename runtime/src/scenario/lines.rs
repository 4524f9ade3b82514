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
    text: &'a str,
    starts: Vec<usize>,
}

impl<'a> Lines<'a> {
    pub(crate) fn new(text: &'a str, source_name: &'a str) -> Self {
        let starts = std::iter::once(0)
            .chain(text.match_indices('\n').map(|(i, _)| i + 1))
            .collect();
        Lines {
            source_name,
            text,
            starts,
        }
    }

    /// The key whose value starts at `offset`: the bare key before the last `=` of that
    /// line up to `offset` (`speed` for `speed = "fast"`, `policy` inside `agent = { policy =
    /// 3 }`), if there is one.
    fn key_before(&self, offset: usize) -> Option<&'a str> {
        let offset = offset.min(self.text.len());
        let line = self.starts[self.line(offset) - 1];
        let before = self.text.get(line..offset)?;
        let eq = before.rfind('=')?;
        let key = before[..eq]
            .rsplit(['{', ',', '['])
            .next()
            .unwrap_or("")
            .trim();
        let bare = !key.is_empty()
            && key
                .bytes()
                .all(|b| b.is_ascii_alphanumeric() || b == b'_' || b == b'-' || b == b'.');
        bare.then_some(key)
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

    /// `v`, if given, when it is in `[lo, hi]`; else an error at its line (`unit` follows
    /// the range in it: `must be in [1, 15] cells, got 0`).
    pub(super) fn in_range(
        &self,
        v: &Option<Spanned<i64>>,
        key: &str,
        (lo, hi): (i64, i64),
        unit: &str,
    ) -> Result<Option<i64>, ScenarioError> {
        let Some(v) = v else { return Ok(None) };
        let x = *v.get_ref();
        if (lo..=hi).contains(&x) {
            return Ok(Some(x));
        }
        Err(ScenarioError::InvalidParameter {
            at: self.at(v),
            key: key.into(),
            problem: format!("must be in [{lo}, {hi}]{unit}, got {x}"),
        })
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
    let key = e.span().and_then(|s| lines.key_before(s.start));
    let message = type_in_words(&message, key).unwrap_or(message);
    ScenarioError::Toml { at, message }
}

/// serde's `invalid type: string "fast", expected f64` (or `invalid value: ...`) in the
/// words of the scenario format: `speed: expected a number, got the string "fast"`. `None`
/// for any other message.
fn type_in_words(message: &str, key: Option<&str>) -> Option<String> {
    let rest = message
        .strip_prefix("invalid type: ")
        .or_else(|| message.strip_prefix("invalid value: "))?;
    let (got, expected) = rest.rsplit_once(", expected ")?;
    let plain = |s: &str| s.trim_matches('`').to_string();
    let got = if let Some(s) = got.strip_prefix("string ") {
        format!("the string {s}")
    } else if let Some(n) = got
        .strip_prefix("integer ")
        .or_else(|| got.strip_prefix("floating point "))
        .or_else(|| got.strip_prefix("boolean "))
    {
        plain(n)
    } else {
        match got {
            "sequence" => "a list".into(),
            "map" => "a table".into(),
            other => other.into(),
        }
    };
    let expected = match expected {
        "f32" | "f64" => "a number",
        "u8" | "u16" | "u32" | "u64" | "usize" => "a whole number, 0 or more",
        "i8" | "i16" | "i32" | "i64" | "isize" => "a whole number",
        "a boolean" => "true or false",
        "a string" => "a string in quotes",
        "a sequence" => "a list [...]",
        other => other,
    };
    Some(match key {
        Some(k) => format!("{k}: expected {expected}, got {got}"),
        None => format!("expected {expected}, got {got}"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn serde_type_errors_are_said_in_the_formats_words() {
        let words = |m: &str, k| type_in_words(m, k);
        assert_eq!(
            words("invalid type: string \"fast\", expected f64", Some("speed")).unwrap(),
            "speed: expected a number, got the string \"fast\""
        );
        assert_eq!(
            words("invalid value: integer `-1`, expected u32", Some("step_ms")).unwrap(),
            "step_ms: expected a whole number, 0 or more, got -1"
        );
        assert_eq!(
            words("invalid type: integer `1`, expected a boolean", None).unwrap(),
            "expected true or false, got 1"
        );
        assert_eq!(words("unknown variant `x`, expected `a`", None), None);
    }

    #[test]
    fn the_key_is_the_one_before_the_value() {
        let text = "name = \"t\"\nspeed = \"fast\"\nagent = { policy = 3 }\nrows = [1, \"a\"]\n";
        let lines = Lines::new(text, "t.toml");
        let at = |s: &str| text.find(s).unwrap();
        assert_eq!(lines.key_before(at("\"fast")), Some("speed"));
        assert_eq!(lines.key_before(at("3 }")), Some("policy"));
        assert_eq!(lines.key_before(at("\"a\"]")), Some("rows"));
        assert_eq!(lines.key_before(0), None);
    }
}
