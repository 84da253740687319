//! The resumable grid driver of `map` and `basins`: a grid of points `(a, b)` from two `A:B:N`
//! ranges, laid out in an interleaved order that covers the whole grid early; the results
//! already in `--out` (read back, refused when they do not fit) are skipped; the others are
//! computed with a progress bar and appended to `--out` one flushed row each as they complete,
//! while the file's [`OutLock`] keeps a second run out. Each command supplies what is its own:
//! the CSV columns, how a row is read and written, and the computation.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use clap::{Arg, Args};
use serde::Serialize;

use bistable_analysis::sweep::interleaved;
use bistable_analysis::Threads;
use bistable_core::Width;

use crate::common::{lanes, threads};
use crate::error::CliError;
use crate::output::{read_resumable, CsvFile, OutLock};
use crate::progress::Progress;
use crate::ranges::{Range, MAX_POINTS};

/// The output and worker options of a command over a grid of points (`map`, `basins`,
/// `bifurcation`), flattened into its options; each command words the help of `--out` and
/// `--plot` for its own points with [`grid_help`].
#[derive(Debug, Clone, Args)]
pub struct GridArgs {
    /// Append one row per point to FILE.csv, skipping points already in it.
    #[arg(long, value_name = "FILE.csv", help_heading = "Output")]
    pub out: Option<PathBuf>,

    /// Draw the grid to FILE.png.
    #[arg(long, value_name = "FILE.png", help_heading = "Output")]
    pub plot: Option<PathBuf>,

    /// Worker threads [default: all cores].
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,

    /// Trajectories each thread advances together in SIMD lanes: 1 (one at a time), 4 (AVX2)
    /// or 8 (AVX-512) [default: 4]. The results are the same for every width.
    #[arg(long, value_name = "N")]
    pub lanes: Option<usize>,
}

/// For `#[command(mut_args(grid_help(out, plot)))]`: the help of `--out` and `--plot` (changed
/// in place, so that the options keep their order in `--help`).
pub(crate) fn grid_help(out: &'static str, plot: &'static str) -> impl FnMut(Arg) -> Arg {
    move |a| match a.get_id().as_str() {
        "out" => a.help(out),
        "plot" => a.help(plot),
        _ => a,
    }
}

impl GridArgs {
    /// The checked `--threads` and `--lanes`.
    pub(crate) fn parallel(&self) -> Result<(Threads, Width), CliError> {
        Ok((
            threads(self.threads, "--threads")?,
            lanes(self.lanes, "--lanes")?,
        ))
    }
}

/// The counts of a grid run, in the command's JSON summary (flattened into it).
#[derive(Debug, Serialize)]
pub(crate) struct GridSummary {
    pub points: usize,
    pub computed: usize,
    pub resumed: usize,
    pub failed: usize,
    pub threads: usize,
    /// Trajectories per thread in SIMD lanes.
    pub lanes: usize,
    pub wall_time_s: f64,
}

impl GridSummary {
    /// `N points, N computed, N resumed, N failed` with the command's word for its points and
    /// for the resumed ones.
    pub(crate) fn counts(&self, points: &str, resumed: &str) -> String {
        format!(
            "{} {points}, {} computed, {} {resumed}, {} failed",
            self.points, self.computed, self.resumed, self.failed
        )
    }
}

/// Refuses a grid of `a × b` with more than [`MAX_POINTS`] points (naming `option`, `a`'s).
pub(crate) fn check_size(a: Range, b: Range, option: &str) -> Result<(), CliError> {
    if a.n.saturating_mul(b.n) > MAX_POINTS {
        return Err(CliError::invalid_text(
            option,
            a,
            format!("the grid has more than {MAX_POINTS} points"),
        ));
    }
    Ok(())
}

/// A point by the bits of its coordinates (a resumed row matches to the last bit).
type Key = (u64, u64);

fn key((a, b): (f64, f64)) -> Key {
    (a.to_bits(), b.to_bits())
}

/// The file of a grid command whose results are `T`: its CSV columns, what the file is called
/// in errors (`map` file), the names of the two coordinates in warnings (`Ω`, `V`), the point
/// of a result, and how many rows a point has.
pub(crate) struct GridFile<T> {
    pub columns: &'static [&'static str],
    pub kind: &'static str,
    pub axes: [&'static str; 2],
    pub point: fn(&T) -> (f64, f64),
    pub rows: Rows<T>,
}

/// How a point's result is written.
pub(crate) enum Rows<T> {
    /// One row (a later row of the same point replaces an earlier one).
    One,
    /// Several rows, each read as a `T` and merged into the point's result with `merge`; a
    /// point counts as done when `complete` says so (an interrupted run may have written only
    /// some of its rows: the point is computed again and its rows appended).
    Group {
        merge: fn(&mut T, T),
        complete: fn(&T) -> bool,
    },
}

/// One run of a grid command: the grid, the results in hand (read from `--out` or computed),
/// and the lock on `--out` (released when the run is dropped).
pub(crate) struct GridRun<'a, T> {
    file: &'a GridFile<T>,
    out: Option<&'a Path>,
    _lock: Option<OutLock>,
    done: HashMap<Key, T>,
    /// The grid's points, `(a.value(k % a.n), b.value(k / a.n))` in interleaved order of `k`.
    pub grid: Vec<(f64, f64)>,
    /// The points not yet in hand, in the order of `grid`.
    pub todo: Vec<(f64, f64)>,
    /// The points of the grid found in `--out`.
    pub resumed: usize,
}

/// What [`GridRun::compute`] did.
pub(crate) struct Computed {
    /// Points computed (and written).
    pub computed: usize,
    /// Points that failed (each reported on stderr).
    pub failed: Vec<(f64, f64)>,
}

impl<'a, T> GridRun<'a, T> {
    /// Takes the lock on `out`, reads the results already in it with `parse` (given a row's
    /// text and its row number; its `Err` is why the file is refused), and lays out the grid of
    /// `a × b`.
    pub(crate) fn open(
        file: &'a GridFile<T>,
        out: Option<&'a Path>,
        (a, b): (Range, Range),
        mut parse: impl FnMut(&str, usize) -> Result<T, String>,
    ) -> Result<Self, CliError> {
        let lock = out.map(OutLock::take).transpose()?;
        let mut done = HashMap::new();
        if let Some(path) = out {
            let mut line = 1;
            read_resumable(path, &file.columns.join(","), file.kind, |text| {
                line += 1;
                let t = parse(text, line)?;
                let k = key((file.point)(&t));
                match (&file.rows, done.get_mut(&k)) {
                    (Rows::Group { merge, .. }, Some(had)) => merge(had, t),
                    _ => {
                        done.insert(k, t);
                    }
                }
                Ok(())
            })?;
            if let Rows::Group { complete, .. } = file.rows {
                done.retain(|_, t| complete(t));
            }
        }
        let grid: Vec<(f64, f64)> = interleaved(a.n * b.n)
            .map(|k| (a.value(k % a.n), b.value(k / a.n)))
            .collect();
        let resumed = grid.iter().filter(|&&p| done.contains_key(&key(p))).count();
        let todo = grid
            .iter()
            .copied()
            .filter(|&p| !done.contains_key(&key(p)))
            .collect();
        Ok(Self {
            file,
            out,
            _lock: lock,
            done,
            grid,
            todo,
            resumed,
        })
    }

    /// The summary counts after `c`, on `threads` of `width` lanes, in `wall` seconds.
    pub(crate) fn summary(
        &self,
        c: &Computed,
        (threads, width): (Threads, Width),
        wall: f64,
    ) -> GridSummary {
        GridSummary {
            points: self.grid.len(),
            computed: c.computed,
            resumed: self.resumed,
            failed: c.failed.len(),
            threads: threads.get(),
            lanes: width.lanes(),
            wall_time_s: wall,
        }
    }

    /// `Ok` unless some of `c`'s points failed; then the error that counts them (`points`: the
    /// command's word for them).
    pub(crate) fn check(&self, c: &Computed, points: &str) -> Result<(), CliError> {
        if c.failed.is_empty() {
            return Ok(());
        }
        Err(CliError::Failed(format!(
            "{} of {} {points} failed (listed above); the others are saved",
            c.failed.len(),
            self.todo.len()
        )))
    }

    /// The result at `p`, if in hand.
    pub(crate) fn get(&self, p: (f64, f64)) -> Option<&T> {
        self.done.get(&key(p))
    }

    /// Writes `--out` anew with `write` (the header first), through a temporary file renamed
    /// over it, so that an interruption leaves the old file whole.
    pub(crate) fn rewrite(
        &self,
        write: impl FnOnce(&mut CsvFile) -> Result<(), CliError>,
    ) -> Result<(), CliError> {
        let Some(path) = self.out else {
            return Ok(());
        };
        let mut name = path.file_name().unwrap_or_default().to_os_string();
        name.push(".tmp");
        let tmp = path.with_file_name(name);
        let mut csv = CsvFile::create(&tmp, &self.file.columns.join(","))?;
        write(&mut csv)?;
        csv.finish()?;
        std::fs::rename(&tmp, path).map_err(|e| CliError::io("cannot replace", path, e))
    }

    /// Computes the points of `todo` with a progress bar labelled `message`: `run` is given
    /// them and a sink for each result as it completes (by its index in `todo`); each result
    /// is written to `--out` with `write` (flushed at once) and kept. Failures are reported on
    /// stderr and returned.
    pub(crate) fn compute(
        &mut self,
        message: String,
        write: impl Fn(&mut CsvFile, &T) -> Result<(), CliError>,
        run: impl FnOnce(
            &[(f64, f64)],
            &mut dyn FnMut(usize, Result<T, CliError>) -> Result<(), CliError>,
        ) -> Result<(), CliError>,
    ) -> Result<Computed, CliError> {
        let mut csv = match self.out {
            Some(p) if p.exists() => Some(CsvFile::append(p)?),
            Some(p) => Some(CsvFile::create(p, &self.file.columns.join(","))?),
            None => None,
        };
        if let Some(c) = csv.as_mut() {
            c.flush()?;
        }
        let (todo, done, point) = (&self.todo, &mut self.done, self.file.point);
        let mut failed = Vec::new();
        let mut computed = 0usize;
        let mut progress = Progress::new(todo.len() as f64, message);
        run(todo, &mut |i, r| {
            match r {
                Ok(t) => {
                    if let Some(c) = csv.as_mut() {
                        write(c, &t)?;
                        c.flush()?;
                    }
                    done.insert(key(point(&t)), t);
                    computed += 1;
                }
                Err(e) => failed.push((todo[i], e)),
            }
            progress.set((computed + failed.len()) as f64);
            Ok(())
        })?;
        progress.finish();
        if let Some(c) = csv {
            c.finish()?;
        }
        let [a, b] = self.file.axes;
        for ((x, y), e) in &failed {
            eprintln!("warning: {a} = {x}, {b} = {y}: {e}");
        }
        Ok(Computed {
            computed,
            failed: failed.into_iter().map(|f| f.0).collect(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::Field;

    /// A result: the point and a value.
    type Item = (f64, f64, f64);

    const FILE: GridFile<Item> = GridFile {
        columns: &["a", "b", "value"],
        kind: "test",
        axes: ["a", "b"],
        point: |t| (t.0, t.1),
        rows: Rows::One,
    };

    fn parse(text: &str, row: usize) -> Result<Item, String> {
        let f: Vec<f64> = text.split(',').map(|c| c.parse().unwrap()).collect();
        match f[..] {
            [a, b, v] => Ok((a, b, v)),
            _ => Err(format!("has a bad row {row}")),
        }
    }

    /// Computes every point of `todo` as `a + 10 b` but fails the first `fail` of them.
    fn compute(run: &mut GridRun<'_, Item>, fail: usize) -> Computed {
        run.compute(
            "test".to_string(),
            |c, t| c.row(&[Field::F(t.0), Field::F(t.1), Field::F(t.2)]),
            |todo, done| {
                for (i, &(a, b)) in todo.iter().enumerate() {
                    let r = if i < fail {
                        Err(CliError::Failed("no".into()))
                    } else {
                        Ok((a, b, a + 10.0 * b))
                    };
                    done(i, r)?;
                }
                Ok(())
            },
        )
        .unwrap()
    }

    #[test]
    fn resumes_from_the_rows_in_the_file() {
        let dir = std::env::temp_dir().join(format!("bistable-grid-{}", std::process::id()));
        let out = dir.join("g.csv");
        let _ = std::fs::remove_dir_all(&dir);
        let ranges = ("1:3:3".parse().unwrap(), "0:1:2".parse().unwrap());
        let mut run = GridRun::open(&FILE, Some(&out), ranges, parse).unwrap();
        assert_eq!((run.grid.len(), run.todo.len(), run.resumed), (6, 6, 0));
        let c = compute(&mut run, 2);
        assert_eq!((c.computed, c.failed.len()), (4, 2));
        assert_eq!(
            run.summary(&c, (Threads::all(), Width::from_lanes(1).unwrap()), 0.0)
                .failed,
            2
        );
        assert!(run.check(&c, "points").is_err());
        drop(run);
        assert!(!dir.join("g.csv.lock").exists());
        // An interrupted write leaves half a row: it is dropped, the failed points are redone.
        let mut text = std::fs::read_to_string(&out).unwrap();
        assert_eq!(text.lines().count(), 5);
        text.push_str("9,9");
        std::fs::write(&out, text).unwrap();
        let mut run = GridRun::open(&FILE, Some(&out), ranges, parse).unwrap();
        assert_eq!((run.todo.len(), run.resumed), (2, 4));
        let c = compute(&mut run, 0);
        assert_eq!((c.computed, c.failed.len()), (2, 0));
        for &p in &run.grid {
            assert_eq!(run.get(p).map(|t| t.2), Some(p.0 + 10.0 * p.1));
        }
        drop(run);
        let text = std::fs::read_to_string(&out).unwrap();
        assert_eq!(text.lines().count(), 7);
        assert!(text.starts_with("a,b,value\n") && text.ends_with('\n'));
        let run = GridRun::open(&FILE, Some(&out), ranges, parse).unwrap();
        assert_eq!((run.todo.len(), run.resumed), (0, 6));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
