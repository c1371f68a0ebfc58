//! Line-and-scatter plots written as PNG with plotters' bitmap backend and the embedded
//! DejaVu Sans font (registered once; text without a registered font would panic).

use std::path::Path;
use std::sync::Once;

use anyhow::{Result, anyhow};
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

/// Draws the panels side by side into a PNG of `size` pixels.
pub fn plot_panels(path: &Path, size: (u32, u32), panels: &[Panel]) -> Result<()> {
    ensure_font();
    let err = |e: &dyn std::fmt::Display| anyhow!("cannot draw {}: {e}", path.display());
    let root = BitMapBackend::new(path, size).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let areas = root.split_evenly((1, panels.len().max(1)));
    for (area, panel) in areas.iter().zip(panels) {
        let mut chart = ChartBuilder::on(area)
            .caption(&panel.title, ("sans-serif", 20))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(
                panel.x_range.0..panel.x_range.1,
                panel.y_range.0..panel.y_range.1,
            )
            .map_err(|e| err(&e))?;
        chart
            .configure_mesh()
            .x_desc(&panel.x_label)
            .y_desc(&panel.y_label)
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
}
