//! The Python the client tests run (`tests/python_client.rs`, `tests/ros2.rs`,
//! `tests/foxglove.rs`): the virtual
//! environment with `clients/python/requirements.txt` installed, `$HNAV_PYTHON`, else
//! `target/py-venv/bin/python` (made by the command in docs/how-to/python-client.md). Without
//! either the tests skip, saying so, unless `HNAV_REQUIRE_PYTHON` is set (CI sets it): then
//! they fail.

use std::path::PathBuf;

use crate::swarm::repo_root;

/// The virtual environment's Python, or `None` (with the reason printed) when the test
/// should skip.
pub fn python() -> Option<PathBuf> {
    let explicit = std::env::var_os("HNAV_PYTHON").map(PathBuf::from);
    let path = explicit
        .clone()
        .unwrap_or_else(|| repo_root().join("target/py-venv/bin/python"));
    if path.exists() {
        return Some(path);
    }
    let why = format!(
        "no Python virtual environment at {} ({}); make it with `python3 -m venv target/py-venv \
         && target/py-venv/bin/pip install -r clients/python/requirements.txt`",
        path.display(),
        if explicit.is_some() {
            "$HNAV_PYTHON"
        } else {
            "the default; or set $HNAV_PYTHON"
        }
    );
    if std::env::var_os("HNAV_REQUIRE_PYTHON").is_some() {
        panic!("HNAV_REQUIRE_PYTHON is set but there is {why}");
    }
    eprintln!("SKIPPED: {why}");
    None
}
