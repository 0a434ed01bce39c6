//! Mutation testing: thousands of malformed copies of real inputs (glTF JSON and GLB, RON
//! scenes, OBJ/MTL, EXR) must each load and render, or fail with a clear error; never panic,
//! hang or reach the last line of defence ([`myriad::guard`]).
//!
//! The quick test runs a few thousand cases in this process (`MYRIAD_MUTATIONS` sets how
//! many). The campaign (`cargo test --release --test it mutation_campaign -- --ignored
//! --nocapture`, `MYRIAD_MUTATIONS` cases, 30 000 by default) runs each case through the
//! real binary under a 4 GB address-space cap and a 10 s limit, so that aborts and
//! out-of-memory kills count too, and prints the distinct failures with a reproducer of each
//! in `target/mutations/`.

use myriad::commands::{SceneOptions, load_scene};
use myriad::light_sampler::LightStrategy;
use myriad::math::UVec2;
use myriad::render::{Budget, RenderSettings, render};
use myriad::scene::{AUTO_CAMERA, BuildOptions};
use myriad::settings::{Clamp, LightSamplerKind};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::time::Duration;

use crate::common::{join_glb, split_glb};

/// SplitMix64: the cases are a pure function of their number.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        myriad::sampling::fmix64(self.0)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
    fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
    fn chance(&mut self, percent: u64) -> bool {
        self.next() % 100 < percent
    }
}

/// Numbers that break things: huge, tiny, negative, not a number, past integer widths.
const NUMBERS: [&str; 16] = [
    "1e38",
    "-1e38",
    "1e300",
    "NaN",
    "inf",
    "-inf",
    "0",
    "-0",
    "-1",
    "4294967295",
    "4294967296",
    "2147483647",
    "18446744073709551615",
    "1e-30",
    "99999999",
    "3",
];

/// JSON values that break things, by the same token.
fn json_values() -> Vec<Value> {
    serde_json::from_str(
        r#"[null, true, "x", [], {}, 0, -1, 1e38, -1e38, 1e300, 2147483647, 4294967296,
            18446744073709551615, 99, 1e-30, 0.5, -0.0, [1e38, 1e38, 1e38], [0, 0, 0, 0], {"index": 99}]"#,
    )
    .unwrap()
}

/// One input to break: its file name and contents, and files it needs beside it.
#[derive(Clone)]
struct Input {
    name: &'static str,
    bytes: Vec<u8>,
    beside: Vec<(&'static str, Vec<u8>)>,
}

fn data(path: &str) -> Vec<u8> {
    std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join(path)).unwrap()
}

/// A RON scene with one of everything the format has.
const EVERYTHING_RON: &str = r#"Scene(
    camera: Perspective(eye: (0, 1, 4.4), look_at: (0, 1, 0), yfov_deg: 37),
    film: (resolution: (8, 6)),
    render: (spp: 2, max_depth: 3, sampler: tree, seed: 1),
    materials: {
        "white": Diffuse(albedo: (0.73, 0.73, 0.73)),
        "steel": MetalRough(base_color: (0.6, 0.6, 0.65), metallic: 1, roughness: 0.3),
        "glow":  Emissive(radiance: (20, 18, 15), two_sided: false),
    },
    objects: [
        Quad(corner: (-1, 0, 1), edge1: (2, 0, 0), edge2: (0, 0, -2), material: "white"),
        Box(size: (0.6, 0.6, 0.6), transform: (translate: (0.4, 0.3, 0), rotate_deg: (0, -17, 0)), material: "glow"),
        Sphere(center: (-0.4, 0.3, 0), radius: 0.3, subdivisions: 2, material: "steel"),
        Mesh(path: "cornell.obj", transform: (scale: (0.5, 0.5, 0.5))),
    ],
    lights: [
        Point(position: (0, 1.5, 0), intensity: (1, 1, 1)),
        Spot(position: (1, 2, 1), direction: (-1, -2, -1), intensity: (50, 50, 50), inner_deg: 20, outer_deg: 30),
        Directional(direction: (0.3, -1, 0.2), irradiance: (2, 2, 2)),
        Quad(corner: (-0.1, 1.99, -0.1), edge1: (0.2, 0, 0), edge2: (0, 0, 0.2), radiance: (30, 30, 30)),
        Grid(center: (0, 1.999, 0), normal: (0, -1, 0), extent: (1.2, 1.2), rows: 4, cols: 5,
             fill: 0.25, emission: Power(watts: 45, color: (1, 1, 1)),
             color_jitter: 0.15, decades: 2, seed: 7, two_sided: false),
    ],
    environment: Map(path: "sky.exr", scale: 0.5, rotate_deg: 30),
)"#;

/// The real files every case starts from.
fn inputs() -> Vec<Input> {
    let obj = ("cornell.obj", data("tests/data/cornell/cornell.obj"));
    let mtl = ("cornell.mtl", data("tests/data/cornell/cornell.mtl"));
    let mut exr = Vec::new();
    {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("x.exr");
        let layers = myriad::image::Layers {
            size: UVec2::new(5, 3),
            channels: ["R", "G", "B", "variance.R"]
                .iter()
                .map(|n| myriad::image::Channel { name: n.to_string(), data: (0..15).map(|i| i as f32).collect() })
                .collect(),
        };
        myriad::io::exr::write(&path, &layers, &[("myriad.spp".into(), "4".into())]).unwrap();
        exr.extend(std::fs::read(path).unwrap());
    }
    vec![
        Input { name: "scene.gltf", bytes: data("tests/data/cornell/cornell-striped.gltf"), beside: vec![] },
        Input { name: "scene.glb", bytes: data("tests/data/blender/panels.glb"), beside: vec![] },
        Input { name: "scene.glb", bytes: data("tests/data/blender/punctual.glb"), beside: vec![] },
        Input { name: "scene.glb", bytes: data("tests/data/blender/materials.glb"), beside: vec![] },
        Input { name: "scene.glb", bytes: data("tests/data/blender/glass.glb"), beside: vec![] },
        // Compressed streams: Draco (draco-core) and meshopt (meshoptimizer) decode bytes.
        Input { name: "scene.glb", bytes: data("tests/data/gltf-variants/draco.glb"), beside: vec![] },
        Input { name: "scene.glb", bytes: data("tests/data/gltf-variants/meshopt.glb"), beside: vec![] },
        Input {
            name: "scene.ron",
            bytes: EVERYTHING_RON.as_bytes().to_vec(),
            beside: vec![obj.clone(), mtl.clone(), ("sky.exr", exr.clone())],
        },
        Input { name: "scene.ron", bytes: data("tests/data/cornell/cornell.ron"), beside: vec![] },
        Input { name: "scene.obj", bytes: obj.1.clone(), beside: vec![mtl.clone()] },
        Input { name: "scene.mtl", bytes: mtl.1.clone(), beside: vec![obj.clone()] },
        Input { name: "image.exr", bytes: exr, beside: vec![] },
    ]
}

/// A random place in `v` (a path of keys and indices), reached by a random walk.
fn random_path(v: &Value, rng: &mut Rng) -> Vec<String> {
    let mut path = Vec::new();
    let mut here = v;
    loop {
        let keys: Vec<String> = match here {
            Value::Object(m) => m.keys().cloned().collect(),
            Value::Array(a) => (0..a.len()).map(|i| i.to_string()).collect(),
            _ => Vec::new(),
        };
        if keys.is_empty() || (!path.is_empty() && rng.chance(25)) {
            return path;
        }
        let k = rng.pick(&keys).clone();
        here = match here {
            Value::Object(m) => &m[&k],
            Value::Array(a) => &a[k.parse::<usize>().unwrap()],
            _ => unreachable!("only containers have keys"),
        };
        path.push(k);
    }
}

/// The value at `path`.
fn at_path<'a>(v: &'a mut Value, path: &[String]) -> &'a mut Value {
    path.iter().fold(v, |here, k| match here {
        Value::Object(m) => m.get_mut(k).unwrap(),
        Value::Array(a) => &mut a[k.parse::<usize>().unwrap()],
        _ => unreachable!("paths lead through containers"),
    })
}

/// One mutation of a JSON document: replace a value, delete it, duplicate or empty an array.
fn mutate_json(doc: &mut Value, rng: &mut Rng) {
    let values = json_values();
    let path = random_path(doc, rng);
    match rng.below(4) {
        0 | 1 => *at_path(doc, &path) = rng.pick(&values).clone(),
        2 => match at_path(doc, &path) {
            Value::Array(a) if !a.is_empty() => {
                let copy = a[rng.below(a.len())].clone();
                a.push(copy);
            }
            spot @ Value::Number(_) => *spot = serde_json::json!(spot.as_f64().unwrap_or(0.0) * 1e6 + 7.0),
            _ => {}
        },
        _ => {
            // Delete this key or element from its parent.
            let Some((last, parent)) = path.split_last() else { return };
            match at_path(doc, parent) {
                Value::Object(m) => {
                    m.remove(last);
                }
                Value::Array(a) => {
                    a.remove(last.parse::<usize>().unwrap());
                }
                _ => {}
            }
        }
    }
}

/// One mutation of a text file: a number replaced, a line dropped, doubled or cut, a
/// character dropped or changed.
fn mutate_text(text: &str, rng: &mut Rng) -> String {
    let lines: Vec<&str> = text.lines().collect();
    let mut lines: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
    if lines.is_empty() {
        return text.to_string();
    }
    let i = rng.below(lines.len());
    match rng.below(6) {
        0 | 1 => {
            // Replace one number of a line.
            let words: Vec<(usize, usize)> = number_spans(&lines[i]);
            if let Some(&(a, b)) = words.get(rng.below(words.len().max(1))) {
                let number: &str = NUMBERS[rng.below(NUMBERS.len())];
                lines[i].replace_range(a..b, number);
            }
        }
        2 => {
            lines.remove(i);
        }
        3 => {
            let copy = lines[i].clone();
            lines.insert(i, copy);
        }
        4 => {
            let cut = rng.below(lines[i].len() + 1);
            let cut = (0..=cut).rev().find(|&c| lines[i].is_char_boundary(c)).unwrap_or(0);
            lines[i].truncate(cut);
        }
        _ => {
            let punctuation = ["(", ")", "[", "]", ",", ":", "\"", "/", "-", " ", ""];
            let l = &mut lines[i];
            if let Some((at, c)) = l.char_indices().nth(rng.below(l.chars().count().max(1))) {
                let with: &str = punctuation[rng.below(punctuation.len())];
                l.replace_range(at..at + c.len_utf8(), with);
            }
        }
    }
    lines.join("\n")
}

/// Byte ranges of the numbers in `line`.
fn number_spans(line: &str) -> Vec<(usize, usize)> {
    let b = line.as_bytes();
    let mut spans = Vec::new();
    let mut i = 0;
    while i < b.len() {
        if b[i].is_ascii_digit() || (b[i] == b'-' && b.get(i + 1).is_some_and(u8::is_ascii_digit)) {
            let start = i;
            i += 1;
            while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'.' || b[i] == b'-' || b[i] == b'+') {
                i += 1;
            }
            spans.push((start, i));
        } else {
            i += 1;
        }
    }
    spans
}

/// One mutation of binary data: truncated, a bit flipped, a byte zeroed or saturated (in the
/// first `hot` bytes, where headers are, more often than not).
fn mutate_bytes(bytes: &mut Vec<u8>, rng: &mut Rng, hot: usize) {
    if bytes.is_empty() {
        return;
    }
    let at = if rng.chance(70) { rng.below(hot.min(bytes.len())) } else { rng.below(bytes.len()) };
    match rng.below(4) {
        0 => bytes.truncate(at),
        1 => bytes[at] ^= 1 << rng.below(8),
        2 => bytes[at] = 0,
        _ => bytes[at] = 0xff,
    }
}

/// Case `k`: which input, and its mutated bytes.
fn case(inputs: &[Input], k: u64) -> Input {
    let mut rng = Rng(k.wrapping_mul(0xd1b5_4a32_d192_ed03) ^ 0x1234_5678);
    let mut input = rng.pick(inputs).clone();
    let edits = 1 + rng.below(3);
    for _ in 0..edits {
        input.bytes = match input.name {
            "scene.gltf" => match serde_json::from_slice::<Value>(&input.bytes) {
                Ok(mut doc) if rng.chance(85) => {
                    mutate_json(&mut doc, &mut rng);
                    doc.to_string().into_bytes()
                }
                _ => mutate_text(&String::from_utf8_lossy(&input.bytes), &mut rng).into_bytes(),
            },
            "scene.glb" => match split_glb(&input.bytes) {
                Some((mut doc, rest)) if rng.chance(70) => {
                    mutate_json(&mut doc, &mut rng);
                    join_glb(&doc, &rest)
                }
                _ => {
                    let mut b = input.bytes.clone();
                    mutate_bytes(&mut b, &mut rng, 64);
                    b
                }
            },
            "image.exr" => {
                let mut b = input.bytes.clone();
                mutate_bytes(&mut b, &mut rng, 400);
                b
            }
            _ => mutate_text(&String::from_utf8_lossy(&input.bytes), &mut rng).into_bytes(),
        };
    }
    input
}

/// Writes `input` into `dir`; the path of the file to open.
fn write(dir: &Path, input: &Input) -> PathBuf {
    for (name, bytes) in &input.beside {
        std::fs::write(dir.join(name), bytes).unwrap();
    }
    let path = dir.join(input.name);
    std::fs::write(&path, &input.bytes).unwrap();
    // A mutated MTL is opened through its OBJ.
    if input.name == "scene.mtl" {
        std::fs::rename(&path, dir.join("cornell.mtl")).unwrap();
        return dir.join("cornell.obj");
    }
    path
}

/// Loads (or reads) the case's file and renders one tiny sample pass with two samplers.
fn exercise(path: &Path) -> myriad::Result<()> {
    if path.extension().is_some_and(|e| e == "exr") {
        return myriad::io::exr::read(path).map(|_| ());
    }
    let obj = path.extension().is_some_and(|e| e == "obj");
    let options = SceneOptions {
        load: Default::default(),
        build: BuildOptions {
            resolution: Some(UVec2::new(4, 3)),
            camera: obj.then(|| AUTO_CAMERA.to_string()),
            ..Default::default()
        },
    };
    let loaded = load_scene(Some(path), &options)?;
    let (scene, resolution) = (loaded.scene, loaded.report.resolution);
    for kind in [LightSamplerKind::Tree, LightSamplerKind::Power] {
        let strategy = LightStrategy::build(kind, &scene.lights, scene.center, scene.radius);
        let settings = RenderSettings {
            budget: Budget::Spp(1),
            seed: 1,
            max_depth: 3,
            clamp: Clamp::OFF,
            guiding: false,
            caustics: true,
            resolution,
            aovs: Default::default(),
        };
        render(&scene, &strategy, &settings, &mut ());
    }
    Ok(())
}

/// Where reproducers of failures go.
fn failures_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("target/mutations")
}

/// Keeps a failing case's files for the person who will fix it.
fn keep(input: &Input, k: u64, label: &str) -> PathBuf {
    let dir = failures_dir().join(format!("case-{k}-{label}"));
    std::fs::create_dir_all(&dir).unwrap();
    write(&dir, input);
    dir
}

fn cases_wanted(default: u64) -> u64 {
    std::env::var("MYRIAD_MUTATIONS").ok().and_then(|v| v.parse().ok()).unwrap_or(default)
}

#[test]
fn mutated_inputs_load_render_or_fail_clearly() {
    crate::bad_input::low_memory_limit();
    let inputs = inputs();
    let n = cases_wanted(3000);
    let dir = tempfile::tempdir().unwrap();
    let (mut errors, mut failures) = (0u64, Vec::new());
    let start = std::time::Instant::now();
    for k in 0..n {
        let input = case(&inputs, k);
        let case_dir = dir.path().join(k.to_string());
        std::fs::create_dir(&case_dir).unwrap();
        let path = write(&case_dir, &input);
        // A hang shows as a case that does not finish: run it on a thread and wait.
        let (tx, rx) = std::sync::mpsc::channel();
        let p = path.clone();
        std::thread::spawn(move || {
            let outcome = std::panic::catch_unwind(|| exercise(&p));
            let _ = tx.send(outcome);
        });
        match rx.recv_timeout(Duration::from_secs(20)) {
            Ok(Ok(Ok(()))) => {}
            Ok(Ok(Err(e))) if !e.to_string().contains(myriad::guard::BUG_REPORT) => errors += 1,
            Ok(Ok(Err(e))) => failures.push(format!("case {k} ({}): {e}", keep(&input, k, "caught").display())),
            Ok(Err(_)) => failures.push(format!("case {k} ({}): panicked", keep(&input, k, "panic").display())),
            Err(_) => {
                failures.push(format!("case {k} ({}): still running after 20 s", keep(&input, k, "hang").display()));
                break;
            }
        }
        let _ = std::fs::remove_dir_all(&case_dir);
    }
    eprintln!(
        "{n} mutated inputs in {:.1} s: {errors} clear errors, {} failures",
        start.elapsed().as_secs_f64(),
        failures.len()
    );
    assert!(failures.is_empty(), "{} of {n} cases failed:\n{}", failures.len(), failures.join("\n"));
}

/// Options a user could mistype, with values that break things.
const OPTIONS: [(&str, &[&str]); 12] = [
    ("--spp", &["0", "-1", "x", "4294967296", "1e9"]),
    ("--resolution", &["0x0", "99999x1", "16384x16384", "axb", "1x1", "32768x32768"]),
    ("--time", &["0", "-1", "NaN", "inf", "1e300", "0.001"]),
    ("--threads", &["0", "100000", "65536", "1"]),
    ("--exposure", &["NaN", "inf", "1e9", "-1e9"]),
    ("--max-depth", &["0", "4294967295", "-1"]),
    ("--seed", &["18446744073709551615", "-1", "x"]),
    ("--camera", &["nope", "auto", ""]),
    ("--gltf-scene", &["99", "18446744073709551615"]),
    ("--punctual-scale", &["NaN", "-1", "1e38", "0", "inf"]),
    ("--max-memory", &["0", "1e-9", "NaN", "1e30"]),
    ("--sampler", &["all", "local", "uniform", "nope"]),
];

/// The command line case `k` runs: render (or diff) its file, with a mistyped option one
/// time in five.
fn command_line(path: &Path, k: u64) -> Vec<String> {
    let mut rng = Rng(k ^ 0xc0ff_ee00_d00d_f00d);
    let file = path.file_name().unwrap().to_string_lossy().into_owned();
    let mut args: Vec<String> = if file.ends_with(".exr") {
        vec!["diff".into(), file, "reference.exr".into()]
    } else {
        let mut a: Vec<String> =
            ["render", &file, "-o", "out.exr", "--spp", "1", "--resolution", "8x6", "--max-depth", "3", "-q"]
                .iter()
                .map(|s| s.to_string())
                .collect();
        if file.ends_with(".obj") {
            a.extend(["--camera".into(), "auto".into()]);
        }
        a
    };
    if rng.chance(20) && args[0] == "render" {
        let (flag, values) = rng.pick(&OPTIONS);
        let global = matches!(*flag, "--threads" | "--max-memory");
        let pair = [flag.to_string(), rng.pick(values).to_string()];
        if global {
            args.splice(0..0, pair);
        } else {
            args.extend(pair);
        }
    }
    args
}

/// How one run of the binary ended, as a failure's signature (`None`: fine).
fn classify(status: Option<std::process::ExitStatus>, stderr: &str) -> Option<String> {
    use std::os::unix::process::ExitStatusExt;
    let Some(status) = status else { return Some("hang: still running after 10 s".into()) };
    if let Some(at) = stderr.find("panicked at ") {
        let place: String = stderr[at..].chars().take_while(|&c| c != '\n' && c != ':').collect();
        let line: String = stderr[at + place.len()..].chars().skip(1).take_while(char::is_ascii_digit).collect();
        return Some(format!("{place}:{line}"));
    }
    if stderr.contains(myriad::guard::BUG_REPORT) {
        let at = stderr.find(" at ").map_or("", |i| &stderr[i..]);
        return Some(format!("contained panic{}", at.split(')').next().unwrap_or("")));
    }
    if let Some(bytes) = stderr.find("memory allocation of").map(|i| &stderr[i..]) {
        return Some(format!("out of memory: {}", bytes.lines().next().unwrap_or("")));
    }
    match (status.code(), status.signal()) {
        (Some(0..=2), _) => None,
        (_, Some(signal)) => Some(format!("killed by signal {signal}")),
        (code, _) => Some(format!("exit code {code:?}")),
    }
}

/// Runs `args` in `dir` under a 4 GB address-space cap for at most 10 s.
fn run_capped(binary: &Path, dir: &Path, args: &[String]) -> (Option<std::process::ExitStatus>, String) {
    use std::os::unix::process::CommandExt;
    let mut command = std::process::Command::new(binary);
    command.args(args).current_dir(dir).stdout(std::process::Stdio::null()).stderr(std::process::Stdio::piped());
    // SAFETY: setrlimit is async-signal-safe, as code between fork and exec must be.
    unsafe {
        command.pre_exec(|| {
            let cap = libc::rlimit { rlim_cur: 4 << 30, rlim_max: 4 << 30 };
            libc::setrlimit(libc::RLIMIT_AS, &cap);
            Ok(())
        });
    }
    let mut child = command.spawn().expect("the binary starts");
    let mut stderr = child.stderr.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut text = String::new();
        std::io::Read::read_to_string(&mut stderr, &mut text).ok();
        text
    });
    let start = std::time::Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break Some(s);
        }
        if start.elapsed() > Duration::from_secs(10) {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    (status, reader.join().unwrap_or_default())
}

/// The long campaign: see the module docs. `MYRIAD_BIN` runs another build of the binary
/// (an older one, to count what it got wrong).
#[test]
#[ignore = "a campaign of minutes: cargo test --release --test it mutation_campaign -- --ignored --nocapture"]
fn mutation_campaign() {
    use rayon::prelude::*;
    use std::collections::BTreeMap;
    let binary =
        std::env::var_os("MYRIAD_BIN").map_or_else(|| PathBuf::from(env!("CARGO_BIN_EXE_myriad")), PathBuf::from);
    let inputs = inputs();
    let reference = inputs.iter().find(|i| i.name == "image.exr").unwrap().bytes.clone();
    let n = cases_wanted(30_000);
    let root = tempfile::tempdir().unwrap();
    let start = std::time::Instant::now();
    let done = std::sync::atomic::AtomicU64::new(0);
    let found: Vec<(String, u64, Vec<String>)> = (0..n)
        .into_par_iter()
        .filter_map(|k| {
            let finished = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            if finished.is_multiple_of(1000) {
                eprintln!("{finished} of {n} cases, {:.0} s", start.elapsed().as_secs_f64());
            }
            let input = case(&inputs, k);
            let dir = root.path().join(k.to_string());
            std::fs::create_dir(&dir).unwrap();
            let path = write(&dir, &input);
            std::fs::write(dir.join("reference.exr"), &reference).unwrap();
            let args = command_line(&path, k);
            let (status, stderr) = run_capped(&binary, &dir, &args);
            let _ = std::fs::remove_dir_all(&dir);
            classify(status, &stderr).map(|signature| {
                let kept = keep(&input, k, "campaign");
                std::fs::write(kept.join("command.txt"), args.join(" ")).unwrap();
                std::fs::write(kept.join("stderr.txt"), &stderr).unwrap();
                (signature, k, args)
            })
        })
        .collect();
    let mut distinct: BTreeMap<&str, (usize, u64)> = BTreeMap::new();
    for (signature, k, _) in &found {
        let e = distinct.entry(signature).or_insert((0, *k));
        e.0 += 1;
    }
    eprintln!(
        "{n} cases through {} in {:.0} s: {} failed, {} distinct failures",
        binary.display(),
        start.elapsed().as_secs_f64(),
        found.len(),
        distinct.len()
    );
    for (signature, (count, k)) in &distinct {
        eprintln!("  {count:>6} × {signature}   (e.g. {}/case-{k}-campaign)", failures_dir().display());
    }
    assert!(found.is_empty(), "{} distinct failures", distinct.len());
}
