# SPDX-License-Identifier: Apache-2.0
"""Our RIHS01 implementation (ros2_typehash) against hashes published by ROS 2 itself
(rosidl-generated sources, `ros2 topic info -v` of real systems, ros2cli's tests), as collected
in ../shared/docs/dds.md §3.3 — so the hashes it computes for urtwin's other types, and the
ones urtwin puts into USER_DATA, can be trusted."""
import pytest

from ros2_typehash import rihs01

PUBLISHED_BY_ROS = {
    "builtin_interfaces/msg/Time": "b106235e25a4c5ed35098aa0a61a3ee9c9b18d197f398b0e4206cea9acf9c197",
    "std_msgs/msg/Header": "f49fb3ae2cf070f793645ff749683ac6b06203e41c891e17701b1cb597ce6a01",
    "sensor_msgs/msg/JointState": "a13ee3a330e346c9d87b5aa18d24e11690752bd33a0350f11c5882bc9179260e",
    "geometry_msgs/msg/WrenchStamped": "8dc3deaf06b2ab281f9f9a742a8961c328ca7cec16e3fd6586d3a5c83fa78f77",
    "geometry_msgs/msg/PoseStamped": "10f3786d7d40fd2b54367835614bff85d4ad3b5dab62bf8bca0cc232d73b4cd8",
    "std_msgs/msg/Float64": "705ba9c3d1a09df43737eb67095534de36fd426c0587779bda2bc51fe790182a",
    "std_msgs/msg/Bool": "feb91e995ff9ebd09c0cb3d2aed18b11077585839fb5db80193b62d74528f6c9",
    "ur_msgs/msg/IOStates": "7a62606d52c4b2aaa3fd3c5bc565cfda9c6fe8c2d69bbc7e3eadccde4cfc2a32",
    "ur_dashboard_msgs/msg/RobotMode": "ba3c379b3c995f660b38d03a195dc23ed7571a1bc06ceed2cec38c75ae9bd634",
    "ur_dashboard_msgs/msg/SafetyMode": "9eb2716e6905f06e4eb60af26712660486e909026aa89c553dd633f1fb22f592",
    "rmw_dds_common/msg/ParticipantEntitiesInfo":
        "91a0593bacdcc50ea9bdcf849a938b128412cc1ea821245c663bcd26f83c295e",
    "geometry_msgs/msg/Pose": "d501954e9476cea2996984e812054b68026ae0bfae789d9a10b23daf35cc90fa",
}


@pytest.mark.parametrize("type_name", sorted(PUBLISHED_BY_ROS))
def test_hash_equals_the_one_ros_publishes(type_name):
    assert rihs01(type_name) == "RIHS01_" + PUBLISHED_BY_ROS[type_name]


def test_a_changed_field_changes_the_hash(monkeypatch):
    import ros2_msg_defs
    before = rihs01("std_msgs/msg/Float64")
    monkeypatch.setitem(ros2_msg_defs.MSGS, "std_msgs/msg/Float64", "float32 data\n")
    assert rihs01("std_msgs/msg/Float64") != before
