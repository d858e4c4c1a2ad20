//! Report output: atomic files and directories, CSV tables through polars, the run manifest.
//!
//! A run writes into a hidden sibling directory `reports/.<name>.tmp-<pid>` and renames it to
//! `reports/<name>` only when every table, figure and the manifest are written
//! ([`ReportDir::commit`]). A failed or killed run therefore never leaves a half-written report,
//! and an earlier complete report stays in place until the new one replaces it. Single files
//! (datasets, redrawn figures) go through [`write_atomic`]: temp file + rename.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use polars::prelude::*;
use serde::Serialize;
use sha2::{Digest, Sha256};

use crate::error::{Error, Result};

/// Writes a file atomically: a temporary sibling, then rename. The temporary name is unique per
/// process, call and random draw, so threads — or processes on other machines sharing the
/// directory, which may have the same process id — writing the same file concurrently do not
/// share it (the last rename wins, each reader sees a whole file).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    static SERIAL: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir).map_err(|e| Error::write(dir, e))?;
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let serial = SERIAL.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let tmp = dir.join(format!(".{name}.tmp-{}-{serial}-{:016x}", std::process::id(), rand::random::<u64>()));
    std::fs::write(&tmp, bytes).map_err(|e| Error::write(&tmp, e))?;
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        Error::write(path, e)
    })
}

/// A scratch directory under the system's temporary directory, removed with everything in it
/// when dropped (benchmarks, tests). partlife keeps it in-house rather than depend on a crate:
/// the test build must resolve exactly the release build's dependency features.
#[derive(Debug)]
pub struct TempDir {
    path: PathBuf,
}

impl TempDir {
    /// A new, empty directory `partlife-<label>-<pid>-<serial>`; never an existing one.
    pub fn new(label: &str) -> Result<TempDir> {
        static SERIAL: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
        let base = std::env::temp_dir();
        loop {
            let serial = SERIAL.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            let path = base.join(format!("partlife-{label}-{}-{serial}", std::process::id()));
            match std::fs::create_dir(&path) {
                Ok(()) => return Ok(TempDir { path }),
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
                Err(e) => return Err(Error::write(&path, e)),
            }
        }
    }

    /// Its path.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.path);
    }
}

/// Appends one ASCII VTK XML `<DataArray>` to `s`: the crate's one VTK array writer, used by
/// the FE's `.vtu` and the DEM's `.vtp`. `comps` values per tuple (NumberOfComponents when > 1),
/// one tuple per line; `integer` writes the values as integers (ids, connectivity, offsets,
/// cell types), otherwise in `{:e}` notation (round-trips every f64).
pub fn vtk_data_array(s: &mut String, ty: &str, name: &str, comps: usize, values: impl Iterator<Item = f64>, integer: bool) {
    use std::fmt::Write as _;
    let _ = write!(s, "<DataArray type=\"{ty}\" Name=\"{name}\"");
    if comps > 1 {
        let _ = write!(s, " NumberOfComponents=\"{comps}\"");
    }
    s.push_str(" format=\"ascii\">\n");
    for (k, v) in values.enumerate() {
        if integer {
            let _ = write!(s, "{}", v as i64);
        } else {
            let _ = write!(s, "{v:e}");
        }
        s.push(if (k + 1) % comps.max(1) == 0 { '\n' } else { ' ' });
    }
    s.push_str("</DataArray>\n");
}

/// SHA-256 of bytes, hex.
pub fn sha256_hex(bytes: &[u8]) -> String {
    let digest = Sha256::digest(bytes);
    digest.iter().map(|b| format!("{b:02x}")).collect()
}

/// A report directory under construction.
#[derive(Debug)]
pub struct ReportDir {
    final_path: PathBuf,
    tmp_path: PathBuf,
    files: Vec<String>,
    committed: bool,
    documents: bool,
    /// Whether dropping it uncommitted removes the directory (false for a [`ReportDir::branch`]).
    owner: bool,
}

impl ReportDir {
    /// Starts `root/<name>` in a temporary sibling directory.
    pub fn create(root: &Path, name: &str) -> Result<Self> {
        std::fs::create_dir_all(root).map_err(|e| Error::write(root, e))?;
        let tmp_path = root.join(format!(".{name}.tmp-{}", std::process::id()));
        if tmp_path.exists() {
            std::fs::remove_dir_all(&tmp_path).map_err(|e| Error::write(&tmp_path, e))?;
        }
        std::fs::create_dir(&tmp_path).map_err(|e| Error::write(&tmp_path, e))?;
        Ok(ReportDir { final_path: root.join(name), tmp_path, files: Vec::new(), committed: false, documents: true, owner: true })
    }

    /// Whether the commit writes `report.pdf` and `report.html` (`crate::runkit`); on by default.
    pub fn documents(&self) -> bool {
        self.documents
    }

    /// Turns the documents on or off (`partlife run --no-document`).
    pub fn set_documents(&mut self, on: bool) {
        self.documents = on;
    }

    /// Where files are written until commit.
    pub fn path(&self) -> &Path {
        &self.tmp_path
    }

    /// The directory the report will have after commit.
    pub fn final_path(&self) -> &Path {
        &self.final_path
    }

    /// Files written so far (relative names, in order).
    pub fn files(&self) -> &[String] {
        &self.files
    }

    /// Writes raw bytes to `name`.
    pub fn write_bytes(&mut self, name: &str, bytes: &[u8]) -> Result<()> {
        let p = self.tmp_path.join(name);
        std::fs::write(&p, bytes).map_err(|e| Error::write(&p, e))?;
        self.files.push(name.to_string());
        Ok(())
    }

    /// Writes a table as CSV (`name` without extension).
    pub fn write_table(&mut self, name: &str, df: &mut DataFrame) -> Result<()> {
        let bytes = table_to_csv(df)?;
        self.write_bytes(&format!("{name}.csv"), &bytes)
    }

    /// A writer into the same temporary directory with a list of files of its own, for tables
    /// written in parallel: [`ReportDir::adopt`] appends its files, so the report lists them in
    /// the order the caller adopts the branches whatever order they were written in. A branch
    /// never removes the directory.
    pub fn branch(&self) -> ReportDir {
        ReportDir { final_path: self.final_path.clone(), tmp_path: self.tmp_path.clone(), files: Vec::new(), committed: false, documents: self.documents, owner: false }
    }

    /// Appends the files a [`ReportDir::branch`] wrote.
    pub fn adopt(&mut self, mut branch: ReportDir) {
        self.files.append(&mut branch.files);
    }

    /// Records files written by someone else into the directory (figures).
    pub fn record(&mut self, names: impl IntoIterator<Item = String>) {
        self.files.extend(names);
    }

    /// Renames the temporary directory into place, replacing an earlier report.
    pub fn commit(mut self) -> Result<PathBuf> {
        debug_assert!(self.owner, "a branch is adopted, not committed");
        let old = self.final_path.with_file_name(format!(
            ".{}.old-{}",
            self.final_path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default(),
            std::process::id()
        ));
        let had_old = self.final_path.exists();
        if had_old {
            std::fs::rename(&self.final_path, &old).map_err(|e| Error::write(&self.final_path, e))?;
        }
        if let Err(e) = std::fs::rename(&self.tmp_path, &self.final_path) {
            if had_old {
                let _ = std::fs::rename(&old, &self.final_path);
            }
            return Err(Error::write(&self.final_path, e));
        }
        if had_old {
            let _ = std::fs::remove_dir_all(&old);
        }
        self.committed = true;
        Ok(self.final_path.clone())
    }
}

impl Drop for ReportDir {
    fn drop(&mut self) {
        if self.owner && !self.committed {
            let _ = std::fs::remove_dir_all(&self.tmp_path);
        }
    }
}

/// Formats a table as CSV bytes.
pub fn table_to_csv(df: &mut DataFrame) -> Result<Vec<u8>> {
    let mut buf = Vec::new();
    CsvWriter::new(&mut buf)
        .finish(df)
        .map_err(|e| Error::numerical("formatting a CSV table", e.to_string()))?;
    Ok(buf)
}

/// Builds a table from named columns.
pub fn table(columns: Vec<Column>) -> Result<DataFrame> {
    DataFrame::new_infer_height(columns).map_err(|e| Error::numerical("building a table", e.to_string()))
}

/// A float column.
pub fn fcol(name: &str, values: Vec<f64>) -> Column {
    Column::new(name.into(), values)
}

/// A count column.
pub fn ucol(name: &str, values: Vec<u64>) -> Column {
    Column::new(name.into(), values)
}

/// A text column.
pub fn scol(name: &str, values: Vec<String>) -> Column {
    Column::new(name.into(), values)
}

/// Reads a report table (types inferred from the whole file).
pub fn read_table(path: &Path) -> Result<DataFrame> {
    read_csv(path, None)
}

/// Reads a CSV input file once: its text ([`read_input_text`]), its shape
/// ([`check_csv_shape`]), then the table parsed by polars from that text, with types inferred
/// from the first `infer` rows (`Some(0)`: every column as text; `None`: the whole file).
pub fn read_csv(path: &Path, infer: Option<usize>) -> Result<DataFrame> {
    let text = read_input_text(path)?;
    check_csv_shape(path, &text)?;
    CsvReadOptions::default()
        .with_has_header(true)
        .with_infer_schema_length(infer)
        .into_reader_with_file_handle(std::io::Cursor::new(text.into_bytes()))
        .finish()
        .map_err(|e| polars_read_error(path, &e.to_string()))
}

/// The text of an input file (a study file, a report table). A missing path, a directory, an
/// unreadable file ([`crate::intake::read_bytes`]) and bytes that are not UTF-8 are each named
/// as such.
pub fn read_input_text(path: &Path) -> Result<String> {
    let bytes = crate::intake::read_bytes(path)?;
    String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let line = e.as_bytes()[..at].iter().filter(|&&b| b == b'\n').count() + 1;
        Error::data_file(path, format!("line {line}"), "is not UTF-8 text")
    })
}

/// Checks the shape of a CSV text before any cell is read: a header with named, distinct
/// columns, and every non-blank row with as many fields as the header (shorter rows are not
/// padded, longer ones not cut).
pub fn check_csv_shape(path: &Path, text: &str) -> Result<()> {
    let mut lines = text.lines();
    let Some(header) = lines.next().filter(|h| !h.trim().is_empty()) else {
        return Err(Error::data_file(path, "header", "the file is empty or its first line is blank: a header row is expected"));
    };
    let names = crate::intake::text::split_line(header, ',');
    for (k, name) in names.iter().enumerate() {
        if name.is_empty() {
            return Err(Error::data_file(path, "header", format!("column {} has no name", k + 1)));
        }
        if let Some(j) = names[..k].iter().position(|n| n == name) {
            return Err(Error::data_file(path, "header", format!("column `{name}` appears twice (columns {} and {})", j + 1, k + 1)));
        }
    }
    for (i, line) in lines.enumerate().filter(|(_, l)| !l.trim().is_empty()) {
        let got = crate::intake::text::split_line(line, ',').len();
        if got != names.len() {
            return Err(Error::Data { file: path.display().to_string(), location: format!("row {} (line {})", i + 1, i + 2), rule: format!("has {got} fields, the header has {}", names.len()) });
        }
    }
    Ok(())
}

/// Polars' refusal of a CSV file whose shape passed [`check_csv_shape`], on one line.
pub fn polars_read_error(path: &Path, message: &str) -> Error {
    let flat = message.split_whitespace().collect::<Vec<_>>().join(" ");
    Error::data_file(path, "file", format!("not a readable CSV table: {flat}"))
}

/// A float column of a report table (integers are converted).
pub fn col_f64(df: &DataFrame, path: &Path, name: &str) -> Result<Vec<f64>> {
    let col = df.column(name).map_err(|_| Error::data_file(path, "header", format!("missing column `{name}`")))?;
    let cast = col
        .cast(&DataType::Float64)
        .map_err(|e| Error::data_file(path, format!("column {name}"), format!("not numeric: {e}")))?;
    let ca = cast.f64().map_err(|e| Error::data_file(path, format!("column {name}"), e.to_string()))?;
    ca.iter()
        .enumerate()
        .map(|(i, v)| v.ok_or_else(|| Error::data_row(path, i, name, "cell is empty")))
        .collect()
}

/// A text column of a report table.
pub fn col_str(df: &DataFrame, path: &Path, name: &str) -> Result<Vec<String>> {
    let col = df.column(name).map_err(|_| Error::data_file(path, "header", format!("missing column `{name}`")))?;
    let cast = col
        .cast(&DataType::String)
        .map_err(|e| Error::data_file(path, format!("column {name}"), e.to_string()))?;
    let ca = cast.str().map_err(|e| Error::data_file(path, format!("column {name}"), e.to_string()))?;
    Ok(ca.iter().map(|v| v.unwrap_or("").to_string()).collect())
}

/// One input file of a run.
#[derive(Debug, Clone, Serialize)]
pub struct InputFile {
    /// Path as given in the study.
    pub path: String,
    /// SHA-256 of its bytes.
    pub sha256: String,
    /// Size in bytes.
    pub bytes: u64,
    /// How a tabular input was read: format, sheet, columns with units and conversions, filter,
    /// joined files ([`crate::intake`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub read: Option<crate::intake::Provenance>,
}

impl InputFile {
    /// Hashes a file.
    pub fn hash(path: &Path) -> Result<Self> {
        let bytes = std::fs::read(path).map_err(|e| Error::read(path, e))?;
        Ok(InputFile { path: path.display().to_string(), sha256: sha256_hex(&bytes), bytes: bytes.len() as u64, read: None })
    }

    /// Hashes a tabular input and keeps the record of how it was read; a joined file gets an
    /// entry of its own (hash only: its record is inside this one's).
    pub fn read(path: &Path, provenance: &crate::intake::Provenance) -> Result<Vec<Self>> {
        let mut out = vec![InputFile { read: Some(provenance.clone()), ..InputFile::hash(path)? }];
        for j in &provenance.joined {
            let p = Path::new(&j.file);
            if p != path {
                out.push(InputFile::hash(p)?);
            }
        }
        Ok(out)
    }
}

/// `manifest.json` of a run.
#[derive(Debug, Clone, Serialize)]
pub struct Manifest {
    /// Crate version.
    pub partlife_version: String,
    /// The git commit partlife was built from (None: built outside a git clone).
    pub partlife_revision: Option<String>,
    /// Study name (file stem).
    pub study: String,
    /// Study file path.
    pub study_file: String,
    /// The study file verbatim.
    pub study_toml: String,
    /// The study with every default filled in.
    pub study_resolved: serde_json::Value,
    /// Input files with hashes (the study file first).
    pub inputs: Vec<InputFile>,
    /// Seed of all random draws.
    pub seed: u64,
    /// Worker threads (rayon).
    pub threads: usize,
    /// Git revision of the working tree the study lives in, when known (the study's, not the
    /// tool's: `partlife_revision`).
    pub git_revision: Option<String>,
    /// True when that working tree had uncommitted changes.
    pub git_dirty: Option<bool>,
    /// Start time, seconds since the Unix epoch.
    pub started_unix_s: u64,
    /// Wall time of the run (s).
    pub wall_time_s: f64,
    /// Model evaluations by model name.
    pub evaluations: BTreeMap<String, u64>,
    /// Failed evaluations (θ and message).
    pub failures: Vec<String>,
    /// What the run found in its inputs that a reader must know (absent when none).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// Files of the report, relative to its directory.
    pub outputs: Vec<String>,
}

/// Git revision and dirtiness of the repository containing `dir`, when git is available.
pub fn git_state(dir: &Path) -> (Option<String>, Option<bool>) {
    let run = |args: &[&str]| {
        std::process::Command::new("git")
            .arg("-C")
            .arg(dir)
            .args(args)
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    let rev = run(&["rev-parse", "HEAD"]);
    let dirty = rev.as_ref().and_then(|_| run(&["status", "--porcelain"])).map(|s| !s.is_empty());
    (rev, dirty)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uncommitted_report_leaves_nothing_and_commit_replaces() {
        let root = crate::io::TempDir::new("test").unwrap();
        {
            let mut r = ReportDir::create(root.path(), "x").unwrap();
            r.write_bytes("a.txt", b"1").unwrap();
        } // dropped without commit
        assert_eq!(std::fs::read_dir(root.path()).unwrap().count(), 0);
        let mut r = ReportDir::create(root.path(), "x").unwrap();
        r.write_bytes("a.txt", b"1").unwrap();
        r.commit().unwrap();
        let mut r = ReportDir::create(root.path(), "x").unwrap();
        r.write_bytes("b.txt", b"2").unwrap();
        r.commit().unwrap();
        let names: Vec<_> = std::fs::read_dir(root.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(names, vec![std::ffi::OsString::from("x")]);
        assert!(root.path().join("x/b.txt").exists() && !root.path().join("x/a.txt").exists());
    }

    #[test]
    fn branches_list_their_files_in_the_order_they_are_adopted() {
        let root = crate::io::TempDir::new("test").unwrap();
        let mut r = ReportDir::create(root.path(), "x").unwrap();
        r.write_bytes("first.txt", b"0").unwrap();
        let (mut a, mut b) = (r.branch(), r.branch());
        b.write_bytes("b.txt", b"2").unwrap();
        a.write_bytes("a.txt", b"1").unwrap();
        r.adopt(a);
        // A branch dropped (here after adoption) leaves the directory and its files alone.
        assert!(r.path().join("a.txt").exists() && r.path().join("b.txt").exists());
        r.adopt(b);
        assert_eq!(r.files(), ["first.txt", "a.txt", "b.txt"]);
        let dropped = r.branch();
        drop(dropped);
        let done = r.commit().unwrap();
        assert!(done.join("a.txt").exists() && done.join("b.txt").exists());
    }

    #[test]
    fn tables_round_trip() {
        let dir = crate::io::TempDir::new("test").unwrap();
        let mut df = table(vec![fcol("x", vec![1.0, 2.5]), scol("s", vec!["a".into(), "b,c".into()])]).unwrap();
        let p = dir.path().join("t.csv");
        write_atomic(&p, &table_to_csv(&mut df).unwrap()).unwrap();
        let back = read_table(&p).unwrap();
        assert_eq!(col_f64(&back, &p, "x").unwrap(), vec![1.0, 2.5]);
        assert_eq!(col_str(&back, &p, "s").unwrap(), vec!["a".to_string(), "b,c".to_string()]);
        assert!(col_f64(&back, &p, "nope").is_err());
    }
}
