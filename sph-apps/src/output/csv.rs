//! A buffered text file that names itself in errors.

use crate::AppError;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// A buffered text file, written line by line; errors name the file.
#[derive(Debug)]
pub struct CsvFile {
    path: PathBuf,
    w: BufWriter<File>,
}

impl CsvFile {
    /// Creates (or truncates) `path`.
    pub fn create(path: &Path) -> Result<Self, AppError> {
        let f = File::create(path).map_err(|e| AppError::io(path, e))?;
        Ok(Self {
            path: path.to_path_buf(),
            w: BufWriter::new(f),
        })
    }

    /// Writes `s` and a newline.
    pub fn line(&mut self, s: &str) -> Result<(), AppError> {
        writeln!(self.w, "{s}").map_err(|e| AppError::io(&self.path, e))
    }

    /// Writes `args` (from `format_args!`) and a newline, without an
    /// intermediate `String`.
    pub fn line_fmt(&mut self, args: std::fmt::Arguments<'_>) -> Result<(), AppError> {
        self.w
            .write_fmt(args)
            .and_then(|()| self.w.write_all(b"\n"))
            .map_err(|e| AppError::io(&self.path, e))
    }

    /// Writes out what is buffered.
    pub fn flush(&mut self) -> Result<(), AppError> {
        self.w.flush().map_err(|e| AppError::io(&self.path, e))
    }
}
