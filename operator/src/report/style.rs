//! The report's colours and the heatmap's log scale. A robot's marks (start, goal, committed
//! cells, trajectory, conflicts, replans, its agent down) are all in [`robot`]'s colour.

use plotters::prelude::*;
use plotters::style::colors::colormaps::ViridisRGB;

/// Obstacle cells (map and heatmaps).
pub const OBSTACLE: RGBColor = RGBColor(64, 64, 64);
/// The outline of a cell that closed during the run (a door): gold, a colour no robot has.
pub const CLOSED: RGBColor = RGBColor(255, 215, 0);
/// Floor a robot's range sensor saw during the run: a pale blue under everything.
pub const SENSED: RGBColor = RGBColor(222, 235, 247);
/// A mover's track and last place (a person, a forklift): dark red-brown, no robot's colour.
pub const MOVER: RGBColor = RGBColor(120, 40, 20);
/// The frame of a panel.
pub const FRAME: RGBColor = RGBColor(160, 160, 160);
/// Collision rings.
pub const COLLISION: RGBColor = RGBColor(228, 26, 28);

/// Matplotlib's "tab10": ten colours that stay apart on white.
const TAB10: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// Robot `i`'s colour: tab10, then plotters' 99-colour palette.
pub fn robot(i: usize) -> RGBColor {
    match TAB10.get(i) {
        Some(c) => *c,
        None => {
            let (r, g, b) = Palette99::pick(i).rgb();
            RGBColor(r, g, b)
        }
    }
}

/// The heatmap's scale: `log10` of the positive activations, from the smallest to the
/// largest of the map (a neural map falls off exponentially from its target, so a linear
/// scale would show one bright cell and black).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LogScale {
    /// `log10` of the smallest positive activation.
    pub lo: f64,
    /// `log10` of the largest.
    pub hi: f64,
}

impl LogScale {
    /// The scale of `values`; `None` when no value is positive.
    pub fn of(values: &[f32]) -> Option<Self> {
        let mut range: Option<(f64, f64)> = None;
        for v in values.iter().filter(|v| **v > 0.0 && v.is_finite()) {
            let l = f64::from(*v).log10();
            range = Some(range.map_or((l, l), |(lo, hi)| (lo.min(l), hi.max(l))));
        }
        range.map(|(lo, hi)| LogScale {
            lo,
            hi: if hi - lo < 1e-9 { lo + 1.0 } else { hi },
        })
    }

    /// The colour of activation `v`; `None` for a value that is not positive (a cell the
    /// map does not reach, or an obstacle).
    pub fn colour(&self, v: f32) -> Option<RGBColor> {
        if !(v > 0.0 && v.is_finite()) {
            return None;
        }
        let l = f64::from(v).log10().clamp(self.lo, self.hi);
        Some(ViridisRGB.get_color_normalized(l, self.lo, self.hi))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_log_scale_spans_the_positive_values() {
        let s = LogScale::of(&[0.0, 1e-6, 1e-3, 1.0, -2.0]).unwrap();
        assert!((s.lo + 6.0).abs() < 1e-6 && s.hi.abs() < 1e-9, "{s:?}");
        assert_eq!(s.colour(0.0), None);
        assert_ne!(s.colour(1e-6), s.colour(1.0));
        assert_eq!(LogScale::of(&[0.0, -1.0]), None);
        let flat = LogScale::of(&[0.5, 0.5]).unwrap();
        assert!(flat.hi > flat.lo);
    }

    #[test]
    fn robots_get_distinct_colours() {
        let cs: Vec<RGBColor> = (0..12).map(robot).collect();
        for (i, a) in cs.iter().enumerate() {
            assert!(cs[i + 1..].iter().all(|b| b != a), "robot {i}");
        }
    }
}
