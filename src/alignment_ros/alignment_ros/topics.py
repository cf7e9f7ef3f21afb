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
ALIGN_ODOM = '/alignment/odom'      # the slave INS solution after the filter's corrections
DIAGNOSTICS = '/diagnostics'
# air data (the air-data nodes): five-port FADS pressures, the solved air data, and their truth
FADS_PORT_TOPICS = tuple(f'/fads/port_{k}' for k in range(5))
AIR_DATA_VELOCITY = '/air_data/velocity'
AIR_DATA_STATIC_PRESSURE = '/air_data/static_pressure'
AIR_DATA_TOTAL_PRESSURE = '/air_data/total_pressure'
AIR_DATA_WIND = '/air_data/wind'
AIR_DATA_STATE = '/air_data/state'
TRUTH_AIR_DATA_STATE = '/truth/air_data/state'
TRUTH_WIND = '/truth/wind'
AIR_DATA_TOPICS = (*FADS_PORT_TOPICS, AIR_DATA_VELOCITY, AIR_DATA_STATIC_PRESSURE, AIR_DATA_TOTAL_PRESSURE,
                   AIR_DATA_WIND, AIR_DATA_STATE, TRUTH_AIR_DATA_STATE, TRUTH_WIND)
REFERENCE_INS_ODOM = '/reference_ins/odom'   # a reference INS (scenarios without a deck phase)
RECORDER_PROGRESS = '/recorder/progress'   # what the run's recorder has taken (never recorded)

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
    ALIGN_ODOM: 'nav_msgs/msg/Odometry',
    DIAGNOSTICS: 'diagnostic_msgs/msg/DiagnosticArray',
    **{t: 'sensor_msgs/msg/FluidPressure' for t in FADS_PORT_TOPICS},
    AIR_DATA_VELOCITY: 'geometry_msgs/msg/TwistWithCovarianceStamped',
    AIR_DATA_STATIC_PRESSURE: 'sensor_msgs/msg/FluidPressure',
    AIR_DATA_TOTAL_PRESSURE: 'sensor_msgs/msg/FluidPressure',
    AIR_DATA_WIND: 'geometry_msgs/msg/TwistWithCovarianceStamped',
    AIR_DATA_STATE: 'std_msgs/msg/Float64MultiArray',
    TRUTH_AIR_DATA_STATE: 'std_msgs/msg/Float64MultiArray',
    TRUTH_WIND: 'geometry_msgs/msg/Vector3Stamped',
    REFERENCE_INS_ODOM: 'nav_msgs/msg/Odometry',
}

# the streams the ship may pace itself on: the interface's, and the recorder's progress
PACEABLE_TYPES: dict[str, str] = {**TOPIC_TYPES, RECORDER_PROGRESS: 'rosgraph_msgs/msg/Clock'}

# what a replay feeds into a fresh filter
SENSOR_TOPICS = (CLOCK, MASTER_ODOM, AIRCRAFT_IMU, LDV_TWIST)
FILTER_OUTPUT_TOPICS = (ALIGN_MISALIGNMENT, ALIGN_ATTITUDE, ALIGN_STATE, ALIGN_ODOM, DIAGNOSTICS)

# frames (REP-103/105): nav frame is local-level ENU; bodies are FLU
FRAME_WORLD = 'world'
FRAME_SHIP = 'ship'
FRAME_AIRCRAFT = 'aircraft'

# the frames the filter node expects on its inputs: topic -> (header.frame_id, child_frame_id or None)
INPUT_FRAMES: dict[str, tuple[str, str | None]] = {
    AIRCRAFT_IMU: (FRAME_AIRCRAFT, None),
    MASTER_ODOM: (FRAME_WORLD, FRAME_SHIP),
    LDV_TWIST: (FRAME_SHIP, None),
    DOPPLER_TWIST: (FRAME_AIRCRAFT, None),
}


def msg_class(type_name: str):
    """Import and return the rclpy message class for 'pkg/msg/Type'."""
    import importlib
    pkg, _, name = type_name.split('/')
    return getattr(importlib.import_module(f'{pkg}.msg'), name)
