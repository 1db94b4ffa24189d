# SPDX-License-Identifier: Apache-2.0
"""Helpers for the DDS tests: a participant on the loopback configuration, readers and writers
with the QoS of ROS 2 (SystemDefaultsQoS on Cyclone: RELIABLE, KEEP_LAST 1), raw-byte takes.

Every test process uses config/cyclonedds-lo.xml (CYCLONEDDS_URI, set here before Cyclone is
loaded) and a domain of its own, so nothing leaves loopback and parallel runs do not meet."""
import os
import random
import time

from urtwin_proc import ROOT

LOOPBACK_CONFIG = os.path.join(ROOT, "config", "cyclonedds-lo.xml")
os.environ["CYCLONEDDS_URI"] = "file://" + LOOPBACK_CONFIG

from cyclonedds._clayer import ddspy_take  # noqa: E402  (after CYCLONEDDS_URI)
from cyclonedds.core import Policy, Qos  # noqa: E402
from cyclonedds.domain import DomainParticipant  # noqa: E402
from cyclonedds.pub import DataWriter  # noqa: E402
from cyclonedds.sub import DataReader  # noqa: E402
from cyclonedds.topic import Topic  # noqa: E402
from cyclonedds.util import duration  # noqa: E402


def random_domain():
    """A domain id for one test (1..200): ports 7400 + 250·domain stay below 57 400."""
    return random.Random(os.getpid() * 7919 + time.monotonic_ns()).randint(1, 200)


def ros_qos(depth=1, latched=False, best_effort=False):
    return Qos(Policy.BestEffort if best_effort else Policy.Reliability.Reliable(duration(seconds=1)),
               Policy.Durability.TransientLocal if latched else Policy.Durability.Volatile,
               Policy.History.KeepLast(depth))


def reader(dp, topic, cls, depth=1, latched=False):
    return DataReader(dp, Topic(dp, "rt/" + topic, cls), qos=ros_qos(depth, latched))


def writer(dp, topic, cls):
    return DataWriter(dp, Topic(dp, "rt/" + topic, cls), qos=ros_qos(1))


def take_raw(rd, n=256):
    """[(CDR bytes as received, sample info)] of the valid samples waiting in a reader."""
    out = ddspy_take(rd._ref, n)
    if isinstance(out, int):
        raise RuntimeError(f"ddspy_take failed: {out}")
    return [(data, info) for data, info in out if info.valid_data]


def wait_data(rd, timeout=10.0):
    """Wait for the reader's first sample (discovery and matching done); returns it raw."""
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        got = take_raw(rd, 1)
        if got:
            return got[0]
        time.sleep(0.01)
    raise TimeoutError(f"no sample within {timeout} s")


def endpoints(dp, publications=True, topic_prefix="rt/", timeout=10.0, expect=1):
    """{topic name: [DcpsEndpoint]} of the remote writers (or readers) discovered, from the
    built-in topics, once at least `expect` topics with that prefix are known."""
    from cyclonedds.builtin import (BuiltinDataReader, BuiltinTopicDcpsPublication,
                                    BuiltinTopicDcpsSubscription)
    rd = BuiltinDataReader(dp, BuiltinTopicDcpsPublication if publications
                           else BuiltinTopicDcpsSubscription)
    found = {}
    mine = dp.get_guid()
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        for ep in rd.take(N=256):
            if ep.topic_name.startswith(topic_prefix) and ep.participant_key != mine:
                found.setdefault(ep.topic_name, []).append(ep)
        if len(found) >= expect:
            time.sleep(0.2)  # the rest of this participant's endpoints
            for ep in rd.take(N=256):
                if ep.topic_name.startswith(topic_prefix) and ep.participant_key != mine:
                    found.setdefault(ep.topic_name, []).append(ep)
            return found
        time.sleep(0.05)
    raise TimeoutError(f"fewer than {expect} topics discovered within {timeout} s: {sorted(found)}")


__all__ = ["DomainParticipant", "DataReader", "DataWriter", "Topic", "Policy", "Qos", "duration",
           "random_domain", "ros_qos", "reader", "writer", "take_raw", "wait_data", "endpoints",
           "LOOPBACK_CONFIG"]
