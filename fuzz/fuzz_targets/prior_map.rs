//! The prior map file (`kiss_odom_core::prior_map`): any bytes are refused with a reason or
//! opened; every tile of an opened map reads as finite points inside its square, each found by
//! its voxel's search, or is refused alone; a localizer on it answers a frame without panicking.
#![no_main]

use kiss_odom_core::localize::{Localizer, PriorCapacities, Settings};
use kiss_odom_core::prior_map::{TileMap, TileKey};
use kiss_odom_core::{Config, Pose, Sequential};
use libfuzzer_sys::fuzz_target;

const CAPS: PriorCapacities = PriorCapacities { source_points: 64 };

fuzz_target!(|data: &[u8]| {
    let Ok(map) = TileMap::open(data) else { return };
    let h = *map.header();
    for t in 0..map.len() {
        let (key, _) = map.entry(t).expect("an entry below len");
        assert_eq!(map.find(key), Some(t), "the index finds its own entries");
        if let Ok(tile) = map.tile(t) {
            for (k, p) in tile.points().enumerate() {
                assert!(p.iter().all(|v| v.is_finite()));
                let at = TileKey::of(p[0], p[1], h.tile_size);
                let near = (at.i - key.i).abs() <= 1 && (at.j - key.j).abs() <= 1;
                assert!(near, "a point of tile {key:?} lies in {at:?}");
                let run = tile.voxel(&tile.voxel_at(k));
                assert!(run.contains(&k), "point {k} of tile {key:?} not in its voxel's run");
                assert!(run.len() <= h.points_per_voxel as usize);
            }
        }
    }
    let mut config = Config::new(h.voxel_size * 100.0);
    config.voxel_size = h.voxel_size;
    if config.validate().is_err() {
        return;
    }
    let mut words = vec![0u64; Localizer::<f64, &mut [u64]>::words(&CAPS)];
    let settings = Settings::for_config(&config);
    let Ok(mut loc) = Localizer::<f64, _>::new(
        map,
        h.frame_name(),
        &config,
        settings,
        CAPS,
        &mut words[..],
        Pose::identity(),
    ) else {
        return;
    };
    let source = [[1.0, 2.0, 0.5], [-3.0, 4.0, 1.0], [5.0, -1.0, -1.5]];
    let r = loc.locate(&Sequential, &source, &Pose::identity(), 0.5);
    assert!(r.pose.translation.vector.iter().all(|v| v.is_finite()));
});
