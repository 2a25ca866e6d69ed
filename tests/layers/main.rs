//! The layers are real, across the workspace's crates and inside them:
//!
//! - every `crate::MODULE` a source file names belongs to a layer below the file's own (or to
//!   its own module), so the dependency graph has no cycles and a reader can learn the code
//!   bottom-up from `src/lib.rs`;
//! - the core (this crate) depends on none of the service, the command line, the wire schema,
//!   iceoryx2, clap, the renderers or the monitor's Foxglove and MCAP crates, the service not on
//!   the command line or the monitor, and the monitor not on the command line, in their
//!   `Cargo.toml` and in their sources;
//! - no import cycle of any length between the files of a crate (`cycles`).
//!
//! The layers, with what each module owns, are described in one place,
//! `docs/architecture.md`; [`LAYERS`] below is their machine-readable form.
//!
//! Modules of one rank do not use each other, with the exceptions in [`SIBLING_EDGES`].

mod cycles;

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// (module, rank): every top-level module of the core, then the service crate, the monitor
/// crate and the two modules of the command-line crate.
const LAYERS: &[(&str, u32)] = &[
    ("input_file", 0),
    ("memory_budget", 0),
    ("output_file", 0),
    ("alloc_count", 0),
    ("status", 0),
    ("simd", 0),
    ("rng", 0),
    ("eig3", 0),
    ("identify", 0),
    ("scene", 1),
    ("stats", 1),
    ("measured", 1),
    ("kinematics", 2),
    ("caspr", 2),
    ("elastic_catenary", 2),
    ("trajectory", 3),
    ("tension", 3),
    ("cable", 3),
    ("modal", 4),
    ("estimator", 5),
    ("study", 6),
    ("prelude", 7),
    ("calibration", 6),
    ("service", 7),
    ("monitor", 8),
    ("report", 8),
    ("cli", 9),
];

/// Same-rank uses that are allowed, with why.
const SIBLING_EDGES: &[(&str, &str, &str)] = &[(
    "output_file",
    "input_file",
    "test_files", // the hostile-file helpers, shared by both modules' unit tests
)];

/// The workspace's crates above the core: (directory, how its files are ranked). The
/// service's files all belong to `service`, the monitor's to `monitor`; the command line's to
/// their first directory (`report` or `cli`; `lib.rs` and `main.rs` to `cli`).
const UPPER_CRATES: &[(&str, Option<&str>)] = &[
    ("service/src", Some("service")),
    ("monitor/src", Some("monitor")),
    ("cli/src", None),
];

/// What each crate must not depend on (its `Cargo.toml` `[dependencies]`) nor name in its
/// sources (as `name::`).
const FORBIDDEN: &[(&str, &[&str])] = &[
    (
        "",
        &[
            "cablevib-ipc",
            "cablevib-service",
            "cablevib-cli",
            "cablevib-monitor",
            "iceoryx2",
            "foxglove",
            "mcap",
            "clap",
            "clap_complete",
            "clap_mangen",
            "resvg",
            "svg2pdf",
            "tracing-subscriber",
        ],
    ),
    (
        "service",
        &[
            "cablevib-cli",
            "cablevib-monitor",
            "foxglove",
            "mcap",
            // Option parsing is the command line's: the service's errors name parameters.
            "clap",
            "clap_complete",
            "clap_mangen",
        ],
    ),
    ("monitor", &["cablevib-cli", "clap"]),
    (
        "python",
        &[
            "cablevib-ipc",
            "cablevib-service",
            "cablevib-cli",
            "cablevib-monitor",
            "iceoryx2",
            "foxglove",
            "mcap",
            "clap",
        ],
    ),
];

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn rank(module: &str) -> Option<u32> {
    LAYERS.iter().find(|(m, _)| *m == module).map(|&(_, r)| r)
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("read src") {
        let p = entry.expect("dir entry").path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
}

/// The top-level module a file under src/ belongs to (`None` for lib.rs and main.rs).
fn module_of(src: &Path, file: &Path) -> Option<String> {
    let rel = file.strip_prefix(src).ok()?;
    let first = rel.components().next()?.as_os_str().to_str()?;
    let name = first.strip_suffix(".rs").unwrap_or(first);
    (name != "lib" && name != "main").then(|| name.to_string())
}

fn ident(s: &str) -> String {
    s.chars()
        .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
        .collect()
}

/// Every `crate::a::b` path in `text`, as (a, b) (b empty when absent), comments included:
/// a doc link to a higher layer is a dependency of the reader, too.
fn crate_paths(text: &str) -> BTreeSet<(String, String)> {
    let mut out = BTreeSet::new();
    for (i, _) in text.match_indices("crate::") {
        let before = text[..i].chars().next_back();
        if before.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_' || c == '$') {
            continue; // e.g. `cablevib_crate::`, `$crate::`
        }
        let rest = &text[i + "crate::".len()..];
        let a = ident(rest);
        if rest[a.len()..].starts_with('!') {
            continue; // a macro exported at the crate root (`crate::outln!`), not a module
        }
        let b = rest[a.len()..]
            .strip_prefix("::")
            .map(ident)
            .unwrap_or_default();
        out.insert((a, b));
    }
    out
}

/// The names a path prefix reaches in `text`: for each `prefix` not preceded by an
/// identifier character, the identifier after it, or every first identifier of a
/// `prefix{a, b::c, …}` group.
fn names_after(text: &str, prefix: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    for (i, _) in text.match_indices(prefix) {
        let before = text[..i].chars().next_back();
        if before.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_' || c == ':') {
            continue;
        }
        let rest = &text[i + prefix.len()..];
        if let Some(group) = rest.strip_prefix('{') {
            let mut depth = 0;
            let mut start = true;
            for (j, c) in group.char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' if depth == 0 => break,
                    '}' => depth -= 1,
                    ',' if depth == 0 => start = true,
                    c if start && !c.is_whitespace() => {
                        out.insert(ident(&group[j..]));
                        start = false;
                    }
                    _ => {}
                }
            }
        } else {
            out.insert(ident(rest));
        }
    }
    out
}

/// Checks every file of one crate's `src`: `rank_of(file)` gives the file's module.
fn layer_violations(
    src: &Path,
    module_of: &dyn Fn(&Path) -> Option<String>,
) -> (Vec<String>, usize) {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    files.sort();
    let mut violations = Vec::new();
    let mut checked = 0;
    for file in &files {
        let Some(module) = module_of(file) else {
            continue;
        };
        let own = rank(&module)
            .unwrap_or_else(|| panic!("{}: module `{module}` has no layer", file.display()));
        let text = std::fs::read_to_string(file).expect("read source");
        for (dep, sub) in crate_paths(&text) {
            checked += 1;
            if dep == module || dep.is_empty() {
                continue;
            }
            let Some(r) = rank(&dep) else {
                // A module of the file's own crate that is not a layer (the service's own
                // modules: `crate::ports`, …; the monitor's) is the file's own module.
                if module == "service" || module == "monitor" {
                    continue;
                }
                violations.push(format!("{}: unknown module crate::{dep}", file.display()));
                continue;
            };
            let sibling_ok = SIBLING_EDGES
                .iter()
                .any(|&(from, to, s)| from == module && to == dep && s == sub);
            if r > own || (r == own && !sibling_ok) {
                violations.push(format!(
                    "{}: `{module}` (layer {own}) uses crate::{dep}::{sub} (layer {r})",
                    file.display()
                ));
            }
        }
    }
    (violations, checked)
}

#[test]
fn every_module_uses_only_the_layers_below_it() {
    let src = root().join("src");
    let (mut violations, mut checked) = layer_violations(&src, &|f| module_of(&src, f));
    for &(dir, whole) in UPPER_CRATES {
        let src = root().join(dir);
        let (v, c) = layer_violations(&src, &|f| match whole {
            Some(m) => Some(m.to_string()),
            None => Some(module_of(&src, f).unwrap_or_else(|| "cli".to_string())),
        });
        violations.extend(v);
        checked += c;
    }
    assert!(
        checked > 50,
        "only {checked} crate paths found: is the scan broken?"
    );
    assert!(
        violations.is_empty(),
        "layer violations:\n{}",
        violations.join("\n")
    );
}

/// The names of a manifest's `[dependencies]` table (not dev- or build-dependencies).
fn dependencies(manifest: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let mut inside = false;
    for line in manifest.lines() {
        let l = line.trim();
        if l.starts_with('[') {
            inside = l == "[dependencies]";
            continue;
        }
        if inside && !l.is_empty() && !l.starts_with('#') {
            if let Some((name, _)) = l.split_once('=') {
                out.insert(name.trim().to_string());
            }
        }
    }
    out
}

#[test]
fn the_core_builds_nothing_of_the_crates_above_it() {
    let mut violations = Vec::new();
    for &(dir, forbidden) in FORBIDDEN {
        let crate_dir = root().join(dir);
        let manifest =
            std::fs::read_to_string(crate_dir.join("Cargo.toml")).expect("read Cargo.toml");
        let deps = dependencies(&manifest);
        assert!(
            deps.contains("nalgebra"),
            "{dir}/Cargo.toml: no dependencies found: is the scan broken?"
        );
        let mut files = Vec::new();
        rust_files(&crate_dir.join("src"), &mut files);
        for name in forbidden {
            if deps.contains(*name) {
                violations.push(format!("{dir}/Cargo.toml depends on {name}"));
            }
            let path = format!("{}::", name.replace('-', "_"));
            for f in &files {
                let text = std::fs::read_to_string(f).expect("read source");
                if !names_after(&text, &path).is_empty() {
                    violations.push(format!("{} names {path}", f.display()));
                }
            }
        }
    }
    assert!(
        violations.is_empty(),
        "dependencies on upper crates:\n{}",
        violations.join("\n")
    );
}

#[test]
fn the_scan_finds_paths_and_layers_reject_upward_uses() {
    let p = crate_paths(
        "use crate::modal::{A, B};\n/// [`crate::cli`]\nmy_crate::x crate::service::stats::percentile $crate::Y",
    );
    let expected: BTreeSet<(String, String)> = [("modal", ""), ("cli", ""), ("service", "stats")]
        .iter()
        .map(|&(a, b)| (a.to_string(), b.to_string()))
        .collect();
    assert_eq!(p, expected);
    assert!(rank("scene") < rank("estimator") && rank("estimator") < rank("service"));
    assert!(rank("service") < rank("report") && rank("report") < rank("cli"));
    assert_eq!(rank("no_such_module"), None);
    let n = names_after(
        "use super::{a, b::{c, d}, e};\nsuper::f::g(); x::super::h",
        "super::",
    );
    let want: BTreeSet<String> = ["a", "b", "e", "f"].iter().map(|s| s.to_string()).collect();
    assert_eq!(n, want);
    let deps = dependencies("[package]\nname = \"x\"\n[dependencies]\na = \"1\"\n# c\nb = { path = \"..\" }\n[dev-dependencies]\nc = \"1\"\n");
    let want: BTreeSet<String> = ["a", "b"].iter().map(|s| s.to_string()).collect();
    assert_eq!(deps, want);
}
