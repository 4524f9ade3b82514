//! Parsers of command-line values that say what a value must be in the words of the
//! command line (`--agents 0` or `--agents -1`), instead of leaving it to the scenario
//! (`the scenario has no [[agents]]`) or to clap's tip about `--`.

/// `--agents N`: a whole number from 1. The upper limit is the scenario's to check, with a
/// message that names it (`msg::MAX_AGENTS`).
pub fn agent_count(text: &str) -> Result<usize, String> {
    match text.trim().parse::<i128>() {
        Ok(n) if n >= 1 => usize::try_from(n).map_err(|_| format!("{n} agents is far too many")),
        Ok(_) => Err("a run needs at least one agent: N is a whole number from 1".into()),
        Err(_) => Err("N is a whole number of agents, from 1".into()),
    }
}

/// An agent's number (`--agent N`): a whole number from 0.
pub fn agent_index(text: &str) -> Result<u32, String> {
    text.trim()
        .parse::<u32>()
        .map_err(|_| "N is an agent's number, a whole number from 0".to_string())
}

/// A seed (`--seed S`): a whole number from 0 to 2^64 - 1.
pub fn seed(text: &str) -> Result<u64, String> {
    text.trim()
        .parse::<u64>()
        .map_err(|_| format!("S is a whole number from 0 to {}", u64::MAX))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_and_seeds_say_what_they_must_be() {
        assert_eq!(agent_count("32"), Ok(32));
        assert!(agent_count("0").unwrap_err().contains("at least one agent"));
        assert!(agent_count("-1")
            .unwrap_err()
            .contains("at least one agent"));
        assert!(agent_count("x").unwrap_err().contains("whole number"));
        assert!(agent_index("-1").unwrap_err().contains("from 0"));
        assert_eq!(seed("7"), Ok(7));
        assert!(seed("-1").unwrap_err().contains("from 0"));
    }
}
