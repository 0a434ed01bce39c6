//! Renders split into sample ranges (`render --samples A..B`) and `merge`, as a cluster job
//! runs them: the merged image is bit-identical to one render of the union, whatever the
//! split and for every sampler (the learning one too); parts that do not belong together,
//! overlaps and gaps are clear errors naming the part, and nothing is written then.

use std::path::Path;
use std::process::{Command, Output};

use myriad::io::exr;

pub fn myriad(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_myriad")).args(args).current_dir(dir).output().expect("myriad runs")
}

/// What a run printed, standard output then standard error.
pub fn text(out: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr))
}

pub fn ok(args: &[&str], dir: &Path) -> String {
    let out = myriad(args, dir);
    let text = text(&out);
    assert!(out.status.success(), "{args:?}: {text}");
    text
}

fn fails(args: &[&str], dir: &Path, needles: &[&str]) {
    let out = myriad(args, dir);
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!out.status.success(), "{args:?} succeeded");
    assert!(!err.contains("panicked"), "{err}");
    for n in needles {
        assert!(err.contains(n), "{args:?}: error lacks '{n}':\n{err}");
    }
}

/// Every channel of two EXR files, bit for bit.
pub fn same_pixels(a: &Path, b: &Path) {
    let (la, _) = exr::read(a).unwrap();
    let (lb, _) = exr::read(b).unwrap();
    assert_eq!(la.channels.len(), lb.channels.len());
    for (ca, cb) in la.channels.iter().zip(&lb.channels) {
        assert_eq!(ca.name, cb.name);
        let bits = |c: &myriad::image::Channel| c.data.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert!(bits(ca) == bits(cb), "channel {} differs between {} and {}", ca.name, a.display(), b.display());
    }
}

#[test]
fn parts_merge_to_the_one_machine_image_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/offices.ron");
    let scene = scene.to_str().unwrap();
    let common = ["--resolution", "24x18", "--max-depth", "4", "--aov", "albedo,depth,variance"];
    // Path guiding learns between passes too, and must split as `learned` does.
    for (sampler, guiding) in [("tree", "off"), ("learned", "off"), ("tree", "on")] {
        let common = [&common[..], &["--guiding", guiding]].concat();
        let full = format!("{sampler}-{guiding}-full.exr");
        ok(&[&["render", scene, "--spp", "20", "--sampler", sampler, "-o", &full][..], &common].concat(), d);
        // Ranges cut across the learning boundaries (1, 2, 4, 8, 16), given in any order.
        let ranges = ["13..20", "0..3", "3..13"];
        let mut parts = Vec::new();
        for r in ranges {
            let part = format!("{sampler}-{guiding}-{}.part", r.replace("..", "-"));
            let said =
                ok(&[&["render", scene, "--samples", r, "--sampler", sampler, "-o", &part][..], &common].concat(), d);
            assert!(said.contains(&part), "{said}");
            parts.push(part);
        }
        let merged = format!("{sampler}-{guiding}-merged.exr");
        let said =
            ok(&[&["merge"][..], &parts.iter().map(String::as_str).collect::<Vec<_>>(), &["-o", &merged]].concat(), d);
        assert!(said.contains("3 parts") && said.contains("20 spp"), "{said}");
        same_pixels(&d.join(&merged), &d.join(&full));
    }
}

#[test]
fn parts_that_do_not_belong_together_are_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let render = |range: &str, extra: &[&str], out: &str| {
        ok(&[&["render", "--resolution", "8x6", "--samples", range, "-o", out][..], extra].concat(), d);
    };
    render("0..2", &[], "a.part");
    render("2..4", &[], "b.part");
    render("2..4", &["--seed", "9"], "seed.part");
    render("1..3", &[], "overlap.part");
    render("5..6", &[], "late.part");
    render("2..4", &["--clamp", "3"], "clamp.part");
    render("2..4", &["--guiding", "on"], "guided.part");
    render("2..4", &["--caustics", "off"], "unsolved.part");
    fails(&["merge", "a.part", "seed.part", "-o", "x.exr"], d, &["seed.part", "does not belong", "seed 9"]);
    fails(&["merge", "a.part", "clamp.part", "-o", "x.exr"], d, &["clamp.part", "does not belong", "clamp 0,3"]);
    fails(&["merge", "a.part", "guided.part", "-o", "x.exr"], d, &["guided.part", "does not belong", "guiding on"]);
    fails(&["merge", "a.part", "unsolved.part", "-o", "x.exr"], d, &["unsolved.part", "caustics off"]);
    fails(&["merge", "a.part", "overlap.part", "-o", "x.exr"], d, &["overlap.part", "1..3", "overlap"]);
    fails(&["merge", "a.part", "b.part", "late.part", "-o", "x.exr"], d, &["4..5", "--allow-gaps"]);
    std::fs::write(d.join("cut.part"), &std::fs::read(d.join("a.part")).unwrap()[..200]).unwrap();
    fails(&["merge", "cut.part", "-o", "x.exr"], d, &["cut.part"]);
    fails(&["render", "--samples", "3..3", "-o", "x.part"], d, &["3..3"]);
    assert!(!d.join("x.exr").exists() && !d.join("x.part").exists(), "nothing written on error");
    // With --allow-gaps the gap is merged around and reported.
    let said = ok(&["merge", "a.part", "b.part", "late.part", "-o", "gap.exr", "--allow-gaps"], d);
    assert!(said.contains("4..5") && said.contains("5 spp"), "{said}");
}
