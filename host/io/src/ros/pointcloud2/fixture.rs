//! Clouds built by tests, with values known independently of `decode`.

use super::*;

/// Every field of a PointCloud2 as a test writes it.
#[derive(Clone, Debug)]
pub struct RawCloud {
    pub sec: u32,
    pub nsec: u32,
    pub frame_id: String,
    pub height: u32,
    pub width: u32,
    pub fields: Vec<PointField>,
    pub is_bigendian: bool,
    pub point_step: u32,
    pub row_step: u32,
    pub data: Vec<u8>,
    pub is_dense: bool,
}

/// Frame `k`: `n` points x = k + i/8, y = -i/4, z = 0.5 and `t` = i/16 (all exact in
/// f32), little-endian, 16 bytes per point; stamp k + 0.25 s after 1_700_000_000.
pub fn xyzt(k: u32, n: usize) -> RawCloud {
    let mut data = Vec::with_capacity(16 * n);
    for i in 0..n {
        let i = i as f32;
        for v in [k as f32 + i / 8.0, -i / 4.0, 0.5, i / 16.0] {
            data.extend_from_slice(&v.to_le_bytes());
        }
    }
    let f = |name: &str, offset| PointField {
        name: name.into(),
        offset,
        datatype: FLOAT32,
        count: 1,
    };
    RawCloud {
        sec: 1_700_000_000 + k,
        nsec: 250_000_000,
        frame_id: "os_sensor".into(),
        height: 1,
        width: n as u32,
        fields: vec![f("x", 0), f("y", 4), f("z", 8), f("t", 12)],
        is_bigendian: false,
        point_step: 16,
        row_step: 16 * n as u32,
        data,
        is_dense: true,
    }
}

/// The points [`xyzt`] wrote for frame `k`.
pub fn xyzt_points(k: u32, n: usize) -> Vec<[f64; 3]> {
    (0..n)
        .map(|i| [f64::from(k) + i as f64 / 8.0, -(i as f64) / 4.0, 0.5])
        .collect()
}

/// The times [`xyzt`] wrote.
pub fn xyzt_times(n: usize) -> Vec<f64> {
    (0..n).map(|i| i as f64 / 16.0).collect()
}

/// Writes `bytes` to `name` in `dir`.
pub fn save(dir: &tempfile::TempDir, name: &str, bytes: &[u8]) -> std::path::PathBuf {
    let p = dir.path().join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

/// Reads a container's stream to its end: the items, and the error that ended it, if any
/// (after which the stream must stay ended).
pub fn drain(
    src: &mut dyn crate::dataset::FrameSource,
) -> (Vec<crate::dataset::Item>, Option<String>) {
    let mut items = Vec::new();
    loop {
        match src.next_item() {
            Ok(Some(item)) => items.push(item),
            Ok(None) => return (items, None),
            Err(e) => {
                assert!(
                    src.next_item().unwrap().is_none(),
                    "stream continues after Err"
                );
                return (items, Some(format!("{e:#}")));
            }
        }
    }
}

/// The frame an item holds; a skip fails the test.
pub fn frame(item: &crate::dataset::Item) -> &crate::dataset::Frame {
    match item {
        crate::dataset::Item::Frame(f) => f,
        crate::dataset::Item::Skipped { reason, .. } => panic!("unexpected skip: {reason}"),
    }
}

/// Checks that `f` is frame `k` of an [`xyzt`] stream of 6 points on `/points`, read at
/// stream position `index`.
pub fn assert_frame_k(f: &crate::dataset::Frame, index: usize, k: u32) {
    assert_eq!(f.index, index);
    assert_eq!(f.points, xyzt_points(k, 6), "points of frame {k}");
    assert_eq!(f.stamps.as_deref(), Some(&xyzt_times(6)[..]));
    assert_eq!(f.time, Some(f64::from(1_700_000_000 + k) + 0.25));
    assert!(
        f.name
            .ends_with(&format!(":/points@{}.250000000", 1_700_000_000 + k)),
        "{}",
        f.name
    );
}
