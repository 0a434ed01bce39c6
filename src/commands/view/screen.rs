//! What the viewer's window shows: the image (tonemapped at the chosen exposure, or the
//! false-colour relative error against the reference, as `compare`'s error maps) above a
//! status bar, as the 0RGB words the window takes.

use crate::compare::images::{Canvas, error_picture, preview_picture};
use crate::compare::metrics::relative_error_map;
use crate::math::{Rgb, UVec2};

/// Height of the status bar under the image, in pixels: two lines of text.
pub const BAR_HEIGHT: u32 = 34;
const TEXT_PX: f32 = 13.0;
const BAR_GREY: u8 = 24;
const TEXT_COLOR: [u8; 3] = [220, 220, 220];

/// The window's pixels: the image (`size`) above the two status lines. The image is the
/// render at exposure `stops` (the PNG previews' tonemap), or its relative error against
/// `error_against` when given.
pub fn compose(size: UVec2, pixels: &[Rgb], stops: f32, error_against: Option<&[Rgb]>, status: [&str; 2]) -> Vec<u32> {
    let picture = match error_against {
        Some(reference) => error_picture(size, &relative_error_map(pixels, reference)),
        None => preview_picture(size, pixels, stops),
    };
    let mut canvas = Canvas::new(UVec2::new(size.x, size.y + BAR_HEIGHT), BAR_GREY);
    canvas.blit(&picture, 0, 0);
    for (i, line) in status.iter().enumerate() {
        canvas.text(line, 4.0, (size.y + 2) as f32 + i as f32 * (TEXT_PX + 3.0), TEXT_PX, TEXT_COLOR);
    }
    canvas.picture().bytes.chunks_exact(3).map(|c| (c[0] as u32) << 16 | (c[1] as u32) << 8 | c[2] as u32).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::png::to_srgb8;

    #[test]
    fn the_image_area_is_the_png_preview_and_the_bar_is_below() {
        let size = UVec2::new(3, 2);
        let pixels: Vec<Rgb> = (0..6).map(|i| Rgb::splat(i as f32 * 0.15)).collect();
        let words = compose(size, &pixels, 1.0, None, ["a", "b"]);
        assert_eq!(words.len(), 3 * (2 + BAR_HEIGHT as usize));
        let png = to_srgb8(&pixels, 1.0);
        for (i, w) in words[..6].iter().enumerate() {
            assert_eq!(w.to_be_bytes()[1..], png[3 * i..3 * i + 3], "pixel {i}");
        }
        assert!(words[6..].iter().all(|&w| w >> 16 & 0xff >= BAR_GREY as u32));
        // The error look against itself is the ramp's darkest colour everywhere.
        let err = compose(size, &pixels, 1.0, Some(&pixels), ["", ""]);
        assert!(err[..6].iter().all(|&w| w == err[0]) && err[0] != words[0]);
    }
}
