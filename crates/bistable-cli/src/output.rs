//! Output helpers: full-precision numbers, CSV files, JSON on stdout.

use std::fmt::Write as _;
use std::fs::File;
use std::io::{BufRead, BufReader, BufWriter, Write};
use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::error::CliError;

/// Shortest decimal text that parses back to exactly `x` (Rust's round-trip formatting):
/// positional for `1e-5 ≤ |x| < 1e16` and zero, scientific (`1.5e-7`) otherwise. Non-finite
/// values print as `NaN`, `inf`, `-inf`.
pub fn num(x: f64) -> String {
    let mut s = String::new();
    push_num(&mut s, x);
    s
}

/// Appends [`num`]`(x)` to `s`.
pub fn push_num(s: &mut String, x: f64) {
    let a = x.abs();
    // Writing to a String cannot fail.
    let _ = if x == 0.0 || !x.is_finite() || (1e-5..1e16).contains(&a) {
        write!(s, "{x}")
    } else {
        write!(s, "{x:e}")
    };
}

/// A CSV field: a number, an integer, a text, or empty.
#[derive(Debug, Clone, Copy)]
pub enum Field<'a> {
    /// Written with [`num`].
    F(f64),
    /// An integer.
    I(u64),
    /// Written as is (must not contain commas or quotes).
    S(&'a str),
    /// Nothing between the commas.
    Empty,
}

impl<'a> From<bistable_analysis::record::Value<'a>> for Field<'a> {
    /// A record's value as a CSV field (a list of outcomes as its text).
    fn from(v: bistable_analysis::record::Value<'a>) -> Self {
        use bistable_analysis::record::Value;
        match v {
            Value::F(x) => Field::F(x),
            Value::I(n) => Field::I(n),
            Value::Bool(b) => Field::flag(b),
            Value::S(t) => Field::S(t),
            Value::Null => Field::Empty,
            Value::Outcomes(_, text) => Field::S(text),
        }
    }
}

impl Field<'_> {
    /// `true` or `false`.
    pub fn flag(v: bool) -> Field<'static> {
        Field::S(if v { "true" } else { "false" })
    }
}

/// Appends `fields` to `line`, comma separated.
pub fn push_fields(line: &mut String, fields: &[Field<'_>]) {
    for (i, f) in fields.iter().enumerate() {
        if i > 0 {
            line.push(',');
        }
        match *f {
            Field::F(x) => push_num(line, x),
            Field::I(n) => {
                let _ = write!(line, "{n}");
            }
            Field::S(s) => line.push_str(s),
            Field::Empty => {}
        }
    }
}

/// A CSV file being written; errors name the file.
pub struct CsvFile {
    path: PathBuf,
    out: BufWriter<File>,
    line: String,
}

impl CsvFile {
    /// Creates `path` (and missing parent directories) and writes the header line.
    pub fn create(path: &Path, header: &str) -> Result<Self, CliError> {
        create_parent(path)?;
        let file = File::create(path).map_err(|e| CliError::io("cannot create", path, e))?;
        let mut csv = Self {
            path: path.to_path_buf(),
            out: BufWriter::new(file),
            line: String::with_capacity(256),
        };
        csv.write_line(header)?;
        Ok(csv)
    }

    /// Opens an existing CSV file for appending rows (its header is not checked here).
    pub fn append(path: &Path) -> Result<Self, CliError> {
        let file = std::fs::OpenOptions::new()
            .append(true)
            .open(path)
            .map_err(|e| CliError::io("cannot open", path, e))?;
        Ok(Self {
            path: path.to_path_buf(),
            out: BufWriter::new(file),
            line: String::with_capacity(256),
        })
    }

    /// Writes one row.
    pub fn row(&mut self, fields: &[Field<'_>]) -> Result<(), CliError> {
        let mut line = std::mem::take(&mut self.line);
        line.clear();
        push_fields(&mut line, fields);
        let r = self.write_line(&line);
        self.line = line;
        r
    }

    /// Pushes the rows written so far to the operating system (so that they survive if the
    /// process is killed).
    pub fn flush(&mut self) -> Result<(), CliError> {
        self.out
            .flush()
            .map_err(|e| CliError::io("cannot write", &self.path, e))
    }

    fn write_line(&mut self, line: &str) -> Result<(), CliError> {
        self.out
            .write_all(line.as_bytes())
            .and_then(|()| self.out.write_all(b"\n"))
            .map_err(|e| CliError::io("cannot write", &self.path, e))
    }

    /// Flushes the file to disk.
    pub fn finish(mut self) -> Result<PathBuf, CliError> {
        self.flush()?;
        Ok(self.path)
    }
}

/// Reads a resumable CSV this program writes row by row (`--out` of `map` and `basins`): nothing
/// if `path` does not exist; a file whose first line is not `header` is refused as not a `kind`
/// file; each complete non-empty row after it goes to `row`, whose `Err` is the reason the file
/// is refused (reported as `--out`'s); an incomplete last line (an interrupted write) is cut
/// from the file, and a file without a complete header is started afresh with `header`.
pub fn read_resumable(
    path: &Path,
    header: &str,
    kind: &str,
    mut row: impl FnMut(&str) -> Result<(), String>,
) -> Result<(), CliError> {
    let file = match File::open(path) {
        Ok(f) => f,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(CliError::io("cannot read", path, e)),
    };
    let bad = |rule: String| CliError::invalid_text("--out", path.display(), rule);
    let mut reader = BufReader::new(file);
    let (mut line, mut first, mut complete) = (String::new(), true, 0u64);
    loop {
        line.clear();
        let n = reader
            .read_line(&mut line)
            .map_err(|e| CliError::io("cannot read", path, e))?;
        if n == 0 || !line.ends_with('\n') {
            break;
        }
        let text = line.trim_end();
        if first {
            first = false;
            if text != header {
                return Err(bad(format!(
                    "is not a {kind} file (its header is not {header})"
                )));
            }
        } else if !text.is_empty() {
            row(text).map_err(bad)?;
        }
        complete += n as u64;
    }
    if first && complete == 0 {
        // Empty (or only a partial header): start afresh.
        CsvFile::create(path, header)?.finish()?;
        return Ok(());
    }
    let actual = std::fs::metadata(path)
        .map_err(|e| CliError::io("cannot read", path, e))?
        .len();
    if actual > complete {
        let f = std::fs::OpenOptions::new()
            .write(true)
            .open(path)
            .map_err(|e| CliError::io("cannot open", path, e))?;
        f.set_len(complete)
            .map_err(|e| CliError::io("cannot truncate", path, e))?;
    }
    Ok(())
}

/// `FILE.csv.lock` holding this process's id while it appends to `FILE.csv`, so that two runs
/// cannot interleave their rows. A lock left by a process that no longer runs (killed) is
/// taken over.
pub(crate) struct OutLock(PathBuf);

impl OutLock {
    pub(crate) fn take(out: &Path) -> Result<Self, CliError> {
        let path = PathBuf::from(format!("{}.lock", out.display()));
        if let Ok(text) = std::fs::read_to_string(&path) {
            let pid = text.trim();
            let alive = !pid.is_empty()
                && pid != std::process::id().to_string()
                && Path::new("/proc").join(pid).exists();
            if alive {
                return Err(CliError::invalid_text(
                    "--out",
                    out.display(),
                    format!(
                        "is being written by another run (process {pid}, see {}); wait for it or stop it",
                        path.display()
                    ),
                ));
            }
        }
        create_parent(&path)?;
        std::fs::write(&path, std::process::id().to_string())
            .map_err(|e| CliError::io("cannot write", &path, e))?;
        Ok(Self(path))
    }
}

impl Drop for OutLock {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

/// Creates the parent directory of `path` if it is missing.
pub fn create_parent(path: &Path) -> Result<(), CliError> {
    match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() && !dir.exists() => create_dir(dir),
        _ => Ok(()),
    }
}

/// Creates `dir` and its parents.
pub fn create_dir(dir: &Path) -> Result<(), CliError> {
    std::fs::create_dir_all(dir).map_err(|e| CliError::io("cannot create directory", dir, e))
}

/// `<dir>/<stem><suffix>` for the file `path`, e.g. `out/impacts.csv` → `out/impacts_sticking.csv`.
pub fn sibling(path: &Path, suffix: &str) -> PathBuf {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!("{stem}{suffix}"))
}

/// Prints `value` as pretty JSON on stdout.
pub fn print_json(value: &impl Serialize) -> Result<(), CliError> {
    let mut text = serde_json::to_string_pretty(value).map_err(|e| {
        CliError::io(
            "cannot serialise the result for",
            Path::new("<stdout>"),
            e.into(),
        )
    })?;
    text.push('\n');
    print_text(&text)
}

/// Writes `text` to stdout. A closed pipe (`bistable … | head`) is not an error.
pub fn print_text(text: &str) -> Result<(), CliError> {
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
            Err(CliError::io("cannot write", Path::new("<stdout>"), e))
        }
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_round_trip() {
        for x in [
            0.0,
            -0.0,
            1.0,
            0.07,
            1.0 / 3.0,
            std::f64::consts::TAU,
            1e-7,
            -2.5e-300,
            1.2345678901234567e20,
            f64::MIN_POSITIVE,
            f64::MAX,
        ] {
            let s = num(x);
            assert_eq!(s.parse::<f64>().unwrap().to_bits(), x.to_bits(), "{s}");
        }
        assert_eq!(num(0.5), "0.5");
        assert_eq!(num(1e-7), "1e-7");
    }

    #[test]
    fn sibling_names() {
        assert_eq!(
            sibling(Path::new("out/imp.csv"), "_sticking.csv"),
            PathBuf::from("out/imp_sticking.csv")
        );
        assert_eq!(
            sibling(Path::new("imp"), "_snaps.csv"),
            PathBuf::from("imp_snaps.csv")
        );
    }
}
