//! `myriad diff`: the compare metrics between two EXR files.

use std::fmt;
use std::path::Path;

use crate::compare::images::error_picture;
use crate::compare::metrics::{ErrorMetrics, error_metrics, relative_error_map};
use crate::compare::report::num;
use crate::error::{Error, Result};
use crate::math::Rgb;

/// The metrics of `image` against `reference`.
pub struct DiffReport {
    /// MSE and relMSE.
    pub metrics: ErrorMetrics,
    /// Image size.
    pub size: crate::math::UVec2,
    /// Mean of each channel of the image and of the reference.
    pub means: [Rgb; 2],
}

/// The mean of each channel (summed in f64).
fn mean(pixels: &[Rgb]) -> Rgb {
    let sum = pixels.iter().fold([0.0f64; 3], |s, p| [s[0] + p.x as f64, s[1] + p.y as f64, s[2] + p.z as f64]);
    let n = pixels.len().max(1) as f64;
    Rgb::new((sum[0] / n) as f32, (sum[1] / n) as f32, (sum[2] / n) as f32)
}

/// Compares `image` against `reference` (EXR files with R, G, B of the same size); writes a
/// false-colour relative-error PNG to `error_png` when given.
pub fn diff(image: &Path, reference: &Path, error_png: Option<&Path>) -> Result<DiffReport> {
    let read = |p: &Path| -> Result<_> {
        let (layers, _) = crate::io::exr::read(p)?;
        let rgb =
            layers.rgb().ok_or_else(|| Error::Input { path: p.into(), message: "has no R, G, B channels".into() })?;
        Ok((layers.size, rgb))
    };
    let ((sa, a), (sb, b)) = (read(image)?, read(reference)?);
    if sa != sb {
        return Err(Error::Input {
            path: image.into(),
            message: format!("is {} × {} but {} is {} × {}", sa.x, sa.y, reference.display(), sb.x, sb.y),
        });
    }
    let metrics = error_metrics(&a, &b)?;
    if let Some(p) = error_png {
        let pic = error_picture(sa, &relative_error_map(&a, &b));
        crate::io::png::write_srgb8(p, pic.size, pic.bytes)?;
    }
    Ok(DiffReport { metrics, size: sa, means: [mean(&a), mean(&b)] })
}

impl fmt::Display for DiffReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "size    {} × {}", self.size.x, self.size.y)?;
        writeln!(f, "MSE     {}", num(self.metrics.mse))?;
        writeln!(f, "relMSE  {}", num(self.metrics.rel_mse))?;
        let [a, b] = self.means;
        let ratio = |c: usize| if b[c] > 0.0 { format!("{:+.2} %", 100.0 * (a[c] / b[c] - 1.0)) } else { "n/a".into() };
        writeln!(f, "mean    {:.5} {:.5} {:.5} (reference {:.5} {:.5} {:.5})", a.x, a.y, a.z, b.x, b.y, b.z)?;
        write!(f, "ratio   {} {} {}", ratio(0), ratio(1), ratio(2))
    }
}
