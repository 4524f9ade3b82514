//! `latency.svg`: one-way p50 (solid, dots) and p99 (dashed) against payload size, one colour
//! per transport and mode, both axes logarithmic, so that a zero-copy row stays flat while a
//! copying one climbs with the size. The size axis is drawn as log2 of the size, so that its
//! ticks fall on powers of two and read as `64 B`, `4 KiB`, `4 MiB`.

use std::collections::BTreeMap;
use std::path::Path;

use anyhow::{anyhow, ensure, Result};
use plotters::prelude::*;

use super::report::fmt_size;
use super::{Direction, Mode, Point, TransportKind};

/// Pixels of the picture.
const SIZE: (u32, u32) = (960, 600);

/// The one-way points of each transport and mode, by size.
fn series(points: &[Point]) -> BTreeMap<(TransportKind, Mode), Vec<&Point>> {
    let mut out: BTreeMap<(TransportKind, Mode), Vec<&Point>> = BTreeMap::new();
    for p in points.iter().filter(|p| p.direction == Direction::OneWay) {
        out.entry((p.transport, p.mode)).or_default().push(p);
    }
    for v in out.values_mut() {
        v.sort_by_key(|p| p.size);
    }
    out
}

/// Draws the one-way points of `points` into the SVG file `path`.
pub fn write_svg(path: &Path, points: &[Point]) -> Result<()> {
    let series = series(points);
    ensure!(!series.is_empty(), "no one-way points to plot");
    let all = series.values().flatten();
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, 0f64, f64::MAX, 0f64);
    for p in all {
        x0 = x0.min(log2(p.size));
        x1 = x1.max(log2(p.size));
        y0 = y0.min(p.summary.p50_us().max(0.01));
        y1 = y1.max(p.summary.p99_us().max(0.01));
    }
    // Room around the points; one decade at least on the latency axis.
    let (x0, x1) = (x0 - 0.5, x1 + 0.5);
    let (y0, y1) = (y0 / 1.5, (y1 * 1.5).max(y0 * 10.0));
    draw(path, &series, (x0, x1), (y0, y1)).map_err(|e| anyhow!("draw {}: {e}", path.display()))
}

/// The x coordinate of `size` bytes.
fn log2(size: usize) -> f64 {
    (size as f64).log2()
}

/// The label of tick `v` of the size axis: the size at even powers of two (16 B, 64 B, ...,
/// 4 MiB: every other power, so that the labels do not run into each other), else nothing.
fn size_label(v: f64) -> String {
    let whole = (v - v.round()).abs() < 1e-9;
    if whole && (0.0..63.0).contains(&v) && (v.round() as u32).is_multiple_of(2) {
        fmt_size(1usize << v.round() as u32)
    } else {
        String::new()
    }
}

fn draw(
    path: &Path,
    series: &BTreeMap<(TransportKind, Mode), Vec<&Point>>,
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
) -> Result<(), Box<dyn std::error::Error>> {
    let root = SVGBackend::new(path, SIZE).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            "one-way latency against payload size: p50 (solid) and p99 (dashed)",
            ("sans-serif", 20),
        )
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(64)
        .build_cartesian_2d(x0..x1, (y0..y1).log_scale())?;
    chart
        .configure_mesh()
        .x_desc("payload")
        .y_desc("latency, µs")
        .x_labels(((x1 - x0) as usize).max(2))
        .x_label_formatter(&|v| size_label(*v))
        .y_label_formatter(&|v| format!("{v}"))
        .draw()?;
    for (i, ((t, m), pts)) in series.iter().enumerate() {
        let colour = Palette99::pick(i).to_rgba();
        let p50: Vec<(f64, f64)> = pts
            .iter()
            .map(|p| (log2(p.size), p.summary.p50_us().max(y0)))
            .collect();
        let p99: Vec<(f64, f64)> = pts
            .iter()
            .map(|p| (log2(p.size), p.summary.p99_us().max(y0)))
            .collect();
        chart
            .draw_series(LineSeries::new(p50.iter().copied(), colour.stroke_width(2)))?
            .label(format!("{}/{}", t.name(), m.name()))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour));
        chart.draw_series(p50.iter().map(|&c| Circle::new(c, 3, colour.filled())))?;
        chart.draw_series(DashedLineSeries::new(p99, 6, 4, colour.stroke_width(1)))?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .border_style(BLACK)
        .background_style(WHITE.mix(0.85))
        .draw()?;
    root.present()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::latency::Summary;

    fn point(t: TransportKind, size: usize, p50: u64) -> Point {
        Point {
            transport: t,
            mode: Mode::Event,
            direction: Direction::OneWay,
            size,
            summary: Summary {
                n: 10,
                mean_ns: p50 as f64,
                p50_ns: p50,
                p90_ns: p50,
                p99_ns: 2 * p50,
                p999_ns: 3 * p50,
                max_ns: 4 * p50,
            },
        }
    }

    #[test]
    fn the_svg_has_a_line_and_a_label_per_transport() {
        let points = [
            point(TransportKind::Hnav, 64, 9_000),
            point(TransportKind::Hnav, 4 << 20, 10_000),
            point(TransportKind::Uds, 64, 5_000),
            point(TransportKind::Uds, 4 << 20, 700_000),
        ];
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("latency.svg");
        write_svg(&path, &points).unwrap();
        let svg = std::fs::read_to_string(&path).unwrap();
        assert!(svg.starts_with("<svg"), "{}", &svg[..80.min(svg.len())]);
        for label in ["hnav/event", "uds/event", "4 MiB"] {
            assert!(svg.contains(label), "no {label:?} in the SVG");
        }
        // Two solid and two dashed series: at least four polylines.
        assert!(svg.matches("<polyline").count() >= 4);
    }

    #[test]
    fn no_one_way_point_is_an_error() {
        let mut p = point(TransportKind::Hnav, 64, 1);
        p.direction = Direction::RoundTrip;
        let dir = tempfile::tempdir().unwrap();
        assert!(write_svg(&dir.path().join("x.svg"), &[p]).is_err());
    }
}
