//! The layering rule of docs/architecture.md, held by reading the source: no two modules of `src/` import each
//! other, directly or around a circle (a child's use of its parent's items does not count: a `mod.rs` owns its
//! files). A new circle fails this test with the modules that form it.
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Every module of `src/` (`render::frame`, `vk`, ...) and its file, without `lib.rs` and `main.rs`.
fn modules() -> BTreeMap<String, String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut found = BTreeMap::new();
    let mut dirs = vec![root.clone()];
    while let Some(dir) = dirs.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                dirs.push(path);
                continue;
            }
            if path.extension().is_none_or(|e| e != "rs") {
                continue;
            }
            let relative = path.strip_prefix(&root).unwrap().with_extension("");
            let mut parts: Vec<String> = relative.iter().map(|p| p.to_string_lossy().into_owned()).collect();
            if parts.last().is_some_and(|p| p == "mod") {
                parts.pop();
            }
            if parts == ["lib"] || parts == ["main"] {
                continue;
            }
            found.insert(parts.join("::"), std::fs::read_to_string(&path).unwrap());
        }
    }
    found
}

/// The source without comments and without its unit tests (which may reach anywhere).
fn code_of(text: &str) -> String {
    let without_tests = match text.find("#[cfg(test)]\nmod tests") {
        Some(at) => &text[..at],
        None => text,
    };
    without_tests.lines().map(|l| l.split("//").next().unwrap_or("")).collect::<Vec<_>>().join("\n")
}

/// The module a path names from module `here` (`crate::a::b::Item`, `super::c::Item`), the longest that exists.
fn target(here: &str, path: &str, modules: &BTreeMap<String, String>) -> Option<String> {
    let mut segments: Vec<&str> = path.split("::").collect();
    let mut base: Vec<&str> = Vec::new();
    match segments.first() {
        Some(&"crate") | Some(&"strata") => {
            segments.remove(0);
        }
        Some(&"super") => {
            base = here.split("::").collect();
            base.pop();
            segments.remove(0);
            while segments.first() == Some(&"super") {
                base.pop();
                segments.remove(0);
            }
        }
        _ => return None,
    }
    (1..=segments.len())
        .rev()
        .map(|n| base.iter().chain(&segments[..n]).copied().collect::<Vec<_>>().join("::"))
        .find(|candidate| modules.contains_key(candidate))
}

fn imports(modules: &BTreeMap<String, String>) -> BTreeMap<String, BTreeSet<String>> {
    let mut edges = BTreeMap::new();
    for (name, text) in modules {
        let code = code_of(text);
        let mut to = BTreeSet::new();
        let bytes = code.as_bytes();
        for start in ["crate::", "super::", "strata::"] {
            for (at, _) in code.match_indices(start) {
                if at > 0 && (bytes[at - 1].is_ascii_alphanumeric() || bytes[at - 1] == b'_') {
                    continue;
                }
                let end = code[at..]
                    .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_' || c == ':'))
                    .map_or(code.len(), |e| at + e);
                if let Some(t) = target(name, code[at..end].trim_end_matches(':'), modules) {
                    // A module's use of its own parent (or the parent's items) is not an edge of the graph.
                    if t != *name && !name.starts_with(&format!("{t}::")) {
                        to.insert(t);
                    }
                }
            }
        }
        edges.insert(name.clone(), to);
    }
    edges
}

/// The strongly connected components of more than one module (Tarjan).
fn circles(edges: &BTreeMap<String, BTreeSet<String>>) -> Vec<Vec<String>> {
    struct State<'a> {
        edges: &'a BTreeMap<String, BTreeSet<String>>,
        index: BTreeMap<&'a str, usize>,
        low: BTreeMap<&'a str, usize>,
        stack: Vec<&'a str>,
        next: usize,
        found: Vec<Vec<String>>,
    }
    fn visit<'a>(s: &mut State<'a>, v: &'a str) {
        s.index.insert(v, s.next);
        s.low.insert(v, s.next);
        s.next += 1;
        s.stack.push(v);
        for w in &s.edges[v] {
            let w = w.as_str();
            if !s.index.contains_key(w) {
                visit(s, w);
                let lw = s.low[w];
                s.low.insert(v, s.low[v].min(lw));
            } else if s.stack.contains(&w) {
                let iw = s.index[w];
                s.low.insert(v, s.low[v].min(iw));
            }
        }
        if s.low[v] == s.index[v] {
            let mut component = Vec::new();
            while let Some(w) = s.stack.pop() {
                component.push(w.to_string());
                if w == v {
                    break;
                }
            }
            if component.len() > 1 {
                component.sort();
                s.found.push(component);
            }
        }
    }
    let mut state =
        State { edges, index: BTreeMap::new(), low: BTreeMap::new(), stack: Vec::new(), next: 0, found: Vec::new() };
    for v in edges.keys() {
        if !state.index.contains_key(v.as_str()) {
            visit(&mut state, v);
        }
    }
    state.found
}

#[test]
fn no_module_imports_another_that_imports_it_back() {
    let modules = modules();
    assert!(modules.len() > 50 && modules.contains_key("vk::device"), "{:?}", modules.keys());
    let found = circles(&imports(&modules));
    assert!(found.is_empty(), "import circles in src/: {found:?}");
}

#[test]
fn the_checker_finds_a_circle() {
    let mut modules = BTreeMap::new();
    modules.insert("a".to_string(), "use crate::b::Thing;".to_string());
    modules.insert("b".to_string(), "fn f() { super::a::g(); } // crate::c::X".to_string());
    modules.insert("c".to_string(), "use crate::a;".to_string());
    assert_eq!(circles(&imports(&modules)), vec![vec!["a".to_string(), "b".to_string()]]);
}
