//! The comparison as one self-contained HTML page (`report.html`, `diff --html`): every image
//! as linear half floats, so the page can change the exposure and compute error maps itself;
//! the viewer (`assets/report/viewer.js`, plain JavaScript, no build step, no network) flips
//! between images at the same zoom and position, zooms with nearest-neighbour pixels, shows
//! render / relative error / |difference| and the value under the cursor in every image.
//!
//! Image data: RGB as IEEE half floats, split into byte planes (every high byte, then every
//! low byte, per channel) so that deflate finds the slowly varying exponents, zlib-compressed
//! (miniz_oxide), base64-encoded in 1 MiB `<script>` pieces; the page decodes and inflates it
//! with the browser's own `fetch` of a data URL and `DecompressionStream`, and reads the
//! planes in place. About 3.3–3.7 bytes a pixel before base64 on renders of 1–16 spp.
//! The error map's ramp, decades and ε come from [`super::images`] and [`super::metrics`],
//! so the page draws what `compare`'s PNG error maps show.

use base64::Engine;
use serde::Serialize;

use super::images::{ERROR_DECADES, RAMP};
use super::metrics::REL_MSE_EPSILON;
use super::report::Table;
use crate::math::{Rgb, UVec2};

const VIEWER_JS: &str = include_str!("../../assets/report/viewer.js");
const VIEWER_CSS: &str = include_str!("../../assets/report/viewer.css");

/// One image of the page.
pub struct PageImage<'a> {
    /// Its name on the buttons and in the readout ("reference", "tree").
    pub name: String,
    /// A line under the name (spp, time).
    pub caption: String,
    /// Linear RGB, row-major, top row first.
    pub pixels: &'a [Rgb],
}

/// Everything on the page.
pub struct Page<'a> {
    /// Title (scene and mode).
    pub title: String,
    /// Size of every image.
    pub size: UVec2,
    /// The images; the first is the one the others are measured against.
    pub images: Vec<PageImage<'a>>,
    /// The metrics.
    pub table: Table,
    /// The convergence plot, as SVG, if there is one.
    pub plot_svg: Option<String>,
    /// Settings, scene, seeds: (name, value); the page adds the myriad version and revision.
    pub facts: Vec<(String, String)>,
    /// Starting exposure in stops.
    pub exposure: f32,
}

#[derive(Serialize)]
struct Data<'a> {
    title: &'a str,
    width: u32,
    height: u32,
    exposure: f32,
    ramp: [[f32; 3]; 6],
    decades: [f32; 2],
    epsilon: f64,
    images: Vec<ImageData>,
    table: &'a Table,
    facts: &'a [(String, String)],
}

#[derive(Serialize)]
struct ImageData {
    name: String,
    caption: String,
}

/// Base64 characters per `<script>` element that carries image data: browsers parse one huge
/// element in time that grows faster than its length (45 MB in one: 1.1 s; in 1 MB pieces:
/// 0.37 s, Chromium 1xx).
const CHUNK: usize = 1 << 20;

/// The image as half floats in byte planes, zlib-compressed.
pub fn encode_pixels(pixels: &[Rgb]) -> Vec<u8> {
    let n = pixels.len();
    let mut planes = vec![0u8; 6 * n];
    for (i, p) in pixels.iter().enumerate() {
        for c in 0..3 {
            let [lo, hi] = half::f16::from_f32(p[c]).to_le_bytes();
            planes[c * n + i] = hi;
            planes[(3 + c) * n + i] = lo;
        }
    }
    miniz_oxide::deflate::compress_to_vec_zlib(&planes, 6)
}

/// The page's HTML.
pub fn page(page: &Page) -> String {
    let b64 = base64::engine::general_purpose::STANDARD;
    let images =
        page.images.iter().map(|im| ImageData { name: im.name.clone(), caption: im.caption.clone() }).collect();
    let mut pixels = String::new();
    for (k, im) in page.images.iter().enumerate() {
        let text = b64.encode(encode_pixels(im.pixels));
        // Base64 is ASCII: any byte offset is a character boundary.
        for piece in text.as_bytes().chunks(CHUNK) {
            let piece = std::str::from_utf8(piece).expect("base64 is ASCII");
            pixels += &format!("<script type=\"application/octet-stream\" data-image=\"{k}\">{piece}</script>\n");
        }
    }
    let mut facts = page.facts.clone();
    facts.push(("myriad".into(), format!("{} ({})", env!("CARGO_PKG_VERSION"), env!("MYRIAD_GIT_REVISION"))));
    let data = Data {
        title: &page.title,
        width: page.size.x,
        height: page.size.y,
        exposure: page.exposure,
        ramp: RAMP,
        decades: [ERROR_DECADES.0, ERROR_DECADES.1],
        epsilon: REL_MSE_EPSILON,
        images,
        table: &page.table,
        facts: &facts,
    };
    // JSON inside <script> may not contain "</": escape every '<'.
    let json = serde_json::to_string(&data).expect("plain data serialises").replace('<', "\\u003c");
    let plot = page.plot_svg.as_deref().map_or(String::new(), |svg| format!("<section id=\"plot\">{svg}</section>"));
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{title}</title>\
         <style>{VIEWER_CSS}</style></head>\n<body>\n<h1>{title}</h1>\n\
         <div id=\"bar\"></div>\n<div id=\"view\"><canvas id=\"canvas\"></canvas></div>\n\
         <div id=\"readout\"></div>\n<p id=\"help\"></p>\n<section id=\"metrics\"></section>\n{plot}\n\
         <section id=\"facts\"></section>\n\
         <script type=\"application/json\" id=\"myriad-data\">{json}</script>\n{pixels}\
         <script>{VIEWER_JS}</script>\n</body></html>\n",
        title = escape(&page.title),
    )
}

/// Text for HTML.
fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pixels_go_in_as_half_float_planes_and_the_page_holds_no_raw_markup() {
        let pixels = [Rgb::new(1.0, 0.5, 65504.0), Rgb::new(0.0, 1e-3, 2.0)];
        let planes = miniz_oxide::inflate::decompress_to_vec_zlib(&encode_pixels(&pixels)).unwrap();
        assert_eq!(planes.len(), 12);
        let value =
            |c: usize, i: usize| half::f16::from_le_bytes([planes[(3 + c) * 2 + i], planes[c * 2 + i]]).to_f32();
        assert_eq!((value(0, 0), value(1, 0), value(2, 0)), (1.0, 0.5, 65504.0));
        assert!((value(1, 1) - 1e-3).abs() < 1e-6);
        let html = page(&Page {
            title: "a <b> & \"c\"".into(),
            size: UVec2::new(2, 1),
            images: vec![PageImage { name: "x</script>".into(), caption: String::new(), pixels: &pixels }],
            table: Table::default(),
            plot_svg: None,
            facts: vec![],
            exposure: 0.0,
        });
        assert!(html.contains("<title>a &lt;b&gt; &amp; &quot;c&quot;</title>"));
        assert!(!html.contains("x</script>"), "a name cannot end the data's script");
        // The data, one image piece, the viewer.
        assert_eq!(html.matches("</script>").count(), 3);
        assert!(!html.contains("http://") && !html.contains("https://"), "nothing from the network");
    }
}
