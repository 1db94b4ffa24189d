# SPDX-License-Identifier: Apache-2.0
"""The ROS 2 .msg definitions of every type urtwin puts on DDS, as ROS 2 ships them
(ros2/common_interfaces, rcl_interfaces, ur_msgs, ur_dashboard_msgs; constants and comments
left out: they never reach the wire or the type hash), and urtwin's own from
net/dds/msg/urtwin_msgs. Used by the DDS tests as the independent description of the wire:
mcap-ros2-support decodes the bytes with these texts, and ros2_typehash computes the RIHS01
hashes from them."""
import os

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

MSGS = {
    "builtin_interfaces/msg/Time": "int32 sec\nuint32 nanosec\n",
    "builtin_interfaces/msg/Duration": "int32 sec\nuint32 nanosec\n",
    "std_msgs/msg/Header": "builtin_interfaces/Time stamp\nstring frame_id\n",
    "std_msgs/msg/Float64": "float64 data\n",
    "std_msgs/msg/Bool": "bool data\n",
    "std_msgs/msg/MultiArrayDimension": "string label\nuint32 size\nuint32 stride\n",
    "std_msgs/msg/MultiArrayLayout": "MultiArrayDimension[] dim\nuint32 data_offset\n",
    "std_msgs/msg/Float64MultiArray": "MultiArrayLayout layout\nfloat64[] data\n",
    "sensor_msgs/msg/JointState": ("std_msgs/Header header\nstring[] name\nfloat64[] position\n"
                                   "float64[] velocity\nfloat64[] effort\n"),
    "geometry_msgs/msg/Vector3": "float64 x\nfloat64 y\nfloat64 z\n",
    "geometry_msgs/msg/Point": "float64 x\nfloat64 y\nfloat64 z\n",
    "geometry_msgs/msg/Quaternion": "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n",
    "geometry_msgs/msg/Wrench": "Vector3 force\nVector3 torque\n",
    "geometry_msgs/msg/WrenchStamped": "std_msgs/Header header\nWrench wrench\n",
    "geometry_msgs/msg/Pose": "Point position\nQuaternion orientation\n",
    "geometry_msgs/msg/PoseStamped": "std_msgs/Header header\nPose pose\n",
    "trajectory_msgs/msg/JointTrajectoryPoint": (
        "float64[] positions\nfloat64[] velocities\nfloat64[] accelerations\nfloat64[] effort\n"
        "builtin_interfaces/Duration time_from_start\n"),
    "trajectory_msgs/msg/JointTrajectory": ("std_msgs/Header header\nstring[] joint_names\n"
                                            "JointTrajectoryPoint[] points\n"),
    "ur_msgs/msg/Digital": "uint8 pin\nbool state\n",
    "ur_msgs/msg/Analog": "uint8 pin\nuint8 domain\nfloat32 state\n",
    "ur_msgs/msg/IOStates": ("Digital[] digital_in_states\nDigital[] digital_out_states\n"
                             "Digital[] flag_states\nAnalog[] analog_in_states\n"
                             "Analog[] analog_out_states\n"),
    "ur_dashboard_msgs/msg/RobotMode": "int8 mode\n",
    "ur_dashboard_msgs/msg/SafetyMode": "uint8 mode\n",
    "rmw_dds_common/msg/Gid": "char[16] data\n",
    "rmw_dds_common/msg/NodeEntitiesInfo": ("string<=256 node_namespace\nstring<=256 node_name\n"
                                            "Gid[] reader_gid_seq\nGid[] writer_gid_seq\n"),
    "rmw_dds_common/msg/ParticipantEntitiesInfo": "Gid gid\nNodeEntitiesInfo[] node_entities_info_seq\n",
}


def _own(name):
    with open(os.path.join(ROOT, "net/dds/msg/urtwin_msgs/msg", name + ".msg")) as f:
        return f.read()


MSGS["urtwin_msgs/msg/DriveSample"] = _own("DriveSample")
MSGS["urtwin_msgs/msg/Drive"] = _own("Drive")

PRIMITIVES = {"bool", "byte", "char", "float32", "float64", "int8", "uint8", "int16", "uint16",
              "int32", "uint32", "int64", "uint64", "string", "wstring"}


def fields(type_name):
    """[(field name, base type, array spec, string bound)] of a .msg: base type fully qualified
    (pkg/msg/Name) for nested types; array spec None, ('fixed', n), ('bounded', n) or
    ('unbounded', 0)."""
    pkg = type_name.split("/")[0]
    out = []
    for line in MSGS[type_name].splitlines():
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        parts = line.split()
        t, name = parts[0], parts[1]
        if "=" in name:  # a constant
            continue
        arr = None
        if "[" in t:
            t, spec = t[:-1].split("[")
            arr = ("unbounded", 0) if spec == "" else (
                ("bounded", int(spec[2:])) if spec.startswith("<=") else ("fixed", int(spec)))
        sbound = 0
        if t.startswith("string<="):
            t, sbound = "string", int(t[8:])
        if t not in PRIMITIVES:
            p, n = t.split("/") if "/" in t else (pkg, t)
            t = f"{p}/msg/{n}"
        out.append((name, t, arr, sbound))
    return out


def dependencies(type_name):
    """Every nested type, transitively, sorted by name."""
    seen, todo = set(), [type_name]
    while todo:
        for _, t, _, _ in fields(todo.pop()):
            if t not in PRIMITIVES and t not in seen:
                seen.add(t)
                todo.append(t)
    return sorted(seen)


def mcap_schema(type_name):
    """The ros2msg schema text mcap-ros2-support reads: the type, then each dependency after a
    separator line (the format `ros2 bag record` writes into MCAP files)."""
    text = MSGS[type_name]
    for dep in dependencies(type_name):
        p, _, n = dep.split("/")
        text += "=" * 80 + f"\nMSG: {p}/{n}\n" + MSGS[dep]
    return text
