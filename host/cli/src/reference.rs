//! What the developer tool's commands (`crosscheck`, `bench`) share: where the reference
//! kiss-icp 1.3.0 is, and the rule that only the settings it takes may differ from their
//! defaults.

use anyhow::{bail, Result};
use kiss_odom_drive::settings::Settings;
use std::path::{Path, PathBuf};

/// `--config` of the commands that compare with the reference.
pub const CONFIG_HELP_WITH_REFERENCE: &str = "Settings file: TOML, as `run` writes to \
    `config.toml`, or kiss-icp's YAML (a .yaml or .yml name); flags override it. The reference \
    gets only the range, voxel size and deskewing, so every other pipeline setting must keep \
    its default";

/// `--threads` of the commands that compare with the reference.
pub const THREADS_HELP_WITH_REFERENCE: &str = "Threads for both implementations (the \
    reference's TBB threads), 0 = all cores, at most the machine's cores [default: 1: the \
    reference is nondeterministic with more, and one thread compares like with like]";

/// Where the reference kiss-icp 1.3.0 is.
#[derive(Debug, Clone, clap::Args)]
pub struct ReferenceArgs {
    /// Python with kiss-icp 1.3.0 [default: $KISS_ODOM_PYTHON, else python3].
    #[arg(long)]
    pub python: Option<PathBuf>,
    /// The reference driver [default: $KISS_ODOM_DRIVER, else tests/reference/driver.py above
    /// the working directory or the executable, else in this source tree].
    #[arg(long)]
    pub driver: Option<PathBuf>,
}

/// Refuses settings the reference would not share: it takes only the range, voxel size and
/// deskewing, so any other pipeline setting away from its default would be compared against a
/// reference that did not use it.
pub fn check_reference_compatible(s: &Settings) -> Result<()> {
    let changed = s.changed_beyond_reference();
    if !changed.is_empty() {
        bail!(
            "the reference takes only max_range, min_range, voxel_size and deskew; these \
             settings differ from their defaults: {}",
            changed.join(", ")
        );
    }
    Ok(())
}

impl ReferenceArgs {
    /// The interpreter: `--python`, else `KISS_ODOM_PYTHON`, else `python3`.
    pub fn python(&self) -> PathBuf {
        self.python
            .clone()
            .or_else(|| std::env::var_os("KISS_ODOM_PYTHON").map(PathBuf::from))
            .unwrap_or_else(|| PathBuf::from("python3"))
    }

    /// The driver script: `--driver`, else `KISS_ODOM_DRIVER`, else
    /// `tests/reference/driver.py` in the first ancestor of the working directory or of the
    /// executable that has it, else in the source tree this binary was built from.
    pub fn driver(&self) -> Result<PathBuf> {
        let given = self
            .driver
            .clone()
            .or_else(|| std::env::var_os("KISS_ODOM_DRIVER").map(PathBuf::from));
        if let Some(p) = given {
            if !p.is_file() {
                bail!(
                    "{}: no such driver script (give --driver, or --no-reference to bench)",
                    p.display()
                );
            }
            return Ok(p);
        }
        let mut bases: Vec<PathBuf> = Vec::new();
        if let Ok(cwd) = std::env::current_dir() {
            bases.extend(cwd.ancestors().map(Path::to_path_buf));
        }
        if let Ok(exe) = std::env::current_exe() {
            bases.extend(exe.ancestors().skip(1).map(Path::to_path_buf));
        }
        bases.push(Path::new(env!("CARGO_MANIFEST_DIR")).join("../.."));
        bases
            .iter()
            .map(|b| b.join(DRIVER_IN_REPO))
            .find(|p| p.is_file())
            .ok_or_else(|| {
                anyhow::anyhow!(
                    "cannot find {DRIVER_IN_REPO} above the working directory or the \
                     executable; give --driver"
                )
            })
    }
}

/// The reference driver script relative to the repository root.
pub const DRIVER_IN_REPO: &str = "tests/reference/driver.py";

#[cfg(test)]
mod tests {
    use super::*;

    fn resolve(argv: &[&str]) -> Result<Settings> {
        crate::args::resolve(argv, None)
    }

    #[test]
    fn only_what_the_reference_takes_may_change_for_it() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("c.toml");
        std::fs::write(&file, "[registration]\nkernel_scale = 0.5\n").unwrap();
        let s = resolve(&["--max-range", "50", "--set", "runtime.scalar=f32"]).unwrap();
        check_reference_compatible(&s).unwrap();
        let s = resolve(&["--config", file.to_str().unwrap()]).unwrap();
        let e = check_reference_compatible(&s).unwrap_err().to_string();
        assert!(e.contains("registration.kernel_scale"), "{e}");
    }
}
