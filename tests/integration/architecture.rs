//! The dependency rule of ARCHITECTURE.md, checked on the source text:
//!
//! - every top-level folder of `src/` is a room with a rank; a file may
//!   name `crate::<room>` only for its own room or a room of lower rank
//!   (`cli` → `service` → `outputs` → `pipeline`, `studies` → `config`,
//!   `io` → core): arrows only point down, and rooms of equal rank do not
//!   import each other;
//! - no module imports from a module that imports it: the graph of `use`s
//!   between modules has no cycle. A file may use its parent's items
//!   (children extend the parent, as `pipeline/align.rs` adds methods to
//!   `Pipeline`), so parent ↔ child edges are containment, not imports;
//! - the core crate depends on faer, realfft, serde and thiserror only and
//!   names no I/O, network, process or clock API.
//!
//! The checker is a plain function of `(path, source)` pairs, so the tests
//! below also show it catching a back-edge and a cycle on made-up sources.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The rooms of `src/` and their ranks: a room may import only from rooms
/// of lower rank.
const ROOMS: [(&str, u32); 7] = [
    ("cli", 5),
    ("service", 4),
    ("outputs", 3),
    ("pipeline", 2),
    ("studies", 2),
    ("config", 1),
    ("io", 1),
];

/// The floors of the core crate (`crates/splinewatch-core/src`) in pipeline
/// order: a floor may import only from floors of lower rank, and no two
/// floors share a rank, so the house reads top-down as the pipeline.
const CORE_ROOMS: [(&str, u32); 8] = [
    ("linalg", 0),
    ("geometry", 1),
    ("model", 2),
    ("solvers", 3),
    ("response", 4),
    ("identification", 5),
    ("updating", 6),
    ("monitoring", 7),
];

/// The largest source file (tests included) of the application, the core
/// and the Python package, and the largest core function, in lines.
const MAX_FILE_LINES: usize = 700;
const CORE_MAX_FUNCTION_LINES: usize = 120;

/// The core crate's only dependencies.
const CORE_DEPENDENCIES: [&str; 5] = ["faer", "realfft", "serde", "statrs", "thiserror"];

/// Names the core crate must not use: I/O, network, processes, the clock,
/// and the application's crates.
const CORE_FORBIDDEN: [&str; 12] = [
    "std::fs",
    "std::net",
    "std::process",
    "std::env",
    "SystemTime",
    "Instant",
    "std::io::stdin",
    "tokio",
    "zenoh",
    "mcap",
    "rerun",
    "println!",
];

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// Every `.rs` file under `dir`, as (path relative to `dir`, text).
fn sources(dir: &Path) -> Vec<(PathBuf, String)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                let text = std::fs::read_to_string(&path).unwrap();
                out.push((path.strip_prefix(dir).unwrap().to_path_buf(), text));
            }
        }
    }
    out.sort();
    out
}

/// The module path of a file: `pipeline/align.rs` → `pipeline::align`,
/// `pipeline/mod.rs` → `pipeline`; `lib.rs` and `main.rs` → the root.
fn module_of(path: &Path) -> Vec<String> {
    let mut parts: Vec<String> = path
        .iter()
        .map(|p| p.to_string_lossy().trim_end_matches(".rs").to_string())
        .collect();
    if matches!(parts.last().map(String::as_str), Some("mod" | "lib" | "main")) {
        parts.pop();
    }
    parts
}

/// The source without comments, string and character literals, with line
/// numbers kept (removed text becomes spaces, newlines stay).
fn code_only(text: &str) -> String {
    let b: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    let blank = |c: char| if c == '\n' { '\n' } else { ' ' };
    while i < b.len() {
        let c = b[i];
        let next = b.get(i + 1).copied();
        if c == '/' && next == Some('/') {
            while i < b.len() && b[i] != '\n' {
                out.push(' ');
                i += 1;
            }
        } else if c == '/' && next == Some('*') {
            let mut depth = 0;
            while i < b.len() {
                if b[i] == '/' && b.get(i + 1) == Some(&'*') {
                    depth += 1;
                    out.push_str("  ");
                    i += 2;
                } else if b[i] == '*' && b.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    out.push_str("  ");
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    out.push(blank(b[i]));
                    i += 1;
                }
            }
        } else if c == 'r' && (next == Some('"') || next == Some('#')) && !is_ident(b.get(i.wrapping_sub(1))) {
            // Raw string r#"…"#: find the closing quote with as many hashes.
            let mut j = i + 1;
            let mut hashes = 0;
            while b.get(j) == Some(&'#') {
                hashes += 1;
                j += 1;
            }
            if b.get(j) != Some(&'"') {
                out.push(c);
                i += 1;
                continue;
            }
            j += 1;
            while j < b.len() && !(b[j] == '"' && (0..hashes).all(|h| b.get(j + 1 + h) == Some(&'#'))) {
                j += 1;
            }
            let end = (j + 1 + hashes).min(b.len());
            out.extend(b[i..end].iter().map(|&c| blank(c)));
            i = end;
        } else if c == '"' {
            out.push(' ');
            i += 1;
            while i < b.len() && b[i] != '"' {
                if b[i] == '\\' {
                    out.push(' ');
                    i += 1;
                }
                if i < b.len() {
                    out.push(blank(b[i]));
                    i += 1;
                }
            }
            out.push(' ');
            i += 1;
        } else if c == '\'' && (b.get(i + 2) == Some(&'\'') || next == Some('\\')) {
            // A character literal ('x' or '\n'); a lifetime ('a) is kept.
            out.push(' ');
            i += 1;
            while i < b.len() && b[i] != '\'' {
                if b[i] == '\\' {
                    out.push(' ');
                    i += 1;
                }
                out.push(' ');
                i += 1;
            }
            out.push(' ');
            i += 1;
        } else {
            out.push(c);
            i += 1;
        }
    }
    out
}

fn is_ident(c: Option<&char>) -> bool {
    c.is_some_and(|c| c.is_alphanumeric() || *c == '_')
}

/// The module paths a file names, with their lines: `crate::a::b`,
/// `crate::{a, b::c}`, `super::x` (resolved against the file's module).
fn references(module: &[String], code: &str) -> Vec<(usize, Vec<String>)> {
    let mut out = Vec::new();
    for (start, prefix) in [("crate::", 0usize), ("super::", 1)] {
        for (at, _) in code.match_indices(start) {
            if is_ident(code[..at].chars().last().as_ref()) {
                continue;
            }
            let line = code[..at].matches('\n').count() + 1;
            // `super` is the parent of the file's module (of `a` for `a/b.rs`
            // and for `a/b/mod.rs`); chained `super::super::` climbs further.
            let mut base: Vec<String> = if prefix == 0 {
                Vec::new()
            } else {
                let mut m = module.to_vec();
                m.pop();
                m
            };
            let mut rest = &code[at + start.len()..];
            while let Some(r) = rest.strip_prefix("super::") {
                base.pop();
                rest = r;
            }
            for path in expand(rest) {
                let mut full = base.clone();
                full.extend(path);
                out.push((line, full));
            }
        }
    }
    out
}

/// `a::b::C` → [[a, b, C]]; `{a, b::{c, d}}` → [[a], [b, c], [b, d]].
fn expand(rest: &str) -> Vec<Vec<String>> {
    let rest = rest.trim_start();
    if let Some(group) = rest.strip_prefix('{') {
        let mut depth = 0;
        let mut end = group.len();
        for (i, ch) in group.char_indices() {
            match ch {
                '{' => depth += 1,
                '}' if depth == 0 => {
                    end = i;
                    break;
                }
                '}' => depth -= 1,
                _ => {}
            }
        }
        let inner = &group[..end];
        let mut items = Vec::new();
        let (mut depth, mut from) = (0, 0);
        for (i, ch) in inner.char_indices() {
            match ch {
                '{' => depth += 1,
                '}' => depth -= 1,
                ',' if depth == 0 => {
                    items.push(&inner[from..i]);
                    from = i + 1;
                }
                _ => {}
            }
        }
        items.push(&inner[from..]);
        return items
            .into_iter()
            .filter(|s| !s.trim().is_empty())
            .flat_map(expand)
            .collect();
    }
    let ident: String = rest.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
    if ident.is_empty() || ident == "self" {
        return vec![Vec::new()];
    }
    let after = &rest[ident.len()..];
    match after.strip_prefix("::") {
        Some(more) => expand(more)
            .into_iter()
            .map(|mut p| {
                p.insert(0, ident.clone());
                p
            })
            .collect(),
        None => vec![vec![ident]],
    }
}

/// Checks the dependency rule of the application's rooms over `files`
/// (paths relative to `src/`); returns one line per violation.
fn check(files: &[(PathBuf, String)]) -> Vec<String> {
    check_rooms(&ROOMS, "src", files)
}

/// Checks the dependency rule over `files` (paths relative to `dir`) with
/// the given rooms and ranks; returns one line per violation.
fn check_rooms(rooms: &[(&str, u32)], dir: &str, files: &[(PathBuf, String)]) -> Vec<String> {
    let rank: BTreeMap<&str, u32> = rooms.iter().copied().collect();
    let modules: BTreeSet<Vec<String>> = files.iter().map(|(p, _)| module_of(p)).collect();
    let mut problems = Vec::new();
    let mut edges: BTreeMap<Vec<String>, BTreeSet<Vec<String>>> = BTreeMap::new();
    for (path, text) in files {
        let module = module_of(path);
        let Some(room) = module.first() else { continue };
        let Some(&own_rank) = rank.get(room.as_str()) else {
            problems.push(format!(
                "{dir}/{}: {room:?} is not a room of the dependency rule",
                path.display()
            ));
            continue;
        };
        for (line, target) in references(&module, &code_only(text)) {
            let Some(target_room) = target.first() else { continue };
            if target_room != room {
                match rank.get(target_room.as_str()) {
                    Some(&r) if r < own_rank => {}
                    Some(&r) => problems.push(format!(
                        "{dir}/{}:{line}: {room} (rank {own_rank}) imports crate::{} (rank {r}): arrows must point down",
                        path.display(),
                        target.join("::")
                    )),
                    None => problems.push(format!(
                        "{dir}/{}:{line}: crate::{} is outside every room",
                        path.display(),
                        target.join("::")
                    )),
                }
            }
            // The module the path lands in: its longest prefix that is a file.
            let Some(to) = (1..=target.len())
                .rev()
                .map(|n| target[..n].to_vec())
                .find(|p| modules.contains(p))
            else {
                continue;
            };
            let contains = |a: &[String], b: &[String]| b.starts_with(a);
            if to != module && !contains(&to, &module) && !contains(&module, &to) {
                edges.entry(module.clone()).or_default().insert(to);
            }
        }
    }
    problems.extend(cycles(&edges));
    problems
}

/// Every cycle of the module graph (one report per strongly connected set).
fn cycles(edges: &BTreeMap<Vec<String>, BTreeSet<Vec<String>>>) -> Vec<String> {
    let mut reported: BTreeSet<Vec<String>> = BTreeSet::new();
    let mut out = Vec::new();
    for start in edges.keys() {
        // Depth-first search for a path back to `start`.
        let mut stack = vec![(start.clone(), vec![start.clone()])];
        let mut seen = BTreeSet::new();
        while let Some((node, path)) = stack.pop() {
            for next in edges.get(&node).into_iter().flatten() {
                if next == start {
                    let mut members: Vec<String> = path.iter().map(|m| m.join("::")).collect();
                    members.sort();
                    if reported.insert(members.clone()) {
                        let ring: Vec<String> = path.iter().chain([start]).map(|m| m.join("::")).collect();
                        out.push(format!("import cycle: {}", ring.join(" → ")));
                    }
                } else if seen.insert(next.clone()) {
                    let mut p = path.clone();
                    p.push(next.clone());
                    stack.push((next.clone(), p));
                }
            }
        }
    }
    out
}

#[test]
fn application_imports_only_point_down_and_never_in_a_circle() {
    let files: Vec<_> = sources(&root().join("src"))
        .into_iter()
        .filter(|(p, _)| !matches!(p.to_str(), Some("lib.rs" | "main.rs")))
        .collect();
    assert!(files.len() > 40, "found only {} source files", files.len());
    let problems = check(&files);
    assert!(problems.is_empty(), "dependency rule broken:\n{}", problems.join("\n"));
    // Every room exists, and no file lies outside the rooms.
    let rooms: BTreeSet<String> = files
        .iter()
        .filter_map(|(p, _)| module_of(p).first().cloned())
        .collect();
    let expected: BTreeSet<String> = ROOMS.iter().map(|(r, _)| r.to_string()).collect();
    assert_eq!(rooms, expected);
}

#[test]
fn every_room_says_what_it_may_import() {
    for (room, _) in ROOMS {
        let text = std::fs::read_to_string(root().join("src").join(room).join("mod.rs")).unwrap();
        let head: Vec<&str> = text.lines().take(6).collect();
        assert!(
            head.iter().any(|l| l.starts_with("//!") && l.contains("May import")),
            "src/{room}/mod.rs does not open with what it may import"
        );
    }
}

#[test]
fn the_core_crate_does_no_io() {
    let manifest = std::fs::read_to_string(root().join("crates/splinewatch-core/Cargo.toml")).unwrap();
    let manifest: toml::Table = toml::from_str(&manifest).unwrap();
    let deps: BTreeSet<&str> = manifest["dependencies"]
        .as_table()
        .unwrap()
        .keys()
        .map(String::as_str)
        .collect();
    assert_eq!(deps, CORE_DEPENDENCIES.into_iter().collect());
    for (path, text) in sources(&root().join("crates/splinewatch-core/src")) {
        let code = code_only(&text);
        for name in CORE_FORBIDDEN {
            assert!(
                !code.contains(name),
                "crates/splinewatch-core/src/{} uses {name}: the core crate does no I/O",
                path.display()
            );
        }
    }
}

/// The rooms of the application the Python package (python/, a thin shell
/// like `cli`) may reach: the daemon's rooms are not in its build.
const PYTHON_ROOMS: [&str; 4] = ["config", "io", "pipeline", "studies"];

/// The Python package depends on the core and the application built
/// without its daemon (no zenoh, Rerun or tokio: it builds in minutes),
/// and names only the rooms of that build.
#[test]
fn the_python_package_is_a_thin_shell_without_the_daemon() {
    let manifest = std::fs::read_to_string(root().join("python/Cargo.toml")).unwrap();
    let manifest: toml::Table = toml::from_str(&manifest).unwrap();
    let deps = manifest["dependencies"].as_table().unwrap();
    assert_eq!(
        deps["splinewatch"].get("default-features").and_then(|v| v.as_bool()),
        Some(false),
        "python/Cargo.toml must take the application without its `daemon` feature"
    );
    for forbidden in ["zenoh", "rerun", "tokio"] {
        assert!(
            !deps.contains_key(forbidden),
            "python/Cargo.toml depends on {forbidden}"
        );
    }
    let files = sources(&root().join("python/src"));
    assert!(files.len() >= 4, "found only {} Python-binding sources", files.len());
    for (path, text) in files {
        let code = code_only(&text);
        for (at, _) in code.match_indices("splinewatch::") {
            let room: String = code[at + "splinewatch::".len()..]
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            assert!(
                PYTHON_ROOMS.contains(&room.as_str()),
                "python/src/{} names splinewatch::{room}: the package reaches only {PYTHON_ROOMS:?}",
                path.display()
            );
        }
    }
}

fn core_sources() -> Vec<(PathBuf, String)> {
    sources(&root().join("crates/splinewatch-core/src"))
        .into_iter()
        .filter(|(p, _)| p.to_str() != Some("lib.rs"))
        .collect()
}

#[test]
fn core_imports_follow_the_pipeline_and_never_in_a_circle() {
    let files = core_sources();
    assert!(files.len() > 30, "found only {} core source files", files.len());
    let problems = check_rooms(&CORE_ROOMS, "crates/splinewatch-core/src", &files);
    assert!(
        problems.is_empty(),
        "core dependency rule broken:\n{}",
        problems.join("\n")
    );
    let floors: BTreeSet<String> = files
        .iter()
        .filter_map(|(p, _)| module_of(p).first().cloned())
        .collect();
    let expected: BTreeSet<String> = CORE_ROOMS.iter().map(|(r, _)| r.to_string()).collect();
    assert_eq!(floors, expected);
    // The crate root declares the floors in pipeline order.
    let lib = std::fs::read_to_string(root().join("crates/splinewatch-core/src/lib.rs")).unwrap();
    let declared: Vec<&str> = lib
        .lines()
        .filter_map(|l| l.strip_prefix("pub mod ")?.strip_suffix(';'))
        .collect();
    let mut by_rank = CORE_ROOMS;
    by_rank.sort_by_key(|(_, r)| *r);
    assert_eq!(declared, by_rank.map(|(r, _)| r));
}

#[test]
fn every_core_floor_says_what_it_may_import() {
    let src = root().join("crates/splinewatch-core/src");
    for (floor, _) in CORE_ROOMS {
        let folder = src.join(floor).join("mod.rs");
        let path = if folder.exists() {
            folder
        } else {
            src.join(format!("{floor}.rs"))
        };
        let text = std::fs::read_to_string(&path).unwrap();
        let head: Vec<&str> = text.lines().take(6).collect();
        assert!(
            head.iter().any(|l| l.starts_with("//!") && l.contains("May import")),
            "{} does not open with what it may import",
            path.display()
        );
    }
}

/// Every `fn` with a body in `code` (comments and literals removed): its
/// name, first line and length in lines, signature to closing brace.
fn function_lengths(code: &str) -> Vec<(String, usize, usize)> {
    let bytes = code.as_bytes();
    let mut out = Vec::new();
    for (at, _) in code.match_indices("fn ") {
        if is_ident(code[..at].chars().last().as_ref()) {
            continue;
        }
        let name: String = code[at + 3..]
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        if name.is_empty() {
            continue;
        }
        let rest = &code[at..];
        let (Some(brace), semi) = (rest.find('{'), rest.find(';')) else {
            continue;
        };
        if semi.is_some_and(|s| s < brace) {
            continue; // a declaration without a body (trait method)
        }
        let mut depth = 0usize;
        let mut end = at + brace;
        for (i, &b) in bytes.iter().enumerate().skip(at + brace) {
            match b {
                b'{' => depth += 1,
                b'}' => {
                    depth -= 1;
                    if depth == 0 {
                        end = i;
                        break;
                    }
                }
                _ => {}
            }
        }
        let first = code[..at].matches('\n').count() + 1;
        let last = code[..end].matches('\n').count() + 1;
        out.push((name, first, last - first + 1));
    }
    out
}

#[test]
fn source_files_and_core_functions_stay_readable() {
    let mut problems = Vec::new();
    for dir in ["src", "crates/splinewatch-core/src", "python/src"] {
        for (path, text) in sources(&root().join(dir)) {
            let lines = text.lines().count();
            if lines > MAX_FILE_LINES {
                problems.push(format!(
                    "{dir}/{}: {lines} lines (at most {MAX_FILE_LINES})",
                    path.display()
                ));
            }
        }
    }
    for (path, text) in core_sources() {
        for (name, line, length) in function_lengths(&code_only(&text)) {
            if length > CORE_MAX_FUNCTION_LINES {
                problems.push(format!(
                    "{}:{line}: fn {name} is {length} lines (at most {CORE_MAX_FUNCTION_LINES})",
                    path.display()
                ));
            }
        }
    }
    assert!(problems.is_empty(), "split these:\n{}", problems.join("\n"));
    // The measure itself, on a made-up source.
    let lengths = function_lengths(&code_only("trait T { fn a(); }\nfn b() {\n  if x { y() }\n}\n"));
    assert_eq!(lengths, [("b".to_string(), 2, 3)]);
}

fn made_up(files: &[(&str, &str)]) -> Vec<(PathBuf, String)> {
    files.iter().map(|(p, t)| (PathBuf::from(p), t.to_string())).collect()
}

#[test]
fn the_checker_catches_a_back_edge_and_a_cycle() {
    // outputs (rank 3) reaching up into service (rank 4), inside a group.
    let problems = check(&made_up(&[
        (
            "outputs/mod.rs",
            "use crate::{pipeline::Health, service::daemon::Thing};",
        ),
        ("pipeline/mod.rs", "pub struct Health;"),
        ("service/daemon.rs", "use crate::config::Config;"),
    ]));
    assert_eq!(problems.len(), 1, "{problems:?}");
    assert!(problems[0].contains("src/outputs/mod.rs:1") && problems[0].contains("crate::service::daemon::Thing"));
    // Equal ranks do not import each other.
    let problems = check(&made_up(&[("studies/mod.rs", "fn f() { crate::pipeline::run(); }")]));
    assert_eq!(problems.len(), 1, "{problems:?}");
    // Two sibling files importing each other, one through `super`.
    let problems = check(&made_up(&[
        ("pipeline/mod.rs", "mod a; mod b;"),
        ("pipeline/a.rs", "use super::b::B;"),
        ("pipeline/b.rs", "use crate::pipeline::a::A;"),
    ]));
    assert_eq!(problems, ["import cycle: pipeline::a → pipeline::b → pipeline::a"]);
    // A child using its parent's items is not a cycle; comments and strings are not imports.
    let problems = check(&made_up(&[
        ("pipeline/mod.rs", "mod a; use a::A; pub struct P;"),
        (
            "pipeline/a.rs",
            "use super::P; // crate::service\nconst S: &str = \"crate::cli\";",
        ),
    ]));
    assert!(problems.is_empty(), "{problems:?}");
}
