//! Node parameters: frames, topics, covariance, what to publish, and the odometry's
//! [`Settings`], read from a ROS 2 parameter file (`node_name: ros__parameters: {...}`).
//!
//! Names follow kiss-icp's ROS 2 wrapper where they map: `base_frame`, `lidar_odom_frame`,
//! `publish_odom_tf`, `invert_odom_tf`, `position_covariance`, `orientation_covariance`, and the
//! odometry's `max_range`, `min_range`, `deskew`, `voxel_size`, `max_points_per_voxel`,
//! `initial_threshold`, `min_motion_th`, `max_num_iterations`, `convergence_criterion`,
//! `max_num_threads`. The grouped form of kiss-icp's `config.yaml` (`data:`, `mapping:`,
//! `adaptive_threshold:`, `registration:`) is the same as `kiss-odom run --config`'s TOML sections
//! and accepted too, with `capacities:` and `runtime:`. Unknown names are errors.

use anyhow::{anyhow, bail, Context, Result};
use kiss_odom_drive::settings::Settings;
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};
use serde::{Deserialize, Serialize};
use serde_yaml_ng::{Mapping, Value};
use std::path::Path;

/// Default node name: the key looked up in a parameter file.
pub(crate) const NODE_NAME: &str = "kiss_odom";

/// Everything about the node that is not the odometry itself.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct NodeParams {
    /// Moving frame; empty means the cloud's own `frame_id` (the pose is the sensor's).
    pub base_frame: String,
    /// Fixed frame the odometry is expressed in (the base frame at the first cloud).
    pub lidar_odom_frame: String,
    /// Publish `lidar_odom_frame -> base` on `/tf`.
    pub publish_odom_tf: bool,
    /// Publish `base -> lidar_odom_frame` instead (for trees where base already has a parent).
    pub invert_odom_tf: bool,
    /// Variance of x, y and z in the pose covariance (m^2).
    pub position_covariance: f64,
    /// Variance of the three rotations in the pose covariance (rad^2).
    pub orientation_covariance: f64,
    /// Pose of the LiDAR in the base frame, `[x, y, z, qx, qy, qz, qw]`; none is the identity.
    pub base_to_lidar: Option<[f64; 7]>,
    /// Cloud topic.
    pub points_topic: String,
    /// Odometry topic.
    pub odom_topic: String,
    /// Publish the local map.
    pub publish_local_map: bool,
    /// Local map topic.
    pub local_map_topic: String,
    /// Seconds between local map messages (at most one per registered cloud).
    pub local_map_period: f64,
    /// Scan period (s) for the twist when consecutive stamps do not give one.
    pub scan_period: f64,
    /// A prior map (`kiss-odom map build`) to localize each registered cloud in; empty: none.
    /// Its frame is the settings' `output.map_frame`.
    pub map_file: String,
    /// The sensor's pose in the map frame at the first cloud, `X,Y,Z,ROLL,PITCH,YAW` (metres,
    /// degrees), as `run --initial-pose`; needed with `map_file`.
    pub initial_pose: String,
    /// Topic of the base's pose in the map frame (`nav_msgs/Odometry`), with `map_file`.
    pub map_pose_topic: String,
}

impl Default for NodeParams {
    fn default() -> Self {
        Self {
            base_frame: String::new(),
            lidar_odom_frame: "odom_lidar".into(),
            publish_odom_tf: true,
            invert_odom_tf: false,
            position_covariance: 0.1,
            orientation_covariance: 0.1,
            base_to_lidar: None,
            points_topic: "/points".into(),
            odom_topic: "/kiss/odometry".into(),
            publish_local_map: false,
            local_map_topic: "/kiss/local_map".into(),
            local_map_period: 1.0,
            scan_period: 0.1,
            map_file: String::new(),
            initial_pose: String::new(),
            map_pose_topic: "/kiss/map_pose".into(),
        }
    }
}

impl NodeParams {
    /// The base-to-LiDAR transform, checked.
    pub fn extrinsic(&self) -> Result<Isometry3<f64>> {
        let Some([x, y, z, qx, qy, qz, qw]) = self.base_to_lidar else {
            return Ok(Isometry3::identity());
        };
        let q = Quaternion::new(qw, qx, qy, qz);
        if !q
            .coords
            .iter()
            .chain([x, y, z].iter())
            .all(|v| v.is_finite())
            || q.norm() < 1e-9
        {
            bail!("base_to_lidar: needs finite values and a non-zero quaternion");
        }
        Ok(Isometry3::from_parts(
            Translation3::new(x, y, z),
            UnitQuaternion::from_quaternion(q),
        ))
    }

    /// Refuses values no node can use.
    pub(crate) fn validate(&self) -> Result<()> {
        let finite_nonneg = |v: f64| v.is_finite() && v >= 0.0;
        if !finite_nonneg(self.position_covariance) || !finite_nonneg(self.orientation_covariance) {
            bail!("position_covariance and orientation_covariance must be finite and >= 0");
        }
        if !(self.scan_period.is_finite() && self.scan_period > 0.0) {
            bail!("scan_period must be positive");
        }
        if !finite_nonneg(self.local_map_period) {
            bail!("local_map_period must be finite and >= 0");
        }
        if self.lidar_odom_frame.is_empty() {
            bail!("lidar_odom_frame must not be empty");
        }
        if !self.map_file.is_empty() && self.initial_pose.is_empty() {
            bail!(
                "map_file needs initial_pose X,Y,Z,ROLL,PITCH,YAW: the start is not searched \
                 for over the whole map"
            );
        }
        self.extrinsic().map(|_| ())
    }
}

/// kiss-icp wrapper names of odometry parameters and where they live in [`Settings`].
const FLAT: [(&str, &str, &str); 10] = [
    ("max_range", "data", "max_range"),
    ("min_range", "data", "min_range"),
    ("deskew", "data", "deskew"),
    ("voxel_size", "mapping", "voxel_size"),
    ("max_points_per_voxel", "mapping", "max_points_per_voxel"),
    (
        "initial_threshold",
        "adaptive_threshold",
        "initial_threshold",
    ),
    ("min_motion_th", "adaptive_threshold", "min_motion_th"),
    ("max_num_iterations", "registration", "max_num_iterations"),
    (
        "convergence_criterion",
        "registration",
        "convergence_criterion",
    ),
    ("max_num_threads", "runtime", "threads"),
];

/// Sections of [`Settings`].
const SECTIONS: [&str; 6] = [
    "data",
    "mapping",
    "adaptive_threshold",
    "registration",
    "capacities",
    "runtime",
];

/// Applies the parameters for `node` in the YAML text `text` over `settings` and `params`.
/// Entries under `/**` (every node) apply first, then those under `node` or `/node`.
pub(crate) fn apply_yaml(
    text: &str,
    node: &str,
    settings: &mut Settings,
    params: &mut NodeParams,
) -> Result<()> {
    let doc: Value = serde_yaml_ng::from_str(text)?;
    let Value::Mapping(top) = doc else {
        bail!("expected `{node}: ros__parameters: {{...}}` at the top");
    };
    let slash = format!("/{node}");
    let mut found = false;
    for key in ["/**", node, slash.as_str()] {
        let Some(entry) = top.get(key) else {
            continue;
        };
        found = true;
        let ros = entry
            .get("ros__parameters")
            .ok_or_else(|| anyhow!("`{key}` has no `ros__parameters`"))?;
        let Value::Mapping(values) = ros else {
            bail!("`{key}.ros__parameters` is not a mapping");
        };
        apply(values, settings, params).with_context(|| format!("`{key}.ros__parameters`"))?;
    }
    if !found {
        let keys: Vec<String> = top
            .keys()
            .map(|k| {
                serde_yaml_ng::to_string(k)
                    .unwrap_or_default()
                    .trim()
                    .to_string()
            })
            .collect();
        bail!(
            "no parameters for node `{node}` (found: {}); name the node with --node-name",
            keys.join(", ")
        );
    }
    Ok(())
}

/// Reads a parameter file; see [`apply_yaml`].
pub(crate) fn load_yaml(
    path: &Path,
    node: &str,
    settings: &mut Settings,
    params: &mut NodeParams,
) -> Result<()> {
    let text = std::fs::read_to_string(path).with_context(|| format!("{}", path.display()))?;
    apply_yaml(&text, node, settings, params).with_context(|| format!("{}", path.display()))
}

fn apply(values: &Mapping, settings: &mut Settings, params: &mut NodeParams) -> Result<()> {
    let mut s = serde_yaml_ng::to_value(&*settings)?;
    let mut p = serde_yaml_ng::to_value(&*params)?;
    for (k, v) in values {
        let name = k
            .as_str()
            .ok_or_else(|| anyhow!("parameter names are strings"))?;
        if let Some((_, section, field)) = FLAT.iter().find(|(n, _, _)| *n == name) {
            merge(
                &mut s,
                &Value::Mapping(Mapping::from_iter([(
                    Value::from(*section),
                    Value::Mapping(Mapping::from_iter([(Value::from(*field), v.clone())])),
                )])),
            );
        } else if SECTIONS.contains(&name) {
            merge(
                &mut s,
                &Value::Mapping(Mapping::from_iter([(k.clone(), v.clone())])),
            );
        } else if p.get(name).is_some() {
            merge(
                &mut p,
                &Value::Mapping(Mapping::from_iter([(k.clone(), v.clone())])),
            );
        } else {
            let node: Vec<&str> = p
                .as_mapping()
                .map(|m| m.keys().filter_map(Value::as_str).collect())
                .unwrap_or_default();
            let odometry: Vec<&str> = FLAT.iter().map(|(n, _, _)| *n).collect();
            bail!(
                "unknown parameter `{name}` (node: {}; odometry: {}; groups: {})",
                node.join(", "),
                odometry.join(", "),
                SECTIONS.join(", ")
            );
        }
    }
    *settings = serde_yaml_ng::from_value(s)?;
    *params = serde_yaml_ng::from_value(p)?;
    Ok(())
}

/// Deep merge: mappings key by key, anything else replaced.
fn merge(into: &mut Value, from: &Value) {
    match (into, from) {
        (Value::Mapping(a), Value::Mapping(b)) => {
            for (k, v) in b {
                match a.get_mut(k) {
                    Some(slot) => merge(slot, v),
                    None => {
                        a.insert(k.clone(), v.clone());
                    }
                }
            }
        }
        (slot, v) => *slot = v.clone(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kiss_icp_names_flat_and_grouped_and_node_names_apply() {
        let yaml = "
/**:
  ros__parameters:
    position_covariance: 0.5
kiss_odom:
  ros__parameters:
    base_frame: base_link
    lidar_odom_frame: odom
    publish_odom_tf: false
    max_range: 60
    deskew: false
    max_num_threads: 1
    mapping:
      max_points_per_voxel: 7
    base_to_lidar: [0.1, 0, 1.5, 0, 0, 0, 1]
other_node:
  ros__parameters:
    max_range: 5.0
";
        let mut s = Settings::default();
        s.mapping.alpha = 0.25; // from an earlier layer; a partial section must keep it
        let mut p = NodeParams::default();
        apply_yaml(yaml, NODE_NAME, &mut s, &mut p).unwrap();
        assert_eq!(s.data.max_range, 60.0);
        assert!(!s.data.deskew);
        assert_eq!(s.runtime.threads, 1);
        assert_eq!(s.mapping.max_points_per_voxel, 7);
        assert_eq!(s.mapping.alpha, 0.25);
        assert_eq!(s.voxel_size(), 0.6);
        assert_eq!(p.base_frame, "base_link");
        assert_eq!(p.lidar_odom_frame, "odom");
        assert!(!p.publish_odom_tf);
        assert_eq!(p.position_covariance, 0.5);
        assert_eq!(p.orientation_covariance, 0.1);
        assert_eq!(p.extrinsic().unwrap().translation.vector.z, 1.5);
        p.validate().unwrap();
    }

    #[test]
    fn typos_wrong_shapes_and_missing_nodes_are_errors() {
        let err = |yaml: &str| {
            let mut s = Settings::default();
            let mut p = NodeParams::default();
            format!(
                "{:#}",
                apply_yaml(yaml, NODE_NAME, &mut s, &mut p).unwrap_err()
            )
        };
        let e = err("kiss_odom:\n  ros__parameters:\n    max_rnage: 3.0\n");
        assert!(
            e.contains("unknown parameter `max_rnage`") && e.contains("max_range"),
            "{e}"
        );
        let e = err("kiss_odom:\n  ros__parameters:\n    data:\n      max_rnage: 3.0\n");
        assert!(e.contains("max_rnage"), "{e}");
        let e = err("kiss_icp_node:\n  ros__parameters:\n    max_range: 3.0\n");
        assert!(
            e.contains("kiss_icp_node") && e.contains("--node-name"),
            "{e}"
        );
        let e = err("kiss_odom:\n  max_range: 3.0\n");
        assert!(e.contains("ros__parameters"), "{e}");
        let e = err("kiss_odom:\n  ros__parameters:\n    max_range: far\n");
        assert!(e.contains("max_range") || e.contains("invalid"), "{e}");
        let mut p = NodeParams {
            base_to_lidar: Some([0.0; 7]),
            ..NodeParams::default()
        };
        assert!(p.validate().is_err());
        p.base_to_lidar = None;
        p.scan_period = 0.0;
        assert!(p.validate().is_err());
    }
}
