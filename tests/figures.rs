//! The Section 6 figures and the reproduction study as a user meets them: the files are valid
//! PNG and SVG images of the stated size with real content, the slip counts in the panel titles
//! are the counts `thermocontact run` reports, and the study writes its tables into a report.

use std::path::{Path, PathBuf};
use std::process::Command;

use thermocontact::mesh::chains;
use thermocontact::output::figures::{render, DeformedFigure, Figure, Panel};
use thermocontact::studies::reproduction::{panel_title, record_run};
use thermocontact::Scenario;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_thermocontact"))
}

fn scratch(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("thermocontact-fig-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// A coarse version of the paper's example: 16 × 4 cells, 16 steps.
const COARSE: [&str; 6] = ["--set", "mesh.nx=16", "--set", "mesh.ny=4", "--set", "time.steps=16"];

/// Decodes a PNG and checks that it is an image with content: the stated size, many colours.
fn decode_png(path: &Path) -> image::RgbImage {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "{} is a PNG", path.display());
    let img = image::load_from_memory(&bytes).unwrap().to_rgb8();
    let mut colours: Vec<[u8; 3]> = img.pixels().map(|p| p.0).collect();
    colours.sort_unstable();
    colours.dedup();
    assert!(
        colours.len() > 10,
        "{} has only {} colours",
        path.display(),
        colours.len()
    );
    img
}

/// The `width` and `height` attributes of an SVG document's root element.
fn svg_size(svg: &str) -> (u32, u32) {
    assert!(svg.trim_start().starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
    let attribute = |name: &str| -> u32 {
        let start = svg.find(&format!("{name}=\"")).unwrap() + name.len() + 2;
        let end = start + svg[start..].find('"').unwrap();
        svg[start..end].parse().unwrap()
    };
    (attribute("width"), attribute("height"))
}

/// The panel titles "… t = T s: S slip, K stick …" of an SVG, as (t, slip, stick).
fn title_counts(svg: &str) -> Vec<(f64, u64, u64)> {
    let mut out = Vec::new();
    for piece in svg.split("<text").skip(1) {
        let Some(open) = piece.find('>') else { continue };
        let text = &piece[open + 1..piece.find("</text>").unwrap_or(piece.len())];
        let Some(at) = text.find("t = ") else { continue };
        let rest = &text[at + 4..];
        let Some((t, rest)) = rest.split_once(" s: ") else {
            continue;
        };
        let Some((slip, rest)) = rest.split_once(" slip, ") else {
            continue;
        };
        let Some((stick, _)) = rest.split_once(" stick") else {
            continue;
        };
        out.push((t.parse().unwrap(), slip.parse().unwrap(), stick.parse().unwrap()));
    }
    out
}

#[test]
fn figures_are_valid_images_whose_titles_carry_the_counts_of_run() {
    let out = scratch("figures");
    let result = bin()
        .arg("figures")
        .args(COARSE)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(result.status.success(), "{}", String::from_utf8_lossy(&result.stderr));

    for name in ["fig2_deformed", "fig3_expansion", "slip_history", "contact_profiles"] {
        let png = decode_png(&out.join(format!("{name}.png")));
        let svg = std::fs::read_to_string(out.join(format!("{name}.svg"))).unwrap();
        assert_eq!(svg_size(&svg), png.dimensions(), "{name}: PNG and SVG sizes agree");
    }
    // The history plot has a fixed size; Fig. 2 is one column of panels and a colour bar.
    assert_eq!(decode_png(&out.join("slip_history.png")).dimensions(), (1100, 702));
    let fig2 = decode_png(&out.join("fig2_deformed.png"));
    assert_eq!(fig2.width(), 1460);
    // Slip nodes are drawn in pure red.
    assert!(fig2.pixels().any(|p| p.0 == [255, 0, 0]), "slip markers are drawn");

    // The counts in the Fig. 2 titles are those of `thermocontact run` on the same scenario.
    let run_dir = scratch("figures-run");
    let result = bin()
        .args(["run", "--quiet"])
        .args(COARSE)
        .arg("--out")
        .arg(&run_dir)
        .output()
        .unwrap();
    assert!(result.status.success(), "{}", String::from_utf8_lossy(&result.stderr));
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(run_dir.join("summary.json")).unwrap()).unwrap();
    let outputs = summary["outputs"].as_array().unwrap();
    let svg = std::fs::read_to_string(out.join("fig2_deformed.svg")).unwrap();
    let titles = title_counts(&svg);
    assert_eq!(titles.len(), outputs.len(), "one titled panel per output time");
    assert!(titles.iter().any(|t| t.1 > 0), "the coarse example slips: {titles:?}");
    for ((t, slip, stick), o) in titles.iter().zip(outputs) {
        assert!((t - o["t"].as_f64().unwrap()).abs() < 1e-12);
        assert_eq!(*slip, o["slip_nodes"].as_u64().unwrap(), "slip count at t = {t}");
        assert_eq!(*stick, o["stick_nodes"].as_u64().unwrap(), "stick count at t = {t}");
    }
    // And the summary.json written beside the figures says the same.
    let own: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(own["outputs"].as_array().unwrap().len(), outputs.len());
    for (a, b) in own["outputs"].as_array().unwrap().iter().zip(outputs) {
        assert_eq!(a["slip_nodes"], b["slip_nodes"]);
    }
    // Fig. 3 shows α_exp = 1·10⁻⁴ and 1·10⁻³ at t = T with their own counts.
    let fig3: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("fig3_summaries.json")).unwrap()).unwrap();
    let svg3 = std::fs::read_to_string(out.join("fig3_expansion.svg")).unwrap();
    let titles3 = title_counts(&svg3);
    assert_eq!(titles3.len(), 2);
    for ((_, slip, _), run) in titles3.iter().zip(fig3.as_array().unwrap()) {
        let last = run["summary"]["outputs"].as_array().unwrap().last().unwrap().clone();
        assert_eq!(*slip, last["slip_nodes"].as_u64().unwrap());
    }
    std::fs::remove_dir_all(&out).ok();
    std::fs::remove_dir_all(&run_dir).ok();
}

#[test]
fn a_rendered_panel_has_the_figure_size_and_shows_the_temperature() {
    let scenario = Scenario::load(None, &["mesh.nx=8".into(), "mesh.ny=2".into(), "time.steps=8".into()]).unwrap();
    let run = record_run(&scenario, true).unwrap();
    let last = run.snapshots.last().unwrap();
    let figure = DeformedFigure {
        name: "panel".into(),
        heading: "test".into(),
        subheading: "8 × 2".into(),
        panels: vec![Panel {
            title: panel_title("", &last.record, None),
            mesh: &run.problem.mesh,
            u: &last.state.u,
            theta: &last.state.theta,
            contact: &last.record.contact,
        }],
        columns: 1,
        scale: 1.0,
        gamma_c: chains::part_chains(&run.problem.mesh, &run.problem.parts.contact),
        force_unit: 150.0,
    };
    let rendered = render(&figure).unwrap();
    let img = image::load_from_memory(&rendered.png).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), figure.size());
    assert_eq!(svg_size(&rendered.svg), figure.size());
    // θ ranges over the data (cooled Γ_C, θ₀ = 25 °C inside): both ends of the viridis map appear
    // in the colour bar, dark purple (68, 1, 84) and yellow (254, 232, 37).
    let near = |p: &image::Rgb<u8>, c: [i32; 3]| (0..3).all(|i| (p.0[i] as i32 - c[i]).abs() <= 12);
    assert!(img.pixels().any(|p| near(p, [68, 1, 84])));
    assert!(img.pixels().any(|p| near(p, [254, 232, 37])));
    assert!(
        rendered.svg.contains(&format!("{} slip", last.record.slip_nodes)),
        "the title carries the count"
    );
}

#[test]
fn reproduce_writes_tables_into_the_report_between_its_markers() {
    let out = scratch("reproduce");
    std::fs::create_dir_all(&out).unwrap();
    let report = out.join("report.md");
    std::fs::write(
        &report,
        format!(
            "# Report\n\n{}\nstale\n{}\n\nThe end.\n",
            thermocontact::studies::reproduction::study::BEGIN_MARKER,
            thermocontact::studies::reproduction::study::END_MARKER
        ),
    )
    .unwrap();
    let result = bin()
        .arg("reproduce")
        .args(COARSE)
        .args(["--meshes", "8,16", "--steps", "16", "--no-fine", "--out"])
        .arg(&out)
        .arg("--report")
        .arg(&report)
        .output()
        .unwrap();
    assert!(result.status.success(), "{}", String::from_utf8_lossy(&result.stderr));
    let tables = std::fs::read_to_string(out.join("tables.md")).unwrap();
    let text = std::fs::read_to_string(&report).unwrap();
    assert!(text.contains(tables.trim_end()), "the report holds the new tables");
    assert!(!text.contains("stale") && text.ends_with("\n\nThe end.\n"));
    // Both θ_D readings, the paper's counts, the default mesh row.
    assert!(
        tables.contains("θ_D = 0 °C") && tables.contains("θ_D = 25 °C"),
        "{tables}"
    );
    assert!(
        tables.contains("| **paper** (mesh not given) | | | | 4 · – · – · 30 |"),
        "{tables}"
    );
    assert!(tables.contains("16 × 4 (default)"), "{tables}");
    let study: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("study.json")).unwrap()).unwrap();
    // 2 readings × (2 meshes × 1 step + 2 meshes × 2 other α_exp) runs, plus 2 diagnostics.
    assert_eq!(study["cases"].as_array().unwrap().len(), 12);
    assert_eq!(study["diagnostics"].as_array().unwrap().len(), 3);
    for figure in ["fig2_deformed", "fig3_expansion", "slip_history", "contact_profiles"] {
        assert!(out.join(format!("{figure}.png")).is_file() && out.join(format!("{figure}.svg")).is_file());
    }
    std::fs::remove_dir_all(&out).ok();
}

#[test]
fn bad_figure_options_exit_non_zero_naming_the_option() {
    let out = scratch("bad");
    let result = bin()
        .arg("figures")
        .args(COARSE)
        .args(["--scale=-1", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(!result.status.success());
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(stderr.contains("--scale") && stderr.contains("-1"), "{stderr}");
    assert!(!out.exists(), "nothing is written for invalid options");
}

/// docs/reproduction.md holds generated tables made with the current default scenario: its
/// mesh is the one marked "(default)", and its θ_D and time step head the tables.
#[test]
fn the_report_tables_were_made_with_the_default_scenario() {
    use thermocontact::studies::reproduction::study::{BEGIN_MARKER, END_MARKER};
    let report = include_str!("../docs/reproduction.md");
    let begin = report.find(BEGIN_MARKER).expect("the report has the begin marker") + BEGIN_MARKER.len();
    let end = begin + report[begin..].find(END_MARKER).expect("and the end marker");
    let tables = &report[begin..end];
    let default = Scenario::default();
    let grid = default.structured().unwrap();
    let label = format!("| {} × {} (default) |", grid.nx(), grid.ny());
    assert!(tables.contains(&label), "the generated tables mark {label}");
    assert!(
        tables.contains(&format!("#### Slip nodes, θ_D = {} °C", default.boundary.temperature)),
        "the tables cover the default θ_D"
    );
    assert!(
        tables.contains(&format!("(k = 1/{})", default.time.steps)),
        "the tables use the default time step"
    );
    assert!(report.contains("thermocontact reproduce") || report.contains("-- reproduce"));
}

/// The report's tables are reproducible: its coarse entries (16 × 4 cells, k = 1/16, both θ_D,
/// α_exp = 3·10⁻⁴) are what a fresh run of this code gives. A change of the solver or the
/// default scenario that moves them makes this fail until the report is regenerated.
#[test]
fn the_reports_coarse_entries_match_a_fresh_run() {
    let report = include_str!("../docs/reproduction.md");
    for theta_d in [0.0, 25.0] {
        let heading = format!("#### Slip nodes, θ_D = {theta_d} °C, α_exp = 3·10⁻⁴");
        let table = &report[report.find(&heading).expect("a table per θ_D")..];
        let header = table.lines().find(|l| l.starts_with("| mesh")).unwrap();
        let column = header
            .split('|')
            .position(|c| c.trim() == "k = 1/16")
            .expect("a k = 1/16 column");
        let row = table.lines().find(|l| l.starts_with("| 16 × 4")).expect("a 16 × 4 row");
        let reported: Vec<usize> = row
            .split('|')
            .nth(column)
            .unwrap()
            .split('·')
            .map(|n| n.trim().parse().unwrap())
            .collect();

        let scenario = Scenario::load(
            None,
            &[
                "mesh.nx=16".into(),
                "mesh.ny=4".into(),
                "time.steps=16".into(),
                "material.thermal_expansion=3e-4".into(),
                format!("boundary.temperature={theta_d}"),
            ],
        )
        .unwrap();
        let run = record_run(&scenario, false).unwrap();
        let computed: Vec<usize> = run.summary.outputs.iter().map(|o| o.slip_nodes).collect();
        assert_eq!(reported, computed, "θ_D = {theta_d}: report against a fresh run");
    }
}

#[test]
fn figures_of_a_curved_gmsh_contact_follow_the_arc() {
    let out = scratch("curved");
    let scenario = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/brake_shoe.toml");
    let result = bin()
        .arg("figures")
        .arg(&scenario)
        .args(["--expansions", "1e-3", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(result.status.success(), "{}", String::from_utf8_lossy(&result.stderr));
    let fig2 = decode_png(&out.join("fig2_deformed.png"));
    assert!(
        fig2.pixels().any(|p| p.0 == [255, 0, 0]),
        "the shoe slips: slip markers are drawn"
    );
    // The legend names a finite arrow stride (a wrong spacing along a curve once gave 4·10⁹).
    let svg = std::fs::read_to_string(out.join("fig2_deformed.svg")).unwrap();
    let needle = "friction stress ξ on Γ_C at every ";
    let at = svg.find(needle).expect("arrow legend") + needle.len();
    let stride: String = svg[at..].chars().take_while(char::is_ascii_digit).collect();
    assert!((1..=10).contains(&stride.parse::<u32>().unwrap()), "stride {stride}");
    // Panel counts are the run's, and the profiles are drawn against arc length.
    let summary: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    let titles = title_counts(&svg);
    for ((_, slip, _), o) in titles.iter().zip(summary["outputs"].as_array().unwrap()) {
        assert_eq!(*slip, o["slip_nodes"].as_u64().unwrap());
    }
    let profiles = std::fs::read_to_string(out.join("contact_profiles.svg")).unwrap();
    assert!(profiles.contains("arc length s along Γ_C"));
    std::fs::remove_dir_all(&out).ok();
}
