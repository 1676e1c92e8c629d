//! The workspace's end-to-end tests in one binary: the command run in process and as a
//! process, every reader, the sensor path, ROS 2 interop, the bare-metal builds and the
//! cross-checks against the reference kiss-icp and the sensors' own decoders. One module per
//! subject; `interrupted_bag`, `mcap_memory` and `long_run` are binaries of their own because
//! they need the whole process (a raised stop flag, the process's peak memory).

mod accurate;
mod bags;
mod capture_kit;
mod cli_bad_input;
mod common;
mod configuration_doc;
mod crosscheck;
mod dataset_containers;
mod dataset_folders;
mod dataset_process;
mod db3_nebula;
mod degeneracy;
mod embedded;
mod golden;
mod imu_check;
mod imu_pcaps;
mod imu_prior;
mod imu_readers;
mod layouts;
mod listen_poses;
mod live;
mod livox_bags;
mod localize;
mod map_build;
mod metrics;
mod nebula_reading;
mod packet_bags;
mod readers;
mod reliability;
mod ros2;
mod ros2_bad_input;
mod ros2_common;
mod run_loop;
mod sensor_dump;
mod sensor_points;
mod sensors;
mod sensors_bad_input;
mod sensors_capture;
mod sensors_hesai;
mod sensors_hesai128;
mod sensors_hesai_at128;
mod sensors_hesai_fixed_bad;
mod sensors_hesai_nebula;
mod sensors_imu;
mod sensors_livox;
mod sensors_memory;
mod sensors_nebula_velodyne;
mod sensors_report;
mod sensors_run;
mod sensors_simulated;
mod signals;
mod simulate;
mod threads;
mod user_files;
mod view;
mod work_budget;
