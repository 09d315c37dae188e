//! Charts: bars with quantile whiskers in one panel per group, and lines with markers and a
//! legend. Drawn with plotters into memory and written atomically.

use std::path::Path;

use plotters::coord::ranged1d::SegmentValue;
use plotters::prelude::*;

use crate::error::draw_error;
use crate::font::{FONT_FAMILY, register_default_font};
use crate::{PlotError, write_png};

const WIDTH: u32 = 1000;
const HEIGHT: u32 = 620;

/// Distinct colours for up to ten series (matplotlib's tab10).
const PALETTE: [RGBColor; 10] = [
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

/// One bar: a method's mean and its 25–75 % quantile whisker.
#[derive(Clone, Debug, PartialEq)]
pub struct Bar {
    pub label: String,
    pub mean: f64,
    pub quantiles: [f64; 2],
}

/// A named sequence of (x, y) points.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64)>,
}

/// One panel per group (e.g. difficulty) with a bar per method, whiskers at the quantiles, the
/// mean written above each bar.
pub fn bar_chart(path: &Path, title: &str, y_label: &str, groups: &[(String, Vec<Bar>)]) -> Result<(), PlotError> {
    register_default_font();
    // Wide enough for every bar's label (~7 px per character at the label font).
    let bars_total: usize = groups.iter().map(|(_, bars)| bars.len()).sum();
    let longest_label = groups.iter().flat_map(|(_, bars)| bars.iter().map(|b| b.label.chars().count())).max();
    let bar_width = 130.max(7 * longest_label.unwrap_or(0) as u32 + 16);
    let width = WIDTH.max(bar_width * bars_total as u32 + 90 * groups.len() as u32);
    let mut rgb = vec![255u8; 3 * (width * HEIGHT) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (width, HEIGHT)).into_drawing_area();
        let root = root.titled(title, (FONT_FAMILY, 26)).map_err(draw_error(path))?;
        let panels = root.split_evenly((1, groups.len().max(1)));
        let top = groups
            .iter()
            .flat_map(|(_, bars)| bars.iter().map(|b| b.quantiles[1].max(b.mean)))
            .filter(|v| v.is_finite())
            .fold(0.0f64, f64::max)
            .max(0.1)
            * 1.15;
        for (panel, (group, bars)) in panels.iter().zip(groups) {
            let names: Vec<String> = bars.iter().map(|b| b.label.clone()).collect();
            let mut chart = ChartBuilder::on(panel)
                .caption(group, (FONT_FAMILY, 22))
                .margin(12)
                .x_label_area_size(40)
                .y_label_area_size(60)
                // A segmented range a..b has b − a + 1 segments.
                .build_cartesian_2d((0..bars.len() as i32 - 1).into_segmented(), 0.0..top)
                .map_err(draw_error(path))?;
            chart
                .configure_mesh()
                .disable_x_mesh()
                .y_desc(y_label)
                .label_style((FONT_FAMILY, 13))
                // One label per bar: plotters draws at most ten by default.
                .x_labels(bars.len())
                .x_label_formatter(&|v| match v {
                    SegmentValue::CenterOf(i) => names.get(*i as usize).cloned().unwrap_or_default(),
                    _ => String::new(),
                })
                .draw()
                .map_err(draw_error(path))?;
            for (i, bar) in bars.iter().enumerate() {
                let i = i as i32;
                let colour = PALETTE[i as usize % PALETTE.len()];
                let mut rect = Rectangle::new(
                    [(SegmentValue::Exact(i), 0.0), (SegmentValue::Exact(i + 1), bar.mean)],
                    colour.mix(0.85).filled(),
                );
                rect.set_margin(0, 0, 12, 12);
                chart.draw_series(std::iter::once(rect)).map_err(draw_error(path))?;
                chart
                    .draw_series(std::iter::once(PathElement::new(
                        vec![
                            (SegmentValue::CenterOf(i), bar.quantiles[0]),
                            (SegmentValue::CenterOf(i), bar.quantiles[1]),
                        ],
                        BLACK.stroke_width(2),
                    )))
                    .map_err(draw_error(path))?;
                let above = bar.quantiles[1].max(bar.mean) + 0.02 * top;
                chart
                    .draw_series(std::iter::once(Text::new(
                        format!("{:.3}", bar.mean),
                        (SegmentValue::CenterOf(i), above),
                        (FONT_FAMILY, 16).into_font().color(&BLACK).pos(plotters::style::text_anchor::Pos::new(
                            plotters::style::text_anchor::HPos::Center,
                            plotters::style::text_anchor::VPos::Bottom,
                        )),
                    )))
                    .map_err(draw_error(path))?;
            }
        }
        root.present().map_err(draw_error(path))?;
    }
    write_png(path, width, HEIGHT, &rgb)
}

/// Lines with markers, one per series, with a legend.
pub fn line_chart(path: &Path, title: &str, x_label: &str, y_label: &str, series: &[Series]) -> Result<(), PlotError> {
    register_default_font();
    let points = || series.iter().flat_map(|s| s.points.iter()).filter(|(x, y)| x.is_finite() && y.is_finite());
    let x_max = points().map(|p| p.0).fold(1.0f64, f64::max);
    let y_max = points().map(|p| p.1).fold(0.1f64, f64::max) * 1.1;
    let mut rgb = vec![255u8; 3 * (WIDTH * HEIGHT) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (WIDTH, HEIGHT)).into_drawing_area();
        let mut chart = ChartBuilder::on(&root)
            .caption(title, (FONT_FAMILY, 26))
            .margin(16)
            .x_label_area_size(45)
            .y_label_area_size(65)
            .build_cartesian_2d(0.0..x_max, 0.0..y_max)
            .map_err(draw_error(path))?;
        chart
            .configure_mesh()
            .x_desc(x_label)
            .y_desc(y_label)
            .label_style((FONT_FAMILY, 15))
            .x_labels(x_max as usize + 1)
            .x_label_formatter(&|x| format!("{x:.0}"))
            .draw()
            .map_err(draw_error(path))?;
        for (k, s) in series.iter().enumerate() {
            let colour = PALETTE[k % PALETTE.len()];
            chart
                .draw_series(LineSeries::new(s.points.iter().copied(), colour.stroke_width(3)))
                .map_err(draw_error(path))?
                .label(s.label.clone())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], colour.stroke_width(3)));
            chart
                .draw_series(s.points.iter().map(|&p| Circle::new(p, 5, colour.filled())))
                .map_err(draw_error(path))?;
        }
        chart
            .configure_series_labels()
            .label_font((FONT_FAMILY, 17))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(draw_error(path))?;
        root.present().map_err(draw_error(path))?;
    }
    write_png(path, WIDTH, HEIGHT, &rgb)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn decode(path: &Path) -> (u32, u32) {
        let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
        let reader = decoder.read_info().unwrap();
        (reader.info().width, reader.info().height)
    }

    #[test]
    fn charts_are_written_as_pngs() {
        let dir = tempfile::tempdir().unwrap();
        let bars = vec![
            Bar { label: "amber-mean".into(), mean: 0.3, quantiles: [0.2, 0.4] },
            Bar { label: "amber-max".into(), mean: 0.35, quantiles: [0.25, 0.5] },
        ];
        let path = dir.path().join("bars.png");
        bar_chart(&path, "normalised DCD", "normalised DCD", &[("easy".into(), bars.clone()), ("hard".into(), bars)])
            .unwrap();
        assert_eq!(decode(&path), (WIDTH, HEIGHT));
        let one = vec![Bar { label: "amber-mean".into(), mean: 0.3, quantiles: [0.2, 0.4] }];
        bar_chart(&path, "one bar", "normalised DCD", &[("hard".into(), one)]).unwrap();
        let path = dir.path().join("steps.png");
        let series = Series { label: "amber-mean".into(), points: vec![(0.0, 1.0), (1.0, 0.5), (2.0, 0.3)] };
        line_chart(&path, "per step", "step", "normalised DCD", &[series]).unwrap();
        assert_eq!(decode(&path), (WIDTH, HEIGHT));
    }
}
