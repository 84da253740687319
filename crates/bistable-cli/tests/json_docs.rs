//! The JSON examples of `docs/json.md` against the real output: every command of the page is run
//! (in the page's order, in one scratch directory, so a command may read an earlier one's files)
//! and its output must have exactly the keys and value types of the example shown, so that the
//! page and the program cannot drift apart. Every subcommand is either documented there or
//! listed here as printing no JSON.

use std::path::PathBuf;
use std::process::Command;

use serde_json::Value;

/// The documented outputs: each subcommand's first word, with the option that changes its
/// object (`orbit --continue-omega`).
const DOCUMENTED: &[&str] = &[
    "simulate",
    "classify",
    "map",
    "basins",
    "coexistence",
    "bifurcation",
    "orbit",
    "orbit --continue-omega",
    "atlas",
    "thresholds",
    "spectrum",
];

/// Subcommands that print no JSON (`energy-map` only draws).
const NO_JSON: &[&str] = &["energy-map"];

/// Objects whose keys are data, not names (the class labels of `map`'s `counts`): their values
/// are checked, not their keys.
const DATA_KEYED: &[&str] = &["counts"];

fn doc() -> String {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../docs/json.md");
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The page's `(command line, example)` pairs, in order: a ```sh block of one `bistable` line
/// followed by a ```json block. Asserts that every ```json block has its command.
fn examples(doc: &str) -> Vec<(String, Value)> {
    let lines: Vec<&str> = doc.lines().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i + 4 < lines.len() {
        let command = lines[i + 1];
        if lines[i] == "```sh" && command.starts_with("bistable ") && lines[i + 3] == "```json" {
            assert_eq!(lines[i + 2], "```", "the command block of {command:?}");
            let len = lines[i + 4..]
                .iter()
                .position(|l| *l == "```")
                .unwrap_or_else(|| panic!("unclosed example of {command:?}"));
            let text = lines[i + 4..i + 4 + len].join("\n");
            let example = serde_json::from_str(&text)
                .unwrap_or_else(|e| panic!("the example of {command:?} is not JSON: {e}"));
            out.push((command.to_string(), example));
            i += 4 + len;
        }
        i += 1;
    }
    let blocks = lines.iter().filter(|l| **l == "```json").count();
    assert_eq!(out.len(), blocks, "a ```json block without its command");
    out
}

/// The name of a value's type as the page's examples tell them apart.
fn kind(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "bool",
        Value::Number(n) if n.is_f64() => "float",
        Value::Number(_) => "int",
        Value::String(_) => "string",
        Value::Array(_) => "array",
        Value::Object(_) => "object",
    }
}

/// Collects into `errors` where `real` (at `path`) differs from `example` in keys or types.
fn compare(path: &str, example: &Value, real: &Value, errors: &mut Vec<String>) {
    if kind(example) != kind(real) {
        errors.push(format!(
            "{path}: {} in the output, {} in the example",
            kind(real),
            kind(example)
        ));
        return;
    }
    match (example, real) {
        (Value::Object(e), Value::Object(r)) => {
            let name = path.rsplit('.').next().unwrap_or_default();
            if DATA_KEYED.contains(&name) {
                let values: Vec<&Value> = e.values().collect();
                for (k, v) in r {
                    one_of(&format!("{path}.{k}"), &values, v, errors);
                }
                return;
            }
            for k in e.keys().filter(|k| !r.contains_key(*k)) {
                errors.push(format!("{path}.{k}: in the example, not in the output"));
            }
            for (k, v) in r {
                match e.get(k) {
                    Some(ev) => compare(&format!("{path}.{k}"), ev, v, errors),
                    None => errors.push(format!("{path}.{k}: in the output, not in the example")),
                }
            }
        }
        (Value::Array(e), Value::Array(r)) => {
            let elements: Vec<&Value> = e.iter().collect();
            for (i, v) in r.iter().enumerate() {
                one_of(&format!("{path}[{i}]"), &elements, v, errors);
            }
        }
        _ => {}
    }
}

/// Collects into `errors` unless `real` has the keys and types of one of `examples` (the
/// differences from the first when it has none).
fn one_of(path: &str, examples: &[&Value], real: &Value, errors: &mut Vec<String>) {
    let mut first = None;
    for e in examples {
        let mut errs = Vec::new();
        compare(path, e, real, &mut errs);
        if errs.is_empty() {
            return;
        }
        first.get_or_insert(errs);
    }
    match first {
        Some(errs) => errors.extend(errs),
        None => errors.push(format!("{path}: the example's array or object is empty")),
    }
}

/// Which documented output a command line prints.
fn output_of(command: &str) -> String {
    let words: Vec<&str> = command.split_whitespace().collect();
    match words[1] {
        "orbit" if words.contains(&"--continue-omega") => "orbit --continue-omega".into(),
        sub => sub.into(),
    }
}

/// The subcommands `bistable --help` lists.
fn subcommands() -> Vec<String> {
    let o = Command::new(env!("CARGO_BIN_EXE_bistable"))
        .arg("--help")
        .output()
        .expect("run bistable --help");
    let help = String::from_utf8(o.stdout).unwrap();
    help.lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter(|l| !l.starts_with("   "))
        .filter_map(|l| l.split_whitespace().next())
        .filter(|s| *s != "help")
        .map(String::from)
        .collect()
}

#[test]
fn every_subcommand_is_documented_or_prints_no_json() {
    let documented: Vec<String> = examples(&doc()).iter().map(|(c, _)| output_of(c)).collect();
    for want in DOCUMENTED {
        assert!(documented.iter().any(|d| d == want), "no example of {want}");
    }
    for d in &documented {
        assert!(DOCUMENTED.contains(&d.as_str()), "{d} is not in DOCUMENTED");
    }
    let subs = subcommands();
    assert!(subs.len() >= DOCUMENTED.len(), "{subs:?}");
    for sub in &subs {
        assert!(
            NO_JSON.contains(&sub.as_str()) || documented.contains(sub),
            "bistable {sub}: no example in docs/json.md"
        );
    }
}

#[test]
fn the_documented_examples_have_the_keys_and_types_of_the_real_output() {
    let dir = std::env::temp_dir().join(format!("bistable-json-docs-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let mut errors = Vec::new();
    for (command, example) in examples(&doc()) {
        let o = Command::new(env!("CARGO_BIN_EXE_bistable"))
            .args(command.split_whitespace().skip(1))
            .current_dir(&dir)
            .output()
            .expect("run bistable");
        assert!(
            o.status.success(),
            "{command}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let real: Value = serde_json::from_slice(&o.stdout)
            .unwrap_or_else(|e| panic!("{command}: the output is not JSON: {e}"));
        let mut errs = Vec::new();
        compare("", &example, &real, &mut errs);
        errors.extend(errs.into_iter().map(|e| format!("{command}\n    {e}")));
    }
    let _ = std::fs::remove_dir_all(&dir);
    assert!(
        errors.is_empty(),
        "docs/json.md differs from the output (scripts/json_examples.py rewrites its \
         examples):\n{}",
        errors.join("\n")
    );
}

#[test]
fn the_comparison_finds_a_missing_key_a_new_key_and_a_changed_type() {
    let example: Value =
        serde_json::from_str(r#"{"a": 1, "b": [{"c": 1.0}, {"c": null}], "counts": {"x": 1}}"#)
            .unwrap();
    let errors = |real: &str| {
        let mut e = Vec::new();
        compare("", &example, &serde_json::from_str(real).unwrap(), &mut e);
        e
    };
    assert!(errors(r#"{"a": 2, "b": [{"c": null}, {"c": 2.5}], "counts": {"y": 3}}"#).is_empty());
    assert_eq!(
        errors(r#"{"a": 2.0, "b": [], "counts": {}}"#),
        [".a: float in the output, int in the example"]
    );
    assert_eq!(
        errors(r#"{"b": [{"c": 1}], "counts": {}, "d": true}"#),
        [
            ".a: in the example, not in the output",
            ".b[0].c: int in the output, float in the example",
            ".d: in the output, not in the example"
        ]
    );
}
