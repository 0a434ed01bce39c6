//! `myriad view` under a real X server, Xvfb (CI installs `xvfb`, `xdotool` and `x11-apps`
//! and sets MYRIAD_VIEW_TESTS=1; elsewhere the test runs when those tools are there and says
//! why it is skipped when not): the window opens and renders, a key switches the sampler, the
//! image area of a screenshot equals the PNG preview of a headless render of the same
//! samples, the save key writes that render's EXR, a drag moves the camera and R brings it
//! back, and Esc closes the window cleanly.

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{self, Receiver};
use std::time::{Duration, Instant};

use crate::split::{ok, same_pixels};

/// Whether Xvfb, xdotool and xwd are here; with MYRIAD_VIEW_TESTS=1 they must be.
fn tools() -> bool {
    let found = |tool: &str| {
        Command::new("sh").args(["-c", &format!("command -v {tool}")]).output().is_ok_and(|o| o.status.success())
    };
    let missing: Vec<&str> = ["Xvfb", "xdotool", "xwd"].into_iter().filter(|t| !found(t)).collect();
    let required = std::env::var("MYRIAD_VIEW_TESTS").is_ok_and(|v| v == "1");
    assert!(
        missing.is_empty() || !required,
        "MYRIAD_VIEW_TESTS=1 but {missing:?} missing: apt-get install xvfb xdotool x11-apps"
    );
    if !missing.is_empty() {
        eprintln!("skipped: {missing:?} not installed (apt-get install xvfb xdotool x11-apps)");
    }
    missing.is_empty()
}

/// An X server of our own, stopped when dropped.
struct Xvfb {
    server: Child,
    display: String,
}

impl Xvfb {
    fn start() -> Self {
        let n = (100..400)
            .find(|n| {
                !Path::new(&format!("/tmp/.X11-unix/X{n}")).exists() && !Path::new(&format!("/tmp/.X{n}-lock")).exists()
            })
            .expect("a free display number");
        let display = format!(":{n}");
        let server = Command::new("Xvfb")
            .args([&display, "-screen", "0", "640x480x24", "-nolisten", "tcp"])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("Xvfb starts");
        let start = Instant::now();
        while !Path::new(&format!("/tmp/.X11-unix/X{n}")).exists() {
            assert!(start.elapsed() < Duration::from_secs(10), "Xvfb {display} did not come up");
            std::thread::sleep(Duration::from_millis(50));
        }
        Self { server, display }
    }

    fn run(&self, program: &str, args: &[&str]) -> Vec<u8> {
        let out = Command::new(program).args(args).env("DISPLAY", &self.display).output().expect("the X tool runs");
        assert!(out.status.success(), "{program} {args:?}: {}", String::from_utf8_lossy(&out.stderr));
        out.stdout
    }

    /// The window's id, once it is there.
    fn window(&self, name: &str) -> String {
        let start = Instant::now();
        loop {
            let out = Command::new("xdotool")
                .args(["search", "--name", name])
                .env("DISPLAY", &self.display)
                .output()
                .unwrap();
            if let Some(id) = String::from_utf8_lossy(&out.stdout).lines().next() {
                return id.to_string();
            }
            assert!(start.elapsed() < Duration::from_secs(20), "no window named {name}");
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    /// The window's pixels as (width, height, RGB bytes), from an XWD dump.
    fn screenshot(&self, window: &str) -> (usize, usize, Vec<u8>) {
        parse_xwd(&self.run("xwd", &["-id", window, "-silent"]))
    }
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.server.kill();
        let _ = self.server.wait();
    }
}

/// An XWD file (32-bit TrueColor ZPixmap, as Xvfb at depth 24 writes) → width, height, RGB.
fn parse_xwd(d: &[u8]) -> (usize, usize, Vec<u8>) {
    let h = |i: usize| u32::from_be_bytes(d[4 * i..4 * i + 4].try_into().unwrap()) as usize;
    let (header, width, height, lsb_first, bpp, stride, ncolors) = (h(0), h(4), h(5), h(7) == 0, h(11), h(12), h(19));
    assert_eq!((bpp, h(14), h(15), h(16)), (32, 0xff0000, 0xff00, 0xff), "a 32-bit 0RGB dump");
    let data = &d[header + 12 * ncolors..];
    let mut rgb = Vec::with_capacity(width * height * 3);
    for y in 0..height {
        for x in 0..width {
            let p: [u8; 4] = data[y * stride + 4 * x..][..4].try_into().unwrap();
            let v = if lsb_first { u32::from_le_bytes(p) } else { u32::from_be_bytes(p) };
            rgb.extend([(v >> 16) as u8, (v >> 8) as u8, v as u8]);
        }
    }
    (width, height, rgb)
}

/// The lines the viewer writes on stderr, as they come.
fn lines_of(child: &mut Child) -> Receiver<String> {
    let (send, lines) = mpsc::channel();
    let stderr = BufReader::new(child.stderr.take().unwrap());
    std::thread::spawn(move || {
        for line in stderr.lines().map_while(Result::ok) {
            if send.send(line).is_err() {
                return;
            }
        }
    });
    lines
}

fn wait_for(lines: &Receiver<String>, needle: &str) -> String {
    let deadline = Instant::now() + Duration::from_secs(60);
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        match lines.recv_timeout(left) {
            Ok(line) if line.contains(needle) => return line,
            Ok(_) => {}
            Err(e) => panic!("no line with '{needle}' from the viewer ({e})"),
        }
    }
}

/// Takes screenshots until the image area (the top `w × h`) equals `png` (the window may not
/// have been redrawn yet), for a few seconds.
fn shows(x: &Xvfb, window: &str, png: &Path) -> Vec<u8> {
    let want = image::open(png).unwrap().to_rgb8();
    let (w, h) = (want.width() as usize, want.height() as usize);
    let start = Instant::now();
    loop {
        let (sw, sh, shot) = x.screenshot(window);
        assert!(sw == w && sh > h, "window {sw} × {sh} for a {w} × {h} image and its status bar");
        let area: Vec<u8> = shot[..w * h * 3].to_vec();
        if area == want.as_raw().as_slice() {
            return area;
        }
        let differ = area.iter().zip(want.as_raw()).filter(|(a, b)| a != b).count();
        assert!(
            start.elapsed() < Duration::from_secs(5),
            "{differ} of {} bytes differ from {}",
            w * h * 3,
            png.display()
        );
        std::thread::sleep(Duration::from_millis(100));
    }
}

#[test]
fn the_window_switches_sampler_on_a_key_and_shows_what_a_headless_render_makes() {
    if !tools() {
        return;
    }
    let x = Xvfb::start();
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let settings = ["--resolution", "48x36", "--spp", "4", "--seed", "5", "--max-depth", "4"];
    for sampler in ["tree", "uniform"] {
        ok(&[&["render", "-q", "--sampler", sampler, "-o", &format!("{sampler}.exr")][..], &settings].concat(), d);
    }
    let mut viewer = Command::new(env!("CARGO_BIN_EXE_myriad"))
        .args([&["view", "--sampler", "tree", "--out-dir", "saved"][..], &settings].concat())
        .current_dir(d)
        .env("DISPLAY", &x.display)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let lines = lines_of(&mut viewer);
    wait_for(&lines, "showing tree at 4 spp (done)");
    let window = x.window("myriad view");
    let tree = shows(&x, &window, &d.join("tree.png"));

    x.run("xdotool", &["key", "--window", &window, "2"]);
    wait_for(&lines, "showing uniform at 4 spp (done)");
    let uniform = shows(&x, &window, &d.join("uniform.png"));
    assert_ne!(tree, uniform, "the samplers' images differ at 4 spp");

    x.run("xdotool", &["key", "--window", &window, "s"]);
    wait_for(&lines, "saved");
    same_pixels(&d.join("saved/view-uniform-4spp.exr"), &d.join("uniform.exr"));

    // A drag orbits the camera (a new view, another image); R brings the scene's camera back.
    x.run("xdotool", &["mousemove", "--window", &window, "10", "10", "mousedown", "1"]);
    std::thread::sleep(Duration::from_millis(100));
    x.run("xdotool", &["mousemove", "--window", &window, "30", "14"]);
    std::thread::sleep(Duration::from_millis(100));
    x.run("xdotool", &["mouseup", "1"]);
    wait_for(&lines, "showing uniform at 4 spp (done)");
    let (_, _, orbited) = x.screenshot(&window);
    assert_ne!(orbited[..uniform.len()], uniform[..], "the drag moved the camera");
    x.run("xdotool", &["key", "--window", &window, "r"]);
    wait_for(&lines, "showing uniform at 4 spp (done)");
    shows(&x, &window, &d.join("uniform.png"));

    x.run("xdotool", &["key", "--window", &window, "Escape"]);
    let start = Instant::now();
    let status = loop {
        if let Some(s) = viewer.try_wait().unwrap() {
            break s;
        }
        assert!(start.elapsed() < Duration::from_secs(10), "the viewer did not close on Esc");
        std::thread::sleep(Duration::from_millis(50));
    };
    let summary = std::io::read_to_string(viewer.stdout.take().unwrap()).unwrap();
    assert!(status.success(), "{status}: {summary}");
    assert!(summary.contains("last image uniform at 4 spp"), "{summary}");
    // tree, uniform, the drag (one move or more), the reset.
    let views: u32 = summary.split(" view(s)").next().and_then(|s| s.rsplit(' ').next()).unwrap().parse().unwrap();
    assert!(views >= 4, "{summary}");
    let left: Vec<_> = std::fs::read_dir(d.join("saved")).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(left.len(), 1, "only the saved image, no temporary file: {left:?}");
}

#[test]
fn without_a_display_the_viewer_says_what_to_do() {
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_myriad"))
        .args(["view", "--resolution", "8x6"])
        .current_dir(dir.path())
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && !err.contains("panicked"), "{err}");
    assert!(err.contains("needs a display") && err.contains("myriad render"), "{err}");
}
