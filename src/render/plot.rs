//! Line-and-scatter plots written as PNG with plotters' bitmap backend and the embedded
//! DejaVu Sans font (registered once; text without a registered font would panic).
//!
//! Tick labels ([`tick_label`]): plotters' own fixed-point labels (at most five decimals)
//! wherever they resolve the ticks — values of ordinary size, as before — and scientific
//! notation with one exponent per axis (`0.5e-13`, `1.0e-13`, `1.5e-13`) on axes whose
//! ticks are finer than 1e-4 or whose values reach 1e5, where plotters would print every
//! label of a 1e-13 axis as "0.0".

use std::path::Path;
use std::sync::Once;

use anyhow::{Result, anyhow};
use plotters::coord::ranged1d::Ranged;
use plotters::coord::types::RangedCoordf64;
use plotters::data::float::FloatPrettyPrinter;
use plotters::prelude::*;
use plotters::style::{FontStyle, register_font};

/// One curve or point set of a panel.
pub struct Series {
    pub label: Option<String>,
    pub points: Vec<(f64, f64)>,
    pub color: RGBColor,
    pub style: SeriesStyle,
}

#[derive(Clone, Copy, PartialEq, Eq)]
pub enum SeriesStyle {
    Line,
    Dashed,
    Dots,
    /// Few points that must be seen: filled circles of radius 5.
    Markers,
}

/// One panel: axes, labels and its series.
pub struct Panel {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub x_range: (f64, f64),
    pub y_range: (f64, f64),
    pub series: Vec<Series>,
}

/// A perceptually ordered palette (viridis samples) for families of curves.
pub const PALETTE: [RGBColor; 5] = [
    RGBColor(68, 1, 84),
    RGBColor(59, 82, 139),
    RGBColor(33, 145, 140),
    RGBColor(94, 201, 98),
    RGBColor(253, 231, 37),
];

/// Registers the embedded DejaVu Sans as "sans-serif", once per process.
pub(crate) fn ensure_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The embedded font cannot be invalid; if it were, the first text would say so.
        let _ = register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular());
    });
}

/// Most tick labels per axis: plotters' default, which [`AxisTicks`] assumes.
const MAX_LABELS: usize = 11;

/// How the tick labels of one axis are written: from the ticks plotters will place on
/// `lo..hi` (at most [`MAX_LABELS`], steps of 1, 2 or 5 × 10ᵏ).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisTicks {
    /// Spacing of the labelled ticks.
    pub step: f64,
    /// Scientific notation: the ticks are finer than 1e-4 (plotters' labels stop at five
    /// decimals) or the values reach 1e5.
    pub scientific: bool,
    /// The power of ten all scientific labels of the axis share: that of its largest
    /// value, so the ticks read 0.5e-13, 1.0e-13, 1.5e-13.
    pub exponent: i32,
}

/// ⌊log₁₀ |x|⌋ (0 for zero or non-finite x).
fn decade(x: f64) -> i32 {
    let l = x.abs().log10().floor();
    if l.is_finite() { l as i32 } else { 0 }
}

impl AxisTicks {
    pub fn new(lo: f64, hi: f64) -> Self {
        let (lo, hi) = (lo.min(hi), lo.max(hi));
        let ticks = if lo.is_finite() && hi.is_finite() {
            RangedCoordf64::from(lo..hi).key_points(MAX_LABELS)
        } else {
            Vec::new()
        };
        let step = ticks
            .windows(2)
            .map(|w| w[1] - w[0])
            .fold(f64::INFINITY, f64::min);
        let step = if step.is_finite() && step > 0.0 {
            step
        } else {
            hi - lo
        };
        let max_abs = lo.abs().max(hi.abs());
        // A degenerate axis (one value) goes by the size of that value.
        let fine = if step > 0.0 { step } else { max_abs };
        let scientific = (fine > 0.0 && fine < 1e-4) || max_abs >= 1e5;
        Self {
            step,
            scientific,
            exponent: decade(max_abs),
        }
    }

    /// The label of the tick at `v` ([`tick_label`]).
    pub fn label(&self, v: f64) -> String {
        // A tick within round-off of zero is zero (not "-0.0").
        let v = if v.abs() <= 1e-9 * self.step { 0.0 } else { v };
        if !self.scientific {
            return FloatPrettyPrinter {
                allow_scientific: false,
                min_decimal: 1,
                max_decimal: 5,
            }
            .print(v);
        }
        if v == 0.0 {
            return "0".into();
        }
        let e = self.exponent;
        let mantissa = v / 10f64.powi(e);
        // Enough decimals to tell ticks a step apart (1.5e-13 on a 5e-14 step), more only
        // if the value needs them (a tick between the steps plotters was assumed to use).
        let needed = if self.step > 0.0 && self.step.is_finite() {
            (e - decade(self.step)).clamp(0, 12) as usize
        } else {
            0
        };
        let d = (needed..=needed + 3)
            .find(|&d| {
                format!("{mantissa:.d$}")
                    .parse::<f64>()
                    .is_ok_and(|back| (back - mantissa).abs() <= 1e-9 * mantissa.abs())
            })
            .unwrap_or(needed + 3);
        format!("{mantissa:.d$}e{e}")
    }
}

/// The tick label of `v` on an axis over `lo..hi`: as plotters writes it ("0.25", "3.0")
/// where its five decimals resolve the ticks and the values stay below 1e5, else in
/// scientific notation with the exponent of the axis's largest value and the decimals the
/// tick spacing needs ("1.2e-13", "0.5e-13", "0").
pub fn tick_label(v: f64, lo: f64, hi: f64) -> String {
    AxisTicks::new(lo, hi).label(v)
}

/// Draws the panels side by side into a PNG of `size` pixels.
pub fn plot_panels(path: &Path, size: (u32, u32), panels: &[Panel]) -> Result<()> {
    ensure_font();
    let err = |e: &dyn std::fmt::Display| anyhow!("cannot draw {}: {e}", path.display());
    // plotters looks for tick positions without end on an axis that is not finite.
    for panel in panels {
        for (axis, (lo, hi)) in [("x", panel.x_range), ("y", panel.y_range)] {
            if !(lo.is_finite() && hi.is_finite() && (hi - lo).is_finite()) {
                return Err(err(&format!(
                    "the {axis} axis of \"{}\" would run from {lo} to {hi}",
                    panel.title
                )));
            }
        }
    }
    let root = BitMapBackend::new(path, size).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let areas = root.split_evenly((1, panels.len().max(1)));
    for (area, panel) in areas.iter().zip(panels) {
        let x_ticks = AxisTicks::new(panel.x_range.0, panel.x_range.1);
        let y_ticks = AxisTicks::new(panel.y_range.0, panel.y_range.1);
        // Room for the widest y label: 70 pixels as always for plotters' own labels, more
        // for long scientific ones (about 9 pixels a character at size 15).
        let y_area = if y_ticks.scientific {
            let widest = [panel.y_range.0, panel.y_range.1, -y_ticks.step]
                .iter()
                .map(|&v| y_ticks.label(v).chars().count())
                .max()
                .unwrap_or(0)
                .max(7);
            (30 + 9 * widest) as u32
        } else {
            70
        };
        let x_fmt = move |v: &f64| x_ticks.label(*v);
        let y_fmt = move |v: &f64| y_ticks.label(*v);
        let mut chart = ChartBuilder::on(area)
            .caption(&panel.title, ("sans-serif", 20))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(y_area)
            .build_cartesian_2d(
                panel.x_range.0..panel.x_range.1,
                panel.y_range.0..panel.y_range.1,
            )
            .map_err(|e| err(&e))?;
        chart
            .configure_mesh()
            .x_desc(&panel.x_label)
            .y_desc(&panel.y_label)
            .x_label_formatter(&x_fmt)
            .y_label_formatter(&y_fmt)
            .label_style(("sans-serif", 15))
            .axis_desc_style(("sans-serif", 17))
            .draw()
            .map_err(|e| err(&e))?;
        let mut labelled = false;
        for s in &panel.series {
            let color = s.color;
            let anno = match s.style {
                SeriesStyle::Line => chart
                    .draw_series(LineSeries::new(
                        s.points.iter().copied(),
                        color.stroke_width(2),
                    ))
                    .map_err(|e| err(&e))?,
                SeriesStyle::Dashed => chart
                    .draw_series(DashedLineSeries::new(
                        s.points.iter().copied(),
                        8,
                        5,
                        color.stroke_width(2),
                    ))
                    .map_err(|e| err(&e))?,
                SeriesStyle::Dots => chart
                    .draw_series(
                        s.points
                            .iter()
                            .map(|&p| Circle::new(p, 1, color.mix(0.35).filled())),
                    )
                    .map_err(|e| err(&e))?,
                SeriesStyle::Markers => chart
                    .draw_series(s.points.iter().map(|&p| Circle::new(p, 5, color.filled())))
                    .map_err(|e| err(&e))?,
            };
            if let Some(label) = &s.label {
                labelled = true;
                anno.label(label.as_str()).legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
                });
            }
        }
        if labelled {
            chart
                .configure_series_labels()
                .label_font(("sans-serif", 14))
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .position(SeriesLabelPosition::UpperRight)
                .draw()
                .map_err(|e| err(&e))?;
        }
    }
    root.present().map_err(|e| err(&e))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_a_png_with_text() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.png");
        let panel = Panel {
            title: "test".into(),
            x_label: "x".into(),
            y_label: "y".into(),
            x_range: (0.0, 1.0),
            y_range: (0.0, 1.0),
            series: vec![Series {
                label: Some("line".into()),
                points: vec![(0.0, 0.0), (1.0, 1.0)],
                color: PALETTE[0],
                style: SeriesStyle::Dashed,
            }],
        };
        plot_panels(&path, (400, 300), &[panel]).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(&bytes[1..4], b"PNG");
    }

    #[test]
    fn an_axis_that_is_not_finite_is_refused_naming_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.png");
        for (x_range, y_range) in [
            ((0.0, 1.0), (0.0, f64::INFINITY)),
            ((0.0, 1.0), (f64::NAN, 1.0)),
            ((-1e308, 1e308), (0.0, 1.0)),
        ] {
            let panel = Panel {
                title: "Σ".into(),
                x_label: "x".into(),
                y_label: "y".into(),
                x_range,
                y_range,
                series: Vec::new(),
            };
            let e = plot_panels(&path, (400, 300), &[panel])
                .unwrap_err()
                .to_string();
            assert!(e.contains("p.png") && e.contains("axis of \"Σ\""), "{e}");
        }
    }

    #[test]
    fn tick_labels_show_small_and_large_values() {
        // O(1) axes: exactly plotters' own labels, as the plots always had.
        for (lo, hi) in [
            (0.0, 1.0),
            (0.2, 5.0),
            (-0.35, 0.4),
            (0.0, 0.0012),
            (-3.0, 250.0),
        ] {
            let plain = FloatPrettyPrinter {
                allow_scientific: false,
                min_decimal: 1,
                max_decimal: 5,
            };
            assert!(!AxisTicks::new(lo, hi).scientific, "{lo}..{hi}");
            for v in [lo, 0.5 * (lo + hi), hi, 0.25, 3.0] {
                assert_eq!(tick_label(v, lo, hi), plain.print(v));
            }
        }
        assert_eq!(tick_label(0.25, 0.0, 1.0), "0.25");
        assert_eq!(tick_label(-1e-17, -0.35, 0.4), "0.0");
        assert_eq!(tick_label(3.0, 0.0, 5.0), "3.0");
        // A luminosity axis of 1e-13: every label was "0.0".
        let t = AxisTicks::new(-0.2e-13, 3.4e-13);
        assert!(t.scientific && (t.step - 5e-14).abs() < 1e-27, "{t:?}");
        assert_eq!(t.label(1.0e-13), "1.0e-13");
        assert_eq!(t.label(1.5e-13), "1.5e-13");
        assert_eq!(t.label(0.5e-13), "0.5e-13");
        assert_eq!(t.label(-0.1e-13), "-0.1e-13");
        assert_eq!(t.label(0.0), "0");
        assert_eq!(t.label(-1e-30), "0");
        assert_eq!(t.label(3.0e-13 + 1e-29), "3.0e-13");
        // Ticks of 1e-14 around 1.2e-13, and of 5e-16 (two more digits); one exponent.
        assert_eq!(tick_label(1.2e-13, 1.0e-13, 1.6e-13), "1.2e-13");
        assert_eq!(tick_label(1.235e-13, 1.2e-13, 1.25e-13), "1.235e-13");
        assert_eq!(tick_label(1.23e-13, 1.2e-13, 1.25e-13), "1.230e-13");
        assert_eq!(tick_label(1.2e-13, 0.0, 2.0e-13), "1.2e-13");
        // Every label of the axis differs from the next.
        let (lo, hi) = (2.31e-15, 3.47e-15);
        let t = AxisTicks::new(lo, hi);
        let labels: Vec<String> = RangedCoordf64::from(lo..hi)
            .key_points(MAX_LABELS)
            .iter()
            .map(|&v| t.label(v))
            .collect();
        assert!(labels.len() >= 3, "{labels:?}");
        assert!(labels.windows(2).all(|w| w[0] != w[1]), "{labels:?}");
        // Large values and negative ones.
        assert_eq!(tick_label(2.0e6, 0.0, 5.0e6), "2.0e6");
        assert_eq!(tick_label(-2.5e-9, -5e-9, 5e-9), "-2.5e-9");
        assert_eq!(tick_label(1e-20, 1e-20, 1e-20), "1e-20");
        assert_eq!(tick_label(5e-16, 0.0, 2.2e-15), "0.5e-15");
        assert_eq!(tick_label(0.5, 0.5, 0.5), "0.5");
    }
}
