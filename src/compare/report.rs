//! What `compare` found, as data (`report.json`), as a table (terminal and `report.md`).

use serde::Serialize;

use super::metrics::{BIAS_ALPHA, BiasCheck, REL_MSE_EPSILON};

/// Mean and standard deviation of a quantity over seeds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Stat {
    /// Mean over seeds.
    pub mean: f64,
    /// Sample standard deviation (0 for one seed).
    pub std: f64,
}

impl Stat {
    /// Mean and standard deviation of `xs` (non-empty).
    pub fn of(xs: &[f64]) -> Self {
        let n = xs.len() as f64;
        let mean = xs.iter().sum::<f64>() / n;
        let var = if xs.len() > 1 { xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0) } else { 0.0 };
        Self { mean, std: var.sqrt() }
    }
}

/// One render of one sampler with one seed.
#[derive(Clone, Debug, Serialize)]
pub struct RunResult {
    /// The seed the run rendered with.
    pub seed: u64,
    /// Render seconds (scene loading and sampler build excluded).
    pub seconds: f64,
    /// Samples per pixel reached.
    pub spp: u32,
    /// MSE against the reference.
    pub mse: f64,
    /// relMSE against the reference.
    pub rel_mse: f64,
    /// relMSE without the worst 0.1 % of pixels (`metrics::trimmed_rel_mse`).
    pub rel_mse_trimmed: f64,
    /// 1/(relMSE · seconds).
    pub efficiency: f64,
    /// (seconds, relMSE) after each pass.
    pub convergence: Vec<(f64, f64)>,
}

/// Everything measured for one sampler.
#[derive(Clone, Debug, Serialize)]
pub struct SamplerResult {
    /// Sampler name.
    pub sampler: String,
    /// What chose the lights: the sampler's name, or it and what stood in for it
    /// (`cells (as tree)` over 6 lights).
    pub label: String,
    /// Light-sampler build seconds.
    pub build_seconds: f64,
    /// Light-sampler memory in bytes.
    pub memory_bytes: usize,
    /// Render seconds over seeds.
    pub seconds: Stat,
    /// spp over seeds.
    pub spp: Stat,
    /// MSE over seeds.
    pub mse: Stat,
    /// relMSE over seeds.
    pub rel_mse: Stat,
    /// Efficiency: 1/(mean relMSE · mean seconds) over seeds (the time to reach an error is
    /// set by its expectation), ± the spread of the runs' own efficiencies.
    pub efficiency: Stat,
    /// Efficiency divided by the best sampler's.
    pub efficiency_vs_best: f64,
    /// relMSE without the worst 0.1 % of pixels, over seeds.
    pub rel_mse_trimmed: Stat,
    /// 1/(mean trimmed relMSE · mean seconds): the efficiency that a firefly which every
    /// sampler shares does not decide.
    pub efficiency_trimmed: f64,
    /// Does the mean over seeds agree with the reference?
    pub bias: BiasCheck,
    /// Each seed's run.
    pub runs: Vec<RunResult>,
    /// Files written for it (render of the first seed, its error map).
    pub files: Vec<String>,
}

/// How the reference was obtained, and whether it is good enough to judge by.
#[derive(Clone, Debug, Default, Serialize)]
pub struct ReferenceInfo {
    /// Its file.
    pub path: String,
    /// Rendered by myriad (sampler, spp, seed), or given by the user.
    pub origin: String,
    /// True when a cached reference from an earlier run was reused.
    pub reused: bool,
    /// Seconds spent rendering it now (0 when given or reused).
    pub seconds: f64,
    /// Samples per pixel it was rendered with now (0 when given or reused).
    pub spp: u32,
    /// Its own noise: the mean of its variance of the mean over (ref² + ε), the relMSE an
    /// exact image would show against it (unknown without a variance layer).
    pub noise_rel_mse: Option<f64>,
    /// Its noise exceeds a tenth of the least noisy compared run's own: it moves what it
    /// judges.
    pub too_noisy: bool,
    /// The spp it would need to fall below that, when its spp is known.
    pub needed_spp: Option<u64>,
}

impl ReferenceInfo {
    /// The warning a too-noisy reference deserves, if it is one.
    pub fn warning(&self) -> Option<String> {
        self.too_noisy.then(|| {
            format!(
                "the reference is too noisy to judge by: its own noise is relMSE {:.3e}, more than a tenth of the \
                 least noisy run's{}",
                self.noise_rel_mse.unwrap_or(0.0),
                self.needed_spp.map_or(String::new(), |n| format!("; render it with --reference-spp {n} or more"))
            )
        })
    }
}

/// The whole comparison.
#[derive(Clone, Debug, Serialize)]
pub struct CompareReport {
    /// Scene file.
    pub scene: String,
    /// "equal spp (N)" or "equal time (S s)".
    pub mode: String,
    /// Image width and height.
    pub resolution: [u32; 2],
    /// Maximum scattering events.
    pub max_depth: u32,
    /// The runs' sample clamping, `off` or `DIRECT,INDIRECT` (the reference is not clamped,
    /// so the bias column shows what clamping takes away).
    pub clamp: String,
    /// Path guiding of the runs: `off`, or `on` with what it learned (the most any run held,
    /// its learning time).
    pub guiding: String,
    /// Whether the runs solved for light through smooth glass, `on` or `off` (the reference
    /// does).
    pub caustics: String,
    /// Render threads.
    pub threads: usize,
    /// The reference.
    pub reference: ReferenceInfo,
    /// Per sampler, in the order asked.
    pub samplers: Vec<SamplerResult>,
    /// Other files written (contact sheet, plot, reports).
    pub files: Vec<String>,
}

/// A table: a header row, then rows of cells as shown (numbers first, so they sort as numbers).
#[derive(Clone, Debug, Default, Serialize)]
pub struct Table {
    /// Column titles.
    pub columns: Vec<String>,
    /// Each row's cells.
    pub rows: Vec<Vec<Cell>>,
}

/// One cell of a [`Table`]: its text, and a mark where the number needs a second look (the
/// bias check's flag), which Markdown shows in bold and the HTML page as a highlight.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Cell {
    /// What the cell shows.
    pub text: String,
    /// A short note that marks it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mark: Option<String>,
}

impl From<String> for Cell {
    fn from(text: String) -> Self {
        Self { text, mark: None }
    }
}

impl Cell {
    /// The cell in Markdown: its text, and its mark in bold.
    pub fn markdown(&self) -> String {
        match &self.mark {
            Some(m) => format!("{} **{m}**", self.text),
            None => self.text.clone(),
        }
    }
}

/// Formats a number with 4 significant digits (scientific below 1e-3).
pub fn num(x: f64) -> String {
    if x.is_nan() {
        "n/a".into()
    } else if x == 0.0 {
        "0".into()
    } else if x.fract() == 0.0 && x.abs() < 1e9 {
        format!("{x:.0}")
    } else if x.is_infinite() {
        "inf".into()
    } else if x.abs() < 1e-3 || x.abs() >= 1e5 {
        format!("{x:.3e}")
    } else {
        format!("{:.*}", (3 - x.abs().log10().floor() as i32).max(0) as usize, x)
    }
}

fn pm(s: &Stat, seeds: usize) -> String {
    if seeds > 1 && s.std > 0.0 { format!("{} ± {}", num(s.mean), num(s.std)) } else { num(s.mean) }
}

impl CompareReport {
    /// The metrics, a row per sampler: what `table` prints and the HTML page sorts.
    pub fn metrics(&self) -> Table {
        let seeds = self.samplers.first().map_or(1, |s| s.runs.len());
        let columns = [
            "sampler",
            "spp",
            "time (s)",
            "MSE",
            "relMSE",
            "efficiency",
            "vs best",
            "relMSE 99.9 %",
            "efficiency 99.9 %",
            "build (s)",
            "memory (B)",
            "bias z",
        ];
        let rows = self
            .samplers
            .iter()
            .map(|s| {
                let bias = Cell { text: num(s.bias.z), mark: s.bias.flagged.then(|| "biased?".to_string()) };
                let cells = vec![
                    s.label.clone(),
                    pm(&s.spp, seeds),
                    pm(&s.seconds, seeds),
                    pm(&s.mse, seeds),
                    pm(&s.rel_mse, seeds),
                    pm(&s.efficiency, seeds),
                    num(s.efficiency_vs_best),
                    pm(&s.rel_mse_trimmed, seeds),
                    num(s.efficiency_trimmed),
                    num(s.build_seconds),
                    s.memory_bytes.to_string(),
                ];
                cells.into_iter().map(Cell::from).chain([bias]).collect()
            })
            .collect();
        Table { columns: columns.map(String::from).to_vec(), rows }
    }

    /// The results table in Markdown (also what the terminal shows).
    pub fn table(&self) -> String {
        let t = self.metrics();
        let mut md = format!("| {} |\n|---|{}\n", t.columns.join(" | "), "---:|".repeat(t.columns.len() - 1));
        for row in &t.rows {
            md += &format!("| {} |\n", row.iter().map(Cell::markdown).collect::<Vec<_>>().join(" | "));
        }
        md
    }

    /// `report.md`: settings, the table, the contact sheet and the plot.
    pub fn markdown(&self, sheet: &str, plot: &str) -> String {
        let mut md = format!("# myriad compare: {}\n\n", self.scene);
        md += &format!(
            "{}, {} × {} px, max depth {}, clamp {}, guiding {}, caustics {}, {} threads, {} seed(s). Reference: `{}` ({}{}).\n\n",
            self.mode,
            self.resolution[0],
            self.resolution[1],
            self.max_depth,
            self.clamp,
            self.guiding,
            self.caustics,
            self.threads,
            self.samplers.first().map_or(0, |s| s.runs.len()),
            self.reference.path,
            self.reference.origin,
            if self.reference.reused { ", reused from an earlier run" } else { "" }
        );
        md += &self.table();
        if let Some(w) = self.reference.warning() {
            md += &format!("\n**Warning:** {w}.\n");
        }
        md += &format!(
            "\nrelMSE = mean((x − ref)² / (ref² + {REL_MSE_EPSILON})); efficiency = 1 / (relMSE · render \
             seconds), of the means over seeds (± the runs' own spread); `vs best` divides by the best; `99.9 %`: the \
             same without each image's 0.1 % of pixels of largest error, where a caustic firefly that no light \
             sampler reaches would otherwise decide. A bias |z| beyond the {}% level \
             (Šidák-corrected over samplers) is flagged: the mean over seeds disagrees with the reference.\n\n",
            100.0 * BIAS_ALPHA
        );
        md += &format!("![renders (top) and relative error (bottom)]({sheet})\n\n![relMSE against time]({plot})\n");
        md
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_mark_is_bold_in_markdown_and_its_own_field_for_the_page() {
        let flagged = Cell { text: "3.878".into(), mark: Some("biased?".into()) };
        assert_eq!(flagged.markdown(), "3.878 **biased?**");
        let json = serde_json::to_string(&flagged).unwrap();
        assert_eq!(json, r#"{"text":"3.878","mark":"biased?"}"#);
        assert_eq!(serde_json::to_string(&Cell::from("1.5".to_string())).unwrap(), r#"{"text":"1.5"}"#);
    }

    #[test]
    fn numbers_keep_four_significant_digits() {
        assert_eq!(num(0.012345), "0.01235");
        assert_eq!(num(123.456), "123.5");
        assert_eq!(num(1.5e-5), "1.500e-5");
        assert_eq!(num(0.0), "0");
        assert_eq!(num(64.0), "64");
        let s = Stat::of(&[1.0, 2.0, 3.0]);
        assert_eq!((s.mean, s.std), (2.0, 1.0));
    }
}
