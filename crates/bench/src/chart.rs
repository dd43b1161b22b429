//! A line chart as SVG, for the reports' sweeps (time against a swept parameter).

use std::fmt::Write as _;

/// One line of a [`LineChart`]: its legend and its (x, y) points in order.
pub struct Series {
    /// The legend.
    pub name: String,
    /// The points, x in the chart's x units (as placed by its ticks), y ≥ 0.
    pub points: Vec<(f64, f64)>,
}

/// A chart of lines over a linear x axis (place values on a log axis by passing their logs)
/// and a y axis from 0 to 110 % of the highest point.
pub struct LineChart {
    /// The title line.
    pub title: String,
    /// The x axis label.
    pub x_label: String,
    /// The y axis label.
    pub y_label: String,
    /// Labelled x positions; the axis spans the first to the last.
    pub x_ticks: Vec<(f64, String)>,
    /// The lines, coloured in order.
    pub series: Vec<Series>,
}

const COLOURS: [&str; 6] = [
    "#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b",
];

impl LineChart {
    /// The chart as a 700 × 380 SVG document.
    pub fn svg(&self) -> String {
        let highest = self
            .series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.1))
            .fold(0.0, f64::max);
        let max = if highest > 0.0 { highest * 1.1 } else { 1.0 };
        let (pw, ph, left, top) = (520.0, 300.0, 60.0, 30.0);
        let first = self.x_ticks.first().map_or(0.0, |t| t.0);
        let last = self.x_ticks.last().map_or(1.0, |t| t.0);
        let span = if last > first { last - first } else { 1.0 };
        let x_of = |x: f64| left + (x - first) / span * pw;
        let y_of = |y: f64| top + ph - y / max * ph;
        let bottom = top + ph;
        let mut svg = format!(
            "<svg xmlns='http://www.w3.org/2000/svg' width='700' height='380' font-family='sans-serif' font-size='12'>\n<rect width='700' height='380' fill='white'/>\n<text x='{left}' y='18'>{}</text>\n<line x1='{left}' y1='{bottom}' x2='{}' y2='{bottom}' stroke='black'/>\n<line x1='{left}' y1='{top}' x2='{left}' y2='{bottom}' stroke='black'/>\n",
            self.title,
            left + pw,
        );
        for (x, label) in &self.x_ticks {
            let _ = writeln!(
                svg,
                "<text x='{}' y='{}' text-anchor='middle'>{label}</text>",
                x_of(*x),
                bottom + 16.0
            );
        }
        for step in 0..=4 {
            let y = max * f64::from(step) / 4.0;
            let _ = writeln!(
                svg,
                "<text x='{}' y='{}' text-anchor='end'>{y:.2}</text>",
                left - 6.0,
                y_of(y) + 4.0
            );
        }
        let _ = writeln!(
            svg,
            "<text x='{}' y='{}' text-anchor='middle'>{}</text>\n<text x='14' y='{c}' transform='rotate(-90 14 {c})'>{}</text>",
            left + pw / 2.0,
            bottom + 34.0,
            self.x_label,
            self.y_label,
            c = top + ph / 2.0,
        );
        for (i, series) in self.series.iter().enumerate() {
            let colour = COLOURS[i % COLOURS.len()];
            let points: Vec<String> = series
                .points
                .iter()
                .map(|&(x, y)| format!("{:.1},{:.1}", x_of(x), y_of(y)))
                .collect();
            let _ = writeln!(
                svg,
                "<polyline fill='none' stroke='{colour}' stroke-width='2' points='{}'/>\n<text x='{}' y='{}' fill='{colour}'>{}</text>",
                points.join(" "),
                left + pw + 12.0,
                top + 16.0 * i as f64 + 10.0,
                series.name
            );
        }
        svg.push_str("</svg>\n");
        svg
    }
}
