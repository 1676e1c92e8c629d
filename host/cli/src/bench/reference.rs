//! The reference side of `kiss-odom-dev bench`: kiss-icp 1.3.0 in a long-lived Python process
//! (`driver.py bench --serve`) that holds the same frames in memory and runs on request, so the
//! two implementations can take turns.

use anyhow::{bail, Context, Result};
use kiss_odom_drive::settings::Settings;
use kiss_odom_io::Frame;
use serde::Deserialize;
use std::io::{BufRead, BufReader, BufWriter, Write};
use std::path::Path;
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};

/// One timed run of the reference, as `driver.py bench_run` reports it.
#[derive(Clone, Debug, Deserialize)]
pub struct RefRun {
    /// Seconds in `register_frame`, per frame.
    pub seconds: Vec<f64>,
    /// RSS when the run started (frames loaded).
    pub rss_before_bytes: Option<u64>,
    /// Peak RSS during the run.
    pub peak_rss_bytes: Option<u64>,
    /// Most voxels the local map held after any frame (map-stats runs only).
    pub map_voxels_peak: Option<usize>,
    /// Most points the local map held (map-stats runs only).
    pub map_points_peak: Option<usize>,
    /// numpy -> std::vector conversion of each input frame (map-stats runs only).
    pub binding_seconds: Option<Vec<f64>>,
    /// Row-major 4x4 poses (when asked).
    pub poses: Option<Vec<Vec<f64>>>,
}

/// What the reference process says once its frames are loaded.
#[derive(Clone, Debug, Deserialize)]
pub struct Ready {
    /// Frames loaded.
    pub frames: usize,
    /// kiss-icp, numpy and Python versions.
    pub versions: serde_json::Value,
}

/// A running `driver.py bench --serve`.
pub struct Reference {
    child: Child,
    stdin: Option<BufWriter<ChildStdin>>,
    stdout: BufReader<ChildStdout>,
    /// What it loaded.
    pub ready: Ready,
    _frames_dir: tempfile::TempDir,
}

/// Writes the frames as `driver.py load_frames_dir` reads them: `frames.json`, `points.f64`,
/// `stamps.f64`.
fn write_frames(dir: &Path, frames: &[Frame]) -> Result<()> {
    let mut pts = BufWriter::new(std::fs::File::create(dir.join("points.f64"))?);
    let mut sts = BufWriter::new(std::fs::File::create(dir.join("stamps.f64"))?);
    let mut index = Vec::with_capacity(frames.len());
    for f in frames {
        for p in &f.points {
            for c in p {
                pts.write_all(&c.to_le_bytes())?;
            }
        }
        let stamps = f.stamps.as_deref().unwrap_or(&[]);
        for t in stamps {
            sts.write_all(&t.to_le_bytes())?;
        }
        index.push(serde_json::json!({
            "name": f.name,
            "points": f.points.len(),
            "stamps": stamps.len(),
        }));
    }
    pts.flush()?;
    sts.flush()?;
    let json = serde_json::json!({ "frames": index });
    std::fs::write(dir.join("frames.json"), serde_json::to_string(&json)?)?;
    Ok(())
}

impl Reference {
    /// Starts the reference on `frames` with the settings' range, voxel size and deskewing
    /// and `threads` TBB threads, and waits until it has loaded them.
    pub fn start(
        python: &Path,
        driver: &Path,
        frames: &[Frame],
        settings: &Settings,
        threads: usize,
    ) -> Result<Self> {
        let dir = tempfile::Builder::new()
            .prefix("kiss-odom-bench")
            .tempdir()?;
        write_frames(dir.path(), frames).context("writing frames for the reference")?;
        let mut cmd = Command::new(python);
        cmd.arg(driver)
            .arg("bench")
            .arg("--frames-dir")
            .arg(dir.path())
            .arg("--threads")
            .arg(threads.to_string())
            .arg("--max-range")
            .arg(settings.data.max_range.to_string())
            .arg("--min-range")
            .arg(settings.data.min_range.to_string())
            .arg("--voxel-size")
            .arg(settings.voxel_size().to_string())
            .arg(if settings.data.deskew {
                "--deskew"
            } else {
                "--no-deskew"
            })
            .arg("--serve")
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit());
        let mut child = cmd.spawn().with_context(|| {
            format!(
                "cannot start the reference with {} (give --python, KISS_ODOM_PYTHON or \
                 --no-reference)",
                python.display()
            )
        })?;
        let stdin = BufWriter::new(child.stdin.take().context("reference stdin")?);
        let mut stdout = BufReader::new(child.stdout.take().context("reference stdout")?);
        let ready: Ready = read_line(&mut stdout)?;
        let dir_guard = dir;
        // The frames are in the reference's memory now; the files can go.
        for f in ["points.f64", "stamps.f64"] {
            let _ = std::fs::remove_file(dir_guard.path().join(f));
        }
        Ok(Self {
            child,
            stdin: Some(stdin),
            stdout,
            ready,
            _frames_dir: dir_guard,
        })
    }

    /// One run of a fresh `KissICP` over all frames.
    pub fn run(&mut self, map_stats: bool, poses: bool) -> Result<RefRun> {
        let req = serde_json::json!({ "map_stats": map_stats, "poses": poses });
        let stdin = self.stdin.as_mut().context("reference stdin closed")?;
        writeln!(stdin, "{req}")?;
        stdin.flush()?;
        read_line(&mut self.stdout)
    }
}

impl Drop for Reference {
    fn drop(&mut self) {
        // Closing stdin ends the serve loop; wait so that no zombie is left behind.
        drop(self.stdin.take());
        let _ = self.child.wait();
    }
}

fn read_line<T: for<'de> Deserialize<'de>>(r: &mut impl BufRead) -> Result<T> {
    let mut line = String::new();
    if r.read_line(&mut line)? == 0 {
        bail!("the reference exited early (see its messages above)");
    }
    serde_json::from_str(&line).with_context(|| {
        format!(
            "unexpected reply from the reference: {}",
            line.chars().take(200).collect::<String>()
        )
    })
}
