//! A comparison's report files: the contact sheet, the convergence plot, report.md,
//! report.json and the self-contained report.html.

use super::plan::CompareOptions;
use crate::commands::file_name;
use crate::compare::html::{self, Page, PageImage};
use crate::compare::images::{SheetColumn, contact_sheet};
use crate::compare::plot::{Curve, convergence_svg};
use crate::compare::report::CompareReport;
use crate::error::{Error, Result};
use crate::math::{Rgb, UVec2};

/// The comparison as an HTML page: every image with its caption, the metrics, the plot, the
/// settings and where the numbers come from.
pub(crate) fn html_page(
    opts: &CompareOptions,
    report: &CompareReport,
    columns: &[SheetColumn],
    images: &[Vec<Rgb>],
    svg: &str,
) -> String {
    let size = UVec2::new(report.resolution[0], report.resolution[1]);
    let images = columns
        .iter()
        .zip(images)
        .map(|(c, pixels)| PageImage { name: c.title.clone(), caption: c.caption.replace('\n', ", "), pixels })
        .collect();
    let seeds: Vec<String> =
        report.samplers.first().map_or(Vec::new(), |s| s.runs.iter().map(|r| r.seed.to_string()).collect());
    let facts = [
        ("scene", report.scene.clone()),
        ("mode", report.mode.clone()),
        ("size", format!("{} × {} px", size.x, size.y)),
        ("max depth", report.max_depth.to_string()),
        ("clamp", report.clamp.clone()),
        ("guiding", report.guiding.clone()),
        ("caustics", report.caustics.clone()),
        ("threads", report.threads.to_string()),
        ("seeds", seeds.join(", ")),
        ("reference", format!("{} ({})", report.reference.path, report.reference.origin)),
    ];
    html::page(&Page {
        title: format!("myriad compare: {} ({})", file_name(&opts.scene), report.mode),
        size,
        images,
        table: report.metrics(),
        plot_svg: Some(svg.to_string()),
        facts: facts.into_iter().map(|(k, v)| (k.to_string(), v)).collect(),
        exposure: opts.exposure,
    })
}

/// Writes the contact sheet, the convergence plot, report.md, report.json and report.html
/// (`images`: the reference's, then each column's pixels).
pub(crate) fn write_report(
    opts: &CompareOptions,
    mut report: CompareReport,
    columns: &[SheetColumn],
    images: &[Vec<Rgb>],
) -> Result<CompareReport> {
    let out = |name: &str| opts.out_dir.join(name);
    let (sheet_path, plot_path, md_path, json_path, html_path) =
        (out("contact-sheet.png"), out("convergence.svg"), out("report.md"), out("report.json"), out("report.html"));
    let sheet = contact_sheet(columns);
    crate::io::png::write_srgb8(&sheet_path, sheet.size, sheet.bytes)?;
    let curves: Vec<Curve> = report
        .samplers
        .iter()
        .map(|s| Curve { name: s.sampler.clone(), points: s.runs[0].convergence.clone() })
        .collect();
    let svg = convergence_svg(&format!("{} ({})", file_name(&opts.scene), report.mode), &curves)
        .map_err(|m| Error::Output { path: plot_path.clone(), message: m })?;
    crate::io::write_text(&plot_path, &svg)?;
    report.files = [&sheet_path, &plot_path, &md_path, &json_path, &html_path].iter().map(|p| file_name(p)).collect();
    crate::io::write_text(&html_path, &html_page(opts, &report, columns, images, &svg))?;
    crate::io::write_text(&md_path, &report.markdown(&file_name(&sheet_path), &file_name(&plot_path)))?;
    let json = serde_json::to_string_pretty(&report)
        .map_err(|e| Error::Output { path: json_path.clone(), message: e.to_string() })?;
    crate::io::write_text(&json_path, &json)?;
    Ok(report)
}
