//! The figures of the paper's Section 6, drawn with `plotters` into PNG and SVG.
//!
//! * [`DeformedFigure`]: panels of the deformed configuration x + s·u(x) (s the stated displacement
//!   scale, 1 as in the paper's Figs. 2 and 3), the cells filled by the temperature θ with a shared
//!   colour bar, the reference outline dashed, and on Γ_C the friction stress ξ (the traction the
//!   foundation exerts on the body, −ξ ∈ ∂j_τ(w_τ)) as arrows, stick and slip nodes marked apart
//!   and counted in each panel's title.
//! * [`SlipHistoryFigure`]: the number of slip nodes against time, with the counts the paper
//!   reports as markers.
//! * [`ContactProfileFigure`]: θ, w_τ and ξ against arc length along Γ_C at the output times.
//!
//! Any 2D mesh: the body is drawn from its cells and its outline ([`chains::outline`]), and Γ_C
//! is followed as ordered pieces ([`chains::part_chains`]) with each node's own frame (ν_i, τ_i),
//! so a curved Γ_C or one of several parts gets arrows along the curve at even arc-length steps.
//!
//! A figure is drawn once per backend from the same code ([`Figure::draw`]); [`render`] makes the
//! PNG bytes and the SVG text in memory and [`write()`] stores both atomically.

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::mesh::chains::{self, Chain};
use crate::mesh::Mesh;
use crate::model::ContactRow;
use crate::output::plot::{ensure_fonts, FONT};
use crate::output::{write_atomic, OutputError};

/// Errors of figure making.
#[derive(Debug, thiserror::Error)]
pub enum FigureError {
    /// plotters failed to draw (a backend or layout error).
    #[error("cannot draw {figure}: {message}")]
    Draw { figure: String, message: String },
    /// The PNG encoder failed.
    #[error("cannot encode {figure} as PNG: {message}")]
    Encode { figure: String, message: String },
    /// Writing a file failed.
    #[error(transparent)]
    Output(#[from] OutputError),
}

/// A drawing error before the figure's name is attached.
#[derive(Debug)]
pub struct DrawError(String);

impl<E: std::error::Error + Send + Sync> From<DrawingAreaErrorKind<E>> for DrawError {
    fn from(e: DrawingAreaErrorKind<E>) -> Self {
        DrawError(e.to_string())
    }
}

/// A figure that can draw itself on any plotters backend.
pub trait Figure {
    /// File stem and name in messages, e.g. `fig2_deformed`.
    fn name(&self) -> &str;
    /// Size in pixels.
    fn size(&self) -> (u32, u32);
    /// Draws the whole figure on `root`.
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), DrawError>;
}

/// A figure rendered in memory.
pub struct Rendered {
    /// PNG file bytes (8-bit RGB).
    pub png: Vec<u8>,
    /// SVG document.
    pub svg: String,
}

/// Renders a figure to PNG bytes and SVG text.
pub fn render(figure: &impl Figure) -> Result<Rendered, FigureError> {
    ensure_fonts();
    let (width, height) = figure.size();
    let named = |e: DrawError| FigureError::Draw {
        figure: figure.name().to_string(),
        message: e.0,
    };
    let mut pixels = vec![255u8; width as usize * height as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut pixels, (width, height)).into_drawing_area();
        figure.draw(&root).map_err(named)?;
        root.present().map_err(|e| named(e.into()))?;
    }
    let mut png = Vec::new();
    {
        use image::ImageEncoder;
        image::codecs::png::PngEncoder::new(&mut png)
            .write_image(&pixels, width, height, image::ColorType::Rgb8)
            .map_err(|e| FigureError::Encode {
                figure: figure.name().to_string(),
                message: e.to_string(),
            })?;
    }
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (width, height)).into_drawing_area();
        figure.draw(&root).map_err(named)?;
        root.present().map_err(|e| named(e.into()))?;
    }
    Ok(Rendered { png, svg })
}

/// Renders a figure and writes `DIR/NAME.png` and `DIR/NAME.svg`; returns both paths.
pub fn write(figure: &impl Figure, dir: &Path) -> Result<[PathBuf; 2], FigureError> {
    let rendered = render(figure)?;
    let png = dir.join(format!("{}.png", figure.name()));
    let svg = dir.join(format!("{}.svg", figure.name()));
    write_atomic(&png, &rendered.png).map_err(OutputError::io(&png))?;
    write_atomic(&svg, rendered.svg.as_bytes()).map_err(OutputError::io(&svg))?;
    Ok([png, svg])
}

/// One panel of a [`DeformedFigure`]: a state of the body at one time.
pub struct Panel<'a> {
    /// Title, e.g. "t = 0.25 s: 8 slip, 120 stick".
    pub title: String,
    pub mesh: &'a Mesh,
    /// Displacement u, d per node.
    pub u: &'a [f64],
    /// Temperature θ per node.
    pub theta: &'a [f64],
    /// The contact rows of Γ_C (position, w_τ, ξ, slip status).
    pub contact: &'a [ContactRow],
}

/// Deformed configurations coloured by temperature, with friction stresses and contact states.
pub struct DeformedFigure<'a> {
    /// File stem.
    pub name: String,
    /// Heading over all panels, and a second line (the setting).
    pub heading: String,
    pub subheading: String,
    pub panels: Vec<Panel<'a>>,
    /// Panels per row.
    pub columns: usize,
    /// Displacement scale s: points are drawn at x + s u(x).
    pub scale: f64,
    /// Γ_C as ordered pieces ([`chains::part_chains`]): where the arrows go.
    pub gamma_c: Vec<Chain>,
    /// |ξ| [N/m] drawn as a full-length arrow (the friction bound at rest μ(0)S reads well);
    /// ≤ 0 picks the largest |ξ| of the figure, rounded up.
    pub force_unit: f64,
}

const PANEL_WIDTH: u32 = 1300;
const PANEL_TITLE: i32 = 19;
const PANEL_MARGIN: i32 = 6;
const PANEL_X_LABEL: i32 = 40;
const PANEL_Y_LABEL: i32 = 52;
const HEADING_HEIGHT: u32 = 62;
const LEGEND_HEIGHT: u32 = 56;
const COLORBAR_WIDTH: u32 = 160;

/// A friction arrow in the plot's coordinates, with the node's tangent (the arrow's line).
struct Arrow {
    start: (f64, f64),
    end: (f64, f64),
    tangent: (f64, f64),
}

/// The arrows' geometry, shared by all panels of a figure so that lengths compare.
struct ArrowLayout {
    /// Mean distance [m] between neighbouring nodes along Γ_C.
    spacing: f64,
    /// An arrow at every `stride`-th node of each piece of Γ_C (counted from its end), so that
    /// neighbours do not overlap: arrows lie along Γ_C.
    stride: usize,
    /// Length [m] of an arrow of size `unit`.
    full_length: f64,
    /// |ξ| [N/m] drawn at `full_length`: the figure's `force_unit`, else the largest |ξ| of
    /// the figure rounded up.
    unit: f64,
    /// Offset [m] of the arrows from Γ_C along ν (outside the body).
    gap: f64,
}

impl DeformedFigure<'_> {
    fn theta_range(&self) -> (f64, f64) {
        let (lo, hi) = self
            .panels
            .iter()
            .flat_map(|p| p.theta.iter())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &t| {
                (lo.min(t), hi.max(t))
            });
        if !(lo.is_finite() && hi.is_finite()) {
            return (0.0, 1.0);
        }
        if hi - lo < 1e-9 {
            (lo - 0.5, hi + 0.5)
        } else {
            (lo, hi)
        }
    }

    fn arrow_layout(&self) -> ArrowLayout {
        let Some(first) = self.panels.first() else {
            return ArrowLayout {
                spacing: 1.0,
                stride: 1,
                full_length: 1.0,
                unit: 1.0,
                gap: 0.5,
            };
        };
        // Node spacing along Γ_C: its length over its edges.
        let length: f64 = self.gamma_c.iter().map(Chain::length).sum();
        let edges: usize = self.gamma_c.iter().map(|c| c.nodes.len().saturating_sub(1)).sum();
        let extent = mesh_extent(first.mesh);
        let spacing = if edges > 0 && length > 0.0 {
            length / edges as f64
        } else {
            extent
        };
        // Arrows of about 5% of the body's size, at least one node apart.
        let wanted = 0.05 * extent;
        let stride = ((wanted / spacing).ceil() as usize).max(1);
        let full_length = 0.9 * stride as f64 * spacing;
        let max_xi = self
            .panels
            .iter()
            .flat_map(|p| p.contact.iter())
            .map(|r| crate::la::vector::norm2(&r.xi))
            .fold(0.0, f64::max);
        ArrowLayout {
            spacing,
            stride,
            full_length,
            unit: if self.force_unit > 0.0 {
                self.force_unit
            } else {
                nice_ceiling(max_xi.max(1e-12))
            },
            gap: 0.5 * full_length.max(0.02 * extent),
        }
    }

    /// The deformed nodes x + s u(x) of a panel.
    fn deformed(&self, panel: &Panel) -> Vec<(f64, f64)> {
        let d = panel.mesh.dim;
        panel
            .mesh
            .coords
            .iter()
            .enumerate()
            .map(|(p, x)| {
                (
                    x[0] + self.scale * panel.u[p * d],
                    x[1] + self.scale * panel.u[p * d + 1],
                )
            })
            .collect()
    }

    /// The friction arrows of a panel: from each chosen deformed contact node pushed out by
    /// `gap` along its ν_i, the vector ξ_i = ξ τ_i scaled to `full_length / unit`.
    fn arrow_segments(&self, panel: &Panel, deformed: &[(f64, f64)], arrows: &ArrowLayout) -> Vec<Arrow> {
        let rows: std::collections::HashMap<usize, &ContactRow> = panel.contact.iter().map(|r| (r.node, r)).collect();
        // From the end of each piece (the free end of the paper's Γ_C), so that it has an arrow;
        // clamped nodes have no row and no arrow but keep their place in the count.
        self.gamma_c
            .iter()
            .flat_map(|c| c.distinct_nodes().iter().rev().step_by(arrows.stride))
            .filter_map(|p| rows.get(p))
            .map(|r| {
                let (x, y) = deformed[r.node];
                let (nu, tau, xi) = (r.normal, r.tangents[0], r.friction_vector());
                let start = (x + arrows.gap * nu[0], y + arrows.gap * nu[1]);
                let scale = arrows.full_length / arrows.unit;
                Arrow {
                    start,
                    end: (start.0 + scale * xi[0], start.1 + scale * xi[1]),
                    tangent: (tau[0], tau[1]),
                }
            })
            .collect()
    }

    /// What a panel must show: reference and deformed body, and room for the longest arrows.
    fn panel_bounds(&self, panel: &Panel, deformed: &[(f64, f64)], arrows: &ArrowLayout) -> Bounds {
        let mut bounds = Bounds::default();
        panel.mesh.coords.iter().for_each(|x| bounds.add(x[0], x[1]));
        deformed.iter().for_each(|&(x, y)| bounds.add(x, y));
        for Arrow {
            start: a, tangent: t, ..
        } in self.arrow_segments(panel, deformed, arrows)
        {
            bounds.add(a.0 + arrows.full_length * t.0, a.1 + arrows.full_length * t.1);
            bounds.add(a.0 - arrows.full_length * t.0, a.1 - arrows.full_length * t.1);
        }
        let pad = 0.025 * (bounds.x1 - bounds.x0).max(bounds.y1 - bounds.y0);
        bounds.padded(pad)
    }

    /// Panel height [px] that fits the first panel's content at equal scales across its width.
    fn panel_height(&self) -> u32 {
        let Some(panel) = self.panels.first() else {
            return 300;
        };
        let arrows = self.arrow_layout();
        let b = self.panel_bounds(panel, &self.deformed(panel), &arrows);
        let plot_width = (PANEL_WIDTH as i32 - PANEL_Y_LABEL - 2 * PANEL_MARGIN) as f64;
        let plot_height = plot_width * (b.y1 - b.y0) / (b.x1 - b.x0).max(1e-12);
        // Title line, margins, x labels.
        (plot_height.ceil() as i32 + PANEL_TITLE + 16 + 2 * PANEL_MARGIN + PANEL_X_LABEL).clamp(150, 2000) as u32
    }

    fn draw_panel<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        panel: &Panel,
        theta_range: (f64, f64),
        arrows: &ArrowLayout,
    ) -> Result<f64, DrawError> {
        let mesh = panel.mesh;
        let deformed = self.deformed(panel);
        let arrow_segments = self.arrow_segments(panel, &deformed, arrows);
        let bounds = self.panel_bounds(panel, &deformed, arrows);

        let area = area.titled(&panel.title, (FONT, PANEL_TITLE))?;
        let (margin, x_label, y_label) = (PANEL_MARGIN, PANEL_X_LABEL, PANEL_Y_LABEL);
        let (width, height) = {
            let probe = ChartBuilder::on(&area)
                .margin(margin)
                .x_label_area_size(x_label)
                .y_label_area_size(y_label)
                .build_cartesian_2d(0.0..1.0, 0.0..1.0)?;
            probe.plotting_area().dim_in_pixel()
        };
        // Equal scales on x and y: the body keeps its shape.
        let (x_range, y_range) = bounds.equal_aspect(width as f64, height as f64);
        let mut chart = ChartBuilder::on(&area)
            .margin(margin)
            .x_label_area_size(x_label)
            .y_label_area_size(y_label)
            .build_cartesian_2d(x_range, y_range)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc("x [m]")
            .y_desc("y [m]")
            .label_style((FONT, 14))
            .axis_desc_style((FONT, 15))
            .draw()?;

        // Cells filled by θ: the P1 field is linear on a cell, so a cell whose θ varies by more
        // than a few percent of the colour range is cut into sub-triangles, each filled by the
        // value at its centroid.
        let span = (theta_range.1 - theta_range.0).max(1e-12);
        let patches: Vec<([(f64, f64); 3], f64)> = (0..mesh.n_cells())
            .flat_map(|e| {
                let c = mesh.cell(e);
                let corners = [c[0], c[1], c[2]].map(|p| (deformed[p], panel.theta[p]));
                let values = corners.map(|(_, t)| t);
                let variation = values.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
                    - values.iter().cloned().fold(f64::INFINITY, f64::min);
                let level = ((variation / (0.03 * span)).ceil() as usize).clamp(1, 6);
                subdivide(corners, level)
            })
            .collect();
        chart.draw_series(
            patches
                .iter()
                .map(|(points, theta)| Polygon::new(points.to_vec(), temperature_color(*theta, theta_range).filled())),
        )?;
        // Cell edges where cells are large enough on screen to show them.
        let pixels_per_metre = width as f64 / (x_range_width(&bounds, width, height));
        let edge_pixels = mean_edge_length(mesh) * pixels_per_metre;
        if edge_pixels >= 5.0 {
            // Fainter on fine meshes, where the lines would otherwise darken the colours.
            let alpha = if edge_pixels < 20.0 { 0.1 } else { 0.22 };
            chart.draw_series(
                unique_edges(mesh)
                    .into_iter()
                    .map(|[a, b]| PathElement::new(vec![deformed[a], deformed[b]], BLACK.mix(alpha))),
            )?;
        }
        // Reference outline (dashed) and deformed outline.
        for cycle in chains::outline(mesh) {
            let cycle = cycle.nodes;
            let reference: Vec<(f64, f64)> = cycle.iter().map(|&p| (mesh.coords[p][0], mesh.coords[p][1])).collect();
            chart.draw_series(DashedLineSeries::new(
                reference,
                7,
                5,
                ShapeStyle::from(&full_palette::GREY_700).stroke_width(1),
            ))?;
            let current: Vec<(f64, f64)> = cycle.iter().map(|&p| deformed[p]).collect();
            chart.draw_series(std::iter::once(PathElement::new(current, BLACK.stroke_width(2))))?;
        }
        // Friction stress arrows.
        let head = 0.3 * arrows.full_length;
        let shapes: Vec<ArrowShape> = arrow_segments
            .iter()
            .filter_map(|a| arrow_shape(a.start, a.end, head))
            .collect();
        chart.draw_series(
            shapes
                .iter()
                .map(|s| PathElement::new(s.shaft.to_vec(), BLACK.stroke_width(2))),
        )?;
        chart.draw_series(shapes.iter().map(|s| Polygon::new(s.head.to_vec(), BLACK.filled())))?;
        // Contact states at the deformed nodes: stick as open circles, slip as red triangles,
        // sized to the node spacing on screen.
        let spacing_pixels = arrows.spacing * pixels_per_metre;
        let radius = (0.3 * spacing_pixels).clamp(1.5, 3.5).round() as i32;
        chart.draw_series(
            panel
                .contact
                .iter()
                .filter(|r| !r.slip)
                .map(|r| Circle::new(deformed[r.node], radius, WHITE.filled())),
        )?;
        chart.draw_series(
            panel
                .contact
                .iter()
                .filter(|r| !r.slip)
                .map(|r| Circle::new(deformed[r.node], radius, BLACK.stroke_width(1))),
        )?;
        chart.draw_series(
            panel
                .contact
                .iter()
                .filter(|r| r.slip)
                .map(|r| TriangleMarker::new(deformed[r.node], radius + 2, RED.filled())),
        )?;
        Ok(pixels_per_metre)
    }

    /// The shared legend; the sample arrow has the panels' full arrow length
    /// (`pixels_per_metre` of the panels).
    fn draw_legend<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        arrows: &ArrowLayout,
        pixels_per_metre: f64,
    ) -> Result<(), DrawError> {
        let style = (FONT, 16).into_font().color(&BLACK);
        let (_, height) = area.dim_in_pixel();
        let y = height as i32 / 2;
        let mut x = 20;
        let gap = 36;
        let label = |area: &DrawingArea<DB, Shift>, x: &mut i32, text: &str| -> Result<(), DrawError> {
            let (w, h) = area.estimate_text_size(text, &style)?;
            area.draw(&Text::new(text.to_string(), (*x, y - h as i32 / 2), style.clone()))?;
            *x += w as i32 + gap;
            Ok(())
        };
        area.draw(&Circle::new((x, y), 4, WHITE.filled()))?;
        area.draw(&Circle::new((x, y), 4, BLACK.stroke_width(1)))?;
        x += 12;
        label(area, &mut x, "stick node")?;
        area.draw(&TriangleMarker::new((x, y), 6, RED.filled()))?;
        x += 12;
        label(area, &mut x, "slip node (|w_τ| > tolerance)")?;
        let length = ((arrows.full_length * pixels_per_metre).round() as i32).clamp(12, 200);
        for (a, b) in arrow_pixels((x, y), length) {
            area.draw(&PathElement::new(vec![a, b], BLACK.stroke_width(2)))?;
        }
        x += length + 8;
        let every = if arrows.stride == 1 {
            "at every node".to_string()
        } else {
            format!("at every {}{} node", arrows.stride, ordinal_suffix(arrows.stride))
        };
        label(
            area,
            &mut x,
            &format!(
                "friction stress ξ on Γ_C {every} (arrow = {} N/m)",
                format_number(arrows.unit)
            ),
        )?;
        // Dashed, as the outline in the panels.
        for dash in 0..3 {
            let x0 = x + dash * 12;
            area.draw(&PathElement::new(
                vec![(x0, y), (x0 + 7, y)],
                ShapeStyle::from(&full_palette::GREY_700).stroke_width(1),
            ))?;
        }
        x += 40;
        label(area, &mut x, "reference configuration")?;
        label(
            area,
            &mut x,
            &format!("displacement scale × {}", format_number(self.scale)),
        )?;
        Ok(())
    }
}

impl Figure for DeformedFigure<'_> {
    fn name(&self) -> &str {
        &self.name
    }

    fn size(&self) -> (u32, u32) {
        let columns = self.columns.max(1) as u32;
        let rows = (self.panels.len() as u32).div_ceil(columns).max(1);
        (
            columns * PANEL_WIDTH + COLORBAR_WIDTH,
            HEADING_HEIGHT + rows * self.panel_height() + LEGEND_HEIGHT,
        )
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), DrawError> {
        root.fill(&WHITE)?;
        let (width, height) = self.size();
        let (head, rest) = root.split_vertically(HEADING_HEIGHT);
        draw_heading(&head, &self.heading, &self.subheading)?;
        let (body, legend) = rest.split_vertically(height - HEADING_HEIGHT - LEGEND_HEIGHT);
        let (panels_area, colorbar) = body.split_horizontally(width - COLORBAR_WIDTH);
        let columns = self.columns.max(1);
        let rows = self.panels.len().div_ceil(columns).max(1);
        let cells = panels_area.split_evenly((rows, columns));
        let theta_range = self.theta_range();
        let arrows = self.arrow_layout();
        let mut pixels_per_metre = 0.0;
        for (panel, area) in self.panels.iter().zip(&cells) {
            pixels_per_metre = self.draw_panel(area, panel, theta_range, &arrows)?;
        }
        draw_colorbar(&colorbar, theta_range)?;
        self.draw_legend(&legend, &arrows, pixels_per_metre)?;
        Ok(())
    }
}

/// The number of slip nodes against time for one or more runs.
pub struct SlipHistoryFigure {
    pub name: String,
    pub heading: String,
    pub subheading: String,
    pub series: Vec<HistorySeries>,
}

/// One run's slip count per time level, with the paper's reported counts to compare.
pub struct HistorySeries {
    /// Legend text, e.g. "α_exp = 3·10⁻⁴ (this solver)".
    pub label: String,
    /// (t_n, number of slip nodes) for n = 1..N.
    pub counts: Vec<(f64, usize)>,
    /// (t, count) the paper reports for this run.
    pub paper: Vec<(f64, usize)>,
}

impl Figure for SlipHistoryFigure {
    fn name(&self) -> &str {
        &self.name
    }

    fn size(&self) -> (u32, u32) {
        (1100, 640 + HEADING_HEIGHT)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), DrawError> {
        root.fill(&WHITE)?;
        let (head, root) = root.split_vertically(HEADING_HEIGHT);
        draw_heading(&head, &self.heading, &self.subheading)?;
        let root = &root;
        let t_max = self
            .series
            .iter()
            .flat_map(|s| s.counts.iter().map(|c| c.0))
            .fold(0.0, f64::max)
            .max(1e-9);
        let n_max = self
            .series
            .iter()
            .flat_map(|s| s.counts.iter().map(|c| c.1).chain(s.paper.iter().map(|c| c.1)))
            .max()
            .unwrap_or(1)
            .max(1);
        let mut chart = ChartBuilder::on(root)
            .margin(16)
            .x_label_area_size(48)
            .y_label_area_size(64)
            .build_cartesian_2d(0.0..t_max * 1.04, 0.0..(n_max as f64 * 1.15).ceil())?;
        chart
            .configure_mesh()
            .x_desc("time t [s]")
            .y_desc("number of slip nodes on Γ_C")
            .y_label_formatter(&|n| format!("{n:.0}"))
            .label_style((FONT, 15))
            .axis_desc_style((FONT, 17))
            .light_line_style(WHITE.mix(0.0))
            .draw()?;
        for (i, s) in self.series.iter().enumerate() {
            let color = series_color(i);
            chart
                .draw_series(LineSeries::new(
                    steps(&s.counts),
                    ShapeStyle::from(&color).stroke_width(2),
                ))?
                .label(s.label.clone())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], color.stroke_width(2)));
            if !s.paper.is_empty() {
                chart
                    .draw_series(
                        s.paper
                            .iter()
                            .map(|&(t, n)| Cross::new((t, n as f64), 7, color.stroke_width(3))),
                    )?
                    .label(format!("{}: paper", s.label.split(" (").next().unwrap_or(&s.label)))
                    .legend(move |(x, y)| Cross::new((x + 12, y), 6, color.stroke_width(3)));
            }
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .label_font((FONT, 15))
            .background_style(WHITE.mix(0.9))
            .border_style(BLACK)
            .draw()?;
        Ok(())
    }
}

/// θ, w_τ and ξ along Γ_C at several times.
pub struct ContactProfileFigure {
    pub name: String,
    pub heading: String,
    pub subheading: String,
    /// (t, contact rows) per output time.
    pub profiles: Vec<(f64, Vec<ContactRow>)>,
    /// Γ_C as ordered pieces: the abscissa is the arc length s along them, one piece after the
    /// other.
    pub gamma_c: Vec<Chain>,
    /// μ(0)S, the friction bound at rest, drawn as ±bound on the ξ panel (≤ 0: no line, for a
    /// bound that scales with the contact pressure and has no one value).
    pub bound_at_rest: f64,
}

impl Figure for ContactProfileFigure {
    fn name(&self) -> &str {
        &self.name
    }

    fn size(&self) -> (u32, u32) {
        (1100, 1120 + HEADING_HEIGHT)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), DrawError> {
        root.fill(&WHITE)?;
        let (head, root) = root.split_vertically(HEADING_HEIGHT);
        draw_heading(&head, &self.heading, &self.subheading)?;
        let panels = root.split_evenly((3, 1));
        // Arc length of every Γ_C node, the pieces laid end to end; a piece's nodes in order.
        let mut offset = 0.0;
        let pieces: Vec<Vec<(usize, f64)>> = self
            .gamma_c
            .iter()
            .map(|c| {
                let piece = c.nodes.iter().zip(&c.arc).map(|(&p, &s)| (p, offset + s)).collect();
                offset += c.length();
                piece
            })
            .collect();
        type Pick = fn(&ContactRow) -> f64;
        let quantities: [(&str, Pick); 3] = [
            ("temperature θ on Γ_C [°C]", |r| r.theta),
            ("tangential velocity w_τ [m/s]", |r| r.w_tau[0]),
            ("friction stress ξ [N/m]", |r| r.xi[0]),
        ];
        let mut s_range = Bounds::default();
        s_range.add(0.0, 0.0);
        s_range.add(offset.max(1e-12), 0.0);
        for (q, ((label, pick), area)) in quantities.iter().zip(&panels).enumerate() {
            let mut y = Bounds::default();
            for (_, rows) in &self.profiles {
                for r in rows {
                    y.add(0.0, pick(r));
                }
            }
            if q == 2 {
                y.add(0.0, self.bound_at_rest);
                y.add(0.0, -self.bound_at_rest);
            }
            let span = (y.y1 - y.y0).max(1e-9);
            let mut chart = ChartBuilder::on(area)
                .margin(14)
                .x_label_area_size(46)
                .y_label_area_size(74)
                .build_cartesian_2d(s_range.x0..s_range.x1, (y.y0 - 0.06 * span)..(y.y1 + 0.3 * span))?;
            chart
                .configure_mesh()
                .x_desc("arc length s along Γ_C [m]")
                .y_desc(*label)
                .label_style((FONT, 14))
                .axis_desc_style((FONT, 16))
                .light_line_style(WHITE.mix(0.0))
                .draw()?;
            for (i, (t, rows)) in self.profiles.iter().enumerate() {
                let color = series_color(i);
                let at: std::collections::HashMap<usize, &ContactRow> = rows.iter().map(|r| (r.node, r)).collect();
                let slips = rows.iter().filter(|r| r.slip).count();
                // One line per piece, through its nodes that have a row (clamped nodes have none).
                for (k, piece) in pieces.iter().enumerate() {
                    let points: Vec<(f64, f64)> = piece
                        .iter()
                        .filter_map(|(p, s)| at.get(p).map(|r| (*s, pick(r))))
                        .collect();
                    let series =
                        chart.draw_series(LineSeries::new(points, ShapeStyle::from(&color).stroke_width(2)))?;
                    if k == 0 {
                        series
                            .label(format!("t = {} s ({slips} slip)", format_number(*t)))
                            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], color.stroke_width(2)));
                    }
                }
            }
            if q == 2 && self.bound_at_rest > 0.0 {
                let (x0, x1) = (s_range.x0, s_range.x1);
                for sign in [1.0, -1.0] {
                    let series = chart.draw_series(DashedLineSeries::new(
                        vec![(x0, sign * self.bound_at_rest), (x1, sign * self.bound_at_rest)],
                        8,
                        6,
                        BLACK.stroke_width(1),
                    ))?;
                    if sign > 0.0 {
                        series
                            .label(format!("±μ(0)S = ±{} N/m", format_number(self.bound_at_rest)))
                            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], BLACK.stroke_width(1)));
                    }
                }
            }
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperLeft)
                .label_font((FONT, 14))
                .background_style(WHITE.mix(0.9))
                .border_style(BLACK)
                .draw()?;
        }
        Ok(())
    }
}

/// Two heading lines at the top left: the title in bold, the setting below it.
fn draw_heading<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    heading: &str,
    subheading: &str,
) -> Result<(), DrawError> {
    area.draw(&Text::new(
        heading.to_string(),
        (16, 8),
        (FONT, 22).into_font().style(FontStyle::Bold).color(&BLACK),
    ))?;
    area.draw(&Text::new(
        subheading.to_string(),
        (16, 36),
        (FONT, 16).into_font().color(&BLACK),
    ))?;
    Ok(())
}

/// The data width of the equal-aspect x range of `bounds` in a `width × height` plot.
fn x_range_width(bounds: &Bounds, width: u32, height: u32) -> f64 {
    let (x, _) = bounds.equal_aspect(width as f64, height as f64);
    x.end - x.start
}

/// The colour of temperature θ on the figure's range (viridis).
fn temperature_color(theta: f64, (lo, hi): (f64, f64)) -> RGBColor {
    ViridisRGB::get_color_normalized(theta.clamp(lo, hi), lo, hi)
}

fn draw_colorbar<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, (lo, hi): (f64, f64)) -> Result<(), DrawError> {
    // The label sits above the bar: a rotated axis title would not fit the strip.
    area.draw(&Text::new("θ [°C]", (24, 14), (FONT, 17).into_font().color(&BLACK)))?;
    let mut chart = ChartBuilder::on(area)
        .margin_top(44)
        .margin_bottom(60)
        .margin_left(24)
        .right_y_label_area_size(70)
        .build_cartesian_2d(0.0..1.0, lo..hi)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .label_style((FONT, 14))
        .draw()?;
    let n = 200;
    chart.draw_series((0..n).map(|i| {
        let a = lo + (hi - lo) * i as f64 / n as f64;
        let b = lo + (hi - lo) * (i + 1) as f64 / n as f64;
        Rectangle::new(
            [(0.0, a), (1.0, b)],
            temperature_color(0.5 * (a + b), (lo, hi)).filled(),
        )
    }))?;
    chart.draw_series(std::iter::once(PathElement::new(
        vec![(0.0, lo), (1.0, lo), (1.0, hi), (0.0, hi), (0.0, lo)],
        BLACK.stroke_width(1),
    )))?;
    Ok(())
}

/// Cuts a triangle with nodal values into level² similar sub-triangles, each with the linear
/// interpolant's value at its centroid.
fn subdivide(corners: [((f64, f64), f64); 3], level: usize) -> Vec<([(f64, f64); 3], f64)> {
    let n = level.max(1);
    let [(a, ta), (b, tb), (c, tc)] = corners;
    // The point with barycentric coordinates (i, j, n − i − j)/n.
    let point = |i: f64, j: f64| {
        let (l1, l2) = (i / n as f64, j / n as f64);
        let l0 = 1.0 - l1 - l2;
        (
            (l0 * a.0 + l1 * b.0 + l2 * c.0, l0 * a.1 + l1 * b.1 + l2 * c.1),
            l0 * ta + l1 * tb + l2 * tc,
        )
    };
    let mut out = Vec::with_capacity(n * n);
    for i in 0..n {
        for j in 0..(n - i) {
            let (i, j) = (i as f64, j as f64);
            // Upward sub-triangle, then (where it exists) the downward one beside it.
            let up = [point(i, j), point(i + 1.0, j), point(i, j + 1.0)];
            out.push((up.map(|p| p.0), point(i + 1.0 / 3.0, j + 1.0 / 3.0).1));
            if (i + j) as usize + 2 <= n {
                let down = [point(i + 1.0, j), point(i + 1.0, j + 1.0), point(i, j + 1.0)];
                out.push((down.map(|p| p.0), point(i + 2.0 / 3.0, j + 2.0 / 3.0).1));
            }
        }
    }
    out
}

/// An arrow in data coordinates: a shaft and a triangular head.
struct ArrowShape {
    shaft: [(f64, f64); 2],
    head: [(f64, f64); 3],
}

/// The arrow from `a` to `b` with a head of length at most `head` (data units, equal aspect);
/// `None` for a vanishing arrow (ξ = 0).
fn arrow_shape(a: (f64, f64), b: (f64, f64), head: f64) -> Option<ArrowShape> {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let length = dx.hypot(dy);
    if length < 1e-12 {
        return None;
    }
    let (ux, uy) = (dx / length, dy / length);
    let h = head.min(0.6 * length);
    let w = 0.45 * h;
    let base = (b.0 - h * ux, b.1 - h * uy);
    Some(ArrowShape {
        shaft: [a, base],
        head: [
            b,
            (base.0 - w * uy, base.1 + w * ux),
            (base.0 + w * uy, base.1 - w * ux),
        ],
    })
}

/// A legend arrow in pixels, pointing right from `(x, y)`: shaft and two barbs.
fn arrow_pixels((x, y): (i32, i32), length: i32) -> [((i32, i32), (i32, i32)); 3] {
    let tip = (x + length, y);
    [((x, y), tip), (tip, (tip.0 - 8, y - 5)), (tip, (tip.0 - 8, y + 5))]
}

/// An axis-aligned box of data points.
#[derive(Debug, Clone, Copy)]
struct Bounds {
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
}

impl Default for Bounds {
    fn default() -> Self {
        Bounds {
            x0: f64::INFINITY,
            x1: f64::NEG_INFINITY,
            y0: f64::INFINITY,
            y1: f64::NEG_INFINITY,
        }
    }
}

impl Bounds {
    fn add(&mut self, x: f64, y: f64) {
        if x.is_finite() && y.is_finite() {
            self.x0 = self.x0.min(x);
            self.x1 = self.x1.max(x);
            self.y0 = self.y0.min(y);
            self.y1 = self.y1.max(y);
        }
    }

    fn padded(self, pad: f64) -> Self {
        Bounds {
            x0: self.x0 - pad,
            x1: self.x1 + pad,
            y0: self.y0 - pad,
            y1: self.y1 + pad,
        }
    }

    /// Ranges containing the box, centred, with equal data-per-pixel on both axes.
    fn equal_aspect(self, width: f64, height: f64) -> (std::ops::Range<f64>, std::ops::Range<f64>) {
        let (dx, dy) = ((self.x1 - self.x0).max(1e-12), (self.y1 - self.y0).max(1e-12));
        let per_pixel = (dx / width.max(1.0)).max(dy / height.max(1.0));
        let (cx, cy) = (0.5 * (self.x0 + self.x1), 0.5 * (self.y0 + self.y1));
        let (hx, hy) = (0.5 * per_pixel * width, 0.5 * per_pixel * height);
        ((cx - hx)..(cx + hx), (cy - hy)..(cy + hy))
    }
}

/// The larger side of the mesh's bounding box.
fn mesh_extent(mesh: &Mesh) -> f64 {
    let mut b = Bounds::default();
    mesh.coords.iter().for_each(|x| b.add(x[0], x[1]));
    (b.x1 - b.x0).max(b.y1 - b.y0)
}

/// Every cell edge once, as a sorted node pair.
fn unique_edges(mesh: &Mesh) -> Vec<[usize; 2]> {
    let npc = mesh.nodes_per_cell();
    let mut edges: Vec<[usize; 2]> = (0..mesh.n_cells())
        .flat_map(|e| {
            let c = mesh.cell(e);
            (0..npc).flat_map(move |a| ((a + 1)..npc).map(move |b| [c[a].min(c[b]), c[a].max(c[b])]))
        })
        .collect();
    edges.sort_unstable();
    edges.dedup();
    edges
}

fn mean_edge_length(mesh: &Mesh) -> f64 {
    let edges = unique_edges(mesh);
    let total: f64 = edges
        .iter()
        .map(|&[a, b]| {
            let (p, q) = (mesh.coords[a], mesh.coords[b]);
            (p[0] - q[0]).hypot(p[1] - q[1])
        })
        .sum();
    total / edges.len().max(1) as f64
}

/// A step curve through (t_n, count_n), starting from (0, 0): counts hold over (t_{n−1}, t_n].
fn steps(counts: &[(f64, usize)]) -> Vec<(f64, f64)> {
    let mut points = vec![(0.0, 0.0)];
    let mut previous = 0.0;
    for &(t, n) in counts {
        points.push((previous, n as f64));
        points.push((t, n as f64));
        previous = t;
    }
    points
}

/// Distinct colours for up to a handful of series.
fn series_color(i: usize) -> RGBColor {
    const COLORS: [RGBColor; 6] = [
        RGBColor(31, 119, 180),
        RGBColor(214, 39, 40),
        RGBColor(44, 160, 44),
        RGBColor(148, 103, 189),
        RGBColor(255, 127, 14),
        RGBColor(23, 190, 207),
    ];
    COLORS[i % COLORS.len()]
}

/// The smallest of 1, 2, 2.5, 5 × 10^k at or above `v`.
fn nice_ceiling(v: f64) -> f64 {
    let power = 10f64.powf(v.log10().floor());
    [1.0, 2.0, 2.5, 5.0, 10.0]
        .iter()
        .map(|m| m * power)
        .find(|&c| c >= v * (1.0 - 1e-12))
        .unwrap_or(10.0 * power)
}

fn ordinal_suffix(n: usize) -> &'static str {
    match (n % 10, n % 100) {
        (_, 11..=13) => "th",
        (1, _) => "st",
        (2, _) => "nd",
        (3, _) => "rd",
        _ => "th",
    }
}

/// A number as short as it reads well: 0.25, 150, 1e-4 → "1·10⁻⁴".
pub fn format_number(v: f64) -> String {
    if v != 0.0 && (v.abs() < 1e-2 || v.abs() >= 1e5) {
        let exponent = v.abs().log10().floor() as i32;
        let mantissa = v / 10f64.powi(exponent);
        let mantissa = format!("{mantissa:.2}");
        let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
        return format!("{mantissa}·10{}", superscript(exponent));
    }
    let text = format!("{v:.4}");
    text.trim_end_matches('0').trim_end_matches('.').to_string()
}

fn superscript(n: i32) -> String {
    const DIGITS: [char; 10] = ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'];
    let mut s = String::new();
    if n < 0 {
        s.push('⁻');
    }
    for c in n.unsigned_abs().to_string().chars() {
        s.push(DIGITS[c.to_digit(10).unwrap_or(0) as usize]);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_read_well() {
        assert_eq!(format_number(0.25), "0.25");
        assert_eq!(format_number(1.0), "1");
        assert_eq!(format_number(150.0), "150");
        assert_eq!(format_number(1e-4), "1·10⁻⁴");
        assert_eq!(format_number(3e-4), "3·10⁻⁴");
        assert_eq!(nice_ceiling(38.5), 50.0);
        assert_eq!(nice_ceiling(150.0), 200.0);
        assert_eq!(nice_ceiling(20.0), 20.0);
        assert_eq!(ordinal_suffix(2), "nd");
        assert_eq!(ordinal_suffix(12), "th");
    }

    #[test]
    fn subdivision_tiles_the_triangle_and_interpolates_linearly() {
        let corners = [((0.0, 0.0), 0.0), ((3.0, 0.0), 3.0), ((0.0, 3.0), 6.0)];
        for level in 1..5 {
            let parts = subdivide(corners, level);
            assert_eq!(parts.len(), level * level);
            let area: f64 = parts
                .iter()
                .map(|(p, _)| 0.5 * ((p[1].0 - p[0].0) * (p[2].1 - p[0].1) - (p[2].0 - p[0].0) * (p[1].1 - p[0].1)))
                .sum();
            assert!((area - 4.5).abs() < 1e-12, "level {level}: area {area}");
            for (p, value) in &parts {
                // θ = x + 2y on this triangle: the value at the centroid.
                let (cx, cy) = ((p[0].0 + p[1].0 + p[2].0) / 3.0, (p[0].1 + p[1].1 + p[2].1) / 3.0);
                assert!((value - (cx + 2.0 * cy)).abs() < 1e-12);
            }
        }
    }

    /// Rows of a fabricated state on the inner circle of an annulus: ν_i = −x/|x| (out of Ω, into
    /// the hole), τ_i = ν_i turned by +90°, ξ = `xi` everywhere.
    fn ring_rows(mesh: &Mesh, xi: f64) -> Vec<ContactRow> {
        let inner = mesh.part_index("inner").unwrap();
        let on = mesh.nodes_on(&[inner]);
        (0..mesh.n_nodes())
            .filter(|&p| on[p])
            .map(|p| {
                let x = mesh.coords[p];
                let r = x[0].hypot(x[1]);
                let normal = [-x[0] / r, -x[1] / r, 0.0];
                ContactRow {
                    node: p,
                    x,
                    normal,
                    tangents: vec![[-normal[1], normal[0], 0.0]],
                    w_tau: vec![0.0],
                    xi: vec![xi],
                    bound: 1.0,
                    slip: false,
                    theta: 0.0,
                    slip_distance: None,
                    pressure: None,
                }
            })
            .collect()
    }

    #[test]
    fn arrows_on_a_curved_contact_lie_along_each_nodes_tangent_outside_the_body() {
        let (a, b) = (1.0, 2.0);
        let mesh = crate::mesh::annulus(a, b, 4, 96);
        let rows = ring_rows(&mesh, 0.5);
        let u = vec![0.0; 2 * mesh.n_nodes()];
        let theta = vec![0.0; mesh.n_nodes()];
        let figure = DeformedFigure {
            name: "ring".into(),
            heading: String::new(),
            subheading: String::new(),
            panels: vec![Panel {
                title: String::new(),
                mesh: &mesh,
                u: &u,
                theta: &theta,
                contact: &rows,
            }],
            columns: 1,
            scale: 1.0,
            gamma_c: chains::part_chains(&mesh, &[mesh.part_index("inner").unwrap()]),
            force_unit: 1.0,
        };
        let layout = figure.arrow_layout();
        // Arrows of about 5% of the body (4 m across) at an even stride of the 96 nodes.
        let spacing = 2.0 * a * (std::f64::consts::PI / 96.0).sin();
        assert!((layout.spacing - spacing).abs() < 1e-12);
        assert_eq!(layout.stride, (0.05 * 2.0 * b / spacing).ceil() as usize);
        let deformed = figure.deformed(&figure.panels[0]);
        let arrows = figure.arrow_segments(&figure.panels[0], &deformed, &layout);
        assert_eq!(arrows.len(), 96usize.div_ceil(layout.stride));
        for arrow in &arrows {
            let (s, e) = (arrow.start, arrow.end);
            let r = s.0.hypot(s.1);
            // Offset by the gap into the hole, the side of ν_i.
            assert!((r - (a - layout.gap)).abs() < 1e-9, "start at radius {r}");
            // Along the tangent of the node, at half the full length for ξ = 0.5 · unit.
            let (dx, dy) = (e.0 - s.0, e.1 - s.1);
            assert!((dx * s.0 + dy * s.1).abs() < 1e-9 * r);
            assert!((dx.hypot(dy) - 0.5 * layout.full_length).abs() < 1e-9);
        }
        render(&figure).unwrap();
    }

    #[test]
    fn equal_aspect_keeps_the_box_and_the_scale() {
        let mut b = Bounds::default();
        b.add(0.0, 0.0);
        b.add(40.0, 10.0);
        let (x, y) = b.equal_aspect(800.0, 400.0);
        assert!(x.start <= 0.0 && x.end >= 40.0 && y.start <= 0.0 && y.end >= 10.0);
        let (sx, sy) = ((x.end - x.start) / 800.0, (y.end - y.start) / 400.0);
        assert!((sx - sy).abs() < 1e-12 * sx);
    }
}
