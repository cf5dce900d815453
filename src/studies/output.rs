//! What every study does with its results, in one place: the output
//! folder, the JSON report with who wrote it, the plots and text tables
//! drawn from the report, and the replot that draws them again from an
//! earlier JSON without running anything.
//!
//! A study's report type implements [`StudyReport`]: the name of its JSON
//! file and how it is drawn. [`write_report`] then writes the JSON and
//! the drawings, and [`replot`] redraws them from the JSON. Every file,
//! plots included, is written whole ([`write_whole`]): a failure leaves
//! the earlier complete file, never half of one.

use crate::analysis::plot::{write_svg, write_svg_rows, Panel, PlotError};
use crate::file_error::FileError;
pub use crate::whole_file::write_whole;
use serde::{de::DeserializeOwned, Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Why a study's results could not be written or read back.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// A file or folder could not be created, written or read.
    #[error(transparent)]
    File(#[from] FileError),
    /// A plot could not be drawn.
    #[error(transparent)]
    Plot(#[from] PlotError),
    /// A JSON file is not a report of this study (or of this version).
    #[error("reading {path}: {message}")]
    Json {
        /// The file.
        path: String,
        /// What serde found wrong.
        message: String,
    },
}

/// A study's report: written as JSON, read back for a replot, drawn as
/// plots and tables.
pub trait StudyReport: Serialize + DeserializeOwned {
    /// The JSON file's name in the output folder (`stability.json`).
    const JSON: &'static str;

    /// Writes the plots and tables drawn from the report into `out`.
    fn draw(&self, out: &StudyOutput) -> Result<(), OutputError>;

    /// Why a report read back cannot be drawn (its options out of range,
    /// as a hand-edited file may have them), if it cannot.
    fn check(&self) -> Result<(), String> {
        Ok(())
    }
}

/// A study's output folder, created when opened. Every write goes
/// through a temporary file renamed into place.
#[derive(Clone, Debug)]
pub struct StudyOutput {
    dir: PathBuf,
}

impl StudyOutput {
    /// The folder `dir`, created with its parents if missing.
    pub fn create(dir: &Path) -> Result<Self, FileError> {
        std::fs::create_dir_all(dir).map_err(FileError::on("creating", dir))?;
        Ok(Self {
            dir: dir.to_path_buf(),
        })
    }

    /// The folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The path of file `name` in the folder.
    pub fn path(&self, name: &str) -> PathBuf {
        self.dir.join(name)
    }

    /// Writes `value` as pretty JSON to file `name`.
    pub fn json(&self, name: &str, value: &impl Serialize) -> Result<PathBuf, OutputError> {
        let path = self.path(name);
        write_json(&path, value)?;
        Ok(path)
    }

    /// Writes `text` to file `name`.
    pub fn text(&self, name: &str, text: &str) -> Result<PathBuf, FileError> {
        let path = self.path(name);
        write_whole(&path, text.as_bytes())?;
        Ok(path)
    }

    /// Draws `panels` side by side into the SVG file `name`.
    pub fn svg(&self, name: &str, panels: &[Panel]) -> Result<PathBuf, PlotError> {
        let path = self.path(name);
        write_svg(&path, panels)?;
        Ok(path)
    }

    /// Draws `panels`, `columns` to a row, into the SVG file `name`.
    pub fn svg_rows(
        &self,
        name: &str,
        panels: &[Panel],
        columns: usize,
    ) -> Result<PathBuf, PlotError> {
        let path = self.path(name);
        write_svg_rows(&path, panels, columns)?;
        Ok(path)
    }
}

/// Writes `value` as pretty JSON to `path`, whole: for a study whose
/// JSON is not a [`StudyReport`] (one assembled as a `serde_json::Value`).
pub fn write_json(path: &Path, value: &impl Serialize) -> Result<(), OutputError> {
    let text = serde_json::to_string_pretty(value).map_err(|e| OutputError::Json {
        path: path.display().to_string(),
        message: format!("cannot be written as JSON: {e}"),
    })?;
    Ok(write_whole(path, text.as_bytes())?)
}

/// Writes `report` into the folder `dir`: its JSON, then its drawings.
pub fn write_report<R: StudyReport>(report: &R, dir: &Path) -> Result<StudyOutput, OutputError> {
    let out = StudyOutput::create(dir)?;
    out.json(R::JSON, report)?;
    report.draw(&out)?;
    Ok(out)
}

/// Reads an earlier report from `json`.
pub fn read_report<R: StudyReport>(json: &Path) -> Result<R, OutputError> {
    let text = std::fs::read_to_string(json).map_err(FileError::on("reading", json))?;
    let bad = |message: String| OutputError::Json {
        path: json.display().to_string(),
        message,
    };
    let report: R = serde_json::from_str(&text)
        .map_err(|e| bad(format!("not a valid {} of this version: {e}", R::JSON)))?;
    report.check().map_err(bad)?;
    Ok(report)
}

/// Reads an earlier report from `json` and writes it, with its drawings
/// made by this version, into `dir`, running nothing.
pub fn replot<R: StudyReport>(json: &Path, dir: &Path) -> Result<R, OutputError> {
    let report = read_report(json)?;
    write_report(&report, dir)?;
    Ok(report)
}

/// Where a replot of `json` writes when no folder is given: the JSON's own
/// folder (its report rewritten unchanged, its drawings redrawn), never a
/// study's default folder, which may hold another report.
pub fn replot_folder(json: &Path) -> PathBuf {
    json.parent()
        .filter(|p| !p.as_os_str().is_empty())
        .map_or_else(|| PathBuf::from("."), Path::to_path_buf)
}

/// Who wrote a report, so it can be repeated: the program with its
/// version, and the command line. Flattened into a report's head
/// (`#[serde(flatten)]`), it writes `program` and `command` there; the
/// reports of Hertz, compaction and the multi-contact studies keep the
/// fields they had (their committed JSON stays readable as it is).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Provenance {
    /// `bpm` and its version.
    pub program: String,
    /// The command line as given.
    pub command: String,
}

impl Provenance {
    /// This program, run with `command`.
    pub fn new(command: &str) -> Self {
        Self {
            program: format!("bpm {}", crate::VERSION),
            command: command.into(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::plot::{Mark, Series};

    #[derive(Debug, PartialEq, Serialize, Deserialize)]
    struct Squares {
        #[serde(flatten)]
        provenance: Provenance,
        points: Vec<(f64, f64)>,
    }

    impl StudyReport for Squares {
        const JSON: &'static str = "squares.json";

        fn draw(&self, out: &StudyOutput) -> Result<(), OutputError> {
            let mut panel = Panel {
                title: "squares".into(),
                ..Panel::default()
            };
            panel
                .series
                .push(Series::new("x^2", self.points.clone(), Mark::LinePoints));
            out.svg("squares.svg", &[panel])?;
            let table: String = self
                .points
                .iter()
                .map(|(x, y)| format!("{x} {y}\n"))
                .collect();
            out.text("squares.txt", &table)?;
            Ok(())
        }
    }

    /// An empty folder of the system's temporary space for test `name`.
    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("bpm-output-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn squares() -> Squares {
        Squares {
            provenance: Provenance::new("bpm squares --n 3"),
            points: vec![(1.0, 1.0), (2.0, 4.0), (3.0, 9.0)],
        }
    }

    #[test]
    fn a_report_is_written_whole_and_replotted_from_its_json() {
        let dir = scratch("replot");
        let first = dir.join("first");
        write_report(&squares(), &first).unwrap();
        let json = std::fs::read_to_string(first.join("squares.json")).unwrap();
        assert!(json.starts_with("{\n  \"program\": \"bpm "), "{json}");
        assert!(json.contains("\"command\": \"bpm squares --n 3\""));
        // Nothing is left of the temporary files.
        let mut names: Vec<String> = std::fs::read_dir(&first)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(names, ["squares.json", "squares.svg", "squares.txt"]);

        let again = dir.join("again");
        let read: Squares = replot(&first.join("squares.json"), &again).unwrap();
        assert_eq!(read, squares());
        for name in ["squares.json", "squares.svg", "squares.txt"] {
            assert_eq!(
                std::fs::read(first.join(name)).unwrap(),
                std::fs::read(again.join(name)).unwrap(),
                "{name}"
            );
        }
    }

    #[test]
    fn another_studys_json_is_refused_naming_the_file() {
        let dir = scratch("refused");
        let other = dir.join("other.json");
        std::fs::write(&other, r#"{"program": "bpm 0", "rows": []}"#).unwrap();
        let err = replot::<Squares>(&other, &dir).unwrap_err();
        let message = err.to_string();
        assert!(
            message.contains("other.json") && message.contains("not a valid squares.json"),
            "{message}"
        );
        assert!(!dir.join("squares.svg").exists());
    }
}
