//! The guide and the README stay true (issue 47): the generated reference
//! pages are what the code generates now, every TOML block validates (a
//! fragment inside the bundled config), every command a shell block names
//! exists with the flags it is given, the blocks marked `sh,runnable`
//! run on the bundled data, and those marked `console,tested` print what
//! they show. A TOML block is a fragment laid over
//! `config/sinello.toml`, or over the config its fence names
//! (`toml,config=config/painter-street.toml`), or a whole config when it
//! names its `[structure]`; a block that names a deployed site's files
//! (`toml,site-files`: certificates, a token) is checked key by key but not
//! against this machine's files. `SPLINEWATCH_BLESS=1` rewrites stale generated
//! pages instead of failing.

use crate::common::splinewatch;
use splinewatch::config::Config;
use std::path::{Path, PathBuf};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// README.md and every page of the guide, with their text.
fn pages() -> Vec<(PathBuf, String)> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                walk(&path, out);
            } else if path.extension().is_some_and(|e| e == "md") {
                out.push(path);
            }
        }
    }
    let mut paths = vec![root().join("README.md")];
    walk(&root().join("docs/guide/src"), &mut paths);
    paths.sort();
    paths
        .into_iter()
        .map(|p| {
            let text = std::fs::read_to_string(&p).unwrap();
            (p.strip_prefix(root()).unwrap().to_path_buf(), text)
        })
        .collect()
}

/// The fenced code blocks of `text` (also indented ones, in list items):
/// (info string, body without the fence's indentation, line of the fence).
fn blocks(text: &str) -> Vec<(String, String, usize)> {
    let mut out = Vec::new();
    let mut open: Option<(String, String, usize, usize)> = None;
    for (n, line) in text.lines().enumerate() {
        let trimmed = line.trim_start();
        let indent = line.len() - trimmed.len();
        match (&mut open, trimmed.strip_prefix("```")) {
            (None, Some(info)) => open = Some((info.trim().to_string(), String::new(), n + 1, indent)),
            (Some(_), Some(rest)) if rest.trim().is_empty() => {
                let (info, body, at, _) = open.take().unwrap();
                out.push((info, body, at));
            }
            (Some((_, body, _, fence)), _) => {
                body.push_str(line.get(*fence..).unwrap_or(trimmed));
                body.push('\n');
            }
            (None, None) => {}
        }
    }
    out
}

#[test]
fn the_generated_reference_pages_are_current() {
    let bless = std::env::var("SPLINEWATCH_BLESS").is_ok_and(|v| v == "1");
    let reference = root().join("docs/guide/src/reference");
    let pages = [
        (vec!["reference", "cli"], "cli.md"),
        (vec!["reference", "config"], "config-keys.md"),
        (vec!["reference", "topics"], "results-topics.md"),
        (vec!["config-schema"], "splinewatch.schema.json"),
    ];
    let mut stale = Vec::new();
    for (args, file) in pages {
        let out = splinewatch(&args);
        assert!(
            out.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let generated = String::from_utf8(out.stdout).unwrap();
        let path = reference.join(file);
        if std::fs::read_to_string(&path).ok().as_deref() != Some(generated.as_str()) {
            if bless {
                std::fs::write(&path, &generated).unwrap();
            } else {
                stale.push(file);
            }
        }
    }
    assert!(
        stale.is_empty(),
        "stale generated pages {stale:?}: run `SPLINEWATCH_BLESS=1 cargo test --test integration guide::`"
    );
}

/// `a` with `b`'s keys laid over it (tables merged key by key).
fn merge(a: &mut toml::Table, b: toml::Table) {
    for (key, value) in b {
        match (a.get_mut(&key), value) {
            (Some(toml::Value::Table(inner)), toml::Value::Table(over)) => merge(inner, over),
            (_, value) => {
                a.insert(key, value);
            }
        }
    }
}

#[test]
fn every_toml_block_of_the_guide_and_readme_validates() {
    let read =
        |file: &str| -> toml::Table { toml::from_str(&std::fs::read_to_string(root().join(file)).unwrap()).unwrap() };
    let mut checked = 0;
    for (page, text) in pages() {
        for (info, body, line) in blocks(&text) {
            let mut parts = info.split(',');
            if parts.next() != Some("toml") {
                continue;
            }
            let base = read(
                parts
                    .find_map(|p| p.strip_prefix("config="))
                    .unwrap_or("config/sinello.toml"),
            );
            let fragment: toml::Table =
                toml::from_str(&body).unwrap_or_else(|e| panic!("{}:{line}: not TOML: {e}", page.display()));
            // A whole config (it names its structure) stands alone; a
            // fragment is laid over the bundled deck.
            let mut config = if fragment.contains_key("structure") {
                toml::Table::new()
            } else {
                base.clone()
            };
            if fragment.get("model").and_then(|m| m.get("patches")).is_some() {
                if let Some(toml::Value::Table(model)) = config.get_mut("model") {
                    for key in ["geometry", "discretization", "material", "springs"] {
                        model.remove(key);
                    }
                }
            }
            merge(&mut config, fragment);
            let text = toml::to_string(&config).unwrap();
            let site_files = info.split(',').any(|p| p == "site-files");
            let parsed = Config::from_toml(&text).and_then(|c| if site_files { Ok(()) } else { c.validate() });
            if let Err(e) = parsed {
                panic!("{}:{line}: the TOML block does not validate: {e}", page.display());
            }
            checked += 1;
        }
    }
    assert!(checked >= 4, "only {checked} TOML blocks found");
}

/// The command and flags of a shell line that runs splinewatch.
fn invocation(line: &str) -> Option<(String, Vec<String>)> {
    let line = line
        .split(" #")
        .next()
        .unwrap_or(line)
        .trim()
        .trim_start_matches("$ ")
        .trim_end_matches('\\')
        .trim();
    let rest = [
        "cargo run --release -- ",
        "cargo run --quiet -- ",
        "cargo run -- ",
        "splinewatch ",
    ]
    .iter()
    .find_map(|p| line.strip_prefix(p))?;
    let mut words = rest.split_whitespace();
    let command = words.next()?.to_string();
    // A synopsis's optional flags count too: `[--count N]`, `(--frf FILE`.
    let flags = words
        .map(|w| w.trim_start_matches(['[', '(']))
        .filter(|w| w.starts_with("--"))
        .map(|w| {
            w.split('=')
                .next()
                .unwrap()
                .trim_end_matches([']', ')', '…'])
                .to_string()
        })
        .collect();
    Some((command, flags))
}

#[test]
fn every_command_a_shell_block_names_exists_with_its_flags() {
    let mut checked = Vec::new();
    for (page, text) in pages() {
        for (info, body, line) in blocks(&text) {
            if !matches!(info.split(',').next(), Some("sh" | "console" | "bash")) {
                continue;
            }
            for (command, flags) in body.lines().filter_map(invocation) {
                let help = splinewatch(&[&command, "--help"]);
                assert!(
                    help.status.success(),
                    "{}:{line}: `splinewatch {command}` no longer exists",
                    page.display()
                );
                let help = String::from_utf8_lossy(&help.stdout).into_owned();
                for flag in flags {
                    assert!(
                        help.contains(&format!("{flag} "))
                            || help.contains(&format!("{flag}\n"))
                            || help.contains(&format!("{flag},")),
                        "{}:{line}: `splinewatch {command}` has no {flag}",
                        page.display()
                    );
                }
                checked.push(command);
            }
        }
    }
    for needed in ["demo", "oma", "replay", "simulate"] {
        assert!(checked.iter().any(|c| c == needed), "no shell block runs `{needed}`");
    }
    // The README's quick start: the main job and the test command.
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    assert!(readme.contains("cargo run -- demo") && readme.contains("cargo test --workspace"));
}

#[test]
fn the_blocks_marked_runnable_run_on_the_bundled_data() {
    let scratch = crate::common::fresh_dir("guide-runnable");
    let mut ran = 0;
    for (page, text) in pages() {
        for (info, body, line) in blocks(&text) {
            if info != "sh,runnable" {
                continue;
            }
            for l in body.lines() {
                let l = l.split(" #").next().unwrap().trim();
                let Some(rest) = ["cargo run --release -- ", "cargo run -- ", "splinewatch "]
                    .iter()
                    .find_map(|p| l.strip_prefix(p))
                else {
                    assert!(
                        l.is_empty(),
                        "{}:{line}: a runnable block runs only splinewatch: {l}",
                        page.display()
                    );
                    continue;
                };
                // The guide's `/tmp/…` files go to a folder of this run's own.
                let args: Vec<String> = rest
                    .split_whitespace()
                    .map(|a| match a.strip_prefix("/tmp/") {
                        Some(name) => scratch.join(name).to_string_lossy().into_owned(),
                        None => a.to_string(),
                    })
                    .collect();
                let args: Vec<&str> = args.iter().map(String::as_str).collect();
                let out = splinewatch(&args);
                assert!(
                    out.status.success(),
                    "{}:{line}: `{l}` failed: {}",
                    page.display(),
                    String::from_utf8_lossy(&out.stderr)
                );
                ran += 1;
            }
        }
    }
    assert!(ran >= 2, "only {ran} runnable commands in the guide");
}

/// A printed line with its figures masked: every number (a sign, digits,
/// a decimal point, an exponent) one `#`, the spaces between words one.
/// What a listing shows is compared this way: the words, the columns and
/// their order must be what the program prints, the figures may vary.
fn masked(line: &str) -> String {
    let mut out = String::new();
    let chars: Vec<char> = line.chars().collect();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let starts_number = c.is_ascii_digit()
            || (matches!(c, '-' | '+' | '.' | '−')
                && chars.get(i + 1).is_some_and(char::is_ascii_digit)
                && (i == 0 || !chars[i - 1].is_alphanumeric()));
        if starts_number {
            i += 1;
            while i < chars.len() {
                let d = chars[i];
                let exponent_sign = matches!(d, '-' | '+') && matches!(chars[i - 1], 'e' | 'E');
                let exponent = matches!(d, 'e' | 'E')
                    && chars
                        .get(i + 1)
                        .is_some_and(|n| n.is_ascii_digit() || matches!(n, '-' | '+'));
                if d.is_ascii_digit() || d == '.' || exponent || exponent_sign {
                    i += 1;
                } else {
                    break;
                }
            }
            out.push('#');
        } else {
            out.push(c);
            i += 1;
        }
    }
    out.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// Whether `printed` is what `shown` shows: line by line, masked, a shown
/// `...` standing for any number of printed lines (none too).
fn shows(shown: &[String], printed: &[String]) -> bool {
    match shown.split_first() {
        None => printed.is_empty(),
        Some((first, rest)) if first == "..." => (0..=printed.len()).any(|skip| shows(rest, &printed[skip..])),
        Some((first, rest)) => printed.first().is_some_and(|p| p == first) && shows(rest, &printed[1..]),
    }
}

/// The listings marked `console,tested` show what the program prints: each
/// `$ splinewatch …` line runs (a page's `/tmp/…` files in a folder of its
/// own, and its `toml,file=/tmp/NAME` blocks written there first, in the
/// page's order), and its standard output must be the lines shown below
/// it, up to the next `$` ([`masked`], [`shows`]). Progress and notes go
/// to standard error and are not shown. Renaming a flag, a column or a
/// word the listing shows fails here.
#[test]
fn every_tested_listing_prints_what_it_shows() {
    let mut ran = 0;
    for (page, text) in pages() {
        let scratch = crate::common::fresh_dir(&format!("listing-{}", page.file_stem().unwrap().to_string_lossy()));
        let local = |a: &str| match a.strip_prefix("/tmp/") {
            Some(name) => scratch.join(name).to_string_lossy().into_owned(),
            None => a.to_string(),
        };
        for (info, body, line) in blocks(&text) {
            if let Some(file) = info.split(',').find_map(|p| p.strip_prefix("file=")) {
                std::fs::write(local(file), &body).unwrap();
                continue;
            }
            if info != "console,tested" {
                continue;
            }
            let mut commands: Vec<(String, Vec<String>)> = Vec::new();
            for l in body.lines() {
                match l.strip_prefix("$ ") {
                    Some(command) => commands.push((command.to_string(), Vec::new())),
                    None => commands
                        .last_mut()
                        .unwrap_or_else(|| panic!("{}:{line}: a tested listing starts with `$ `", page.display()))
                        .1
                        .push(masked(l)),
                }
            }
            for (command, shown) in commands {
                let rest = command.strip_prefix("splinewatch ").unwrap_or_else(|| {
                    panic!(
                        "{}:{line}: a tested listing runs splinewatch: {command}",
                        page.display()
                    )
                });
                let args: Vec<String> = rest.split_whitespace().map(local).collect();
                let args: Vec<&str> = args.iter().map(String::as_str).collect();
                let out = splinewatch(&args);
                // The scratch folder printed as the listing's `/tmp`.
                let stdout = String::from_utf8_lossy(&out.stdout).replace(&format!("{}/", scratch.display()), "/tmp/");
                assert!(
                    out.status.success(),
                    "{}:{line}: `{command}` failed: {}",
                    page.display(),
                    String::from_utf8_lossy(&out.stderr)
                );
                let printed: Vec<String> = stdout.lines().map(masked).collect();
                assert!(
                    shows(&shown, &printed),
                    "{}:{line}: `{command}` prints\n{stdout}\nwhich the listing does not show (masked: {printed:#?} against {shown:#?})",
                    page.display()
                );
                ran += 1;
            }
        }
    }
    assert!(ran >= 8, "only {ran} tested commands in the guide");
}

/// The masks and the matcher of the tested listings.
#[test]
fn a_listing_masks_figures_and_keeps_words() {
    assert_eq!(
        masked("west.k1   N/m³  4.036168e8  -1.2e-3  0.31 %"),
        "west.k# N/m³ # # # %"
    );
    assert_eq!(
        masked("ρ: g1–g2 -0.96, 2026-11-21T10:00:00Z"),
        "ρ: g#–g# #, #-#-#T#:#:#Z"
    );
    let lines = |t: &str| t.lines().map(masked).collect::<Vec<_>>();
    assert!(shows(&lines("a 1\n...\nc 3"), &lines("a 2\nb\nb\nc 4")));
    assert!(shows(&lines("a 1\n...\nc 3"), &lines("a 2\nc 4")));
    assert!(!shows(&lines("a 1\nc 3"), &lines("a 2\nb\nc 4")));
    assert!(!shows(&lines("mode freq"), &lines("mode frequency")));
}

#[test]
fn every_relative_link_and_picture_of_the_guide_and_readme_resolves() {
    let mut checked = 0;
    for (page, text) in pages() {
        let dir = root().join(&page).parent().unwrap().to_path_buf();
        for (at, _) in text.match_indices("](") {
            let target: String = text[at + 2..].chars().take_while(|&c| c != ')').collect();
            let target = target
                .split('#')
                .next()
                .unwrap()
                .split_whitespace()
                .next()
                .unwrap_or("");
            if target.is_empty() || target.contains("://") || target.starts_with("mailto:") {
                continue;
            }
            assert!(
                dir.join(target).exists(),
                "{}: the link {target} leads nowhere",
                page.display()
            );
            checked += 1;
        }
    }
    assert!(checked > 50, "only {checked} relative links found");
}

/// Every `{{#include FILE}}` of the guide resolves, and the gallery shows
/// every Python example (its source included, as mdBook renders it).
#[test]
fn every_include_resolves_and_the_gallery_shows_every_example() {
    let mut included = Vec::new();
    for (page, text) in pages() {
        let dir = root().join(&page).parent().unwrap().to_path_buf();
        for (at, _) in text.match_indices("{{#include ") {
            let target: String = text[at + "{{#include ".len()..]
                .chars()
                .take_while(|&c| c != '}')
                .collect();
            let path = dir.join(target.split(':').next().unwrap().trim());
            assert!(
                path.exists(),
                "{}: {{{{#include {target}}}}} leads nowhere",
                page.display()
            );
            included.push(path.canonicalize().unwrap());
        }
    }
    for entry in std::fs::read_dir(root().join("python/examples")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "py") {
            assert!(
                included.contains(&path.canonicalize().unwrap()),
                "the gallery does not show {}",
                path.display()
            );
        }
    }
}

/// Phrases of a diary, not of the software: the pages speak of what the
/// program does, not of when or where it was made (a figure's date stays,
/// once, on the benchmarks or verification page).
const MAKING_OF: &[&str] = &[
    "this machine",
    "this vm",
    "that evening",
    "that morning",
    "same evening",
    "late evening",
    "this session",
    "that session",
    "first session",
    "second session",
    "third session",
    "fourth session",
    "earlier session",
    "later session",
    "next session",
    "last session",
    "here on 20",
    "the issue's",
    "the issue asks",
];

/// Words before "issue #N" that name another project's tracker (zenoh's,
/// faer's): a reference a reader can follow, not this project's history.
const OTHER_TRACKERS: &[&str] = &["zenoh ", "faer's ", "faer ", "rerun ", "upstream "];

/// Where `text` names an issue number of this project ("issue 32",
/// "issues 31", "issue #15", a test named `issue_32_…`): the byte offsets
/// of each "issue" that does.
fn own_issue_numbers(text: &str) -> Vec<usize> {
    let lower = text.to_lowercase();
    lower
        .match_indices("issue")
        .map(|(at, _)| at)
        .filter(|&at| {
            let rest = lower[at + "issue".len()..].trim_start_matches('s');
            let rest = rest.strip_prefix([' ', '_']).unwrap_or(rest);
            let rest = rest.strip_prefix('#').unwrap_or(rest);
            rest.starts_with(|c: char| c.is_ascii_digit()) && !OTHER_TRACKERS.iter().any(|t| lower[..at].ends_with(t))
        })
        .collect()
}

fn own_issue_number(line: &str) -> Option<usize> {
    own_issue_numbers(line).first().copied()
}

/// `text` with every run of whitespace (line breaks included) one space,
/// and the line of `text` each byte of it comes from: a phrase wrapped
/// over two lines is still one phrase.
fn flattened(text: &str) -> (String, Vec<usize>) {
    let (mut flat, mut lines) = (String::with_capacity(text.len()), Vec::with_capacity(text.len()));
    let mut line = 1;
    let mut in_space = false;
    for c in text.chars() {
        if c.is_whitespace() {
            if !in_space {
                flat.push(' ');
                lines.push(line);
            }
            in_space = true;
            if c == '\n' {
                line += 1;
            }
        } else {
            in_space = false;
            flat.push(c);
            lines.extend(std::iter::repeat_n(line, c.len_utf8()));
        }
    }
    (flat, lines)
}

/// The README is the front page, not the manual: at most 200 lines (the
/// guide holds the rest).
#[test]
fn the_readme_stays_within_two_hundred_lines() {
    let lines = std::fs::read_to_string(root().join("README.md"))
        .unwrap()
        .lines()
        .count();
    assert!(
        lines <= 200,
        "README.md has {lines} lines: move the detail to the guide"
    );
}

/// Checked by scanning README.md and every page of the guide, its line
/// breaks read as spaces (lower-cased), for the phrases above and for
/// "issue" followed by a number (unless another project's tracker is named
/// just before it).
#[test]
fn no_page_speaks_of_its_making() {
    let mut found = Vec::new();
    for (page, text) in pages() {
        let (flat, line_of) = flattened(&text.to_lowercase());
        for phrase in MAKING_OF {
            for (at, _) in flat.match_indices(phrase) {
                found.push(format!("{}:{}: {phrase:?}", page.display(), line_of[at]));
            }
        }
        for at in own_issue_numbers(&flat) {
            found.push(format!("{}:{}: an issue number", page.display(), line_of[at]));
        }
    }
    assert!(
        found.is_empty(),
        "pages that speak of their making:\n{}",
        found.join("\n")
    );
    // The check itself: it sees what it must and lets a tracker through.
    assert!(own_issue_number("before issue 32's work").is_some());
    assert!(own_issue_number("(issues #31 and 32)").is_some());
    assert!(own_issue_number("zenoh issue #2711, checked").is_none());
    assert!(own_issue_number("faer's issue #262, a hang").is_none());
    assert!(own_issue_number("no issue found").is_none());
    assert!(own_issue_number("`issue_45_srim_at_mdofs_settings`").is_some());
    // A phrase wrapped over two lines is found, on the line it starts.
    let (flat, line_of) = flattened("one\n116 ms before issue\n17; on this\n  machine");
    assert_eq!(
        own_issue_numbers(&flat)
            .iter()
            .map(|&at| line_of[at])
            .collect::<Vec<_>>(),
        [2]
    );
    assert_eq!(flat.find("this machine").map(|at| line_of[at]), Some(3));
}

/// Words that, a few words before a duration, make it a figure of speed.
const TIMING_VERBS: &[&str] = &[
    "took",
    "takes",
    "take",
    "taking",
    "runs",
    "ran",
    "replayed",
    "published",
    "pushed",
    "assembles",
    "assembled",
    "solves",
    "finishes",
    "finished",
    "costs",
    "cost",
    "compiles",
    "needs",
];

/// The figures of speed a paragraph states: a number and a unit of time a
/// few words after a timing verb ("replayed in 3.5 s"), not an amount of
/// data ("needs 32 s of record").
fn speed_figures(paragraph: &str) -> Vec<String> {
    let words: Vec<&str> = paragraph.split_whitespace().collect();
    let bare = |w: &str| w.trim_matches(|c: char| ",.;:()*`~≈".contains(c)).to_lowercase();
    let mut found = Vec::new();
    for i in 1..words.len() {
        let unit = bare(words[i]);
        let number = bare(words[i - 1]);
        let is_time = ["ms", "µs", "s", "min", "seconds", "minutes"].contains(&unit.as_str());
        let of_data = words.get(i + 1).is_some_and(|w| bare(w) == "of");
        if !is_time || of_data || !number.starts_with(|c: char| c.is_ascii_digit()) {
            continue;
        }
        let before = &words[i.saturating_sub(5)..i - 1];
        if before.iter().any(|w| TIMING_VERBS.contains(&bare(w).as_str())) {
            found.push(words[i.saturating_sub(5)..=i].join(" "));
        }
    }
    found
}

#[test]
fn every_figure_of_speed_lives_on_the_benchmarks_page() {
    let mut found = Vec::new();
    for (page, text) in pages() {
        if page.ends_with("performance/benchmarks.md") {
            continue;
        }
        // A page may round a benchmark's figure beside a link to it.
        for paragraph in text.split("\n\n") {
            if paragraph.contains("benchmarks.md") {
                continue;
            }
            for figure in speed_figures(paragraph) {
                found.push(format!("{}: {figure:?}", page.display()));
            }
        }
    }
    assert!(
        found.is_empty(),
        "figures of speed outside the benchmarks page (move them there, or link to it):\n{}",
        found.join("\n")
    );
    // The check itself: it sees a timing and lets an amount of data through.
    assert_eq!(speed_figures("the stream replayed in 3.5 s, peak").len(), 1);
    assert_eq!(speed_figures("`events` took 8.5 s (two runs)").len(), 1);
    assert!(speed_figures("eight batches needs 32 s of record").is_empty());
    assert!(speed_figures("the grid starts within 0.015 s of it").is_empty());
}
