//! The lane width changes nothing but the speed: `map` and `basins` write the same CSV (every
//! column but the wall time), `bifurcation` and `orbit --continue-omega` the same files byte for
//! byte, and each the same summary with `--lanes 1` (one trajectory at a time, the scalar path),
//! 4 (the default) and 8.

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

/// Runs `args` with each width, writing its files (`--out`, and the orbit CSV beside it) to its
/// own directory; asserts the same bytes in every file and equal summaries (but for the
/// timings, the width and the file names); returns the size of the first `--out` file.
fn same_files_for_every_width(name: &str, args: &[&str], files: &[&str]) -> usize {
    let dir = scratch(name);
    let mut first: Option<(Vec<Vec<u8>>, Value)> = None;
    for lanes in ["1", "4", "8"] {
        let sub = dir.join(format!("lanes{lanes}"));
        std::fs::create_dir_all(&sub).unwrap();
        let out = sub.join(files[0]);
        let mut a = args.to_vec();
        a.extend(["--lanes", lanes, "--out", out.to_str().unwrap(), "--json"]);
        let mut summary = run(&a);
        summary
            .as_object_mut()
            .unwrap()
            .retain(|k, _| !k.contains("time") && k != "lanes" && k != "files");
        let bytes: Vec<Vec<u8>> = files
            .iter()
            .map(|f| std::fs::read(sub.join(f)).unwrap_or_else(|e| panic!("{f}: {e}")))
            .collect();
        match &first {
            None => first = Some((bytes, summary)),
            Some((bytes1, summary1)) => {
                for ((f, b), b1) in files.iter().zip(&bytes).zip(bytes1) {
                    assert!(b == b1, "--lanes {lanes}: {f} differs");
                }
                assert_eq!(&summary, summary1, "--lanes {lanes}: summary differs");
            }
        }
    }
    first.unwrap().0[0].len()
}

#[test]
fn bifurcation_is_the_same_for_every_lane_width() {
    // 61 points across the period-doubling cascade of the demo's diagram, with the branches
    // seeded from the recorded attractors.
    let n = same_files_for_every_width(
        "bifurcation",
        &[
            "bifurcation",
            "--param",
            "omega",
            "--range",
            "2.0:2.7:61",
            "--velocity",
            "0.07",
            "--transient",
            "300",
            "--record",
            "40",
            "--threads",
            "2",
        ],
        &["bif.csv", "bif_orbits.csv"],
    );
    assert!(n > 61 * 40 * 20, "{n} bytes");
}

#[test]
fn orbit_continuation_is_the_same_for_every_lane_width() {
    let n = same_files_for_every_width(
        "orbits",
        &[
            "orbit",
            "--continue-omega",
            "1.2:2.4:25",
            "--velocity",
            "0.05",
            "--settle",
            "300",
            "--threads",
            "2",
        ],
        &["orbits.csv"],
    );
    assert!(n > 100, "{n} bytes");
}
