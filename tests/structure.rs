//! The code's shape, checked: no source file over 800 lines, and no two source files of a crate that import
//! each other (inside a crate dependencies run one way; a piece two files share lives below both).
//!
//! "Imports" are the paths a file names through `crate::` or `super::` (in `use` lines and in code) and the
//! child modules a file uses by name; a path through the crate root's `pub use` list counts as the module that
//! defines the item. Code after a file's `#[cfg(test)]` module is not read: a test may use anything.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The longest a source file may be.
const MAX_LINES: usize = 800;

/// Every `.rs` file below `dir`, sorted.
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&d) else { continue };
        for e in entries.flatten() {
            let p = e.path();
            if p.is_dir() {
                if p.file_name().is_some_and(|n| n != "target") {
                    stack.push(p);
                }
            } else if p.extension().is_some_and(|x| x == "rs") {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// The source trees of the workspace: each crate's `src` (a crate root `lib.rs` or `main.rs`).
fn source_trees(repo: &Path) -> Vec<PathBuf> {
    let mut trees = vec![repo.join("src"), repo.join("dev/src")];
    if let Ok(entries) = std::fs::read_dir(repo.join("crates")) {
        let mut crates: Vec<PathBuf> = entries.flatten().map(|e| e.path().join("src")).filter(|p| p.is_dir()).collect();
        crates.sort();
        trees.extend(crates);
    }
    trees
}

/// The module path of a file of the tree rooted at `src` (`[]` for the crate root, `["a", "b"]` for `a/b.rs` or
/// `a/b/mod.rs`); `None` for files that are not modules of the crate (binaries under `src/bin`).
fn module_path(src: &Path, file: &Path) -> Option<Vec<String>> {
    let rel = file.strip_prefix(src).ok()?;
    let mut parts: Vec<String> = rel.iter().map(|s| s.to_string_lossy().into_owned()).collect();
    if parts.first().is_some_and(|p| p == "bin") {
        return None;
    }
    let last = parts.pop()?;
    let stem = last.trim_end_matches(".rs");
    if !(stem == "mod" || (parts.is_empty() && (stem == "lib" || stem == "main"))) {
        parts.push(stem.to_string());
    }
    Some(parts)
}

/// The text a file's imports are read from: comments and the `#[cfg(test)]` module onwards left out.
fn code_of(text: &str) -> String {
    let mut out = String::new();
    let mut lines = text.lines().peekable();
    while let Some(line) = lines.next() {
        let t = line.trim_start();
        if t.starts_with("#[cfg(test)]") && lines.peek().is_some_and(|n| n.trim_start().starts_with("mod ")) {
            break;
        }
        if t.starts_with("//") {
            continue;
        }
        let code = match line.find("//") {
            Some(i) if !line[..i].contains('"') => &line[..i],
            _ => line,
        };
        out.push_str(code);
        out.push('\n');
    }
    out
}

fn is_ident(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_'
}

/// The paths that follow `prefix` (`crate::` or `super::`) in `code`, braces expanded one level:
/// `crate::{a::X, b}` gives `a::X` and `b`.
fn paths_after(code: &str, prefix: &str) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    let mut at = 0;
    while let Some(i) = code[at..].find(prefix) {
        let start = at + i;
        at = start + prefix.len();
        if start > 0 && code[..start].chars().next_back().is_some_and(|c| is_ident(c) || c == ':') {
            continue;
        }
        let rest = &code[at..];
        if let Some(group) = rest.strip_prefix('{') {
            let end = group.find('}').unwrap_or(group.len());
            for item in group[..end].split(',') {
                let segs: Vec<String> = item.trim().split("::").map(|s| s.trim().to_string()).collect();
                if segs.first().is_some_and(|s| !s.is_empty() && s.chars().all(is_ident)) {
                    out.push(segs.into_iter().take_while(|s| s.chars().all(is_ident) && !s.is_empty()).collect());
                }
            }
        } else {
            let mut segs = Vec::new();
            let mut s = rest;
            loop {
                let n = s.find(|c: char| !is_ident(c)).unwrap_or(s.len());
                if n == 0 {
                    break;
                }
                segs.push(s[..n].to_string());
                match s[n..].strip_prefix("::") {
                    Some(r) if r.starts_with(|c: char| is_ident(c)) => s = r,
                    _ => break,
                }
            }
            if !segs.is_empty() {
                out.push(segs);
            }
        }
    }
    out
}

/// The names a crate root re-exports, each with the module path it comes from (`pub use a::b::{X, Y};`).
fn root_reexports(root_code: &str) -> BTreeMap<String, Vec<String>> {
    let mut out = BTreeMap::new();
    for stmt in root_code.split(';') {
        let Some(body) = stmt.trim().strip_prefix("pub use ") else { continue };
        let body: String = body.split_whitespace().collect::<Vec<_>>().join(" ");
        let (module, names) = match body.find("::{") {
            Some(i) => (&body[..i], body[i + 3..].trim_end_matches('}').to_string()),
            None => match body.rfind("::") {
                Some(i) => (&body[..i], body[i + 2..].to_string()),
                None => continue,
            },
        };
        let module: Vec<String> = module.split("::").map(str::to_string).collect();
        for name in names.split(',') {
            let name = name.trim();
            if !name.is_empty() && name.chars().all(is_ident) {
                out.insert(name.to_string(), module.clone());
            }
        }
    }
    out
}

/// Pairs of files of one crate that import each other.
fn mutual_imports(src: &Path) -> Vec<(PathBuf, PathBuf)> {
    let files: Vec<(Vec<String>, PathBuf)> =
        rust_files(src).into_iter().filter_map(|f| module_path(src, &f).map(|m| (m, f))).collect();
    let by_module: BTreeMap<Vec<String>, PathBuf> = files.iter().map(|(m, f)| (m.clone(), f.clone())).collect();
    let root_code = by_module.get(&Vec::new()).map(|f| code_of(&std::fs::read_to_string(f).unwrap_or_default()));
    let reexports = root_code.as_deref().map(root_reexports).unwrap_or_default();
    // The file that defines what `path` (absolute, from the crate root) names.
    let resolve = |path: &[String]| -> Option<&PathBuf> {
        let mut path = path.to_vec();
        if !by_module.contains_key(&path[..1.min(path.len())])
            && let Some(m) = path.first().and_then(|p| reexports.get(p))
        {
            path = m.clone();
        }
        (0..=path.len()).rev().find_map(|n| by_module.get(&path[..n]))
    };
    let mut edges: BTreeSet<(PathBuf, PathBuf)> = BTreeSet::new();
    for (module, file) in &files {
        let code = code_of(&std::fs::read_to_string(file).unwrap_or_default());
        let is_dir_module = file.file_name().is_some_and(|n| n == "mod.rs" || n == "lib.rs" || n == "main.rs");
        let mut targets: Vec<Vec<String>> = paths_after(&code, "crate::");
        for rel in paths_after(&code, "super::") {
            // `super` of `a/b.rs` is `a`; of `a/b/mod.rs` it is `a` too (the module `a::b`'s parent).
            let mut base = module.clone();
            base.pop();
            let mut rel = rel.as_slice();
            while rel.first().is_some_and(|s| s == "super") {
                base.pop();
                rel = &rel[1..];
            }
            targets.push(base.into_iter().chain(rel.iter().cloned()).collect());
        }
        // A module's children used by name (`use child::X;`, not the `pub use` that re-exports them).
        if is_dir_module {
            for stmt in code.split(';') {
                let t = stmt.trim();
                if let Some(p) = t.strip_prefix("use ") {
                    let head: String = p.chars().take_while(|&c| is_ident(c)).collect();
                    let child: Vec<String> = module.iter().cloned().chain([head]).collect();
                    if by_module.contains_key(&child) {
                        targets.push(child);
                    }
                }
            }
        }
        for t in targets {
            if let Some(g) = resolve(&t)
                && g != file
            {
                edges.insert((file.clone(), g.clone()));
            }
        }
    }
    edges.iter().filter(|(a, b)| a < b && edges.contains(&(b.clone(), a.clone()))).cloned().collect()
}

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn no_source_file_is_over_800_lines() {
    let repo = repo();
    let mut dirs = source_trees(&repo);
    dirs.push(repo.join("tests"));
    for c in std::fs::read_dir(repo.join("crates")).unwrap().flatten() {
        dirs.extend(["tests", "benches"].map(|d| c.path().join(d)));
    }
    let long: Vec<String> = dirs
        .iter()
        .flat_map(|d| rust_files(d))
        .filter_map(|f| {
            let n = std::fs::read_to_string(&f).unwrap().lines().count();
            (n > MAX_LINES).then(|| format!("{} ({n} lines)", f.strip_prefix(&repo).unwrap().display()))
        })
        .collect();
    assert!(long.is_empty(), "source files over {MAX_LINES} lines: {long:#?}");
}

#[test]
fn no_two_source_files_import_each_other() {
    let repo = repo();
    let pairs: Vec<String> = source_trees(&repo)
        .iter()
        .flat_map(|src| mutual_imports(src))
        .map(|(a, b)| {
            format!("{} <-> {}", a.strip_prefix(&repo).unwrap().display(), b.strip_prefix(&repo).unwrap().display())
        })
        .collect();
    assert!(pairs.is_empty(), "files that import each other: {pairs:#?}");
}

#[test]
fn the_import_reader_sees_what_a_module_names() {
    let code =
        code_of("use crate::{grid::X, pose};\n// crate::comment::Y\nfn f() { super::sib::g(); x_crate::no(); }\n");
    assert_eq!(paths_after(&code, "crate::"), vec![vec!["grid".to_string(), "X".into()], vec!["pose".into()]]);
    assert_eq!(paths_after(&code, "super::"), vec![vec!["sib".to_string(), "g".into()]]);
    let re = root_reexports("pub use a::b::{X, Y};\npub use c::Z;\nmod q;");
    assert_eq!(re.get("Y"), Some(&vec!["a".to_string(), "b".into()]));
    assert_eq!(re.get("Z"), Some(&vec!["c".to_string()]));
}
