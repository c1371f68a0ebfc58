//! The layers of ARCHITECTURE.md, read from the source tree: `analysis/` (exact solutions,
//! norms, the periodogram, Roche geometry) uses nothing of the solver, the set-ups, the
//! run loop or the `analyse` commands; `render/` and `domain/` do not use the run loop
//! (`simulation.rs`), and the run loop does not use the `analyse` commands (`reports/`).

use std::path::Path;

/// Every `.rs` file under `src/<dir>` (recursively), with its text.
fn sources(dir: &str) -> Vec<(String, String)> {
    fn walk(dir: &Path, out: &mut Vec<(String, String)>) {
        let mut entries: Vec<_> = std::fs::read_dir(dir)
            .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
            .map(|e| e.unwrap().path())
            .collect();
        entries.sort();
        for path in entries {
            if path.is_dir() {
                walk(&path, out);
            } else if path.extension().is_some_and(|x| x == "rs") {
                let text = std::fs::read_to_string(&path).unwrap();
                out.push((path.display().to_string(), text));
            }
        }
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src").join(dir);
    let mut out = Vec::new();
    if root.is_dir() {
        walk(&root, &mut out);
    } else {
        let file = root.with_extension("rs");
        out.push((
            file.display().to_string(),
            std::fs::read_to_string(&file).unwrap_or_else(|e| panic!("{}: {e}", file.display())),
        ));
    }
    assert!(!out.is_empty(), "no sources under src/{dir}");
    out
}

/// The first segments of the top-level paths of a `use` group's body (after its `{`):
/// `a, b::c, d::{e, f}}` → a, b, d.
fn group_heads(group: &str) -> Vec<String> {
    let (mut heads, mut word, mut depth, mut at_head) = (Vec::new(), String::new(), 0, true);
    for ch in group.chars() {
        if at_head && (ch.is_alphanumeric() || ch == '_') {
            word.push(ch);
            continue;
        }
        if !word.is_empty() {
            heads.push(std::mem::take(&mut word));
            at_head = false;
        }
        match ch {
            '{' => depth += 1,
            '}' if depth == 0 => break,
            '}' => depth -= 1,
            ',' if depth == 0 => at_head = true,
            _ => {}
        }
    }
    heads
}

/// Where code (comments left out) names `crate::<module>` or `sphdisk::<module>`, also
/// inside a group (`use crate::{a, <module>::b}`, over several lines): the lines, numbered.
fn uses(text: &str, module: &str) -> Vec<String> {
    let code: Vec<&str> = text
        .lines()
        .map(|l| l.find("//").map_or(l, |i| &l[..i]))
        .collect();
    let joined = code.join("\n");
    let mut found = Vec::new();
    for root in ["crate::", "sphdisk::"] {
        for (i, _) in joined.match_indices(root) {
            let rest = &joined[i + root.len()..];
            let hit = match rest.strip_prefix('{') {
                Some(group) => group_heads(group).iter().any(|h| h == module),
                None => {
                    let end = rest
                        .find(|c: char| !(c.is_alphanumeric() || c == '_'))
                        .unwrap_or(rest.len());
                    &rest[..end] == module
                }
            };
            if hit {
                let line = joined[..i].matches('\n').count();
                found.push(format!("line {}: {}", line + 1, code[line].trim()));
            }
        }
    }
    found
}

/// The lines of src/<layer> that use any of `forbidden`, as "file: line".
fn violations(layer: &str, forbidden: &[&str]) -> Vec<String> {
    let mut found = Vec::new();
    for (file, text) in sources(layer) {
        for module in forbidden {
            for line in uses(&text, module) {
                found.push(format!("{file}: uses {module}: {line}"));
            }
        }
    }
    found
}

#[test]
fn analysis_depends_on_nothing_of_the_solver_the_set_ups_or_the_commands() {
    let v = violations(
        "analysis",
        &[
            "simulation",
            "problems",
            "sweep",
            "physics",
            "integrate",
            "domain",
            "reports",
            "render",
            "config",
        ],
    );
    assert!(
        v.is_empty(),
        "analysis/ crosses its layer:\n{}",
        v.join("\n")
    );
}

#[test]
fn render_and_domain_do_not_use_the_run_loop() {
    let mut v = violations("render", &["simulation", "reports", "problems"]);
    v.extend(violations("domain", &["simulation", "reports"]));
    v.extend(violations("io", &["simulation", "reports", "render"]));
    assert!(v.is_empty(), "a layer uses the run loop:\n{}", v.join("\n"));
}

#[test]
fn the_run_loop_does_not_use_the_analyse_commands() {
    let mut v = violations("simulation", &["reports"]);
    v.extend(violations("problems", &["reports", "simulation"]));
    v.extend(violations("physics", &["reports", "simulation"]));
    v.extend(violations("sweep", &["reports", "simulation"]));
    assert!(v.is_empty(), "the solver uses a command:\n{}", v.join("\n"));
}

#[test]
fn the_checker_sees_a_use_it_forbids() {
    assert_eq!(
        uses("use crate::simulation::SnapshotIndex;", "simulation").len(),
        1
    );
    assert_eq!(uses("use crate::{config, simulation};", "config").len(), 1);
    assert_eq!(
        uses("    let x = crate::problems::sod::params(c);", "problems").len(),
        1
    );
    assert!(uses("// crate::simulation::run", "simulation").is_empty());
    assert_eq!(
        uses(
            "use crate::{\n    boundary::SimBox,\n    simulation::{Run, Team},\n};",
            "simulation"
        )
        .len(),
        1
    );
    assert!(uses("use crate::{io::{simulation, x}, y};", "simulation").is_empty());
    assert!(uses("use crate::simulations_elsewhere;", "simulation").is_empty());
}
