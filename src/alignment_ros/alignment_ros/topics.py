"""Topic names and message types of the graph (the README's interface table, in code)."""
from __future__ import annotations

CLOCK = '/clock'
SHIP_ODOM = '/ship/odom'
SHIP_ACCEL = '/ship/accel'
SHIP_FIX = '/ship/fix'
MASTER_ODOM = '/master/odom'
MASTER_FIX = '/master/fix'
AIRCRAFT_IMU = '/aircraft/imu'
LDV_TWIST = '/ldv/twist'
DOPPLER_TWIST = '/doppler/twist'
TRUTH_AIRCRAFT_ODOM = '/truth/aircraft/odom'
TRUTH_MISALIGNMENT = '/truth/misalignment'
TRUTH_IMU_BIAS = '/truth/imu_bias'
TRUTH_MASTER_ERROR = '/truth/master_error'
ALIGN_MISALIGNMENT = '/alignment/misalignment'
ALIGN_ATTITUDE = '/alignment/attitude'
ALIGN_STATE = '/alignment/state'
DIAGNOSTICS = '/diagnostics'

# topic -> ROS type name (package/msg/Type), as stored in bags
TOPIC_TYPES: dict[str, str] = {
    CLOCK: 'rosgraph_msgs/msg/Clock',
    SHIP_ODOM: 'nav_msgs/msg/Odometry',
    SHIP_ACCEL: 'geometry_msgs/msg/AccelStamped',
    SHIP_FIX: 'sensor_msgs/msg/NavSatFix',
    MASTER_ODOM: 'nav_msgs/msg/Odometry',
    MASTER_FIX: 'sensor_msgs/msg/NavSatFix',
    AIRCRAFT_IMU: 'sensor_msgs/msg/Imu',
    LDV_TWIST: 'geometry_msgs/msg/TwistWithCovarianceStamped',
    DOPPLER_TWIST: 'geometry_msgs/msg/TwistWithCovarianceStamped',
    TRUTH_AIRCRAFT_ODOM: 'nav_msgs/msg/Odometry',
    TRUTH_MISALIGNMENT: 'geometry_msgs/msg/Vector3Stamped',
    TRUTH_IMU_BIAS: 'sensor_msgs/msg/Imu',
    TRUTH_MASTER_ERROR: 'geometry_msgs/msg/Vector3Stamped',
    ALIGN_MISALIGNMENT: 'geometry_msgs/msg/Vector3Stamped',
    ALIGN_ATTITUDE: 'geometry_msgs/msg/PoseWithCovarianceStamped',
    ALIGN_STATE: 'std_msgs/msg/Float64MultiArray',
    DIAGNOSTICS: 'diagnostic_msgs/msg/DiagnosticArray',
}

# what a replay feeds into a fresh filter
SENSOR_TOPICS = (CLOCK, MASTER_ODOM, AIRCRAFT_IMU, LDV_TWIST)
FILTER_OUTPUT_TOPICS = (ALIGN_MISALIGNMENT, ALIGN_ATTITUDE, ALIGN_STATE, DIAGNOSTICS)

# frames (REP-103/105): nav frame is local-level ENU; bodies are FLU
FRAME_WORLD = 'world'
FRAME_SHIP = 'ship'
FRAME_AIRCRAFT = 'aircraft'


def msg_class(type_name: str):
    """Import and return the rclpy message class for 'pkg/msg/Type'."""
    import importlib
    pkg, _, name = type_name.split('/')
    return getattr(importlib.import_module(f'{pkg}.msg'), name)
