//! `myriad diff`: the compare metrics between two EXR files.

use std::fmt;
use std::path::Path;

use crate::compare::images::error_picture;
use crate::compare::metrics::{ErrorMetrics, error_metrics, relative_error_map};
use crate::compare::report::num;
use crate::error::{Error, Result};

/// The metrics of `image` against `reference`.
pub struct DiffReport {
    /// MSE and relMSE.
    pub metrics: ErrorMetrics,
    /// Image size.
    pub size: crate::math::UVec2,
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
    Ok(DiffReport { metrics, size: sa })
}

impl fmt::Display for DiffReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "size    {} × {}", self.size.x, self.size.y)?;
        writeln!(f, "MSE     {}", num(self.metrics.mse))?;
        write!(f, "relMSE  {}", num(self.metrics.rel_mse))
    }
}
