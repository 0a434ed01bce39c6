//! What the viewer's window shows: the image (tonemapped at the chosen exposure, or the
//! false-colour relative error against the reference, as `compare`'s error maps) above a
//! status bar, as the 0RGB words the window takes.
//!
//! The bar's fields (sampler, spp, speed, ..., then the keys) are wrapped at the window's
//! width, a field never cut: a 320-pixel window gets more lines than a 1280-pixel one.

use crate::compare::images::{Canvas, error_picture, preview_picture, text_advance};
use crate::compare::metrics::relative_error_map;
use crate::math::{Rgb, UVec2};

const TEXT_PX: f32 = 13.0;
/// Height of one line of the bar, pixels.
const LINE_PX: u32 = 16;
/// Left and right margin of the bar's text.
const MARGIN_PX: f32 = 4.0;
const BAR_GREY: u8 = 24;
const TEXT_COLOR: [u8; 3] = [220, 220, 220];
/// Between two fields on one line.
const GAP: &str = "  ";

/// The longest status the bar must hold, for sizing it: the longest sampler label, then
/// spp, speed, frame rate, the mode and the longest message the viewer gives (a path it
/// saved or reads may be longer, and then takes a line more than the bar has).
const WIDEST_STATUS: [&str; 6] = [
    "cells (as every light at diffuse points, tree elsewhere)",
    "65536 spp (done)",
    "999.99 Msamples/s",
    "999 frames/s",
    "relative error",
    "no reference to show the error against: pass --reference",
];

/// Characters that fit one line of a `width`-pixel bar.
fn chars_per_line(width: u32) -> usize {
    (((width as f32 - 2.0 * MARGIN_PX) / text_advance(TEXT_PX)).floor() as usize).max(1)
}

/// `text` in pieces of at most `chars` characters, broken between words where it is longer
/// (a word longer than a line is a piece of its own).
fn pieces(text: &str, chars: usize) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for word in text.split(' ') {
        match out.last_mut() {
            Some(piece) if piece.chars().count() + 1 + word.chars().count() <= chars => {
                piece.push(' ');
                piece.push_str(word);
            }
            _ => out.push(word.to_string()),
        }
    }
    out
}

/// `fields` joined into lines of at most `chars` characters, a field moved whole to the next
/// line rather than cut; one longer than a line is broken between its words.
pub fn wrap<S: AsRef<str>>(fields: &[S], chars: usize) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    let split = fields
        .iter()
        .map(AsRef::as_ref)
        .filter(|f| !f.is_empty())
        .flat_map(|f| if f.chars().count() > chars { pieces(f, chars) } else { vec![f.to_string()] });
    for field in split {
        let field = field.as_str();
        match lines.last_mut() {
            Some(line) if line.chars().count() + GAP.len() + field.chars().count() <= chars => {
                line.push_str(GAP);
                line.push_str(field);
            }
            _ => lines.push(field.to_string()),
        }
    }
    lines
}

/// Height of the status bar of a `width`-pixel window: the widest status and the keys,
/// wrapped, one line each.
pub fn bar_height(width: u32, keys: &[&str]) -> u32 {
    let chars = chars_per_line(width);
    let lines = wrap(&WIDEST_STATUS, chars).len() + wrap(keys, chars).len();
    lines as u32 * LINE_PX + 4
}

/// The window's pixels: the image (`size`) above the status bar, the `status` fields then
/// the `keys`, wrapped at the width. The image is the render at exposure `stops` (the PNG
/// previews' tonemap), or its relative error against `error_against` when given.
pub fn compose(
    size: UVec2,
    pixels: &[Rgb],
    stops: f32,
    error_against: Option<&[Rgb]>,
    status: &[String],
    keys: &[&str],
) -> Vec<u32> {
    let picture = match error_against {
        Some(reference) => error_picture(size, &relative_error_map(pixels, reference)),
        None => preview_picture(size, pixels, stops),
    };
    let bar = bar_height(size.x, keys);
    let mut canvas = Canvas::new(UVec2::new(size.x, size.y + bar), BAR_GREY);
    canvas.blit(&picture, 0, 0);
    let chars = chars_per_line(size.x);
    let lines = wrap(status, chars).into_iter().chain(wrap(keys, chars));
    for (i, line) in lines.take(((bar - 4) / LINE_PX) as usize).enumerate() {
        canvas.text(&line, MARGIN_PX, (size.y + 2 + i as u32 * LINE_PX) as f32, TEXT_PX, TEXT_COLOR);
    }
    canvas.picture().bytes.chunks_exact(3).map(|c| (c[0] as u32) << 16 | (c[1] as u32) << 8 | c[2] as u32).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::png::to_srgb8;

    const KEYS: [&str; 3] = ["1-7 sampler", "+/- exposure", "Esc quit"];

    #[test]
    fn the_image_area_is_the_png_preview_and_the_bar_is_below() {
        let size = UVec2::new(3, 2);
        let pixels: Vec<Rgb> = (0..6).map(|i| Rgb::splat(i as f32 * 0.15)).collect();
        let words = compose(size, &pixels, 1.0, None, &["a".into()], &KEYS);
        assert_eq!(words.len(), 3 * (2 + bar_height(3, &KEYS) as usize));
        let png = to_srgb8(&pixels, 1.0);
        for (i, w) in words[..6].iter().enumerate() {
            assert_eq!(w.to_be_bytes()[1..], png[3 * i..3 * i + 3], "pixel {i}");
        }
        assert!(words[6..].iter().all(|&w| w >> 16 & 0xff >= BAR_GREY as u32));
        // The error look against itself is the ramp's darkest colour everywhere.
        let err = compose(size, &pixels, 1.0, Some(&pixels), &[], &KEYS);
        assert!(err[..6].iter().all(|&w| w == err[0]) && err[0] != words[0]);
    }

    #[test]
    fn a_narrow_window_wraps_the_status_into_more_lines_and_cuts_no_field() {
        for width in [200, 320, 640, 1280] {
            let chars = chars_per_line(width);
            let lines = wrap(&WIDEST_STATUS, chars);
            // Every field whole on one line, every line within the width.
            for field in WIDEST_STATUS {
                assert!(lines.iter().any(|l| l.contains(field)) || field.len() > chars, "{width}: {field}");
            }
            assert!(lines.iter().all(|l| l.chars().count() <= chars.max(WIDEST_STATUS[0].len())), "{lines:?}");
            let advance = text_advance(TEXT_PX);
            let fits = |l: &String| 2.0 * MARGIN_PX + l.chars().count() as f32 * advance <= width as f32;
            assert!(lines.iter().all(|l| fits(l) || !l.contains(GAP)), "{width}: {lines:?}");
        }
        assert!(bar_height(320, &KEYS) > bar_height(1280, &KEYS));
        assert_eq!(wrap(&["ab", "cd", "ef"], 6), ["ab  cd", "ef"]);
        assert_eq!(wrap(&["abcdefgh", "", "x"], 6), ["abcdefgh", "x"]);
        assert_eq!(wrap(&["no reference here", "ok"], 8), ["no", "reference", "here  ok"]);
    }
}
