//! The `ros2msg` schema texts of the messages odocal reads and writes, laid
//! out as rosbag2 and rosbags write them: the main definition, then one
//! `====…\nMSG: pkg/Type` block per dependency in depth-first order.

/// Field lists of every message type involved, as in ROS 2 Humble.
const DEFINITIONS: &[(&str, &str)] = &[
    ("builtin_interfaces/Time", "int32 sec\nuint32 nanosec\n"),
    (
        "std_msgs/Header",
        "builtin_interfaces/Time stamp\nstring frame_id\n",
    ),
    (
        "sensor_msgs/LaserScan",
        "std_msgs/Header header\nfloat32 angle_min\nfloat32 angle_max\nfloat32 angle_increment\n\
         float32 time_increment\nfloat32 scan_time\nfloat32 range_min\nfloat32 range_max\n\
         float32[] ranges\nfloat32[] intensities\n",
    ),
    (
        "sensor_msgs/JointState",
        "std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\n\
         float64[] effort\n",
    ),
    (
        "sensor_msgs/Imu",
        "std_msgs/Header header\ngeometry_msgs/Quaternion orientation\n\
         float64[9] orientation_covariance\ngeometry_msgs/Vector3 angular_velocity\n\
         float64[9] angular_velocity_covariance\ngeometry_msgs/Vector3 linear_acceleration\n\
         float64[9] linear_acceleration_covariance\n",
    ),
    (
        "nav_msgs/Odometry",
        "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/PoseWithCovariance pose\n\
         geometry_msgs/TwistWithCovariance twist\n",
    ),
    (
        "geometry_msgs/PoseWithCovariance",
        "geometry_msgs/Pose pose\nfloat64[36] covariance\n",
    ),
    (
        "geometry_msgs/TwistWithCovariance",
        "geometry_msgs/Twist twist\nfloat64[36] covariance\n",
    ),
    (
        "geometry_msgs/Twist",
        "geometry_msgs/Vector3 linear\ngeometry_msgs/Vector3 angular\n",
    ),
    (
        "geometry_msgs/Pose",
        "geometry_msgs/Point position\ngeometry_msgs/Quaternion orientation\n",
    ),
    ("geometry_msgs/Point", "float64 x\nfloat64 y\nfloat64 z\n"),
    ("geometry_msgs/Vector3", "float64 x\nfloat64 y\nfloat64 z\n"),
    (
        "geometry_msgs/Quaternion",
        "float64 x\nfloat64 y\nfloat64 z\nfloat64 w\n",
    ),
    (
        "geometry_msgs/PoseStamped",
        "std_msgs/Header header\ngeometry_msgs/Pose pose\n",
    ),
    (
        "geometry_msgs/PointStamped",
        "std_msgs/Header header\ngeometry_msgs/Point point\n",
    ),
    (
        "geometry_msgs/TransformStamped",
        "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/Transform transform\n",
    ),
    (
        "geometry_msgs/Transform",
        "geometry_msgs/Vector3 translation\ngeometry_msgs/Quaternion rotation\n",
    ),
    (
        "tf2_msgs/TFMessage",
        "geometry_msgs/TransformStamped[] transforms\n",
    ),
];

/// `pkg/msg/Type` or `pkg/Type` → `pkg/Type`.
pub fn short_name(name: &str) -> String {
    name.replacen("/msg/", "/", 1)
}

fn body(short: &str) -> Option<&'static str> {
    DEFINITIONS
        .iter()
        .find(|(n, _)| *n == short)
        .map(|(_, b)| *b)
}

fn collect_deps(short: &str, out: &mut Vec<&'static str>) {
    let Some(b) = body(short) else { return };
    for line in b.lines() {
        let ty = line.split_whitespace().next().unwrap_or("");
        let ty = ty.split('[').next().unwrap_or(ty);
        if !ty.contains('/') {
            continue;
        }
        if let Some((name, _)) = DEFINITIONS.iter().find(|(n, _)| *n == ty) {
            if !out.contains(name) {
                out.push(name);
                collect_deps(name, out);
            }
        }
    }
}

/// The full `ros2msg` schema text of `name` (`pkg/msg/Type`), or `None` for a
/// type odocal does not know.
pub fn schema_text(name: &str) -> Option<String> {
    let short = short_name(name);
    let mut text = body(&short)?.to_string();
    let mut deps = Vec::new();
    collect_deps(&short, &mut deps);
    for d in deps {
        text.push_str(&"=".repeat(80));
        text.push_str("\nMSG: ");
        text.push_str(d);
        text.push('\n');
        text.push_str(body(d).unwrap_or_default());
    }
    Some(text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn point_stamped_matches_rosbags_layout() {
        let expected = "std_msgs/Header header\ngeometry_msgs/Point point\n".to_string()
            + &"=".repeat(80)
            + "\nMSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n"
            + &"=".repeat(80)
            + "\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n"
            + &"=".repeat(80)
            + "\nMSG: geometry_msgs/Point\nfloat64 x\nfloat64 y\nfloat64 z\n";
        assert_eq!(
            schema_text("geometry_msgs/msg/PointStamped").unwrap(),
            expected
        );
        assert!(schema_text("foo_msgs/msg/Bar").is_none());
    }
}
