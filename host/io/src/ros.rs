//! ROS containers: ROS 1 bags ([`bag`], over the container of [`bag_records`]) and ROS 2 MCAP
//! files ([`mcap`]). Both carry `sensor_msgs/PointCloud2`: [`message`] parses its bytes in
//! either generation's serialization into a view, [`pointcloud2`] decodes the view's fields
//! into points and per-point times. With `--imu`, their `sensor_msgs/Imu` topic
//! (`imu_topic`, read by [`imu_msg`]) gives the frames' IMU samples.

pub mod bag;
pub mod bag_records;
pub mod imu_msg;
pub(crate) mod imu_topic;
pub mod mcap;
pub mod message;
pub mod pointcloud2;
