//! No import cycle of any length between the files of a crate.
//!
//! Every source file is a node. A file's code (comments left out: a doc link to the code that
//! uses this one is not an import; `#[cfg(test)]` items left out: a unit test is compiled only
//! into the test binary and may use what it checks against) names other modules by `crate::…`, `super::…` and
//! `self::…` paths, `use` groups included; each path is followed through the module tree to
//! the file that defines what it names (a name a `mod.rs` re-exports with `pub use` is
//! followed to the file it comes from). That is an edge, except from a module's `mod.rs`
//! (or `lib.rs`) to the files under it: a parent declares and re-exports its children. The
//! graph's strongly connected components with more than one file are the cycles.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// A module path from the crate root (`["modal", "solver"]`).
type ModPath = Vec<String>;

/// The crate's files by module path, and each module file's `pub use` names.
struct Tree {
    files: BTreeMap<ModPath, PathBuf>,
    /// For each module file: a name it re-exports → the absolute path it names.
    reexports: BTreeMap<ModPath, BTreeMap<String, ModPath>>,
    /// Each module's code, comments removed.
    code: BTreeMap<ModPath, String>,
}

/// `code` (comments already removed) without its `#[cfg(test)]` items: an inline
/// `mod … { … }` up to its matching brace, any other item up to its `;`.
pub fn strip_tests(code: &str) -> String {
    let mut out = String::with_capacity(code.len());
    let mut rest = code;
    while let Some(at) = rest.find("#[cfg(test)]") {
        out.push_str(&rest[..at]);
        let item = &rest[at + "#[cfg(test)]".len()..];
        let semi = item.find(';').unwrap_or(item.len());
        let brace = item.find('{').unwrap_or(item.len());
        rest = if brace < semi {
            // Skip to the brace that closes the item's first `{`.
            let mut depth = 0usize;
            let mut end = item.len();
            for (i, c) in item[brace..].char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' => {
                        depth -= 1;
                        if depth == 0 {
                            end = brace + i + 1;
                            break;
                        }
                    }
                    _ => {}
                }
            }
            &item[end..]
        } else {
            &item[(semi + 1).min(item.len())..]
        };
    }
    out.push_str(rest);
    out
}

/// `text` without `//` comments (to the line's end) and `/* */` blocks.
pub fn strip_comments(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while !rest.is_empty() {
        let line_c = rest.find("//");
        let block_c = rest.find("/*");
        match (line_c, block_c) {
            (Some(l), b) if b.is_none_or(|b| l < b) => {
                out.push_str(&rest[..l]);
                rest = rest[l..].find('\n').map_or("", |n| &rest[l + n..]);
            }
            (_, Some(b)) => {
                out.push_str(&rest[..b]);
                rest = rest[b..].find("*/").map_or("", |e| &rest[b + e + 2..]);
            }
            _ => {
                out.push_str(rest);
                rest = "";
            }
        }
    }
    out
}

fn ident_at(s: &str) -> &str {
    let end = s
        .char_indices()
        .find(|(_, c)| !(c.is_ascii_alphanumeric() || *c == '_'))
        .map_or(s.len(), |(i, _)| i);
    &s[..end]
}

/// Marks a path's last segment as the name an `as` rename gives it (`a::B as C` is
/// `[a, B, "as C"]`); a segment no identifier can be, so it never names a module.
const ALIAS: &str = "as ";

/// Every path that starts at `i` in `text` (just after a root `crate`/`super`/`self`
/// segment has been read into `prefix`): `a::b::C`, or each leaf of a `{…}` group, with an
/// `as` rename as an [`ALIAS`] segment after it. `*` ends a path.
fn paths_from(text: &str, mut i: usize, prefix: Vec<String>, out: &mut Vec<Vec<String>>) {
    let mut path = prefix;
    loop {
        let rest = &text[i..];
        let trimmed = rest.trim_start();
        i += rest.len() - trimmed.len();
        if let Some(group) = trimmed.strip_prefix('{') {
            // Split the group at its top-level commas.
            let start = i + 1;
            let mut depth = 0;
            let mut item = start;
            for (j, c) in group.char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' if depth == 0 => {
                        paths_from(text, item, path.clone(), out);
                        return;
                    }
                    '}' => depth -= 1,
                    ',' if depth == 0 => {
                        paths_from(text, item, path.clone(), out);
                        item = start + j + 1;
                    }
                    _ => {}
                }
            }
            return;
        }
        let seg = ident_at(trimmed);
        if seg.is_empty() {
            out.push(path);
            return;
        }
        path.push(seg.to_string());
        i += seg.len();
        if text[i..].starts_with("::") {
            i += 2;
        } else {
            let after = text[i..].trim_start();
            if let Some(alias) = after.strip_prefix("as ").map(|a| ident_at(a.trim_start())) {
                if !alias.is_empty() {
                    path.push(format!("{ALIAS}{alias}"));
                }
            }
            out.push(path);
            return;
        }
    }
}

/// Every `crate::`, `super::…` and `self::` path of `code`, as its segments (the root
/// segments included).
fn all_paths(code: &str) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    for root in ["crate::", "super::", "self::"] {
        for (i, _) in code.match_indices(root) {
            let before = code[..i].chars().next_back();
            if before.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_' || c == ':' || c == '$')
            {
                continue; // a later segment (`super::super::`), `$crate::`, `x_crate::`
            }
            let mut prefix = vec![root.trim_end_matches("::").to_string()];
            let mut j = i + root.len();
            while code[j..].starts_with("super::") {
                prefix.push("super".into());
                j += "super::".len();
            }
            paths_from(code, j, prefix, &mut out);
        }
    }
    out
}

impl Tree {
    fn new(src: &Path) -> Tree {
        let mut files = Vec::new();
        super::rust_files(src, &mut files);
        let mut tree = Tree {
            files: BTreeMap::new(),
            reexports: BTreeMap::new(),
            code: BTreeMap::new(),
        };
        for f in &files {
            let rel = f.strip_prefix(src).expect("under src");
            let mut path: ModPath = rel
                .iter()
                .map(|c| {
                    c.to_str()
                        .expect("utf-8 path")
                        .trim_end_matches(".rs")
                        .to_string()
                })
                .collect();
            if path
                .last()
                .is_some_and(|l| l == "mod" || l == "lib" || l == "main")
            {
                path.pop();
            }
            let text = std::fs::read_to_string(f).expect("read source");
            tree.code
                .insert(path.clone(), strip_tests(&strip_comments(&text)));
            tree.files.insert(path, f.clone());
        }
        let modules: Vec<ModPath> = tree.files.keys().cloned().collect();
        for m in modules {
            let code = tree.code[&m].clone();
            let mut names = BTreeMap::new();
            for (i, _) in code.match_indices("use ") {
                // `pub use` or `pub(…) use` at the start of a statement.
                let head = code[..i].trim_end();
                let head = head
                    .rsplit(['\n', ';', '{', '}'])
                    .next()
                    .unwrap_or("")
                    .trim();
                if !(head == "pub" || (head.starts_with("pub(") && head.ends_with(')'))) {
                    continue;
                }
                let mut paths = Vec::new();
                paths_from(&code, i + 4, Vec::new(), &mut paths);
                for mut p in paths {
                    // `pub use a::B as C;` re-exports B under the name C.
                    let name = match p.last().and_then(|l| l.strip_prefix(ALIAS)) {
                        Some(alias) => {
                            let alias = alias.to_string();
                            p.pop();
                            alias
                        }
                        None => match p.last() {
                            Some(l) => l.clone(),
                            None => continue,
                        },
                    };
                    let abs = tree.absolute(&m, &p);
                    names.insert(name, abs);
                }
            }
            tree.reexports.insert(m, names);
        }
        tree
    }

    /// The absolute module path of `path` named in module `m` (`crate::`, `super::`,
    /// `self::`, or a child module's name).
    fn absolute(&self, m: &ModPath, path: &[String]) -> ModPath {
        let mut at: ModPath = m.clone();
        let mut segs = path;
        match segs.first().map(String::as_str) {
            Some("crate") => {
                at.clear();
                segs = &segs[1..];
            }
            Some("self") => segs = &segs[1..],
            _ => {}
        }
        while segs.first().is_some_and(|s| s == "super") {
            at.pop();
            segs = &segs[1..];
        }
        at.extend(segs.iter().cloned());
        at
    }

    /// The file that defines what the absolute path `p` names: the deepest module on it,
    /// then through that module's re-exports (at most `depth` more).
    fn target(&self, p: &ModPath, depth: usize) -> Option<ModPath> {
        let mut at: ModPath = Vec::new();
        let mut i = 0;
        while i < p.len() {
            let mut next = at.clone();
            next.push(p[i].clone());
            if self.files.contains_key(&next) {
                at = next;
                i += 1;
            } else {
                break;
            }
        }
        if i < p.len() && depth > 0 {
            if let Some(to) = self.reexports.get(&at).and_then(|r| r.get(&p[i])) {
                let mut rest = to.clone();
                rest.extend(p[i + 1..].iter().cloned());
                if rest != *p {
                    return self.target(&rest, depth - 1);
                }
            }
        }
        self.files.contains_key(&at).then_some(at)
    }

    /// The edges: each file to the files it names (module files to files under them left
    /// out).
    fn edges(&self) -> BTreeMap<ModPath, BTreeSet<ModPath>> {
        let mut out = BTreeMap::new();
        for (m, file) in &self.files {
            let is_parent =
                file.ends_with("mod.rs") || file.ends_with("lib.rs") || file.ends_with("main.rs");
            // A plain file's own path is its module; `super` of a mod.rs is its directory's
            // parent, of a plain file the directory it is in: both are `m` without its last
            // segment, which is what `absolute` does from `m`.
            let mut to = BTreeSet::new();
            for p in all_paths(&self.code[m]) {
                let abs = self.absolute(m, &p);
                let Some(t) = self.target(&abs, 8) else {
                    continue;
                };
                let below = t.len() > m.len() && t[..m.len()] == m[..];
                if t == *m || (is_parent && below) {
                    continue;
                }
                to.insert(t);
            }
            out.insert(m.clone(), to);
        }
        out
    }
}

/// The strongly connected components of more than one node (Tarjan), each sorted.
fn cycles(edges: &BTreeMap<ModPath, BTreeSet<ModPath>>) -> Vec<Vec<ModPath>> {
    struct State<'a> {
        edges: &'a BTreeMap<ModPath, BTreeSet<ModPath>>,
        index: BTreeMap<&'a ModPath, usize>,
        low: BTreeMap<&'a ModPath, usize>,
        stack: Vec<&'a ModPath>,
        on: BTreeSet<&'a ModPath>,
        next: usize,
        out: Vec<Vec<ModPath>>,
    }
    fn visit<'a>(s: &mut State<'a>, v: &'a ModPath) {
        s.index.insert(v, s.next);
        s.low.insert(v, s.next);
        s.next += 1;
        s.stack.push(v);
        s.on.insert(v);
        let edges = s.edges;
        for w in edges.get(v).into_iter().flatten() {
            let Some((w, _)) = edges.get_key_value(w) else {
                continue;
            };
            if !s.index.contains_key(w) {
                visit(s, w);
                let lw = s.low[w];
                let lv = s.low.get_mut(v).expect("visited");
                *lv = (*lv).min(lw);
            } else if s.on.contains(w) {
                let iw = s.index[w];
                let lv = s.low.get_mut(v).expect("visited");
                *lv = (*lv).min(iw);
            }
        }
        if s.low[v] == s.index[v] {
            let mut comp = Vec::new();
            loop {
                let w = s.stack.pop().expect("on the stack");
                s.on.remove(w);
                comp.push(w.clone());
                if w == v {
                    break;
                }
            }
            if comp.len() > 1 {
                comp.sort();
                s.out.push(comp);
            }
        }
    }
    let mut s = State {
        edges,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on: BTreeSet::new(),
        next: 0,
        out: Vec::new(),
    };
    for v in edges.keys() {
        if !s.index.contains_key(v) {
            visit(&mut s, v);
        }
    }
    s.out
}

/// The import cycles among the files of the crate whose sources are under `src`, each as
/// its files' module paths joined by " ↔ ".
pub fn file_cycles(src: &Path) -> Vec<String> {
    let tree = Tree::new(src);
    cycles(&tree.edges())
        .into_iter()
        .map(|c| {
            c.iter()
                .map(|p| {
                    if p.is_empty() {
                        "crate".to_string()
                    } else {
                        p.join("::")
                    }
                })
                .collect::<Vec<_>>()
                .join(" ↔ ")
        })
        .collect()
}

#[test]
fn no_import_cycle_between_files() {
    let mut found = Vec::new();
    for dir in ["src", "service/src", "monitor/src", "cli/src"] {
        for c in file_cycles(&super::root().join(dir)) {
            found.push(format!("{dir}: {c}"));
        }
    }
    assert!(found.is_empty(), "import cycles:\n{}", found.join("\n"));
}

/// The scan finds a planted cycle of three files through a `use` group, `super::super::`,
/// an `as` re-export of a `mod.rs`, and leaves out a doc comment and a `#[cfg(test)]`
/// module (each of which would close another cycle if it counted).
#[test]
fn the_cycle_scan_finds_a_planted_cycle() {
    let dir = std::env::temp_dir().join(format!("cablevib-cycles-{}", std::process::id()));
    let m = dir.join("m");
    let n = m.join("n");
    std::fs::create_dir_all(&n).expect("create temp dir");
    let write = |p: PathBuf, t: &str| std::fs::write(p, t).expect("write");
    write(dir.join("lib.rs"), "pub mod m;\npub mod y;\npub mod z;");
    write(
        m.join("mod.rs"),
        "mod a; mod b; mod n;\npub use b::B as Bee;\npub(crate) use n::deep::D;",
    );
    write(
        m.join("a.rs"),
        "use super::{Bee, x::{y, z}};\n/// [`crate::y::Y`]\nfn f() -> crate::z::Z { crate::z::Z }",
    );
    write(m.join("b.rs"), "use crate::m::D;\npub struct B;");
    write(n.join("mod.rs"), "pub mod deep;");
    write(n.join("deep.rs"), "use super::super::a::f;\npub struct D;");
    write(dir.join("y.rs"), "use crate::m::a;\npub struct Y;");
    write(
        dir.join("z.rs"),
        "pub struct Z;\n#[cfg(test)]\nmod tests {\n    use crate::m::a;\n    fn t() {}\n}",
    );
    let c = file_cycles(&dir);
    std::fs::remove_dir_all(&dir).ok();
    assert_eq!(c, vec!["m::a ↔ m::b ↔ m::n::deep".to_string()]);
}

#[test]
fn comments_are_left_out_and_paths_split_at_groups() {
    assert_eq!(strip_comments("a // b\nc /* d */ e"), "a \nc  e");
    assert_eq!(
        strip_tests("x\n#[cfg(test)]\nmod t { fn f() { g() } }\ny #[cfg(test)] use z; w"),
        "x\n\ny  w"
    );
    let p = all_paths("use super::{a, b::{c, d as e}, f::*};");
    let want: Vec<Vec<String>> = [
        vec!["super", "a"],
        vec!["super", "b", "c"],
        vec!["super", "b", "d", "as e"],
        vec!["super", "f"],
    ]
    .iter()
    .map(|v| v.iter().map(|s| s.to_string()).collect())
    .collect();
    assert_eq!(p, want);
}
