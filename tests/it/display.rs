//! `render --display`: a fake tev server on a local port reads the packets as tev would
//! (CreateImage, then UpdateImage V3 after every pass) and the last image it got is the EXR
//! the render wrote; with nothing listening, a warning and the render goes on. `compare`
//! streams its runs seed by seed, every sampler in turn.

use std::io::Read;
use std::net::TcpListener;
use std::path::Path;

use myriad::io::exr;

use crate::split::myriad;

/// What the fake tev saw: the image's name and the channel names it was created with, and
/// the channels of the last update, by name.
#[derive(Default)]
struct Seen {
    name: String,
    created: Vec<String>,
    updates: usize,
    last: Vec<(String, Vec<f32>)>,
}

/// Reads tev packets from `bytes` (u32 length including itself, u8 type, fields).
fn parse(bytes: &[u8]) -> Seen {
    let mut seen = Seen::default();
    let mut at = 0;
    while at + 4 <= bytes.len() {
        let len = u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
        let mut p = Packet { b: &bytes[at + 5..at + len], i: 0 };
        match bytes[at + 4] {
            4 => {
                let (_focus, name, _w, _h) = (p.u8(), p.string(), p.u32(), p.u32());
                seen.name = name;
                let n = p.u32();
                seen.created = (0..n).map(|_| p.string()).collect();
            }
            6 => {
                let (_focus, _name) = (p.u8(), p.string());
                let n = p.u32() as usize;
                let names: Vec<String> = (0..n).map(|_| p.string()).collect();
                let (_x, _y, w, h) = (p.u32(), p.u32(), p.u32(), p.u32());
                let offsets: Vec<u64> = (0..n).map(|_| p.u64()).collect();
                let strides: Vec<u64> = (0..n).map(|_| p.u64()).collect();
                let data: Vec<f32> = (0..(p.b.len() - p.i) / 4).map(|_| p.f32()).collect();
                let pixels = (w * h) as u64;
                seen.last = names
                    .into_iter()
                    .enumerate()
                    .map(|(k, name)| {
                        (name, (0..pixels).map(|j| data[(offsets[k] + j * strides[k]) as usize]).collect())
                    })
                    .collect();
                seen.updates += 1;
            }
            t => panic!("unexpected packet type {t}"),
        }
        at += len;
    }
    assert_eq!(at, bytes.len(), "a packet was cut short");
    seen
}

struct Packet<'a> {
    b: &'a [u8],
    i: usize,
}

impl Packet<'_> {
    fn take(&mut self, n: usize) -> &[u8] {
        self.i += n;
        &self.b[self.i - n..self.i]
    }
    fn u8(&mut self) -> u8 {
        self.take(1)[0]
    }
    fn u32(&mut self) -> u32 {
        u32::from_le_bytes(self.take(4).try_into().unwrap())
    }
    fn u64(&mut self) -> u64 {
        u64::from_le_bytes(self.take(8).try_into().unwrap())
    }
    fn f32(&mut self) -> f32 {
        f32::from_le_bytes(self.take(4).try_into().unwrap())
    }
    fn string(&mut self) -> String {
        let end = self.b[self.i..].iter().position(|&c| c == 0).unwrap();
        let s = String::from_utf8(self.b[self.i..self.i + end].to_vec()).unwrap();
        self.i += end + 1;
        s
    }
}

/// A fake tev on a free local port that reads `connections` connections one after another;
/// the port, and what it saw on each.
fn fake_tev(connections: usize) -> (u16, std::thread::JoinHandle<Vec<Seen>>) {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let port = listener.local_addr().unwrap().port();
    let server = std::thread::spawn(move || {
        (0..connections)
            .map(|_| {
                let (mut socket, _) = listener.accept().unwrap();
                let mut bytes = Vec::new();
                socket.read_to_end(&mut bytes).unwrap();
                parse(&bytes)
            })
            .collect()
    });
    (port, server)
}

#[test]
fn the_last_image_tev_gets_is_the_exr_the_render_wrote() {
    let (port, server) = fake_tev(1);
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let out = myriad(
        &[
            "render",
            "--resolution",
            "16x12",
            "--spp",
            "8",
            "--aov",
            "albedo",
            "-o",
            "out.exr",
            "--display",
            &port.to_string(),
        ],
        d,
    );
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let seen = server.join().unwrap().pop().unwrap();
    assert_eq!(seen.created, ["R", "G", "B", "albedo.R", "albedo.G", "albedo.B"]);
    assert!(seen.updates >= 4, "one update a pass (1, 1, 2, 4 spp): {}", seen.updates);
    let (layers, _) = exr::read(&d.join("out.exr")).unwrap();
    for channel in &layers.channels {
        let (_, sent) = seen.last.iter().find(|(n, _)| *n == channel.name).unwrap();
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(sent), bits(&channel.data), "channel {}", channel.name);
    }
}

#[test]
fn without_tev_listening_the_render_warns_and_goes_on() {
    // A port nothing listens on: bind one, then free it.
    let port = TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
    let dir = tempfile::tempdir().unwrap();
    let out = myriad(
        &["render", "--resolution", "8x6", "--spp", "2", "-o", "out.exr", "--display", &format!("127.0.0.1:{port}")],
        dir.path(),
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("no tev display") && err.contains(&port.to_string()), "{err}");
    assert!(Path::new(&dir.path().join("out.exr")).exists());
}

#[test]
fn compare_runs_seed_by_seed_every_sampler_in_turn() {
    // Sampler after sampler, a machine that slowed down for a minute would favour whichever
    // ran outside it at equal time.
    let (port, server) = fake_tev(4);
    let dir = tempfile::tempdir().unwrap();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-5x5.ron");
    let args = ["compare", "--samplers", "uniform,power", "--seeds", "2", "--spp", "2", "--reference-spp", "4"];
    let port = port.to_string();
    let more = [scene.to_str().unwrap(), "--resolution", "16x12", "--display", &port, "-q"];
    let out = myriad(&[&args[..], &more].concat(), dir.path());
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let names: Vec<String> = server.join().unwrap().into_iter().map(|s| s.name).collect();
    assert_eq!(names, ["uniform seed 1", "power seed 1", "uniform seed 2", "power seed 2"]);
}
