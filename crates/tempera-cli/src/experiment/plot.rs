//! Error-versus-time plots of an experiment as SVG (plotters): log-log axes, one line per
//! method through the mean over seeds, and a band from the smallest to the largest seed.

use plotters::prelude::*;

/// One method's curve: per time, the mean, smallest and largest value over seeds.
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64, f64, f64)>,
}

/// Distinguishable line colours (Okabe–Ito, then Tableau).
const PALETTE: [RGBColor; 10] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(230, 159, 0),
    RGBColor(86, 180, 233),
    RGBColor(120, 120, 120),
    RGBColor(240, 228, 66),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];

pub fn colour(i: usize) -> RGBColor {
    PALETTE[i % PALETTE.len()]
}

/// A log-log SVG plot of `series` (`metric` names the y axis); positive values only.
pub fn error_vs_time(title: &str, metric: &str, x_desc: &str, series: &[Series]) -> Result<String, String> {
    let positive = |v: f64| v.is_finite() && v > 0.0;
    let xs = series.iter().flat_map(|s| s.points.iter().map(|p| p.0)).filter(|&v| positive(v));
    let ys = series.iter().flat_map(|s| s.points.iter().flat_map(|p| [p.2, p.3])).filter(|&v| positive(v));
    let range =
        |it: &mut dyn Iterator<Item = f64>| it.fold((f64::INFINITY, 0.0f64), |(lo, hi), v| (lo.min(v), hi.max(v)));
    let (x0, x1) = range(&mut xs.into_iter());
    let (y0, y1) = range(&mut ys.into_iter());
    if !(x0.is_finite() && y0.is_finite()) {
        return Err(format!("{title}: nothing to plot"));
    }
    // Pad the ranges (by a factor) so that single points and flat lines stay visible.
    let (x0, x1) = (x0 / 1.25, x1 * 1.25);
    let (y0, y1) = (y0 / 1.5, y1 * 1.5);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (720, 440)).into_drawing_area();
        let err = |e: DrawingAreaErrorKind<_>| format!("{title}: {e}");
        root.fill(&WHITE).map_err(err)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc(metric)
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .x_label_formatter(&|v| format!("{v}"))
            .draw()
            .map_err(err)?;
        for (i, s) in series.iter().enumerate() {
            let c = colour(i);
            let points: Vec<_> = s.points.iter().filter(|p| positive(p.0) && positive(p.2) && positive(p.3)).collect();
            if points.len() > 1 {
                let band: Vec<(f64, f64)> =
                    points.iter().map(|p| (p.0, p.3)).chain(points.iter().rev().map(|p| (p.0, p.2))).collect();
                chart.draw_series(std::iter::once(Polygon::new(band, c.mix(0.15)))).map_err(err)?;
            }
            let line: Vec<(f64, f64)> = points.iter().filter(|p| positive(p.1)).map(|p| (p.0, p.1)).collect();
            chart
                .draw_series(LineSeries::new(line.clone(), c.stroke_width(2)))
                .map_err(err)?
                .label(s.name.clone())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(2)));
            chart.draw_series(line.iter().map(|&p| Circle::new(p, 3, c.filled()))).map_err(err)?;
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(err)?;
        root.present().map_err(err)?;
    }
    Ok(svg)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plots_have_one_line_per_method_and_a_legend() {
        let series = vec![
            Series { name: "mmlt".into(), points: vec![(1.0, 0.1, 0.08, 0.12), (2.0, 0.05, 0.04, 0.06)] },
            Series { name: "tempered".into(), points: vec![(1.0, 0.2, 0.1, 0.3), (2.0, 0.1, 0.05, 0.2)] },
        ];
        let svg = error_vs_time("default", "relMSE", "time (s)", &series).unwrap();
        assert!(svg.starts_with("<svg") && svg.contains("</svg>"));
        assert!(svg.contains("mmlt") && svg.contains("tempered") && svg.contains("relMSE"));
        assert!(svg.matches("<polyline").count() >= 2, "{svg}");
        assert!(error_vs_time("empty", "relMSE", "time (s)", &[]).is_err());
    }
}
