//! `summary.json`: the [`Summary`] of a run, pretty-printed.

use crate::simulation::Summary;
use crate::AppError;
use std::path::Path;

/// Writes `summary` to `path` (JSON, one trailing newline).
pub fn write(path: &Path, summary: &Summary) -> Result<(), AppError> {
    let json = serde_json::to_string_pretty(summary).expect("summary serialises");
    std::fs::write(path, json + "\n").map_err(|e| AppError::io(path, e))
}
