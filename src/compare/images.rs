//! Pictures for people: false-colour error maps and the labelled contact sheet. Builds
//! 8-bit RGB buffers; `io::png` writes them.
//!
//! Labels are drawn with ab_glyph from DejaVu Sans Mono, shipped in `assets/fonts/` (Bitstream
//! Vera licence), so the output never depends on the fonts a machine happens to have.

use ab_glyph::{Font, FontRef, PxScale, ScaleFont, point};

use crate::io::png::to_srgb8;
use crate::math::{Rgb, UVec2};

const FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSansMono.ttf");

/// Decades of relative error the colour map spans: 10⁻³ (dark) to 10⁰ (bright).
pub const ERROR_DECADES: (f32, f32) = (-3.0, 0.0);

/// An 8-bit sRGB image.
#[derive(Clone, Debug, PartialEq)]
pub struct Picture {
    /// Width and height.
    pub size: UVec2,
    /// RGB bytes, row-major.
    pub bytes: Vec<u8>,
}

/// The "inferno"-like ramp: black → purple → orange → pale yellow, perceptually ordered.
pub const RAMP: [[f32; 3]; 6] = [
    [0.001, 0.000, 0.014],
    [0.258, 0.039, 0.406],
    [0.578, 0.148, 0.404],
    [0.865, 0.317, 0.226],
    [0.988, 0.645, 0.040],
    [0.988, 0.998, 0.645],
];

/// Colour of `t ∈ [0,1]` on the ramp (sRGB-encoded components in [0,1]).
pub fn ramp(t: f32) -> [f32; 3] {
    let x = t.clamp(0.0, 1.0) * (RAMP.len() - 1) as f32;
    let i = (x as usize).min(RAMP.len() - 2);
    let f = x - i as f32;
    [0, 1, 2].map(|c| RAMP[i][c] * (1.0 - f) + RAMP[i + 1][c] * f)
}

/// False-colour map of per-pixel relative errors, log scale over [`ERROR_DECADES`].
pub fn error_picture(size: UVec2, errors: &[f32]) -> Picture {
    let (lo, hi) = ERROR_DECADES;
    let bytes = errors
        .iter()
        .flat_map(|&e| {
            let t = if e > 0.0 { (e.log10() - lo) / (hi - lo) } else { 0.0 };
            ramp(t).map(|v| (v * 255.0 + 0.5) as u8)
        })
        .collect();
    Picture { size, bytes }
}

/// A tonemapped preview of linear pixels (exposure in stops, sRGB curve).
pub fn preview_picture(size: UVec2, pixels: &[Rgb], stops: f32) -> Picture {
    Picture { size, bytes: to_srgb8(pixels, stops) }
}

/// The advance of one character of the bundled monospaced font `px` pixels high.
pub fn text_advance(px: f32) -> f32 {
    let font = FontRef::try_from_slice(FONT).expect("the bundled font parses");
    let scaled = font.as_scaled(PxScale::from(px));
    scaled.h_advance(scaled.glyph_id('M'))
}

/// A canvas to compose pictures and text on (the contact sheet, the viewer's status bar).
pub struct Canvas {
    pic: Picture,
    font: FontRef<'static>,
}

impl Canvas {
    /// A `size` canvas filled with the grey level `grey`.
    pub fn new(size: UVec2, grey: u8) -> Self {
        let font = FontRef::try_from_slice(FONT).expect("the bundled font parses");
        Self { pic: Picture { size, bytes: vec![grey; (size.x * size.y * 3) as usize] }, font }
    }

    /// Copies `src` with its top-left corner at (x0, y0), clipped at the canvas's edges.
    pub fn blit(&mut self, src: &Picture, x0: u32, y0: u32) {
        for y in 0..src.size.y.min(self.pic.size.y.saturating_sub(y0)) {
            let w = src.size.x.min(self.pic.size.x.saturating_sub(x0)) as usize;
            let s = (y * src.size.x) as usize * 3;
            let d = (((y0 + y) * self.pic.size.x) + x0) as usize * 3;
            self.pic.bytes[d..d + 3 * w].copy_from_slice(&src.bytes[s..s + 3 * w]);
        }
    }

    /// Draws `text` with its top-left corner at (x, y), `px` pixels high, in `color`, clipped
    /// at `x_max`.
    fn text_clipped(&mut self, text: &str, x: f32, y: f32, px: f32, color: [u8; 3], x_max: f32) {
        let scale = PxScale::from(px);
        let scaled = self.font.as_scaled(scale);
        let mut caret = point(x, y + scaled.ascent());
        for ch in text.chars() {
            let glyph = scaled.glyph_id(ch).with_scale_and_position(scale, caret);
            caret.x += scaled.h_advance(glyph.id);
            if caret.x > x_max {
                break;
            }
            let Some(outline) = self.font.outline_glyph(glyph) else { continue };
            let b = outline.px_bounds();
            let (w, h) = (self.pic.size.x as i64, self.pic.size.y as i64);
            outline.draw(|gx, gy, coverage| {
                let (px_, py) = (b.min.x as i64 + gx as i64, b.min.y as i64 + gy as i64);
                let w = w.min(x_max.ceil() as i64);
                if px_ < 0 || py < 0 || px_ >= w || py >= h {
                    return;
                }
                let i = ((py * self.pic.size.x as i64 + px_) * 3) as usize;
                for (dst, &src) in self.pic.bytes[i..i + 3].iter_mut().zip(&color) {
                    let old = *dst as f32;
                    *dst = (old + (src as f32 - old) * coverage.min(1.0)).round() as u8;
                }
            });
        }
    }

    /// Draws `text` with its top-left corner at (x, y), `px` pixels high, in `color`.
    pub fn text(&mut self, text: &str, x: f32, y: f32, px: f32, color: [u8; 3]) {
        let x_max = self.pic.size.x as f32;
        self.text_clipped(text, x, y, px, color, x_max);
    }

    /// What was drawn.
    pub fn picture(self) -> Picture {
        self.pic
    }
}

/// One column of the contact sheet: a title, up to two lines of numbers, a render and an
/// error map.
pub struct SheetColumn {
    /// Title (sampler name).
    pub title: String,
    /// Numbers under the title (lines separated by `\n`; clipped to the column).
    pub caption: String,
    /// Tonemapped render.
    pub render: Picture,
    /// Error map (absent for the reference column).
    pub error: Option<Picture>,
}

/// Renders and error maps side by side, labelled, with a colour bar for the error scale.
pub fn contact_sheet(columns: &[SheetColumn]) -> Picture {
    let tile = columns.first().map_or(UVec2::new(64, 48), |c| c.render.size);
    let (pad, header, bar) = (8u32, 52u32, 34u32);
    let width = pad + columns.len() as u32 * (tile.x + pad);
    let height = header + tile.y + pad + tile.y + pad + bar;
    let mut canvas = Canvas::new(UVec2::new(width, height), 32);
    for (i, col) in columns.iter().enumerate() {
        let x = pad + i as u32 * (tile.x + pad);
        let right = (x + tile.x) as f32;
        canvas.text_clipped(&col.title, x as f32, 4.0, 16.0, [255, 255, 255], right);
        for (k, line) in col.caption.lines().take(2).enumerate() {
            canvas.text_clipped(line, x as f32, 23.0 + 13.0 * k as f32, 12.0, [200, 200, 200], right);
        }
        canvas.blit(&col.render, x, header);
        match &col.error {
            Some(e) => canvas.blit(e, x, header + tile.y + pad),
            None => {
                canvas.text("(reference)", x as f32 + 4.0, (header + tile.y + pad + 4) as f32, 14.0, [160, 160, 160])
            }
        }
    }
    // Colour bar: 10^-3 … 10^0 relative error.
    let y0 = header + 2 * tile.y + 2 * pad;
    let bar_w = (width - 2 * pad).min(400);
    for x in 0..bar_w {
        let c = ramp(x as f32 / (bar_w - 1) as f32).map(|v| (v * 255.0 + 0.5) as u8);
        for y in y0..y0 + 10 {
            let i = ((y * width + pad + x) * 3) as usize;
            canvas.pic.bytes[i..i + 3].copy_from_slice(&c);
        }
    }
    let label_y = (y0 + 12) as f32;
    canvas.text("1e-3", pad as f32, label_y, 12.0, [200, 200, 200]);
    canvas.text("relative error (log)", (pad + bar_w / 2 - 70) as f32, label_y, 12.0, [200, 200, 200]);
    canvas.text("1", (pad + bar_w - 8) as f32, label_y, 12.0, [200, 200, 200]);
    canvas.picture()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ramp_is_monotone_in_brightness() {
        let lum = |c: [f32; 3]| 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
        let mut last = -1.0;
        for i in 0..=50 {
            let l = lum(ramp(i as f32 / 50.0));
            assert!(l >= last - 1e-3, "{i}");
            last = l;
        }
    }

    #[test]
    fn contact_sheet_has_the_expected_size_and_text() {
        let render = Picture { size: UVec2::new(40, 30), bytes: vec![0; 40 * 30 * 3] };
        let cols: Vec<SheetColumn> = ["reference", "tree"]
            .iter()
            .map(|t| SheetColumn {
                title: t.to_string(),
                caption: "relMSE 0.01".into(),
                render: render.clone(),
                error: (*t != "reference").then(|| render.clone()),
            })
            .collect();
        let sheet = contact_sheet(&cols);
        assert_eq!(sheet.size, UVec2::new(8 + 2 * 48, 52 + 30 + 8 + 30 + 8 + 34));
        // The title row is not blank: the labels were drawn.
        let header: &[u8] = &sheet.bytes[..(sheet.size.x * 20 * 3) as usize];
        assert!(header.iter().any(|&b| b > 200));
    }
}
