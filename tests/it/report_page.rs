//! The HTML comparison page in a real headless browser (Chromium, driven over the DevTools
//! protocol; CI installs Debian's `chromium` and sets MYRIAD_BROWSER_TESTS=1; elsewhere the
//! test runs when a Chromium is found and says why it is skipped when not): it loads with no
//! console errors, shows the reference at 1:1 as its PNG preview, flips to the next sampler
//! on a key, and the readout under a pixel gives the EXR's values there.

use std::io::{BufRead, BufReader};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use base64::Engine;
use serde_json::{Value, json};
use tungstenite::stream::MaybeTlsStream;
use tungstenite::{Message, WebSocket};

use crate::split::ok;
use myriad::io::png::to_srgb8;

/// A Chromium here, if any; with MYRIAD_BROWSER_TESTS=1 there must be one.
fn chromium() -> Option<PathBuf> {
    let found = ["chromium", "chromium-browser", "google-chrome"].into_iter().find_map(|name| {
        let out = Command::new("sh").args(["-c", &format!("command -v {name}")]).output().ok()?;
        out.status.success().then(|| PathBuf::from(String::from_utf8_lossy(&out.stdout).trim()))
    });
    let required = std::env::var("MYRIAD_BROWSER_TESTS").is_ok_and(|v| v == "1");
    assert!(found.is_some() || !required, "MYRIAD_BROWSER_TESTS=1 but no Chromium: apt-get install chromium");
    if found.is_none() {
        eprintln!("skipped: no Chromium here (apt-get install chromium)");
    }
    found
}

/// A headless Chromium with one page, driven over the DevTools protocol.
struct Browser {
    child: Child,
    socket: WebSocket<MaybeTlsStream<TcpStream>>,
    session: String,
    next_id: u64,
    /// Every event received so far (console messages, exceptions, log entries).
    events: Vec<Value>,
    _profile: tempfile::TempDir,
}

impl Browser {
    fn launch(exe: &Path) -> Self {
        let profile = tempfile::tempdir().unwrap();
        let mut child = Command::new(exe)
            .args(["--headless=new", "--no-sandbox", "--disable-gpu", "--remote-debugging-port=0"])
            .args(["--window-size=1200,900", "--force-device-scale-factor=1", "--hide-scrollbars", "--no-first-run"])
            .arg(format!("--user-data-dir={}", profile.path().display()))
            .arg("about:blank")
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("chromium starts");
        let mut lines = BufReader::new(child.stderr.take().unwrap()).lines();
        let url = loop {
            let line = lines.next().expect("chromium says where DevTools listens").unwrap();
            if let Some(i) = line.find("ws://") {
                break line[i..].trim().to_string();
            }
        };
        std::thread::spawn(move || lines.for_each(drop));
        let (socket, _) = tungstenite::connect(url.as_str()).expect("DevTools connects");
        let mut browser =
            Self { child, socket, session: String::new(), next_id: 0, events: Vec::new(), _profile: profile };
        let target = browser.call("Target.createTarget", json!({ "url": "about:blank" }))["targetId"].clone();
        let session = browser.call("Target.attachToTarget", json!({ "targetId": target, "flatten": true }));
        browser.session = session["sessionId"].as_str().unwrap().to_string();
        for domain in ["Runtime", "Page", "Log"] {
            browser.call(&format!("{domain}.enable"), json!({}));
        }
        browser
    }

    /// Sends a command (to the page once attached) and waits for its answer.
    fn call(&mut self, method: &str, params: Value) -> Value {
        self.next_id += 1;
        let id = self.next_id;
        let mut message = json!({ "id": id, "method": method, "params": params });
        if !self.session.is_empty() {
            message["sessionId"] = json!(self.session);
        }
        self.socket.send(Message::text(message.to_string())).unwrap();
        loop {
            let Message::Text(text) = self.socket.read().expect("DevTools answers") else { continue };
            let v: Value = serde_json::from_str(&text).unwrap();
            if v["id"] == json!(id) {
                assert!(v.get("error").is_none(), "{method}: {v}");
                return v["result"].clone();
            }
            self.events.push(v);
        }
    }

    /// The value of a JavaScript expression (promises awaited).
    fn eval(&mut self, expression: &str) -> Value {
        let r = self
            .call("Runtime.evaluate", json!({ "expression": expression, "returnByValue": true, "awaitPromise": true }));
        assert!(r.get("exceptionDetails").is_none(), "{expression}: {r}");
        r["result"]["value"].clone()
    }

    /// Console errors, uncaught exceptions and error log entries so far.
    fn errors(&self) -> Vec<String> {
        self.events
            .iter()
            .filter(|e| {
                e["method"] == "Runtime.exceptionThrown"
                    || (e["method"] == "Runtime.consoleAPICalled" && e["params"]["type"] == "error")
                    || (e["method"] == "Log.entryAdded" && e["params"]["entry"]["level"] == "error")
            })
            .map(|e| e.to_string())
            .collect()
    }

    /// The page's pixels in a rectangle, as RGB.
    fn screenshot(&mut self, x: f64, y: f64, w: u32, h: u32) -> Vec<u8> {
        let clip = json!({ "x": x, "y": y, "width": w, "height": h, "scale": 1 });
        let shot = self.call("Page.captureScreenshot", json!({ "format": "png", "clip": clip }));
        let png = base64::engine::general_purpose::STANDARD.decode(shot["data"].as_str().unwrap()).unwrap();
        let img = image::load_from_memory(&png).unwrap().to_rgb8();
        assert_eq!((img.width(), img.height()), (w, h), "a screenshot at 1:1");
        img.into_raw()
    }

    fn key(&mut self, key: &str, code: u32) {
        for kind in ["keyDown", "keyUp"] {
            let event = json!({ "type": kind, "key": key, "code": key, "windowsVirtualKeyCode": code, "nativeVirtualKeyCode": code });
            self.call("Input.dispatchKeyEvent", event);
        }
        self.eval("new Promise(r => requestAnimationFrame(() => r(true)))");
    }
}

impl Drop for Browser {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The 8-bit preview of an EXR, as `render` writes it, and its linear pixels.
fn preview(exr: &Path) -> (Vec<u8>, Vec<myriad::math::Rgb>) {
    let (layers, _) = myriad::io::exr::read(exr).unwrap();
    let rgb = layers.rgb().unwrap();
    (to_srgb8(&rgb, 0.0), rgb)
}

/// The page shows `want`: the page carries half floats, so a channel may round to the next
/// 8-bit level where a value sits at a level's edge, never further.
fn shows(got: &[u8], want: &[u8], what: &str) {
    assert_eq!(got.len(), want.len());
    let off: Vec<i32> = got.iter().zip(want).map(|(&a, &b)| a as i32 - b as i32).filter(|d| *d != 0).collect();
    assert!(off.iter().all(|d| d.abs() <= 1), "{what}: a channel is off by more than one level");
    assert!(off.len() * 50 <= got.len(), "{what}: {} of {} channels differ", off.len(), got.len());
}

#[test]
fn the_report_page_shows_the_renders_flips_on_a_key_and_reads_pixel_values() {
    let Some(exe) = chromium() else { return };
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-9x9.ron");
    ok(
        &["compare", scene.to_str().unwrap(), "--samplers", "uniform,tree", "--spp", "4", "--reference-spp", "16"][..]
            .iter()
            .chain(&["--resolution", "48x36", "--max-depth", "3", "--out-dir", "out", "-q"])
            .copied()
            .collect::<Vec<_>>(),
        d,
    );
    let mut browser = Browser::launch(&exe);
    let url = format!("file://{}", d.join("out/report.html").display());
    browser.call("Page.navigate", json!({ "url": url }));
    let start = Instant::now();
    while browser.eval("window.myriadReady === true") != json!(true) {
        assert!(start.elapsed() < Duration::from_secs(20), "the page never got ready: {:?}", browser.errors());
        std::thread::sleep(Duration::from_millis(50));
    }
    assert!(browser.errors().is_empty(), "console errors: {:?}", browser.errors());

    let rect = |b: &mut Browser, id: &str| -> [f64; 4] {
        let r = b.eval(&format!(
            "(() => {{ const r = {id}.getBoundingClientRect(); return [r.x, r.y, r.width, r.height]; }})()"
        ));
        [0, 1, 2, 3].map(|i| r[i].as_f64().unwrap())
    };
    // At first the image fills the view (a small render is not lost in a large canvas),
    // keeping its aspect and centred; 0 shows it at 1:1, f fits it again.
    let [vx, vy, vw, vh] = rect(&mut browser, "view");
    let [fx, fy, fw, fh] = rect(&mut browser, "canvas");
    assert!((fw - vw).abs() < 1.0 || (fh - vh).abs() < 1.0, "fits the view: {fw} × {fh} in {vw} × {vh}");
    assert!(fw <= vw + 0.5 && fh <= vh + 0.5 && (fw / fh - 48.0 / 36.0).abs() < 0.01, "{fw} × {fh}");
    assert!(((fx - vx) - (vx + vw - fx - fw)).abs() < 1.0 && ((fy - vy) - (vy + vh - fy - fh)).abs() < 1.0);
    browser.key("0", 48);
    let [x, y, w, h] = rect(&mut browser, "canvas");
    assert_eq!((w, h), (48.0, 36.0), "1:1 on the 0 key");
    let (reference, _) = preview(&d.join("out/reference.exr"));
    let shot = browser.screenshot(x, y, 48, 36);
    shows(&shot, &reference, "the reference");

    browser.key("ArrowRight", 39);
    let (uniform, linear) = preview(&d.join("out/uniform.exr"));
    let flipped = browser.screenshot(x, y, 48, 36);
    shows(&flipped, &uniform, "after the flip key, uniform");
    assert_ne!(flipped, shot);

    let (px, py) = (20, 10);
    browser.call(
        "Input.dispatchMouseEvent",
        json!({ "type": "mouseMoved", "x": x + px as f64 + 0.5, "y": y + py as f64 + 0.5 }),
    );
    let line = browser.eval("document.querySelector('#readout span[data-name=\"uniform\"]').textContent");
    let values: Vec<f32> = line.as_str().unwrap().split_whitespace().skip(1).map(|v| v.parse().unwrap()).collect();
    let exr = linear[py * 48 + px];
    for c in 0..3 {
        // Half floats (11 significant bits) shown with 4 significant digits.
        assert!(
            (values[c] - exr[c]).abs() <= 2e-3 * exr[c].abs() + 1e-6,
            "channel {c}: page {} vs EXR {}",
            values[c],
            exr[c]
        );
    }
    // The table sorts by a column on a click on its header, and back the other way.
    let column = |b: &mut Browser| -> Vec<f64> {
        let cells =
            b.eval("Array.from(document.querySelectorAll('#metrics tr'), r => r.cells[4].textContent).slice(1)");
        cells
            .as_array()
            .unwrap()
            .iter()
            .map(|c| c.as_str().unwrap().split(' ').next().unwrap().parse().unwrap())
            .collect()
    };
    browser.eval("document.querySelectorAll('#metrics th')[4].click(), true");
    let up = column(&mut browser);
    browser.eval("document.querySelectorAll('#metrics th')[4].click(), true");
    let down = column(&mut browser);
    assert!(up.len() == 2 && up[0] <= up[1] && down[0] >= down[1], "{up:?} {down:?}");
    assert!(browser.eval("document.querySelector('#plot svg') !== null") == json!(true), "the convergence plot");
    browser.key("f", 70);
    assert_eq!(rect(&mut browser, "canvas"), [fx, fy, fw, fh], "f fits the view again");
    // Cells are plain numbers; a flag is a mark of its own, never Markdown.
    let texts = browser.eval("Array.from(document.querySelectorAll('#metrics td'), c => c.textContent).join('|')");
    assert!(!texts.as_str().unwrap().contains("**"), "{texts}");
    assert!(browser.errors().is_empty(), "console errors: {:?}", browser.errors());
}

/// How long a page takes to open, for the README: `MYRIAD_REPORT_PAGE=path/report.html cargo
/// test --release --test it report_page_open_time -- --ignored --nocapture` (navigation to
/// ready: every image inflated and the first one drawn).
#[test]
#[ignore]
fn report_page_open_time() {
    let (Some(exe), Ok(page)) = (chromium(), std::env::var("MYRIAD_REPORT_PAGE")) else { return };
    let page = std::fs::canonicalize(page).unwrap();
    let mut browser = Browser::launch(&exe);
    for run in 0..3 {
        let start = Instant::now();
        browser.call("Page.navigate", json!({ "url": format!("file://{}", page.display()) }));
        while browser.eval("window.myriadReady === true") != json!(true) {
            std::thread::sleep(Duration::from_millis(10));
        }
        let mb = std::fs::metadata(&page).unwrap().len() as f64 / 1e6;
        let times = browser.eval("window.myriadTimes");
        eprintln!(
            "run {run}: {mb:.1} MB ready in {:.2} s {times}, errors {:?}",
            start.elapsed().as_secs_f64(),
            browser.errors()
        );
    }
}
