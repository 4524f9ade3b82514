//! The text `hnav-bench seed002` prints: our means beside the thesis's Table 3.1, then the
//! metrics only we measure and the per-map invariants.

use std::fmt::Write as _;

use hnav_coordinator::planner::PlannerKind;

use super::{DensityResult, Seed002Report, ThesisRow, THESIS_TABLE_3_1};

impl Seed002Report {
    /// Our table beside the thesis's (rows matched by density), then the extra metrics.
    pub fn render(&self) -> String {
        let mut s = String::new();
        self.render_setup(&mut s);
        render_lengths(&mut s, &self.densities);
        render_times(&mut s, &self.densities);
        render_ratios(&mut s, &self.densities);
        render_extras(&mut s, &self.densities);
        render_invariants(&mut s, &self.densities);
        s
    }

    fn render_setup(&self, s: &mut String) {
        let c = &self.config;
        let _ = writeln!(
            s,
            "Seed 002 §4: {side} x {side} m, e = 1 m, start (0.5, 0.5) m, goal ({g}, {g}) m; \
             {} solvable maps per density (seed {}), obstacle radius {}-{} m inflated by {} m, \
             corners {:?}.\nThesis: MATLAB, one unspecified map per row. Ours: mean over the maps, \
             Rust, time in µs (the thesis's in s).\n",
            c.trials,
            c.seed,
            c.radius.0,
            c.radius.1,
            c.inflation,
            c.corner_cutting,
            side = c.side,
            g = f64::from(c.side) - 0.5,
        );
    }
}

/// A thesis value of the density's row, `-` where the thesis has no such row.
fn thesis_cell(density: f64, value: fn(&ThesisRow) -> f64) -> String {
    thesis_row(density).map_or("-".into(), |t| format!("{:.3}", value(&t)))
}

fn render_lengths(s: &mut String, densities: &[DensityResult]) {
    let _ = writeln!(
        s,
        "| density | A* L thesis | A* L ours | Theta* L thesis | Theta* L ours | Lazy L thesis | Lazy L ours |\n|---|---|---|---|---|---|---|"
    );
    for d in densities {
        let th = |f: fn(&ThesisRow) -> f64| thesis_cell(d.density, f);
        let _ = writeln!(
            s,
            "| {:.0} % | {} | {:.3} | {} | {:.3} | {} | {:.3} |",
            d.density * 100.0,
            th(|t| t.astar.0),
            d.mean(0, |r| r.length),
            th(|t| t.basic_theta.0),
            d.mean(1, |r| r.length),
            th(|t| t.lazy_theta.0),
            d.mean(2, |r| r.length),
        );
    }
}

fn render_times(s: &mut String, densities: &[DensityResult]) {
    let _ = writeln!(
        s,
        "\n| density | A* t thesis (s) | A* t ours (µs) | Theta* t thesis | Theta* t ours | Lazy t thesis | Lazy t ours |\n|---|---|---|---|---|---|---|"
    );
    for d in densities {
        let th = |f: fn(&ThesisRow) -> f64| thesis_cell(d.density, f);
        let _ = writeln!(
            s,
            "| {:.0} % | {} | {:.1} | {} | {:.1} | {} | {:.1} |",
            d.density * 100.0,
            th(|t| t.astar.1),
            d.mean(0, |r| r.time_us),
            th(|t| t.basic_theta.1),
            d.mean(1, |r| r.time_us),
            th(|t| t.lazy_theta.1),
            d.mean(2, |r| r.time_us),
        );
    }
}

fn render_ratios(s: &mut String, densities: &[DensityResult]) {
    let _ = writeln!(
        s,
        "\n| density | Lazy vs A* L thesis | ours | Lazy vs Theta* L thesis | ours | Lazy/A* t thesis | ours | Lazy/Theta* t thesis | ours |\n|---|---|---|---|---|---|---|---|---|"
    );
    for d in densities {
        let t = thesis_row(d.density);
        let pct = |a: f64, b: f64| format!("{:+.2} %", 100.0 * (a / b - 1.0));
        let ratio = |a: f64, b: f64| format!("{:.2}", a / b);
        let th = |f: &dyn Fn(&ThesisRow) -> String| t.map_or("-".into(), |t| f(&t));
        let l = |k: usize| d.mean(k, |r| r.length);
        let tm = |k: usize| d.mean(k, |r| r.time_us);
        let _ = writeln!(
            s,
            "| {:.0} % | {} | {} | {} | {} | {} | {} | {} | {} |",
            d.density * 100.0,
            th(&|t| pct(t.lazy_theta.0, t.astar.0)),
            pct(l(2), l(0)),
            th(&|t| pct(t.lazy_theta.0, t.basic_theta.0)),
            pct(l(2), l(1)),
            th(&|t| ratio(t.lazy_theta.1, t.astar.1)),
            ratio(tm(2), tm(0)),
            th(&|t| ratio(t.lazy_theta.1, t.basic_theta.1)),
            ratio(tm(2), tm(1)),
        );
    }
}

fn render_extras(s: &mut String, densities: &[DensityResult]) {
    let _ = writeln!(
        s,
        "\nOurs only (means per map): coverage / blocked after inflation, expansions, line-of-sight checks, heading changes, total turn.\n\
         | density | coverage | blocked | rejected maps | planner | expansions | LOS checks | turns | turn (deg) |\n|---|---|---|---|---|---|---|---|---|"
    );
    for d in densities {
        let n = d.trials.len().max(1) as f64;
        let cov = d.trials.iter().map(|t| t.coverage).sum::<f64>() / n;
        let blk = d.trials.iter().map(|t| t.blocked).sum::<f64>() / n;
        for (k, kind) in PlannerKind::ALL.iter().enumerate() {
            let _ = writeln!(
                s,
                "| {:.0} % | {:.1} % | {:.1} % | {} | {} | {:.1} | {:.1} | {:.2} | {:.1} |",
                d.density * 100.0,
                cov * 100.0,
                blk * 100.0,
                d.rejected_maps,
                kind,
                d.mean(k, |r| r.expansions as f64),
                d.mean(k, |r| r.los_checks as f64),
                d.mean(k, |r| r.heading_changes as f64),
                d.mean(k, |r| r.turn_deg),
            );
        }
    }
}

fn render_invariants(s: &mut String, densities: &[DensityResult]) {
    let _ = writeln!(s, "\nInvariants per map:");
    for d in densities {
        let longer = d
            .trials
            .iter()
            .filter(|t| t.runs[1].length > t.runs[0].length + 1e-9)
            .count();
        let worst = d
            .trials
            .iter()
            .map(|t| (t.runs[2].length / t.runs[1].length - 1.0).abs())
            .fold(0.0, f64::max);
        let los: (u64, u64) = d.trials.iter().fold((0, 0), |a, t| {
            (a.0 + t.runs[2].los_checks, a.1 + t.runs[1].los_checks)
        });
        let _ = writeln!(
            s,
            "  {:.0} %: Theta* longer than A* on {longer}/{} maps; |Lazy/Theta* - 1| <= {:.3} %; \
             LOS checks Lazy/Theta* = {:.3}",
            d.density * 100.0,
            d.trials.len(),
            100.0 * worst,
            los.0 as f64 / los.1.max(1) as f64,
        );
    }
}

/// The thesis's row for a density, if it has one.
fn thesis_row(density: f64) -> Option<ThesisRow> {
    THESIS_TABLE_3_1
        .iter()
        .copied()
        .find(|t| (t.density - density).abs() < 1e-9)
}
