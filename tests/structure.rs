//! The code's shape, as anyone can check it: arrows between a crate's modules run one way (no import circle),
//! and no source file grows past about 800 lines of code — a module that does too much is split by what it is
//! about, before it becomes the place every change collides.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Every `.rs` file under `dir`, recursively.
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            out.extend(rust_files(&p));
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
    out.sort();
    out
}

/// `text` without its `#[cfg(test)]` items — a `mod tests { … }`, a gated function or impl (to its balanced closing
/// brace), a gated field or statement (to its `,` or `;`) — and nothing else: code after a gated field is still
/// read.
fn without_test_items(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(i) = rest.find("#[cfg(test)]") {
        out.push_str(&rest[..i]);
        let item = &rest[i + "#[cfg(test)]".len()..];
        // The item ends at its balanced `}` if a `{` opens before any `;` or `,`, else at that `;` or `,`.
        let open = item.find('{');
        let stop = item.find([';', ',']);
        let end = match (open, stop) {
            (Some(o), s) if s.is_none_or(|s| o < s) => {
                let mut depth = 0usize;
                let mut end = item.len();
                for (k, c) in item[o..].char_indices() {
                    match c {
                        '{' => depth += 1,
                        '}' => {
                            depth -= 1;
                            if depth == 0 {
                                end = o + k + 1;
                                break;
                            }
                        }
                        _ => {}
                    }
                }
                end
            }
            (_, Some(s)) => s + 1,
            _ => item.len(),
        };
        rest = &item[end..];
    }
    out.push_str(rest);
    out
}

/// The modules directly under `root` (a file's stem or a folder's name; not `mod.rs`/`lib.rs`/`main.rs`) and,
/// per module, the sibling modules its files name: through `prefix::X` (`crate::render`, `crate`) or through
/// as many `super::` as lead from the file back to `root`.
fn module_graph(root: &Path, prefix: &str) -> BTreeMap<String, BTreeSet<String>> {
    let mut nodes = BTreeSet::new();
    for e in std::fs::read_dir(root).unwrap() {
        let p = e.unwrap().path();
        let name = p.file_stem().unwrap().to_string_lossy().to_string();
        if (p.is_dir() || p.extension().is_some_and(|x| x == "rs"))
            && !["mod", "lib", "main", "tests"].contains(&name.as_str())
        {
            nodes.insert(name);
        }
    }
    let mut graph = BTreeMap::new();
    for node in &nodes {
        let mut edges = BTreeSet::new();
        let file = root.join(format!("{node}.rs"));
        let files = if file.is_file() {
            vec![file]
        } else {
            rust_files(&root.join(node))
        };
        // (Tests do not count: they may reach anywhere to set up a case.)
        let is_test = |f: &Path| {
            f.components()
                .any(|c| c.as_os_str() == "tests" || c.as_os_str() == "tests.rs")
        };
        for f in files
            .into_iter()
            .filter(|f| !is_test(f.strip_prefix(root).unwrap()))
        {
            let rel = f.strip_prefix(root).unwrap();
            // A file at root/node.rs or root/node/mod.rs is one level down; root/node/x.rs two.
            let depth = rel.components().count() - usize::from(rel.ends_with("mod.rs"));
            let up = "super::".repeat(depth);
            let text = std::fs::read_to_string(&f).unwrap();
            // (Comments do not import, nor do tests, which may reach anywhere to set up a case.)
            let code: String = without_test_items(&text)
                .lines()
                .filter(|l| !l.trim_start().starts_with("//"))
                .collect::<Vec<_>>()
                .join("\n");
            for lead in [format!("{prefix}::"), up.clone()] {
                let mut rest = code.as_str();
                while let Some(i) = rest.find(&lead) {
                    let before = &rest[..i];
                    rest = &rest[i + lead.len()..];
                    // `super::super::x` seen from one level down is not `super::x`.
                    if lead == up && (before.ends_with("super::") || before.ends_with("crate::")) {
                        continue;
                    }
                    let names: Vec<String> = if let Some(list) = rest.strip_prefix('{') {
                        let end = list.find('}').unwrap_or(list.len());
                        list[..end]
                            .split(',')
                            .map(|s| s.trim().split("::").next().unwrap_or("").to_string())
                            .collect()
                    } else {
                        vec![rest
                            .chars()
                            .take_while(|c| c.is_alphanumeric() || *c == '_')
                            .collect()]
                    };
                    for n in names {
                        if nodes.contains(&n) && &n != node {
                            edges.insert(n);
                        }
                    }
                }
            }
        }
        graph.insert(node.clone(), edges);
    }
    graph
}

/// A circle of imports in `graph`, if there is one.
fn circle(graph: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    fn visit(
        n: &str,
        g: &BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<String, u8>,
        path: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        state.insert(n.to_string(), 1);
        path.push(n.to_string());
        for m in &g[n] {
            match state.get(m.as_str()).copied().unwrap_or(0) {
                1 => {
                    let at = path.iter().position(|p| p == m).unwrap();
                    let mut c = path[at..].to_vec();
                    c.push(m.clone());
                    return Some(c);
                }
                0 => {
                    if let Some(c) = visit(m, g, state, path) {
                        return Some(c);
                    }
                }
                _ => {}
            }
        }
        path.pop();
        state.insert(n.to_string(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for n in graph.keys() {
        if state.get(n).copied().unwrap_or(0) == 0 {
            if let Some(c) = visit(n, graph, &mut state, &mut Vec::new()) {
                return Some(c);
            }
        }
    }
    None
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

#[test]
fn imports_between_modules_run_one_way() {
    for (dir, prefix) in [
        ("host-adapters/pbrt/src/render", "crate::render"),
        ("host-adapters/pbrt/src", "crate"),
        ("plugin/src/light", "crate::light"),
        ("plugin/dataset/src", "crate"),
        ("plugin/core/src", "crate"),
        ("plugin/src", "crate"),
        ("plugin/src/volume", "crate::volume"),
        ("plugin/src/export", "crate::export"),
    ] {
        let g = module_graph(&root().join(dir), prefix);
        assert!(g.len() >= 3, "{dir}: {} modules found", g.len());
        let mut g = g;
        let mut found = Vec::new();
        while let Some(c) = circle(&g) {
            found.push(c.join(" → "));
            let (a, b) = (c[c.len() - 2].clone(), c[c.len() - 1].clone());
            g.get_mut(&a).unwrap().remove(&b);
        }
        assert!(
            found.is_empty(),
            "{dir}: import circles: {}",
            found.join("; ")
        );
    }
    // Test items are left out, and only they: code after a gated field or function is still read.
    let text = "struct A {\n    #[cfg(test)]\n    n: crate::x::N,\n}\n#[cfg(test)]\nfn f() { if a { crate::y::g() } }\nuse crate::z;\n#[cfg(test)]\nmod tests {\n    use crate::w;\n}\n";
    let kept = without_test_items(text);
    assert!(
        kept.contains("crate::z")
            && !["crate::x", "crate::y", "crate::w"]
                .iter()
                .any(|x| kept.contains(x)),
        "{kept}"
    );
    // The check sees a circle where there is one.
    let mut g = BTreeMap::new();
    g.insert("a".to_string(), BTreeSet::from(["b".to_string()]));
    g.insert("b".to_string(), BTreeSet::from(["a".to_string()]));
    assert_eq!(circle(&g), Some(vec!["a".into(), "b".into(), "a".into()]));
}

#[test]
fn no_source_file_passes_about_800_lines_of_code() {
    let mut over = Vec::new();
    for dir in ["plugin", "host-adapters", "tools"] {
        for f in rust_files(&root().join(dir)) {
            if f.components().any(|c| c.as_os_str() == "target") {
                continue;
            }
            let text = std::fs::read_to_string(&f).unwrap();
            // Lines of code: neither blank nor only a comment.
            let code = text
                .lines()
                .filter(|l| {
                    let t = l.trim();
                    !t.is_empty() && !t.starts_with("//")
                })
                .count();
            if code > 820 {
                over.push(format!(
                    "{} ({code})",
                    f.strip_prefix(root()).unwrap().display()
                ));
            }
        }
    }
    assert!(
        over.is_empty(),
        "files over ~800 lines of code: {}",
        over.join(", ")
    );
}

#[test]
fn architectures_code_map_names_code_that_exists() {
    // Every path ARCHITECTURE.md names in backticks (`render/media.rs`, `plugin/dataset/`, `render/aov`) is a
    // file or folder of the repository, under one of the roots it speaks from — so its entry points lead
    // somewhere. (Install-prefix paths and grid-name patterns are not the repository's.)
    let text = std::fs::read_to_string(root().join("ARCHITECTURE.md")).unwrap();
    let bases = [
        "",
        "host-adapters",
        "host-adapters/pbrt/src",
        "host-adapters/pbrt/src/render",
        "host-adapters/loader",
        "plugin/dataset",
        "plugin",
        "plugin/src",
        "plugin/dataset/src",
        "plugin/core/src",
        "tools",
        "python",
        "tests",
    ];
    let mut named = 0;
    let mut missing = Vec::new();
    for token in text.split('`').skip(1).step_by(2) {
        let t = token.trim_end_matches('/').split("::").next().unwrap_or("");
        let is_path = token.contains('/')
            && !token.contains(char::is_whitespace)
            && !t.contains(['*', '{', '}', '(', ')', '<', '>', '=', '|', ','])
            && !token.starts_with("../")
            && !["bin/", "lib/", "include/"]
                .iter()
                .any(|p| token.starts_with(p))
            && !token.contains(".x/");
        if !is_path {
            continue;
        }
        named += 1;
        let exists = bases.iter().any(|b| {
            let p = root().join(b).join(t);
            p.exists()
                || p.with_extension("rs").is_file()
                || root().join(b).join(format!("{t}.rs")).is_file()
        });
        if !exists {
            missing.push(token.to_string());
        }
    }
    assert!(named > 30, "only {named} paths found");
    assert!(
        missing.is_empty(),
        "ARCHITECTURE.md names what is not there: {missing:?}"
    );
}
