//! The crate's error type.
//!
//! Every fallible library function returns [`Result<T>`]. The variants separate *bad input*
//! (the user can fix it: a malformed dataset, an unknown study key, an impossible option) from
//! *run failures* (a numerical breakdown, an I/O failure while writing), because the CLI maps the
//! first to exit code 2 and the second to exit code 1 ([`Error::is_bad_input`]).
//!
//! Data errors always name the file, the row (1-based data row, with the physical line number)
//! and column, and the rule that was broken, so a user can find and fix the cell.

use std::path::Path;

/// Result alias used throughout the crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Errors raised by partlife.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A study or generator configuration is invalid: unknown key, impossible value.
    #[error("{file}: {key}: {rule}")]
    Config {
        /// Configuration file (or `<study>` when built in code).
        file: String,
        /// Offending key, dotted (`impact.energy_fraction`).
        key: String,
        /// The rule that was broken, in words.
        rule: String,
    },
    /// A dataset file is malformed or holds an impossible value.
    #[error("{file}: {location}: {rule}")]
    Data {
        /// Dataset file path.
        file: String,
        /// Where: `row 17 (line 18), column diameter_m`, or `header`.
        location: String,
        /// The rule that was broken, in words.
        rule: String,
    },
    /// An input file could not be read.
    #[error("{path}: cannot read: {source}")]
    Read {
        /// File path.
        path: String,
        /// Underlying I/O error.
        source: std::io::Error,
    },
    /// An output could not be written (disk full, permissions): a run failure, not bad input.
    #[error("{path}: cannot write: {source}")]
    Write {
        /// File or directory path.
        path: String,
        /// Underlying I/O error.
        source: std::io::Error,
    },
    /// A parameter vector does not fit its [`crate::params::ParamSpace`], or a name is unknown.
    #[error("parameter {name}: {rule}")]
    Param {
        /// Parameter name.
        name: String,
        /// The rule that was broken.
        rule: String,
    },
    /// A numerical procedure failed (no convergence, non-finite value). A bug or a limit of the
    /// method, never silently ignored.
    #[error("numerical failure in {what}: {detail}")]
    Numerical {
        /// Which computation.
        what: String,
        /// What went wrong and where.
        detail: String,
    },
    /// A figure could not be drawn or converted.
    #[error("figure {name}: {detail}")]
    Figure {
        /// Figure file stem.
        name: String,
        /// What failed.
        detail: String,
    },
}

impl Error {
    /// This error, then `other`, as one message where both are about the same data file ("…;
    /// and <location>: <rule>"), so a file with several things to mend needs one run; this error
    /// alone otherwise.
    pub fn then(self, other: Error) -> Error {
        match (self, other) {
            (Error::Data { file, location, rule }, Error::Data { file: f2, location: l2, rule: r2 }) if file == f2 => Error::Data { file, location, rule: format!("{rule}; and {l2}: {r2}") },
            (first, _) => first,
        }
    }

    /// The error with `note` appended to its rule where the rule tells the user to declare
    /// something in a study (a `Config` or `Data` error whose rule names a study key); any
    /// other error unchanged. For callers that have no study to declare it in (`--data`).
    pub fn noted_where_declared(self, note: &str) -> Self {
        let asks = |rule: &str| rule.contains("declare") || rule.contains("in the study") || rule.contains("ignore = [");
        match self {
            Error::Config { file, key, rule } if asks(&rule) => Error::Config { file, key, rule: format!("{rule}{note}") },
            Error::Data { file, location, rule } if asks(&rule) => Error::Data { file, location, rule: format!("{rule}{note}") },
            other => other,
        }
    }

    /// True when the user can fix the problem by changing the input (exit code 2).
    pub fn is_bad_input(&self) -> bool {
        matches!(
            self,
            Error::Config { .. } | Error::Data { .. } | Error::Read { .. } | Error::Param { .. }
        )
    }

    /// A parameter error raised where the study is not known, placed in study `file`: a key of
    /// the material's own table (`predict`) under `table` (`material[1].predict`), a study-level
    /// key (`contact.averaging`) as it is; other errors unchanged.
    pub fn in_study(self, file: &str, table: &str) -> Self {
        match self {
            Error::Param { name, rule } if name == "predict" => Error::Config { file: file.into(), key: format!("{table}.{name}"), rule },
            Error::Param { name, rule } => Error::Config { file: file.into(), key: name, rule },
            e => e,
        }
    }

    /// A configuration error.
    pub fn config(file: impl Into<String>, key: impl Into<String>, rule: impl Into<String>) -> Self {
        Error::Config { file: file.into(), key: key.into(), rule: rule.into() }
    }

    /// A data error at a data row (0-based index into the data rows; the header is line 1).
    pub fn data_row(file: &Path, row_index: usize, column: &str, rule: impl Into<String>) -> Self {
        Error::Data {
            file: file.display().to_string(),
            location: format!("row {} (line {}), column {column}", row_index + 1, row_index + 2),
            rule: rule.into(),
        }
    }

    /// A data error that concerns the whole file (missing column, empty file).
    pub fn data_file(file: &Path, location: impl Into<String>, rule: impl Into<String>) -> Self {
        Error::Data { file: file.display().to_string(), location: location.into(), rule: rule.into() }
    }

    /// A numerical failure.
    pub fn numerical(what: impl Into<String>, detail: impl Into<String>) -> Self {
        Error::Numerical { what: what.into(), detail: detail.into() }
    }

    /// A read failure.
    pub fn read(path: &Path, source: std::io::Error) -> Self {
        Error::Read { path: path.display().to_string(), source }
    }

    /// A write failure.
    pub fn write(path: &Path, source: std::io::Error) -> Self {
        Error::Write { path: path.display().to_string(), source }
    }
}
