//! End-to-end tests of `bistable simulate`: the built binary is run as a user would.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use bistable_core::{ChatterRule, Event, Params, Simulator, Sinusoid, SolverOptions};

fn bistable(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_bistable"))
        .args(args)
        .output()
        .expect("run bistable")
}

/// A fresh directory for one test's files.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("bistable-cli-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Header and rows of a CSV file (no quoting in our files).
fn read_csv(path: &Path) -> (String, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    let header = lines.next().expect("header").to_string();
    let rows = lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    (header, rows)
}

fn f(x: &str) -> f64 {
    x.parse().unwrap_or_else(|e| panic!("'{x}': {e}"))
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn impacts_csv_matches_the_core_event_list() {
    let dir = scratch("impacts");
    let csv = dir.join("imp.csv");
    let o = bistable(&[
        "simulate",
        "--omega",
        "1.75",
        "--velocity",
        "0.07",
        "--periods",
        "30",
        "--impacts",
        s(&csv),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (header, rows) = read_csv(&csv);
    assert_eq!(header, "index,t,phase,x,v_before,v_after,delta_k");

    // The same case straight from the core, with the CLI's documented defaults (the core's
    // default tolerance and accumulation rule).
    let plate = Sinusoid::new(1.75, 0.07).unwrap();
    let opts = SolverOptions::default();
    let mut sim = Simulator::new(Params::new(0.02, 0.85).unwrap(), plate.into(), opts).unwrap();
    let impacts: Vec<_> = sim
        .events_until(30.0 * std::f64::consts::TAU)
        .unwrap()
        .into_iter()
        .filter_map(|e| match e {
            Event::Impact(i) => Some(i),
            _ => None,
        })
        .collect();
    assert!(impacts.len() > 20);
    assert_eq!(rows.len(), impacts.len(), "row count");

    // Row 0: the impact at τ = 0 with v_after = (1+e)V.
    let r0 = &rows[0];
    assert_eq!(r0[0], "0");
    assert_eq!(f(&r0[1]), 0.0);
    assert_eq!(f(&r0[2]), 0.0);
    assert_eq!(f(&r0[4]), 0.0);
    assert!(
        (f(&r0[5]) - 1.85 * 0.07).abs() < 1e-15,
        "v_after = {}",
        r0[5]
    );

    // Every value equals the core's exactly (shortest round-trip text).
    for (row, imp) in rows.iter().zip(&impacts) {
        assert_eq!(row.len(), 7);
        assert_eq!(row[0].parse::<u64>().unwrap(), imp.index);
        let vals: Vec<f64> = row[1..].iter().map(|x| f(x)).collect();
        let want = [
            imp.t,
            imp.phase.unwrap(),
            imp.x,
            imp.v_before,
            imp.v_after,
            imp.delta_k,
        ];
        for (k, (a, b)) in vals.iter().zip(want).enumerate() {
            assert_eq!(
                a.to_bits(),
                b.to_bits(),
                "impact {} column {}: {a} vs {b}",
                imp.index,
                k + 1
            );
        }
    }
    // The paper's anchor: impact 1 at phase ≈ 0.05 cycles.
    assert!((f(&rows[1][2]) - 0.0507).abs() < 5e-4);

    // Companion files exist with their headers.
    let (h, _) = read_csv(&dir.join("imp_sticking.csv"));
    assert_eq!(h, "start,end,x_start,x_end");
    let (h, _) = read_csv(&dir.join("imp_snaps.csv"));
    assert_eq!(h, "t,v,to_well");
}

#[test]
fn sticking_and_snaps_files_match_the_core() {
    let dir = scratch("sticking");
    let csv = dir.join("chatter.csv");
    // Chatter and sticking at low frequency, with the paper's rule.
    let o = bistable(&[
        "simulate",
        "--omega",
        "0.2",
        "--velocity",
        "0.05",
        "--t-end",
        "60",
        "--chatter",
        "paper",
        "--impacts",
        s(&csv),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let opts = SolverOptions::new(SolverOptions::default().tol(), ChatterRule::paper()).unwrap();
    let plate = Sinusoid::new(0.2, 0.05).unwrap();
    let mut sim = Simulator::new(Params::paper(), plate.into(), opts).unwrap();
    let events = sim.events_until(60.0).unwrap();
    let mut starts = Vec::new();
    let mut ends = Vec::new();
    for e in &events {
        match *e {
            Event::StickStart { t, .. } => starts.push(t),
            Event::StickEnd { t, .. } => ends.push(t),
            _ => {}
        }
    }
    assert!(!starts.is_empty(), "the case should stick");
    let (_, rows) = read_csv(&dir.join("chatter_sticking.csv"));
    assert_eq!(rows.len(), starts.len());
    for (i, row) in rows.iter().enumerate() {
        assert_eq!(row.len(), 4, "{row:?}");
        assert_eq!(f(&row[0]), starts[i]);
        match ends.get(i) {
            Some(&end) => assert_eq!(f(&row[1]), end),
            None => assert!(
                row[1].is_empty() && row[3].is_empty(),
                "open interval: {row:?}"
            ),
        }
    }
    let (_, imp_rows) = read_csv(&csv);
    let n_impacts = events
        .iter()
        .filter(|e| matches!(e, Event::Impact(_)))
        .count();
    assert_eq!(imp_rows.len(), n_impacts);
}

#[test]
fn snap_through_file() {
    let dir = scratch("snaps");
    let csv = dir.join("esc.csv");
    // V = 0.15 at Ω = 0.85 escapes to the second well after the first impact (paper Sec. 5).
    let o = bistable(&[
        "simulate",
        "--omega",
        "0.85",
        "--velocity",
        "0.15",
        "--periods",
        "20",
        "--impacts",
        s(&csv),
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (h, rows) = read_csv(&dir.join("esc_snaps.csv"));
    assert_eq!(h, "t,v,to_well");
    assert_eq!(rows.len(), 1);
    assert_eq!(rows[0][2], "2");
    assert!(f(&rows[0][1]) > 0.0);
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["final_well"], 2);
    assert_eq!(j["snap_throughs"], 1);
    assert_eq!(j["impacts"], 1);
}

#[test]
fn trace_is_equally_spaced_and_above_the_plate() {
    let dir = scratch("trace");
    let csv = dir.join("trace.csv");
    let o = bistable(&[
        "simulate",
        "--omega",
        "0.2",
        "--velocity",
        "0.05",
        "--t-end",
        "60",
        "--trace",
        s(&csv),
        "--dt",
        "0.01",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (header, rows) = read_csv(&csv);
    assert_eq!(header, "t,x,v,z,zdot");
    // t = k·0.01 for k = 0..=6000 (6000·0.01 = 60 exactly in double precision).
    assert_eq!(rows.len(), 6001);
    for (k, row) in rows.iter().enumerate() {
        assert_eq!(row.len(), 5);
        let t = f(&row[0]);
        assert_eq!(t, k as f64 * 0.01, "row {k}");
        let (x, z, zdot) = (f(&row[1]), f(&row[3]), f(&row[4]));
        assert!(x >= z - 1e-12, "row {k}: x = {x} below z = {z}");
        assert!((z - 0.25 * (0.2 * t).sin()).abs() < 1e-14);
        assert!((zdot - 0.05 * (0.2 * t).cos()).abs() < 1e-14);
    }
    // Spacing is uniform.
    let ts: Vec<f64> = rows.iter().map(|r| f(&r[0])).collect();
    for w in ts.windows(2) {
        assert!((w[1] - w[0] - 0.01).abs() < 1e-12);
    }
}

#[test]
fn trace_with_mode_and_well() {
    let dir = scratch("trace-mode");
    let csv = dir.join("trace.csv");
    let o = bistable(&[
        "simulate",
        "--omega",
        "0.2",
        "--velocity",
        "0.05",
        "--t-end",
        "20",
        "--trace",
        s(&csv),
        "--dt",
        "0.5",
        "--trace-mode",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (header, rows) = read_csv(&csv);
    assert_eq!(header, "t,x,v,z,zdot,mode,well");
    assert_eq!(rows.len(), 41);
    assert!(rows.iter().all(|r| r[6] == "1"));
    assert!(rows.iter().any(|r| r[5] == "sticking"));
    assert!(rows.iter().any(|r| r[5] == "free"));
    for r in rows.iter().filter(|r| r[5] == "sticking") {
        assert_eq!(r[1], r[3], "x = z while sticking");
    }
}

/// Width and height from a PNG's IHDR chunk, after checking the signature.
fn png_size(path: &Path) -> (u32, u32) {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert!(bytes.len() > 1000, "{} is too small", path.display());
    assert_eq!(
        &bytes[..8],
        b"\x89PNG\r\n\x1a\n",
        "PNG signature of {}",
        path.display()
    );
    assert_eq!(&bytes[12..16], b"IHDR");
    let w = u32::from_be_bytes(bytes[16..20].try_into().unwrap());
    let h = u32::from_be_bytes(bytes[20..24].try_into().unwrap());
    (w, h)
}

#[test]
fn plot_writes_three_pngs() {
    let dir = scratch("plot");
    let plots = dir.join("figs");
    let o = bistable(&[
        "simulate",
        "--omega",
        "1.75",
        "--velocity",
        "0.07",
        "--periods",
        "20",
        "--plot",
        s(&plots),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    for name in [
        "waveform.png",
        "phase_portrait.png",
        "energy_per_impact.png",
    ] {
        let (w, h) = png_size(&plots.join(name));
        assert!(w >= 800 && h >= 600, "{name}: {w}x{h}");
    }
}

#[test]
fn json_summary_has_the_documented_keys() {
    let o = bistable(&[
        "simulate",
        "--omega",
        "1.75",
        "--velocity",
        "0.07",
        "--t-end",
        "100",
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).expect("stdout is JSON");
    for key in [
        "omega",
        "velocity",
        "zeta",
        "restitution",
        "tol",
        "t_end",
        "impacts",
        "sticking_intervals",
        "snap_throughs",
        "final_well",
        "final_state",
        "wall_time_s",
        "steps",
    ] {
        assert!(j.get(key).is_some(), "missing key {key} in {j}");
    }
    for key in ["t", "x", "v", "z", "zdot", "mode"] {
        assert!(
            j["final_state"].get(key).is_some(),
            "missing final_state.{key}"
        );
    }
    assert_eq!(j["omega"], 1.75);
    assert_eq!(j["velocity"], 0.07);
    assert_eq!(j["zeta"], 0.02);
    assert_eq!(j["restitution"], 0.85);
    assert_eq!(j["tol"], SolverOptions::default().tol());
    assert_eq!(j["t_end"], 100.0);
    assert_eq!(j["final_state"]["t"], 100.0);
    assert_eq!(j["final_well"], 1);
    assert!(j["impacts"].as_u64().unwrap() > 10);
    assert!(j["steps"].as_u64().unwrap() > 0);
    assert!(j["wall_time_s"].as_f64().unwrap() >= 0.0);
    assert_eq!(j["final_state"]["mode"], "free");
}

#[test]
fn human_summary_by_default() {
    let o = bistable(&[
        "simulate",
        "--omega",
        "1.75",
        "--velocity",
        "0.07",
        "--periods",
        "5",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8(o.stdout).unwrap();
    assert!(out.contains("impacts:"), "{out}");
    assert!(out.contains("final state:"), "{out}");
    assert!(serde_json::from_str::<serde_json::Value>(&out).is_err());
}

#[test]
fn invalid_values_exit_2_and_name_the_option() {
    let base = ["simulate", "--omega", "1.75", "--velocity", "0.07"];
    let cases: &[(&[&str], &str)] = &[
        (&["--t-end", "10", "--restitution", "1.5"], "--restitution"),
        (&["--t-end", "10", "--restitution", "-0.1"], "--restitution"),
        (&["--t-end", "10", "--zeta", "-0.1"], "--zeta"),
        (&["--t-end", "10", "--zeta", "NaN"], "--zeta"),
        (&["--t-end", "10", "--tol", "0"], "--tol"),
        (&["--t-end", "10", "--tol", "0.5"], "--tol"),
        (&["--t-end", "-1"], "--t-end"),
        (&["--t-end", "inf"], "--t-end"),
        (&["--periods", "0"], "--periods"),
        (&["--t-end", "10", "--trace", "x.csv", "--dt", "0"], "--dt"),
    ];
    for (extra, option) in cases {
        let mut args: Vec<&str> = base.to_vec();
        args.extend_from_slice(extra);
        let o = bistable(&args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains(option),
            "{args:?}: message does not name {option}: {err}"
        );
        assert_eq!(err.trim().lines().count(), 1, "one line: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
    // Bad shaker parameters (--omega, --velocity themselves).
    for (omega, velocity, option) in [
        ("-1", "0.07", "--omega"),
        ("0", "0.07", "--omega"),
        ("nan", "0.07", "--omega"),
        // Beyond the core's range of Ω (a run at Ω = 1e20 would fall through the plate).
        ("1e20", "0.07", "--omega"),
        ("1.0000000000000002e6", "0.07", "--omega"),
        ("9.9e-7", "0.07", "--omega"),
        ("1.75", "-0.07", "--velocity"),
        ("1.75", "inf", "--velocity"),
        ("1.75", "1.0000000000000002e6", "--velocity"),
    ] {
        let o = bistable(&[
            "simulate",
            "--omega",
            omega,
            "--velocity",
            velocity,
            "--t-end",
            "10",
        ]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{omega} {velocity}: {err}");
        assert!(err.contains(option), "{err}");
        assert!(err.contains("must be"), "states the allowed range: {err}");
    }
}

#[test]
fn missing_or_conflicting_options_are_usage_errors() {
    for args in [
        // Neither --t-end nor --periods.
        &["simulate", "--omega", "1", "--velocity", "0.1"][..],
        // Both.
        &[
            "simulate",
            "--omega",
            "1",
            "--velocity",
            "0.1",
            "--t-end",
            "5",
            "--periods",
            "1",
        ],
        // --trace without --dt, --dt without --trace.
        &[
            "simulate",
            "--omega",
            "1",
            "--velocity",
            "0.1",
            "--t-end",
            "5",
            "--trace",
            "t.csv",
        ],
        &[
            "simulate",
            "--omega",
            "1",
            "--velocity",
            "0.1",
            "--t-end",
            "5",
            "--dt",
            "0.1",
        ],
        // Missing --omega; a value that is not a number; an unknown chatter rule.
        &["simulate", "--velocity", "0.1", "--t-end", "5"],
        &[
            "simulate",
            "--omega",
            "fast",
            "--velocity",
            "0.1",
            "--t-end",
            "5",
        ],
        &[
            "simulate",
            "--omega",
            "1",
            "--velocity",
            "0.1",
            "--t-end",
            "5",
            "--chatter",
            "x",
        ],
    ] {
        let o = bistable(args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).starts_with("error:"), "{}", stderr(&o));
        assert!(o.stdout.is_empty());
    }
    let o = bistable(&["simulate", "--omega", "1", "--velocity", "0.1"]);
    assert!(stderr(&o).contains("--t-end") && stderr(&o).contains("--periods"));
}

#[test]
fn io_errors_name_the_file() {
    let dir = scratch("io");
    // A regular file where a directory is needed.
    let blocker = dir.join("not-a-dir");
    std::fs::write(&blocker, "x").unwrap();
    let target = blocker.join("imp.csv");
    let o = bistable(&[
        "simulate",
        "--omega",
        "1",
        "--velocity",
        "0.1",
        "--t-end",
        "5",
        "--impacts",
        s(&target),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains(s(&target)) || stderr(&o).contains(s(&blocker)),
        "{}",
        stderr(&o)
    );
    let o = bistable(&[
        "simulate",
        "--omega",
        "1",
        "--velocity",
        "0.1",
        "--t-end",
        "5",
        "--plot",
        s(&blocker),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains(s(&blocker)), "{}", stderr(&o));
}

#[test]
fn help_documents_units_and_formats() {
    let o = bistable(&["simulate", "--help"]);
    assert!(o.status.success());
    let help = String::from_utf8(o.stdout).unwrap();
    for needle in [
        "index,t,phase,x,v_before,v_after,delta_k",
        "start,end,x_start,x_end",
        "t,v,to_well",
        "t,x,v,z,zdot",
        "_sticking.csv",
        "_snaps.csv",
        "natural period",
        "--omega",
        "--chatter",
        "--json",
    ] {
        assert!(help.contains(needle), "--help lacks '{needle}'");
    }
}
