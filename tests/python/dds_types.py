# SPDX-License-Identifier: Apache-2.0
"""Python mirrors of the DDS types urtwin uses (net/dds/idl/), for the Python `cyclonedds`
package: same type names (ROS 2 mangling), member names, kinds and @final extensibility, so
that Cyclone's XTypes matching accepts them. Written from the .msg definitions; the bytes are
also checked with an independent ROS 2 CDR decoder (mcap-ros2-support)."""
from dataclasses import dataclass, field

import cyclonedds.idl.annotations as annotate
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import (array, bounded_str, float32, float64, int8, int32, sequence, uint8,
                                  uint32, uint64)


@dataclass
@annotate.final
class Time_(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: int32 = 0
    nanosec: uint32 = 0


@dataclass
@annotate.final
class Duration_(IdlStruct, typename="builtin_interfaces::msg::dds_::Duration_"):
    sec: int32 = 0
    nanosec: uint32 = 0


@dataclass
@annotate.final
class Header_(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp: Time_ = field(default_factory=Time_)
    frame_id: str = ""


@dataclass
@annotate.final
class Float64_(IdlStruct, typename="std_msgs::msg::dds_::Float64_"):
    data: float64 = 0.0


@dataclass
@annotate.final
class Bool_(IdlStruct, typename="std_msgs::msg::dds_::Bool_"):
    data: bool = False


@dataclass
@annotate.final
class MultiArrayDimension_(IdlStruct, typename="std_msgs::msg::dds_::MultiArrayDimension_"):
    label: str = ""
    size: uint32 = 0
    stride: uint32 = 0


@dataclass
@annotate.final
class MultiArrayLayout_(IdlStruct, typename="std_msgs::msg::dds_::MultiArrayLayout_"):
    dim: sequence[MultiArrayDimension_] = field(default_factory=list)
    data_offset: uint32 = 0


@dataclass
@annotate.final
class Float64MultiArray_(IdlStruct, typename="std_msgs::msg::dds_::Float64MultiArray_"):
    layout: MultiArrayLayout_ = field(default_factory=MultiArrayLayout_)
    data: sequence[float64] = field(default_factory=list)


@dataclass
@annotate.final
class JointState_(IdlStruct, typename="sensor_msgs::msg::dds_::JointState_"):
    header: Header_ = field(default_factory=Header_)
    name: sequence[str] = field(default_factory=list)
    position: sequence[float64] = field(default_factory=list)
    velocity: sequence[float64] = field(default_factory=list)
    effort: sequence[float64] = field(default_factory=list)


@dataclass
@annotate.final
class Vector3_(IdlStruct, typename="geometry_msgs::msg::dds_::Vector3_"):
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0


@dataclass
@annotate.final
class Point_(IdlStruct, typename="geometry_msgs::msg::dds_::Point_"):
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0


@dataclass
@annotate.final
class Quaternion_(IdlStruct, typename="geometry_msgs::msg::dds_::Quaternion_"):
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0
    w: float64 = 1.0


@dataclass
@annotate.final
class Wrench_(IdlStruct, typename="geometry_msgs::msg::dds_::Wrench_"):
    force: Vector3_ = field(default_factory=Vector3_)
    torque: Vector3_ = field(default_factory=Vector3_)


@dataclass
@annotate.final
class WrenchStamped_(IdlStruct, typename="geometry_msgs::msg::dds_::WrenchStamped_"):
    header: Header_ = field(default_factory=Header_)
    wrench: Wrench_ = field(default_factory=Wrench_)


@dataclass
@annotate.final
class Pose_(IdlStruct, typename="geometry_msgs::msg::dds_::Pose_"):
    position: Point_ = field(default_factory=Point_)
    orientation: Quaternion_ = field(default_factory=Quaternion_)


@dataclass
@annotate.final
class PoseStamped_(IdlStruct, typename="geometry_msgs::msg::dds_::PoseStamped_"):
    header: Header_ = field(default_factory=Header_)
    pose: Pose_ = field(default_factory=Pose_)


@dataclass
@annotate.final
class JointTrajectoryPoint_(IdlStruct, typename="trajectory_msgs::msg::dds_::JointTrajectoryPoint_"):
    positions: sequence[float64] = field(default_factory=list)
    velocities: sequence[float64] = field(default_factory=list)
    accelerations: sequence[float64] = field(default_factory=list)
    effort: sequence[float64] = field(default_factory=list)
    time_from_start: Duration_ = field(default_factory=Duration_)


@dataclass
@annotate.final
class JointTrajectory_(IdlStruct, typename="trajectory_msgs::msg::dds_::JointTrajectory_"):
    header: Header_ = field(default_factory=Header_)
    joint_names: sequence[str] = field(default_factory=list)
    points: sequence[JointTrajectoryPoint_] = field(default_factory=list)


@dataclass
@annotate.final
class Digital_(IdlStruct, typename="ur_msgs::msg::dds_::Digital_"):
    pin: uint8 = 0
    state: bool = False


@dataclass
@annotate.final
class Analog_(IdlStruct, typename="ur_msgs::msg::dds_::Analog_"):
    pin: uint8 = 0
    domain: uint8 = 0
    state: float32 = 0.0


@dataclass
@annotate.final
class IOStates_(IdlStruct, typename="ur_msgs::msg::dds_::IOStates_"):
    digital_in_states: sequence[Digital_] = field(default_factory=list)
    digital_out_states: sequence[Digital_] = field(default_factory=list)
    flag_states: sequence[Digital_] = field(default_factory=list)
    analog_in_states: sequence[Analog_] = field(default_factory=list)
    analog_out_states: sequence[Analog_] = field(default_factory=list)


@dataclass
@annotate.final
class RobotMode_(IdlStruct, typename="ur_dashboard_msgs::msg::dds_::RobotMode_"):
    mode: int8 = 0


@dataclass
@annotate.final
class SafetyMode_(IdlStruct, typename="ur_dashboard_msgs::msg::dds_::SafetyMode_"):
    mode: uint8 = 0


@dataclass
@annotate.final
class DriveSample_(IdlStruct, typename="urtwin_msgs::msg::dds_::DriveSample_"):
    seq: uint64 = 0
    time: float64 = 0.0
    current: array[float64, 6] = field(default_factory=lambda: [0.0] * 6)
    current_measured: array[float64, 6] = field(default_factory=lambda: [0.0] * 6)
    motor_speed: array[float64, 6] = field(default_factory=lambda: [0.0] * 6)
    gear_output_torque: array[float64, 6] = field(default_factory=lambda: [0.0] * 6)
    friction_torque: array[float64, 6] = field(default_factory=lambda: [0.0] * 6)
    voltage: array[float64, 6] = field(default_factory=lambda: [0.0] * 6)
    temperature: array[float64, 6] = field(default_factory=lambda: [0.0] * 6)


@dataclass
@annotate.final
class Drive_(IdlStruct, typename="urtwin_msgs::msg::dds_::Drive_"):
    header: Header_ = field(default_factory=Header_)
    samples_lost: uint64 = 0
    samples: sequence[DriveSample_] = field(default_factory=list)


@dataclass
@annotate.final
class Gid_(IdlStruct, typename="rmw_dds_common::msg::dds_::Gid_"):
    data: array[uint8, 16] = field(default_factory=lambda: [0] * 16)


@dataclass
@annotate.final
class NodeEntitiesInfo_(IdlStruct, typename="rmw_dds_common::msg::dds_::NodeEntitiesInfo_"):
    node_namespace: bounded_str[256] = ""
    node_name: bounded_str[256] = ""
    reader_gid_seq: sequence[Gid_] = field(default_factory=list)
    writer_gid_seq: sequence[Gid_] = field(default_factory=list)


@dataclass
@annotate.final
class ParticipantEntitiesInfo_(IdlStruct,
                               typename="rmw_dds_common::msg::dds_::ParticipantEntitiesInfo_"):
    gid: Gid_ = field(default_factory=Gid_)
    node_entities_info_seq: sequence[NodeEntitiesInfo_] = field(default_factory=list)


JOINT_NAMES = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint",
               "wrist_2_joint", "wrist_3_joint"]

# (ROS topic without the leading /, mirror type, ROS type, latched) of everything urtwin writes
PUBLISHED = [
    ("joint_states", JointState_, "sensor_msgs/msg/JointState", False),
    ("force_torque_sensor_broadcaster/wrench", WrenchStamped_, "geometry_msgs/msg/WrenchStamped", False),
    ("tcp_pose_broadcaster/pose", PoseStamped_, "geometry_msgs/msg/PoseStamped", False),
    ("speed_scaling_state_broadcaster/speed_scaling", Float64_, "std_msgs/msg/Float64", False),
    ("io_and_status_controller/io_states", IOStates_, "ur_msgs/msg/IOStates", False),
    ("io_and_status_controller/robot_mode", RobotMode_, "ur_dashboard_msgs/msg/RobotMode", True),
    ("io_and_status_controller/safety_mode", SafetyMode_, "ur_dashboard_msgs/msg/SafetyMode", True),
    ("io_and_status_controller/robot_program_running", Bool_, "std_msgs/msg/Bool", True),
    ("urtwin/drive", Drive_, "urtwin_msgs/msg/Drive", False),
]
# and everything it reads
SUBSCRIBED = [
    ("forward_position_controller/commands", Float64MultiArray_, "std_msgs/msg/Float64MultiArray"),
    ("forward_velocity_controller/commands", Float64MultiArray_, "std_msgs/msg/Float64MultiArray"),
    ("scaled_joint_trajectory_controller/joint_trajectory", JointTrajectory_,
     "trajectory_msgs/msg/JointTrajectory"),
]


def dds_type_name(ros_type):
    """sensor_msgs/msg/JointState → sensor_msgs::msg::dds_::JointState_"""
    pkg, sub, name = ros_type.split("/")
    return f"{pkg}::{sub}::dds_::{name}_"
