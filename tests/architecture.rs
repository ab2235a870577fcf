//! The tree's shape, checked (docs/architecture.md): inside each crate, imports run one way
//! between files. A file imports another when it names it in a `use` line or in an inline path
//! (`crate::run::checks::x`, `super::report::y`, `checks::z` for a child module). A `pub use`
//! is a facade's re-export, not an import: a path through it counts as an import of the file
//! that defines the item. A file's `#[cfg(test)]` module may use anything of its crate and is
//! left out. The test builds that graph for `engine`, `comparisons` and the
//! binary and fails on any loop, two files that import each other or a longer circle, naming
//! the lines that close it.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// A module path inside its crate (`["run", "checks"]`; the crate root is empty).
type ModPath = Vec<String>;

/// One crate's files by module path.
struct Tree {
    files: BTreeMap<ModPath, PathBuf>,
}

impl Tree {
    fn read(src: &Path) -> Tree {
        let mut files = BTreeMap::new();
        let mut stack = vec![src.to_path_buf()];
        while let Some(dir) = stack.pop() {
            for entry in std::fs::read_dir(&dir).unwrap() {
                let path = entry.unwrap().path();
                if path.is_dir() {
                    stack.push(path);
                    continue;
                }
                if path.extension().is_none_or(|e| e != "rs") {
                    continue;
                }
                let rel = path.strip_prefix(src).unwrap();
                let mut m: ModPath = rel
                    .parent()
                    .unwrap()
                    .components()
                    .map(|c| c.as_os_str().to_string_lossy().into_owned())
                    .collect();
                let stem = path.file_stem().unwrap().to_string_lossy().into_owned();
                let root = m.is_empty() && (stem == "lib" || stem == "main");
                if stem != "mod" && !root {
                    m.push(stem);
                }
                files.insert(m, path);
            }
        }
        Tree { files }
    }

    /// The file that defines the item or module `path` names: the longest prefix of it that is
    /// a file's module.
    fn file_of(&self, path: &[String]) -> Option<&ModPath> {
        (0..=path.len())
            .rev()
            .find_map(|k| self.files.get_key_value(&path[..k]).map(|(m, _)| m))
    }
}

/// The code of a Rust file with comments and the contents of string and character literals
/// blanked (line breaks kept, so positions keep their line numbers).
fn code_only(text: &str) -> String {
    let c: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let blank = |ch: char| if ch == '\n' { '\n' } else { ' ' };
    let mut i = 0;
    while i < c.len() {
        let next = c.get(i + 1).copied();
        if c[i] == '/' && next == Some('/') {
            while i < c.len() && c[i] != '\n' {
                out.push(' ');
                i += 1;
            }
        } else if c[i] == '/' && next == Some('*') {
            let mut depth = 0;
            loop {
                if c[i] == '/' && c.get(i + 1) == Some(&'*') {
                    depth += 1;
                    out.push_str("  ");
                    i += 2;
                } else if c[i] == '*' && c.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    out.push_str("  ");
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    out.push(blank(c[i]));
                    i += 1;
                }
            }
        } else if c[i] == 'r'
            && (next == Some('"') || next == Some('#'))
            && (i == 0 || !(c[i - 1].is_alphanumeric() || c[i - 1] == '_'))
        {
            // A raw string r"…" or r#"…"#.
            let mut j = i + 1;
            let mut hashes = 0;
            while c.get(j) == Some(&'#') {
                hashes += 1;
                j += 1;
            }
            if c.get(j) != Some(&'"') {
                out.push(c[i]);
                i += 1;
                continue;
            }
            let end: String = std::iter::once('"')
                .chain(std::iter::repeat_n('#', hashes))
                .collect();
            let body = j + 1;
            let close = (body..c.len())
                .find(|&k| c[k..].iter().take(end.len()).collect::<String>() == end)
                .expect("an unterminated raw string");
            for &ch in &c[i..close + end.len()] {
                out.push(blank(ch));
            }
            i = close + end.len();
        } else if c[i] == '"' {
            out.push(' ');
            i += 1;
            while c[i] != '"' {
                if c[i] == '\\' {
                    out.push(' ');
                    i += 1;
                }
                out.push(blank(c[i]));
                i += 1;
            }
            out.push(' ');
            i += 1;
        } else if c[i] == '\'' {
            // A character literal ('x', '\n', '\u{…}'); a lifetime ('a) has no closing quote
            // right after its first character.
            let close = if next == Some('\\') {
                (i + 2..c.len()).find(|&k| c[k] == '\'')
            } else if c.get(i + 2) == Some(&'\'') {
                Some(i + 2)
            } else {
                None
            };
            match close {
                Some(k) => {
                    for &ch in &c[i..=k] {
                        out.push(blank(ch));
                    }
                    i = k + 1;
                }
                None => {
                    out.push('\'');
                    i += 1;
                }
            }
        } else {
            out.push(c[i]);
            i += 1;
        }
    }
    out
}

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Ident(String),
    Path,
    Open,
    Close,
    Comma,
    Semi,
    Star,
    Other,
}

/// Tokens with their line numbers.
fn tokens(code: &str) -> Vec<(Tok, usize)> {
    let c: Vec<char> = code.chars().collect();
    let mut out = Vec::new();
    let (mut i, mut line) = (0, 1);
    while i < c.len() {
        let ch = c[i];
        if ch == '\n' {
            line += 1;
            i += 1;
        } else if ch.is_whitespace() {
            i += 1;
        } else if ch.is_alphabetic() || ch == '_' {
            let start = i;
            while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_') {
                i += 1;
            }
            let word: String = c[start..i].iter().collect();
            // A lifetime or loop label is not a path segment.
            let tok = if start > 0 && c[start - 1] == '\'' {
                Tok::Other
            } else {
                Tok::Ident(word)
            };
            out.push((tok, line));
        } else if ch.is_ascii_digit() {
            while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_' || c[i] == '.') {
                i += 1;
            }
            out.push((Tok::Other, line));
        } else {
            let tok = match ch {
                ':' if c.get(i + 1) == Some(&':') => {
                    i += 1;
                    Tok::Path
                }
                '{' => Tok::Open,
                '}' => Tok::Close,
                ',' => Tok::Comma,
                ';' => Tok::Semi,
                '*' => Tok::Star,
                _ => Tok::Other,
            };
            out.push((tok, line));
            i += 1;
        }
    }
    out
}

/// The paths of a `use` tree starting at `toks[i]` (after `use`), each with its line; returns
/// them and the index past the `;`.
fn use_paths(toks: &[(Tok, usize)], mut i: usize) -> (Vec<(Vec<String>, usize)>, usize) {
    let mut out = Vec::new();
    let mut prefix: Vec<Vec<String>> = vec![Vec::new()];
    let mut current: Vec<String> = Vec::new();
    // `self` in a group names the group's prefix itself.
    let mut itself = false;
    loop {
        let (tok, line) = &toks[i];
        match tok {
            Tok::Ident(w) if w == "as" => i += 1,
            Tok::Ident(w) if w == "self" => itself = true,
            Tok::Ident(w) => current.push(w.clone()),
            Tok::Path | Tok::Star | Tok::Other => {}
            Tok::Open => {
                let mut base = prefix.last().unwrap().clone();
                base.append(&mut current);
                prefix.push(base);
            }
            Tok::Comma | Tok::Close | Tok::Semi => {
                if !current.is_empty() || itself {
                    let mut p = prefix.last().unwrap().clone();
                    p.append(&mut current);
                    out.push((p, *line));
                    itself = false;
                }
                if *tok == Tok::Close {
                    prefix.pop();
                }
                if *tok == Tok::Semi {
                    return (out, i + 1);
                }
            }
        }
        i += 1;
    }
}

/// The module `file` with the inline modules open at a point of it.
fn here(file: &ModPath, inline: &[(String, usize)]) -> ModPath {
    let mut m = file.clone();
    m.extend(inline.iter().map(|(n, _)| n.clone()));
    m
}

/// The module path `p` names from module `at` (`crate::`, `self::`, `super::` or a child
/// module); `None` for another crate's.
fn absolute(tree: &Tree, p: &[String], at: &ModPath) -> Option<ModPath> {
    let mut segs = p.iter().cloned().peekable();
    let mut base = match segs.peek().map(String::as_str) {
        Some("crate") => {
            segs.next();
            Vec::new()
        }
        Some("self") => {
            segs.next();
            at.clone()
        }
        Some("super") => at.clone(),
        Some(w) => {
            // A child module of the current one (2018 paths), or another crate.
            let mut child = at.clone();
            child.push(w.to_string());
            if !tree.files.keys().any(|m| m.starts_with(&child)) {
                return None;
            }
            at.clone()
        }
        None => return None,
    };
    while segs.peek().map(String::as_str) == Some("super") {
        segs.next();
        base.pop();
    }
    base.extend(segs);
    Some(base)
}

/// The files each file of `tree` imports, with the first line naming each.
fn imports(tree: &Tree) -> BTreeMap<ModPath, BTreeMap<ModPath, usize>> {
    let mut found = BTreeMap::new();
    for (module, file) in &tree.files {
        let code = code_only(&std::fs::read_to_string(file).unwrap());
        let toks = tokens(&code);
        // Inline modules (`mod tests { … }`), with the brace depth they close at.
        let mut inline: Vec<(String, usize)> = Vec::new();
        let mut depth = 0;
        let mut paths: Vec<(Vec<String>, ModPath, usize, bool)> = Vec::new();
        // The depth at which an open `#[cfg(test)]` module closes.
        let mut tests_from: Option<usize> = None;
        let mut i = 0;
        while i < toks.len() {
            match &toks[i].0 {
                Tok::Open => depth += 1,
                Tok::Close => {
                    if inline.last().is_some_and(|(_, d)| *d == depth) {
                        inline.pop();
                    }
                    if tests_from == Some(depth) {
                        tests_from = None;
                    }
                    depth -= 1;
                }
                Tok::Ident(w) if w == "mod" => {
                    if let (Some((Tok::Ident(name), _)), Some((Tok::Open, _))) =
                        (toks.get(i + 1), toks.get(i + 2))
                    {
                        depth += 1;
                        inline.push((name.clone(), depth));
                        // `#[cfg(test)] mod …`: unit tests may use anything of their crate.
                        let attr: Vec<&Tok> =
                            toks[i.saturating_sub(5)..i].iter().map(|t| &t.0).collect();
                        if attr.len() == 5
                            && *attr[0] == Tok::Ident("cfg".into())
                            && *attr[2] == Tok::Ident("test".into())
                            && tests_from.is_none()
                        {
                            tests_from = Some(depth);
                        }
                        i += 3;
                        continue;
                    }
                }
                Tok::Ident(w) if w == "use" && tests_from.is_some() => {
                    i = use_paths(&toks, i + 1).1;
                    continue;
                }
                Tok::Ident(first) if tests_from.is_some() && first != "mod" => {}
                Tok::Ident(w) if w == "use" => {
                    let (found, next) = use_paths(&toks, i + 1);
                    let m = here(module, &inline);
                    // `pub use` (and `pub(crate) use`): a re-export, not a use of its own.
                    let public = toks[i.saturating_sub(4)..i]
                        .iter()
                        .rev()
                        .take_while(|(t, _)| !matches!(t, Tok::Semi | Tok::Open | Tok::Close))
                        .any(|(t, _)| *t == Tok::Ident("pub".into()));
                    paths.extend(found.into_iter().map(|(p, l)| (p, m.clone(), l, public)));
                    i = next;
                    continue;
                }
                Tok::Ident(first) if i == 0 || toks[i - 1].0 != Tok::Path => {
                    let mut p = vec![first.clone()];
                    let mut j = i + 1;
                    while let (Some((Tok::Path, _)), Some((Tok::Ident(w), _))) =
                        (toks.get(j), toks.get(j + 1))
                    {
                        p.push(w.clone());
                        j += 2;
                    }
                    if p.len() > 1 {
                        paths.push((p, here(module, &inline), toks[i].1, false));
                        i = j;
                        continue;
                    }
                }
                _ => {}
            }
            i += 1;
        }
        found.insert(module.clone(), paths);
    }
    // What each module re-exports: its name there → the path it stands for.
    let mut reexports: BTreeMap<ModPath, BTreeMap<String, ModPath>> = BTreeMap::new();
    for paths in found.values() {
        for (p, at, _, public) in paths {
            if let (true, Some(abs)) = (*public, absolute(tree, p, at)) {
                let name = abs.last().cloned().unwrap_or_default();
                reexports.entry(at.clone()).or_default().insert(name, abs);
            }
        }
    }
    let mut graph = BTreeMap::new();
    for (module, paths) in found {
        let mut edges: BTreeMap<ModPath, usize> = BTreeMap::new();
        for (p, at, line, public) in paths {
            let Some(mut abs) = absolute(tree, &p, &at).filter(|_| !public) else {
                continue;
            };
            // Through re-exports to the file that defines the item (a facade such as
            // `lib.rs` is not what its users depend on).
            for _ in 0..8 {
                let through = (0..abs.len()).rev().find_map(|k| {
                    reexports
                        .get(&abs[..k])
                        .and_then(|r| r.get(&abs[k]))
                        .map(|t| (k, t.clone()))
                });
                match through {
                    Some((k, t)) if t != abs[..=k] => {
                        let rest = abs.split_off(k + 1);
                        abs = t;
                        abs.extend(rest);
                    }
                    _ => break,
                }
            }
            if let Some(target) = tree.file_of(&abs) {
                if *target != module {
                    edges.entry(target.clone()).or_insert(line);
                }
            }
        }
        graph.insert(module.clone(), edges);
    }
    graph
}

/// The strongly connected components of more than one file (Tarjan).
fn loops(graph: &BTreeMap<ModPath, BTreeMap<ModPath, usize>>) -> Vec<BTreeSet<ModPath>> {
    struct State<'g> {
        graph: &'g BTreeMap<ModPath, BTreeMap<ModPath, usize>>,
        index: BTreeMap<&'g ModPath, (usize, usize)>,
        stack: Vec<&'g ModPath>,
        on: BTreeSet<&'g ModPath>,
        out: Vec<BTreeSet<ModPath>>,
    }
    fn visit<'g>(s: &mut State<'g>, v: &'g ModPath) {
        let k = s.index.len();
        s.index.insert(v, (k, k));
        s.stack.push(v);
        s.on.insert(v);
        for w in s.graph[v].keys() {
            let w = s.graph.get_key_value(w).unwrap().0;
            if !s.index.contains_key(w) {
                visit(s, w);
                let low = s.index[w].1.min(s.index[v].1);
                s.index.get_mut(v).unwrap().1 = low;
            } else if s.on.contains(w) {
                let low = s.index[w].0.min(s.index[v].1);
                s.index.get_mut(v).unwrap().1 = low;
            }
        }
        if s.index[v].0 == s.index[v].1 {
            let mut comp = BTreeSet::new();
            loop {
                let w = s.stack.pop().unwrap();
                s.on.remove(w);
                comp.insert(w.clone());
                if w == v {
                    break;
                }
            }
            if comp.len() > 1 {
                s.out.push(comp);
            }
        }
    }
    let mut s = State {
        graph,
        index: BTreeMap::new(),
        stack: Vec::new(),
        on: BTreeSet::new(),
        out: Vec::new(),
    };
    for v in graph.keys() {
        if !s.index.contains_key(v) {
            visit(&mut s, v);
        }
    }
    s.out
}

fn crate_loops(src: &str) -> Vec<String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join(src);
    let tree = Tree::read(&root);
    let graph = imports(&tree);
    let name = |m: &ModPath| {
        tree.files[m]
            .strip_prefix(&root)
            .unwrap()
            .display()
            .to_string()
    };
    loops(&graph)
        .into_iter()
        .map(|comp| {
            let mut lines = vec![format!(
                "a loop in {src}: {}",
                comp.iter().map(name).collect::<Vec<_>>().join(", ")
            )];
            for a in &comp {
                for (b, line) in &graph[a] {
                    if comp.contains(b) {
                        lines.push(format!("  {}:{line} imports {}", name(a), name(b)));
                    }
                }
            }
            lines.join("\n")
        })
        .collect()
}

#[test]
fn no_file_imports_a_file_that_imports_it_back() {
    let found: Vec<String> = ["engine/src", "comparisons/src", "src"]
        .iter()
        .flat_map(|src| crate_loops(src))
        .collect();
    assert!(
        found.is_empty(),
        "imports go round in a circle; move what both sides share into a leaf file:\n{}",
        found.join("\n")
    );
}

/// The scan sees the ways a file names another: `use` trees with groups, renames and
/// `self`, inline `crate::`, `super::` and child-module paths, paths through a re-export;
/// and not comments or strings.
#[test]
fn the_scan_finds_every_kind_of_import_and_nothing_else() {
    let dir = tempfile::tempdir().unwrap();
    let write = |rel: &str, text: &str| {
        let p = dir.path().join(rel);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, text).unwrap();
    };
    write("lib.rs", "pub mod a;\npub mod b;\npub mod c;\npub mod d;\n");
    write("a/mod.rs", "pub mod x;\npub use x::{self as y, Z};\n");
    write(
        "a/x.rs",
        "// crate::b::Q in a comment\nconst S: &str = \"crate::c::W\";\n",
    );
    write(
        "b.rs",
        "use crate::{a::{x::Z}, c};\nfn f() { let _ = super::d::g(); }\n",
    );
    write(
        "c.rs",
        "fn f<'a>(x: &'a str) -> char { let _ = crate::a::Z; 'c' }\n",
    );
    write(
        "d.rs",
        "mod inner { use super::*; }\n#[cfg(test)]\nmod tests { use crate::b::f; }\n",
    );
    let tree = Tree::read(dir.path());
    let graph = imports(&tree);
    let m = |s: &str| -> ModPath {
        s.split('/')
            .filter(|w| !w.is_empty())
            .map(String::from)
            .collect()
    };
    let edges = |s: &str| graph[&m(s)].keys().cloned().collect::<Vec<_>>();
    assert!(
        edges("a").is_empty(),
        "a facade's re-exports are not its imports"
    );
    assert!(
        edges("a/x").is_empty(),
        "comments and strings are not imports"
    );
    assert_eq!(edges("b"), vec![m("a/x"), m("c"), m("d")]);
    assert_eq!(
        edges("c"),
        vec![m("a/x")],
        "through the re-export to its file"
    );
    assert!(
        edges("d").is_empty(),
        "an inline module's `super` is its own file; tests are out"
    );
    assert!(loops(&graph).is_empty());
    write("a/x.rs", "use crate::b::f;\n");
    let graph = imports(&Tree::read(dir.path()));
    assert_eq!(
        loops(&graph).len(),
        1,
        "a → x → b → a… b imports a/x only: x ↔ b"
    );
}
