# SPDX-License-Identifier: Apache-2.0
"""urtwin on DDS as a ROS 2 system sees it (net/dds, issue 12), judged from the subscriber side
with the Python `cyclonedds` binding of the same Cyclone (0.10.2), an independent ROS 2 CDR
decoder (mcap-ros2-support) and our own RTDE client. Everything runs on config/cyclonedds-lo.xml
(loopback only) in a random domain per test."""
import math
import os
import re
import struct
import subprocess
import threading
import time

import pytest

import dds_support as ds
from dds_types import (JOINT_NAMES, PUBLISHED, SUBSCRIBED, Float64MultiArray_, JointState_,
                       JointTrajectory_, JointTrajectoryPoint_, Duration_, PoseStamped_,
                       WrenchStamped_, Drive_, dds_type_name)
from mcap_ros2._dynamic import generate_dynamic
from ros2_msg_defs import mcap_schema
from ros2_typehash import rihs01
from rtde_client import RtdeClient
from urtwin_proc import CONFIG, ROOT, URTWIN, Emulator, next_host

PERIOD_NS = 2_000_000


def dds_emulator(*args, domain=None):
    domain = domain if domain is not None else ds.random_domain()
    emu = Emulator("--dds", "--dds-domain", str(domain), *args)
    emu.domain = domain
    return emu


def dds_stats(err: bytes):
    """The last 'urtwin: dds:' counters line as a dict."""
    lines = [ln for ln in err.decode(errors="replace").splitlines() if ln.startswith("urtwin: dds:")]
    assert lines, "no dds statistics line on stderr"
    keys = {"ticks": r"ticks (\d+)", "ticks_lost": r"ticks \d+ lost (\d+)",
            "drive_messages": r"drive messages (\d+)", "write_errors": r"write errors (\d+)",
            "received": r"received (\d+)", "accepted": r"accepted (\d+)",
            "invalid": r"invalid (\d+)", "refused": r"refused (\d+)", "dropped": r"dropped (\d+)",
            "traj_late": r"trajectory ticks late (\d+)"}
    return {k: int(re.search(rx, lines[-1]).group(1)) for k, rx in keys.items()}


def stamp_ns(h):
    return h.stamp.sec * 1_000_000_000 + h.stamp.nanosec


def bits(values):
    return struct.pack(f"<{len(values)}d", *values)


def quaternion(r):
    """The axis-angle → quaternion arithmetic urtwin uses (dds_messages.c), step by step."""
    theta = math.sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2])
    if theta > 0.0:
        k = math.sin(theta / 2.0) / theta
        return [r[0] * k, r[1] * k, r[2] * k, math.cos(theta / 2.0)]
    return [0.0, 0.0, 0.0, 1.0]


class Collector(threading.Thread):
    """Takes every sample of some readers into lists until stopped."""

    def __init__(self, readers):
        super().__init__(daemon=True)
        self.readers, self.got = readers, {k: [] for k in readers}
        self.halt = threading.Event()

    def run(self):
        while not self.halt.is_set():
            for k, rd in self.readers.items():
                self.got[k].extend(rd.take(N=2000))
            time.sleep(0.02)
        for k, rd in self.readers.items():
            self.got[k].extend(rd.take(N=2000))

    def stop(self):
        self.halt.set()
        self.join(5)


def rtde_record(host, names, seconds, out):
    with RtdeClient(host) as c:
        c.negotiate_protocol_version(2)
        c.setup_outputs(names, 500.0)
        assert c.start()
        t_end = time.monotonic() + seconds
        while time.monotonic() < t_end:
            out.append(c.receive(timeout=2.0).values)


def latest_q(rd, timeout=5.0):
    t0 = time.monotonic()
    last = None
    while time.monotonic() - t0 < timeout:
        got = rd.take(N=2000)
        if got:
            last = got[-1]
            if time.monotonic() - t0 > 0.05:
                return list(last.position)
        time.sleep(0.02)
    assert last is not None, "no joint state"
    return list(last.position)


def test_the_python_binding_runs_the_emulators_cyclone():
    """The subscriber side is Cyclone 0.10 too: the binding's version is 0.10.x and the C
    library it loaded is the system's libddsc (Debian's 0.10.2), the emulator's."""
    from importlib.metadata import version
    assert version("cyclonedds").startswith("0.10."), version("cyclonedds")
    ds.DomainParticipant(ds.random_domain())
    with open("/proc/self/maps") as f:
        libs = {ln.split()[-1] for ln in f if "libddsc" in ln}
    assert libs and all(lib.startswith(("/usr/lib/", "/lib/")) for lib in libs), libs
    out = subprocess.run(["ldd", URTWIN], capture_output=True, text=True).stdout
    emu_lib = [ln.split("=>")[1].split()[0] for ln in out.splitlines() if "libddsc" in ln]
    assert emu_lib and os.path.realpath(emu_lib[0]) in {os.path.realpath(x) for x in libs}


# ---- publishing -------------------------------------------------------------------------------

def test_joint_states_10_s_no_gap_and_equal_to_rtde_bit_for_bit():
    with dds_emulator() as emu:
        dp = ds.DomainParticipant(emu.domain)
        rds = {"js": ds.reader(dp, "joint_states", JointState_, depth=20000),
               "wr": ds.reader(dp, "force_torque_sensor_broadcaster/wrench", WrenchStamped_, depth=20000),
               "po": ds.reader(dp, "tcp_pose_broadcaster/pose", PoseStamped_, depth=20000)}
        for rd in rds.values():
            ds.wait_data(rd)
        col = Collector(rds)
        col.start()
        rtde = []
        rtde_record(emu.host, ["timestamp", "actual_q", "actual_qd", "actual_current",
                               "actual_TCP_force", "actual_TCP_pose"], 10.5, rtde)
        col.stop()

    js = col.got["js"]
    stamps = [stamp_ns(s.header) for s in js]
    # 10 s at the controller rate, every tick once, in order
    assert stamps[-1] - stamps[0] >= 10 * 1_000_000_000
    steps = {b - a for a, b in zip(stamps, stamps[1:])}
    assert steps == {PERIOD_NS}, f"gaps or repeats in joint_states: steps {sorted(steps)[:10]}"
    for s in js[:5]:
        assert list(s.name) == JOINT_NAMES and s.header.frame_id == "base_link"

    # the same tick on RTDE: stamp = epoch + controller time, epoch found from one exact match
    by_stamp = {stamp_ns(s.header): s for s in js}
    first = rtde[len(rtde) // 2]
    # (the arm rests: quantised positions repeat, the current's noise does not)
    match = [st for st, s in by_stamp.items() if bits(s.position) == bits(first["actual_q"])
             and bits(s.effort) == bits(first["actual_current"])]
    assert len(match) == 1, "no unique joint state with the RTDE sample's actual_q and current"
    epoch = match[0] - round(first["timestamp"] * 1e9)
    wr = {stamp_ns(s.header): s for s in col.got["wr"]}
    po = {stamp_ns(s.header): s for s in col.got["po"]}
    compared = 0
    for r in rtde:
        st = epoch + round(r["timestamp"] * 1e9)
        if st not in by_stamp:
            continue
        s = by_stamp[st]
        assert bits(s.position) == bits(r["actual_q"])
        assert bits(s.velocity) == bits(r["actual_qd"])
        assert bits(s.effort) == bits(r["actual_current"])  # effort = motor current, as the driver
        w = wr[st].wrench
        assert bits([w.force.x, w.force.y, w.force.z, w.torque.x, w.torque.y, w.torque.z]) == \
            bits(r["actual_TCP_force"])
        p = po[st].pose
        assert bits([p.position.x, p.position.y, p.position.z]) == bits(r["actual_TCP_pose"][:3])
        o = p.orientation
        assert bits([o.x, o.y, o.z, o.w]) == bits(quaternion(r["actual_TCP_pose"][3:]))
        compared += 1
    assert compared >= 0.9 * len(rtde) and compared >= 1000, f"compared {compared} of {len(rtde)}"
    print(f"joint_states: {len(js)} samples over {(stamps[-1] - stamps[0]) / 1e9:.3f} s, no gap; "
          f"{compared} ticks equal to RTDE bit for bit (q, qd, current, wrench, pose)")


def test_wire_bytes_decode_as_ros2_and_endpoints_are_rmw_like():
    with dds_emulator() as emu:
        dp = ds.DomainParticipant(emu.domain)
        raw = {}
        for topic, cls, ros_type, latched in PUBLISHED:
            rd = ds.reader(dp, topic, cls, depth=5, latched=latched)
            raw[topic] = (cls, ros_type, ds.wait_data(rd)[0])
        pubs = ds.endpoints(dp, publications=True, expect=len(PUBLISHED))
        subs = ds.endpoints(dp, publications=False, expect=len(SUBSCRIBED))
        from cyclonedds.builtin import BuiltinDataReader, BuiltinTopicDcpsParticipant
        parts = BuiltinDataReader(dp, BuiltinTopicDcpsParticipant).take(N=64)

    def plain(x):
        if hasattr(x, "__dataclass_fields__"):
            return {k: plain(getattr(x, k)) for k in x.__dataclass_fields__ if k != "sample_info"}
        if isinstance(x, (list, tuple)):
            return [plain(v) for v in x]
        if hasattr(x, "__slots__"):
            return {k: plain(getattr(x, k)) for k in x.__slots__}
        return x

    for topic, (cls, ros_type, data) in raw.items():
        # CDR_LE (classic, XCDR1); the options' low bits may count the final padding
        assert data[:2] == b"\x00\x01" and data[2] == 0 and data[3] <= 3, \
            f"{topic}: not classic little-endian CDR: {data[:4].hex()}"
        ros = generate_dynamic(ros_type, mcap_schema(ros_type))[ros_type](data)  # header too
        mine = plain(cls.deserialize(data))
        theirs = plain(ros)
        assert theirs == mine, f"{topic}: the ROS 2 decoder reads something else"
    assert raw["tcp_pose_broadcaster/pose"][0].deserialize(
        raw["tcp_pose_broadcaster/pose"][2]).pose.orientation.w != 0.0

    from cyclonedds.core import Policy
    for topic, _, ros_type, latched in PUBLISHED:
        (ep,) = pubs["rt/" + topic]
        assert ep.type_name == dds_type_name(ros_type)
        q = ep.qos
        assert q[Policy.Userdata].data == f"typehash={rihs01(ros_type)};".encode()
        assert len(q[Policy.Userdata].data) == 81
        assert isinstance(q[Policy.Reliability], Policy.Reliability.Reliable)
        assert q[Policy.Durability] == (Policy.Durability.TransientLocal if latched
                                        else Policy.Durability.Volatile)
        # the driver's KEEP_LAST 1; urtwin's own drive stream keeps 100 batches for repairs
        assert q[Policy.History] == Policy.History.KeepLast(100 if topic == "urtwin/drive" else 1)
        dr = q[Policy.DataRepresentation]
        assert dr.use_cdrv0_representation and not dr.use_xcdrv2_representation
    for topic, _, ros_type in SUBSCRIBED:
        (ep,) = subs["rt/" + topic]
        assert ep.type_name == dds_type_name(ros_type)
        assert ep.qos[Policy.Userdata].data == f"typehash={rihs01(ros_type)};".encode()
        assert isinstance(ep.qos[Policy.Reliability], Policy.Reliability.Reliable)
    enclaves = [p.qos[Policy.Userdata].data for p in parts
                if Policy.Userdata in p.qos and p.key != dp.get_guid()]
    assert b"enclave=/;" in enclaves


def test_latched_modes_reach_a_late_subscriber():
    from dds_types import Bool_, RobotMode_, SafetyMode_
    with dds_emulator() as emu:
        time.sleep(1.0)  # published long before this reader exists
        dp = ds.DomainParticipant(emu.domain)
        got = {}
        for topic, cls in (("io_and_status_controller/robot_mode", RobotMode_),
                           ("io_and_status_controller/safety_mode", SafetyMode_),
                           ("io_and_status_controller/robot_program_running", Bool_)):
            rd = ds.reader(dp, topic, cls, latched=True)
            got[topic] = cls.deserialize(ds.wait_data(rd, timeout=5)[0])
    assert got["io_and_status_controller/robot_mode"].mode == 7      # RUNNING
    assert got["io_and_status_controller/safety_mode"].mode == 1     # NORMAL
    assert got["io_and_status_controller/robot_program_running"].data is False


def drive_seq_time(raw):
    """(seq, time) of every sample in one Drive_ message, read straight from its CDR (Python
    decoding of whole 14 kB batches cannot keep up with 500 of them a second)."""
    body = raw[4:]
    n = struct.unpack_from("<I", body, 8)[0]
    off = 12 + n
    off = (off + 7) & ~7
    off += 8                                   # samples_lost
    count = struct.unpack_from("<I", body, off)[0]
    off = (off + 4 + 7) & ~7
    size = 8 + 8 + 7 * 6 * 8
    return [struct.unpack_from("<Qd", body, off + i * size) for i in range(count)]


def test_drive_batches_every_sample_in_order():
    with dds_emulator("--drive-rate", "20000") as emu:
        dp = ds.DomainParticipant(emu.domain)
        rd = ds.reader(dp, "urtwin/drive", Drive_, depth=5000)
        ds.wait_data(rd)
        raw = []
        t_end = time.monotonic() + 2.0
        while time.monotonic() < t_end:
            raw.extend(d for d, _ in ds.take_raw(rd, 1000))
            time.sleep(0.02)
        time.sleep(0.2)
        raw.extend(d for d, _ in ds.take_raw(rd, 5000))
    st = dds_stats(emu.err)
    samples = [x for r in raw for x in drive_seq_time(r)]
    print(f"drive: {len(raw)} messages, {len(samples)} samples; emulator: {st}")
    seqs = [q for q, _ in samples]
    assert len(samples) >= 30000 and seqs == list(range(seqs[0], seqs[0] + len(seqs)))
    dt = {round((b - a) * 1e6, 3) for (_, a), (_, b) in zip(samples, samples[1:])}
    assert dt == {50.0}, f"sample spacing {sorted(dt)[:5]} us"
    msgs = [Drive_.deserialize(r) for r in raw[::100]]
    assert max(len(m.samples) for m in msgs) <= 64
    assert [(s.seq, s.time) for s in msgs[0].samples] == drive_seq_time(raw[0])
    for m in msgs:
        assert m.header.frame_id == "base" and m.samples_lost == 0
        for s in m.samples[::10]:
            assert all(20.0 <= t <= 120.0 for t in s.temperature)
            assert any(c != cm for c, cm in zip(s.current, s.current_measured))  # sensor != truth


def test_node_info_names_every_endpoint_for_ros2_node_list():
    import uuid
    from dds_types import ParticipantEntitiesInfo_
    with dds_emulator("--dds-node-info", "--dds-prefix", "cell2") as emu:
        dp = ds.DomainParticipant(emu.domain)
        rd = ds.DataReader(dp, ds.Topic(dp, "ros_discovery_info", ParticipantEntitiesInfo_),
                           qos=ds.ros_qos(depth=10, latched=True))
        raw, _ = ds.wait_data(rd)
        info = ParticipantEntitiesInfo_.deserialize(raw)
        pubs = ds.endpoints(dp, publications=True, expect=len(PUBLISHED))
        subs = ds.endpoints(dp, publications=False, expect=len(SUBSCRIBED))
        graph = ds.endpoints(dp, publications=True, topic_prefix="ros_discovery_info")
    (node,) = info.node_entities_info_seq
    assert (node.node_namespace, node.node_name) == ("/cell2", "urtwin")
    gid = lambda g: uuid.UUID(bytes=bytes(g.data))  # noqa: E731
    writers = {ep.key for eps in pubs.values() for ep in eps}
    readers = {ep.key for eps in subs.values() for ep in eps}
    assert {gid(g) for g in node.writer_gid_seq} == writers
    assert {gid(g) for g in node.reader_gid_seq} == readers
    (ep,) = graph["ros_discovery_info"]
    assert gid(info.gid) == ep.participant_key
    from cyclonedds.core import Policy
    assert ep.type_name == "rmw_dds_common::msg::dds_::ParticipantEntitiesInfo_"
    assert ep.qos[Policy.Userdata].data == \
        f"typehash={rihs01('rmw_dds_common/msg/ParticipantEntitiesInfo')};".encode()
    assert ep.qos[Policy.Durability] == Policy.Durability.TransientLocal


def test_prefix_namespaces_every_topic():
    with dds_emulator("--dds-prefix", "robot1") as emu:
        dp = ds.DomainParticipant(emu.domain)
        pubs = ds.endpoints(dp, publications=True, expect=len(PUBLISHED))
        subs = ds.endpoints(dp, publications=False, expect=len(SUBSCRIBED))
    assert sorted(pubs) == sorted("rt/robot1/" + t for t, *_ in PUBLISHED)
    assert sorted(subs) == sorted("rt/robot1/" + t for t, *_ in SUBSCRIBED)


def test_dds_is_off_without_the_option():
    domain = ds.random_domain()
    with Emulator("--dds-domain", str(domain)):
        dp = ds.DomainParticipant(domain)
        with pytest.raises(TimeoutError):
            ds.endpoints(dp, publications=True, expect=1, timeout=2.0)


def test_locators_are_loopback_only():
    """The emulator's participant as the subscriber's Cyclone discovered it (its discovery
    trace): every advertised locator is 127.x."""
    from cyclonedds.domain import Domain
    trace = os.path.join("/tmp", f"urtwin_dds_trace_{os.getpid()}.log")
    xml = open(ds.LOOPBACK_CONFIG).read().replace(
        "</Domain>", f"<Tracing><Category>discovery</Category><OutputFile>{trace}</OutputFile>"
                     "</Tracing></Domain>")
    try:
        with dds_emulator() as emu:
            dom = Domain(emu.domain, xml)  # noqa: F841  (keeps the traced domain alive)
            dp = ds.DomainParticipant(emu.domain)
            ds.wait_data(ds.reader(dp, "joint_states", JointState_))
            pid = emu.proc.pid
        with open(trace) as f:
            spdp = [ln for ln in f if "SPDP" in ln and "NEW" in ln and f'"__Pid":"{pid}"' in ln]
    finally:
        if os.path.exists(trace):
            os.remove(trace)
    assert len(spdp) == 1, "the emulator's participant was not discovered exactly once"
    locators = re.findall(r"udp/([0-9.]+):\d+", spdp[0])
    assert locators and all(a.startswith("127.") for a in locators), locators
    assert 'enclave=/;' in spdp[0]


# ---- commands ---------------------------------------------------------------------------------

def command_path_ready(dp, topic):
    """Wait until the emulator's reader of the topic is discovered (our writer then matches it
    as well), plus a little for the match on its side: a loaded host can take seconds."""
    ds.endpoints(dp, publications=False, topic_prefix="rt/" + topic, timeout=20.0)
    time.sleep(0.3)


def settle(rd, after, timeout=20.0):
    """Joint positions once the arm rests (|Δq| < 1e-4 over 0.3 s), no earlier than `after`
    (monotonic); a loaded host may run the motion late, never differently."""
    t0 = time.monotonic()
    while time.monotonic() < after:
        rd.take(N=2000)
        time.sleep(0.05)
    prev = latest_q(rd)
    while time.monotonic() - t0 < timeout:
        time.sleep(0.3)
        q = latest_q(rd)
        if max(abs(a - b) for a, b in zip(q, prev)) < 1e-4:
            return q
        prev = q
    return prev


def send_forward(wr, q):
    wr.write(Float64MultiArray_(data=list(q)))


def test_forward_position_sine_moves_with_servo_lag_and_stops_after_timeout():
    with dds_emulator() as emu:
        dp = ds.DomainParticipant(emu.domain)
        js = ds.reader(dp, "joint_states", JointState_, depth=20000)
        wr = ds.writer(dp, "forward_position_controller/commands", Float64MultiArray_)
        ds.wait_data(js)
        q0 = latest_q(js)
        command_path_ready(dp, "forward_position_controller/commands")
        col = Collector({"js": js})
        col.start()
        amp, freq, sent = 0.05, 1.0, []
        t_start = time.monotonic()
        k = 0
        while True:
            t = k * 0.002
            if t > 2.0:
                break
            while time.monotonic() < t_start + t:
                pass
            q = list(q0)
            q[0] += amp * math.sin(2 * math.pi * freq * t)
            q[5] += amp * math.sin(2 * math.pi * freq * t)
            send_forward(wr, q)
            sent.append((time.time_ns(), q[0]))
            k += 1
        t_last = time.time_ns()
        # until samples published 0.8 s after the last command are in (a loaded host delivers
        # late: seen 1.2 s behind at a load average of 35 on 2 cores)
        t0 = time.monotonic()
        while time.monotonic() - t0 < 30:
            time.sleep(0.1)
            got = col.got["js"]
            if got and got[-1].sample_info.source_timestamp > t_last + 800_000_000:
                break
        col.stop()
        alive = emu.alive()
    st = dds_stats(emu.err)
    assert alive
    # timed by the DDS source timestamp (wall clock when the loop published the tick), the clock
    # the commands were sent by: header stamps follow controller time, which a loaded host
    # that misses periods lets fall behind wall time
    samples = [(s.sample_info.source_timestamp, s.position[0], s.velocity[0])
               for s in col.got["js"]]
    during = [(t, q) for t, q, _ in samples if sent[0][0] <= t <= t_last]
    # moved: the arm swings through most of the commanded range
    swing = max(q for _, q in during) - min(q for _, q in during)
    assert swing > 1.6 * amp, f"swing {swing:.4f} rad of {2 * amp}"
    # with a lag: the command shifted by the best lag fits the motion closely
    import numpy as np
    ct = np.array([t for t, _ in sent], dtype=float)
    cq = np.array([q for _, q in sent])
    # judged after the first half second (the servo starts from rest into a moving target)
    steady = [(t, q) for t, q in during if t > sent[0][0] + 500_000_000]
    at = np.array([t for t, _ in steady], dtype=float)
    aq = np.array([q for _, q in steady])
    best = min((float(np.sqrt(np.mean((aq - np.interp(at - lag * 1e6, ct, cq)) ** 2))), lag)
               for lag in range(0, 300, 2))
    rms, lag_ms = best
    assert 4 <= lag_ms <= 200, f"lag {lag_ms} ms"
    assert rms < 0.1 * amp, f"rms {rms:.5f} rad after the best lag {lag_ms} ms"
    # stopped: from 0.5 s after the last command the arm is at rest and stays
    after = [(t, q, v) for t, q, v in samples if t > t_last + 500_000_000]
    # (the measured speed carries the encoder's noise: judged on its mean)
    assert after and sum(abs(v) for _, _, v in after) / len(after) < 1e-3
    assert max(q for _, q, _ in after) - min(q for _, q, _ in after) < 2e-4
    # every command taken was applied (the reader keeps the newest only, as the driver's
    # SystemDefaultsQoS does: how many a busy host overwrites first is timing, not judged)
    assert st["accepted"] > 0 and st["refused"] == 0 and st["invalid"] == 0
    assert st["received"] == st["accepted"]
    print(f"forward position: {len(sent)} commands sent, {st['accepted']} taken and applied, lag {lag_ms} ms, "
          f"rms {rms * 1e3:.3f} mrad, swing {swing:.4f} rad")


def test_forward_velocity_moves_and_stops_after_timeout():
    with dds_emulator() as emu:
        dp = ds.DomainParticipant(emu.domain)
        js = ds.reader(dp, "joint_states", JointState_, depth=20000)
        wr = ds.writer(dp, "forward_velocity_controller/commands", Float64MultiArray_)
        ds.wait_data(js)
        q0 = latest_q(js)
        command_path_ready(dp, "forward_velocity_controller/commands")
        t_end = time.monotonic() + 0.5
        while time.monotonic() < t_end:
            send_forward(wr, [0.2, 0, 0, 0, 0, 0])
            time.sleep(0.004)
        q1 = settle(js, time.monotonic() + 0.5)
        time.sleep(0.3)
        q2 = latest_q(js)
    st = dds_stats(emu.err)
    # at most 0.2 rad/s for the 0.5 s of commands and the timeout after them
    assert 0.01 < q1[0] - q0[0] < 0.2 * 0.7, q1[0] - q0[0]
    assert abs(q2[0] - q1[0]) < 2e-4
    assert st["accepted"] > 0 and st["received"] == st["accepted"]


def test_joint_trajectory_of_three_points_ends_within_1_mrad():
    with dds_emulator() as emu:
        dp = ds.DomainParticipant(emu.domain)
        js = ds.reader(dp, "joint_states", JointState_, depth=20000)
        wr = ds.writer(dp, "scaled_joint_trajectory_controller/joint_trajectory", JointTrajectory_)
        ds.wait_data(js)
        q0 = latest_q(js)
        command_path_ready(dp, "scaled_joint_trajectory_controller/joint_trajectory")
        offsets = [(0.15, -0.10), (0.05, 0.10), (0.25, -0.05)]
        # joint order shuffled: the controller maps by name
        order = [2, 0, 1, 5, 4, 3]
        points = []
        for i, (a, b) in enumerate(offsets):
            q = list(q0)
            q[0] += a
            q[2] += b
            points.append(q)
        msg = JointTrajectory_(joint_names=[JOINT_NAMES[j] for j in order], points=[
            JointTrajectoryPoint_(positions=[p[j] for j in order], velocities=[0.0] * 6,
                                  time_from_start=Duration_(sec=i + 1, nanosec=0))
            for i, p in enumerate(points)])
        col = Collector({"js": js})
        col.start()
        wr.write(msg)
        time.sleep(3.2)
        col.stop()
        final = settle(js, time.monotonic())
    st = dds_stats(emu.err)
    got = col.got["js"]
    err = max(abs(a - b) for a, b in zip(final, points[-1]))
    assert err < 1e-3, f"final error {err * 1e3:.3f} mrad"
    # it went through the first point on the way (at rest there: a cubic with zero velocity)
    assert min(abs(s.position[0] - points[0][0]) + abs(s.position[2] - points[0][2])
               for s in got) < 5e-3
    assert st["accepted"] == 1 and st["invalid"] == 0
    assert st["dropped"] == 0
    print(f"trajectory: final error {err * 1e3:.4f} mrad, ticks held late {st['traj_late']}")


def test_commands_refused_in_local_control():
    with dds_emulator("--local-control") as emu:
        dp = ds.DomainParticipant(emu.domain)
        js = ds.reader(dp, "joint_states", JointState_, depth=100)
        wr = ds.writer(dp, "forward_position_controller/commands", Float64MultiArray_)
        tw = ds.writer(dp, "scaled_joint_trajectory_controller/joint_trajectory", JointTrajectory_)
        ds.wait_data(js)
        q0 = latest_q(js)
        command_path_ready(dp, "forward_position_controller/commands")
        command_path_ready(dp, "scaled_joint_trajectory_controller/joint_trajectory")
        target = list(q0)
        target[0] += 0.05
        for _ in range(50):
            send_forward(wr, target)
            time.sleep(0.01)
        tw.write(JointTrajectory_(joint_names=JOINT_NAMES, points=[JointTrajectoryPoint_(
            positions=target, time_from_start=Duration_(sec=1))]))
        time.sleep(1.5)
        q1 = latest_q(js)
    st = dds_stats(emu.err)
    assert max(abs(a - b) for a, b in zip(q0, q1)) < 1e-4
    assert st["accepted"] == 0 and st["refused"] == st["received"] and st["received"] >= 10


def test_bad_commands_are_counted_and_the_emulator_keeps_running():
    with dds_emulator() as emu:
        dp = ds.DomainParticipant(emu.domain)
        js = ds.reader(dp, "joint_states", JointState_, depth=100)
        wr = ds.writer(dp, "forward_position_controller/commands", Float64MultiArray_)
        vw = ds.writer(dp, "forward_velocity_controller/commands", Float64MultiArray_)
        tw = ds.writer(dp, "scaled_joint_trajectory_controller/joint_trajectory", JointTrajectory_)
        ds.wait_data(js)
        q0 = latest_q(js)
        for topic, _, _ in SUBSCRIBED:
            command_path_ready(dp, topic)
        bad = [
            (wr, Float64MultiArray_(data=q0[:5])),                       # 5 values
            (wr, Float64MultiArray_(data=q0 + [0.0])),                   # 7 values
            (wr, Float64MultiArray_(data=[float("nan")] + q0[1:])),      # NaN
            (vw, Float64MultiArray_(data=[float("inf"), 0, 0, 0, 0, 0])),  # Inf
            (tw, JointTrajectory_(joint_names=JOINT_NAMES, points=[JointTrajectoryPoint_(
                positions=[float("nan")] * 6, time_from_start=Duration_(sec=1))])),
            (tw, JointTrajectory_(joint_names=JOINT_NAMES[:5], points=[JointTrajectoryPoint_(
                positions=q0[:5], time_from_start=Duration_(sec=1))])),
            (tw, JointTrajectory_(joint_names=["a", "b", "c", "d", "e", "f"], points=[
                JointTrajectoryPoint_(positions=q0, time_from_start=Duration_(sec=1))])),
            (tw, JointTrajectory_(joint_names=JOINT_NAMES, points=[
                JointTrajectoryPoint_(positions=q0, time_from_start=Duration_(sec=2)),
                JointTrajectoryPoint_(positions=q0, time_from_start=Duration_(sec=1))])),
        ]
        for w, m in bad:
            w.write(m)
            time.sleep(0.3)  # each one taken before the next (the reader keeps the newest only)
        time.sleep(0.5)
        q1 = latest_q(js)
        alive = emu.alive()
    st = dds_stats(emu.err)
    assert alive
    assert st["received"] == len(bad) and st["invalid"] == len(bad) and st["accepted"] == 0
    assert max(abs(a - b) for a, b in zip(q0, q1)) < 1e-4
    assert "trajectory refused" in emu.err.decode()


# ---- options ----------------------------------------------------------------------------------

def run_urtwin(*args):
    return subprocess.run([URTWIN, "--config", CONFIG, "--bind", next_host(), *args],
                          capture_output=True, cwd=ROOT, timeout=30)


def test_out_of_range_domain_is_a_usage_error():
    r = run_urtwin("--dds", "--dds-domain", "233")
    assert r.returncode == 2 and b"dds-domain" in r.stderr


def test_malformed_config_is_a_clear_error(tmp_path):
    bad = tmp_path / "bad.xml"
    bad.write_text("<CycloneDDS><Domain><General><Interfaces><NetworkInterface name='lo'/>")
    r = run_urtwin("--dds", "--dds-config", str(bad))
    assert r.returncode == 2 and b"not a well-formed" in r.stderr and b"never closed" in r.stderr, \
        r.stderr[-500:]
    r = run_urtwin("--dds", "--dds-config", str(tmp_path / "missing.xml"))
    assert r.returncode == 2 and b"cannot read --dds-config" in r.stderr
    unknown = tmp_path / "unknown.xml"
    unknown.write_text('<CycloneDDS xmlns="https://cdds.io/config"><Domain Id="any"><General>'
                       "<NoSuchElement>1</NoSuchElement></General></Domain></CycloneDDS>")
    r = run_urtwin("--dds", "--dds-config", str(unknown))
    assert r.returncode == 2 and b"rejected the configuration" in r.stderr


def test_bad_prefix_is_a_clear_error():
    r = run_urtwin("--dds", "--dds-prefix", "two words")
    assert r.returncode == 2 and b"not a ROS namespace" in r.stderr
