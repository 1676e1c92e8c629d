//! How every command writes its files: whole or not at all, and never beside stale ones.
//!
//! A file is written under a hidden temporary name in its own folder and renamed over its
//! final name when complete, so a reader (or a later command) never sees half a file, and an
//! interrupted or failed command leaves no partial output. Before a command starts it removes
//! the outputs an earlier run left, so a failed run cannot leave an older `summary.json`
//! looking like its own: in an output folder only the files an earlier command recorded as
//! its own ([`outputs`]), and a file the user named (`--json`, `--save-map`) as named
//! ([`remove_stale_file`]); temporary files that a killed process could not clean up go with
//! them.

pub mod outputs;

use anyhow::{Context, Result};
use std::io::Write;
use std::path::{Path, PathBuf};

/// Temporary files start with this, then the final name: `.kiss-odom-tmp-summary.json-XXXXXX`.
const TEMP_PREFIX: &str = ".kiss-odom-tmp-";

fn parent_of(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

fn file_name(path: &Path) -> Result<String> {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .with_context(|| format!("{}: not a file name", path.display()))
}

/// A temporary file beside `path`, with its extension (writers such as the PNG encoder choose
/// the format by it), readable as a normal output once renamed.
fn temp_beside(path: &Path) -> Result<tempfile::NamedTempFile> {
    let prefix = format!("{TEMP_PREFIX}{}-", file_name(path)?);
    let suffix = path
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    let mut b = tempfile::Builder::new();
    b.prefix(&prefix).suffix(&suffix);
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        b.permissions(std::fs::Permissions::from_mode(0o666)); // less the umask, as File::create
    }
    b.tempfile_in(parent_of(path))
        .with_context(|| format!("{}: cannot create a temporary file", path.display()))
}

/// Writes `bytes` to `path` atomically.
pub fn write(path: &Path, bytes: &[u8]) -> Result<()> {
    write_with(path, |w| Ok(w.write_all(bytes)?))
}

/// Writes `path` atomically through `fill`, which writes the content to a buffered writer.
pub fn write_with(path: &Path, fill: impl FnOnce(&mut dyn Write) -> Result<()>) -> Result<()> {
    let tmp = temp_beside(path)?;
    let mut w = std::io::BufWriter::new(tmp.as_file());
    fill(&mut w).with_context(|| format!("{}", path.display()))?;
    w.flush().with_context(|| format!("{}", path.display()))?;
    drop(w);
    tmp.persist(path)
        .map_err(|e| e.error)
        .with_context(|| format!("{}", path.display()))?;
    Ok(())
}

/// Writes `path` atomically through `fill`, which writes a file at the path it is given (for
/// encoders that open the file themselves).
pub fn write_via_path(path: &Path, fill: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let tmp = temp_beside(path)?.into_temp_path();
    fill(&tmp).with_context(|| format!("{}", path.display()))?;
    tmp.persist(path)
        .map_err(|e| e.error)
        .with_context(|| format!("{}", path.display()))?;
    Ok(())
}

/// Removes the temporary files this module left in `dir` for the files `names`. A missing
/// `dir` has none.
fn remove_temporaries(dir: &Path, names: &[&str]) -> Result<()> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Ok(());
    };
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        let ours = name
            .strip_prefix(TEMP_PREFIX)
            .is_some_and(|rest| names.iter().any(|n| rest.starts_with(&format!("{n}-"))));
        if ours {
            remove_file_if_present(&entry.path())?;
        }
    }
    Ok(())
}

/// Removes the output `path` the user named (a `--json` file, `--save-map`) and its
/// temporaries.
pub fn remove_stale_file(path: &Path) -> Result<()> {
    remove_file_if_present(path)?;
    remove_temporaries(parent_of(path), &[&file_name(path)?])
}

/// Refuses an output at `path` that would remove an input: the file there is removed before
/// a command starts, so it must not be one of `inputs` (by any name) nor a file inside an
/// input folder (a frame of a dataset). Nothing at `path` yet is nothing to refuse.
pub fn refuse_input(path: &Path, inputs: &[&Path]) -> Result<()> {
    let entry = |p: &Path| Some(parent_of(p).canonicalize().ok()?.join(p.file_name()?));
    if std::fs::symlink_metadata(path).is_err() {
        return Ok(());
    }
    let Some(out) = entry(path) else {
        return Ok(());
    };
    for input in inputs {
        let folder = input.is_dir().then(|| input.canonicalize().ok()).flatten();
        let within = folder.is_some_and(|f| out.starts_with(f));
        if within || entry(input).as_ref() == Some(&out) {
            anyhow::bail!(
                "{}: would replace a file of this run's input {}; write the output elsewhere",
                path.display(),
                input.display()
            );
        }
    }
    Ok(())
}

/// Refuses two of the options `named` (each with the file it names, if given) that name one
/// file, by any path to it: one output would replace the other.
pub fn refuse_shared(named: &[(&str, Option<&Path>)]) -> Result<()> {
    let given: Vec<(&str, &Path)> = named
        .iter()
        .filter_map(|(o, p)| Some((*o, (*p)?)))
        .collect();
    for (k, (option, path)) in given.iter().enumerate() {
        if let Some((other, _)) = given[k + 1..].iter().find(|(_, p)| same_file(path, p)) {
            anyhow::bail!(
                "{}: {option} and {other} name the same file, and one would replace the other; \
                 give each its own",
                path.display()
            );
        }
    }
    Ok(())
}

/// Whether `a` and `b` name one file, whether it exists yet or not: the same name in the same
/// folder (whatever path leads to it), or one existing file under two names (a link).
pub fn same_file(a: &Path, b: &Path) -> bool {
    let entry = |p: &Path| Some(parent_of(p).canonicalize().ok()?.join(p.file_name()?));
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let (Ok(x), Ok(y)) = (std::fs::metadata(a), std::fs::metadata(b)) {
            if (x.dev(), x.ino()) == (y.dev(), y.ino()) {
                return true;
            }
        }
    }
    match (entry(a), entry(b)) {
        (Some(x), Some(y)) => x == y,
        _ => a == b,
    }
}

/// Removes `path` if it is a file (or a link); anything else there is left alone.
pub fn remove_file_if_present(path: &Path) -> Result<()> {
    match std::fs::symlink_metadata(path) {
        Ok(m) if !m.is_dir() => std::fs::remove_file(path)
            .with_context(|| format!("{}: cannot remove the earlier output", path.display())),
        _ => Ok(()),
    }
}

/// The files directly in `dir` whose names start with the temporary prefix (for tests).
pub fn temporaries_in(dir: &Path) -> Vec<PathBuf> {
    std::fs::read_dir(dir)
        .map(|entries| {
            entries
                .flatten()
                .filter(|e| e.file_name().to_string_lossy().starts_with(TEMP_PREFIX))
                .map(|e| e.path())
                .collect()
        })
        .unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_written_file_appears_whole_and_nothing_else_remains() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("summary.json");
        std::fs::write(&path, "old").unwrap();
        write(&path, b"new").unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "new");
        assert!(temporaries_in(dir.path()).is_empty());
    }

    #[test]
    fn a_failed_write_leaves_the_old_file_and_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("frames.csv");
        std::fs::write(&path, "old").unwrap();
        let e = write_with(&path, |w| {
            w.write_all(b"half")?;
            anyhow::bail!("disk full")
        });
        assert!(e.is_err());
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "old");
        assert!(temporaries_in(dir.path()).is_empty());
    }

    #[test]
    fn an_output_over_an_input_or_a_file_of_an_input_folder_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::create_dir(d.join("sub")).unwrap();
        std::fs::write(d.join("rec.pcap"), "x").unwrap();
        let input = d.join("rec.pcap");
        let e = refuse_input(&d.join("sub/../rec.pcap"), &[&input]).unwrap_err();
        assert!(e.to_string().contains("of this run's input"), "{e}");
        // A file inside an input folder (a frame) too, but not the folder's new files.
        std::fs::write(d.join("sub/000000.ply"), "x").unwrap();
        let folder = d.join("sub");
        assert!(refuse_input(&d.join("sub/000000.ply"), &[&folder]).is_err());
        refuse_input(&d.join("sub/map.ply"), &[&folder]).unwrap();
        // Another file, or none yet, is no conflict.
        std::fs::write(d.join("map.ply"), "x").unwrap();
        refuse_input(&d.join("map.ply"), &[&input]).unwrap();
        refuse_input(&d.join("new.ply"), &[&input]).unwrap();
    }

    #[test]
    fn one_file_is_the_same_under_any_path_to_it_existing_or_not() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::create_dir(d.join("sub")).unwrap();
        let map = d.join("map.ply");
        assert!(same_file(&map, &d.join("sub/../map.ply")), "not there yet");
        assert!(same_file(&map, &d.join("./map.ply")));
        assert!(!same_file(&map, &d.join("cloud.ply")));
        assert!(!same_file(&map, &d.join("sub/map.ply")));
        std::fs::write(&map, "x").unwrap();
        std::fs::hard_link(&map, d.join("link.ply")).unwrap();
        assert!(same_file(&map, &d.join("link.ply")), "one file, two names");
        assert!(same_file(Path::new("new/m.ply"), Path::new("new/./m.ply")));
    }

    #[test]
    fn two_options_naming_one_file_are_refused_naming_both() {
        let dir = tempfile::tempdir().unwrap();
        let (map, cloud) = (dir.path().join("map.ply"), dir.path().join("cloud.ply"));
        let other = dir.path().join("./map.ply");
        let ok = [
            ("--a", Some(map.as_path())),
            ("--b", Some(&cloud)),
            ("--c", None),
        ];
        refuse_shared(&ok).unwrap();
        let e = refuse_shared(&[("--a", Some(&map)), ("--b", None), ("--c", Some(&other))])
            .unwrap_err()
            .to_string();
        assert!(e.contains("map.ply") && e.contains("--a and --c"), "{e}");
    }

    #[test]
    fn a_named_output_and_its_temporaries_are_removed_and_nothing_else() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        for name in [
            "map.ply",
            "notes.txt",
            ".kiss-odom-tmp-map.ply-abc123",
            ".kiss-odom-tmp-other.ply-abc123",
        ] {
            std::fs::write(d.join(name), "x").unwrap();
        }
        std::fs::create_dir(d.join("cloud.ply")).unwrap(); // not a file: left alone
        remove_stale_file(&d.join("map.ply")).unwrap();
        remove_stale_file(&d.join("cloud.ply")).unwrap();
        let mut left: Vec<String> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        left.sort();
        assert_eq!(
            left,
            [".kiss-odom-tmp-other.ply-abc123", "cloud.ply", "notes.txt"]
        );
        remove_stale_file(&d.join("missing/map.ply")).unwrap();
    }
}
