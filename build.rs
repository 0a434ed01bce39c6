//! Records the git revision in the binary (for the provenance EXR header attribute), and
//! links Intel Embree 3 when the system has it (`cfg(embree)`; Debian: `libembree-dev`),
//! saying how to get it when not: myriad then traces with its own BVH.
use std::path::{Path, PathBuf};

fn main() {
    let rev = std::process::Command::new("git")
        .args(["rev-parse", "--short=12", "HEAD"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_else(|| "unknown".into());
    println!("cargo:rustc-env=MYRIAD_GIT_REVISION={rev}");
    println!("cargo:rerun-if-changed=.git/HEAD");
    println!("cargo:rerun-if-changed=.git/refs");
    embree();
}

/// Where Embree 3's header and library are: `EMBREE_DIR` (its `include/` and `lib/`), else
/// the system's folders. `MYRIAD_NO_EMBREE=1` builds without it.
fn embree() {
    println!("cargo:rustc-check-cfg=cfg(embree)");
    println!("cargo:rerun-if-env-changed=EMBREE_DIR");
    println!("cargo:rerun-if-env-changed=MYRIAD_NO_EMBREE");
    if std::env::var("MYRIAD_NO_EMBREE").is_ok_and(|v| v == "1") {
        return;
    }
    let arch = std::env::var("CARGO_CFG_TARGET_ARCH").unwrap_or_default();
    let multiarch = format!("/usr/lib/{arch}-linux-gnu");
    let mut roots: Vec<(PathBuf, PathBuf)> = Vec::new();
    if let Some(dir) = std::env::var_os("EMBREE_DIR") {
        let dir = PathBuf::from(dir);
        roots.push((dir.join("include"), dir.join("lib")));
    }
    for (inc, lib) in
        [("/usr/include", multiarch.as_str()), ("/usr/include", "/usr/lib"), ("/usr/local/include", "/usr/local/lib")]
    {
        roots.push((PathBuf::from(inc), PathBuf::from(lib)));
    }
    let found = roots.iter().find(|(inc, lib)| {
        inc.join("embree3/rtcore.h").is_file()
            && ["libembree3.so", "libembree3.dylib"].iter().any(|f| Path::new(lib).join(f).exists())
    });
    match found {
        Some((inc, lib)) => {
            println!("cargo:rustc-link-search=native={}", lib.display());
            println!("cargo:rustc-cfg=embree");
            println!("cargo:rerun-if-changed={}", inc.join("embree3/rtcore.h").display());
        }
        None => println!(
            "cargo:warning=building without Embree 3, the faster ray tracer for large scenes: on Debian or \
             Ubuntu, apt-get install libembree-dev (or set EMBREE_DIR), then cargo clean -p myriad and build again"
        ),
    }
}
