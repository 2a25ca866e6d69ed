//! The library's layers are real: every `crate::MODULE` a source file names belongs to a
//! layer below the file's own (or to its own module), so the dependency graph has no
//! cycles and a reader can learn the crate bottom-up from `src/lib.rs`.
//!
//! The layers, bottom-up (the same list as the crate docs and the README):
//!
//! | rank | modules |
//! |---|---|
//! | 0 | `input_file`, `alloc_count` |
//! | 1 | `scene` |
//! | 2 | `kinematics`, `caspr`, `sag` |
//! | 3 | `trajectory`, `tension`, `cable` |
//! | 4 | `modal` |
//! | 5 | `estimator` |
//! | 6 | `service`, `study` |
//! | 7 | `report` |
//! | 8 | `cli` (used by `main.rs` alone) |
//!
//! Modules of one rank do not use each other, with the exceptions in [`SIBLING_EDGES`].

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// (module, rank): every top-level module of the library.
const LAYERS: &[(&str, u32)] = &[
    ("input_file", 0),
    ("scene", 1),
    ("alloc_count", 0),
    ("kinematics", 2),
    ("caspr", 2),
    ("sag", 2),
    ("trajectory", 3),
    ("tension", 3),
    ("cable", 3),
    ("modal", 4),
    ("estimator", 5),
    ("service", 6),
    ("study", 6),
    ("report", 7),
    ("cli", 8),
];

/// Same-rank uses that are allowed, with why.
const SIBLING_EDGES: &[(&str, &str, &str)] = &[
    // Offline studies report percentiles and status counts the way the service does: one
    // implementation, in service::stats (which uses nothing of iceoryx2).
    ("study", "service", "stats"),
];

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

/// Every `crate::a::b` path in `text`, as (a, b) (b empty when absent), comments included:
/// a doc link to a higher layer is a dependency of the reader, too.
fn crate_paths(text: &str) -> BTreeSet<(String, String)> {
    let mut out = BTreeSet::new();
    let ident = |s: &str| -> String {
        s.chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
            .collect()
    };
    for (i, _) in text.match_indices("crate::") {
        let before = text[..i].chars().next_back();
        if before.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_') {
            continue; // e.g. `cablevib_crate::`
        }
        let rest = &text[i + "crate::".len()..];
        let a = ident(rest);
        let b = rest[a.len()..]
            .strip_prefix("::")
            .map(ident)
            .unwrap_or_default();
        out.insert((a, b));
    }
    out
}

#[test]
fn every_module_uses_only_the_layers_below_it() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    let mut violations = Vec::new();
    let mut checked = 0;
    for file in &files {
        let Some(module) = module_of(&src, file) else {
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

#[test]
fn the_scan_finds_paths_and_layers_reject_upward_uses() {
    let p = crate_paths(
        "use crate::modal::{A, B};\n/// [`crate::cli`]\nmy_crate::x crate::service::stats::percentile",
    );
    let expected: BTreeSet<(String, String)> = [("modal", ""), ("cli", ""), ("service", "stats")]
        .iter()
        .map(|&(a, b)| (a.to_string(), b.to_string()))
        .collect();
    assert_eq!(p, expected);
    assert!(rank("scene") < rank("estimator") && rank("estimator") < rank("cli"));
    assert_eq!(rank("no_such_module"), None);
}
