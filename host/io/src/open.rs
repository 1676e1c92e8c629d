//! Opening a dataset path: which reader a `--format` (or `auto`) picks.
//!
//! `auto` picks a public dataset's layout by its folders ([`layouts::detect`], refusing a
//! folder with the structure of two), KITTI only for the benchmark layout ([`kitti::detect`]),
//! because KITTI scans get a correction no other data should get, and refuses a KITTI-shaped
//! folder it cannot read as KITTI; bag, MCAP and pcap/pcapng files are recognised by
//! extension; anything else is the generic layout with the one frame format its files show
//! (several is refused). An
//! explicit format always wins. An `imu.csv` given with `--imu FILE` goes to the frames of any
//! format by time, in place of the IMU samples the recording carries.

use crate::dataset::{Dataset, Format, FrameSource, ImuInput, Item, OpenOptions, Trailer};
use crate::folders::{generic, kitti};
use crate::imu::{self, attach::WithImu};
use crate::layouts;
use anyhow::{bail, Result};
use std::path::Path;

/// The format `auto` resolves to for `path`, without reading any frame.
pub fn detect(path: &Path) -> Result<Format> {
    if !path.exists() {
        bail!("{}: no such file or folder", path.display());
    }
    if path.is_file() {
        let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
        return match ext.to_ascii_lowercase().as_str() {
            "bag" => Ok(Format::Bag),
            "mcap" => Ok(Format::Mcap),
            "pcap" | "pcapng" => Ok(Format::Pcap),
            _ => bail!(
                "{}: cannot tell the format of this file (give a folder, a .bag, an .mcap or \
                 a .pcap)",
                path.display()
            ),
        };
    }
    if let Some(format) = layouts::detect(path)? {
        return Ok(format);
    }
    if kitti::detect(path)? {
        return Ok(Format::Kitti);
    }
    match generic::detect_format(path)? {
        Some(format) => Ok(format),
        None => bail!(
            "{}: no frames (*.bin, *.ply or *.pcd) found",
            generic::frames_dir(path).display()
        ),
    }
}

/// Opens `path` as `format` (`Auto` picks one, see the module doc).
pub fn open(path: &Path, format: Format, opts: &OpenOptions) -> Result<Dataset> {
    let format = match format {
        Format::Auto => detect(path)?,
        explicit => explicit,
    };
    let mut dataset = match format {
        Format::Kitti => kitti::open(path, opts)?,
        Format::Bin | Format::Ply | Format::Pcd => generic::open(path, Some(format), opts)?,
        Format::Bag => crate::ros::bag::open(path, opts)?,
        Format::Mcap => crate::ros::mcap::open(path, opts)?,
        Format::Pcap => crate::capture::frames::open(path, opts)?,
        Format::Mulran
        | Format::Nclt
        | Format::Ncd
        | Format::Helipr
        | Format::Boreas
        | Format::Nuscenes
        | Format::Apollo
        | Format::KittiRaw => layouts::open(path, format, opts)?,
        Format::Auto => bail!("{}: format detection failed", path.display()),
    };
    match &opts.imu {
        ImuInput::File(file) => {
            let samples = imu::read_csv(file)?;
            let times = dataset.info.frame_times.clone();
            dataset.frames = Box::new(WithImu::new(dataset.frames, samples).with_times(times));
        }
        ImuInput::Topic(topic) if !matches!(format, Format::Bag | Format::Mcap) => bail!(
            "--imu {topic}: no such file, and {} is not a bag or MCAP file to have such a topic",
            path.display()
        ),
        _ => {}
    }
    dataset.frames = Box::new(TimeOrder {
        inner: dataset.frames,
        last: None,
    });
    Ok(dataset)
}

/// Wraps every source: a frame whose time is earlier than the previous frame's gets a warning,
/// so that times going backwards (a recording out of order, a wrong `times.txt`) are never
/// silent.
struct TimeOrder {
    inner: Box<dyn FrameSource>,
    last: Option<(f64, String)>,
}

impl FrameSource for TimeOrder {
    fn len_hint(&self) -> Option<usize> {
        self.inner.len_hint()
    }

    fn next_item(&mut self) -> Result<Option<Item>> {
        let mut item = self.inner.next_item()?;
        // Skipped frames are left out: their time may come from another clock (a bag's
        // receive time instead of the header stamp).
        if let Some(Item::Frame(f)) = &mut item {
            if let (Some(t), Some((last, last_name))) = (f.time, &self.last) {
                if t < *last {
                    f.warnings.push(format!(
                        "{}: time {t} s is earlier than the previous frame's {last} s ({last_name}): \
                         the times go backwards here",
                        f.name
                    ));
                }
            }
            if let Some(t) = f.time {
                self.last = Some((t, f.name.clone()));
            }
        }
        Ok(item)
    }

    fn seek(&mut self, index: usize) -> bool {
        self.last = None;
        self.inner.seek(index)
    }

    fn trailer(&mut self) -> Trailer {
        self.inner.trailer()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn auto_recognises_containers_by_extension_and_kitti_by_calib() {
        let dir = tempfile::tempdir().unwrap();
        let bag = dir.path().join("run.BAG");
        let mcap = dir.path().join("run.mcap");
        std::fs::write(&bag, []).unwrap();
        std::fs::write(&mcap, []).unwrap();
        for name in ["rec.pcap", "rec.PCAPNG"] {
            std::fs::write(dir.path().join(name), []).unwrap();
            assert_eq!(detect(&dir.path().join(name)).unwrap(), Format::Pcap);
        }
        assert_eq!(detect(&bag).unwrap(), Format::Bag);
        assert_eq!(detect(&mcap).unwrap(), Format::Mcap);
        assert!(detect(&dir.path().join("missing")).is_err());

        let seq = dir.path().join("seq");
        std::fs::create_dir_all(seq.join("velodyne")).unwrap();
        std::fs::write(seq.join("velodyne/000000.bin"), [0u8; 16]).unwrap();
        assert_eq!(detect(&seq).unwrap(), Format::Bin);
        std::fs::write(seq.join("calib.txt"), "P0: 1 0 0 0 0 1 0 0 0 0 1 0\n").unwrap();
        let e = format!("{:#}", detect(&seq).unwrap_err());
        assert!(e.contains("no Tr") && e.contains("--format kitti"), "{e}");
        std::fs::write(seq.join("calib.txt"), "Tr: 1 0 0 0 0 1 0 0 0 0 1 0\n").unwrap();
        assert_eq!(detect(&seq).unwrap(), Format::Kitti);
        // Per-point timestamps mark a generic layout even next to a calib file.
        std::fs::create_dir(seq.join("timestamps")).unwrap();
        assert_eq!(detect(&seq).unwrap(), Format::Bin);
    }
}
