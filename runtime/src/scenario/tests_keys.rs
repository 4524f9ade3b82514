//! [`KEYS`] is every key the parser takes, table by table: the docs that describe the format
//! are checked against it (`tests/tests/docs.rs`), so it must not drift from the parser.

use super::test_support::{parse, BASE};
use super::*;

/// The keys the parser's unknown-key error lists for `table` of [`KEYS`].
fn accepted(table: &str) -> Vec<String> {
    let text = match table {
        "" => format!("zz_unknown = 1\n{BASE}"),
        "map" => BASE.replace("[map]\n", "[map]\nzz_unknown = 1\n"),
        "agents" => BASE.replacen("[[agents]]\n", "[[agents]]\nzz_unknown = 1\n", 1),
        "faults" => format!("{BASE}[[faults]]\nzz_unknown = 1\n"),
        "events" => format!("{BASE}[[events]]\nzz_unknown = 1\n"),
        "restart.ROLE" => format!("{BASE}[restart]\nagent = {{ zz_unknown = 1 }}\n"),
        "tasks.goals" => {
            format!("{BASE}[tasks]\nstream = \"list\"\n[[tasks.goals]]\nzz_unknown = 1\n")
        }
        t => format!("{BASE}[{t}]\nzz_unknown = 1\n"),
    };
    match parse(&text) {
        Err(ScenarioError::UnknownKey { key, expected, .. }) => {
            assert_eq!(key, "zz_unknown", "{table}");
            let mut keys: Vec<String> = expected
                .split('`')
                .skip(1)
                .step_by(2)
                .map(String::from)
                .collect();
            keys.sort();
            keys
        }
        other => panic!("[{table}] with an unknown key: {other:?}"),
    }
}

#[test]
fn keys_are_every_key_the_parser_takes() {
    for (table, keys) in KEYS {
        let mut listed: Vec<String> = keys.iter().map(|k| k.to_string()).collect();
        listed.sort();
        assert_eq!(accepted(table), listed, "table `{table}`");
    }
}
