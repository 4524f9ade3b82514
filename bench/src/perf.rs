//! `hnav-bench perf`: the performance suite in one command — the latency suite, the decision
//! round at 1 to 256 agents under both fsync policies, the commit fan-out, and the neural map
//! — run one after the other on a quiet machine, so that every ratio in `docs/explanation/performance.md`
//! comes from one run.
//!
//! Each part is this binary's own subcommand run as a child process (`latency`, `round`,
//! `fanout`, `neural-map`): the parts stay usable alone, and a part that fails or hangs is reported
//! with its output instead of taking the suite down with it. Their output is echoed and kept
//! in `DIR/<part>.txt`; `DIR/perf.md` gathers the machine, each part's command and duration,
//! and the outputs, ready to paste into `docs/explanation/performance.md`.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};

use crate::latency::RunInfo;

/// One part of the suite: its name (and output file stem) and its arguments.
struct Part {
    name: &'static str,
    args: Vec<String>,
}

/// The parts of the suite, full or `quick`, writing their files under `out`.
fn parts(quick: bool, out: &Path, peers: &[PathBuf]) -> Vec<Part> {
    let out = out.display().to_string();
    let quick_flag = |args: &mut Vec<String>| {
        if quick {
            args.push("--quick".into());
        }
    };
    let mut latency = vec!["latency".into(), "--out".into(), out.clone()];
    quick_flag(&mut latency);
    if !peers.is_empty() {
        let files: Vec<String> = peers.iter().map(|p| p.display().to_string()).collect();
        latency.extend(["--peers".into(), files.join(",")]);
    }
    let mut round = vec![
        "round".into(),
        "--agents".into(),
        "1,8,32,128,256".into(),
        "--fsync".into(),
        "every-record,none".into(),
        "--out".into(),
        out.clone(),
    ];
    quick_flag(&mut round);
    let mut fanout = vec!["fanout".into(), "--out".into(), out];
    quick_flag(&mut fanout);
    let mut neural = vec!["neural-map".into()];
    quick_flag(&mut neural);
    vec![
        Part {
            name: "latency",
            args: latency,
        },
        Part {
            name: "round",
            args: round,
        },
        Part {
            name: "fanout",
            args: fanout,
        },
        Part {
            name: "neural-map",
            args: neural,
        },
    ]
}

/// What one part gave.
struct Ran {
    command: String,
    took: Duration,
    stdout: String,
}

/// Runs the suite (`quick`: the smoke-check variant) and writes its files under `out`;
/// `peers` are CSV files of peer rows for the latency table (`latency --peers`).
pub fn run(quick: bool, out: &Path, peers: &[PathBuf]) -> Result<PathBuf> {
    std::fs::create_dir_all(out).with_context(|| format!("create {}", out.display()))?;
    let exe = std::env::current_exe().context("find the hnav-bench executable")?;
    let info = RunInfo::now();
    let started = Instant::now();
    let mut ran = Vec::new();
    for part in parts(quick, out, peers) {
        hnav_runtime::errln!("perf: {} ...", part.name);
        let r = run_part(&exe, &part)?;
        let file = out.join(format!("{}.txt", part.name));
        std::fs::write(&file, &r.stdout).with_context(|| format!("write {}", file.display()))?;
        hnav_runtime::out!("{}", r.stdout);
        ran.push((part.name, r));
    }
    let md = out.join("perf.md");
    let text = render(&info, quick, started.elapsed(), &ran);
    std::fs::write(&md, text).with_context(|| format!("write {}", md.display()))?;
    Ok(md)
}

fn run_part(exe: &Path, part: &Part) -> Result<Ran> {
    let command = format!("hnav-bench {}", part.args.join(" "));
    let t = Instant::now();
    let output = Command::new(exe)
        .args(&part.args)
        .stdin(Stdio::null())
        .stderr(Stdio::inherit())
        .output()
        .with_context(|| format!("start {command}"))?;
    let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
    if !output.status.success() {
        bail!(
            "{command} failed ({}); its output:\n{stdout}",
            output.status
        );
    }
    Ok(Ran {
        command,
        took: t.elapsed(),
        stdout,
    })
}

/// The machine as far as the suite can tell: CPU model, cores, kernel.
fn machine() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into());
    let kernel = std::fs::read_to_string("/proc/sys/kernel/osrelease")
        .map(|s| s.trim().to_string())
        .unwrap_or_else(|_| "unknown kernel".into());
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    format!("{cpu}, {cores} cores, Linux {kernel}")
}

fn render(info: &RunInfo, quick: bool, took: Duration, ran: &[(&str, Ran)]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# Performance suite ({})\n",
        if quick { "quick" } else { "full" }
    );
    let _ = writeln!(s, "- date: {}", info.date);
    let _ = writeln!(s, "- machine: {} ({})", machine(), info.platform);
    let _ = writeln!(s, "- whole suite: {:.0} s", took.as_secs_f64());
    for (name, r) in ran {
        let _ = writeln!(
            s,
            "\n## {name}\n\n`{}` ({:.0} s)\n\n```text\n{}```",
            r.command,
            r.took.as_secs_f64(),
            r.stdout
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quick_parts_pass_quick_and_write_under_the_directory() {
        let parts = parts(true, Path::new("/tmp/x"), &[]);
        let names: Vec<&str> = parts.iter().map(|p| p.name).collect();
        assert_eq!(names, ["latency", "round", "fanout", "neural-map"]);
        for p in &parts {
            assert_eq!(p.args[0], p.name);
            assert!(p.args.iter().any(|a| a == "--quick"), "{:?}", p.args);
        }
        assert!(parts[1].args.iter().any(|a| a == "1,8,32,128,256"));
        let full = super::parts(false, Path::new("/tmp/x"), &[PathBuf::from("/p/z.csv")]);
        assert!(full.iter().all(|p| !p.args.iter().any(|a| a == "--quick")));
        assert!(full[0]
            .args
            .ends_with(&["--peers".into(), "/p/z.csv".into()]));
    }
}
