//! End-to-end tests of the analysis subcommands (`classify`, `map`, `bifurcation`, `orbit`,
//! `thresholds`, `energy-map`, `spectrum`): the built binary is run as a user would, and its
//! results are checked against the paper and against the core.

use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use bistable_core::{Event, Params, Simulator, Sinusoid, SolverOptions};
use serde_json::Value;

fn bistable(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_bistable"))
        .args(args)
        .output()
        .expect("run bistable")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Runs and parses the JSON on stdout; panics with stderr on failure.
fn json(args: &[&str]) -> Value {
    let o = bistable(args);
    assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    serde_json::from_slice(&o.stdout)
        .unwrap_or_else(|e| panic!("{args:?}: {e}: {}", String::from_utf8_lossy(&o.stdout)))
}

/// A fresh directory for one test's files.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "bistable-cli-analyses-{}-{name}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Asserts that `path` is a PNG of at least 800 × 600 pixels.
fn assert_png(path: &Path) {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "{}", path.display());
    let w = u32::from_be_bytes(bytes[16..20].try_into().unwrap());
    let h = u32::from_be_bytes(bytes[20..24].try_into().unwrap());
    assert!(w >= 800 && h >= 600, "{}: {w} × {h}", path.display());
}

/// CSV rows as maps from column name to text.
fn csv_rows(path: &Path) -> Vec<std::collections::HashMap<String, String>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_string)
        .collect();
    lines
        .map(|l| {
            header
                .iter()
                .cloned()
                .zip(l.split(',').map(str::to_string))
                .collect()
        })
        .collect()
}

const CLASSIFY_KEYS: [&str; 12] = [
    "class",
    "period",
    "chaotic",
    "snap_throughs",
    "final_well",
    "at_rest_in_second_well",
    "periods_simulated",
    "lyapunov",
    "impacts_per_period",
    "stopped_early",
    "wall_time_s",
    "sticking",
];

#[test]
fn classify_reports_the_paper_classes() {
    let c = json(&["classify", "--omega", "0.85", "--velocity", "0.11"]);
    for k in CLASSIFY_KEYS {
        assert!(c.get(k).is_some(), "missing key {k}: {c}");
    }
    assert_eq!(c["class"], "intrawell");
    assert_eq!(c["period"], 4);
    assert_eq!(c["impacts_per_period"], 5);
    assert_eq!(c["chaotic"], false);
    assert_eq!(c["snap_throughs"], 0);
    assert_eq!(c["final_well"], 1);
    assert_eq!(c["at_rest_in_second_well"], false);
    assert_eq!(c["stopped_early"], true);
    assert!(c["periods_simulated"].as_f64().unwrap() < 20_000.0);

    let c = json(&["classify", "--omega", "0.85", "--velocity", "0.15"]);
    assert_eq!(c["class"], "transient_interwell");
    assert_eq!(c["at_rest_in_second_well"], true);
    assert_eq!(c["final_well"], 2);
    assert_eq!(c["snap_throughs"], 1);

    // --full runs the whole length and decides the same class.
    let c = json(&[
        "classify",
        "--omega",
        "0.85",
        "--velocity",
        "0.11",
        "--full",
        "--max-periods",
        "400",
    ]);
    assert_eq!(c["stopped_early"], false);
    assert!(
        (c["periods_simulated"].as_f64().unwrap() - 400.0).abs() < 2.0,
        "{c}"
    );
    assert_eq!(
        (c["class"].as_str(), c["period"].as_u64()),
        (Some("intrawell"), Some(4))
    );
}

/// The `outcomes` of a classify JSON as `(class:period:well, fraction)`, most frequent first;
/// checks that every entry is an object with the documented keys, consistent with `runs`.
fn outcomes(c: &Value) -> Vec<(String, f64)> {
    let runs = c["runs"].as_u64().unwrap() as f64;
    c["outcomes"]
        .as_array()
        .unwrap_or_else(|| panic!("outcomes is not a list: {c}"))
        .iter()
        .map(|o| {
            // (serde_json's map sorts keys here; the printed order is checked by the Python
            // tests, which compare with `bi.classify`'s dicts.)
            let mut keys: Vec<&str> = o.as_object().unwrap().keys().map(|k| k.as_str()).collect();
            keys.sort_unstable();
            assert_eq!(
                keys,
                [
                    "chaotic",
                    "class",
                    "count",
                    "final_well",
                    "fraction",
                    "period"
                ],
                "{o}"
            );
            let period = match (&o["period"], &o["chaotic"]) {
                (Value::Number(p), _) => format!("P-{p}"),
                (_, Value::Bool(true)) => "chaotic".into(),
                _ => "aperiodic".into(),
            };
            let well = o["final_well"]
                .as_u64()
                .map_or("-".to_string(), |w| w.to_string());
            let fraction = o["fraction"].as_f64().unwrap();
            assert_eq!(fraction, o["count"].as_u64().unwrap() as f64 / runs, "{o}");
            (
                format!("{}:{period}:{well}", o["class"].as_str().unwrap()),
                fraction,
            )
        })
        .collect()
}

/// A mass that never leaves the plate (V = 0: the plate stands still and the mass rests on
/// it) is reported at rest, on the plate (sticking), without impacts; a plate that moves
/// launches it (not at rest), and rest in well 2 is at rest too.
#[test]
fn classify_reports_a_mass_that_never_leaves_the_plate_at_rest() {
    let c = json(&["classify", "--omega", "0.85", "--velocity", "0"]);
    assert_eq!(c["at_rest"], true, "{c}");
    assert_eq!(c["sticking"], true, "{c}");
    assert_eq!(c["impacts_per_period"], 0, "{c}");
    assert_eq!(
        (&c["class"], &c["final_well"], &c["at_rest_in_second_well"]),
        (&"intrawell".into(), &1.into(), &false.into()),
        "{c}"
    );
    let c = json(&["classify", "--omega", "0.85", "--velocity", "0.01"]);
    assert_eq!(
        (&c["at_rest"], &c["sticking"]),
        (&false.into(), &false.into()),
        "{c}"
    );
    assert!(c["impacts_per_period"].as_u64().unwrap() > 0, "{c}");
    let c = json(&["classify", "--omega", "0.85", "--velocity", "0.15"]);
    assert_eq!(
        (&c["at_rest"], &c["at_rest_in_second_well"]),
        (&true.into(), &true.into())
    );
    assert_eq!(c["sticking"], false, "{c}");
}

#[test]
fn classify_flags_points_whose_outcome_rounding_decides() {
    // The paper's (0.85, 0.13): a chaotic transient of hundreds of shaker periods ends at rest
    // in well 2 or on the continuous interwell P-1 orbit, depending on rounding.
    let c = json(&["classify", "--omega", "0.85", "--velocity", "0.13"]);
    assert_eq!(c["sensitive"], true, "{c}");
    assert_eq!(c["runs"], 9);
    assert_eq!(c["sensitivity_trigger"], "growth");
    let o = outcomes(&c);
    let mut keys: Vec<&str> = o.iter().map(|x| x.0.as_str()).collect();
    keys.sort();
    assert_eq!(
        keys,
        ["continuous_interwell:P-1:-", "transient_interwell:P-1:2"],
        "{c}"
    );
    // Shares are multiples of 1/9 (counts of the 9 runs).
    assert!((o.iter().map(|x| x.1).sum::<f64>() - 1.0).abs() < 1e-12);
    // The reported class is the most frequent outcome.
    assert!(o[0].0.starts_with(c["class"].as_str().unwrap()), "{c}");
    assert_eq!(c["majority_fraction"].as_f64().unwrap(), o[0].1);
    assert!(c["efoldings"].as_f64().unwrap() >= c["efoldings_threshold"].as_f64().unwrap());

    // Decided early with little growth: a single run, identical to a run without the test.
    for (w, v) in [("1.75", "0.07"), ("0.85", "0.11"), ("0.85", "0.15")] {
        let c = json(&["classify", "--omega", w, "--velocity", v]);
        assert_eq!(
            (c["sensitive"].clone(), c["runs"].clone()),
            (false.into(), 1.into()),
            "{c}"
        );
        assert_eq!(c["sensitivity_trigger"], "none");
        let plain = json(&["classify", "--omega", w, "--velocity", v, "--repeats", "0"]);
        for k in [
            "class",
            "period",
            "snap_throughs",
            "final_well",
            "periods_simulated",
        ] {
            assert_eq!(c[k], plain[k], "{w} {v} {k}");
        }
        assert_eq!(plain["efoldings"], Value::Null);
    }

    // A chaotic attractor reached and kept by every run is a determinate outcome.
    let c = json(&["classify", "--omega", "2.45", "--velocity", "0.07"]);
    assert_eq!(c["sensitive"], false, "{c}");
    assert_eq!(c["chaotic"], true);
    assert_eq!(c["sensitivity_trigger"], "aperiodic");
    assert_eq!(outcomes(&c), [("intrawell:chaotic:1".to_string(), 1.0)]);
}

/// Every point of the 60 × 40 map grid whose label changes between tol 1e-16, 1e-15 and 1e-14
/// (`tests/data/tol_flips_60x40.csv`, see `tests/data/README.md`) is flagged sensitive, with the
/// map's Lyapunov window of 300 shaker periods. One, (2.7169, 0.015), is a late transition: the
/// chaotic run enters a non-chaotic aperiodic regime after about 5,000 natural periods at tol
/// 1e-14 but only after about 21,000 at tol 1e-16, past the 20,000 of a map run; run for
/// 22,500, the windows in the last quarter of the run meet both regimes and flag it.
#[test]
fn every_point_whose_label_flips_with_tol_is_sensitive() {
    let text = include_str!("data/tol_flips_60x40.csv");
    let points: Vec<(String, String)> = text
        .lines()
        .skip(1)
        .map(|l| {
            let mut f = l.split(',');
            (f.next().unwrap().to_string(), f.next().unwrap().to_string())
        })
        .collect();
    assert_eq!(points.len(), 19);
    let late = ("2.716949152542373", "0.015");
    let results: Vec<(bool, Value)> = std::thread::scope(|s| {
        let handles: Vec<_> = points
            .iter()
            .map(|(w, v)| {
                let (periods, windows) = if (w.as_str(), v.as_str()) == late {
                    ("22500", "1024")
                } else {
                    ("20000", "8")
                };
                s.spawn(move || {
                    let c = json(&[
                        "classify",
                        "--omega",
                        w,
                        "--velocity",
                        v,
                        "--lyapunov-periods",
                        "300",
                        "--max-periods",
                        periods,
                        "--lyapunov-windows",
                        windows,
                    ]);
                    (c["sensitive"] == true, c)
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    let missed: Vec<String> = results
        .iter()
        .filter(|r| !r.0)
        .map(|r| {
            format!(
                "({}, {}): {}",
                r.1["omega"], r.1["velocity"], r.1["outcomes"]
            )
        })
        .collect();
    assert!(missed.is_empty(), "not flagged: {missed:#?}");
}

/// The map's sensitivity test skips work without changing any label: on the 60 × 40 grid every
/// point has the label (class, period, chaotic, final well, at rest in well 2) of the full test
/// it replaced (`tests/data/map_labels_60x40.csv`: further Lyapunov windows integrated after the
/// run, repeats of an aperiodic run over 1,000 natural periods; see `tests/data/README.md`).
#[test]
fn map_labels_equal_those_of_the_full_sensitivity_test() {
    let dir = scratch("labels");
    let csv = dir.join("map.csv");
    json(&[
        "map",
        "--omega-range",
        "0.2:3.5:60",
        "--velocity-range",
        "0.005:0.2:40",
        "--out",
        s(&csv),
        "--json",
    ]);
    let label = |r: &std::collections::HashMap<String, String>| {
        [
            "class",
            "period",
            "chaotic",
            "final_well",
            "at_rest_in_second_well",
        ]
        .map(|k| r[k].as_str())
        .join("/")
    };
    let rows: std::collections::HashMap<(String, String), (String, String)> = csv_rows(&csv)
        .iter()
        .map(|r| {
            (
                (r["omega"].clone(), r["velocity"].clone()),
                (label(r), r["sensitive"].clone()),
            )
        })
        .collect();
    assert_eq!(rows.len(), 2400);
    let stored = include_str!("data/map_labels_60x40.csv");
    let (mut changed, mut flags_gained, mut flags_lost) = (Vec::new(), 0, 0);
    for line in stored.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let (label, sensitive) = &rows[&(f[0].to_string(), f[1].to_string())];
        if label != f[2] {
            changed.push(format!("({}, {}): {} -> {label}", f[0], f[1], f[2]));
        }
        match (f[3], sensitive.as_str()) {
            ("false", "true") => flags_gained += 1,
            ("true", "false") => flags_lost += 1,
            _ => {}
        }
    }
    assert!(
        changed.is_empty(),
        "{} labels changed ({flags_gained} sensitive flags gained, {flags_lost} lost): {changed:#?}",
        changed.len()
    );
    eprintln!(
        "60 x 40 labels unchanged; sensitive flags: {flags_gained} gained, {flags_lost} lost"
    );
}

#[test]
fn basins_find_coexisting_attractors_and_resume() {
    let dir = scratch("basins");
    let (csv, png) = (dir.join("basins.csv"), dir.join("basins.png"));
    let args = |extra: &[&str]| {
        let mut a: Vec<String> = [
            "basins",
            "--omega",
            "1.45",
            "--velocity",
            "0.05",
            "--x-range",
            "0:1.2:24",
            "--v-range",
            "-0.6:0.6:24",
            "--uncertainty-samples",
            "60",
            "--out",
            s(&csv),
            "--plot",
            s(&png),
            "--json",
        ]
        .iter()
        .map(|x| x.to_string())
        .collect();
        a.extend(extra.iter().map(|x| x.to_string()));
        a
    };
    let run = |a: Vec<String>| json(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let b = run(args(&[]));
    assert_png(&png);
    assert_eq!(b["points"], 576);
    let attractors = b["attractors"].as_array().unwrap();
    // Rest in well 2 and a P-1 orbit in well 1 coexist (and share most of the plane).
    let labels: Vec<&str> = attractors
        .iter()
        .map(|a| a["label"].as_str().unwrap())
        .collect();
    assert!(labels.contains(&"rest in well 2"), "{labels:?}");
    assert!(
        labels.iter().any(|l| l.starts_with("P-1 in well 1")),
        "{labels:?}"
    );
    let total: f64 = attractors
        .iter()
        .map(|a| a["fraction"].as_f64().unwrap())
        .sum();
    assert!((total - 1.0).abs() < 1e-12);
    assert!(attractors
        .iter()
        .all(|a| a["fraction"].as_f64().unwrap() >= 0.0));
    // Every start's row agrees with `classify` run from the same state: the start (0, 0) at
    // phase 0 is the paper's initial condition.
    let rows = csv_rows(&csv);
    assert_eq!(rows.len(), 576);
    let origin = rows
        .iter()
        .find(|r| r["x0"] == "0" && r["v0"] == "-0.6")
        .expect("a row at x0 = 0");
    assert!(!origin["class"].is_empty());
    // f(ε) is a fraction and the exponent, when measured, positive.
    for u in b["uncertainty"].as_array().unwrap() {
        let f = u["fraction"].as_f64().unwrap();
        assert!((0.0..=1.0).contains(&f));
    }
    if let Some(a) = b["uncertainty_exponent"].as_f64() {
        assert!(a > 0.0 && a <= 1.5, "{a}");
    }
    // A rerun resumes every start and finds the same attractors.
    let again = run(args(&[]));
    assert_eq!(
        (again["computed"].clone(), again["resumed"].clone()),
        (0.into(), 576.into())
    );
    assert_eq!(again["attractors"], b["attractors"]);

    // Starts below the plate are refused, naming the option: at a quarter cycle the plate is at
    // its top, V/Ω = 0.0345.
    let o = bistable(&[
        "basins",
        "--omega",
        "1.45",
        "--velocity",
        "0.05",
        "--phase",
        "0.25",
        "--x-range",
        "0:1:4",
        "--plot",
        "x.png",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("--x-range") && stderr(&o).contains("below the plate"),
        "{}",
        stderr(&o)
    );
    let o = bistable(&[
        "basins",
        "--omega",
        "1.45",
        "--velocity",
        "0.05",
        "--phase",
        "1.5",
        "--plot",
        "x.png",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--phase"), "{}", stderr(&o));
    let o = bistable(&[
        "basins",
        "--omega",
        "1.45",
        "--velocity",
        "0.05",
        "--x-range",
        "0:1:4",
        "--recurrence-hits",
        "0",
        "--plot",
        "x.png",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--recurrence-hits"), "{}", stderr(&o));
}

#[test]
fn basins_by_recurrence_label_cells_as_the_full_decision() {
    // The default decides by recurrence (docs/sensitivity.md), --full-decision every start in
    // full: on this 30 × 30 grid the same cells but for the columns that tell how.
    let dir = scratch("basins_rec");
    let mut rows = Vec::new();
    for extra in [None, Some("--full-decision")] {
        let csv = dir.join(format!("{}.csv", extra.is_some()));
        let _ = std::fs::remove_file(&csv);
        let mut a = vec![
            "basins",
            "--omega",
            "1.45",
            "--velocity",
            "0.05",
            "--x-range",
            "0:1.2:30",
            "--v-range",
            "-0.6:0.6:30",
            "--uncertainty-samples",
            "0",
            "--out",
            s(&csv),
            "--json",
        ];
        a.extend(extra);
        let b = json(&a);
        let captured = b["recurrence"]["decided_by_recurrence"].as_u64();
        match extra {
            None => {
                assert_eq!(b["decision"], "recurrence");
                assert!(captured.is_some_and(|n| n > 0), "{b}");
            }
            Some(_) => {
                assert_eq!(b["decision"], "full");
                assert!(b["recurrence"].is_null());
            }
        }
        rows.push(csv_rows(&csv));
    }
    let key = |r: &std::collections::HashMap<String, String>| (r["x0"].clone(), r["v0"].clone());
    let full: std::collections::HashMap<_, _> = rows[1].iter().map(|r| (key(r), r)).collect();
    assert_eq!(rows[0].len(), 900);
    for r in &rows[0] {
        let f = full[&key(r)];
        for c in [
            "class",
            "period",
            "chaotic",
            "final_well",
            "at_rest_in_second_well",
        ] {
            assert_eq!(r[c], f[c], "{c} at {:?}", key(r));
        }
        assert_eq!(f["decided_by"], "full");
    }
}

#[test]
fn basin_cells_match_classify_from_the_paper_start() {
    // The cell (0, 0) at phase 0 is the paper's initial condition: the same outcome as
    // `classify` (whose decided-early runs are single runs).
    let dir = scratch("basins1");
    let csv = dir.join("b.csv");
    for (w, v) in [("0.85", "0.11"), ("1.75", "0.07"), ("0.85", "0.15")] {
        let _ = std::fs::remove_file(&csv);
        let b = json(&[
            "basins",
            "--omega",
            w,
            "--velocity",
            v,
            "--x-range",
            "0:0:1",
            "--v-range",
            "0:0:1",
            "--uncertainty-samples",
            "0",
            "--max-periods",
            "20000",
            "--out",
            s(&csv),
            "--json",
        ]);
        let c = json(&["classify", "--omega", w, "--velocity", v]);
        let row = &csv_rows(&csv)[0];
        assert_eq!(row["class"], c["class"].as_str().unwrap(), "{w} {v}");
        assert_eq!(row["period"], c["period"].to_string(), "{w} {v}");
        assert_eq!(
            row["periods_simulated"].parse::<f64>().unwrap(),
            c["periods_simulated"].as_f64().unwrap()
        );
        assert_eq!(b["attractors"].as_array().unwrap().len(), 1);
    }
}

#[test]
fn period_doubling_into_chaos_at_v_0_07() {
    let dir = scratch("bifurcation");
    let (csv, png) = (dir.join("bif.csv"), dir.join("bif.png"));
    // Ω = 2.0 + 0.005·i: 2.2 is i = 40, 2.245 is i = 49, 2.45 is i = 90.
    let b = json(&[
        "bifurcation",
        "--param",
        "omega",
        "--range",
        "2.0:2.7:141",
        "--velocity",
        "0.07",
        "--out",
        s(&csv),
        "--plot",
        s(&png),
        "--json",
    ]);
    assert_png(&png);
    let points = b["points"].as_array().unwrap();
    assert_eq!(points.len(), 141);
    let distinct = |i: usize| points[i]["distinct_max_x"].as_u64().unwrap();
    assert_eq!(distinct(0), 1, "Ω = 2.0: period 1");
    assert_eq!(distinct(40), 2, "Ω = 2.2: period 2");
    assert_eq!(distinct(49), 4, "Ω = 2.245: period 4");
    assert!(distinct(90) > 50, "Ω = 2.45: chaos, {}", distinct(90));
    // The cascade in order: the number of distinct maxima only doubles up to chaos.
    let first_chaos = (0..141).find(|&i| distinct(i) > 16).unwrap();
    let counts: Vec<u64> = (0..first_chaos).map(distinct).collect();
    assert!(
        counts.windows(2).all(|w| w[1] == w[0] || w[1] == 2 * w[0]),
        "{counts:?}"
    );
    for p in [1, 2, 4] {
        assert!(counts.contains(&p), "{counts:?}");
    }
    // The CSV has 100 maxima per point and the impact phases in [0, 1).
    let rows = csv_rows(&csv);
    let maxima = rows.iter().filter(|r| r["kind"] == "max_x").count();
    assert_eq!(maxima, 141 * 100);
    assert!(rows
        .iter()
        .filter(|r| r["kind"] == "impact_phase")
        .all(|r| (0.0..1.0).contains(&r["value"].parse::<f64>().unwrap())));
    // Orbits: stable period 1 at Ω = 2.0; at 2.2 the period-1 orbit is unstable with a
    // multiplier below −1 (it doubled) and a stable period-2 orbit exists.
    let orbits = csv_rows(&dir.join("bif_orbits.csv"));
    let at = |w: f64, p: &str| {
        orbits
            .iter()
            .filter(|r| (r["omega"].parse::<f64>().unwrap() - w).abs() < 1e-12 && r["period"] == p)
            .collect::<Vec<_>>()
    };
    assert!(at(2.0, "1").iter().any(|r| r["stable"] == "true"));
    let p1 = at(2.2, "1");
    assert!(p1.iter().any(|r| r["stable"] == "false"
        && r["multiplier_1_re"].parse::<f64>().unwrap() < -1.0
        && r["multiplier_1_im"].parse::<f64>().unwrap() == 0.0));
    assert!(at(2.2, "2").iter().any(|r| r["stable"] == "true"));
}

#[test]
fn lyapunov_exponent_positive_in_chaos_negative_on_periodic_branches() {
    let c = json(&["classify", "--omega", "2.45", "--velocity", "0.07"]);
    assert_eq!(c["period"], Value::Null);
    assert_eq!(c["chaotic"], true);
    assert!(c["lyapunov"].as_f64().unwrap() > 0.01, "{c}");
    // The periodic attractors at 2.0 (P-1) and 2.2 (P-2): stable, negative Floquet exponent.
    for (w, p) in [("2.0", "1"), ("2.2", "2")] {
        let o = json(&[
            "orbit",
            "--omega",
            w,
            "--velocity",
            "0.07",
            "--period",
            p,
            "--json",
        ]);
        assert_eq!(o["stable"], true, "{o}");
        assert!(o["floquet_exponent"].as_f64().unwrap() < -1e-3, "{o}");
        assert!(o["max_abs_multiplier"].as_f64().unwrap() < 1.0);
    }
}

#[test]
fn stable_orbit_is_the_long_run_attractor() {
    let o = json(&["orbit", "--omega", "1.75", "--velocity", "0.07", "--json"]);
    assert_eq!(o["stable"], true);
    assert_eq!(o["period"], 1);
    assert_eq!(o["impacts"], 1);
    assert!(o["det_relative_error"].as_f64().unwrap() < 1e-9, "{o}");
    let m = &o["monodromy"];
    let det = m[0][0].as_f64().unwrap() * m[1][1].as_f64().unwrap()
        - m[0][1].as_f64().unwrap() * m[1][0].as_f64().unwrap();
    let identity = 0.85f64.powi(2) * (-2.0 * 0.02 * std::f64::consts::TAU / 1.75).exp();
    assert!(((det - identity) / identity).abs() < 1e-9);
    // The section point of a long run with the core, 3000 shaker periods from rest.
    let plate = Sinusoid::new(1.75, 0.07).unwrap();
    let mut sim = Simulator::new(Params::paper(), plate.into(), SolverOptions::default()).unwrap();
    sim.advance_instant(plate.section(3000), &mut |_: &Event| {})
        .unwrap();
    let st = sim.state();
    let (x0, v0) = (o["x0"].as_f64().unwrap(), o["v0"].as_f64().unwrap());
    assert!(
        (x0 - st.x).abs() < 1e-9 && (v0 - st.v).abs() < 1e-9,
        "{x0} {v0} vs {st:?}"
    );
    // From a rough guess Newton finds the same orbit.
    let g = json(&[
        "orbit",
        "--omega",
        "1.75",
        "--velocity",
        "0.07",
        "--guess",
        "0.05,0",
        "--json",
    ]);
    assert!((g["x0"].as_f64().unwrap() - x0).abs() < 1e-9);
    assert!(g["iterations"].as_u64().unwrap() > 1);
}

#[test]
fn orbit_continuation_writes_branches_and_plot() {
    let dir = scratch("continuation");
    let (csv, png) = (dir.join("orbits.csv"), dir.join("orbits.png"));
    let c = json(&[
        "orbit",
        "--continue-omega",
        "1.6:2.4:17",
        "--velocity",
        "0.05,0.07",
        "--settle",
        "500",
        "--out",
        s(&csv),
        "--plot",
        s(&png),
        "--json",
    ]);
    assert_png(&png);
    let branches = c["branches"].as_array().unwrap();
    assert_eq!(branches.len(), 2);
    for b in branches {
        assert!(b["orbits"].as_u64().unwrap() >= 17, "{b}");
    }
    let rows = csv_rows(&csv);
    // At V = 0.07 the period-1 orbit is stable at Ω = 1.75 … and unstable past the doubling.
    let stable_at = |w: f64| {
        rows.iter()
            .filter(|r| {
                r["velocity"] == "0.07" && (r["omega"].parse::<f64>().unwrap() - w).abs() < 1e-12
            })
            .map(|r| r["stable"] == "true")
            .collect::<Vec<_>>()
    };
    assert!(stable_at(1.8).contains(&true));
    assert!(stable_at(2.4).contains(&false));
}

#[test]
fn arclength_continuation_turns_at_folds() {
    let dir = scratch("arclength");
    let csv = dir.join("arc.csv");
    let c = json(&[
        "orbit",
        "--continue-omega",
        "0.8:2.0:61",
        "--velocity",
        "0.03",
        "--settle",
        "500",
        "--arclength",
        "--out",
        s(&csv),
        "--json",
    ]);
    assert_eq!(c["method"], "pseudo-arclength");
    // The resonance curve bends over: a lower fold near Ω = 1.57 and an upper one near 0.93.
    assert!(c["branches"][0]["folds"].as_u64().unwrap() >= 2, "{c}");
    let rows = csv_rows(&csv);
    let f = |r: &std::collections::HashMap<String, String>, k: &str| r[k].parse::<f64>().unwrap();
    // At Ω ≈ 1.2 three period-1 orbits coexist: small and large stable ones, and between them
    // a saddle (real multiplier > 1) that natural continuation cannot reach.
    let near: Vec<_> = rows
        .iter()
        .filter(|r| (f(r, "omega") - 1.2).abs() < 0.03)
        .collect();
    assert!(near
        .iter()
        .any(|r| r["stable"] == "true" && f(r, "max_x") < 0.1));
    assert!(near
        .iter()
        .any(|r| r["stable"] == "true" && f(r, "max_x") > 0.2));
    assert!(near.iter().any(|r| r["stable"] == "false"
        && f(r, "multiplier_1_re") > 1.0
        && f(r, "multiplier_1_im") == 0.0
        && f(r, "max_x") > 0.1
        && f(r, "max_x") < 0.3));
    // At a fold a real multiplier passes through +1.
    let closest = rows
        .iter()
        .filter(|r| f(r, "multiplier_1_im") == 0.0)
        .map(|r| (f(r, "multiplier_1_re") - 1.0).abs())
        .fold(f64::INFINITY, f64::min);
    assert!(closest < 0.05, "{closest}");
}

fn map_args<'a>(csv: &'a str, png: &'a str, extra: &[&'a str]) -> Vec<&'a str> {
    let mut a = vec![
        "map",
        "--omega-range",
        "0.85:1.85:3",
        "--velocity-range",
        "0.11:0.15:3",
        "--out",
        csv,
        "--plot",
        png,
        "--json",
    ];
    a.extend_from_slice(extra);
    a
}

#[test]
fn map_writes_resumes_and_classifies() {
    let dir = scratch("map");
    let (csv, png) = (dir.join("map.csv"), dir.join("map.png"));
    let m = json(&map_args(s(&csv), s(&png), &[]));
    assert_eq!(
        (m["points"].as_u64(), m["computed"].as_u64()),
        (Some(9), Some(9))
    );
    assert_png(&png);
    let rows = csv_rows(&csv);
    assert_eq!(rows.len(), 9);
    let row = |w: &str, v: &str| {
        rows.iter()
            .find(|r| r["omega"] == w && r["velocity"] == v)
            .unwrap_or_else(|| panic!("no row for {w}, {v}"))
    };
    assert_eq!(row("0.85", "0.11")["class"], "intrawell");
    assert_eq!(row("0.85", "0.11")["period"], "4");
    assert_eq!(row("0.85", "0.15")["class"], "transient_interwell");
    assert_eq!(row("0.85", "0.15")["at_rest_in_second_well"], "true");
    assert_eq!(row("0.85", "0.15")["final_well"], "2");

    // A rerun skips every point.
    let again = json(&map_args(s(&csv), s(&png), &[]));
    assert_eq!(
        (again["computed"].as_u64(), again["resumed"].as_u64()),
        (Some(0), Some(9))
    );
    assert_eq!(csv_rows(&csv).len(), 9);

    // An interrupted run: two rows lost and half a row written. Only those two are redone.
    let text = std::fs::read_to_string(&csv).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let mut cut = lines[..lines.len() - 2].join("\n");
    cut.push('\n');
    cut.push_str(&lines[lines.len() - 1][..10]);
    std::fs::write(&csv, cut).unwrap();
    let resumed = json(&map_args(s(&csv), s(&png), &[]));
    assert_eq!(resumed["computed"].as_u64(), Some(2));
    assert_eq!(resumed["resumed"].as_u64(), Some(7));
    let rows = csv_rows(&csv);
    assert_eq!(rows.len(), 9);
    assert!(rows.iter().all(|r| r.len() == 24), "no broken rows");

    // No lock is left behind; a lock held by a live process (this test) refuses the run, a
    // stale one (no such process) is taken over.
    let lock = dir.join("map.csv.lock");
    assert!(!lock.exists());
    std::fs::write(&lock, std::process::id().to_string()).unwrap();
    let o = bistable(&map_args(s(&csv), s(&png), &[]));
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("another run"), "{}", stderr(&o));
    std::fs::write(&lock, "999999999").unwrap();
    let o = bistable(&map_args(s(&csv), s(&png), &[]));
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!lock.exists());

    // The same file with another restitution is refused (exit 2, naming --out).
    let o = bistable(&map_args(s(&csv), s(&png), &["--restitution", "0.7"]));
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("--out") && stderr(&o).contains("e = 0.85"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn map_for_the_experimental_restitution() {
    let dir = scratch("map07");
    let (csv, png) = (dir.join("m.csv"), dir.join("m.png"));
    let m = json(&[
        "map",
        "--restitution",
        "0.7",
        "--omega-range",
        "0.5:3:6",
        "--velocity-range",
        "0.02:0.2:4",
        "--out",
        s(&csv),
        "--plot",
        s(&png),
        "--json",
    ]);
    assert_eq!(m["computed"].as_u64(), Some(24));
    assert_png(&png);
    let rows = csv_rows(&csv);
    assert!(rows.iter().all(|r| r["restitution"] == "0.7"));
    let v = |r: &std::collections::HashMap<String, String>| r["velocity"].parse::<f64>().unwrap();
    // Far below the interwell threshold (1−e)/(2(1+e)) = 0.088 the motion stays in well 1;
    // above the single-impact threshold 1/(4(1+e)) = 0.147 the first impact clears the barrier.
    assert!(rows
        .iter()
        .filter(|r| v(r) < 0.03)
        .all(|r| r["class"] == "intrawell"));
    assert!(rows
        .iter()
        .filter(|r| v(r) > 0.147)
        .all(|r| r["snap_throughs"].parse::<u64>().unwrap() >= 1));
}

#[test]
fn thresholds_energy_map_and_spectrum() {
    let t = json(&[
        "thresholds",
        "--restitution",
        "0.7",
        "--omega",
        "0.3",
        "--json",
    ]);
    assert!((t["single_impact"].as_f64().unwrap() - 1.0 / 6.8).abs() < 1e-15);
    assert!((t["interwell"].as_f64().unwrap() - 0.3 / 3.4).abs() < 1e-15);
    assert!((t["quasi_static"].as_f64().unwrap() - 0.15).abs() < 1e-15);
    let text = bistable(&["thresholds"]);
    assert!(String::from_utf8_lossy(&text.stdout).contains("0.135135"));

    let dir = scratch("figures");
    let em = dir.join("em.png");
    let o = bistable(&[
        "energy-map",
        "--overlay",
        "--omega",
        "1.75",
        "--velocity",
        "0.07",
        "--periods",
        "50",
        "--plot",
        s(&em),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_png(&em);

    let sp = |w: &str| {
        json(&[
            "spectrum",
            "--omega",
            w,
            "--velocity",
            "0.07",
            "--record",
            "256",
            "--plot",
            s(&dir.join(format!("sp{w}.png"))),
            "--json",
        ])
    };
    let periodic = sp("2.2");
    let chaotic = sp("2.45");
    assert_eq!(periodic["period"], 2);
    assert!((periodic["peak_freq_over_omega"].as_f64().unwrap() - 0.5).abs() < 1e-12);
    assert_eq!(chaotic["period"], Value::Null);
    // Chaos is broadband: the spectrum is many orders of magnitude flatter.
    let (fp, fc) = (
        periodic["spectral_flatness"].as_f64().unwrap(),
        chaotic["spectral_flatness"].as_f64().unwrap(),
    );
    assert!(fc > 1e-4 && fc > 1e6 * fp, "{fc} vs {fp}");
    assert_png(&dir.join("sp2.45.png"));
}

#[test]
fn bad_input_exits_2_naming_the_option() {
    let cases: &[(&[&str], &str)] = &[
        (
            &["classify", "--omega", "0.85", "--velocity", "-1"],
            "--velocity",
        ),
        (
            &["classify", "--omega", "0", "--velocity", "0.1"],
            "--omega",
        ),
        (
            &[
                "classify",
                "--omega",
                "1",
                "--velocity",
                "0.1",
                "--max-periods",
                "0",
            ],
            "--max-periods",
        ),
        (
            &["map", "--omega-range", "1:2", "--plot", "x.png"],
            "--omega-range",
        ),
        (
            &["map", "--velocity-range", "-0.1:0.2:5", "--plot", "x.png"],
            "--velocity-range",
        ),
        // Beyond the core's ranges (Ω in [1e-6, 1e6], V in [0, 1e6]): refused before any point.
        (
            &["map", "--omega-range", "1:1e7:3", "--plot", "x.png"],
            "--omega-range",
        ),
        (
            &["map", "--velocity-range", "0.1:2e6:3", "--plot", "x.png"],
            "--velocity-range",
        ),
        (
            &[
                "bifurcation",
                "--param",
                "omega",
                "--range",
                "1e-7:1:3",
                "--velocity",
                "0.07",
                "--plot",
                "x.png",
            ],
            "--range",
        ),
        (&["map", "--threads", "0", "--plot", "x.png"], "--threads"),
        (
            &[
                "classify",
                "--omega",
                "1",
                "--velocity",
                "0.1",
                "--horizon",
                "0",
            ],
            "--horizon",
        ),
        (
            &[
                "map",
                "--repeat-periods",
                "inf",
                "--out",
                "x.csv",
                "--plot",
                "x.png",
            ],
            "--repeat-periods",
        ),
        (&["map", "--omega-range", "0.5:1:3"], "--out"),
        (
            &[
                "bifurcation",
                "--param",
                "omega",
                "--range",
                "2:2.7:10",
                "--json",
            ],
            "--velocity",
        ),
        (
            &[
                "bifurcation",
                "--param",
                "velocity",
                "--range",
                "0:0.2:0",
                "--omega",
                "1",
                "--json",
            ],
            "--range",
        ),
        (
            &[
                "orbit",
                "--omega",
                "1.75",
                "--velocity",
                "0.07",
                "--period",
                "0",
            ],
            "--period",
        ),
        (
            &["orbit", "--omega", "1.75", "--velocity", "0.05,0.07"],
            "--velocity",
        ),
        (
            &[
                "orbit",
                "--omega",
                "1.75",
                "--velocity",
                "0.07",
                "--guess",
                "1",
            ],
            "--guess",
        ),
        (&["thresholds", "--restitution", "1"], "--restitution"),
        (
            &["energy-map", "--plot", "x.png", "--u-range", "3:1"],
            "--u-range",
        ),
        (
            &["energy-map", "--plot", "x.png", "--omega", "1"],
            "--overlay",
        ),
        (
            &[
                "spectrum",
                "--omega",
                "2",
                "--velocity",
                "0.07",
                "--record",
                "2",
            ],
            "--record",
        ),
    ];
    for (args, option) in cases {
        let o = bistable(args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(option), "{args:?}: {}", stderr(&o));
        assert!(o.stdout.is_empty(), "{args:?}");
    }
}

#[test]
fn every_analysis_has_help() {
    for (cmd, needle) in [
        ("classify", "intrawell"),
        ("map", "Resuming"),
        ("basins", "Uncertainty exponent"),
        ("bifurcation", "Hermite"),
        ("orbit", "Floquet"),
        ("thresholds", "1/(4(1+e))"),
        ("energy-map", "grazing"),
        ("spectrum", "Hann"),
    ] {
        let o = bistable(&[cmd, "--help"]);
        assert!(o.status.success(), "{cmd}");
        let text = String::from_utf8_lossy(&o.stdout);
        assert!(text.contains(needle), "{cmd} --help lacks '{needle}'");
    }
}

#[test]
fn orbit_continuation_locates_the_fig6_period_doubling() {
    let dir = scratch("bifurcations");
    let (csv, png) = (dir.join("p1.csv"), dir.join("p1.png"));
    let c = json(&[
        "orbit",
        "--continue-omega",
        "2.05:2.25:41",
        "--velocity",
        "0.07",
        "--out",
        s(&csv),
        "--plot",
        s(&png),
        "--json",
    ]);
    assert_png(&png);
    let points = c["bifurcations"].as_array().unwrap();
    assert_eq!(points.len(), 1, "{c}");
    let p = &points[0];
    assert_eq!(p["kind"], "period_doubling");
    assert_eq!(p["period"], 1);
    let omega = p["omega"].as_f64().unwrap();
    assert!(2.12 < omega && omega < 2.13, "{p}");
    assert!(p["omega_error"].as_f64().unwrap() <= 1e-12, "{p}");
    let lambda = p["multipliers"][0]["re"].as_f64().unwrap();
    assert!((lambda + 1.0).abs() < 1e-8, "{p}");
    // The same point in the CSV beside --out.
    let rows = csv_rows(&dir.join("p1_bifurcations.csv"));
    assert_eq!(rows.len(), 1);
    assert_eq!(rows[0]["kind"], "period_doubling");
    assert_eq!(rows[0]["omega"].parse::<f64>().unwrap(), omega);
    assert_eq!(rows[0]["impacts_before"], "1");
    // `bifurcation` finds it on its P-1 branch too, and the P-2 → P-4 doubling.
    let b = json(&[
        "bifurcation",
        "--param",
        "omega",
        "--range",
        "2.05:2.25:41",
        "--velocity",
        "0.07",
        "--branch-periods",
        "1,2",
        "--json",
    ]);
    let kinds: Vec<(u64, f64)> = b["bifurcations"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|p| p["kind"] == "period_doubling")
        .map(|p| (p["period"].as_u64().unwrap(), p["omega"].as_f64().unwrap()))
        .collect();
    assert_eq!(kinds.len(), 2, "{b}");
    assert!((kinds[0].1 - omega).abs() < 1e-10, "{kinds:?}");
    assert_eq!(kinds[1].0, 2);
    assert!(2.23 < kinds[1].1 && kinds[1].1 < 2.24, "{kinds:?}");
}

#[test]
fn atlas_continues_the_fig6_period_doubling_in_omega_and_v() {
    let dir = scratch("atlas");
    let csv = dir.join("pd.csv");
    let c = json(&[
        "atlas",
        "--continue-omega",
        "2.05:2.25:41",
        "--velocity",
        "0.07",
        "--velocity-bounds",
        "0.065,0.075",
        "--out",
        s(&csv),
        "--json",
    ]);
    let curves = c["curves"].as_array().unwrap();
    assert_eq!(curves.len(), 1, "{c}");
    assert_eq!(curves[0]["kind"], "period_doubling");
    let rows = csv_rows(&csv);
    assert_eq!(rows.len() as u64, curves[0]["points"].as_u64().unwrap());
    let f = |r: &std::collections::HashMap<String, String>, k: &str| r[k].parse::<f64>().unwrap();
    for r in &rows {
        assert!((f(r, "multiplier_1_re") + 1.0).abs() < 1e-8, "{r:?}");
    }
    // From the lower V bound, 0.065 (at Ω ≈ 2.19), to where Ω leaves the grid at 2.05 (at
    // V ≈ 0.074): Ω decreases as V grows.
    let (first, last) = (&rows[0], &rows[rows.len() - 1]);
    assert!(
        f(first, "velocity") < 0.0655 && f(first, "velocity") > 0.064,
        "{first:?}"
    );
    assert!(
        f(last, "omega") < 2.05 && f(last, "velocity") > 0.074,
        "{last:?}"
    );
    // Bounds that do not contain --velocity are refused, naming the option.
    let o = bistable(&[
        "atlas",
        "--continue-omega",
        "2.05:2.25:41",
        "--velocity",
        "0.07",
        "--velocity-bounds",
        "0.08,0.09",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--velocity-bounds"), "{}", stderr(&o));
}

#[test]
fn atlas_reports_codimension_two_points() {
    // At V = 0.05: the resonance fold and the high-energy branch's doubling cross at
    // (Ω, V) = (1.3805425687, 0.0606302369) (docs/bifurcations.md).
    let dir = scratch("atlas-points");
    let (csv, png) = (dir.join("fold.csv"), dir.join("fold.png"));
    let c = json(&[
        "atlas",
        "--continue-omega",
        "1.2:1.6:41",
        "--velocity",
        "0.05",
        "--arclength",
        "--velocity-bounds",
        "0.03,0.07",
        "--out",
        s(&csv),
        "--plot",
        s(&png),
        "--json",
    ]);
    let points = c["points"].as_array().unwrap();
    assert_eq!(points.len(), 1, "{c}");
    let p = &points[0];
    assert_eq!(p["kind"], "crossing");
    assert_eq!(
        (p["curve"].as_u64(), p["other_curve"].as_u64()),
        (Some(0), Some(1))
    );
    let at = |k: &str| p[k].as_f64().unwrap();
    assert!((at("omega") - 1.3805425687).abs() < 1e-9, "{p}");
    assert!((at("velocity") - 0.0606302369).abs() < 1e-9, "{p}");
    assert!(at("error") <= 1e-12, "{p}");
    // The same in <stem>_points.csv, written beside --out and listed with the files.
    let rows = csv_rows(&dir.join("fold_points.csv"));
    assert_eq!(rows.len(), 1);
    assert_eq!(rows[0]["kind"], "crossing");
    assert_eq!(rows[0]["omega"].parse::<f64>().unwrap(), at("omega"));
    assert_eq!(rows[0]["other_curve"], "1");
    let files: Vec<&str> = c["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f.as_str().unwrap())
        .collect();
    assert!(
        files.iter().any(|f| f.ends_with("fold_points.csv")),
        "{files:?}"
    );
    assert!(std::fs::metadata(&png).unwrap().len() > 0);
}

#[test]
fn atlas_plot_over_a_map_and_the_p1_p2_check() {
    let dir = scratch("atlas-map");
    let (map, curves, png) = (
        dir.join("map.csv"),
        dir.join("pd.csv"),
        dir.join("atlas.png"),
    );
    // 3 × 3 cells around the P-1 → P-2 doubling at (Ω, V) = (2.1243, 0.07): P-1 below and
    // left of the curve, P-2 above and right of it.
    json(&[
        "map",
        "--omega-range",
        "2.10:2.15:3",
        "--velocity-range",
        "0.065:0.075:3",
        "--out",
        s(&map),
        "--json",
    ]);
    fn atlas<'a>(extra: &[&'a str]) -> Vec<&'a str> {
        let mut a = vec![
            "atlas",
            "--continue-omega",
            "2.05:2.25:41",
            "--velocity",
            "0.07",
            "--velocity-bounds",
            "0.065,0.075",
        ];
        a.extend_from_slice(extra);
        a
    }
    let c = json(&atlas(&[
        "--out",
        s(&curves),
        "--map",
        s(&map),
        "--plot",
        s(&png),
        "--json",
    ]));
    assert_png(&png);
    let m = &c["map_check"];
    assert_eq!(m["pairs"], 4, "{c}");
    assert_eq!(m["crossed"], 4, "{c}");
    assert_eq!(m["fraction_in_span"], 1.0, "{c}");
    // The curves of an earlier run drawn again without a map.
    let c = json(&atlas(&[
        "--curves",
        s(&curves),
        "--plot",
        s(&png),
        "--json",
    ]));
    assert!(c.get("map_check").is_none(), "{c}");
    assert_png(&png);
    // Files of the wrong kind, or a map of another e, are refused with exit code 2.
    for (args, what) in [
        (vec!["--map", s(&curves)], "not a map file"),
        (vec!["--curves", s(&map)], "not an atlas file"),
        (vec!["--map", s(&map), "--restitution", "0.7"], "e = 0.7"),
        (vec!["--map", s(&dir.join("none.csv"))], "cannot be read"),
    ] {
        let o = bistable(&atlas(&args));
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(what), "{args:?}: {}", stderr(&o));
    }
}

/// The default box of starts is a valid one (x0 from 0, on the plate at phase 0, up).
#[test]
fn basins_default_x_range_is_accepted() {
    let dir = scratch("basins_default");
    let csv = dir.join("basins.csv");
    let v = json(&[
        "basins",
        "--omega",
        "1.45",
        "--velocity",
        "0.05",
        "--v-range",
        "0:0:1",
        "--uncertainty-samples",
        "0",
        "--out",
        s(&csv),
        "--json",
    ]);
    assert_eq!(v["x_range"], "0:1.2:100");
    assert_eq!(v["points"], 100);
}

/// `coexistence` over a small grid: `extra` options, `--out csv`, `--json`.
fn coexistence_args<'a>(csv: &'a str, extra: &[&'a str]) -> Vec<&'a str> {
    let mut a = vec![
        "coexistence",
        "--omega-range",
        "1.40:1.50:3",
        "--velocity-range",
        "0.04:0.05:2",
        "--starts",
        "8x8",
        "--max-periods",
        "2000",
        "--out",
        csv,
        "--json",
    ];
    a.extend_from_slice(extra);
    a
}

#[test]
fn coexistence_writes_resumes_and_matches_branches() {
    let dir = scratch("coexistence");
    let (csv, png) = (dir.join("co.csv"), dir.join("co.png"));
    let j = json(&coexistence_args(s(&csv), &["--plot", s(&png)]));
    assert_png(&png);
    assert_eq!(
        (j["points"].as_u64(), j["starts_per_point"].as_u64()),
        (Some(6), Some(64))
    );
    let rows = csv_rows(&csv);
    let text = std::fs::read_to_string(&csv).unwrap();
    // Grid order (Ω inner, V outer), every attractor of a point in one group, numbered from
    // 1 by basin size; fractions of the 64 starts with their binomial errors; one paper start.
    let mut points: Vec<(String, String)> = Vec::new();
    for r in &rows {
        let p = (r["omega"].clone(), r["velocity"].clone());
        if points.last() != Some(&p) {
            points.push(p);
        }
    }
    assert_eq!(points.len(), 6, "{text}");
    assert_eq!(points[1].0.parse::<f64>().unwrap(), 1.45);
    for (w, v) in &points {
        let here: Vec<_> = rows
            .iter()
            .filter(|r| &r["omega"] == w && &r["velocity"] == v)
            .collect();
        let n: usize = here[0]["attractors"].parse().unwrap();
        assert_eq!(here.len(), n);
        let counts: Vec<usize> = here.iter().map(|r| r["count"].parse().unwrap()).collect();
        assert_eq!(counts.iter().sum::<usize>(), 64, "{here:?}");
        assert!(counts.windows(2).all(|c| c[0] >= c[1]));
        for (k, r) in here.iter().enumerate() {
            assert_eq!(r["attractor"], (k + 1).to_string());
            assert!(!r["branch"].is_empty());
            let f: f64 = r["fraction"].parse().unwrap();
            let se: f64 = r["fraction_se"].parse().unwrap();
            assert_eq!(f, counts[k] as f64 / 64.0);
            assert!((se - (f * (1.0 - f) / 64.0).sqrt()).abs() < 1e-15);
        }
        assert_eq!(
            here.iter().filter(|r| r["paper_start"] == "true").count(),
            1
        );
        // One branch per attractor at a point.
        let mut b: Vec<&str> = here.iter().map(|r| r["branch"].as_str()).collect();
        b.sort_unstable();
        b.dedup();
        assert_eq!(b.len(), n);
    }
    // Rest in well 2 keeps one branch over the whole grid.
    let rest: Vec<&str> = rows
        .iter()
        .filter(|r| r["class"] == "rest")
        .map(|r| r["branch"].as_str())
        .collect();
    assert_eq!(rest.len(), 6);
    assert!(rest.iter().all(|b| *b == rest[0]));
    // The paper's start is the map's start: its class and period are `classify`'s.
    let c = json(&[
        "classify",
        "--omega",
        "1.45",
        "--velocity",
        "0.05",
        "--max-periods",
        "2000",
    ]);
    let paper = rows
        .iter()
        .find(|r| r["omega"] == "1.45" && r["velocity"] == "0.05" && r["paper_start"] == "true")
        .unwrap();
    assert_eq!(paper["paper_class"], c["class"].as_str().unwrap());
    assert_eq!(paper["paper_period"], c["period"].to_string());

    // Resuming after an interruption that left the first point's rows partly written: the
    // missing points are computed and the file ends as it was.
    let lines: Vec<&str> = text.lines().collect();
    let n0: usize = rows[0]["attractors"].parse().unwrap();
    assert!(n0 >= 2, "{text}");
    std::fs::write(
        &csv,
        format!("{}\n{}\n{}", lines[0], lines[1], &lines[2][..5]),
    )
    .unwrap();
    let again = json(&coexistence_args(s(&csv), &[]));
    assert_eq!(
        (again["resumed"].as_u64(), again["computed"].as_u64()),
        (Some(0), Some(6))
    );
    assert_eq!(std::fs::read_to_string(&csv).unwrap(), text);
    let done = json(&coexistence_args(s(&csv), &[]));
    assert_eq!(
        (done["resumed"].as_u64(), done["computed"].as_u64()),
        (Some(6), Some(0))
    );
    assert_eq!(std::fs::read_to_string(&csv).unwrap(), text);

    // A file of another grid, or other starts, is refused naming --out.
    for other in [
        &["--omega-range", "1.40:1.60:3"][..],
        &["--starts", "random:64:1"][..],
    ] {
        let mut a = coexistence_args(s(&csv), &[]);
        a.extend_from_slice(other);
        let o = bistable(&a);
        assert_eq!(o.status.code(), Some(2), "{other:?}: {}", stderr(&o));
        assert!(stderr(&o).contains("--out"), "{other:?}: {}", stderr(&o));
    }
}

#[test]
fn coexistence_stopped_by_ctrl_c_resumes_to_the_same_result() {
    let dir = scratch("coexistence-sigint");
    let (whole, cut) = (dir.join("whole.csv"), dir.join("cut.csv"));
    let args = |csv: &Path| -> Vec<String> {
        [
            "coexistence",
            "--omega-range",
            "1.2:1.8:7",
            "--velocity-range",
            "0.03:0.07:5",
            "--starts",
            "10x10",
            "--max-periods",
            "2000",
            "--threads",
            "1",
            "--out",
            s(csv),
        ]
        .iter()
        .map(|a| a.to_string())
        .collect()
    };
    let o = Command::new(env!("CARGO_BIN_EXE_bistable"))
        .args(args(&whole))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let mut command = Command::new(env!("CARGO_BIN_EXE_bistable"));
    command
        .args(args(&cut))
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null());
    // Ctrl-C in a terminal finds SIGINT at its default action. A background job of a
    // non-interactive shell (as some CI runners start the suite) has it ignored, and a child
    // inherits that, so the child is given the default back.
    // SAFETY: `signal` is async-signal-safe, as `pre_exec` requires.
    unsafe {
        command.pre_exec(|| {
            libc::signal(libc::SIGINT, libc::SIG_DFL);
            Ok(())
        });
    }
    let mut child = command.spawn().unwrap();
    // Interrupt once some points are written.
    let started = std::time::Instant::now();
    while std::fs::read_to_string(&cut).map_or(0, |t| t.lines().count()) < 4 {
        assert!(started.elapsed().as_secs() < 120, "no rows written");
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    let killed = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    let status = child.wait().unwrap();
    assert!(!status.success(), "the run ended before the interrupt");
    let partial = std::fs::read_to_string(&cut).unwrap();
    assert!(partial.lines().count() < std::fs::read_to_string(&whole).unwrap().lines().count());
    let o = Command::new(env!("CARGO_BIN_EXE_bistable"))
        .args(args(&cut))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(
        std::fs::read_to_string(&cut).unwrap(),
        std::fs::read_to_string(&whole).unwrap()
    );
}

#[test]
fn coexistence_refuses_bad_starts_naming_the_option() {
    let cases: &[(&[&str], &str)] = &[
        (&["--box", "0.5:0.5,-0.6:0.6"], "--box"),
        (&["--box", "0:1.2,0.6:-0.6"], "--box"),
        (&["--box", "-0.1:1.2,-0.6:0.6"], "--box"),
        (&["--box", "0:1.2"], "--box"),
        (&["--starts", "0x20"], "--starts"),
        (&["--starts", "random:0"], "--starts"),
        (&["--starts", "2000x2000"], "--starts"),
        (&["--starts", "twenty"], "--starts"),
        (&["--match-distance", "-1"], "--match-distance"),
        (&["--aperiodic-hits", "0"], "--aperiodic-hits"),
    ];
    for (extra, option) in cases {
        let mut a = vec!["coexistence", "--plot", "never.png"];
        a.extend_from_slice(extra);
        let o = bistable(&a);
        assert_eq!(o.status.code(), Some(2), "{extra:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(option), "{extra:?}: {}", stderr(&o));
    }
    assert!(!Path::new("never.png").exists());
}
