//! Every command-line form of a fault, and every bad one with its exact error.

use super::*;

fn ok(flag: FaultFlag, value: &str) -> FaultSpec {
    parse(flag, value).unwrap_or_else(|e| panic!("{e}"))
}

fn err(flag: FaultFlag, value: &str) -> String {
    parse(flag, value).unwrap_err().to_string()
}

#[test]
fn every_form_parses() {
    assert_eq!(
        ok(FaultFlag::Kill, "agent:3@round:40"),
        FaultSpec {
            at: FaultTime::Round(40),
            action: FaultAction::Kill(FaultSignal::Kill),
            target: FaultTarget::Agent(3),
        }
    );
    assert_eq!(
        ok(FaultFlag::Kill, "coordinator@2.5s"),
        FaultSpec {
            at: FaultTime::Seconds(2.5),
            action: FaultAction::Kill(FaultSignal::Kill),
            target: FaultTarget::Coordinator,
        }
    );
    assert_eq!(
        ok(FaultFlag::Term, "sim@round:200"),
        FaultSpec {
            at: FaultTime::Round(200),
            action: FaultAction::Kill(FaultSignal::Term),
            target: FaultTarget::Sim,
        }
    );
    assert_eq!(
        ok(FaultFlag::Freeze, "agent:5@round:60+3s"),
        FaultSpec {
            at: FaultTime::Round(60),
            action: FaultAction::Freeze { for_s: Some(3.0) },
            target: FaultTarget::Agent(5),
        }
    );
    assert_eq!(
        ok(FaultFlag::Freeze, "agent:0@1s"),
        FaultSpec {
            at: FaultTime::Seconds(1.0),
            action: FaultAction::Freeze { for_s: None },
            target: FaultTarget::Agent(0),
        }
    );
    assert_eq!(ok(FaultFlag::Kill, "sim@0s").at, FaultTime::Seconds(0.0));
    assert_eq!(
        ok(FaultFlag::Freeze, "sim@0.25s+0.3s").action,
        FaultAction::Freeze { for_s: Some(0.3) }
    );
}

#[test]
fn every_bad_form_gets_its_error() {
    use FaultFlag::*;
    let cases = [
        (Kill, "agent:3", "--kill agent:3: expected TARGET@WHEN, e.g. agent:3@round:40"),
        (Kill, "@round:3", "--kill @round:3: expected TARGET@WHEN, e.g. agent:3@round:40"),
        (Kill, "sim@", "--kill sim@: expected TARGET@WHEN, e.g. agent:3@round:40"),
        (
            Freeze,
            "agent:3",
            "--freeze agent:3: expected TARGET@WHEN[+SECONDSs], e.g. agent:5@round:60+3s",
        ),
        (
            Kill,
            "robot:3@round:4",
            "--kill robot:3@round:4: unknown target `robot:3`: expected agent:N, coordinator, coordinator:ID or sim",
        ),
        (
            Kill,
            "agent@round:4",
            "--kill agent@round:4: `agent` needs its number: agent:N, e.g. agent:3",
        ),
        (Kill, "agent:x@round:4", "--kill agent:x@round:4: `x` is not an agent number"),
        (Kill, "agent:-1@round:4", "--kill agent:-1@round:4: `-1` is not an agent number"),
        (Kill, "sim@round:x", "--kill sim@round:x: `x` is not a round number"),
        (Kill, "sim@round:-4", "--kill sim@round:-4: `-4` is not a round number"),
        (
            Kill,
            "sim@40",
            "--kill sim@40: unknown time `40`: expected round:R or SECONDSs, e.g. round:40 or 2.5s",
        ),
        (
            Term,
            "sim@-1s",
            "--term sim@-1s: time `-1s` must be a finite number of seconds >= 0, got -1",
        ),
        (
            Kill,
            "sim@infs",
            "--kill sim@infs: time `infs` must be a finite number of seconds >= 0, got inf",
        ),
        (Kill, "sim@round:4+3s", "--kill sim@round:4+3s: `+3s`: only --freeze takes a duration"),
        (Term, "sim@1s+3s", "--term sim@1s+3s: `+3s`: only --freeze takes a duration"),
        (Freeze, "sim@round:4+3", "--freeze sim@round:4+3: `+3`: expected +SECONDSs, e.g. +3s"),
        (
            Freeze,
            "sim@round:4+0s",
            "--freeze sim@round:4+0s: duration `+0s` must be a positive, finite number of seconds, got 0",
        ),
    ];
    for (flag, value, want) in cases {
        assert_eq!(err(flag, value), want, "{value}");
    }
}

#[test]
fn an_agent_beyond_the_scenario_is_named_with_the_argument() {
    let f = ok(FaultFlag::Kill, "agent:9@round:40");
    assert_eq!(
        check_target(FaultFlag::Kill, "agent:9@round:40", &f, 8)
            .unwrap_err()
            .to_string(),
        "--kill agent:9@round:40: the scenario has 8 agents (0-7)"
    );
    assert!(check_target(FaultFlag::Kill, "agent:9@round:40", &f, 10).is_ok());
    let f = ok(FaultFlag::Freeze, "agent:1@1s");
    assert_eq!(
        check_target(FaultFlag::Freeze, "agent:1@1s", &f, 1)
            .unwrap_err()
            .to_string(),
        "--freeze agent:1@1s: the scenario has 1 agent (0)"
    );
}

#[test]
fn a_fault_goes_to_the_processes_and_back_unchanged() {
    for (flag, value) in [
        (FaultFlag::Kill, "agent:3@round:40"),
        (FaultFlag::Term, "coordinator@2.5s"),
        (FaultFlag::Freeze, "agent:5@round:60+3s"),
        (FaultFlag::Freeze, "sim@0.1s"),
        (FaultFlag::Kill, "sim@0.30000000000000004s"),
    ] {
        let f = ok(flag, value);
        assert_eq!(to_arg(&f), (flag, value.to_string()));
        assert_eq!(parse_process_arg(&to_process_arg(&f)), Ok(f));
        assert_eq!(f.to_string(), format!("--{} {value}", flag.name()));
    }
    assert_eq!(
        parse_process_arg("pause=sim@1s").unwrap_err(),
        "`pause=sim@1s`: expected kill=, term= or freeze= and a fault"
    );
}

#[test]
fn targets_alone_parse_for_hnav_kill() {
    assert_eq!(parse_target("agent:0"), Ok(FaultTarget::Agent(0)));
    assert_eq!(parse_target("coordinator"), Ok(FaultTarget::Coordinator));
    assert_eq!(parse_target("sim"), Ok(FaultTarget::Sim));
    assert_eq!(parse_target("coordinator:2"), Ok(FaultTarget::Replica(2)));
    assert_eq!(target_arg(FaultTarget::Replica(2)), "coordinator:2");
    assert!(parse_target("coordinator:0")
        .unwrap_err()
        .contains("not a coordinator replica"));
    assert!(parse_target("coordinator:6").is_err());
    assert_eq!(
        parse_target("agent:3@round:4").unwrap_err(),
        "`3@round:4` is not an agent number"
    );
    assert_eq!(target_arg(FaultTarget::Agent(7)), "agent:7");
}
