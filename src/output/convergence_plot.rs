//! Log-log convergence plots in the manner of the paper's Fig. 4: errors against h = k, one
//! curve per norm, and a dashed reference line of slope 1 (the order c(h + k) of Corollary 16).
//!
//! Each plot is written as PNG and SVG, both atomically (a temporary sibling, then a rename).

use std::path::{Path, PathBuf};

use plotters::prelude::*;

use super::plot::{ensure_fonts, FONT};
use super::OutputError;

/// One curve: its legend label and its (h, error) points. An emphasized curve is drawn thicker
/// and anchors the slope-1 line at its finest point.
#[derive(Debug, Clone)]
pub struct Curve {
    pub label: String,
    pub points: Vec<(f64, f64)>,
    pub emphasis: bool,
}

const SIZE: (u32, u32) = (900, 640);

/// Writes `stem.png` and `stem.svg`; returns their paths. Non-positive errors (log scale) are
/// left out of the curves.
pub fn write_convergence_plot(stem: &Path, title: &str, curves: &[Curve]) -> Result<Vec<PathBuf>, OutputError> {
    ensure_fonts();
    let png = stem.with_extension("png");
    let svg = stem.with_extension("svg");

    let mut text = String::new();
    draw(SVGBackend::with_string(&mut text, SIZE), title, curves)
        .map_err(|e| io_error(&svg, format!("cannot draw the plot: {e}")))?;
    super::write_atomic(&svg, text.as_bytes()).map_err(OutputError::io(&svg))?;

    // The bitmap backend writes the file itself and picks the format from the extension: draw to
    // a temporary `.png` sibling, then rename.
    let name = png
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = png.with_file_name(format!(".{name}.tmp-{}.png", std::process::id()));
    let drawn = draw(BitMapBackend::new(&tmp, SIZE), title, curves);
    if let Err(e) = drawn {
        let _ = std::fs::remove_file(&tmp);
        return Err(io_error(&png, format!("cannot draw the plot: {e}")));
    }
    std::fs::rename(&tmp, &png).map_err(|source| {
        let _ = std::fs::remove_file(&tmp);
        OutputError::Io {
            path: png.clone(),
            source,
        }
    })?;
    Ok(vec![png, svg])
}

fn io_error(path: &Path, message: String) -> OutputError {
    OutputError::Io {
        path: path.to_path_buf(),
        source: std::io::Error::other(message),
    }
}

/// The points of a curve that a log scale can show.
fn positive(points: &[(f64, f64)]) -> Vec<(f64, f64)> {
    points
        .iter()
        .copied()
        .filter(|(h, e)| *h > 0.0 && *e > 0.0 && e.is_finite())
        .collect()
}

fn draw<DB: DrawingBackend>(backend: DB, title: &str, curves: &[Curve]) -> Result<(), Box<dyn std::error::Error>>
where
    DB::ErrorType: 'static,
{
    let root = backend.into_drawing_area();
    root.fill(&WHITE)?;
    let shown: Vec<Vec<(f64, f64)>> = curves.iter().map(|c| positive(&c.points)).collect();
    // Slope 1 through the finest point of the emphasized curve: e = e_f h / h_f.
    let anchor = curves
        .iter()
        .zip(&shown)
        .find(|(c, _)| c.emphasis)
        .and_then(|(_, pts)| pts.iter().copied().min_by(|a, b| a.0.total_cmp(&b.0)));
    let all: Vec<(f64, f64)> = shown.iter().flatten().copied().collect();
    let (mut h_min, mut h_max) = all
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), p| (lo.min(p.0), hi.max(p.0)));
    if all.is_empty() {
        (h_min, h_max) = (0.1, 1.0);
    }
    let reference: Vec<(f64, f64)> = anchor
        .map(|(hf, ef)| vec![(h_min, ef * h_min / hf), (h_max, ef * h_max / hf)])
        .unwrap_or_default();
    let (e_min, e_max) = all
        .iter()
        .chain(&reference)
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), p| (lo.min(p.1), hi.max(p.1)));
    let (e_min, e_max) = if e_max > 0.0 { (e_min, e_max) } else { (1e-3, 1.0) };
    // Ticks at the levels' h (1/2, 1/4, …), not at the decades' 1, 2, 3, … multiples.
    let mut ticks: Vec<f64> = all.iter().map(|p| p.0).collect();
    ticks.sort_by(f64::total_cmp);
    ticks.dedup();

    let mut chart = ChartBuilder::on(&root)
        .caption(title, (FONT, 22))
        .margin(16)
        .x_label_area_size(50)
        .y_label_area_size(80)
        .build_cartesian_2d(
            (h_min / 1.4..h_max * 1.4).log_scale().with_key_points(ticks),
            // Headroom above the curves for the legend (upper left: errors grow with h).
            (e_min / 2.0..e_max * 40.0).log_scale(),
        )?;
    chart
        .configure_mesh()
        .x_desc("h = k")
        .y_desc("error")
        .label_style((FONT, 15))
        .axis_desc_style((FONT, 17))
        .x_label_formatter(&|h| format!("1/{:.0}", 1.0 / h))
        .x_max_light_lines(0)
        .y_label_formatter(&|e| format!("{e:.0e}"))
        .draw()?;

    for (i, (curve, points)) in curves.iter().zip(&shown).enumerate() {
        let color = Palette99::pick(i).to_rgba();
        let width = if curve.emphasis { 3 } else { 1 };
        let style = ShapeStyle {
            color,
            filled: false,
            stroke_width: width,
        };
        chart
            .draw_series(LineSeries::new(points.iter().copied(), style))?
            .label(curve.label.as_str())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], style));
        chart.draw_series(
            points
                .iter()
                .map(|&p| Circle::new(p, if curve.emphasis { 5 } else { 3 }, style.filled())),
        )?;
    }
    if !reference.is_empty() {
        let style = ShapeStyle {
            color: BLACK.to_rgba(),
            filled: false,
            stroke_width: 1,
        };
        chart
            .draw_series(DashedLineSeries::new(reference, 8, 6, style))?
            .label("slope 1: c(h + k)")
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], style));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font((FONT, 15))
        .draw()?;
    root.present()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plots_are_written_as_png_and_svg() {
        let dir = std::env::temp_dir().join(format!("thermocontact-convplot-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let curves = [
            Curve {
                label: "‖u − u_h‖_E at T".into(),
                points: vec![(0.5, 0.4), (0.25, 0.2), (0.125, 0.1)],
                emphasis: true,
            },
            Curve {
                label: "max ‖θ − θ_h‖".into(),
                points: vec![(0.5, 0.05), (0.25, 0.0), (0.125, 0.01)],
                emphasis: false,
            },
        ];
        let files = write_convergence_plot(&dir.join("study"), "test", &curves).unwrap();
        let png = std::fs::read(&files[0]).unwrap();
        assert_eq!(&png[1..4], b"PNG");
        let svg = std::fs::read_to_string(&files[1]).unwrap();
        assert!(svg.contains("<svg") && svg.contains("slope 1"));
        let left: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
        assert_eq!(left.len(), 2, "no temporary files remain");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
