//! Unit tests of `[[faults]]`: times in rounds or seconds, kills and freezes, their errors,
//! and the hash of a plan.

use super::test_support::{parse, BASE};
use super::*;

/// `BASE` with one `[[faults]]` entry; its first key is on line 17.
fn fault(body: &str) -> Result<Scenario, ScenarioError> {
    parse(&format!("{BASE}[[faults]]\n{body}"))
}

fn fault_err(body: &str) -> String {
    fault(body).unwrap_err().to_string()
}

#[test]
fn times_in_seconds_and_freezes_parse() {
    let s = fault("at_s = 2.5\naction = \"kill\"\nrole = \"coordinator\"\nsignal = \"TERM\"\n")
        .unwrap();
    assert_eq!(
        s.faults[0],
        FaultSpec {
            at: FaultTime::Seconds(2.5),
            action: FaultAction::Kill(FaultSignal::Term),
            target: FaultTarget::Coordinator,
        }
    );
    let s = fault("at_round = 60\naction = \"freeze\"\nrole = \"agent\"\nindex = 1\nfor_s = 3\n")
        .unwrap();
    assert_eq!(
        s.faults[0],
        FaultSpec {
            at: FaultTime::Round(60),
            action: FaultAction::Freeze { for_s: Some(3.0) },
            target: FaultTarget::Agent(1),
        }
    );
    let s = fault("at_s = 0\naction = \"freeze\"\nrole = \"sim\"\n").unwrap();
    assert_eq!(s.faults[0].action, FaultAction::Freeze { for_s: None });
}

#[test]
fn every_bad_combination_names_its_line() {
    assert_eq!(
        fault_err("at_round = 4\nat_s = 1.0\naction = \"kill\"\nrole = \"sim\"\n"),
        "t.toml:18: fault 0: give one of `at_round` and `at_s`, not both"
    );
    assert_eq!(
        fault_err("action = \"kill\"\nrole = \"sim\"\n"),
        "t.toml:16: fault 0: needs `at_round` or `at_s`"
    );
    assert_eq!(
        fault_err("at_round = 4\naction = \"kill\"\nrole = \"sim\"\nfor_s = 1.0\n"),
        "t.toml:20: fault 0: `for_s` is only meaningful with action = \"freeze\""
    );
    assert_eq!(
        fault_err("at_round = 4\naction = \"freeze\"\nrole = \"sim\"\nsignal = \"KILL\"\n"),
        "t.toml:20: fault 0: `signal` is only meaningful with action = \"kill\" \
         (a freeze sends SIGSTOP, then SIGCONT after `for_s`)"
    );
    assert_eq!(
        fault_err("at_s = -1\naction = \"kill\"\nrole = \"sim\"\n"),
        "t.toml:17: fault 0: `at_s` must be a finite number of seconds >= 0, got -1"
    );
    assert_eq!(
        fault_err("at_s = nan\naction = \"kill\"\nrole = \"sim\"\n"),
        "t.toml:17: fault 0: `at_s` must be a finite number of seconds >= 0, got NaN"
    );
    assert_eq!(
        fault_err("at_round = 4\naction = \"freeze\"\nrole = \"sim\"\nfor_s = 0\n"),
        "t.toml:20: fault 0: `for_s` must be a positive, finite number of seconds, got 0"
    );
    let e = fault("at_round = 4\naction = \"pause\"\nrole = \"sim\"\n").unwrap_err();
    assert!(matches!(e, ScenarioError::Toml { .. }), "{e}");
    assert!(e.to_string().starts_with("t.toml:18: "), "{e}");
    let e = fault("at_round = 4\naction = \"kill\"\nrole = \"sim\"\nfor = 1\n").unwrap_err();
    assert!(matches!(e, ScenarioError::UnknownKey { .. }), "{e}");
    assert!(e.to_string().contains("for_s"), "lists the keys: {e}");
}

#[test]
fn a_time_in_seconds_is_a_round_in_lockstep() {
    let s = fault("at_s = 0.3\naction = \"kill\"\nrole = \"sim\"\n").unwrap();
    // 10 ms control periods by default.
    assert_eq!(s.faults[0].lockstep_round(&s.sim), 30);
    let s = fault("at_round = 7\naction = \"kill\"\nrole = \"sim\"\n").unwrap();
    assert_eq!(s.faults[0].lockstep_round(&s.sim), 7);
}

#[test]
fn a_kill_plan_keeps_its_hash_and_new_kinds_change_it() {
    let kills = "[[faults]]\nat_round = 40\naction = \"kill\"\nrole = \"agent\"\nindex = 1\n\
                 [[faults]]\nat_round = 90\naction = \"kill\"\nrole = \"coordinator\"\n\
                 signal = \"TERM\"\n";
    let mut s = parse(&format!("{BASE}{kills}")).unwrap();
    // What `hnav check` printed for this scenario before times in seconds and freezes, when
    // the dissertation's rules were the only ones.
    s.coordinator.rules = Rules::Dissertation;
    assert_eq!(format!("{:016x}", s.scenario_hash()), "a74e51dad32551c6");
    let mut seconds = s.clone();
    seconds.faults[0].at = FaultTime::Seconds(40.0);
    let mut freeze = s.clone();
    freeze.faults[0].action = FaultAction::Freeze { for_s: None };
    let mut thawed = s.clone();
    thawed.faults[0].action = FaultAction::Freeze { for_s: Some(1.0) };
    let hashes = [&s, &seconds, &freeze, &thawed].map(|x| x.scenario_hash());
    for i in 0..hashes.len() {
        for j in i + 1..hashes.len() {
            assert_ne!(hashes[i], hashes[j], "{i} and {j}");
        }
    }
}

#[test]
fn revalidate_checks_the_numbers_of_faults_made_in_code() {
    let mut s = parse(BASE).unwrap();
    s.faults.push(FaultSpec {
        at: FaultTime::Round(1),
        action: FaultAction::Freeze { for_s: Some(-1.0) },
        target: FaultTarget::Sim,
    });
    assert_eq!(
        s.validate().unwrap_err().to_string(),
        "t.toml: fault 0: `for_s` must be a positive, finite number of seconds, got -1"
    );
}
