//! `myriad diff`: the compare metrics between two EXR files.

use std::fmt;
use std::path::{Path, PathBuf};

use super::file_name;
use crate::compare::html::{self, Page, PageImage};
use crate::compare::images::error_picture;
use crate::compare::metrics::{ErrorMetrics, error_metrics, relative_error_map};
use crate::compare::report::{Cell, Table, num};
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

/// What `diff` compares and writes.
#[derive(Clone, Debug, Default)]
pub struct DiffOptions {
    /// The image to judge.
    pub image: PathBuf,
    /// The reference.
    pub reference: PathBuf,
    /// A false-colour relative-error PNG to write.
    pub error_png: Option<PathBuf>,
    /// An HTML page to write (the two images, as compare's report.html shows them).
    pub html: Option<PathBuf>,
}

/// Compares `image` against `reference` (EXR files with R, G, B of the same size); writes
/// the error PNG and the page when asked.
pub fn diff(opts: &DiffOptions) -> Result<DiffReport> {
    let (image, reference) = (opts.image.as_path(), opts.reference.as_path());
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
    if let Some(p) = &opts.error_png {
        let pic = error_picture(sa, &relative_error_map(&a, &b));
        crate::io::png::write_srgb8(p, pic.size, pic.bytes)?;
    }
    let report = DiffReport { metrics, size: sa, means: [mean(&a), mean(&b)] };
    if let Some(p) = &opts.html {
        crate::io::write_text(p, &page(opts, &report, &a, &b))?;
    }
    Ok(report)
}

/// The two images on compare's HTML page: the reference first, the metrics, both paths.
fn page(opts: &DiffOptions, report: &DiffReport, image: &[Rgb], reference: &[Rgb]) -> String {
    let (image_name, reference_name) = (file_name(&opts.image), file_name(&opts.reference));
    let table = Table {
        columns: ["image", "MSE", "relMSE"].map(String::from).to_vec(),
        rows: vec![[image_name.clone(), num(report.metrics.mse), num(report.metrics.rel_mse)].map(Cell::from).to_vec()],
    };
    html::page(&Page {
        title: format!("myriad diff: {image_name} against {reference_name}"),
        size: report.size,
        images: vec![
            PageImage { name: reference_name, caption: "reference".into(), pixels: reference },
            PageImage { name: image_name, caption: String::new(), pixels: image },
        ],
        table,
        plot_svg: None,
        facts: vec![
            ("image".into(), opts.image.display().to_string()),
            ("reference".into(), opts.reference.display().to_string()),
        ],
        exposure: 0.0,
    })
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
