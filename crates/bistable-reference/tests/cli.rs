//! The `bistable-reference` binary: CSV on success, a clear error and non-zero exit otherwise.

use std::process::Command;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_bistable-reference"))
}

#[test]
fn prints_csv() {
    let out = bin()
        .args(["--omega", "1.75", "--velocity", "0.07", "--t-end", "10"])
        .output()
        .unwrap();
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("kind,index,t,phase,x,v_before,v_after,to_well")
    );
    assert!(lines.next().unwrap().starts_with("impact,0,0.0,0.0,"));
    assert!(lines.next().unwrap().starts_with("impact,1,3.7725317"));
}

#[test]
fn paper_chatter_rule_is_selectable() {
    let out = bin()
        .args([
            "--omega",
            "0.2",
            "--velocity",
            "0.05",
            "--t-end",
            "12",
            "--chatter",
            "paper",
        ])
        .output()
        .unwrap();
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text
        .lines()
        .any(|l| l.starts_with("stick_start,0,10.22186")));
}

#[test]
fn bad_arguments_fail() {
    for args in [
        vec!["--velocity", "0.07"],
        vec!["--omega", "x", "--velocity", "0.07"],
        vec!["--omega", "1.75", "--velocity", "0.07", "--chatter", "nope"],
        vec!["--omega", "1.75", "--velocity", "0.07", "--bogus"],
        vec!["--omega", "-1", "--velocity", "0.07"],
    ] {
        let out = bin().args(&args).output().unwrap();
        assert!(!out.status.success(), "{args:?}");
        let err = String::from_utf8(out.stderr).unwrap();
        assert!(err.starts_with("error:"), "{args:?}: {err}");
    }
}
