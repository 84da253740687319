//! The resumable grid driver of `map` and `basins`: a grid of points `(a, b)` from two `A:B:N`
//! ranges, laid out in an interleaved order that covers the whole grid early; the results
//! already in `--out` (read back, refused when they do not fit) are skipped; the others are
//! computed with a progress bar and appended to `--out` one flushed row each as they complete,
//! while the file's [`OutLock`] keeps a second run out. Each command supplies what is its own:
//! the CSV columns, how a row is read and written, and the computation.

use std::collections::HashMap;
use std::path::Path;

use bistable_analysis::sweep::interleaved;

use crate::error::CliError;
use crate::output::{read_resumable, CsvFile, OutLock};
use crate::progress::Progress;
use crate::ranges::Range;

/// A point by the bits of its coordinates (a resumed row matches to the last bit).
type Key = (u64, u64);

fn key((a, b): (f64, f64)) -> Key {
    (a.to_bits(), b.to_bits())
}

/// The file of a grid command: its CSV columns, what the file is called in errors (`map`
/// file), and the names of the two coordinates in warnings (`Ω`, `V`).
pub(crate) struct GridFile {
    pub columns: &'static [&'static str],
    pub kind: &'static str,
    pub axes: [&'static str; 2],
}

/// One run of a grid command: the grid, the results in hand (read from `--out` or computed),
/// and the lock on `--out` (released when the run is dropped).
pub(crate) struct GridRun<'a, T> {
    file: GridFile,
    out: Option<&'a Path>,
    _lock: Option<OutLock>,
    point: fn(&T) -> (f64, f64),
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
    /// text and its line number; its `Err` is why the file is refused), keyed by `point`, and
    /// lays out the grid of `a × b`.
    pub(crate) fn open(
        file: GridFile,
        out: Option<&'a Path>,
        (a, b): (Range, Range),
        point: fn(&T) -> (f64, f64),
        mut parse: impl FnMut(&str, usize) -> Result<T, String>,
    ) -> Result<Self, CliError> {
        let lock = out.map(OutLock::take).transpose()?;
        let mut done = HashMap::new();
        if let Some(path) = out {
            let mut line = 1;
            read_resumable(path, &file.columns.join(","), file.kind, |text| {
                line += 1;
                let t = parse(text, line)?;
                done.insert(key(point(&t)), t);
                Ok(())
            })?;
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
            point,
            done,
            grid,
            todo,
            resumed,
        })
    }

    /// The result at `p`, if in hand.
    pub(crate) fn get(&self, p: (f64, f64)) -> Option<&T> {
        self.done.get(&key(p))
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
        let (todo, done, point) = (&self.todo, &mut self.done, self.point);
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
