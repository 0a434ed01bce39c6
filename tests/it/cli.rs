//! The `myriad` binary as users run it: bad input gives a clear error and a non-zero exit,
//! never a panic or a half-written file; good input gives EXR + PNG with provenance.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn myriad(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_myriad")).args(args).current_dir(dir).output().expect("myriad runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A small scene that renders.
pub const GOOD: &str = r#"Scene(
    camera: Perspective(eye: (0, 1, 3), look_at: (0, 1, 0), yfov_deg: 40),
    film: (resolution: (16, 12)),
    materials: { "white": Diffuse(albedo: (0.7, 0.7, 0.7)) },
    objects: [ Quad(corner: (-1, 0, 1), edge1: (2, 0, 0), edge2: (0, 0, -2), material: "white") ],
    lights: [ Quad(corner: (-0.2, 1.9, -0.2), edge1: (0.4, 0, 0), edge2: (0, 0, 0.4), radiance: (5, 5, 5)) ],
)"#;

/// Writes `text` as a scene in a fresh directory; returns (dir guard, scene path).
fn scene_file(text: &str) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scene.ron");
    std::fs::write(&path, text).unwrap();
    (dir, path)
}

/// Runs the binary with `args` in a folder holding `text` as `scene.ron`, expecting a clear
/// error mentioning every one of `needles` and no file besides the scene (no output, no
/// temporary file).
fn expect_failure(text: &str, args: &[&str], needles: &[&str]) {
    let (dir, _) = scene_file(text);
    let out = myriad(args, dir.path());
    let err = stderr(&out);
    assert!(!out.status.success(), "{args:?} succeeded: {err}");
    assert!(!err.contains("panicked") && !err.contains(myriad::guard::BUG_REPORT), "{args:?}: {err}");
    for n in needles {
        assert!(err.contains(n), "{args:?}: error lacks '{n}':\n{err}");
    }
    let files: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(files, vec![std::ffi::OsString::from("scene.ron")], "{args:?}: files left behind");
}

/// Renders `text` and expects failure mentioning every one of `needles`.
fn expect_error(text: &str, needles: &[&str]) {
    expect_failure(text, &["render", "scene.ron", "-o", "out.exr", "--spp", "1"], needles);
}

#[test]
fn typo_names_line_column_and_the_expected_fields() {
    expect_error(&GOOD.replace("yfov_deg", "yfov_dg"), &["scene.ron", "2:", "yfov_dg", "yfov_deg", "^"]);
}

#[test]
fn unknown_material_lists_the_defined_ones() {
    expect_error(&GOOD.replace("material: \"white\"", "material: \"whte\""), &["objects[0] Quad", "whte", "white"]);
}

#[test]
fn missing_mesh_file_names_it() {
    let text = GOOD.replace("objects: [", "objects: [ Mesh(path: \"assets/missing.obj\"),");
    expect_error(&text, &["objects[0] Mesh", "missing.obj", "No such file"]);
}

#[test]
fn nan_coordinates_are_rejected() {
    expect_error(&GOOD.replace("corner: (-1, 0, 1)", "corner: (NaN, 0, 1)"), &["objects[0] Quad", "non-finite"]);
}

#[test]
fn zero_area_light_is_rejected() {
    expect_error(&GOOD.replace("edge2: (0, 0, 0.4)", "edge2: (0.8, 0, 0)"), &["lights[0] Quad", "zero area"]);
}

#[test]
fn negative_radiance_is_rejected() {
    expect_error(&GOOD.replace("radiance: (5, 5, 5)", "radiance: (5, -1, 5)"), &["lights[0] Quad", "negative"]);
}

#[test]
fn bad_grid_is_explained() {
    let text = GOOD.replace(
        "lights: [",
        "lights: [ Grid(center: (0, 1.9, 0), normal: (0, -1, 0), extent: (1, 1), rows: 0, cols: 4, emission: Radiance(rgb: (1, 1, 1))),",
    );
    expect_error(&text, &["lights[0] Grid", "rows"]);
}

#[test]
fn over_many_lights_the_summary_says_the_tables_choose_among_clusters() {
    let text = GOOD.replace(
        "lights: [",
        "lights: [ Grid(center: (0, 1.9, 0), normal: (0, -1, 0), extent: (1.6, 1.6), rows: 40, cols: 40, emission: Radiance(rgb: (1, 1, 1))),",
    );
    let (dir, _) = scene_file(&text);
    let out = myriad(&["render", "scene.ron", "--spp", "4", "-o", "out.exr"], dir.path());
    assert!(out.status.success(), "{}", stderr(&out));
    let summary = String::from_utf8_lossy(&out.stdout);
    assert!(summary.contains("1601 lights") && summary.contains("sampler cells built"), "{summary}");
    assert!(summary.contains("clusters of lights at diffuse points (the tree chooses within them"), "{summary}");
}

#[test]
fn unwritable_output_fails_before_rendering_and_keeps_old_files() {
    let (dir, _) = scene_file(GOOD);
    let out = myriad(&["render", "scene.ron", "-o", "no/such/dir/out.exr", "--spp", "100000"], dir.path());
    assert!(!out.status.success());
    assert!(stderr(&out).contains("no/such/dir/out.exr"), "{}", stderr(&out));
    // An existing output survives a failed render untouched.
    std::fs::write(dir.path().join("keep.exr"), b"previous render").unwrap();
    let bad = GOOD.replace("radiance: (5, 5, 5)", "radiance: (5, -1, 5)");
    std::fs::write(dir.path().join("scene.ron"), bad).unwrap();
    let out = myriad(&["render", "scene.ron", "-o", "keep.exr"], dir.path());
    assert!(!out.status.success());
    assert_eq!(std::fs::read(dir.path().join("keep.exr")).unwrap(), b"previous render");
}

#[test]
fn unknown_sampler_suggests_the_names() {
    let (dir, _) = scene_file(GOOD);
    let out = myriad(&["render", "scene.ron", "--sampler", "powr"], dir.path());
    assert!(!out.status.success());
    let err = stderr(&out);
    assert!(err.contains("power") && err.contains("uniform"), "{err}");
}

#[test]
fn render_writes_exr_with_provenance_and_png_and_nothing_else() {
    let (dir, _) = scene_file(GOOD);
    let out = myriad(
        &["render", "scene.ron", "-o", "img.exr", "--spp", "4", "--seed", "3", "--aov", "albedo,normal,depth,variance"],
        dir.path(),
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let summary = String::from_utf8_lossy(&out.stdout);
    for key in ["samples/s", "rays/s", "lights", "triangles", "BVH"] {
        assert!(summary.contains(key), "summary lacks {key}: {summary}");
    }
    let (layers, meta) = myriad::io::exr::read(&dir.path().join("img.exr")).unwrap();
    for c in ["R", "G", "B", "albedo.R", "N.X", "Z", "variance.G"] {
        assert!(layers.channel(c).is_some(), "missing channel {c}");
    }
    let get = |k: &str| meta.iter().find(|(a, _)| a == k).map(|(_, v)| v.clone());
    assert_eq!(get("myriad.sampler").as_deref(), Some("cells"));
    assert_eq!(get("myriad.spp").as_deref(), Some("4"));
    assert_eq!(get("myriad.seed").as_deref(), Some("3"));
    assert_eq!(get("myriad.max_depth").as_deref(), Some("8"));
    assert!(get("myriad.render_seconds").is_some() && get("myriad.version").is_some());
    let mut files: Vec<String> =
        std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
    files.sort();
    assert_eq!(files, ["img.exr", "img.png", "scene.ron"]);
}

#[test]
fn default_scene_renders_without_arguments_and_threads_do_not_change_pixels() {
    let dir = tempfile::tempdir().unwrap();
    let args = |t: &'static str, o: &'static str| {
        ["--threads", t, "render", "-o", o, "--resolution", "20x15", "--spp", "3", "--no-png"]
    };
    assert!(myriad(&args("1", "a.exr"), dir.path()).status.success());
    assert!(myriad(&args("2", "b.exr"), dir.path()).status.success());
    let (a, _) = myriad::io::exr::read(&dir.path().join("a.exr")).unwrap();
    let (b, _) = myriad::io::exr::read(&dir.path().join("b.exr")).unwrap();
    assert_eq!(a, b);
    assert!(a.channel("R").unwrap().data.iter().any(|v| *v > 0.0));
}

#[test]
fn info_reports_counts() {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-9x9.ron");
    let out = myriad(&["info", scene.to_str().unwrap()], Path::new("."));
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("81 (81 quad)"), "{text}");
    assert!(text.contains("B/triangle"), "{text}");
}

/// Runs the binary with `args` beside the good scene, expecting a clear error.
fn expect_usage_error(args: &[&str], needles: &[&str]) {
    expect_failure(GOOD, args, needles);
}

#[test]
fn absurd_options_are_refused_with_the_reason() {
    expect_usage_error(&["render", "scene.ron", "--time", "1e300"], &["1e300", "longer than"]);
    expect_usage_error(&["render", "scene.ron", "--time", "NaN"], &["positive"]);
    expect_usage_error(&["--threads", "100000", "render", "scene.ron"], &["100000", "1..=1024"]);
    expect_usage_error(&["render", "scene.ron", "--exposure", "NaN"], &["exposure"]);
    expect_usage_error(&["render", "scene.ron", "-o", "x.png"], &["x.png", ".exr"]);
    expect_usage_error(&["render", "scene.ron", "-o", "x.exr", "--png", "./x.exr"], &["--png", "overwrite"]);
    expect_usage_error(
        &["--max-memory", "1", "render", "scene.ron", "--resolution", "16384x16384"],
        &["16384 × 16384", "memory", "--max-memory"],
    );
    expect_usage_error(&["--max-memory", "0", "info", "scene.ron"], &["gigabytes"]);
}

#[test]
fn clamping_darkens_what_it_clamps_and_every_output_says_so() {
    let (dir, _) = scene_file(GOOD);
    let d = dir.path();
    let mean_and_meta = |name: &str| {
        let (layers, meta) = myriad::io::exr::read(&d.join(name)).unwrap();
        let rgb = layers.rgb().unwrap();
        let mean = rgb.iter().map(|c| (c.x + c.y + c.z) as f64).sum::<f64>() / rgb.len() as f64;
        (mean, meta.into_iter().find(|(k, _)| k == "myriad.clamp").map(|(_, v)| v))
    };
    crate::split::ok(&["render", "scene.ron", "--spp", "16", "-o", "free.exr"], d);
    crate::split::ok(&["render", "scene.ron", "--spp", "16", "--clamp", "0.3,0.05", "-o", "clamped.exr"], d);
    let ((free, none), (clamped, said)) = (mean_and_meta("free.exr"), mean_and_meta("clamped.exr"));
    assert!(none.is_none() && said.as_deref() == Some("0.3,0.05"), "{none:?} {said:?}");
    assert!(clamped < 0.9 * free, "clamped mean {clamped} against {free}");
    // A clamp as large as nothing reaches changes no bit.
    crate::split::ok(&["render", "scene.ron", "--spp", "16", "--clamp", "1e30,1e30", "-o", "loose.exr"], d);
    crate::split::same_pixels(&d.join("loose.exr"), &d.join("free.exr"));
    // The same clamp from the scene file gives the same image.
    let in_file = GOOD.replace(
        "film: (resolution: (16, 12)),",
        "film: (resolution: (16, 12)),\n    render: (clamp: (direct: 0.3, indirect: 0.05)),",
    );
    std::fs::write(d.join("clamped.ron"), &in_file).unwrap();
    crate::split::ok(&["render", "clamped.ron", "--spp", "16", "-o", "from-file.exr"], d);
    crate::split::same_pixels(&d.join("from-file.exr"), &d.join("clamped.exr"));
    expect_failure(&in_file.replace("direct: 0.3", "direct: -0.3"), &["render", "scene.ron"], &["render.clamp", "≥ 0"]);
    expect_usage_error(&["render", "scene.ron", "--clamp", "-1"], &["clamp", "≥ 0"]);
    expect_usage_error(&["render", "scene.ron", "--clamp", "a,b"], &["'a' is not a number"]);
    // compare clamps its runs, never its reference, and says so.
    let args = ["compare", "scene.ron", "--samplers", "uniform", "--spp", "4", "--reference-spp", "8"];
    crate::split::ok(&[&args[..], &["--clamp", "0.3,0.05", "--out-dir", "cmp"]].concat(), d);
    let report = std::fs::read_to_string(d.join("cmp/report.md")).unwrap();
    assert!(report.contains("clamp 0.3,0.05"), "{report}");
}

#[test]
fn guiding_is_asked_for_anywhere_and_every_output_says_so() {
    let (dir, _) = scene_file(GOOD);
    let d = dir.path();
    let guiding_of = |name: &str| {
        let (_, meta) = myriad::io::exr::read(&d.join(name)).unwrap();
        meta.into_iter().find(|(k, _)| k == "myriad.guiding").map(|(_, v)| v)
    };
    let said = crate::split::ok(&["render", "scene.ron", "--spp", "16", "--guiding", "on", "-o", "on.exr"], d);
    assert!(said.contains("guiding ") && said.contains("regions") && said.contains("path vertices"), "{said}");
    crate::split::ok(&["render", "scene.ron", "--spp", "16", "--guiding", "off", "-o", "off.exr"], d);
    assert_eq!((guiding_of("on.exr").as_deref(), guiding_of("off.exr")), (Some("on"), None));
    // The scene file's switch gives the command line's image.
    let in_file =
        GOOD.replace("film: (resolution: (16, 12)),", "film: (resolution: (16, 12)),\n    render: (guiding: true),");
    std::fs::write(d.join("guided.ron"), &in_file).unwrap();
    crate::split::ok(&["render", "guided.ron", "--spp", "16", "-o", "from-file.exr"], d);
    crate::split::same_pixels(&d.join("from-file.exr"), &d.join("on.exr"));
    // The command line wins over the file.
    crate::split::ok(&["render", "guided.ron", "--spp", "16", "--guiding", "off", "-o", "overridden.exr"], d);
    crate::split::same_pixels(&d.join("overridden.exr"), &d.join("off.exr"));
    expect_usage_error(&["render", "scene.ron", "--guiding", "yes"], &["on or off", "'yes'"]);
    let info = crate::split::ok(&["info", "guided.ron"], d);
    assert!(info.contains("guiding      on") && info.contains("learns until 64 spp"), "{info}");
    // compare guides its runs, never its reference, and says so.
    let args = ["compare", "scene.ron", "--samplers", "tree", "--spp", "4", "--reference-spp", "8"];
    crate::split::ok(&[&args[..], &["--guiding", "on", "--out-dir", "cmp"]].concat(), d);
    let report = std::fs::read_to_string(d.join("cmp/report.md")).unwrap();
    assert!(report.contains("guiding on (") && report.contains("learned in"), "{report}");
}

#[test]
fn compare_on_a_broken_scene_leaves_no_folder() {
    let text = GOOD.replace("lights: [", "lights: [ Point(position: (0, 1.5, 0), intensity: (1e38, 1e38, 1e38)),");
    let (dir, _) = scene_file(&text);
    let out = myriad(&["compare", "scene.ron", "--spp", "1", "--out-dir", "cmp"], dir.path());
    let err = stderr(&out);
    assert!(!out.status.success() && err.contains("light 0") && !err.contains("panicked"), "{err}");
    assert!(!dir.path().join("cmp").exists(), "compare left a folder");
}

#[test]
fn diff_of_a_broken_exr_is_an_error() {
    let (dir, _) = scene_file(GOOD);
    assert!(myriad(&["render", "scene.ron", "-o", "a.exr", "--spp", "1", "--no-png"], dir.path()).status.success());
    let mut bytes = std::fs::read(dir.path().join("a.exr")).unwrap();
    // Zero a byte of the data window: the header then declares a different image size.
    let at = bytes.windows(10).position(|w| w == b"dataWindow").unwrap() + 20;
    bytes[at] = 0xff;
    bytes[at + 1] = 0x7f;
    std::fs::write(dir.path().join("b.exr"), &bytes).unwrap();
    let out = myriad(&["diff", "b.exr", "a.exr"], dir.path());
    let err = stderr(&out);
    assert!(!out.status.success() && err.contains("b.exr") && !err.contains("panicked"), "{err}");
}

/// Starts `myriad render` of the built-in scene at `size` for a very long time in `dir`
/// (which holds an earlier `out.exr`), and returns once it says it is rendering, with a
/// thread collecting the rest of its stderr.
fn start_long_render(dir: &Path, size: &str) -> (std::process::Child, std::thread::JoinHandle<String>) {
    use std::io::BufRead;
    std::fs::write(dir.join("out.exr"), b"the previous render").unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_myriad"))
        .args(["render", "-o", "out.exr", "--spp", "1000000", "--resolution", size])
        .current_dir(dir)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut stderr = std::io::BufReader::new(child.stderr.take().unwrap());
    let mut line = String::new();
    while !line.starts_with("rendering") {
        line.clear();
        assert!(stderr.read_line(&mut line).unwrap() > 0, "myriad ended before rendering");
    }
    let rest = std::thread::spawn(move || {
        let mut text = String::new();
        std::io::Read::read_to_string(&mut stderr, &mut text).unwrap();
        text
    });
    (child, rest)
}

fn signal(child: &std::process::Child, signal: i32) {
    // SAFETY: kill sends a signal to a process we started; no memory is involved.
    assert_eq!(unsafe { libc::kill(child.id() as i32, signal) }, 0);
}

/// The names in `dir`, sorted.
fn names(dir: &Path) -> Vec<String> {
    let mut n: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
    n.sort();
    n
}

#[test]
fn a_first_ctrl_c_finishes_the_pass_and_writes_what_was_rendered() {
    let dir = tempfile::tempdir().unwrap();
    let (child, _) = start_long_render(dir.path(), "64x48");
    std::thread::sleep(std::time::Duration::from_millis(300));
    signal(&child, libc::SIGINT);
    let out = child.wait_with_output().unwrap();
    let summary = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(130), "{summary}");
    assert!(summary.contains("interrupted after") && summary.contains("out.exr"), "{summary}");
    let (_, meta) = myriad::io::exr::read(&dir.path().join("out.exr")).unwrap();
    let spp: u32 = meta.iter().find(|(k, _)| k == "myriad.spp").unwrap().1.parse().unwrap();
    assert!((1..1_000_000).contains(&spp), "{spp} spp");
    assert_eq!(names(dir.path()), ["out.exr", "out.png"], "temporary files left");
}

#[test]
fn a_second_ctrl_c_or_a_sigterm_writes_nothing_and_leaves_no_temporary_file() {
    // Large enough that writing the image takes longer than the 20 ms between the signals.
    for signals in [&[libc::SIGINT, libc::SIGINT][..], &[libc::SIGTERM]] {
        let dir = tempfile::tempdir().unwrap();
        let (child, stderr) = start_long_render(dir.path(), "1280x960");
        for &s in signals {
            signal(&child, s);
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
        let out = child.wait_with_output().unwrap();
        let err = stderr.join().unwrap();
        assert_eq!(out.status.code(), Some(130), "{signals:?}: {err}");
        assert!(err.contains("nothing was written"), "{signals:?}: {err}");
        assert_eq!(std::fs::read(dir.path().join("out.exr")).unwrap(), b"the previous render");
        assert_eq!(names(dir.path()), ["out.exr"], "{signals:?}: files left");
    }
}

#[test]
fn progress_off_a_terminal_is_plain_lines_with_the_time_left() {
    let (dir, _) = scene_file(GOOD);
    let out = myriad(&["render", "scene.ron", "-o", "out.exr", "--spp", "8"], dir.path());
    let err = stderr(&out);
    assert!(out.status.success(), "{err}");
    assert!(err.lines().any(|l| l.contains("100% (") && l.contains("s left")), "no progress line:\n{err}");
    let quiet = myriad(&["render", "scene.ron", "-o", "q.exr", "--spp", "8", "-q"], dir.path());
    assert!(!stderr(&quiet).contains("% ("), "-q shows no progress");
}
