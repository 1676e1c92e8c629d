//! Which files of an output folder a command may replace: its own, and nothing else.
//!
//! A command that writes into a folder (`run`, `live`, `listen-poses`) records there which files
//! it wrote: its `summary.json`, written last, has an `outputs` object giving the SHA-256 of
//! every other file it wrote ([`Outputs`]). Before the next command removes the earlier outputs
//! ([`Earlier`]), it checks every file at one of its names: a file is ours while the record
//! lists it with the digest its bytes still have, and `summary.json` is ours when it holds such
//! a record. A file at one of those names that is not ours (a hand-written `config.toml`, the
//! data set's own when the folder is the data set, an output edited since) refuses the command
//! before anything is removed. A digest cannot mistake a user's file for ours (equal bytes
//! would be ours anyway), and no file is added to the folder for it. Outputs the record lists
//! under other names (another command's) go with it, so none stays behind unrecorded.

use anyhow::{bail, Context, Result};
use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The file that holds the record: the command's summary.
pub const RECORD: &str = "summary.json";

/// The record's key in [`RECORD`]: an object from file name to SHA-256 (lowercase hex).
pub const RECORD_KEY: &str = "outputs";

/// The record: file name to SHA-256 (lowercase hex) of the bytes written.
pub type Digests = BTreeMap<String, String>;

fn hex(digest: &[u8]) -> String {
    digest.iter().map(|b| format!("{b:02x}")).collect()
}

/// The SHA-256 of `path`'s bytes, lowercase hex.
pub fn digest_of_file(path: &Path) -> Result<String> {
    let mut file =
        std::fs::File::open(path).with_context(|| format!("{}: cannot read", path.display()))?;
    let mut hasher = Sha256::new();
    std::io::copy(&mut file, &mut hasher).with_context(|| format!("{}", path.display()))?;
    Ok(hex(&hasher.finalize()))
}

/// A plain file name: no folder, not `.` or `..` (a record never reaches out of its folder).
fn plain(name: &str) -> bool {
    !name.is_empty() && name != "." && name != ".." && !name.contains(['/', '\\'])
}

/// The record in `text`, if it is a summary a command of ours wrote.
fn parse_record(text: &str) -> Option<Digests> {
    let value: serde_json::Value = serde_json::from_str(text).ok()?;
    let record = value.as_object()?.get(RECORD_KEY)?.as_object()?;
    let sha = |s: &str| s.len() == 64 && s.bytes().all(|b| matches!(b, b'0'..=b'9' | b'a'..=b'f'));
    record
        .iter()
        .map(|(name, d)| {
            let d = d.as_str().filter(|d| sha(d))?;
            plain(name).then(|| (name.clone(), d.to_string()))
        })
        .collect()
}

/// Why a file cannot be replaced, and what to do.
fn not_ours(path: &Path, why: &str) -> anyhow::Error {
    anyhow::anyhow!(
        "{}: {why}; kiss-odom replaces only the files it wrote: move it away or write the \
         outputs to another folder",
        path.display()
    )
}

/// The earlier outputs in a folder, checked to be ours, for a command about to write there.
#[derive(Debug)]
pub struct Earlier {
    dir: PathBuf,
    names: Vec<String>,
    /// The files to remove and the digest each had when checked.
    ours: Vec<(PathBuf, Option<String>)>,
}

impl Earlier {
    /// Checks the files `names` present in `dir` (a missing `dir` has none): each must be
    /// ours (see the module doc), else an error naming the first that is not. Nothing is
    /// removed here.
    pub fn check(dir: &Path, names: &[&str]) -> Result<Self> {
        let present = |name: &str| {
            let path = dir.join(name);
            std::fs::symlink_metadata(&path)
                .ok()
                .filter(|m| !m.is_dir())
                .map(|_| path)
        };
        let record_path = dir.join(RECORD);
        let record = match present(RECORD) {
            None => None,
            Some(path) => {
                let text = std::fs::read_to_string(&path).unwrap_or_default();
                match parse_record(&text) {
                    Some(r) => Some(r),
                    None if names.contains(&RECORD) => {
                        return Err(not_ours(&path, "not a summary kiss-odom wrote"))
                    }
                    None => None,
                }
            }
        };
        let mut ours = Vec::new();
        let listed = |name: &str| record.as_ref().and_then(|r| r.get(name));
        for name in names.iter().filter(|n| **n != RECORD) {
            let Some(path) = present(name) else { continue };
            let Some(recorded) = listed(name) else {
                let why = match record {
                    Some(_) => format!("not an output of kiss-odom ({RECORD} does not list it)"),
                    None => {
                        format!("not an output of kiss-odom (no {RECORD} of kiss-odom lists it)")
                    }
                };
                return Err(not_ours(&path, &why));
            };
            if digest_of_file(&path).ok().as_ref() != Some(recorded) {
                return Err(not_ours(&path, "changed since kiss-odom wrote it"));
            }
            ours.push((path, Some(recorded.clone())));
        }
        if let Some(record) = &record {
            // The record's other files that are still as written: they would stay unrecorded.
            for (name, recorded) in record {
                let path = dir.join(name);
                let other = !names.contains(&name.as_str());
                if other && digest_of_file(&path).ok().as_ref() == Some(recorded) {
                    ours.push((path, Some(recorded.clone())));
                }
            }
            if record_path.is_file() {
                ours.push((record_path, None));
            }
        }
        Ok(Self {
            dir: dir.to_path_buf(),
            names: names.iter().map(|n| n.to_string()).collect(),
            ours,
        })
    }

    /// Removes the files [`Self::check`] found ours, and the temporary files a killed command
    /// left for `names`; a file changed since the check is refused, before any is removed.
    pub fn remove(self) -> Result<()> {
        for (path, recorded) in &self.ours {
            if let Some(d) = recorded {
                if digest_of_file(path).ok().as_ref() != Some(d) {
                    return Err(not_ours(path, "changed since kiss-odom wrote it"));
                }
            }
        }
        for (path, _) in &self.ours {
            super::remove_file_if_present(path)?;
        }
        let names: Vec<&str> = self.names.iter().map(String::as_str).collect();
        super::remove_temporaries(&self.dir, &names)
    }
}

/// A writer that hashes what passes through it.
struct Hashing<'a> {
    inner: &'a mut dyn Write,
    hasher: &'a mut Sha256,
}

impl Write for Hashing<'_> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.hasher.update(&buf[..n]);
        Ok(n)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

/// The files a command writes into its folder, each atomically ([`super::write`]), and the
/// record of them that its [`RECORD`] carries under [`RECORD_KEY`].
#[derive(Debug)]
pub struct Outputs {
    dir: PathBuf,
    written: Digests,
}

impl Outputs {
    /// Outputs into `dir`.
    pub fn new(dir: &Path) -> Self {
        Self {
            dir: dir.to_path_buf(),
            written: Digests::new(),
        }
    }

    /// Writes `bytes` to `dir/name`.
    pub fn write(&mut self, name: &str, bytes: &[u8]) -> Result<()> {
        super::write(&self.dir.join(name), bytes)?;
        self.written
            .insert(name.into(), hex(&Sha256::digest(bytes)));
        Ok(())
    }

    /// Writes `dir/name` through `fill`, as [`super::write_with`].
    pub fn write_with(
        &mut self,
        name: &str,
        fill: impl FnOnce(&mut dyn Write) -> Result<()>,
    ) -> Result<()> {
        let mut hasher = Sha256::new();
        super::write_with(&self.dir.join(name), |w| {
            fill(&mut Hashing {
                inner: w,
                hasher: &mut hasher,
            })
        })?;
        self.written.insert(name.into(), hex(&hasher.finalize()));
        Ok(())
    }

    /// Writes `dir/name` through `fill`, which writes the file at the path it is given, as
    /// [`super::write_via_path`].
    pub fn write_via_path(
        &mut self,
        name: &str,
        fill: impl FnOnce(&Path) -> Result<()>,
    ) -> Result<()> {
        let mut digest = None;
        super::write_via_path(&self.dir.join(name), |p| {
            fill(p)?;
            digest = Some(digest_of_file(p)?);
            Ok(())
        })?;
        if let Some(d) = digest {
            self.written.insert(name.into(), d);
        }
        Ok(())
    }

    /// The record of the files written so far: what [`RECORD`] holds under [`RECORD_KEY`].
    pub fn record(&self) -> &Digests {
        &self.written
    }

    /// Writes `summary`, which must carry [`Self::record`] under [`RECORD_KEY`], to
    /// [`RECORD`]: the last file, so that it records all the others.
    pub fn write_summary(&self, summary: &impl serde::Serialize) -> Result<()> {
        let text = serde_json::to_string_pretty(summary)? + "\n";
        if parse_record(&text).as_ref() != Some(&self.written) {
            bail!("{RECORD}: the summary does not carry the record of the outputs");
        }
        super::write(&self.dir.join(RECORD), text.as_bytes())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const NAMES: [&str; 3] = ["poses.txt", "config.toml", RECORD];

    fn files(d: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    /// A command's outputs in `d`: two files and the summary recording them.
    fn written(d: &Path) {
        let mut o = Outputs::new(d);
        o.write("poses.txt", b"1 0 0 0 0 1 0 0 0 0 1 0\n").unwrap();
        o.write_with("config.toml", |w| Ok(w.write_all(b"[data]\n")?))
            .unwrap();
        let record = o.record().clone();
        o.write_summary(&serde_json::json!({"frames": 1, RECORD_KEY: record}))
            .unwrap();
    }

    #[test]
    fn a_commands_own_outputs_are_removed_and_recorded_by_digest() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        written(d);
        let text = std::fs::read_to_string(d.join(RECORD)).unwrap();
        let record = parse_record(&text).unwrap();
        assert_eq!(record.len(), 2, "{text}");
        assert_eq!(
            record["poses.txt"],
            digest_of_file(&d.join("poses.txt")).unwrap()
        );
        std::fs::write(d.join("notes.txt"), "mine").unwrap();
        std::fs::write(d.join(".kiss-odom-tmp-poses.txt-abc"), "half").unwrap();
        Earlier::check(d, &NAMES).unwrap().remove().unwrap();
        assert_eq!(files(d), ["notes.txt"]);
    }

    #[test]
    fn a_file_not_recorded_or_changed_since_refuses_and_nothing_is_removed() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        // No record at all.
        std::fs::write(d.join("config.toml"), "# mine").unwrap();
        let e = Earlier::check(d, &NAMES).unwrap_err().to_string();
        assert!(
            e.contains("config.toml") && e.contains("not an output"),
            "{e}"
        );
        // A record that does not list it.
        std::fs::remove_file(d.join("config.toml")).unwrap();
        let mut o = Outputs::new(d);
        o.write("poses.txt", b"x\n").unwrap();
        o.write_summary(&serde_json::json!({ RECORD_KEY: o.record() }))
            .unwrap();
        std::fs::write(d.join("config.toml"), "# mine").unwrap();
        let e = Earlier::check(d, &NAMES).unwrap_err().to_string();
        assert!(e.contains("does not list it"), "{e}");
        // Listed, but changed since.
        std::fs::remove_file(d.join("config.toml")).unwrap();
        std::fs::write(d.join("poses.txt"), "edited\n").unwrap();
        let e = Earlier::check(d, &NAMES).unwrap_err().to_string();
        assert!(
            e.contains("poses.txt") && e.contains("changed since"),
            "{e}"
        );
        assert_eq!(files(d), ["poses.txt", RECORD]);
        // A summary that is not ours.
        std::fs::remove_file(d.join("poses.txt")).unwrap();
        std::fs::write(d.join(RECORD), "{\"frames\": 3}").unwrap();
        let e = Earlier::check(d, &NAMES).unwrap_err().to_string();
        assert!(e.contains(RECORD), "{e}");
        assert_eq!(files(d), [RECORD]);
    }

    #[test]
    fn a_file_changed_between_the_check_and_the_removal_is_kept() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        written(d);
        let earlier = Earlier::check(d, &NAMES).unwrap();
        std::fs::write(d.join("config.toml"), "# mine now").unwrap();
        assert!(earlier.remove().is_err());
        assert_eq!(files(d), ["config.toml", "poses.txt", RECORD]);
    }

    #[test]
    fn another_commands_recorded_outputs_go_with_the_record_unless_changed() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let mut o = Outputs::new(d);
        o.write("poses.txt", b"x\n").unwrap();
        o.write("trajectory.png", b"png").unwrap();
        o.write("diagnostics.png", b"png 2").unwrap();
        o.write_summary(&serde_json::json!({ RECORD_KEY: o.record() }))
            .unwrap();
        std::fs::write(d.join("diagnostics.png"), "mine now").unwrap();
        Earlier::check(d, &["poses.txt", RECORD])
            .unwrap()
            .remove()
            .unwrap();
        assert_eq!(files(d), ["diagnostics.png"]);
    }

    #[test]
    fn a_summary_without_the_record_of_the_outputs_is_not_written() {
        let dir = tempfile::tempdir().unwrap();
        let mut o = Outputs::new(dir.path());
        o.write("poses.txt", b"x\n").unwrap();
        let stale = serde_json::json!({ RECORD_KEY: {} });
        assert!(o.write_summary(&stale).is_err());
        assert!(o.write_summary(&serde_json::json!({"frames": 1})).is_err());
        assert!(!dir.path().join(RECORD).exists());
    }

    #[test]
    fn a_record_naming_a_path_outside_its_folder_is_not_a_record() {
        let d = "a".repeat(64);
        assert!(parse_record(&format!("{{\"outputs\": {{\"x.txt\": \"{d}\"}}}}")).is_some());
        for name in ["../x.txt", "sub/x.txt", ".."] {
            let text = format!("{{\"outputs\": {{\"{name}\": \"{d}\"}}}}");
            assert!(parse_record(&text).is_none(), "{name}");
        }
        assert!(parse_record("{\"outputs\": {\"x.txt\": \"abc\"}}").is_none());
        assert!(parse_record("[1, 2]").is_none());
    }
}
