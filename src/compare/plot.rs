//! The convergence plot: relMSE against render time, log-log, one line per sampler, with the
//! 1/t slope an unbiased estimator converges at drawn for reference. SVG (plotters), so no
//! fonts are needed to write it.

use plotters::prelude::*;

/// One sampler's convergence curve: (seconds, relMSE) points.
pub struct Curve {
    /// Sampler name.
    pub name: String,
    /// Points in time order.
    pub points: Vec<(f64, f64)>,
}

/// The plot as an SVG document.
pub fn convergence_svg(title: &str, curves: &[Curve]) -> Result<String, String> {
    let pts = || curves.iter().flat_map(|c| c.points.iter()).filter(|(t, e)| *t > 0.0 && *e > 0.0);
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(t, e) in pts() {
        x0 = x0.min(t);
        x1 = x1.max(t);
        y0 = y0.min(e);
        y1 = y1.max(e);
    }
    if x0 > x1 {
        return Err("no convergence points to plot".into());
    }
    let (x0, x1, y0, y1) = (x0 * 0.8, x1 * 1.25, y0 * 0.5, y1 * 2.0);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (800, 520)).into_drawing_area();
        let e = |err: DrawingAreaErrorKind<std::io::Error>| err.to_string();
        root.fill(&WHITE).map_err(e)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 20))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
            .map_err(e)?;
        chart
            .configure_mesh()
            .x_desc("render time (s)")
            .y_desc("relMSE")
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .max_light_lines(2)
            .draw()
            .map_err(e)?;
        for (i, c) in curves.iter().enumerate() {
            let color = Palette99::pick(i).to_rgba();
            let line: Vec<(f64, f64)> = c.points.iter().copied().filter(|(t, e)| *t > 0.0 && *e > 0.0).collect();
            chart
                .draw_series(LineSeries::new(line.clone(), color.stroke_width(2)))
                .map_err(e)?
                .label(c.name.as_str())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
            chart.draw_series(line.iter().map(|&p| Circle::new(p, 3, color.filled()))).map_err(e)?;
        }
        // The 1/t slope through the middle of the plot.
        let (xm, ym) = ((x0 * x1).sqrt(), (y0 * y1).sqrt());
        let slope = vec![(x0, ym * xm / x0), (x1, ym * xm / x1)];
        chart
            .draw_series(LineSeries::new(slope, BLACK.mix(0.4).stroke_width(1)))
            .map_err(e)?
            .label("1/t")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.mix(0.4)));
        chart.configure_series_labels().border_style(BLACK).background_style(WHITE.mix(0.85)).draw().map_err(e)?;
        root.present().map_err(e)?;
    }
    Ok(svg)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn svg_has_a_line_per_sampler_and_the_slope() {
        let curves = vec![
            Curve { name: "power".into(), points: vec![(0.1, 0.5), (0.2, 0.25), (0.4, 0.12)] },
            Curve { name: "tree".into(), points: vec![(0.12, 0.1), (0.25, 0.05)] },
        ];
        let svg = convergence_svg("test", &curves).unwrap();
        assert!(svg.starts_with("<svg") && svg.contains("power") && svg.contains("tree") && svg.contains("1/t"));
        assert!(convergence_svg("empty", &[]).is_err());
    }
}
