//! The documentation stays true: every relative link and image in README.md and docs/*.md
//! resolves to a file in the repository, the README's two commands are the ones `.ci/run`
//! runs, and docs/cli.md holds each command's own `--help`, word for word
//! (`MYRIAD_BLESS=1 cargo test --release --test it docs` rewrites its help blocks).

use std::path::{Path, PathBuf};

use crate::split::ok;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// README.md and every page in docs/.
fn pages() -> Vec<PathBuf> {
    let mut pages = vec![root().join("README.md")];
    let mut docs: Vec<PathBuf> = std::fs::read_dir(root().join("docs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    docs.sort();
    pages.extend(docs);
    pages
}

/// The targets of Markdown links and images (`[text](target)`, `![alt](target)`) in `text`.
fn link_targets(text: &str) -> Vec<String> {
    let mut targets = Vec::new();
    let mut rest = text;
    while let Some(i) = rest.find("](") {
        let after = &rest[i + 2..];
        let end = after.find(')').unwrap_or(after.len());
        let target = after[..end].split_whitespace().next().unwrap_or("").to_string();
        targets.push(target);
        rest = &after[end..];
    }
    targets
}

#[test]
fn every_relative_link_and_image_resolves_to_a_file_in_the_repository() {
    let mut broken = Vec::new();
    for page in pages() {
        let text = std::fs::read_to_string(&page).unwrap();
        for target in link_targets(&text) {
            let external = ["http://", "https://", "mailto:"].iter().any(|s| target.starts_with(s));
            if external || target.starts_with('#') || target.is_empty() {
                continue;
            }
            let path = target.split('#').next().unwrap();
            let file = page.parent().unwrap().join(path);
            let inside = file.canonicalize().is_ok_and(|f| f.starts_with(root().canonicalize().unwrap()));
            if !inside {
                broken.push(format!("{}: {target}", page.strip_prefix(root()).unwrap().display()));
            }
        }
    }
    assert!(broken.is_empty(), "links to nothing in the repository:\n{}", broken.join("\n"));
}

#[test]
fn the_readme_quick_start_commands_are_the_ones_ci_runs() {
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    let quick = readme.split("## Quick start").nth(1).expect("a Quick start section");
    let quick = quick.split("\n## ").next().unwrap();
    let commands: Vec<&str> =
        quick.split("```sh\n").skip(1).map(|block| block.split("```").next().unwrap().trim()).collect();
    assert_eq!(commands.len(), 2, "two commands, one block each: {commands:?}");
    assert!(commands[0].starts_with("cargo run --release -- render") && commands[1] == "cargo test --release");
    let ci = std::fs::read_to_string(root().join(".ci/run")).unwrap();
    for c in commands {
        assert!(ci.lines().any(|l| l.trim() == c), ".ci/run does not run the README's `{c}`");
    }
}

/// The commands docs/cli.md documents, `myriad` itself first.
const COMMANDS: [&str; 8] = ["", "render", "info", "compare", "diff", "merge", "slurm", "view"];

/// The marker lines around a command's help block in docs/cli.md.
fn markers(command: &str) -> (String, String) {
    let name = if command.is_empty() { "myriad".to_string() } else { format!("myriad {command}") };
    (format!("<!-- help: {name} -->\n```text\n"), format!("```\n<!-- /help: {name} -->"))
}

#[test]
fn the_cli_reference_holds_every_commands_own_help() {
    let path = root().join("docs/cli.md");
    let mut doc = std::fs::read_to_string(&path).unwrap();
    let bless = std::env::var("MYRIAD_BLESS").is_ok_and(|v| v == "1");
    let mut stale = Vec::new();
    for command in COMMANDS {
        let args: Vec<&str> = [command, "--help"].into_iter().filter(|a| !a.is_empty()).collect();
        let help = ok(&args, Path::new("."));
        let (begin, end) = markers(command);
        let (Some(a), Some(b)) = (doc.find(&begin), doc.find(&end)) else {
            stale.push(format!("{begin:?} … {end:?} missing"));
            continue;
        };
        let current = &doc[a + begin.len()..b];
        if current.trim_end() != help.trim_end() {
            stale.push(format!("`myriad {command} --help`"));
            doc.replace_range(a + begin.len()..b, &format!("{}\n", help.trim_end()));
        }
    }
    if bless {
        std::fs::write(&path, &doc).unwrap();
        return;
    }
    assert!(
        stale.is_empty(),
        "docs/cli.md is not what the commands print for {}; run MYRIAD_BLESS=1 cargo test --release --test it docs",
        stale.join(", ")
    );
}
