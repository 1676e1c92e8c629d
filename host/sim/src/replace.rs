//! What `simulate` may replace in its output folder: nothing, or with `--overwrite` the data
//! set an earlier `simulate` wrote there, and only that.
//!
//! A data set is `simulate`'s when its `sim.toml` starts with the line `simulate` writes and
//! ends with the list of the files and folders beside it that it wrote ([`written_table`]). A
//! file of a name `simulate` writes that the list leaves out, a folder without such a
//! `sim.toml` (a real data set), or a file in a frame folder that is not a frame, refuses the
//! run before anything is removed. The old data set goes only once the new one is complete
//! ([`Replacement::remove_old`]), so a refused, failed or interrupted run leaves the folder as
//! it was. The folders the list names go whole: they are the data set the user asked to
//! replace.

use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};
use std::fs;
use std::path::{Path, PathBuf};

/// The provenance file, beside the data set.
pub const SIM_TOML: &str = "sim.toml";

/// How every `sim.toml` that `simulate` writes begins.
pub const HEADER: &str = "# Written by `kiss-odom simulate";

/// Folders of the generic layout that hold frame files only.
const FRAME_DIRS: [&str; 2] = ["velodyne", "timestamps"];

/// Staging folders start with this (hidden, so no reader takes one for a data set).
pub const STAGING_PREFIX: &str = ".kiss-odom-simulate-";

/// The table `sim.toml` ends with.
#[derive(Serialize, Deserialize)]
struct Record {
    written: Entries,
}

#[derive(Serialize, Deserialize)]
struct Entries {
    /// The files and folders beside `sim.toml` that `simulate` wrote.
    entries: Vec<String>,
}

/// The end of `sim.toml`: the files and folders `entries` beside it that `simulate` wrote,
/// what a later `--overwrite` replaces.
pub fn written_table(entries: &[&str]) -> Result<String> {
    let record = Record {
        written: Entries {
            entries: entries.iter().map(|e| e.to_string()).collect(),
        },
    };
    let table = toml::to_string(&record).context("serialising sim.toml")?;
    Ok(format!(
        "\n# The files and folders beside this one that simulate wrote (--overwrite replaces \
         them).\n{table}"
    ))
}

/// Whether `name` is a frame file's name: six or more digits and `.bin`.
pub fn is_frame_name(name: &str) -> bool {
    name.len() >= 10
        && name.ends_with(".bin")
        && name[..name.len() - 4].bytes().all(|b| b.is_ascii_digit())
}

/// A plain name in the folder: no path, not `.` or `..`.
fn plain(name: &str) -> bool {
    !name.is_empty() && name != "." && name != ".." && !name.contains(['/', '\\'])
}

/// The entries the `sim.toml` at `path` lists, if `simulate` wrote it.
fn listed(path: &Path) -> Option<Vec<String>> {
    let text = fs::read_to_string(path).ok()?;
    if !text.starts_with(HEADER) {
        return None;
    }
    let record: Record = toml::from_str(&text).ok()?;
    let entries = record.written.entries;
    entries.iter().all(|e| plain(e)).then_some(entries)
}

/// The old data set in an output folder, checked, to be removed once the new one is complete.
#[derive(Debug)]
pub struct Replacement {
    /// The old data set's files and folders (with its `sim.toml`).
    old: Vec<PathBuf>,
}

impl Replacement {
    /// Checks `dir` before a data set whose top-level entries are `names` is written there
    /// (see the module doc); staging folders a killed run left are removed once the checks
    /// pass. Nothing else is removed here.
    pub fn check(dir: &Path, names: &[&str], overwrite: bool) -> Result<Self> {
        let exists = |n: &str| fs::symlink_metadata(dir.join(n)).is_ok();
        let mut present: Vec<&str> = names.iter().copied().filter(|n| exists(n)).collect();
        if exists(SIM_TOML) && !present.contains(&SIM_TOML) {
            present.push(SIM_TOML);
        }
        let mut old = Vec::new();
        if !present.is_empty() {
            if !overwrite {
                bail!(
                    "{} already holds a data set ({}); pass --overwrite to replace it",
                    dir.display(),
                    present.join(", ")
                );
            }
            let toml = dir.join(SIM_TOML);
            let Some(entries) = listed(&toml) else {
                let why = if exists(SIM_TOML) {
                    format!("{} is not one simulate wrote", toml.display())
                } else {
                    format!("it has no {SIM_TOML}")
                };
                bail!(
                    "{}: --overwrite replaces only a data set `kiss-odom simulate` wrote, and \
                     {why}; move the data set away or choose another --out",
                    dir.display()
                );
            };
            for name in present.iter().filter(|n| **n != SIM_TOML) {
                if !entries.iter().any(|e| e == name) {
                    bail!(
                        "{}: not part of the data set simulate wrote ({SIM_TOML} does not list \
                         it); move it away or choose another --out",
                        dir.join(name).display()
                    );
                }
            }
            for entry in entries.iter().filter(|e| exists(e)) {
                if FRAME_DIRS.contains(&entry.as_str()) {
                    only_frames(&dir.join(entry))?;
                }
                old.push(dir.join(entry));
            }
            old.push(toml);
        }
        remove_staging(dir)?;
        Ok(Self { old })
    }

    /// Removes the old data set (call it once the new one is complete, before moving it in).
    pub fn remove_old(&self) -> Result<()> {
        for path in &self.old {
            let removed = match fs::symlink_metadata(path) {
                Ok(m) if m.is_dir() => fs::remove_dir_all(path),
                Ok(_) => fs::remove_file(path),
                Err(_) => Ok(()),
            };
            removed.with_context(|| {
                format!("{}: cannot remove the earlier data set", path.display())
            })?;
        }
        Ok(())
    }
}

/// Checks that the frame folder `dir` holds frame files only.
fn only_frames(dir: &Path) -> Result<()> {
    let entries = fs::read_dir(dir).with_context(|| format!("listing {}", dir.display()))?;
    for entry in entries {
        let entry = entry.with_context(|| format!("listing {}", dir.display()))?;
        let frame = entry.file_name().to_str().is_some_and(is_frame_name)
            && entry.file_type().is_ok_and(|t| t.is_file());
        if !frame {
            bail!(
                "{}: not a frame simulate wrote; move it away or choose another --out",
                entry.path().display()
            );
        }
    }
    Ok(())
}

/// Removes the staging folders a killed run left in `dir`.
fn remove_staging(dir: &Path) -> Result<()> {
    let Ok(entries) = fs::read_dir(dir) else {
        return Ok(());
    };
    for entry in entries.flatten() {
        let stale = entry
            .file_name()
            .to_string_lossy()
            .starts_with(STAGING_PREFIX);
        if stale && entry.file_type().is_ok_and(|t| t.is_dir()) {
            fs::remove_dir_all(entry.path())
                .with_context(|| format!("removing {}", entry.path().display()))?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const NAMES: [&str; 4] = ["velodyne", "poses.txt", "imu.csv", SIM_TOML];

    /// A data set of ours in `d` listing `entries`, with one frame.
    fn ours(d: &Path, entries: &[&str]) {
        fs::create_dir_all(d.join("velodyne")).unwrap();
        fs::write(d.join("velodyne/000000.bin"), [0u8; 16]).unwrap();
        fs::write(d.join("poses.txt"), "1 0 0 0 0 1 0 0 0 0 1 0\n").unwrap();
        let toml = format!("{HEADER}`\n\nseed = 0\n{}", written_table(entries).unwrap());
        fs::write(d.join(SIM_TOML), toml).unwrap();
    }

    fn left(d: &Path) -> Vec<String> {
        let mut v: Vec<String> = fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn a_data_set_simulate_wrote_is_replaced_whole_once_checked() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        ours(d, &["velodyne", "poses.txt"]);
        fs::write(d.join("notes.txt"), "mine").unwrap();
        fs::create_dir(d.join(format!("{STAGING_PREFIX}abc"))).unwrap();
        let e = Replacement::check(d, &NAMES, false)
            .unwrap_err()
            .to_string();
        assert!(e.contains("--overwrite"), "{e}");
        let r = Replacement::check(d, &NAMES, true).unwrap();
        assert_eq!(left(d), ["notes.txt", "poses.txt", SIM_TOML, "velodyne"]);
        r.remove_old().unwrap();
        assert_eq!(left(d), ["notes.txt"]);
    }

    #[test]
    fn what_simulate_did_not_write_refuses_overwrite_and_stays() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        // A name simulate writes that its sim.toml does not list.
        ours(d, &["velodyne", "poses.txt"]);
        fs::write(d.join("imu.csv"), "mine").unwrap();
        let e = Replacement::check(d, &NAMES, true).unwrap_err().to_string();
        assert!(e.contains("imu.csv") && e.contains("does not list"), "{e}");
        fs::remove_file(d.join("imu.csv")).unwrap();
        // A file in a frame folder that is not a frame.
        fs::write(d.join("velodyne/notes.txt"), "mine").unwrap();
        let e = Replacement::check(d, &NAMES, true).unwrap_err().to_string();
        assert!(e.contains("notes.txt") && e.contains("not a frame"), "{e}");
        fs::remove_file(d.join("velodyne/notes.txt")).unwrap();
        // A sim.toml simulate did not write, or none.
        fs::write(d.join(SIM_TOML), "seed = 0\n").unwrap();
        let e = Replacement::check(d, &NAMES, true).unwrap_err().to_string();
        assert!(e.contains("not one simulate wrote"), "{e}");
        fs::remove_file(d.join(SIM_TOML)).unwrap();
        let e = Replacement::check(d, &NAMES, true).unwrap_err().to_string();
        assert!(e.contains("no sim.toml"), "{e}");
        assert_eq!(left(d), ["poses.txt", "velodyne"]);
        assert_eq!(left(&d.join("velodyne")), ["000000.bin"]);
    }

    #[test]
    fn a_list_reaching_out_of_the_folder_is_not_simulates() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        ours(d, &["../elsewhere", "poses.txt"]);
        assert!(Replacement::check(d, &NAMES, true).is_err());
        assert!(is_frame_name("000042.bin") && !is_frame_name("notes.bin"));
    }
}
