//! Folder datasets: one file per frame. [`listing`] decides which files are frames and which
//! frame each is, [`generic`] reads the generic layout (frames, `times.txt`, `poses.txt`,
//! per-point times beside them), [`kitti`] the KITTI benchmark layout on top of it; [`bin`],
//! [`ply`] and [`pcd`] read one frame file each into a [`file_cloud::Cloud`].

pub mod bin;
pub mod file_cloud;
pub mod generic;
pub mod kitti;
pub mod listing;
pub mod pcd;
pub mod ply;
