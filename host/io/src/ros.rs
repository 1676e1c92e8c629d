//! ROS recordings: ROS 1 bags ([`bag`], over the container of [`bag_records`]), ROS 2 MCAP
//! files ([`mcap`]) and ROS 2 sqlite3 bags ([`db3`]), each a [`recording::Recording`] whose
//! messages [`frames`] turns into frames the same way: `sensor_msgs/PointCloud2` ([`message`]
//! parses its bytes in either generation's serialization (`serial`) into a view,
//! [`pointcloud2`] decodes the view's fields into points and per-point times), sensor packets
//! ([`packets`] reads the drivers' packet messages, [`packet_frames`] decodes them into sweeps
//! as a pcap of the same packets is) and Livox points ([`livox`]). [`kinds`] names the message
//! types read. With `--imu`, their `sensor_msgs/Imu` topic (`imu_topic`, read by [`imu_msg`])
//! gives the frames' IMU samples.

pub mod bag;
pub mod bag_records;
pub mod db3;
pub mod frames;
pub mod imu_msg;
pub(crate) mod imu_topic;
pub mod kinds;
pub mod livox;
pub mod mcap;
pub mod message;
pub mod packet_frames;
pub mod packets;
pub mod pointcloud2;
pub mod recording;
pub(crate) mod serial;
#[cfg(test)]
pub(crate) mod test_messages;
