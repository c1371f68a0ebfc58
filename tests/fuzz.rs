//! Fuzzes the command line with a seeded generator: problem files from `problems/` with a key
//! dropped, duplicated, retyped or set to an absurd value (1e308, -1, 0, NaN, inf, huge
//! arrays), `--set` overrides of the same kinds and plausible ones (the problem's own values
//! ×0.5–×2, small integers, other accepted names: these mostly run, so that the fuzz reaches
//! the simulation and not only the checks), and checkpoints and snapshots with random bytes
//! overwritten or cut short. Every case must end either with exit 0 and finite
//! outputs, or with exit 2 and one `error:` line naming the key or the file — never a
//! panic, an abort or a hang (each case is killed after a time limit and fails).

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use sphdisk::io::{checkpoint, hdf5};
use sphdisk::rng::Rng;

mod common;
use common::path_str as s;

/// Longest a case may run before it counts as a hang.
const LIMIT: Duration = Duration::from_secs(20);

/// How one case ended.
struct Outcome {
    code: i32,
    stderr: String,
}

/// Runs `sphdisk` with `args` in `dir`, killing it after [`LIMIT`]; fails the test on a
/// hang, a signal (abort) or a panic.
fn sphdisk(dir: &Path, args: &[String], what: &str) -> Result<Outcome, String> {
    let err_path = dir.join("stderr.txt");
    let err_file = std::fs::File::create(&err_path).unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_sphdisk"))
        .args(args)
        .current_dir(dir)
        .stdout(Stdio::null())
        .stderr(err_file)
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    let status = loop {
        if let Some(st) = child.try_wait().unwrap() {
            break st;
        }
        if t0.elapsed() > LIMIT {
            child.kill().unwrap();
            child.wait().unwrap();
            return Err(format!("{what}: still running after {LIMIT:?}: {args:?}"));
        }
        std::thread::sleep(Duration::from_millis(2));
    };
    let stderr = std::fs::read_to_string(&err_path).unwrap_or_default();
    let Some(code) = status.code() else {
        return Err(format!(
            "{what}: ended by a signal ({status}): {args:?}\n{stderr}"
        ));
    };
    if stderr.contains("panicked") || code == 101 {
        return Err(format!("{what}: panicked: {args:?}\n{stderr}"));
    }
    Ok(Outcome { code, stderr })
}

/// The single error line of a failed case, which must name one of `names`.
fn one_error_line(
    o: &Outcome,
    names: &[String],
    what: &str,
    args: &[String],
) -> Result<(), String> {
    let lines: Vec<&str> = o.stderr.lines().filter(|l| !l.trim().is_empty()).collect();
    if o.code != 2 || lines.len() != 1 || !lines[0].starts_with("error: ") {
        return Err(format!(
            "{what}: exit code {}, not one error line: {args:?}\n{}",
            o.code, o.stderr
        ));
    }
    // The mutated key, the file, or the key it conflicts with (`key `…``, `table `[…]``).
    let named = names.iter().any(|n| lines[0].contains(n.as_str()))
        || lines[0].contains("key `")
        || lines[0].contains("keys `")
        || lines[0].contains("table `[");
    if !named {
        return Err(format!(
            "{what}: the error names none of {names:?}: {}",
            lines[0]
        ));
    }
    if !lines[0].matches('`').count().is_multiple_of(2) {
        return Err(format!("{what}: a stray backtick: {}", lines[0]));
    }
    Ok(())
}

/// Every number a successful case wrote is finite: final.csv, summary.json, the newest
/// checkpoint and every snapshot.
fn finite_outputs(out: &Path, skip: &[PathBuf], what: &str) -> Result<(), String> {
    if let Ok(csv) = std::fs::read_to_string(out.join("final.csv")) {
        for line in csv.lines().skip(1) {
            for v in line.split(',') {
                let x: f64 = v.parse().unwrap_or(f64::NAN);
                if !x.is_finite() {
                    return Err(format!("{what}: final.csv has `{v}` in `{line}`"));
                }
            }
        }
    }
    if let Ok(json) = std::fs::read_to_string(out.join("summary.json")) {
        for bad in ["NaN", "inf"] {
            if json.contains(bad) {
                return Err(format!("{what}: summary.json has {bad}:\n{json}"));
            }
        }
        // Every number present; null only for the energy drift of a gas whose u is not
        // evolved (isothermal: no energy to conserve, as `io::summary` documents).
        let mut v: serde_json::Value = serde_json::from_str(&json)
            .map_err(|e| format!("{what}: summary.json does not parse: {e}"))?;
        let run: toml::Table = std::fs::read_to_string(out.join("run.toml"))
            .ok()
            .and_then(|t| t.parse().ok())
            .unwrap_or_default();
        let ideal = run
            .get("eos")
            .and_then(|e| e.get("kind"))
            .and_then(|k| k.as_str())
            == Some("ideal");
        if !ideal && v["conservation"]["energy"].is_null() {
            v["conservation"]["energy"] = serde_json::json!(0.0);
        }
        if v.to_string().contains("null") {
            return Err(format!("{what}: summary.json has null:\n{json}"));
        }
    }
    let mut files: Vec<PathBuf> = checkpoint::list(out).unwrap_or_default();
    files.truncate(1);
    for e in std::fs::read_dir(out).into_iter().flatten().flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        if name.starts_with("snap_") && name.ends_with(".hdf5") && !skip.contains(&e.path()) {
            files.push(e.path());
        }
    }
    for f in files {
        if f.starts_with(checkpoint::folder(out)) {
            let d = checkpoint::dimension(&f).map_err(|e| format!("{what}: {e:#}"))?;
            let arrays = match d {
                1 => checkpoint::read::<1>(&f).map(|(_, mut p)| flat(p.named_arrays_mut())),
                2 => checkpoint::read::<2>(&f).map(|(_, mut p)| flat(p.named_arrays_mut())),
                _ => checkpoint::read::<3>(&f).map(|(_, mut p)| flat(p.named_arrays_mut())),
            }
            .map_err(|e| format!("{what}: {e:#}"))?;
            if !arrays.iter().all(|x| x.is_finite()) {
                return Err(format!("{what}: {} holds a non-finite value", f.display()));
            }
            continue;
        }
        // read_snapshot refuses a non-finite value itself.
        hdf5::read_snapshot(&f).map_err(|e| format!("{what}: {e:#}"))?;
    }
    Ok(())
}

/// Every value of a checkpoint's arrays, one after the other.
fn flat(arrays: Vec<(String, &mut Vec<f64>)>) -> Vec<f64> {
    arrays.into_iter().flat_map(|(_, v)| v.clone()).collect()
}

/// Problem files small enough to start in a fraction of a second: (file, overrides).
fn bases() -> Vec<(&'static str, toml::Table)> {
    let names = [
        "sod.toml",
        "sod3d.toml",
        "lax.toml",
        "strong_shock.toml",
        "stationary_contact.toml",
        "rarefactions123.toml",
        "advection.toml",
        "advection2d.toml",
        "sedov.toml",
        "sedov2d.toml",
        "ring.toml",
        "disk3d.toml",
        "roche_stream.toml",
        "cv2d.toml",
        "cv2d_cooling.toml",
        "oy_car.toml",
        "outbursts.toml",
        "superhump.toml",
    ];
    names
        .iter()
        .map(|name| {
            let text = std::fs::read_to_string(common::problem_file(name)).unwrap();
            let mut t: toml::Table = text.parse().unwrap();
            let dim = t["problem"]["dimension"].as_integer().unwrap();
            let small = match (t["problem"]["kind"].as_str().unwrap(), dim) {
                ("disk", _) => 4,
                // Two kernel supports must fit in the box: the stationary contact's quintic
                // spline at h = 2 sparse spacings (16 dense ones) needs n ≥ 80.
                (_, 1) => 80,
                (_, 2) => 12,
                _ => 6,
            };
            let particles = t["particles"].as_table_mut().unwrap();
            if particles.contains_key("n") {
                particles.insert("n".into(), toml::Value::Integer(small));
            }
            // The 3D tube's cross-section holds two kernel supports of its coarse lattice.
            if let Some(sod) = t.get_mut("sod").and_then(|s| s.as_table_mut())
                && dim == 3
            {
                sod.insert("width".into(), toml::Value::Float(1.0));
            }
            (*name, t)
        })
        .collect()
}

/// Dotted paths of every leaf value (and every table) of `t`.
fn paths(t: &toml::Table, prefix: &str, out: &mut Vec<String>) {
    for (k, v) in t {
        let p = if prefix.is_empty() {
            k.clone()
        } else {
            format!("{prefix}.{k}")
        };
        out.push(p.clone());
        if let toml::Value::Table(sub) = v {
            paths(sub, &p, out);
        }
    }
}

/// An absurd or mistyped value.
fn bad_value(rng: &mut Rng, huge_len: usize) -> toml::Value {
    use toml::Value as V;
    let huge = || V::Array((0..huge_len).map(|_| V::Float(1.0)).collect());
    match rng.next_u64() % 24 {
        0 => V::Float(1e308),
        1 => V::Float(-1e308),
        2 => V::Integer(-1),
        3 => V::Integer(0),
        4 => V::Float(0.0),
        5 => V::Float(f64::NAN),
        6 => V::Float(f64::INFINITY),
        7 => V::Float(f64::NEG_INFINITY),
        8 => V::Float(1e-308),
        9 => V::Float(5e-324),
        10 => V::Integer(i64::MAX),
        11 => V::Integer(4_294_967_296),
        12 => V::String("nan".into()),
        13 => V::String("1.0".into()),
        14 => V::Boolean(true),
        15 => V::Array(vec![V::Integer(1), V::Integer(2)]),
        16 => V::Array(vec![]),
        17 => V::Table(toml::Table::new()),
        18 => huge(),
        19 => V::Float(-0.0),
        20 => V::Float(1.5),
        21 => V::Float(1e30),
        22 => V::Integer(1_000_000),
        _ => V::Float(-1e-300),
    }
}

/// Every value a string key takes in the problem files, and the names every enum key
/// accepts: the choices a plausible override of that key picks from.
fn string_choices(bases: &[(&str, toml::Table)]) -> BTreeMap<String, BTreeSet<String>> {
    let mut choices: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (_, t) in bases {
        let mut all = Vec::new();
        paths(t, "", &mut all);
        for p in all {
            if let Some(toml::Value::String(s)) = value_at(t, &p) {
                choices.entry(p).or_default().insert(s.clone());
            }
        }
    }
    let enums: [(&str, &[&str]); 5] = [
        ("boundary.x", &["periodic", "reflecting", "open"]),
        ("boundary.y", &["periodic", "reflecting", "open"]),
        ("boundary.z", &["periodic", "reflecting", "open"]),
        (
            "particles.kernel",
            &[
                "cubic",
                "quintic",
                "wendland_c2",
                "wendland_c4",
                "wendland_c6",
            ],
        ),
        ("eos.kind", &["ideal", "isothermal", "locally_isothermal"]),
    ];
    for (key, names) in enums {
        let set = choices.entry(key.to_string()).or_default();
        set.extend(names.iter().map(|n| n.to_string()));
    }
    choices
}

/// The value at the dotted `path` of `t`.
fn value_at<'a>(t: &'a toml::Table, path: &str) -> Option<&'a toml::Value> {
    let (first, rest) = path
        .split_once('.')
        .map_or((path, None), |(a, b)| (a, Some(b)));
    let v = t.get(first)?;
    match (rest, v) {
        (None, _) => Some(v),
        (Some(r), toml::Value::Table(sub)) => value_at(sub, r),
        _ => None,
    }
}

/// A factor between ×0.5 and ×2, even in the logarithm.
fn factor(rng: &mut Rng) -> f64 {
    2f64.powf(2.0 * (rng.next_u64() % 1001) as f64 / 1000.0 - 1.0)
}

/// A value a user might well write for the key at `path` whose problem-file value is `v`:
/// a number ×0.5–×2 (an integer rounded, a zero a small number), a small integer, another
/// name the key accepts, the other boolean; arrays and inline tables element by element.
fn plausible_value(
    rng: &mut Rng,
    path: &str,
    v: &toml::Value,
    choices: &BTreeMap<String, BTreeSet<String>>,
) -> toml::Value {
    use toml::Value as V;
    match v {
        V::Float(x) if *x == 0.0 => V::Float([0.0, 0.01, 0.05, 0.1][(rng.next_u64() % 4) as usize]),
        V::Float(x) => V::Float(x * factor(rng)),
        V::Integer(n) if *n <= 0 || rng.next_u64().is_multiple_of(4) => {
            V::Integer(1 + (rng.next_u64() % 8) as i64)
        }
        V::Integer(n) => V::Integer(((*n as f64 * factor(rng)).round() as i64).max(1)),
        V::String(s) => {
            let names: Vec<&String> = choices
                .get(path)
                .map(|c| c.iter().collect())
                .unwrap_or_default();
            if names.is_empty() {
                V::String(s.clone())
            } else {
                V::String(names[(rng.next_u64() % names.len() as u64) as usize].clone())
            }
        }
        V::Boolean(b) => V::Boolean(!b),
        V::Array(a) => V::Array(
            a.iter()
                .map(|x| plausible_value(rng, path, x, choices))
                .collect(),
        ),
        V::Table(t) => V::Table(
            t.iter()
                .map(|(k, x)| {
                    (
                        k.clone(),
                        plausible_value(rng, &format!("{path}.{k}"), x, choices),
                    )
                })
                .collect(),
        ),
        other => other.clone(),
    }
}

fn get_mut<'a>(t: &'a mut toml::Table, path: &str) -> Option<(&'a mut toml::Table, String)> {
    let parts: Vec<&str> = path.split('.').collect();
    let mut cur = t;
    for p in &parts[..parts.len() - 1] {
        cur = cur.get_mut(*p)?.as_table_mut()?;
    }
    Some((cur, parts[parts.len() - 1].to_string()))
}

/// The names an error about `path` may use: the dotted key, its table, the file.
fn names_for(path: &str, file: &str) -> Vec<String> {
    let mut v = vec![path.to_string(), file.to_string()];
    let parts: Vec<&str> = path.split('.').collect();
    for k in 1..parts.len() {
        let table = parts[..k].join(".");
        v.push(format!("[{table}]"));
        v.push(format!("`{table}`"));
    }
    v
}

/// The common tail of a fuzzed run: small, quiet, at most a few steps.
fn run_args(file: &str, out: &str) -> Vec<String> {
    [
        "--threads",
        "1",
        "run",
        file,
        "--quiet",
        "--out",
        out,
        "--stop-after",
        "3",
    ]
    .iter()
    .map(|x| x.to_string())
    .collect()
}

/// Checks one finished case: exit 0 with finite outputs, or one line naming `names`.
/// Returns whether it ran; a defect goes to `defects`.
fn judge(
    o: Result<Outcome, String>,
    out: &Path,
    skip: &[PathBuf],
    names: &[String],
    what: &str,
    args: &[String],
    defects: &mut Vec<String>,
) -> bool {
    let verdict = o.and_then(|o| {
        if o.code == 0 {
            finite_outputs(out, skip, what).map(|()| true)
        } else {
            one_error_line(&o, names, what, args).map(|()| false)
        }
    });
    verdict.unwrap_or_else(|d| {
        defects.push(d);
        false
    })
}

/// Fails with every defect found, after all cases ran.
fn no_defects(defects: &[String], cases: usize) {
    assert!(
        defects.is_empty(),
        "{} of {cases} cases failed:\n{}",
        defects.len(),
        defects.join("\n")
    );
}

#[test]
fn mutated_problem_files_run_or_fail_with_one_line_naming_the_key() {
    let mut rng = Rng::new(17);
    let bases = bases();
    let (mut ran, mut refused) = (0, 0);
    let mut defects = Vec::new();
    let dir = tempfile::tempdir().unwrap();
    for case in 0..160 {
        let (name, base) = &bases[(rng.next_u64() % bases.len() as u64) as usize];
        let mut t = base.clone();
        let mut all = Vec::new();
        paths(&t, "", &mut all);
        let path = all[(rng.next_u64() % all.len() as u64) as usize].clone();
        let (table, key) = get_mut(&mut t, &path).unwrap();
        let op = rng.next_u64() % 4;
        let mut text;
        match op {
            0 => {
                table.remove(&key);
                text = toml::to_string(&t).unwrap();
            }
            1 => {
                // Duplicate the key's line (or its table header).
                text = toml::to_string(&t).unwrap();
                let needle = format!("\n{key} = ");
                if let Some(at) = text.find(&needle) {
                    let end = text[at + 1..].find('\n').map_or(text.len(), |e| at + 1 + e);
                    let line = text[at..end].to_string();
                    text.insert_str(end, &line);
                } else {
                    let _ = write!(text, "\n[{path}]\n");
                }
            }
            _ => {
                table.insert(key.clone(), bad_value(&mut rng, 200_000));
                text = toml::to_string(&t).unwrap();
            }
        }
        let case_dir = dir.path().join(format!("p{case}"));
        std::fs::create_dir_all(&case_dir).unwrap();
        let file = format!("fuzz_{case}.toml");
        std::fs::write(case_dir.join(&file), &text).unwrap();
        let args = run_args(&file, "out");
        let what = format!("case {case} ({name}, {path}, op {op})");
        let o = sphdisk(&case_dir, &args, &what);
        let out = case_dir.join("out");
        if judge(
            o,
            &out,
            &[],
            &names_for(&path, &file),
            &what,
            &args,
            &mut defects,
        ) {
            ran += 1;
        } else {
            refused += 1;
        }
        std::fs::remove_dir_all(&case_dir).unwrap();
    }
    eprintln!("mutated problem files: {ran} ran, {refused} refused by name");
    no_defects(&defects, 160);
    assert!(ran > 0 && refused > 0);
}

#[test]
fn fuzzed_overrides_run_or_fail_with_one_line_naming_the_key() {
    let mut rng = Rng::new(1717);
    let bases = bases();
    let mut defects = Vec::new();
    let dir = tempfile::tempdir().unwrap();
    let choices = string_choices(&bases);
    // (ran, refused) of the absurd and of the plausible overrides.
    let mut counts = [(0, 0); 2];
    for case in 0..120 {
        let (name, base) = &bases[(rng.next_u64() % bases.len() as u64) as usize];
        let mut all = Vec::new();
        paths(base, "", &mut all);
        let plausible = rng.next_u64() % 10 < 6;
        let mut sets = Vec::new();
        if plausible {
            // One to three keys of the problem set to values a user might write.
            let leaves: Vec<&String> = all
                .iter()
                .filter(|p| !matches!(value_at(base, p), Some(toml::Value::Table(_))))
                .collect();
            for _ in 0..1 + rng.next_u64() % 3 {
                let key = leaves[(rng.next_u64() % leaves.len() as u64) as usize];
                let v = value_at(base, key).unwrap();
                let value = plausible_value(&mut rng, key, v, &choices);
                sets.push((key.clone(), toml::Value::to_string(&value)));
            }
        } else {
            let key = match rng.next_u64() % 8 {
                0 => "no.such.key".to_string(),
                1 => vec!["a"; 30_000].join("."),
                2 => "particles..n".to_string(),
                _ => all[(rng.next_u64() % all.len() as u64) as usize].clone(),
            };
            let value = match rng.next_u64() % 6 {
                0 => "nan".to_string(),
                1 => "1e999".to_string(),
                2 => "[1, 2".to_string(),
                // A command-line argument holds at most 128 KiB.
                _ => toml::Value::to_string(&bad_value(&mut rng, 10_000)),
            };
            sets.push((key, value));
        }
        let case_dir = dir.path().join(format!("o{case}"));
        std::fs::create_dir_all(&case_dir).unwrap();
        let mut text = toml::to_string(base).unwrap();
        text.push('\n');
        let small = case_dir.join(name);
        std::fs::write(&small, text).unwrap();
        let mut args = run_args(&s(&small), "out");
        let mut names = vec!["--set".to_string()];
        let mut shown = Vec::new();
        for (key, value) in &sets {
            args.push("--set".into());
            args.push(format!("{key}={value}"));
            names.extend(names_for(key, name));
            shown.push(format!("{key:.40}={value:.40}"));
        }
        let what = format!("override case {case} ({name}, {})", shown.join(" "));
        let o = sphdisk(&case_dir, &args, &what);
        let count = &mut counts[usize::from(plausible)];
        if judge(
            o,
            &case_dir.join("out"),
            &[],
            &names,
            &what,
            &args,
            &mut defects,
        ) {
            count.0 += 1;
        } else {
            count.1 += 1;
        }
        std::fs::remove_dir_all(&case_dir).unwrap();
    }
    let [(ran_absurd, refused_absurd), (ran, refused)] = counts;
    eprintln!(
        "fuzzed overrides: absurd {ran_absurd} ran, {refused_absurd} refused by name; \
         plausible {ran} ran, {refused} refused by name"
    );
    no_defects(&defects, 120);
    assert!(refused_absurd > 0 && ran > 0 && refused > 0);
    // Most plausible overrides run: the fuzz reaches the simulation, not only the checks.
    assert!(
        ran + ran_absurd >= 36,
        "only {} of 120 override cases ran",
        ran + ran_absurd
    );
}

/// Overwrites random bytes of `f`, cuts it short, or both.
fn corrupt(f: &Path, rng: &mut Rng) -> &'static str {
    let mut bytes = std::fs::read(f).unwrap();
    let how = rng.next_u64() % 4;
    if how != 1 {
        let k = 1 + rng.next_u64() % 64;
        for _ in 0..k {
            let at = (rng.next_u64() % bytes.len() as u64) as usize;
            bytes[at] = rng.next_u64() as u8;
        }
    }
    if how >= 1 {
        let keep = (rng.next_u64() % bytes.len() as u64) as usize;
        bytes.truncate(keep);
    }
    if how == 3 {
        bytes.extend((0..4096).map(|_| rng.next_u64() as u8));
    }
    std::fs::write(f, bytes).unwrap();
    [
        "bytes",
        "truncated",
        "bytes+truncated",
        "bytes+truncated+garbage",
    ][how as usize]
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        if e.path().is_dir() {
            copy_dir(&e.path(), &to.join(e.file_name()));
        } else {
            std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
        }
    }
}

#[test]
fn corrupted_checkpoints_and_snapshots_resume_or_fail_with_one_line_naming_the_file() {
    let mut rng = Rng::new(171717);
    let dir = tempfile::tempdir().unwrap();
    // Two stopped runs (1D and 2D) with checkpoints of steps 4 and 6 and snapshots, and a
    // finished 1D run for `analyse sod`.
    let sod = common::problem_file("sod.toml");
    let sedov = common::problem_file("sedov2d.toml");
    let mut bases = Vec::new();
    for (name, file, sets) in [
        (
            "sod",
            &sod,
            &["particles.n=40", "output.interval=0.002", "time.end=0.01"][..],
        ),
        (
            "sedov2d",
            &sedov,
            &["particles.n=12", "output.interval=0.002", "time.end=0.01"][..],
        ),
    ] {
        let out = dir.path().join(name);
        let mut args: Vec<String> = run_args(file, &s(&out));
        args.truncate(args.len() - 2);
        for x in sets.iter().chain(&["output.checkpoint_steps=2"]) {
            args.push("--set".into());
            args.push(x.to_string());
        }
        let mut stopped = args.clone();
        // run_args puts --out's value at index 6.
        stopped[6] = s(&dir.path().join(format!("{name}_stopped")));
        stopped.extend(["--stop-after".into(), "6".into()]);
        for a in [&args, &stopped] {
            let o = sphdisk(dir.path(), a, name).unwrap();
            assert_eq!(o.code, 0, "{}", o.stderr);
        }
        bases.push((
            name,
            file.clone(),
            out,
            dir.path().join(format!("{name}_stopped")),
        ));
    }
    let (mut ran, mut refused) = (0, 0);
    let mut defects = Vec::new();
    for case in 0..120 {
        let (name, file, finished, stopped) = &bases[(rng.next_u64() % 2) as usize];
        let case_dir = dir.path().join(format!("c{case}"));
        let target = rng.next_u64() % 6;
        let (run_dir, args, victims): (PathBuf, Vec<String>, Vec<PathBuf>) = match target {
            // The newest checkpoint, or both, then --resume.
            0 | 1 => {
                let run = case_dir.join("run");
                copy_dir(stopped, &run);
                let mut v = checkpoint::list(&run).unwrap();
                if target == 0 {
                    v.truncate(1);
                }
                let args = vec![
                    "--threads".into(),
                    "1".into(),
                    "run".into(),
                    "--quiet".into(),
                    "--resume".into(),
                    s(&run),
                ];
                (run, args, v)
            }
            // A snapshot for render, --from, analyse.
            _ => {
                let run = case_dir.join("run");
                copy_dir(finished, &run);
                let k = 1 + rng.next_u64() % 4;
                let snap = run.join(format!("snap_{k:04}.hdf5"));
                let t = s(&snap);
                let args: Vec<String> = match target {
                    2 => vec!["render", &t, "--resolution", "32", "--out", "x.png"]
                        .into_iter()
                        .map(String::from)
                        .collect(),
                    3 => {
                        let mut a = run_args(file, "from");
                        a.extend(["--from".into(), t.clone()]);
                        a
                    }
                    4 => {
                        let f = run.join("final.hdf5");
                        let t = s(&f);
                        let v = ["render", &t, "--resolution", "32", "--out", "x.png"];
                        let a: Vec<String> = v.into_iter().map(String::from).collect();
                        let victims = [f];
                        let what = corrupt(&victims[0], &mut rng);
                        let o = sphdisk(&case_dir, &a, what);
                        let names = vec!["final.hdf5".to_string()];
                        let out = case_dir.join("none");
                        if judge(o, &out, &[], &names, what, &a, &mut defects) {
                            ran += 1;
                        } else {
                            refused += 1;
                        }
                        std::fs::remove_dir_all(&case_dir).unwrap();
                        continue;
                    }
                    _ if *name == "sod" => vec!["analyse".into(), "sod".into(), s(&run)],
                    _ => ["render", &s(&run), "--resolution", "32", "--out", "frames"]
                        .into_iter()
                        .map(String::from)
                        .collect(),
                };
                (run, args, vec![snap])
            }
        };
        let mut how = Vec::new();
        for v in &victims {
            how.push(corrupt(v, &mut rng));
        }
        let what = format!("file case {case} ({name}, target {target}, {how:?})");
        let o = sphdisk(&case_dir, &args, &what);
        let mut names: Vec<String> = victims
            .iter()
            .map(|v| v.file_name().unwrap().to_string_lossy().into_owned())
            .collect();
        names.push("snap_".into());
        let out = if target == 3 {
            case_dir.join("from")
        } else {
            run_dir
        };
        if judge(o, &out, &victims, &names, &what, &args, &mut defects) {
            ran += 1;
        } else {
            refused += 1;
        }
        std::fs::remove_dir_all(&case_dir).unwrap();
    }
    eprintln!("corrupted files: {ran} ran, {refused} refused by name");
    no_defects(&defects, 120);
    assert!(ran > 0 && refused > 0);
}
