//! The lane width changes nothing but the speed: `map` and `basins` write the same CSV (every
//! column but the wall time) and the same summary with `--lanes 1` (one trajectory at a time,
//! the scalar path), 4 (the default) and 8.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

fn run(args: &[&str]) -> Value {
    let o = Command::new(env!("CARGO_BIN_EXE_bistable"))
        .args(args)
        .output()
        .expect("run bistable");
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_slice(&o.stdout).expect("JSON summary")
}

fn scratch(name: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("bistable-cli-lanes-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The CSV's rows keyed by their first two columns (the grid point), without the columns whose
/// name contains `wall`; the rows come in completion order, which depends on the width.
fn rows(path: &Path) -> BTreeMap<(String, String), Vec<(String, String)>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let rows: BTreeMap<_, _> = lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            assert_eq!(f.len(), header.len(), "{l}");
            let kept = header
                .iter()
                .zip(&f)
                .filter(|(h, _)| !h.contains("wall"))
                .map(|(h, v)| (h.to_string(), v.to_string()))
                .collect();
            ((f[0].to_string(), f[1].to_string()), kept)
        })
        .collect();
    assert_eq!(rows.len(), text.lines().count() - 1, "a point twice");
    rows
}

/// Runs `args` with each width writing to its own CSV; asserts equal rows and equal summaries
/// (but for the timings and the width); returns the number of rows.
fn same_for_every_width(name: &str, args: &[&str]) -> usize {
    let dir = scratch(name);
    let mut first: Option<(BTreeMap<_, _>, Value)> = None;
    for lanes in ["1", "4", "8"] {
        let csv = dir.join(format!("lanes{lanes}.csv"));
        let mut a = args.to_vec();
        a.extend(["--lanes", lanes, "--out", csv.to_str().unwrap(), "--json"]);
        let mut summary = run(&a);
        assert_eq!(summary["lanes"], lanes.parse::<u64>().unwrap());
        let obj = summary.as_object_mut().unwrap();
        obj.retain(|k, _| {
            !k.contains("time") && !k.contains("per_second") && k != "lanes" && k != "out"
        });
        let got = rows(&csv);
        match &first {
            None => first = Some((got, summary)),
            Some((rows1, summary1)) => {
                let differ: Vec<_> = rows1
                    .iter()
                    .filter(|(k, v)| got.get(*k) != Some(v))
                    .map(|(k, _)| k.clone())
                    .take(5)
                    .collect();
                assert!(
                    differ.is_empty(),
                    "--lanes {lanes}: rows differ at {differ:?}"
                );
                assert_eq!(got.len(), rows1.len());
                assert_eq!(&summary, summary1, "--lanes {lanes}: summary differs");
            }
        }
    }
    first.unwrap().0.len()
}

#[test]
fn map_is_the_same_for_every_lane_width() {
    // A 30 × 20 grid over the paper's map, sensitivity test on (its repeats at other
    // tolerances run in their own batches).
    let n = same_for_every_width(
        "map",
        &[
            "map",
            "--omega-range",
            "0.2:3.5:30",
            "--velocity-range",
            "0.005:0.2:20",
            "--threads",
            "2",
        ],
    );
    assert_eq!(n, 600);
}

#[test]
fn basins_are_the_same_for_every_lane_width() {
    // 100 × 100 starts at (1.45, 0.05), with the uncertainty exponent's displaced starts.
    let n = same_for_every_width(
        "basins",
        &[
            "basins",
            "--omega",
            "1.45",
            "--velocity",
            "0.05",
            "--x-range",
            "0:1.2:100",
            "--v-range",
            "-0.6:0.6:100",
            "--uncertainty-samples",
            "200",
        ],
    );
    assert_eq!(n, 10_000);
}
