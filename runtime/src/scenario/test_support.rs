//! What the scenario unit tests share: a small valid scenario and a parser for test text.

use std::path::Path;

use super::{Scenario, ScenarioError};

/// A 6x4 map with three obstacles and two agents crossing, valid as it is.
pub(super) const BASE: &str = r#"name = "t"
[map]
rows = [
  "......",
  ".@@...",
  "......",
  "...@..",
]
[[agents]]
start = [0, 0]
goal = [5, 3]
[[agents]]
start = [5, 0]
goal = [0, 3]
speed = 2.0
"#;

/// Parses scenario text as if it came from `t.toml` in the current directory.
pub(super) fn parse(text: &str) -> Result<Scenario, ScenarioError> {
    Scenario::from_str(text, "t.toml", Path::new("."))
}
